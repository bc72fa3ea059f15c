!> ARKODE's explicit Runge-Kutta method ('erk') through the driver: dense output is as accurate
!> as the steps, higher orders take fewer steps, breakpoints restart it, status codes and bad
!> options are handled as for the other methods. (That its error follows rtol is checked with
!> the other methods' in test_integrators_oscillator.)
program test_integrators_erk
  use core_kinds, only: wp, i8
  use core_error, only: error_t, ERR_INPUT, ERR_NUMERIC
  use core_strings, only: int_str
  use integrators_system, only: integrator_options_t, integrator_stats_t, &
    INTEGRATOR_ERK, INTEGRATOR_AUTO
  use integrators_driver, only: integrate
  use test_oscillators, only: oscillator_t, run_oscillator, switched_oscillator_t, &
    failing_oscillator_t
  use testing, only: suite_t
  implicit none
  type(suite_t) :: suite
  real(wp), allocatable :: t_out(:)
  real(wp) :: no_breakpoints(0)
  integer :: i

  call suite%init('integrators: explicit Runge-Kutta (ARKODE ERKStep)')
  t_out = [(0.1_wp * i, i = 0, 10)]
  call check_dense_output()
  call check_orders()
  call check_bad_options()
  call check_breakpoint()
  call check_recoverable()
  call check_repeated_recoverable()
  call check_fatal()
  call check_step_limit()
  call suite%finish()

contains

  subroutine run(opts, times, sys, stats, err)
    type(integrator_options_t), intent(in) :: opts
    real(wp), intent(in) :: times(:)
    type(oscillator_t), intent(out) :: sys
    type(integrator_stats_t), intent(out) :: stats
    type(error_t), intent(out) :: err
    character(len=120) :: line
    call run_oscillator(sys, opts, times, stats, err)
    write(line, '(a,i0,a,es8.1,a,i0,a,es9.2,a,i0,a,i0,a,i0)') 'erk order ', opts%erk_order, &
      ' rtol', opts%rtol, ', ', size(times), ' outputs: error', sys%max_error, ', steps ', &
      stats%n_steps, ', accel ', stats%n_rhs_evals, ', err test fails ', stats%n_err_test_fails
    write(*, '(4x,a)') trim(line)
  end subroutine run

  !> Many outputs per step: all but the last come from ARKODE's interpolant, the last one
  !> (the stop time) from the step itself.
  subroutine check_dense_output()
    type(integrator_options_t) :: opts
    type(oscillator_t) :: sys
    type(integrator_stats_t) :: stats
    type(error_t) :: err
    opts = integrator_options_t(method=INTEGRATOR_ERK, rtol=1.0e-6_wp, atol=1.0e-8_wp)
    call run(opts, [(1.0e-3_wp * i, i = 0, 2000)], sys, stats, err)
    call suite%check(err%ok() .and. sys%n_records == 2001 .and. sys%times_exact, &
      'erk records 2001 output times')
    call suite%check(stats%n_steps < 200, 'erk steps over many outputs at once')
    call suite%check(sys%max_error < 200 * opts%rtol, 'erk is as accurate between steps')
  end subroutine check_dense_output

  !> Each order's own accuracy, at the end time (a step end, no interpolation), and its cost.
  subroutine check_orders()
    integer, parameter :: orders(6) = [2, 3, 4, 5, 6, 8]
    type(integrator_options_t) :: opts
    type(oscillator_t) :: sys
    type(integrator_stats_t) :: stats
    type(error_t) :: err
    integer(i8) :: steps(size(orders))
    integer :: i

    do i = 1, size(orders)
      opts = integrator_options_t(method=INTEGRATOR_ERK, rtol=1.0e-8_wp, atol=1.0e-10_wp, &
        erk_order=orders(i))
      call run(opts, [0.0_wp, 2.0_wp], sys, stats, err)
      ! Two periods at unit amplitude: up to 5 rtol (orders 2, 3); 100 rtol still fails a wrong
      ! solution (O(1)) or an error control that ignores rtol.
      call suite%check(err%ok() .and. sys%max_error < 100 * opts%rtol, &
        'erk order ' // int_str(orders(i)) // ' is accurate')
      steps(i) = stats%n_steps
    end do
    call suite%check(steps(6) < steps(1), 'erk order 8 takes fewer steps than order 2')
    call suite%check(steps(4) < steps(1), 'erk order 5 takes fewer steps than order 2')
  end subroutine check_orders

  subroutine check_breakpoint()
    type(integrator_options_t) :: opts
    type(switched_oscillator_t) :: sys, sys_blind
    type(integrator_stats_t) :: stats, stats_blind
    type(error_t) :: err
    opts = integrator_options_t(method=INTEGRATOR_ERK, rtol=1.0e-7_wp, atol=1.0e-9_wp)
    call integrate(sys, opts, t_out, [0.0_wp], [0.0_wp], [sys%t_b], stats, err)
    write(*, '(4x,a,es9.2,a,i0,a,i0,a,i0)') 'erk with breakpoint: error', sys%max_error, &
      ', steps ', stats%n_steps, ', err test fails ', stats%n_err_test_fails, ', restarts ', &
      stats%n_restarts
    call suite%check(err%ok() .and. stats%n_restarts == 1 .and. sys%n_records == size(t_out), &
      'erk restarts once at t_b')
    call suite%check(sys%max_error < 100 * opts%rtol, 'erk is accurate across the jump')
    call suite%check(sys%n_evals_at_t_b == 0, 'erk never evaluates a at t_b itself')
    call integrate(sys_blind, opts, t_out, [0.0_wp], [0.0_wp], no_breakpoints, stats_blind, err)
    write(*, '(4x,a,es9.2,a,i0,a,i0)') 'erk told nothing: error', sys_blind%max_error, &
      ', steps ', stats_blind%n_steps, ', err test fails ', stats_blind%n_err_test_fails
    call suite%check(err%ok() .and. stats_blind%n_restarts == 0, &
      'erk also runs without being told of the jump')
    call suite%check(stats%n_err_test_fails < stats_blind%n_err_test_fails, &
      'the restart saves the error test failures at the jump')
    ! A breakpoint a rounding error after an output time: no step to take, only a restart.
    sys%t_b = 0.4_wp
    call integrate(sys, opts, t_out, [0.0_wp], [0.0_wp], [nearest(sys%t_b, 1.0_wp)], stats, err)
    call suite%check(err%ok() .and. stats%n_restarts == 1 .and. sys%max_error < 100 * opts%rtol, &
      'erk handles a breakpoint next to an output time')
  end subroutine check_breakpoint

  subroutine check_bad_options()
    call expect_input_error(integrator_options_t(method=INTEGRATOR_ERK, erk_order=7), 'erk_order', &
      'erk_order 7')
    call expect_input_error(integrator_options_t(method=INTEGRATOR_ERK, erk_order=1), 'erk_order', &
      'erk_order 1')
    call expect_input_error(integrator_options_t(method=INTEGRATOR_ERK, rtol=0.0_wp), 'rtol', &
      'rtol = 0')
    call expect_input_error(integrator_options_t(method=INTEGRATOR_ERK, atol=-1.0_wp), 'atol', &
      'atol < 0')
    call expect_input_error(integrator_options_t(method=INTEGRATOR_ERK, max_step=-1.0_wp), &
      'max_step', 'max_step < 0')
    call expect_input_error(integrator_options_t(method=INTEGRATOR_AUTO), "'erk'", &
      'method auto, which the caller resolves (the message lists erk)')
  end subroutine check_bad_options

  subroutine expect_input_error(opts, word, what)
    type(integrator_options_t), intent(in) :: opts
    character(len=*), intent(in) :: word, what
    type(oscillator_t) :: sys
    type(integrator_stats_t) :: stats
    type(error_t) :: err
    call integrate(sys, opts, t_out, [1.0_wp], [0.0_wp], no_breakpoints, stats, err)
    call suite%check(err%code == ERR_INPUT .and. sys%n_records == 0, &
      'bad option gives ERR_INPUT: ' // what)
    if (.not. err%ok()) write(*, '(4x,a)') 'message: ' // err%message
    if (err%ok()) return
    call suite%check(index(err%message, word) > 0, 'the message names ' // word)
  end subroutine expect_input_error

  subroutine check_recoverable()
    type(failing_oscillator_t) :: sys
    type(integrator_stats_t) :: stats
    type(error_t) :: err
    sys%status_code = 1
    sys%n_failures = 1
    call integrate(sys, integrator_options_t(method=INTEGRATOR_ERK), t_out, [1.0_wp], [0.0_wp], &
      no_breakpoints, stats, err)
    write(*, '(4x,a,i0,a,i0,a,es9.2)') 'erk after one recoverable status: steps ', &
      stats%n_steps, ', err test fails ', stats%n_err_test_fails, ', error ', sys%max_error
    if (.not. err%ok()) write(*, '(4x,a)') 'message: ' // err%message
    call suite%check(sys%n_failures == 0, 'erk: the failing call happened')
    call suite%check(err%ok() .and. sys%n_records == size(t_out), &
      'erk retries after a recoverable status')
    call suite%check(sys%max_error < 1.0e-4_wp, 'erk is still accurate after the retry')
  end subroutine check_recoverable

  !> A status that stays recoverable however small the step: the retries are limited.
  subroutine check_repeated_recoverable()
    type(failing_oscillator_t) :: sys
    type(integrator_stats_t) :: stats
    type(error_t) :: err
    sys%status_code = 1
    sys%n_failures = huge(1)
    call integrate(sys, integrator_options_t(method=INTEGRATOR_ERK), t_out, [1.0_wp], [0.0_wp], &
      no_breakpoints, stats, err)
    call suite%check(err%code == ERR_NUMERIC .and. index(err%message, 'retries') > 0, &
      'erk gives up after repeated recoverable statuses')
    if (.not. err%ok()) write(*, '(4x,a)') 'message: ' // err%message
    call suite%check(sys%n_records == 6, 'erk: outputs stop at the failure')
  end subroutine check_repeated_recoverable

  subroutine check_fatal()
    type(failing_oscillator_t) :: sys
    type(integrator_stats_t) :: stats
    type(error_t) :: err
    sys%status_code = -2
    sys%n_failures = 1
    call integrate(sys, integrator_options_t(method=INTEGRATOR_ERK), t_out, [1.0_wp], [0.0_wp], &
      no_breakpoints, stats, err)
    call suite%check(err%code == ERR_NUMERIC, 'erk: a fatal status is an ERR_NUMERIC')
    if (.not. err%ok()) write(*, '(4x,a)') 'message: ' // err%message
    call suite%check(index(err%message, 't = 0.5') > 0 .or. index(err%message, 't = 0.6') > 0, &
      'erk: the message gives the time')
    call suite%check(index(err%message, 'status -2') > 0, 'erk: the message gives the status')
    call suite%check(sys%n_records == 6, 'erk: outputs stop at the failure')
  end subroutine check_fatal

  subroutine check_step_limit()
    type(integrator_options_t) :: opts
    type(oscillator_t) :: sys
    type(integrator_stats_t) :: stats
    type(error_t) :: err
    opts = integrator_options_t(method=INTEGRATOR_ERK, max_steps=30_i8)
    call integrate(sys, opts, t_out, [1.0_wp], [0.0_wp], no_breakpoints, stats, err)
    call suite%check(err%code == ERR_NUMERIC .and. stats%n_steps <= opts%max_steps, &
      'erk: max_steps limits the whole run')
    if (.not. err%ok()) write(*, '(4x,a)') 'message: ' // err%message
  end subroutine check_step_limit
end program test_integrators_erk
