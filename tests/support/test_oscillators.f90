!> The undamped linear oscillator q'' = -omega^2 q shared by the integrator tests, with its
!> exact solution from q(0) = 1, v(0) = 0, and two variants of it: one with a force switched off
!> at t_b (a jump of a(t), to be given as a breakpoint) and one whose callbacks fail on demand.
module test_oscillators
  use core_kinds, only: wp
  use core_error, only: error_t
  use integrators_system, only: ode2_system_t, integrator_options_t, integrator_stats_t, &
    system_fd_jacobian
  use integrators_driver, only: integrate
  implicit none
  private
  public :: oscillator_t, oscillator_error, run_oscillator, switched_oscillator_t, &
    failing_oscillator_t, stiff_follower_t

  real(wp), parameter :: pi = acos(-1.0_wp)

  !> q'' = -omega^2 q; record compares with the exact solution from q(0) = 1, v(0) = 0.
  type, extends(ode2_system_t) :: oscillator_t
    real(wp) :: omega = 2 * pi
    real(wp) :: max_error = 0       !< largest |q - q_exact| + |v - v_exact| / omega at outputs
    integer :: n_records = 0
    real(wp) :: last_q = 0          !< q at the last output
    logical :: times_exact = .true.
    real(wp), allocatable :: t_expected(:)
  contains
    procedure :: accel => oscillator_accel
    procedure :: record => oscillator_record
    procedure :: jacobian => oscillator_jacobian
  end type oscillator_t

  !> q'' = -omega^2 q + F(t), F = force before t_b and 0 after, from rest at q = 0 (record
  !> compares with that exact solution); the Jacobian is the oscillator's.
  type, extends(oscillator_t) :: switched_oscillator_t
    real(wp) :: force = 20, t_b = 0.37_wp
    !> Which side of the jump F(t_b) belongs to: the integrators must not care.
    logical :: force_at_t_b = .false.
    integer :: n_evals_at_t_b = 0
  contains
    procedure :: accel => switched_accel
    procedure :: record => switched_record
  end type switched_oscillator_t

  !> The oscillator whose accel returns `status_code` on its first `n_failures` calls after
  !> t_fail, and whose record returns `record_status` at output `k_record_fail`.
  type, extends(oscillator_t) :: failing_oscillator_t
    real(wp) :: t_fail = 0.55_wp
    integer :: status_code = 0, n_failures = 0
    integer :: record_status = 0, k_record_fail = -1
  contains
    procedure :: accel => failing_accel
    procedure :: record => failing_record
    procedure :: jacobian => failing_jacobian
  end type failing_oscillator_t

  !> A slow oscillator q1'' = -q1 driving a stiff follower q2'' = -k (q2 - q1^2): q2 stays
  !> within O(1/k) of q1^2, while its own frequency sqrt(k) = 1e4 would limit an explicit
  !> method to steps below 2e-4.
  type, extends(ode2_system_t) :: stiff_follower_t
    real(wp) :: k = 1.0e8_wp
    real(wp) :: worst = 0    !< largest |q1 - cos t| + |q2 - q1^2| at the outputs
  contains
    procedure :: accel => follower_accel
    procedure :: record => follower_record
    procedure :: jacobian => follower_jacobian
  end type stiff_follower_t

