!> Scalar results of one sweep case, taken from a finished run (docs/sweep.md, "Metrics").
!> A metric that does not apply (no output after the motion, a full run's error estimate) is
!> NaN, written explicitly: the file documents NaN as "not applicable or not run".
module sweep_metrics
  use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_INPUT
  use analysis_run, only: run_t
  use model_control, only: LAW_PID
  implicit none
  private
  public :: METRIC_NAMES, METRIC_UNITS, case_metrics, not_available, check_metric_node

  !> The control errors are in the measured outputs' units (m or rad), the largest over all
  !> PID controllers: NaN without one (a user law's error is its own).
  !> error_check, error_check_rotation: the largest distance and rotation from the second run
  !> of &dynamic error_check (NaN without it, and the rotation without nodes that have one).
  character(len=20), parameter :: METRIC_NAMES(10) = [character(len=20) :: &
    'max_tip_deflection', 'residual_vibration', 'n_steps', 'n_model_evals', 'error_estimate', &
    'n_modes', 'max_control_error', 'final_control_error', 'error_check', &
    'error_check_rotation']
  character(len=3), parameter :: METRIC_UNITS(10) = [character(len=3) :: 'm', 'm', '', '', &
    'm', '', '', '', 'm', 'rad']

contains

  !> NaN for every metric.
  function not_available() result(m)
    real(wp) :: m(size(METRIC_NAMES))
    m = ieee_value(1.0_wp, ieee_quiet_nan)
  end function not_available

  !> The sweep's node must exist and the scene must run a dynamic analysis.
  subroutine check_metric_node(run, node, err)
    type(run_t), intent(in) :: run
    character(len=*), intent(in) :: node
    type(error_t), intent(inout) :: err
    if (.not. run%scene%dynamic%active) then
      call err%set(ERR_INPUT, 'the base scene has no &dynamic group: the sweep metrics ' // &
        'need a dynamic analysis')
    else if (run%dyn%model%find_node(node) == 0) then
      call err%set(ERR_INPUT, 'group &sweep: variable ''node'': the base scene has no node ''' &
        // node // '''')
    end if
  end subroutine check_metric_node

  !> Metrics of a finished dynamic run. The rigid-link reference is the kinematics with every
  !> dynamic coordinate zero, solved at each output time (after the run, so it costs nothing
  !> during the integration).
  subroutine case_metrics(run, node, metrics, err)
    type(run_t), intent(inout) :: run
    character(len=*), intent(in) :: node
    real(wp), intent(out) :: metrics(:)
    type(error_t), intent(out) :: err
    real(wp), allocatable :: deflection(:), zero(:)
    real(wp) :: motion_end
    logical, allocatable :: pid(:)
    integer :: k, in, nt
    metrics = not_available()
    associate (dyn => run%dyn, model => run%dyn%model)
      in = model%find_node(node)
      nt = size(run%time)
      allocate(deflection(nt), zero(model%n_dy))
      zero = 0.0_wp
      ! The kinematics was left at the run's end: Newton from there to the start of a large
      ! motion fails (the sweep example's case with the joints turned by 3 pi / 4 and pi / 2).
      ! The run's first configuration is next to the rigid one; each later rigid solution
      ! starts from the one before.
      call dyn%kin%restart_from(dyn%x_hist(:, 1))
      do k = 1, nt
        call dyn%kin%solve(model, dyn%full_q(run%time(k), zero), err)
        if (.not. err%ok()) return
        deflection(k) = model%translation(in, dyn%x_hist(:, k) - dyn%kin%x)
      end do
      metrics(1) = maxval(deflection)
      motion_end = 0.0_wp
      ! The last change of any law (a ramp or harmonic law changes only at its start).
      do k = 1, model%n_motions
        motion_end = max(motion_end, maxval([0.0_wp, model%motions(k)%breakpoints()]))
      end do
      if (any(run%time > motion_end)) metrics(2) = maxval(deflection, mask=run%time > motion_end)
      metrics(3) = real(run%stats%n_steps, wp)
      metrics(4) = real(dyn%n_evals, wp)
      metrics(6) = 0.0_wp
      if (allocated(run%red)) then
        metrics(6) = real(run%red%basis%k(), wp)
        if (run%red%has_estimate) metrics(5) = run%red%estimate_max()
      end if
      if (allocated(run%check_distance)) metrics(9) = maxval(run%check_distance)
      if (allocated(run%check_rotation)) metrics(10) = maxval(run%check_rotation)
      ! A user law computes its errors itself: only the PIDs' r - y are known (the history's
      ! rows of the others hold 0).
      if (allocated(run%control%error_hist) .and. allocated(model%controllers)) then
        pid = model%controllers%law_kind == LAW_PID
        if (any(pid) .and. size(run%control%error_hist, 1) == size(pid)) then
          metrics(7) = maxval(abs(run%control%error_hist), mask=spread(pid, 2, nt))
          metrics(8) = maxval(abs(run%control%error_hist(:, nt)), mask=pid)
        end if
      end if
    end associate
  end subroutine case_metrics
end module sweep_metrics
