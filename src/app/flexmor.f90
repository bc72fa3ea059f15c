!> flexmor FILE.nml [-o OUT.h5] [-q]: run the analyses of one scene file, write one HDF5 file.
!> Exit status 0 on success; on error a one-line message on stderr and status 1 (input),
!> 2 (model), 3 (numerical failure), 4 (file system) or 5 (internal).
program flexmor_main
  use, intrinsic :: iso_fortran_env, only: error_unit
  use core_error, only: error_t, ERR_INPUT
  use core_linalg, only: single_thread_blas
  use analysis_run, only: run_t, FLEXMOR_VERSION
  implicit none
  type(run_t) :: run
  type(error_t) :: err
  character(len=:), allocatable :: input, output

  call single_thread_blas()
  call parse_arguments(input, output, run%verbose, err)
  if (err%ok()) call run%load(input, err)
  if (err%ok()) call run%execute(err)
  if (err%ok()) call run%write(output, err)
  if (.not. err%ok()) then
    write(error_unit, '(a)') 'flexmor: error: ' // err%message
    call exit_with(err%code)
  end if
  if (run%verbose) write(*, '(a,f0.3,a)') 'wrote ' // output // ' (', run%wall_time_s, ' s)'

contains

  subroutine parse_arguments(input, output, verbose, err)
    character(len=:), allocatable, intent(out) :: input, output
    logical, intent(inout) :: verbose
    type(error_t), intent(out) :: err
    character(len=4096) :: arg
    integer :: i, n, dot
    n = command_argument_count()
    i = 0
    do while (i < n)
      i = i + 1
      call get_command_argument(i, arg)
      select case (trim(arg))
      case ('-h', '--help')
        write(*, '(a)') 'usage: flexmor FILE.nml [-o OUT.h5] [-q]', &
          '  runs the static, modal and dynamic analyses FILE.nml asks for and writes one', &
          '  HDF5 file (default: FILE.h5 in the current directory). See README.md.'
        stop
      case ('--version')
        write(*, '(a)') 'flexmor ' // FLEXMOR_VERSION
        stop
      case ('-q', '--quiet')
        verbose = .false.
      case ('-o')
        if (i == n) then
          call err%set(ERR_INPUT, 'option -o needs a file name')
          return
        end if
        i = i + 1
        call get_command_argument(i, arg)
        output = trim(arg)
      case default
        if (arg(1:1) == '-' .or. allocated(input)) then
          call err%set(ERR_INPUT, 'unexpected argument ''' // trim(arg) // &
            ''' (usage: flexmor FILE.nml [-o OUT.h5] [-q])')
          return
        end if
        input = trim(arg)
      end select
    end do
    if (.not. allocated(input)) then
      call err%set(ERR_INPUT, 'no input file (usage: flexmor FILE.nml [-o OUT.h5] [-q])')
      return
    end if
    if (.not. allocated(output)) then
      output = input(index(input, '/', back=.true.) + 1:)
      dot = index(output, '.', back=.true.)
      if (dot > 1) output = output(1:dot - 1)
      output = output // '.h5'
    end if
  end subroutine parse_arguments

  subroutine exit_with(code)
    integer, intent(in) :: code
    select case (code)
    case (1); stop 1, quiet=.true.
    case (2); stop 2, quiet=.true.
    case (3); stop 3, quiet=.true.
    case (4); stop 4, quiet=.true.
    case default; stop 5, quiet=.true.
    end select
  end subroutine exit_with
end program flexmor_main
