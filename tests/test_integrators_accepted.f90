!> ode2_system_t%step_accepted: every integrator calls it once per accepted step, in time
!> order, with the state it accepted (on the solution within the run's error), never with a
!> rejected trial; CVODE stepping one step per call for a system that wants the steps gives
!> the same outputs, bit for bit, as one call per output.
module accepted_oscillators
  use core_kinds, only: wp
  use test_oscillators, only: oscillator_t, oscillator_error
  implicit none
  private
  public :: watched_oscillator_t

  !> The oscillator, keeping what step_accepted is given.
  type, extends(oscillator_t) :: watched_oscillator_t
    logical :: wants = .true.
    integer :: n_accepted = 0
    real(wp) :: t_last = -1.0_wp
    logical :: in_order = .true.
    real(wp) :: accepted_error = 0.0_wp   !< largest oscillator_error at the accepted states
  contains
    procedure :: step_accepted => watched_step_accepted
    procedure :: wants_steps => watched_wants_steps
  end type watched_oscillator_t

contains

  subroutine watched_step_accepted(this, t, q, v)
    class(watched_oscillator_t), intent(inout) :: this
    real(wp), intent(in) :: t, q(:), v(:)
    this%n_accepted = this%n_accepted + 1
    this%in_order = this%in_order .and. t > this%t_last
    this%t_last = t
    this%accepted_error = max(this%accepted_error, oscillator_error(this%omega, t, q(1), v(1)))
  end subroutine watched_step_accepted

  logical function watched_wants_steps(this)
    class(watched_oscillator_t), intent(in) :: this
    watched_wants_steps = this%wants
  end function watched_wants_steps
end module accepted_oscillators

program test_integrators_accepted
  use core_kinds, only: wp
  use core_error, only: error_t
  use integrators_system, only: integrator_options_t, integrator_stats_t, INTEGRATOR_BDF, &
    INTEGRATOR_GALPHA, INTEGRATOR_GALPHA_ADAPTIVE, INTEGRATOR_ERK
  use integrators_driver, only: integrate
  use accepted_oscillators, only: watched_oscillator_t
  use testing, only: suite_t
  implicit none
  type(suite_t) :: suite
  real(wp), allocatable :: t_out(:)
  real(wp), parameter :: pi = acos(-1.0_wp)
  integer :: i

  call suite%init('integrators: step_accepted at every accepted step')
  t_out = [(0.1_wp * i, i = 0, 10)]
  ! Bounds on the error at the accepted states over one period: BDF and ERK 1000 rtol (observed
  ! 15 and 0.4 rtol); galpha_adaptive, second order under local error control, 200 rtol^(2/3)
  ! (test_integrators_agalpha; observed 3.4 rtol^(2/3)); galpha's fixed step 2 omega T
  ! (omega dt)^2 as in test_integrators_status (observed 0.06 of it).
  call check('bdf', integrator_options_t(method=INTEGRATOR_BDF, rtol=1.0e-6_wp, &
    atol=1.0e-8_wp), 1.0e-3_wp)
  call check('galpha_adaptive', integrator_options_t(method=INTEGRATOR_GALPHA_ADAPTIVE, &
    rtol=1.0e-6_wp, atol=1.0e-8_wp), 200 * 1.0e-6_wp**(2.0_wp / 3))
  call check('erk', integrator_options_t(method=INTEGRATOR_ERK, rtol=1.0e-6_wp, &
    atol=1.0e-8_wp), 1.0e-3_wp)
  call check('galpha', integrator_options_t(method=INTEGRATOR_GALPHA, dt=0.005_wp), &
    2 * (2 * pi)**3 * 0.005_wp**2)
  call check_cvode_one_step()
  call suite%finish()

contains

  subroutine check(name, opts, tol)
    character(len=*), intent(in) :: name
    type(integrator_options_t), intent(in) :: opts
    real(wp), intent(in) :: tol
    type(watched_oscillator_t) :: sys
    type(integrator_stats_t) :: stats
    type(error_t) :: err
    real(wp) :: none(0)
    call integrate(sys, opts, t_out, [1.0_wp], [0.0_wp], none, stats, err)
    write(*, '(4x,a,i0,a,i0,a,i0,a,es9.2)') name // ': steps ', stats%n_steps, &
      ', step_accepted calls ', sys%n_accepted, ', rejected ', stats%n_err_test_fails, &
      ', error at the accepted states ', sys%accepted_error
    call suite%check(err%ok(), name // ' runs')
    call suite%check(sys%n_accepted == stats%n_steps, name // ': one call per accepted step')
    call suite%check(sys%in_order, name // ': in time order')
    call suite%check(abs(sys%t_last - t_out(size(t_out))) <= 1.0e-12_wp, &
      name // ': the last at the end of the run')
    call suite%check(sys%accepted_error < tol, name // ': the accepted states are on the solution')
  end subroutine check

  !> Outputs 1 ms apart at a rough tolerance: a step passes several of them (the next call
  !> then starts with CVODE already past its target), and at a tight one: several steps
  !> between outputs.
  subroutine check_cvode_one_step()
    real(wp) :: dense_out(1001)
    integer :: j
    do j = 1, size(dense_out)
      dense_out(j) = 1.0e-3_wp * (j - 1)
    end do
    call compare_modes(dense_out, 1.0e-3_wp, 'outputs 1 ms apart')
    call compare_modes(t_out, 1.0e-8_wp, 'outputs 0.1 s apart')
  end subroutine check_cvode_one_step

  subroutine compare_modes(times, rtol, what)
    real(wp), intent(in) :: times(:), rtol
    character(len=*), intent(in) :: what
    type(watched_oscillator_t) :: stepped, normal
    type(integrator_stats_t) :: s1, s2
    type(error_t) :: e1, e2
    type(integrator_options_t) :: opts
    real(wp) :: none(0)
    opts = integrator_options_t(method=INTEGRATOR_BDF, rtol=rtol, atol=1.0e-2_wp * rtol)
    normal%wants = .false.
    call integrate(stepped, opts, times, [1.0_wp], [0.0_wp], none, s1, e1)
    call integrate(normal, opts, times, [1.0_wp], [0.0_wp], none, s2, e2)
    write(*, '(4x,a,i0,a,i0,a)') 'bdf, ' // what // ': ', s1%n_steps, ' steps for ', &
      size(times) - 1, ' outputs'
    if (.not. e1%ok()) write(*, '(4x,a)') 'one step at a time: ' // e1%message
    call suite%check(e1%ok() .and. e2%ok(), 'bdf, ' // what // ': both modes run')
    call suite%check(normal%n_accepted == 0, 'bdf, ' // what // &
      ': no step calls for a system that wants none')
    call suite%check(stepped%n_accepted == s1%n_steps, 'bdf, ' // what // &
      ': one call per accepted step')
    call suite%check(s1%n_steps == s2%n_steps .and. s1%n_rhs_evals == s2%n_rhs_evals, &
      'bdf, ' // what // ': the same steps one at a time')
    call suite%check(stepped%n_records == normal%n_records .and. &
      stepped%last_q == normal%last_q .and. stepped%max_error == normal%max_error, &
      'bdf, ' // what // ': the same outputs one step at a time')
  end subroutine compare_modes
end program test_integrators_accepted
