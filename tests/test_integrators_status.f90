!> Failure paths: a recoverable status from accel makes the methods retry and still succeed, a
!> fatal one ends with ERR_NUMERIC naming the time, so does a failing record or the step limit,
!> and bad options give ERR_INPUT.
program test_integrators_status
  use core_kinds, only: wp, i8
  use core_error, only: error_t, ERR_INPUT, ERR_NUMERIC
  use integrators_system, only: integrator_options_t, integrator_stats_t, &
    INTEGRATOR_BDF, INTEGRATOR_GALPHA, INTEGRATOR_GALPHA_ADAPTIVE, JACOBIAN_INTERNAL
  use integrators_driver, only: integrate
  use test_oscillators, only: failing_oscillator_t
  use testing, only: suite_t
  implicit none
  type(suite_t) :: suite
  real(wp), allocatable :: t_out(:)
  type(integrator_options_t) :: bdf, bdf_internal, galpha
  integer :: i

  call suite%init('integrators: status codes and errors')
  t_out = [(0.1_wp * i, i = 0, 10)]
  bdf = integrator_options_t(method=INTEGRATOR_BDF, rtol=1.0e-6_wp, atol=1.0e-8_wp)
  bdf_internal = bdf
  bdf_internal%jacobian = JACOBIAN_INTERNAL
  galpha = integrator_options_t(method=INTEGRATOR_GALPHA, dt=0.005_wp, rho_inf=0.8_wp)

  ! Unit oscillator, omega = 2 pi, T = 1 s. BDF: 1000 rtol (global error of an rtol-controlled
  ! run, about 14 rtol here). galpha: 2 omega T (omega dt)^2, twice the second-order phase
  ! error bound (observed 0.1 of it; first order would be omega T omega dt = 0.2).
  call check_recoverable('bdf', bdf, 1000 * bdf%rtol)
  call check_recoverable('bdf (internal Jacobian)', bdf_internal, 1000 * bdf%rtol)
  call check_recoverable('galpha', galpha, 2 * (2 * acos(-1.0_wp))**3 * galpha%dt**2)
  call check_fatal('bdf', bdf)
  call check_fatal('galpha', galpha)
  call check_record_failure('bdf', bdf)
  call check_record_failure('galpha', galpha)
  call check_step_limit('bdf', bdf)
  call check_step_limit('galpha', galpha)
  call check_bad_options()
  call suite%finish()

