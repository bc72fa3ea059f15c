!> Stiff 2-DOF system: two unit masses on soft ground springs (k = 1) coupled by a stiff spring
!> (k = 1e6) with a damper. The mean motion oscillates at 1 rad/s, the relative one decays
!> within milliseconds: BDF must take large steps after the transient, with the system's
!> Jacobian and with CVODE's own, and generalized-alpha must stay stable with dt >> 1/omega_fast.
module stiff_test_system
  use core_kinds, only: wp
  use integrators_system, only: ode2_system_t
  implicit none
  private
  public :: stiff_pair_t

  type, extends(ode2_system_t) :: stiff_pair_t
    real(wp) :: k_soft = 1, k_stiff = 1.0e6_wp, c = 1.0e3_wp
    real(wp) :: s0 = 1, d0 = 2.0e-3_wp   !< initial mean and relative positions (at rest)
    real(wp) :: max_error = 0
  contains
    procedure :: accel => stiff_accel
    procedure :: record => stiff_record
    procedure :: jacobian => stiff_jacobian
  end type stiff_pair_t

contains

  subroutine stiff_accel(this, t, q, v, a, status)
    class(stiff_pair_t), intent(inout) :: this
    real(wp), intent(in) :: t, q(:), v(:)
    real(wp), intent(out) :: a(:)
    integer, intent(out) :: status
    real(wp) :: coupling
    coupling = this%k_stiff * (q(1) - q(2)) + this%c * (v(1) - v(2))
    a(1) = -this%k_soft * q(1) - coupling
    a(2) = -this%k_soft * q(2) + coupling
    status = 0
  end subroutine stiff_accel

  subroutine stiff_jacobian(this, t, q, v, dadq, dadv, status)
    class(stiff_pair_t), intent(inout) :: this
    real(wp), intent(in) :: t, q(:), v(:)
    real(wp), intent(out) :: dadq(:, :), dadv(:, :)
    integer, intent(out) :: status
    dadq = reshape([-this%k_soft - this%k_stiff, this%k_stiff, &
                    this%k_stiff, -this%k_soft - this%k_stiff], [2, 2])
    dadv = reshape([-this%c, this%c, this%c, -this%c], [2, 2])
    status = 0
  end subroutine stiff_jacobian

  !> Mean s'' = -k_soft s; relative d'' + 2 c d' + (k_soft + 2 k_stiff) d = 0 (underdamped).
  subroutine stiff_record(this, k, t, q, v, status)
    class(stiff_pair_t), intent(inout) :: this
    integer, intent(in) :: k
    real(wp), intent(in) :: t, q(:), v(:)
    integer, intent(out) :: status
    real(wp) :: s, d, omega_d
    s = this%s0 * cos(sqrt(this%k_soft) * t)
    omega_d = sqrt(this%k_soft + 2 * this%k_stiff - this%c**2)
    d = exp(-this%c * t) * this%d0 * (cos(omega_d * t) + this%c / omega_d * sin(omega_d * t))
    this%max_error = max(this%max_error, abs(q(1) - (s + d / 2)), abs(q(2) - (s - d / 2)))
    status = 0
  end subroutine stiff_record
end module stiff_test_system

program test_integrators_stiff
  use core_kinds, only: wp
  use core_error, only: error_t
  use integrators_system, only: integrator_options_t, integrator_stats_t, &
    INTEGRATOR_BDF, INTEGRATOR_GALPHA, JACOBIAN_INTERNAL
  use integrators_driver, only: integrate
  use stiff_test_system, only: stiff_pair_t
  use testing, only: suite_t
  implicit none
  type(suite_t) :: suite
  real(wp), allocatable :: t_out(:)
  integer :: i

  call suite%init('integrators: stiff 2-DOF system')
  t_out = [(0.5_wp * i, i = 0, 20)]
  ! The fast eigenvalues are -1000 +- 1000i: an explicit method would need some 5000 steps.
  ! Error bounds: BDF 1000 rtol (global error of an rtol-controlled run, 10 to 25 rtol here);
  ! galpha 10 omega T (omega dt)^2 (phase error of a second-order method on the slow mode,
  ! omega = 1, T = 10 s; first order would give omega T omega dt = 0.1). Steps: BDF below 3500,
  ! 0.7 of what explicit stability needs; galpha exactly T / dt.
  call check('bdf, system Jacobian', &
    integrator_options_t(method=INTEGRATOR_BDF, rtol=1.0e-6_wp, atol=1.0e-9_wp), 1.0e-3_wp, 3500)
  call check('bdf, internal Jacobian', &
    integrator_options_t(method=INTEGRATOR_BDF, rtol=1.0e-6_wp, atol=1.0e-9_wp, &
    jacobian=JACOBIAN_INTERNAL), 1.0e-3_wp, 3500)
  call check('galpha rho_inf 0.5', &
    integrator_options_t(method=INTEGRATOR_GALPHA, dt=0.01_wp, rho_inf=0.5_wp), &
    10 * 10 * 0.01_wp**2, 1000)
  call check('galpha rho_inf 0', &
    integrator_options_t(method=INTEGRATOR_GALPHA, dt=0.01_wp, rho_inf=0.0_wp), &
    10 * 10 * 0.01_wp**2, 1000)
  call suite%finish()

contains

  subroutine check(name, opts, tol, max_steps)
    character(len=*), intent(in) :: name
    type(integrator_options_t), intent(in) :: opts
    real(wp), intent(in) :: tol
    integer, intent(in) :: max_steps
    type(stiff_pair_t) :: sys
    type(integrator_stats_t) :: stats
    type(error_t) :: err
    real(wp) :: no_breakpoints(0)
    character(len=160) :: line
    call integrate(sys, opts, t_out, [sys%s0 + sys%d0 / 2, sys%s0 - sys%d0 / 2], &
      [0.0_wp, 0.0_wp], no_breakpoints, stats, err)
    write(line, '(a,a,es9.2,a,i0,a,i0,a,i0,a,i0,a,i0)') name, ': error', sys%max_error, &
      ', steps ', stats%n_steps, ', accel ', stats%n_rhs_evals, ', jac ', stats%n_jac_evals, &
      ', err test fails ', stats%n_err_test_fails, ', nonlin fails ', stats%n_nonlin_fails
    write(*, '(4x,a)') trim(line)
    call suite%check(err%ok(), name // ' runs')
    call suite%check(sys%max_error < tol, name // ' is accurate')
    call suite%check(stats%n_steps <= max_steps, name // ' takes few steps')
  end subroutine check
end program test_integrators_stiff