contains

  !> Integrate a fresh oscillator from q(0) = 1, v(0) = 0 through the driver, recording at
  !> `times` (which record checks it is called at exactly); no breakpoints.
  subroutine run_oscillator(sys, opts, times, stats, err)
    type(oscillator_t), intent(out) :: sys
    type(integrator_options_t), intent(in) :: opts
    real(wp), intent(in) :: times(:)
    type(integrator_stats_t), intent(out) :: stats
    type(error_t), intent(out) :: err
    real(wp) :: no_breakpoints(0)
    sys%t_expected = times
    call integrate(sys, opts, times, [1.0_wp], [0.0_wp], no_breakpoints, stats, err)
  end subroutine run_oscillator

  !> |q - cos(omega t)| + |v + omega sin(omega t)| / omega: the error against the exact
  !> solution from q(0) = 1, v(0) = 0.
  pure real(wp) function oscillator_error(omega, t, q, v)
    real(wp), intent(in) :: omega, t, q, v
    oscillator_error = abs(q - cos(omega * t)) + abs(v + omega * sin(omega * t)) / omega
  end function oscillator_error

  subroutine oscillator_accel(this, t, q, v, a, status)
    class(oscillator_t), intent(inout) :: this
    real(wp), intent(in) :: t, q(:), v(:)
    real(wp), intent(out) :: a(:)
    integer, intent(out) :: status
    a = -this%omega**2 * q
    status = 0
  end subroutine oscillator_accel

  subroutine oscillator_jacobian(this, t, q, v, dadq, dadv, status)
    class(oscillator_t), intent(inout) :: this
    real(wp), intent(in) :: t, q(:), v(:)
    real(wp), intent(out) :: dadq(:, :), dadv(:, :)
    integer, intent(out) :: status
    dadq = -this%omega**2
    dadv = 0
    status = 0
  end subroutine oscillator_jacobian

  subroutine oscillator_record(this, k, t, q, v, status)
    class(oscillator_t), intent(inout) :: this
    integer, intent(in) :: k
    real(wp), intent(in) :: t, q(:), v(:)
    integer, intent(out) :: status
    this%max_error = max(this%max_error, oscillator_error(this%omega, t, q(1), v(1)))
    this%n_records = this%n_records + 1
    this%last_q = q(1)
    if (allocated(this%t_expected)) then
      this%times_exact = this%times_exact .and. .not. abs(t - this%t_expected(k)) > 0
    end if
    status = 0
  end subroutine oscillator_record

  subroutine switched_accel(this, t, q, v, a, status)
    class(switched_oscillator_t), intent(inout) :: this
    real(wp), intent(in) :: t, q(:), v(:)
    real(wp), intent(out) :: a(:)
    integer, intent(out) :: status
    logical :: on
    if (.not. abs(t - this%t_b) > 0) this%n_evals_at_t_b = this%n_evals_at_t_b + 1
    on = t < this%t_b .or. (this%force_at_t_b .and. .not. t > this%t_b)
    a = -this%omega**2 * q
    if (on) a = a + this%force
    status = 0
  end subroutine switched_accel

  !> Error against the exact solution: forced response, then free vibration from t_b.
  subroutine switched_record(this, k, t, q, v, status)
    class(switched_oscillator_t), intent(inout) :: this
    integer, intent(in) :: k
    real(wp), intent(in) :: t, q(:), v(:)
    integer, intent(out) :: status
    real(wp) :: w, q_static, q_b, v_b, q_exact, v_exact
    w = this%omega
    q_static = this%force / w**2
    if (t <= this%t_b) then
      q_exact = q_static * (1 - cos(w * t))
      v_exact = q_static * w * sin(w * t)
    else
      q_b = q_static * (1 - cos(w * this%t_b))
      v_b = q_static * w * sin(w * this%t_b)
      q_exact = q_b * cos(w * (t - this%t_b)) + v_b / w * sin(w * (t - this%t_b))
      v_exact = -q_b * w * sin(w * (t - this%t_b)) + v_b * cos(w * (t - this%t_b))
    end if
    this%max_error = max(this%max_error, abs(q(1) - q_exact) + abs(v(1) - v_exact) / w)
    this%n_records = this%n_records + 1
    status = 0
  end subroutine switched_record

  subroutine failing_accel(this, t, q, v, a, status)
    class(failing_oscillator_t), intent(inout) :: this
    real(wp), intent(in) :: t, q(:), v(:)
    real(wp), intent(out) :: a(:)
    integer, intent(out) :: status
    a = -this%omega**2 * q
    status = 0
    if (t > this%t_fail .and. this%n_failures > 0) then
      this%n_failures = this%n_failures - 1
      status = this%status_code
      a = 0
    end if
  end subroutine failing_accel

  !> The default finite differences of accel, not the oscillator's own Jacobian: so the
  !> failures of accel reach the integrators through the Jacobian too.
  subroutine failing_jacobian(this, t, q, v, dadq, dadv, status)
    class(failing_oscillator_t), intent(inout) :: this
    real(wp), intent(in) :: t, q(:), v(:)
    real(wp), intent(out) :: dadq(:, :), dadv(:, :)
    integer, intent(out) :: status
    call system_fd_jacobian(this, t, q, v, dadq, dadv, status)
  end subroutine failing_jacobian

  subroutine failing_record(this, k, t, q, v, status)
    class(failing_oscillator_t), intent(inout) :: this
    integer, intent(in) :: k
    real(wp), intent(in) :: t, q(:), v(:)
    integer, intent(out) :: status
    call this%oscillator_t%record(k, t, q, v, status)
    if (k == this%k_record_fail) status = this%record_status
  end subroutine failing_record
  subroutine follower_accel(this, t, q, v, a, status)
    class(stiff_follower_t), intent(inout) :: this
    real(wp), intent(in) :: t, q(:), v(:)
    real(wp), intent(out) :: a(:)
    integer, intent(out) :: status
    a(1) = -q(1)
    a(2) = -this%k * (q(2) - q(1)**2)
    status = 0
  end subroutine follower_accel

  subroutine follower_jacobian(this, t, q, v, dadq, dadv, status)
    class(stiff_follower_t), intent(inout) :: this
    real(wp), intent(in) :: t, q(:), v(:)
    real(wp), intent(out) :: dadq(:, :), dadv(:, :)
    integer, intent(out) :: status
    dadq = reshape([-1.0_wp, 2 * this%k * q(1), 0.0_wp, -this%k], [2, 2])
    dadv = 0
    status = 0
  end subroutine follower_jacobian

  subroutine follower_record(this, k, t, q, v, status)
    class(stiff_follower_t), intent(inout) :: this
    integer, intent(in) :: k
    real(wp), intent(in) :: t, q(:), v(:)
    integer, intent(out) :: status
    ! q2 lags q1^2 by about (d2/dt2 q1^2) / k = 2 cos(2t) / k = 2e-8: far below the bound.
    this%worst = max(this%worst, abs(q(1) - cos(t)) + abs(q(2) - q(1)**2))
    status = 0
  end subroutine follower_record

end module test_oscillators