contains

  subroutine check_recoverable(name, opts, tol)
    character(len=*), intent(in) :: name
    type(integrator_options_t), intent(in) :: opts
    real(wp), intent(in) :: tol
    type(failing_oscillator_t) :: sys
    type(integrator_stats_t) :: stats
    type(error_t) :: err
    real(wp) :: none(0)
    sys%status_code = 1
    sys%n_failures = 1
    call integrate(sys, opts, t_out, [1.0_wp], [0.0_wp], none, stats, err)
    write(*, '(4x,a,i0,a,i0,a,es9.2)') name // ' after one recoverable status: steps ', &
      stats%n_steps, ', nonlinear failures ', stats%n_nonlin_fails, ', error ', sys%max_error
    call suite%check(sys%n_failures == 0, name // ': the failing call happened')
    call suite%check(err%ok() .and. sys%n_records == size(t_out), &
      name // ' retries after a recoverable status')
    call suite%check(sys%max_error < tol, name // ' is still accurate after the retry')
  end subroutine check_recoverable

  subroutine check_fatal(name, opts)
    character(len=*), intent(in) :: name
    type(integrator_options_t), intent(in) :: opts
    type(failing_oscillator_t) :: sys
    type(integrator_stats_t) :: stats
    type(error_t) :: err
    real(wp) :: none(0)
    sys%status_code = -2
    sys%n_failures = 1
    call integrate(sys, opts, t_out, [1.0_wp], [0.0_wp], none, stats, err)
    call suite%check(err%code == ERR_NUMERIC, name // ': a fatal status is an ERR_NUMERIC')
    if (.not. err%ok()) write(*, '(4x,a)') 'message: ' // err%message
    call suite%check(index(err%message, 't = 0.5') > 0 .or. index(err%message, 't = 0.6') > 0, &
      name // ': the message gives the time')
    call suite%check(sys%n_records == 6, name // ': outputs stop at the failure')
  end subroutine check_fatal

  subroutine check_record_failure(name, opts)
    character(len=*), intent(in) :: name
    type(integrator_options_t), intent(in) :: opts
    type(failing_oscillator_t) :: sys
    type(integrator_stats_t) :: stats
    type(error_t) :: err
    real(wp) :: none(0)
    sys%k_record_fail = 4
    sys%record_status = 7
    call integrate(sys, opts, t_out, [1.0_wp], [0.0_wp], none, stats, err)
    call suite%check(.not. err%ok() .and. sys%n_records == 4, &
      name // ': a failing record stops the run')
    if (.not. err%ok()) write(*, '(4x,a)') 'message: ' // err%message
  end subroutine check_record_failure

  subroutine check_step_limit(name, opts)
    character(len=*), intent(in) :: name
    type(integrator_options_t), intent(in) :: opts
    type(integrator_options_t) :: limited
    type(failing_oscillator_t) :: sys
    type(integrator_stats_t) :: stats
    type(error_t) :: err
    real(wp) :: none(0)
    limited = opts
    limited%max_steps = 30_i8
    call integrate(sys, limited, t_out, [1.0_wp], [0.0_wp], none, stats, err)
    call suite%check(err%code == ERR_NUMERIC .and. stats%n_steps <= limited%max_steps, &
      name // ': max_steps limits the whole run')
    ! Where it stopped was all it said (t_end = 1e30 ran into it): it says why.
    call suite%check(index(err%message, 'the 30 steps a run may take did not reach t = ') > 0 &
      .and. index(err%message, 't_end far beyond') > 0, name // ': the limit is named')
    if (.not. err%ok()) write(*, '(4x,a)') 'message: ' // err%message
  end subroutine check_step_limit

  subroutine check_bad_options()
    type(integrator_options_t) :: opts
    ! 0: no INTEGRATOR_* or JACOBIAN_* constant.
    call expect_input_error(integrator_options_t(method=0), t_out, 'unknown method')
    call expect_input_error(integrator_options_t(method=INTEGRATOR_BDF, rtol=0.0_wp), t_out, &
      'rtol = 0')
    call expect_input_error(integrator_options_t(method=INTEGRATOR_BDF, atol=-1.0_wp), t_out, &
      'atol < 0')
    ! Below what double precision can meet, or weights that overflow when squared.
    call expect_input_error(integrator_options_t(method=INTEGRATOR_GALPHA_ADAPTIVE, &
      rtol=1.0e-20_wp), t_out, 'rtol = 1e-20')
    call expect_input_error(integrator_options_t(method=INTEGRATOR_BDF, atol=1.0e-200_wp), &
      t_out, 'atol = 1e-200')
    call expect_input_error(integrator_options_t(method=INTEGRATOR_BDF, max_order=6), t_out, &
      'max_order 6')
    call expect_input_error(integrator_options_t(method=INTEGRATOR_BDF, jacobian=0), t_out, &
      'unknown jacobian')
    call expect_input_error(integrator_options_t(method=INTEGRATOR_GALPHA, dt=0.0_wp), t_out, &
      'dt = 0')
    call expect_input_error(integrator_options_t(method=INTEGRATOR_GALPHA, rho_inf=1.5_wp), t_out, &
      'rho_inf > 1')
    call expect_input_error(integrator_options_t(method=INTEGRATOR_GALPHA, rho_inf=-0.1_wp), &
      t_out, 'rho_inf < 0')
    call expect_input_error(integrator_options_t(method=INTEGRATOR_GALPHA, max_steps=0_i8), t_out, &
      'max_steps = 0')
    opts = integrator_options_t(method=INTEGRATOR_BDF)
    call expect_input_error(opts, [0.0_wp, 0.2_wp, 0.1_wp], 'decreasing output times')
    call expect_input_error(opts, [0.0_wp, 0.1_wp, 0.1_wp], 'repeated output time')
  end subroutine check_bad_options

  subroutine expect_input_error(opts, times, what)
    type(integrator_options_t), intent(in) :: opts
    real(wp), intent(in) :: times(:)
    character(len=*), intent(in) :: what
    type(failing_oscillator_t) :: sys
    type(integrator_stats_t) :: stats
    type(error_t) :: err
    real(wp) :: none(0)
    call integrate(sys, opts, times, [1.0_wp], [0.0_wp], none, stats, err)
    call suite%check(err%code == ERR_INPUT .and. sys%n_records == 0, &
      'bad option gives ERR_INPUT: ' // what)
    if (.not. err%ok()) write(*, '(4x,a)') 'message: ' // err%message
  end subroutine expect_input_error
end program test_integrators_status
