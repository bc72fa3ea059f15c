!> The second-order system every flexmor integrator advances:
!>     q'' = a(t, q, v),   v = q'
!> The model (full or reduced) extends `ode2_system_t`; the integrators know nothing else of it.
!>
!> Status codes of the callbacks follow SUNDIALS: 0 ok, > 0 recoverable (the integrator cuts the
!> step and retries, e.g. a kinematic Newton solve that did not converge), < 0 fatal.
module integrators_system
  use core_kinds, only: wp, i8
  use core_progress, only: progress_t
  implicit none
  private
  public :: ode2_system_t, integrator_options_t, integrator_stats_t, system_fd_jacobian, &
    bdf_order

  !> The methods, in the order of their names (&dynamic integrator's choices: io_fields'
  !> rd_enum checks them against the schema's). INTEGRATOR_AUTO is the scene's choice by rtol
  !> and the model's stiffness (model_scene), made before integrating: no method of its own.
  integer, parameter, public :: INTEGRATOR_AUTO = 1, INTEGRATOR_BDF = 2, INTEGRATOR_GALPHA = 3, &
    INTEGRATOR_GALPHA_ADAPTIVE = 4, INTEGRATOR_ERK = 5
  character(len=*), parameter, public :: INTEGRATOR_NAMES(5) = [character(len=15) :: 'auto', &
    'bdf', 'galpha', 'galpha_adaptive', 'erk']
  !> The smallest tolerances: below MIN_RTOL double precision cannot meet the error test
  !> (galpha_adaptive at rtol 1e-20 shrank its steps without end); below MIN_ATOL the error
  !> weights 1 / atol overflow when squared (CVODE at atol 1e-200: a floating-point trap).
  real(wp), parameter, public :: MIN_RTOL = 1.0e-14_wp, MIN_ATOL = 1.0e-100_wp
  !> The Jacobian of the implicit methods, in the order of &dynamic jacobian's choices. The
  !> integrators take the system's (ode2_system_t%jacobian) for any but JACOBIAN_INTERNAL
  !> (CVODE's difference quotients); which of the other two it is concerns the system: flexmor's
  !> models give their linearised matrices or forward differences.
  integer, parameter, public :: JACOBIAN_LINEARISED = 1, JACOBIAN_FD = 2, JACOBIAN_INTERNAL = 3
  character(len=*), parameter, public :: JACOBIAN_NAMES(3) = [character(len=10) :: &
    'linearised', 'fd', 'internal']

  type, abstract :: ode2_system_t
  contains
    !> Accelerations a(t, q, v).
    procedure(accel_iface), deferred :: accel
    !> Called at every requested output time with the state there.
    procedure(record_iface), deferred :: record
    !> Jacobians da/dq and da/dv (n x n). The default is forward differences of `accel`;
    !> a model may override it with its linearised matrices.
    procedure :: jacobian => system_fd_jacobian
    !> A model may solve the Newton systems of implicit steps itself, e.g. sparse where a
    !> dense n x n Jacobian would cost O(n^2) memory and O(n^3) work. Then
    !> iteration_factor(c_q, c_v) factors I - c_q da/dq - c_v da/dv at the state of the last
    !> `accel` or newton_correction (an integrator refactors where its last step ended),
    !> and newton_correction(t, q, v, x, dx) returns dx = that matrix's inverse times
    !> (a(t, q, v) - x), formed as the model likes (flexmor's: from the residual of the
    !> equations of motion, without factoring its mass matrix). Default: not offered.
    procedure :: has_iteration_solver => system_no_iteration_solver
    procedure :: iteration_factor => system_iteration_factor
    procedure :: newton_correction => system_newton_correction
    !> Norm of the local error estimate dq of q over a step from q_old to q_new, for the
    !> adaptive generalized-alpha method (a step is accepted when it is <= 1). The default is
    !> the weighted RMS over q, weights atol + rtol max(|q_old|, |q_new|); a model may measure
    !> the error where its user looks instead (flexmor's models: on the nodal coordinates).
    procedure :: error_norm => system_error_norm
    !> Called by the driver at the first time and at every breakpoint, before the method
    !> (re)starts there: a system whose equations change at given times (a sampled
    !> controller's hold) updates itself. Status as for accel. The default does nothing.
    procedure :: at_breakpoint => system_at_breakpoint
    !> Called by the driver after every output but the first: a system whose coordinates are
    !> a chart that must move with the motion (a free rotation's rotation vector) may change
    !> q and v there to other coordinates of the same state, and says so (`changed`); the
    !> driver then restarts the method from them. Status as for accel. Default: no change.
    procedure :: rechart => system_no_rechart
    !> Called by every integrator after each step it accepts, with the state there (not at
    !> the trial states of rejected steps or Newton iterates, which `accel` also sees): a
    !> system that measures along its trajectory (the expanded reduced model: the farthest
    !> state each expansion served) records it here. Default: nothing.
    procedure :: step_accepted => system_step_accepted
    !> Whether step_accepted does anything: CVODE then steps one step at a time to call it
    !> (otherwise it runs to each output in one call). Default: false.
    procedure :: wants_steps => system_wants_no_steps
  end type ode2_system_t

  abstract interface
    subroutine accel_iface(this, t, q, v, a, status)
      import :: ode2_system_t, wp
      class(ode2_system_t), intent(inout) :: this
      real(wp), intent(in) :: t, q(:), v(:)
      real(wp), intent(out) :: a(:)
      integer, intent(out) :: status
    end subroutine accel_iface

    subroutine record_iface(this, k, t, q, v, status)
      import :: ode2_system_t, wp
      class(ode2_system_t), intent(inout) :: this
      integer, intent(in) :: k          !< index into the output times
      real(wp), intent(in) :: t, q(:), v(:)
      integer, intent(out) :: status
    end subroutine record_iface
  end interface

  !> Options common to all integrators; each method reads the ones that apply to it.
  type :: integrator_options_t
    !> INTEGRATOR_BDF (CVODE), INTEGRATOR_GALPHA (fixed step, ours), INTEGRATOR_GALPHA_ADAPTIVE
    !> (error-controlled, ours), INTEGRATOR_ERK (ARKODE explicit Runge-Kutta); scenes choose by
    !> rtol when not given (model_scene)
    integer :: method = INTEGRATOR_GALPHA_ADAPTIVE
    real(wp) :: rtol = 1.0e-6_wp              !< relative tolerance (adaptive methods)
    real(wp) :: atol = 1.0e-8_wp              !< absolute tolerance (adaptive methods)
    real(wp) :: max_step = 0.0_wp             !< largest step, 0 = no limit (adaptive methods)
    !> BDF order limit 1..5, or 0: by the tolerance, bdf_order(rtol) (measured, docs/input.md)
    integer :: max_order = 0
    !> Order of the explicit Runge-Kutta pair: 2, 3, 4, 5, 6 or 8 (ARKODE's default tables)
    integer :: erk_order = 5
    integer(i8) :: max_steps = 10000000_i8    !< step limit over the whole run
    integer :: jacobian = JACOBIAN_LINEARISED  !< JACOBIAN_*: the system's, or JACOBIAN_INTERNAL
    real(wp) :: dt = 1.0e-3_wp                !< step of fixed-step methods
    real(wp) :: rho_inf = 0.8_wp              !< generalized-alpha spectral radius at infinity
    !> Progress lines of a long run, polled per step or right-hand side evaluation (none when
    !> not associated). The run owns it; the integration only reports to it.
    type(progress_t), pointer :: progress => null()
  end type integrator_options_t

  !> Counters written to the output so runs can be compared.
  type :: integrator_stats_t
    integer(i8) :: n_steps = 0
    integer(i8) :: n_rhs_evals = 0        !< calls of `accel`
    integer(i8) :: n_jac_evals = 0        !< Jacobian evaluations
    integer(i8) :: n_factorisations = 0   !< factorisations of the Newton iteration matrix
    integer(i8) :: n_err_test_fails = 0   !< steps rejected by the error test
    integer(i8) :: n_nonlin_fails = 0     !< Newton (corrector) convergence failures
    integer(i8) :: n_restarts = 0         !< re-initialisations at breakpoints
  end type integrator_stats_t

contains

  !> BDF's order limit for max_order = 0: on undamped flexible models high orders are limited
  !> by stability, so order 2 is faster down to rtol 1e-5; at tighter tolerances order 5 is
  !> (two-link, 3 elements per link: rtol 1e-4 order 2 0.19 s, order 5 1.2 s; rtol 1e-6
  !> order 2 2.2 s, order 5 0.8 s; docs/bench/work_precision.md).
  pure integer function bdf_order(max_order, rtol)
    integer, intent(in) :: max_order
    real(wp), intent(in) :: rtol
    bdf_order = max_order
    if (max_order == 0) bdf_order = merge(2, 5, rtol >= 1.0e-5_wp)
  end function bdf_order

  logical function system_no_iteration_solver(this)
    class(ode2_system_t), intent(in) :: this
    system_no_iteration_solver = .false.
  end function system_no_iteration_solver

  !> Never called when has_iteration_solver is false; reports failure if it is.
  subroutine system_iteration_factor(this, c_q, c_v, status)
    class(ode2_system_t), intent(inout) :: this
    real(wp), intent(in) :: c_q, c_v
    integer, intent(out) :: status
    status = -1
  end subroutine system_iteration_factor

  !> Never called when has_iteration_solver is false; reports failure if it is.
  subroutine system_newton_correction(this, t, q, v, x, dx, status)
    class(ode2_system_t), intent(inout) :: this
    real(wp), intent(in) :: t, q(:), v(:), x(:)
    real(wp), intent(out) :: dx(:)
    integer, intent(out) :: status
    dx = 0.0_wp
    status = -1
  end subroutine system_newton_correction

  subroutine system_at_breakpoint(this, t, q, v, status)
    class(ode2_system_t), intent(inout) :: this
    real(wp), intent(in) :: t, q(:), v(:)
    integer, intent(out) :: status
    status = 0
  end subroutine system_at_breakpoint

  subroutine system_no_rechart(this, t, q, v, changed, status)
    class(ode2_system_t), intent(inout) :: this
    real(wp), intent(in) :: t
    real(wp), intent(inout) :: q(:), v(:)
    logical, intent(out) :: changed
    integer, intent(out) :: status
    changed = .false.
    status = 0
  end subroutine system_no_rechart

  subroutine system_step_accepted(this, t, q, v)
    class(ode2_system_t), intent(inout) :: this
    real(wp), intent(in) :: t, q(:), v(:)
  end subroutine system_step_accepted

  logical function system_wants_no_steps(this)
    class(ode2_system_t), intent(in) :: this
    system_wants_no_steps = .false.
  end function system_wants_no_steps

  subroutine system_error_norm(this, dq, q_old, q_new, rtol, atol, norm)
    class(ode2_system_t), intent(inout) :: this
    real(wp), intent(in) :: dq(:), q_old(:), q_new(:), rtol, atol
    real(wp), intent(out) :: norm
    norm = sqrt(sum((dq / (atol + rtol * max(abs(q_old), abs(q_new))))**2) / size(dq))
  end subroutine system_error_norm

  subroutine system_fd_jacobian(this, t, q, v, dadq, dadv, status)
    class(ode2_system_t), intent(inout) :: this
    real(wp), intent(in) :: t, q(:), v(:)
    real(wp), intent(out) :: dadq(:, :), dadv(:, :)
    integer, intent(out) :: status
    real(wp) :: a0(size(q)), a1(size(q)), qp(size(q)), vp(size(q)), h
    integer :: j
    call this%accel(t, q, v, a0, status)
    if (status /= 0) return
    do j = 1, size(q)
      qp = q
      h = sqrt(epsilon(1.0_wp)) * max(abs(q(j)), 1.0e-3_wp)
      qp(j) = q(j) + h
      call this%accel(t, qp, v, a1, status)
      if (status /= 0) return
      dadq(:, j) = (a1 - a0) / h
      vp = v
      h = sqrt(epsilon(1.0_wp)) * max(abs(v(j)), 1.0e-2_wp)
      vp(j) = v(j) + h
      call this%accel(t, q, vp, a1, status)
      if (status /= 0) return
      dadv(:, j) = (a1 - a0) / h
    end do
  end subroutine system_fd_jacobian
end module integrators_system
