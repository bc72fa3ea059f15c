!> Command lines of the flexmor executables: `PROGRAM INPUT [-o OUTPUT] [-q] [options]`.
!> The output defaults to the input's base name with .h5, in the current directory.
module io_cli
  use, intrinsic :: iso_fortran_env, only: output_unit
  use core_error, only: error_t, ERR_INPUT
  use io_schema, only: write_schema
  implicit none
  private
  public :: cli_args_t, parse_cli

  type :: cli_args_t
    character(len=:), allocatable :: input, output
    logical :: verbose = .true.
    logical :: check = .false.       !< --check (where the program offers it)
    logical :: done = .false.        !< --help or --version answered: nothing to run
  end type cli_args_t

contains

  !> `help` lines follow the usage line for -h; `version` is printed for --version, the scene
  !> schema (every input variable, tab-separated: docs/input.md) for --schema; with
  !> `allow_check`, --check is accepted. Output goes only where `args%verbose` is set on entry
  !> (e.g. rank 0 of an MPI job).
  subroutine parse_cli(usage, help, version, allow_check, args, err)
    character(len=*), intent(in) :: usage, help(:), version
    logical, intent(in) :: allow_check
    type(cli_args_t), intent(inout) :: args
    type(error_t), intent(out) :: err
    character(len=4096) :: arg
    integer :: i, k, n, dot
    logical :: talk
    talk = args%verbose
    n = command_argument_count()
    i = 0
    do while (i < n)
      i = i + 1
      call get_command_argument(i, arg)
      select case (trim(arg))
      case ('-h', '--help')
        if (talk) write(*, '(a)') usage, (trim(help(k)), k = 1, size(help))
        args%done = .true.
        return
      case ('--version')
        if (talk) write(*, '(a)') version
        args%done = .true.
        return
      case ('--schema')
        if (talk) call write_schema(output_unit)
        args%done = .true.
        return
      case ('-q', '--quiet')
        args%verbose = .false.
      case ('-o')
        ! The first name would be dropped without a word.
        if (allocated(args%output)) then
          call err%set(ERR_INPUT, 'option -o given twice (' // usage // ')')
          return
        end if
        if (i == n) then
          call err%set(ERR_INPUT, 'option -o needs a file name')
          return
        end if
        i = i + 1
        call get_command_argument(i, arg)
        args%output = trim(arg)
      case default
        if (trim(arg) == '--check' .and. allow_check) then
          args%check = .true.
        else if (arg(1:1) == '-' .or. allocated(args%input)) then
          call err%set(ERR_INPUT, 'unexpected argument ''' // trim(arg) // ''' (' // usage // ')')
          return
        else
          args%input = trim(arg)
        end if
      end select
    end do
    if (.not. allocated(args%input)) then
      call err%set(ERR_INPUT, 'no input file (' // usage // ')')
      return
    end if
    if (.not. allocated(args%output)) then
      args%output = args%input(index(args%input, '/', back=.true.) + 1:)
      dot = index(args%output, '.', back=.true.)
      if (dot > 1) args%output = args%output(1:dot - 1)
      args%output = args%output // '.h5'
    end if
  end subroutine parse_cli
end module io_cli
