!> Undamped linear oscillator q'' = -omega^2 q (test_oscillators) against its exact solution,
!> for all methods: the error of the adaptive ones (BDF, ERK) follows rtol, generalized-alpha's
!> shrinks fourfold when dt halves.
program test_integrators_oscillator
  use core_kinds, only: wp
  use core_error, only: error_t
  use integrators_system, only: integrator_options_t, integrator_stats_t, &
    INTEGRATOR_BDF, INTEGRATOR_GALPHA, INTEGRATOR_ERK, INTEGRATOR_NAMES, JACOBIAN_INTERNAL
  use test_oscillators, only: oscillator_t, run_oscillator
  use testing, only: suite_t
  implicit none
  type(suite_t) :: suite
  real(wp), allocatable :: t_out(:)
  integer :: i

  call suite%init('integrators: linear oscillator')
  t_out = [(0.125_wp * i, i = 0, 16)]
  call check_adaptive(INTEGRATOR_BDF)
  call check_adaptive(INTEGRATOR_ERK)
  call check_bdf_internal_jacobian()
  call check_galpha(0.8_wp)
  call check_galpha(1.0_wp)
  call check_galpha(0.0_wp)
  call check_galpha_uneven_steps()
  call suite%finish()

contains

  !> INTEGRATOR_BDF or INTEGRATOR_ERK at three tolerances.
  subroutine check_adaptive(method)
    integer, intent(in) :: method
    type(integrator_options_t) :: opts
    type(oscillator_t) :: sys
    type(integrator_stats_t) :: stats
    type(error_t) :: err
    real(wp) :: errors(3), rtols(3)
    integer :: i
    logical :: implicit_method, counters_ok
    character(len=120) :: line
    character(len=:), allocatable :: name

    name = trim(INTEGRATOR_NAMES(method))
    ! Only BDF evaluates Jacobians and solves nonlinear systems.
    implicit_method = method == INTEGRATOR_BDF
    rtols = [1.0e-4_wp, 1.0e-6_wp, 1.0e-8_wp]
    do i = 1, 3
      opts = integrator_options_t(method=method, rtol=rtols(i), atol=1.0e-2_wp * rtols(i))
      call run_oscillator(sys, opts, t_out, stats, err)
      call suite%check(err%ok(), name // ' runs at rtol ' // es(rtols(i)))
      errors(i) = sys%max_error
      write(line, '(a,a,es8.1,a,es9.2,a,i0,a,i0,a,i0,a,i0)') name, ' rtol', rtols(i), &
        ': error', errors(i), ', steps ', stats%n_steps, ', accel ', stats%n_rhs_evals, &
        ', jac ', stats%n_jac_evals, ', err test fails ', stats%n_err_test_fails
      write(*, '(4x,a)') trim(line)
      call suite%check(sys%n_records == size(t_out) .and. sys%times_exact, &
        name // ' records every output time exactly')
      counters_ok = stats%n_steps > 0 .and. stats%n_rhs_evals > stats%n_steps .and. &
        stats%n_restarts == 0 .and. (stats%n_jac_evals > 0 .eqv. implicit_method) .and. &
        (stats%n_nonlin_fails == 0 .or. implicit_method)
      call suite%check(counters_ok, name // ' counters are filled')
      ! Global error over 2 periods grows past rtol as rtol shrinks (10, 40, 60 rtol for bdf):
      ! 2000 rtol still fails an integrator that ignores rtol (error O(1) at rtol 1e-4).
      call suite%check(errors(i) < 2000 * rtols(i), name // ' error is of the order of rtol')
    end do
    ! 100x smaller rtol: at least 2x smaller error (bdf gains about 30x, erk 100x).
    call suite%check(errors(2) < 0.5_wp * errors(1) .and. errors(3) < 0.5_wp * errors(2), &
      name // ' error shrinks with rtol')
  end subroutine check_adaptive

  subroutine check_bdf_internal_jacobian()
    type(integrator_options_t) :: opts
    type(oscillator_t) :: sys
    type(integrator_stats_t) :: stats
    type(error_t) :: err
    opts = integrator_options_t(method=INTEGRATOR_BDF, rtol=1.0e-6_wp, atol=1.0e-8_wp, &
      jacobian=JACOBIAN_INTERNAL)
    call run_oscillator(sys, opts, t_out, stats, err)
    call suite%check(err%ok() .and. sys%max_error < 200 * opts%rtol, &
      'bdf with the internal Jacobian is as accurate')
  end subroutine check_bdf_internal_jacobian

  subroutine check_galpha(rho_inf)
    real(wp), intent(in) :: rho_inf
    type(integrator_options_t) :: opts
    type(oscillator_t) :: sys
    type(integrator_stats_t) :: stats
    type(error_t) :: err
    real(wp) :: errors(3), dts(3)
    integer :: i
    character(len=100) :: line

    dts = [1.0_wp / 64, 1.0_wp / 128, 1.0_wp / 256]
    do i = 1, 3
      opts = integrator_options_t(method=INTEGRATOR_GALPHA, dt=dts(i), rho_inf=rho_inf)
      call run_oscillator(sys, opts, t_out, stats, err)
      call suite%check(err%ok() .and. sys%n_records == size(t_out) .and. sys%times_exact, &
        'galpha runs, rho_inf ' // fx(rho_inf) // ' dt ' // es(dts(i)))
      errors(i) = sys%max_error
      write(line, '(a,f4.2,a,es9.2,a,es9.2,a,i0,a,i0,a,i0)') 'galpha rho_inf ', rho_inf, &
        ' dt', dts(i), ': error', errors(i), ', steps ', stats%n_steps, ', accel ', &
        stats%n_rhs_evals, ', jac ', stats%n_jac_evals
      write(*, '(4x,a)') trim(line)
      call suite%check(stats%n_steps == nint(2 / dts(i), kind(stats%n_steps)), &
        'galpha takes exactly (t_end - t0) / dt steps')
    end do
    do i = 2, 3
      call suite%order(errors(i - 1), errors(i), 2, 'galpha second order')
    end do
  end subroutine check_galpha

  !> dt does not divide the output interval: the steps are shortened, outputs still exact.
  subroutine check_galpha_uneven_steps()
    type(integrator_options_t) :: opts
    type(oscillator_t) :: sys, sys_fine
    type(integrator_stats_t) :: stats
    type(error_t) :: err
    opts = integrator_options_t(method=INTEGRATOR_GALPHA, dt=0.0113_wp, rho_inf=0.8_wp)
    call run_oscillator(sys, opts, t_out, stats, err)
    call suite%check(err%ok() .and. sys%times_exact, 'galpha lands on outputs with uneven dt')
    call suite%check(stats%n_steps == 16 * ceiling(0.125_wp / opts%dt), &
      'galpha shortens steps evenly within each output interval')
    opts%dt = opts%dt / 2
    call run_oscillator(sys_fine, opts, t_out, stats, err)
    call suite%order(sys%max_error, sys_fine%max_error, 2, &
      'galpha stays second order with shortened steps')
  end subroutine check_galpha_uneven_steps

  function es(x) result(s)
    real(wp), intent(in) :: x
    character(len=9) :: s
    write(s, '(es9.2)') x
  end function es

  function fx(x) result(s)
    real(wp), intent(in) :: x
    character(len=4) :: s
    write(s, '(f4.2)') x
  end function fx
end program test_integrators_oscillator
