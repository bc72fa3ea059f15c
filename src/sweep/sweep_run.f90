!> A parameter sweep under MPI (docs/sweep.md): every case is an independent flexmor run of the
!> base scene with the case's values set; results go to one HDF5 file.
!>
!> Rank 0 owns the file and hands out cases one at a time (dynamic scheduling: a reduced case
!> costs a hundredth of a full one, so a static split would leave ranks idle); ranks 1..N-1 run
!> them. Rank 0 writes and flushes each result as it arrives, so a finished case is durable
!> before its rank gets the next one, and a rerun skips every case already in the file.
!> Why one writer: a per-case flush is collective in parallel HDF5, which would make every rank
!> wait for the slowest case; writing one row costs rank 0 well under a millisecond.
!> With one rank, rank 0 runs the cases itself. With &sweep case_files each rank also writes
!> the result file of every case it runs (the flexmor program's, docs/output.md) into one
!> folder that rank 0 creates first.
module sweep_run
  use, intrinsic :: iso_c_binding, only: c_int
  use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
  use mpi_f08, only: MPI_Comm, MPI_Status, MPI_Comm_rank, MPI_Comm_size, MPI_Send, MPI_Recv, &
    MPI_Iprobe, MPI_Bcast, MPI_INTEGER, MPI_DOUBLE_PRECISION, MPI_CHARACTER, MPI_ANY_SOURCE, &
    MPI_ANY_TAG, MPI_Wtime
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_INPUT
  use core_strings, only: int_str, approx_str, real_str
  use io_namelist, only: nml_file_t
  use io_sweep_file, only: sweep_file_t, sweep_attrs_t, SWEEP_MESSAGE_LEN
  use io_fs, only: make_folder
  use core_version, only: FLEXMOR_VERSION
  use analysis_run, only: run_t
  use sweep_spec, only: sweep_spec_t, apply_case
  use sweep_metrics, only: METRIC_NAMES, METRIC_UNITS, case_metrics, not_available, &
    check_metric_node
  implicit none
  private
  public :: run_sweep, check_sweep

  !> A failed case's message, as long as the file keeps.
  integer, parameter :: MESSAGE_LEN = SWEEP_MESSAGE_LEN
  integer, parameter :: TAG_WORK = 1, TAG_STOP = 2, TAG_RESULT = 3, TAG_MESSAGE = 4
  !> Result record sent by a worker: case, status, wall time, then the metrics.
  integer, parameter :: HEAD = 3

  interface
    !> Rank 0 sleeps between probes, so that it does not take a core from the workers.
    function c_usleep(us) bind(C, name='usleep') result(rc)
      import :: c_int
      integer(c_int), value :: us
      integer(c_int) :: rc
    end function c_usleep
  end interface

  !> One case's outcome.
  type :: outcome_t
    integer :: icase = 0, status = 0, rank = 0
    real(wp) :: wall_time_s = 0.0_wp
    real(wp) :: metrics(size(METRIC_NAMES)) = 0.0_wp
    character(len=MESSAGE_LEN) :: message = ''
  end type outcome_t

  !> What rank 0 tracks to report progress.
  type :: progress_t
    integer :: total = 0, done = 0, failed = 0, skipped = 0
    real(wp) :: t_start = 0.0_wp, t_last = 0.0_wp
    logical :: verbose = .true.
  end type progress_t

contains

  !> Run the sweep of `spec` into `out_path` on all ranks of `comm`. Every rank returns the
  !> same error state (input errors are found identically everywhere; rank 0's file errors are
  !> broadcast).
  subroutine run_sweep(spec, out_path, comm, verbose, err)
    type(sweep_spec_t), intent(in) :: spec
    character(len=*), intent(in) :: out_path
    type(MPI_Comm), intent(in) :: comm
    logical, intent(in) :: verbose
    type(error_t), intent(out) :: err
    type(nml_file_t) :: base
    type(sweep_file_t) :: file
    type(progress_t) :: progress
    integer, allocatable :: pending(:)
    integer :: rank, n_ranks, flag(1)
    character(len=:), allocatable :: folder

    call MPI_Comm_rank(comm, rank)
    call MPI_Comm_size(comm, n_ranks)
    call base%load(spec%base_path, err)
    if (err%ok()) call validate(spec, base, err)
    if (.not. err%ok()) return
    folder = case_folder(spec, out_path)
    flag = 0
    if (rank == 0) then
      ! The folder after the file: an -o that is no sweep file is refused leaving nothing.
      call open_results(spec, base, out_path, folder, file, pending, err)
      if (err%ok() .and. len(folder) > 0) then
        call make_folder(folder, err)
        if (.not. err%ok()) call file%close()
      end if
      if (.not. err%ok()) flag = 1
    end if
    call MPI_Bcast(flag, 1, MPI_INTEGER, 0, comm)
    if (flag(1) /= 0) then
      if (rank /= 0) call err%set(ERR_INPUT, 'rank 0 could not open the result file')
      return
    end if
    if (rank == 0) then
      progress%verbose = verbose
      progress%total = spec%n_cases()
      progress%skipped = spec%n_cases() - size(pending)
      progress%t_start = MPI_Wtime()
      progress%t_last = progress%t_start
      if (verbose) write(*, '(a)') 'sweep: ' // int_str(spec%n_cases()) // ' cases, ' // &
        int_str(progress%skipped) // ' already in ' // out_path // ', ' // &
        int_str(n_ranks) // ' rank(s)'
      if (n_ranks == 1) then
        call run_serial(spec, base, folder, pending, file, progress, err)
      else
        call run_master(comm, n_ranks, pending, file, progress, err)
      end if
      call report(progress, .true.)
      call file%close()
    else
      call run_worker(spec, base, folder, comm, rank)
    end if
    flag = merge(0, 1, err%ok())
    call MPI_Bcast(flag, 1, MPI_INTEGER, 0, comm)
    if (flag(1) /= 0 .and. rank /= 0) call err%set(ERR_INPUT, 'the sweep failed on rank 0')
  end subroutine run_sweep

  !> The folder of the cases' result files: the result file's path without its extension and
  !> with '_cases' ('' without &sweep case_files).
  function case_folder(spec, out_path) result(folder)
    type(sweep_spec_t), intent(in) :: spec
    character(len=*), intent(in) :: out_path
    character(len=:), allocatable :: folder
    integer :: dot
    folder = ''
    if (.not. spec%case_files) return
    dot = index(out_path, '.', back=.true.)
    if (dot <= index(out_path, '/', back=.true.) + 1) dot = len(out_path) + 1
    folder = out_path(:dot - 1) // '_cases'
  end function case_folder

  !> 'motion.phi1.end = 0.5, link.link1.n_elements = 4': the case's parameters, for its file.
  function case_overrides(spec, icase) result(text)
    type(sweep_spec_t), intent(in) :: spec
    integer, intent(in) :: icase
    character(len=:), allocatable :: text
    integer :: j
    text = ''
    do j = 1, spec%n_parameters()
      if (j > 1) text = text // ', '
      text = text // spec%names(j)%s // ' = ' // real_str(spec%values(icase, j))
    end do
  end function case_overrides

  !> folder/case_0007.h5: case icase of n, numbered from 1 with as many digits as n has.
  function case_file(folder, icase, n) result(path)
    character(len=*), intent(in) :: folder
    integer, intent(in) :: icase, n
    character(len=:), allocatable :: path
    character(len=16) :: fmt
    character(len=24) :: num
    write(fmt, '(a,i0,a,i0,a)') '(i', len(int_str(n)), '.', len(int_str(n)), ')'
    write(num, fmt) icase
    path = folder // '/case_' // trim(num) // '.h5'
  end function case_file

  !> The sweep's own input errors, without running anything (flexmor-sweep --check).
  subroutine check_sweep(spec, err)
    type(sweep_spec_t), intent(in) :: spec
    type(error_t), intent(out) :: err
    type(nml_file_t) :: base
    call base%load(spec%base_path, err)
    if (err%ok()) call validate(spec, base, err)
  end subroutine check_sweep

  !> Input errors of the sweep itself, found before any work: every parameter must name a
  !> variable the scene reader knows (an unknown one is reported by the reader as unknown).
  subroutine validate(spec, base, err)
    type(sweep_spec_t), intent(in) :: spec
    type(nml_file_t), intent(in) :: base
    type(error_t), intent(inout) :: err
    type(nml_file_t) :: scene_file
    type(run_t) :: run
    type(error_t) :: case_err
    call apply_case(spec, base, 1, scene_file, err)
    if (.not. err%ok()) return
    run%verbose = .false.
    call run%load_parsed(scene_file, case_err)
    if (.not. case_err%ok()) then
      if (index(case_err%message, 'unknown variable') > 0) then
        call err%set(ERR_INPUT, spec%path // ': a &parameter name is not a scene variable: ' // &
          case_err%message)
      end if
      return
    end if
    call check_metric_node(run, spec%node, err)
    if (.not. err%ok()) call err%prefix(spec%path // ': ')
  end subroutine validate

  subroutine open_results(spec, base, out_path, folder, file, pending, err)
    type(sweep_spec_t), intent(in) :: spec
    type(nml_file_t), intent(in) :: base
    character(len=*), intent(in) :: out_path, folder
    type(sweep_file_t), intent(inout) :: file
    integer, allocatable, intent(out) :: pending(:)
    type(error_t), intent(inout) :: err
    type(sweep_attrs_t) :: attrs
    integer, allocatable :: status(:)
    integer :: i
    logical :: exists
    inquire(file=out_path, exist=exists)
    if (exists) then
      call file%open_existing(out_path, spec%text, err)
      if (.not. err%ok()) return
      status = file%status()
    else
      attrs%flexmor_version = FLEXMOR_VERSION
      attrs%sweep_input = spec%text
      attrs%sweep_file = spec%path
      attrs%base_input = base%text
      attrs%base_scene = spec%base_path
      attrs%mode = spec%mode
      attrs%n_cases = spec%n_cases()
      attrs%n_parameters = spec%n_parameters()
      attrs%seed = spec%seed
      attrs%node = spec%node
      attrs%title = spec%title
      ! Beside the result file: its name is enough for a reader.
      attrs%case_files = folder(index(folder, '/', back=.true.) + 1:)
      call file%create(out_path, attrs, spec%names, spec%values, METRIC_NAMES, err, &
        metric_units=METRIC_UNITS)
      if (.not. err%ok()) return
      allocate(status(spec%n_cases()))
      status = -1
    end if
    pending = pack([(i, i = 1, size(status))], status == -1)
  end subroutine open_results

  !> One case from start to metrics; never fails itself: a failure is the case's outcome.
  subroutine run_case(spec, base, folder, icase, rank, out)
    type(sweep_spec_t), intent(in) :: spec
    type(nml_file_t), intent(in) :: base
    character(len=*), intent(in) :: folder
    integer, intent(in) :: icase, rank
    type(outcome_t), intent(out) :: out
    type(nml_file_t) :: scene_file
    type(run_t) :: run
    type(error_t) :: err
    out%icase = icase
    out%rank = rank
    out%metrics = not_available()
    out%wall_time_s = ieee_value(1.0_wp, ieee_quiet_nan)
    call apply_case(spec, base, icase, scene_file, err)
    run%verbose = .false.
    if (err%ok()) call run%load_parsed(scene_file, err)
    if (err%ok()) call run%execute(err)
    if (err%ok()) call case_metrics(run, spec%node, out%metrics, err)
    if (err%ok() .and. len(folder) > 0) then
      run%input_overrides = case_overrides(spec, icase)
      call run%write(case_file(folder, icase, spec%n_cases()), err)
    end if
    if (err%ok()) then
      out%status = 0
      out%wall_time_s = run%wall_time_s
    else
      out%status = max(1, err%code)
      out%message = err%message
    end if
  end subroutine run_case

  subroutine run_serial(spec, base, folder, pending, file, progress, err)
    type(sweep_spec_t), intent(in) :: spec
    type(nml_file_t), intent(in) :: base
    character(len=*), intent(in) :: folder
    integer, intent(in) :: pending(:)
    type(sweep_file_t), intent(inout) :: file
    type(progress_t), intent(inout) :: progress
    type(error_t), intent(inout) :: err
    type(outcome_t) :: out
    integer :: i
    do i = 1, size(pending)
      call run_case(spec, base, folder, pending(i), 0, out)
      call record(file, out, progress, err)
      if (.not. err%ok()) return
    end do
  end subroutine run_serial

  !> Rank 0: keep every worker busy while cases remain; write each result as it arrives.
  subroutine run_master(comm, n_ranks, pending, file, progress, err)
    type(MPI_Comm), intent(in) :: comm
    integer, intent(in) :: n_ranks, pending(:)
    type(sweep_file_t), intent(inout) :: file
    type(progress_t), intent(inout) :: progress
    type(error_t), intent(inout) :: err
    type(outcome_t) :: out
    type(MPI_Status) :: st
    integer :: next, busy, worker, dummy(1)
    next = 1
    busy = 0
    do worker = 1, n_ranks - 1
      if (next <= size(pending)) then
        call MPI_Send([pending(next)], 1, MPI_INTEGER, worker, TAG_WORK, comm)
        next = next + 1
        busy = busy + 1
      end if
    end do
    do while (busy > 0)
      call receive_outcome(comm, out, st)
      busy = busy - 1
      ! A write error ends the hand-out but the busy workers' results are still collected.
      if (err%ok()) call record(file, out, progress, err)
      if (next <= size(pending) .and. err%ok()) then
        call MPI_Send([pending(next)], 1, MPI_INTEGER, st%MPI_SOURCE, TAG_WORK, comm)
        next = next + 1
        busy = busy + 1
      end if
    end do
    dummy = 0
    do worker = 1, n_ranks - 1
      call MPI_Send(dummy, 1, MPI_INTEGER, worker, TAG_STOP, comm)
    end do
  end subroutine run_master

  subroutine receive_outcome(comm, out, st)
    type(MPI_Comm), intent(in) :: comm
    type(outcome_t), intent(out) :: out
    type(MPI_Status), intent(out) :: st
    type(MPI_Status) :: st2
    real(wp) :: buf(HEAD + size(METRIC_NAMES))
    logical :: arrived
    integer(c_int) :: rc
    integer :: k
    outer: do
      ! Open MPI reports a message that has arrived only after a few probes (its progress
      ! engine runs inside them): probing once per sleep cost a worker about 4.5 ms per case.
      do k = 1, 5
        call MPI_Iprobe(MPI_ANY_SOURCE, TAG_RESULT, comm, arrived, st)
        if (arrived) exit outer
      end do
      rc = c_usleep(500_c_int)
    end do outer
    call MPI_Recv(buf, size(buf), MPI_DOUBLE_PRECISION, st%MPI_SOURCE, TAG_RESULT, comm, st)
    call MPI_Recv(out%message, MESSAGE_LEN, MPI_CHARACTER, st%MPI_SOURCE, TAG_MESSAGE, comm, st2)
    out%icase = nint(buf(1))
    out%status = nint(buf(2))
    out%wall_time_s = buf(3)
    out%metrics = buf(HEAD + 1:)
    out%rank = st%MPI_SOURCE
  end subroutine receive_outcome

  !> Ranks 1..N-1: run the cases rank 0 sends until it says stop.
  subroutine run_worker(spec, base, folder, comm, rank)
    type(sweep_spec_t), intent(in) :: spec
    type(nml_file_t), intent(in) :: base
    character(len=*), intent(in) :: folder
    type(MPI_Comm), intent(in) :: comm
    integer, intent(in) :: rank
    type(outcome_t) :: out
    type(MPI_Status) :: st
    integer :: icase(1)
    do
      call MPI_Recv(icase, 1, MPI_INTEGER, 0, MPI_ANY_TAG, comm, st)
      if (st%MPI_TAG == TAG_STOP) exit
      call run_case(spec, base, folder, icase(1), rank, out)
      call MPI_Send([real(out%icase, wp), real(out%status, wp), out%wall_time_s, out%metrics], &
        HEAD + size(METRIC_NAMES), MPI_DOUBLE_PRECISION, 0, TAG_RESULT, comm)
      call MPI_Send(out%message, MESSAGE_LEN, MPI_CHARACTER, 0, TAG_MESSAGE, comm)
    end do
  end subroutine run_worker

  subroutine record(file, out, progress, err)
    type(sweep_file_t), intent(inout) :: file
    type(outcome_t), intent(in) :: out
    type(progress_t), intent(inout) :: progress
    type(error_t), intent(inout) :: err
    call file%write_case(out%icase, out%status, trim(out%message), out%wall_time_s, out%rank, &
      out%metrics, err)
    progress%done = progress%done + 1
    if (out%status /= 0) progress%failed = progress%failed + 1
    if (out%status /= 0 .and. progress%verbose) write(*, '(a)') 'sweep: case ' // &
      int_str(out%icase) // ' failed: ' // trim(out%message)
    call report(progress, .false.)
  end subroutine record

  !> done/total, failures, rate and ETA, at most every 5 s (and at the end).
  subroutine report(progress, final)
    type(progress_t), intent(inout) :: progress
    logical, intent(in) :: final
    real(wp) :: now, rate, eta
    integer :: left
    if (.not. progress%verbose) return
    now = MPI_Wtime()
    if (.not. final .and. now - progress%t_last < 5.0_wp) return
    progress%t_last = now
    rate = progress%done / max(now - progress%t_start, 1.0e-9_wp)
    left = progress%total - progress%skipped - progress%done
    eta = left / max(rate, 1.0e-12_wp)
    write(*, '(a)') 'sweep: ' // int_str(progress%skipped + progress%done) // '/' // &
      int_str(progress%total) // ' done, ' // int_str(progress%failed) // ' failed, ' // &
      approx_str(rate) // ' cases/s, ETA ' // approx_str(eta) // ' s'
    flush(6)
  end subroutine report
end module sweep_run
