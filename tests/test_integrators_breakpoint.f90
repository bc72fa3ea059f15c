!> Oscillator with a force that switches off at t_b (switched_oscillator_t of test_oscillators).
!> Given t_b as a breakpoint, both methods land on it, restart there and keep their accuracy
!> (galpha its second order); the jump is never evaluated at t_b itself.
program test_integrators_breakpoint
  use core_kinds, only: wp
  use core_error, only: error_t
  use integrators_system, only: integrator_options_t, integrator_stats_t, &
    INTEGRATOR_BDF, INTEGRATOR_GALPHA, INTEGRATOR_NAMES
  use integrators_driver, only: integrate
  use test_oscillators, only: switched_oscillator_t
  use testing, only: suite_t
  implicit none
  type(suite_t) :: suite
  real(wp), allocatable :: t_out(:)
  type(integrator_options_t) :: bdf, galpha
  integer :: i

  call suite%init('integrators: breakpoints')
  t_out = [(0.1_wp * i, i = 0, 10)]
  bdf = integrator_options_t(method=INTEGRATOR_BDF, rtol=1.0e-7_wp, atol=1.0e-9_wp)
  galpha = integrator_options_t(method=INTEGRATOR_GALPHA, dt=0.008_wp, rho_inf=0.8_wp)

  call check_bdf(0.37_wp, .false.)
  call check_bdf(0.37_wp, .true.)
  call check_bdf(0.4_wp, .false.)
  call check_galpha(0.37_wp, .false.)
  call check_galpha(0.37_wp, .true.)
  call check_galpha(0.4_wp, .true.)
  call check_outside_and_repeated()
  call suite%finish()

contains

  subroutine run(opts, t_b, force_at_t_b, breakpoints, sys, stats, err)
    type(integrator_options_t), intent(in) :: opts
    real(wp), intent(in) :: t_b
    logical, intent(in) :: force_at_t_b
    real(wp), intent(in) :: breakpoints(:)
    type(switched_oscillator_t), intent(out) :: sys
    type(integrator_stats_t), intent(out) :: stats
    type(error_t), intent(out) :: err
    character(len=160) :: line
    sys%t_b = t_b
    sys%force_at_t_b = force_at_t_b
    call integrate(sys, opts, t_out, [0.0_wp], [0.0_wp], breakpoints, stats, err)
    write(line, '(a,a,f5.2,a,i0,a,l1,a,es9.2,a,i0,a,i0,a,i0,a,i0)') &
      trim(INTEGRATOR_NAMES(opts%method)), ' t_b', t_b, ' breakpoints ', size(breakpoints), &
      ' F(t_b) on ', force_at_t_b, ': error', sys%max_error, ', steps ', stats%n_steps, ', accel ', stats%n_rhs_evals, &
      ', err test fails ', stats%n_err_test_fails, ', restarts ', stats%n_restarts
    write(*, '(4x,a)') trim(line)
  end subroutine run

  subroutine check_bdf(t_b, force_at_t_b)
    real(wp), intent(in) :: t_b
    logical, intent(in) :: force_at_t_b
    type(switched_oscillator_t) :: sys, sys_blind
    type(integrator_stats_t) :: stats, stats_blind
    type(error_t) :: err
    real(wp) :: none(0)
    call run(bdf, t_b, force_at_t_b, [t_b], sys, stats, err)
    call suite%check(err%ok() .and. stats%n_restarts == 1, 'bdf restarts once at t_b')
    ! Global error of an rtol-controlled run over one period of a unit-scale response is some
    ! 10 rtol (told nothing of the jump too); 1000 rtol still fails on a mishandled jump (O(1)).
    call suite%check(sys%max_error < 1000 * bdf%rtol, 'bdf is accurate across the jump')
    call suite%check(sys%n_evals_at_t_b == 0, 'bdf never evaluates a at t_b itself')
    call run(bdf, t_b, force_at_t_b, none, sys_blind, stats_blind, err)
    call suite%check(err%ok() .and. stats_blind%n_restarts == 0, &
      'bdf also runs without being told of the jump')
    call suite%check(stats%n_err_test_fails < stats_blind%n_err_test_fails, &
      'the restart saves the error test failures at the jump')
  end subroutine check_bdf

  subroutine check_galpha(t_b, force_at_t_b)
    real(wp), intent(in) :: t_b
    logical, intent(in) :: force_at_t_b
    type(integrator_options_t) :: opts
    type(switched_oscillator_t) :: sys, sys_fine, sys_blind, sys_blind_fine
    type(integrator_stats_t) :: stats
    type(error_t) :: err
    real(wp) :: none(0)
    opts = galpha
    call run(opts, t_b, force_at_t_b, [t_b], sys, stats, err)
    call suite%check(err%ok() .and. stats%n_restarts == 1, 'galpha restarts once at t_b')
    call suite%check(sys%n_evals_at_t_b == 0, 'galpha never evaluates a at t_b itself')
    opts%dt = galpha%dt / 2
    call run(opts, t_b, force_at_t_b, [t_b], sys_fine, stats, err)
    call suite%order(sys%max_error, sys_fine%max_error, 2, &
      'galpha stays second order across the jump')
    ! Told nothing, galpha steps over the jump and drops to first order.
    call run(galpha, t_b, force_at_t_b, none, sys_blind, stats, err)
    call run(opts, t_b, force_at_t_b, none, sys_blind_fine, stats, err)
    call suite%check(sys_blind%max_error > 2 * sys%max_error, &
      'the breakpoint makes galpha more accurate')
  end subroutine check_galpha

  subroutine check_outside_and_repeated()
    type(switched_oscillator_t) :: sys
    type(integrator_stats_t) :: stats
    type(error_t) :: err
    call run(bdf, 0.37_wp, .false., [2.0_wp, 0.37_wp, -1.0_wp, 0.0_wp, 1.0_wp, 0.37_wp], &
      sys, stats, err)
    call suite%check(err%ok() .and. stats%n_restarts == 1, &
      'breakpoints outside (t0, t_end) and repeats are ignored')
    ! A breakpoint a rounding error after an output time: no step to take, only a restart.
    call run(bdf, 0.4_wp, .false., [nearest(0.4_wp, 1.0_wp)], sys, stats, err)
    call suite%check(err%ok() .and. stats%n_restarts == 1 .and. sys%max_error < 1000 * bdf%rtol, &
      'a breakpoint next to an output time is handled')
  end subroutine check_outside_and_repeated
end program test_integrators_breakpoint
