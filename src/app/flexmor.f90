!> flexmor FILE.nml [-o OUT.h5] [-q]: run the analyses of one scene file, write one HDF5 file.
!> Exit status 0 on success; on error a one-line message on stderr and status 1 (input),
!> 2 (model), 3 (numerical failure), 4 (file system) or 5 (internal); interrupted by SIGINT or
!> SIGTERM, one line and 130 or 143, leaving no result file.
program flexmor_main
  use, intrinsic :: iso_fortran_env, only: error_unit
  use core_kinds, only: wp
  use core_error, only: error_t
  use core_linalg, only: single_thread_blas, steady_heap
  use io_cli, only: cli_args_t, parse_cli
  use io_fs, only: check_output_path, install_interrupt_guard
  use core_version, only: FLEXMOR_VERSION
  use core_strings, only: approx_str
  use analysis_run, only: run_t
  implicit none
  type(run_t) :: run
  type(error_t) :: err
  type(cli_args_t) :: args
  integer :: i

  call single_thread_blas()
  call steady_heap()
  call parse_cli('usage: flexmor FILE.nml [-o OUT.h5] [-q]', [character(len=80) :: &
    '  runs the static, modal and dynamic analyses FILE.nml asks for and writes one', &
    '  HDF5 file (default: FILE.h5 in the current directory). See README.md.', &
    '  --schema prints every scene variable (group, name, type, unit, default, ...).'], &
    'flexmor ' // FLEXMOR_VERSION, .false., args, err)
  if (args%done) stop
  run%verbose = args%verbose
  call set_progress_interval(run)
  if (err%ok()) call install_interrupt_guard('flexmor', 'no result file written', err)
  if (err%ok()) call check_output_path(args%output, err, input=args%input)
  if (err%ok()) call run%load(args%input, err)
  if (err%ok()) call run%execute(err)
  if (err%ok()) call run%write(args%output, err)
  if (.not. err%ok()) then
    write(error_unit, '(a)') 'flexmor: error: ' // err%message
    select case (err%code)
    case (1); stop 1, quiet=.true.
    case (2); stop 2, quiet=.true.
    case (3); stop 3, quiet=.true.
    case (4); stop 4, quiet=.true.
    case default; stop 5, quiet=.true.
    end select
  end if
  if (allocated(run%warnings)) write(error_unit, '(a)') &
    ('flexmor: warning: ' // run%warnings(i)%s, i = 1, size(run%warnings))
  if (run%verbose) write(*, '(a)') 'wrote ' // args%output // ' (' // &
    approx_str(run%wall_time_s) // ' s)'

contains

  !> $FLEXMOR_PROGRESS_INTERVAL [s], when set to a positive number, replaces the 2 s between
  !> progress lines (for tests, and for logs that want more or fewer lines).
  subroutine set_progress_interval(run)
    type(run_t), intent(inout) :: run
    character(len=64) :: buf
    integer :: n, stat
    real(wp) :: interval
    call get_environment_variable('FLEXMOR_PROGRESS_INTERVAL', buf, n, stat)
    if (stat /= 0 .or. n == 0) return
    read(buf, *, iostat=stat) interval
    if (stat == 0 .and. interval > 0) run%progress%interval = interval
  end subroutine set_progress_interval
end program flexmor_main
