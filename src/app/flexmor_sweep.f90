!> flexmor-sweep SWEEP.nml [-o OUT.h5] [-q] [--check]: run a parameter sweep (docs/sweep.md) on
!> all ranks of MPI_COMM_WORLD (mpirun -n N, or alone as one rank) into one HDF5 file. Rerunning
!> on an existing file resumes it. Exit status as flexmor: 0 ok (failed cases are results, not
!> errors), 1 input, 4 file system, 5 internal; rank 0 prints the message. SIGINT/SIGTERM: one
!> line, exit 130/143, the finished cases stay in the file (rerun to resume).
program flexmor_sweep_main
  use, intrinsic :: iso_fortran_env, only: error_unit
  use mpi_f08, only: MPI_Init, MPI_Finalize, MPI_Comm_rank, MPI_Barrier, MPI_COMM_WORLD
  use core_error, only: error_t, ERR_IO
  use core_linalg, only: single_thread_blas, steady_heap
  use io_cli, only: cli_args_t, parse_cli
  use io_fs, only: install_interrupt_guard, same_file
  use core_version, only: FLEXMOR_VERSION
  use sweep_spec, only: sweep_spec_t
  use sweep_run, only: run_sweep, check_sweep
  implicit none
  type(sweep_spec_t) :: spec
  type(error_t) :: err, guard_err
  type(cli_args_t) :: args
  integer :: rank, code

  call MPI_Init()
  call MPI_Comm_rank(MPI_COMM_WORLD, rank)
  call single_thread_blas()
  call steady_heap()
  args%verbose = rank == 0
  call parse_cli('usage: flexmor-sweep SWEEP.nml [-o OUT.h5] [-q] [--check]', &
    [character(len=90) :: &
    '  runs every case of SWEEP.nml (under mpirun: on all ranks) and writes one HDF5', &
    '  file (default: SWEEP.h5 in the current directory); rerun to resume.', &
    '  --check: validate the sweep and list its cases without running. See docs/sweep.md.'], &
    'flexmor-sweep ' // FLEXMOR_VERSION, .true., args, err)
  if (err%ok() .and. .not. args%done) call spec%load(args%input, err)
  if (err%ok() .and. .not. args%done) then
    if (args%check) then
      call check_sweep(spec, err)
      if (err%ok() .and. rank == 0) call list_cases(spec)
    else
      ! The sweep file is flushed after every case: an interrupt keeps what is done.
      call install_interrupt_guard('flexmor-sweep', 'the finished cases are kept in ' // &
        args%output // '; rerun the same command to resume', err, silent=rank /= 0)
      ! An existing result file is resumed, anything else refused with 'remove it': not
      ! advice to give about the sweep file or its base scene.
      if (err%ok()) then
        if (same_file(args%output, args%input)) then
          call err%set(ERR_IO, "cannot write the sweep result file '" // args%output // &
            "': it is the sweep file (give another name, e.g. -o sweep.h5)")
        else if (same_file(args%output, spec%base_path)) then
          call err%set(ERR_IO, "cannot write the sweep result file '" // args%output // &
            "': it is the base scene '" // spec%base_path // "' (give another name)")
        end if
      end if
      if (err%ok()) call run_sweep(spec, args%output, MPI_COMM_WORLD, args%verbose, err)
    end if
  end if
  ! The run is over: a SIGTERM from mpiexec now (another rank has exited with an error first)
  ! must not claim that finished cases are kept: say nothing, the error line says it all.
  call install_interrupt_guard('flexmor-sweep', '', guard_err, silent=.true.)
  code = 0
  if (.not. err%ok()) then
    if (rank == 0) write(error_unit, '(a)') 'flexmor-sweep: error: ' // err%message
    flush(error_unit)
    code = err%code
  end if
  ! No rank exits (which makes mpiexec stop the others) before rank 0 has said why.
  call MPI_Barrier(MPI_COMM_WORLD)
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
end program flexmor_sweep_main
