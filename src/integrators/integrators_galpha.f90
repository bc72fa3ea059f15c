!> Generalized-alpha method (Chung & Hulbert 1993) for q'' = a(t, q, v), in the form of
!> Arnold & Brüls (2007) with the acceleration-like variable `acc`:
!>
!>     q+   = q + h v + h^2 (1/2 - beta) acc + h^2 beta acc+
!>     v+   = v + h (1 - gamma) acc + h gamma acc+
!>     (1 - alpha_m) acc+ + alpha_m acc = (1 - alpha_f) qdd+ + alpha_f qdd,   qdd+ = a(t+, q+, v+)
!>
!> with alpha_m = (2 rho - 1)/(rho + 1), alpha_f = rho/(rho + 1), gamma = 1/2 + alpha_f - alpha_m,
!> beta = (gamma + 1/2)^2 / 4: second order, unconditionally stable for linear problems, and
!> rho = rho_inf is the spectral radius at h omega -> infinity (1: no numerical damping, 0:
!> unresolved modes annihilated in one step). Newton iterates on qdd+.
!>
!> Two step controls ('galpha' and 'galpha_adaptive'):
!> - fixed: steps are dt, shortened evenly so that output times and breakpoints are landed on
!>   exactly; a step whose Newton fails is halved, locally and at most max_halvings times;
!> - adaptive: the local error of q is estimated in every step (docs/theory.md section 6) and
!>   the step chosen to keep its norm (the system's error_norm, rtol and atol) below 1, dt the first
!>   step; output times inside a step are interpolated (cubic Hermite), breakpoints landed on.
!>
!> The Newton matrix I - c_q da/dq - c_v da/dv comes from sys%jacobian, or from the system
!> itself when it offers an iteration solver (the sparse path: no dense n x n matrices), and
!> is kept across iterations and steps: the Jacobian is re-evaluated only after a slow or
!> failed Newton solve or a restart, the matrix refactored when h changes (adaptive: by more
!> than refactor_ratio). Newton stops when its update of q and v, times the contraction rate
!> (kept across steps, as in CVODE), is below a tenth of rtol/atol.
module integrators_galpha
  use core_kinds, only: wp, i8
  use core_strings, only: int_str, real_str
  use core_linalg, only: lu_factor, lu_solve_vector
  use core_error, only: error_t, ERR_NUMERIC
  use integrators_system, only: ode2_system_t, integrator_options_t, integrator_stats_t, &
    INTEGRATOR_GALPHA_ADAPTIVE
  use integrators_base, only: integrator_t
  use core_progress, only: progress_t
  implicit none
  private
  public :: galpha_solver_t

  integer, parameter :: max_newton_iters = 8
  !> Converging in more iterations than this makes the next step refresh the Jacobian.
  integer, parameter :: slow_newton_iters = 3
  !> Newton stops when the change of q and v is below this fraction of rtol/atol.
  real(wp), parameter :: newton_tol = 0.1_wp
  !> A contraction rate above this counts as divergence.
  real(wp), parameter :: max_newton_rate = 0.9_wp
  !> The kept rate decays by this factor per iteration unless a slower one is observed
  !> (CVODE's CRDOWN).
  real(wp), parameter :: rate_decay = 0.3_wp
  integer, parameter :: rate_lifetime = 20
  !> A system-solver step that its matrix's measured rate kept from stopping after one
  !> correction refactors the matrix at its end if it is this many steps old (take_step).
  integer, parameter :: refactor_age = 2
  !> Local step halvings after failed steps before giving up (fixed step).
  integer, parameter :: max_halvings = 10
  !> Successful steps at a halved step size before trying the double again (fixed step).
  integer, parameter :: steps_before_growth = 2
  !> A shortened step this close to the distance left (relative) lands on the target.
  real(wp), parameter :: landing_slack = 1.0e-8_wp
  !> Adaptive step: safety factor, limits of the step ratio, and the relative change of h that
  !> makes the Newton matrix be refactored. CVODE waits for 0.3 on gamma; here a refactorisation
  !> costs less than the iterations a mismatched matrix adds (two-link, rtol 1e-6: 0.25 -> 0.05
  !> took 12,315 -> 9,273 evaluations and 1,023 -> 309 Jacobian refreshes for the same steps).
  real(wp), parameter :: safety = 0.85_wp, grow_max = 2.0_wp, shrink_min = 0.2_wp
  real(wp), parameter :: refactor_ratio = 0.05_wp
  !> After an accepted step, a proposed ratio in [keep_above, grow_min) keeps the step: a new
  !> step costs a refactorisation and the Newton rate (the next step then verifies with a
  !> second correction), more than the few per cent of step length it would gain or the
  !> slightly smaller error it would buy (two-link, 8 el/link, rtol 1e-6: 8,303 -> 5,971
  !> evaluations and 264 -> 88 rejected steps, tip error 1.1e-5 -> 9.0e-6 m).
  real(wp), parameter :: keep_above = 0.9_wp, grow_min = 1.5_wp
  !> Adaptive step: consecutive failures (error test or Newton) at one time before giving up.
  integer, parameter :: max_failures = 15

  integer, parameter :: STEP_OK = 0, STEP_NEWTON_FAILED = 1, STEP_RECOVERABLE = 2, &
    STEP_FATAL = 3

  type, extends(integrator_t) :: galpha_solver_t
    private
    logical :: adaptive = .false.
    integer :: n = 0
    real(wp) :: dt = 0, rtol = 0, atol = 0, max_step = 0
    real(wp) :: alpha_m = 0, alpha_f = 0, beta = 0, gamma = 0
    !> The local error of q is err_coef h^2 (qdd+ - qdd) (docs/theory.md section 6).
    real(wp) :: err_coef = 0
    integer(i8) :: max_steps = 0
    !> Accepted state: time, position, velocity, true and acceleration-like accelerations.
    real(wp) :: t = 0
    real(wp), allocatable :: q(:), v(:), qdd(:), acc(:)
    !> The accepted state before the last step (for interpolation).
    real(wp) :: t_prev = 0, h_last_prev = 0
    real(wp), allocatable :: q_prev(:), v_prev(:), qdd_prev(:), acc_prev(:)
    !> Accelerations at the start of the last accepted step and its length: Newton starts
    !> from qdd extrapolated linearly through them (h_old = 0: no such step since a restart).
    real(wp), allocatable :: qdd_old(:)
    !> take_step's vectors (automatic arrays would be a heap allocation each, per step).
    real(wp), allocatable :: work(:, :)
    real(wp) :: h_old = 0
    !> Step that produced `acc`: acc approximates qdd at t + (alpha_m - alpha_f) h_last.
    real(wp) :: h_last = 0
    !> Adaptive: the next step to try.
    real(wp) :: h_next = 0
    !> accel is evaluated at times clamped into [t_lo, t_hi] (see the driver); no step goes
    !> past t_stop.
    real(wp) :: t_lo = -huge(1.0_wp), t_hi = huge(1.0_wp), t_stop = huge(1.0_wp)
    logical :: system_solver = .false.        !< the system solves the Newton systems
    real(wp), allocatable :: dadq(:, :), dadv(:, :)
    !> LU factors of the iteration matrix I - c_q da/dq - c_v da/dv for the step h_lu.
    real(wp), allocatable :: lu(:, :)
    integer, allocatable :: pivots(:)
    real(wp) :: h_lu = 0
    !> Newton's contraction rate, kept across steps (as CVODE's crate): the last correction
    !> times it estimates the error left, so a step can stop after one correction.
    real(wp) :: newton_rate = 1
    !> Steps since the rate was last measured: it is forgotten after rate_lifetime of them,
    !> since steps that stop after one correction do not see it grow (CVODE likewise resets
    !> it at its periodic matrix update).
    integer :: rate_age = 0
    logical :: have_jac = .false., jac_is_current = .false., refresh_jac = .true.
    logical :: lu_valid = .false.
    !> System solver: refactor before the next step at the state the last step ended on (its
    !> last evaluation), and steps since the last factorisation (see take_step).
    logical :: refactor_here = .false.
    integer :: matrix_age = 0
    integer :: halvings = 0, steps_at_level = 0
    !> The last non-zero status of accel, for the error message.
    integer :: bad_status = 0
    type(integrator_stats_t) :: stats
    type(progress_t), pointer :: progress => null()   !< polled once per step
  contains
    procedure :: start => galpha_start
    procedure :: advance => galpha_advance
    procedure :: restart => galpha_restart
    procedure :: get_stats => galpha_get_stats
    procedure :: clamped => galpha_clamped
  end type galpha_solver_t

  interface
    !> Evaluate the Jacobian when asked to, and refactor when it or the step has changed
    !> (integrators_galpha_newton).
    module subroutine refresh_iteration_matrix(this, sys, h, err)
      type(galpha_solver_t), intent(inout) :: this
      class(ode2_system_t), intent(inout) :: sys
      real(wp), intent(in) :: h
      type(error_t), intent(inout) :: err
    end subroutine refresh_iteration_matrix
    !> One step from this%t to t_new = this%t + h by Newton's method on the
    !> generalized-alpha equations; the state is updated only on success.
    module subroutine take_step(this, sys, h, t_new, outcome)
      type(galpha_solver_t), intent(inout) :: this
      class(ode2_system_t), intent(inout) :: sys
      real(wp), intent(in) :: h, t_new
      integer, intent(out) :: outcome
    end subroutine take_step
  end interface

contains

  subroutine galpha_start(this, sys, opts, t0, q, v, t_stop, t_lo, t_hi, err)
    class(galpha_solver_t), intent(inout) :: this
    class(ode2_system_t), intent(inout), target :: sys
    type(integrator_options_t), intent(in) :: opts
    real(wp), intent(in) :: t0, q(:), v(:), t_stop, t_lo, t_hi
    type(error_t), intent(inout) :: err
    real(wp) :: rho

    this%adaptive = opts%method == INTEGRATOR_GALPHA_ADAPTIVE
    this%n = size(q)
    this%dt = opts%dt
    this%rtol = opts%rtol
    this%atol = opts%atol
    this%max_step = opts%max_step
    this%max_steps = opts%max_steps
    this%progress => opts%progress
    rho = opts%rho_inf
    this%alpha_m = (2 * rho - 1) / (rho + 1)
    this%alpha_f = rho / (rho + 1)
    this%gamma = 0.5_wp + this%alpha_f - this%alpha_m
    this%beta = 0.25_wp * (this%gamma + 0.5_wp)**2
    this%err_coef = abs(this%beta - 0.5_wp * this%gamma + 1.0_wp / 12)
    this%stats = integrator_stats_t()
    allocate(this%q(this%n), this%v(this%n), this%qdd(this%n), this%acc(this%n))
    allocate(this%q_prev(this%n), this%v_prev(this%n), this%qdd_prev(this%n))
    allocate(this%acc_prev(this%n), this%qdd_old(this%n), this%work(this%n, 9))
    this%system_solver = sys%has_iteration_solver()
    if (.not. this%system_solver) then
      allocate(this%dadq(this%n, this%n), this%dadv(this%n, this%n), this%lu(this%n, this%n))
      allocate(this%pivots(this%n))
    end if
    this%have_jac = .false.
    this%h_next = this%dt
    call set_initial_state(this, sys, t0, q, v, t_stop, t_lo, t_hi, err)
  end subroutine galpha_start

  !> Start again after a jump of a(t, ...) at t: the acceleration history is no longer valid.
  subroutine galpha_restart(this, sys, t, q, v, t_stop, t_lo, t_hi, err)
    class(galpha_solver_t), intent(inout) :: this
    class(ode2_system_t), intent(inout) :: sys
    real(wp), intent(in) :: t, q(:), v(:), t_stop, t_lo, t_hi
    type(error_t), intent(inout) :: err
    this%stats%n_restarts = this%stats%n_restarts + 1
    ! The step that suited the end of the old segment is no guide after a jump.
    this%h_next = min(this%h_next, this%dt)
    call set_initial_state(this, sys, t, q, v, t_stop, t_lo, t_hi, err)
  end subroutine galpha_restart

  subroutine set_initial_state(this, sys, t, q, v, t_stop, t_lo, t_hi, err)
    type(galpha_solver_t), intent(inout) :: this
    class(ode2_system_t), intent(inout) :: sys
    real(wp), intent(in) :: t, q(:), v(:), t_stop, t_lo, t_hi
    type(error_t), intent(inout) :: err
    integer :: status

    this%t = t
    this%q = q
    this%v = v
    this%t_lo = t_lo
    this%t_hi = t_hi
    this%t_stop = t_stop
    call sys%accel(this%clamped(t), q, v, this%qdd, status)
    this%stats%n_rhs_evals = this%stats%n_rhs_evals + 1
    if (status /= 0) then
      call err%set(ERR_NUMERIC, 'galpha: accel returned status ' // int_str(status) // &
        ' at the initial time t = ' // real_str(t))
      return
    end if
    this%acc = this%qdd
    this%h_old = 0
    ! acc = qdd, so the step-size rescaling of acc is a no-op whatever h_last is.
    this%h_last = this%dt
    this%refresh_jac = .true.
    this%halvings = 0
    this%steps_at_level = 0
    call keep_previous(this)
  end subroutine set_initial_state

  subroutine keep_previous(this)
    type(galpha_solver_t), intent(inout) :: this
    this%t_prev = this%t
    this%q_prev = this%q
    this%v_prev = this%v
    this%qdd_prev = this%qdd
    this%acc_prev = this%acc
    this%h_last_prev = this%h_last
  end subroutine keep_previous

  !> Step to t_target and return the state there: landed on (fixed step, or a breakpoint), or
  !> interpolated within the last step (adaptive).
  subroutine galpha_advance(this, sys, t_target, q, v, err)
    class(galpha_solver_t), intent(inout) :: this
    class(ode2_system_t), intent(inout) :: sys
    real(wp), intent(in) :: t_target
    real(wp), intent(out) :: q(:), v(:)
    type(error_t), intent(inout) :: err
    real(wp) :: h
    logical :: lands
    integer :: outcome

    do while (this%t < t_target)
      if (this%stats%n_steps >= this%max_steps) then
        call err%set(ERR_NUMERIC, 'galpha: max_steps reached at t = ' // real_str(this%t))
        return
      end if
      if (this%adaptive) then
        call adaptive_step(this, sys, err)
        if (.not. err%ok()) return
        call sys%step_accepted(this%t, this%q, this%v)
        cycle
      end if
      call choose_step(this, t_target, h, lands)
      call refresh_iteration_matrix(this, sys, h, err)
      if (.not. err%ok()) return
      call keep_previous(this)
      call take_step(this, sys, h, merge(t_target, this%t + h, lands), outcome)
      select case (outcome)
      case (STEP_OK)
        call after_success(this)
        call sys%step_accepted(this%t, this%q, this%v)
      case (STEP_FATAL)
        call fatal_status(this, h, err)
        return
      case default
        call after_failure(this, outcome, h, err)
        if (.not. err%ok()) return
      end select
    end do
    if (this%t > t_target) then
      call interpolate(this, t_target, q, v)
    else
      q = this%q
      v = this%v
    end if
  end subroutine galpha_advance

  subroutine fatal_status(this, h, err)
    type(galpha_solver_t), intent(in) :: this
    real(wp), intent(in) :: h
    type(error_t), intent(inout) :: err
    call err%set(ERR_NUMERIC, 'galpha: accel returned status ' // int_str(this%bad_status) // &
      ' in the step from t = ' // real_str(this%t) // ' to ' // real_str(this%t + h))
  end subroutine fatal_status

  !> One accepted adaptive step (after as many rejected tries as it takes). The step is the
  !> proposed one, at most max_step, and stretched or cut to land on t_stop rather than leave
  !> a sliver before it.
  subroutine adaptive_step(this, sys, err)
    type(galpha_solver_t), intent(inout) :: this
    class(ode2_system_t), intent(inout) :: sys
    type(error_t), intent(inout) :: err
    real(wp) :: h, left, error_norm, t_new
    integer :: outcome, failures

    failures = 0
    do
      h = this%h_next
      if (this%max_step > 0) h = min(h, this%max_step)
      left = this%t_stop - this%t
      t_new = this%t + h
      ! Stretch by up to 25 % to land rather than leave a sliver, but not a step that was just
      ! cut after a failure (it would be stretched back to the failed one).
      if (h >= left * (1 - landing_slack) .or. (failures == 0 .and. left - h < 0.25_wp * h)) then
        h = left
        t_new = this%t_stop
      end if
      if (h <= 16 * spacing(max(abs(this%t), 1.0_wp))) then
        call err%set(ERR_NUMERIC, 'galpha_adaptive: the step became too small at t = ' // &
          real_str(this%t) // ' (' // int_str(failures) // ' failed tries)')
        return
      end if
      call refresh_iteration_matrix(this, sys, h, err)
      if (.not. err%ok()) return
      call keep_previous(this)
      call take_step(this, sys, h, t_new, outcome)
      if (outcome == STEP_FATAL) then
        call fatal_status(this, h, err)
        return
      end if
      if (outcome == STEP_OK) then
        call sys%error_norm(this%err_coef * h**2 * (this%qdd - this%qdd_prev), this%q_prev, &
          this%q, this%rtol, this%atol, error_norm)
        if (error_norm <= 1) then
          call remember_accepted(this)
          this%stats%n_steps = this%stats%n_steps + 1
          this%jac_is_current = .false.
          this%h_next = h * kept_ratio(step_ratio(error_norm, grow_max))
          call report_progress(this)
          return
        end if
        ! Rejected: back to the state before the step, shorter step.
        call restore_previous(this)
        this%stats%n_err_test_fails = this%stats%n_err_test_fails + 1
        this%h_next = h * step_ratio(error_norm, 1.0_wp)
      else
        this%stats%n_nonlin_fails = this%stats%n_nonlin_fails + 1
        if (outcome == STEP_NEWTON_FAILED .and. .not. this%jac_is_current) then
          this%refresh_jac = .true.
        else
          this%h_next = 0.25_wp * h
        end if
      end if
      failures = failures + 1
      if (failures > max_failures) then
        call err%set(ERR_NUMERIC, 'galpha_adaptive: ' // int_str(max_failures) // &
          ' failed tries of the step at t = ' // real_str(this%t) // ' (last h = ' // &
          real_str(h) // ')')
        return
      end if
    end do
  end subroutine adaptive_step

  !> 1 for a ratio in [keep_above, grow_min), else the ratio.
  pure real(wp) function kept_ratio(ratio)
    real(wp), intent(in) :: ratio
    kept_ratio = ratio
    if (ratio >= keep_above .and. ratio < grow_min) kept_ratio = 1
  end function kept_ratio

  !> The factor of the next step for an error norm: 0.85 norm^(-1/3) (local error O(h^3)),
  !> kept in [shrink_min, largest]; a zero error (a step without acceleration change) grows
  !> by the largest factor.
  pure real(wp) function step_ratio(error_norm, largest) result(ratio)
    real(wp), intent(in) :: error_norm, largest
    ratio = largest
    if (error_norm * (largest / safety)**3 > 1) ratio = safety * error_norm**(-1.0_wp / 3)
    ratio = min(largest, max(shrink_min, ratio))
  end function step_ratio

  subroutine restore_previous(this)
    type(galpha_solver_t), intent(inout) :: this
    this%t = this%t_prev
    this%q = this%q_prev
    this%v = this%v_prev
    this%qdd = this%qdd_prev
    this%acc = this%acc_prev
    this%h_last = this%h_last_prev
  end subroutine restore_previous

  !> The state at t in (t_prev, t] of the last step: cubic Hermite interpolation of q from
  !> (q, v) and of v from (v, qdd) at both ends, third-order accurate like the step itself.
  subroutine interpolate(this, t, q, v)
    type(galpha_solver_t), intent(in) :: this
    real(wp), intent(in) :: t
    real(wp), intent(out) :: q(:), v(:)
    real(wp) :: h, s, h00, h10, h01, h11
    h = this%t - this%t_prev
    s = (t - this%t_prev) / h
    h00 = (1 + 2 * s) * (1 - s)**2
    h10 = s * (1 - s)**2
    h01 = s**2 * (3 - 2 * s)
    h11 = s**2 * (s - 1)
    q = h00 * this%q_prev + h10 * h * this%v_prev + h01 * this%q + h11 * h * this%v
    v = h00 * this%v_prev + h10 * h * this%qdd_prev + h01 * this%v + h11 * h * this%qdd
  end subroutine interpolate

  subroutine report_progress(this)
    type(galpha_solver_t), intent(inout) :: this
    if (associated(this%progress)) then
      if (this%progress%due()) call this%progress%report_time(this%t, this%stats%n_steps)
    end if
  end subroutine report_progress

  !> The nominal step (dt, halved after failures), shortened evenly over the distance left so
  !> that the target is hit exactly without a tiny last step.
  subroutine choose_step(this, t_target, h, lands)
    type(galpha_solver_t), intent(in) :: this
    real(wp), intent(in) :: t_target
    real(wp), intent(out) :: h
    logical, intent(out) :: lands
    real(wp) :: h_nominal, left, n_steps

    h_nominal = this%dt / 2.0_wp**this%halvings
    left = t_target - this%t
    n_steps = left / h_nominal
    lands = n_steps <= 1 + landing_slack
    if (lands) then
      h = left
    else if (n_steps < 1.0e9_wp) then
      h = left / aint(n_steps + (1 - landing_slack))
    else
      h = h_nominal
    end if
  end subroutine choose_step

  subroutine after_success(this)
    type(galpha_solver_t), intent(inout) :: this
    call remember_accepted(this)
    this%stats%n_steps = this%stats%n_steps + 1
    this%jac_is_current = .false.
    if (this%halvings > 0) then
      this%steps_at_level = this%steps_at_level + 1
      if (this%steps_at_level >= steps_before_growth) then
        this%halvings = this%halvings - 1
        this%steps_at_level = 0
      end if
    end if
    call report_progress(this)
  end subroutine after_success

  !> The step just accepted started from qdd_prev and was h_last long: the predictor's history.
  subroutine remember_accepted(this)
    type(galpha_solver_t), intent(inout) :: this
    this%qdd_old = this%qdd_prev
    this%h_old = this%h_last
  end subroutine remember_accepted

  !> A stale Jacobian gets one more try with a fresh one; otherwise halve the step.
  subroutine after_failure(this, outcome, h, err)
    type(galpha_solver_t), intent(inout) :: this
    integer, intent(in) :: outcome
    real(wp), intent(in) :: h
    type(error_t), intent(inout) :: err
    this%stats%n_nonlin_fails = this%stats%n_nonlin_fails + 1
    if (outcome == STEP_NEWTON_FAILED .and. .not. this%jac_is_current) then
      this%refresh_jac = .true.
      return
    end if
    this%halvings = this%halvings + 1
    this%steps_at_level = 0
    if (this%halvings > max_halvings) then
      if (outcome == STEP_RECOVERABLE) then
        call err%set(ERR_NUMERIC, 'galpha: the system kept returning a recoverable status at t = ' &
          // real_str(this%t) // ' with the step halved ' // int_str(max_halvings) // &
          ' times (h = ' // real_str(h) // ')')
      else
        call err%set(ERR_NUMERIC, 'galpha: Newton did not converge at t = ' // &
          real_str(this%t) // ' with the step halved ' // int_str(max_halvings) // &
          ' times (h = ' // real_str(h) // ')')
      end if
    end if
  end subroutine after_failure

  !> t within the integration's limits (evaluations never leave them).
  pure real(wp) function galpha_clamped(this, t) result(clamped)
    class(galpha_solver_t), intent(in) :: this
    real(wp), intent(in) :: t
    clamped = min(max(t, this%t_lo), this%t_hi)
  end function galpha_clamped

  subroutine galpha_get_stats(this, stats)
    class(galpha_solver_t), intent(in) :: this
    type(integrator_stats_t), intent(out) :: stats
    stats = this%stats
  end subroutine galpha_get_stats
end module integrators_galpha
