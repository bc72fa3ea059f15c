!> Nonlinear pendulum phi'' = -(g/L) sin(phi) at large amplitude: both methods conserve the
!> energy (the system keeps the default finite-difference Jacobian of ode2_system_t).
module pendulum_test_system
  use core_kinds, only: wp
  use integrators_system, only: ode2_system_t
  implicit none
  private
  public :: pendulum_t

  type, extends(ode2_system_t) :: pendulum_t
    real(wp) :: g_over_l = 9.81_wp
    real(wp) :: e0 = -1                 !< energy at the first output
    real(wp) :: max_drift = 0           !< largest |E - E0| / E0 over the outputs
  contains
    procedure :: accel => pendulum_accel
    procedure :: record => pendulum_record
  end type pendulum_t

contains

  subroutine pendulum_accel(this, t, q, v, a, status)
    class(pendulum_t), intent(inout) :: this
    real(wp), intent(in) :: t, q(:), v(:)
    real(wp), intent(out) :: a(:)
    integer, intent(out) :: status
    a = -this%g_over_l * sin(q)
    status = 0
  end subroutine pendulum_accel

  subroutine pendulum_record(this, k, t, q, v, status)
    class(pendulum_t), intent(inout) :: this
    integer, intent(in) :: k
    real(wp), intent(in) :: t, q(:), v(:)
    integer, intent(out) :: status
    real(wp) :: energy
    energy = 0.5_wp * v(1)**2 + this%g_over_l * (1 - cos(q(1)))
    if (k == 1) this%e0 = energy
    this%max_drift = max(this%max_drift, abs(energy - this%e0) / this%e0)
    status = 0
  end subroutine pendulum_record
end module pendulum_test_system

program test_integrators_pendulum
  use core_kinds, only: wp
  use core_error, only: error_t
  use integrators_system, only: integrator_options_t, integrator_stats_t, &
    INTEGRATOR_BDF, INTEGRATOR_GALPHA
  use integrators_driver, only: integrate
  use pendulum_test_system, only: pendulum_t
  use testing, only: suite_t
  implicit none
  type(suite_t) :: suite
  real(wp), allocatable :: t_out(:)
  real(wp) :: no_breakpoints(0)
  integer :: i

  call suite%init('integrators: pendulum energy')
  ! 2.5 rad amplitude, about 10 periods of 2.4 s; BDF's drift is global error, about 100 rtol
  t_out = [(0.1_wp * i, i = 0, 240)]
  ! BDF: the drift is global error, 200 to 400 rtol here; bound 1e4 rtol (an integrator
  ! ignoring rtol drifts by O(1)). galpha: second order, energy error C (omega dt)^2 with
  ! omega^2 = g / l and C about 0.2; bound 10 (omega dt)^2 (first order would give omega dt).
  call check('bdf', integrator_options_t(method=INTEGRATOR_BDF, rtol=1.0e-6_wp, atol=1.0e-8_wp), &
    1.0e4_wp * 1.0e-6_wp)
  call check('bdf', integrator_options_t(method=INTEGRATOR_BDF, rtol=1.0e-9_wp, atol=1.0e-11_wp), &
    1.0e4_wp * 1.0e-9_wp)
  call check('galpha', integrator_options_t(method=INTEGRATOR_GALPHA, dt=0.01_wp, &
    rho_inf=1.0_wp), 10 * 9.81_wp * 0.01_wp**2)
  call check('galpha', integrator_options_t(method=INTEGRATOR_GALPHA, dt=0.005_wp, &
    rho_inf=0.9_wp), 10 * 9.81_wp * 0.005_wp**2)
  call suite%finish()

contains

  subroutine check(name, opts, tol)
    character(len=*), intent(in) :: name
    type(integrator_options_t), intent(in) :: opts
    real(wp), intent(in) :: tol
    type(pendulum_t) :: sys
    type(integrator_stats_t) :: stats
    type(error_t) :: err
    character(len=120) :: line
    call integrate(sys, opts, t_out, [2.5_wp], [0.0_wp], no_breakpoints, stats, err)
    write(line, '(a,a,es8.1,a,es8.1,a,f4.2,a,es9.2,a,es9.2,a,i0,a,i0,a,i0)') name, ' rtol', &
      opts%rtol, ' dt', opts%dt, ' rho_inf ', opts%rho_inf, ': energy drift', sys%max_drift, &
      ' (bound', tol, '), steps ', stats%n_steps, ', accel ', stats%n_rhs_evals, ', jac ', &
      stats%n_jac_evals
    write(*, '(4x,a)') trim(line)
    call suite%check(err%ok(), name // ' runs')
    call suite%check(sys%max_drift < tol, name // ' conserves the energy')
  end subroutine check
end program test_integrators_pendulum
