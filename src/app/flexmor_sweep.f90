!> flexmor-sweep SWEEP.nml [-o OUT.h5] [-q] [--check]: run a parameter sweep (docs/sweep.md) on all
!> ranks of MPI_COMM_WORLD (mpirun -n N, or alone as one rank) into one HDF5 file. Rerunning on
!> an existing file resumes it. Exit status as flexmor: 0 ok (failed cases are results, not
!> errors), 1 input, 4 file system, 5 internal; rank 0 prints the message.
program flexmor_sweep_main
  use, intrinsic :: iso_fortran_env, only: error_unit
  use mpi_f08, only: MPI_Init, MPI_Finalize, MPI_Comm_rank, MPI_COMM_WORLD
  use core_error, only: error_t, ERR_INPUT
  use core_linalg, only: single_thread_blas
  use analysis_run, only: FLEXMOR_VERSION
  use sweep_spec, only: sweep_spec_t
  use sweep_run, only: run_sweep, check_sweep
  implicit none
  type(sweep_spec_t) :: spec
  type(error_t) :: err
  character(len=:), allocatable :: input, output
  logical :: verbose, check_only
  integer :: rank, code

  call MPI_Init()
  call MPI_Comm_rank(MPI_COMM_WORLD, rank)
  call single_thread_blas()
  verbose = rank == 0
  check_only = .false.
  call parse_arguments(input, output, verbose, check_only, err)
  ! --help and --version leave no input: nothing to run.
  if (err%ok() .and. len(input) > 0) call spec%load(input, err)
  if (err%ok() .and. len(input) > 0) then
    if (check_only) then
      call check_sweep(spec, err)
      if (err%ok() .and. rank == 0) call list_cases(spec)
    else
      call run_sweep(spec, output, MPI_COMM_WORLD, verbose, err)
    end if
  end if
  code = 0
  if (.not. err%ok()) then
    if (rank == 0) write(error_unit, '(a)') 'flexmor-sweep: error: ' // err%message
    code = err%code
  end if
  call MPI_Finalize()
  select case (code)
  case (0)
  case (1); stop 1, quiet=.true.
  case (4); stop 4, quiet=.true.
  case default; stop 5, quiet=.true.
  end select

contains

  !> --check: what the sweep would run, one line per case.
  subroutine list_cases(spec)
    type(sweep_spec_t), intent(in) :: spec
    integer :: i, j
    write(*, '(a,i0,a)') 'sweep: ', spec%n_cases(), ' cases of ' // spec%base_path // &
      ' (mode ' // spec%mode // '); the input is valid'
    write(*, '(a6,*(2x,a))') 'case', (spec%names(j)%s, j = 1, spec%n_parameters())
    do i = 1, spec%n_cases()
      write(*, '(i6,*(2x,g0.8))') i, spec%values(i, :)
    end do
  end subroutine list_cases

  subroutine parse_arguments(input, output, verbose, check_only, err)
    character(len=:), allocatable, intent(out) :: input, output
    logical, intent(inout) :: verbose, check_only
    type(error_t), intent(out) :: err
    character(len=*), parameter :: usage = &
      'usage: flexmor-sweep SWEEP.nml [-o OUT.h5] [-q] [--check]'
    character(len=4096) :: arg
    integer :: i, n, dot
    n = command_argument_count()
    i = 0
    do while (i < n)
      i = i + 1
      call get_command_argument(i, arg)
      select case (trim(arg))
      case ('-h', '--help')
        if (verbose) write(*, '(a)') usage, &
          '  runs every case of SWEEP.nml (under mpirun: on all ranks) and writes one HDF5', &
          '  file (default: SWEEP.h5 in the current directory); rerun to resume.', &
          '  --check: validate the sweep and list its cases without running. See docs/sweep.md.'
        output = ''
        input = ''
        return
      case ('--version')
        if (verbose) write(*, '(a)') 'flexmor-sweep ' // FLEXMOR_VERSION
        output = ''
        input = ''
        return
      case ('-q', '--quiet')
        verbose = .false.
      case ('--check')
        check_only = .true.
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
          call err%set(ERR_INPUT, 'unexpected argument ''' // trim(arg) // ''' (' // usage // ')')
          return
        end if
        input = trim(arg)
      end select
    end do
    if (.not. allocated(input)) then
      call err%set(ERR_INPUT, 'no sweep file (' // usage // ')')
      return
    end if
    if (.not. allocated(output)) then
      output = input(index(input, '/', back=.true.) + 1:)
      dot = index(output, '.', back=.true.)
      if (dot > 1) output = output(1:dot - 1)
      output = output // '.h5'
    end if
  end subroutine parse_arguments
end program flexmor_sweep_main
