!> Adaptive generalized-alpha on the benchmark (input/two_link.nml, mid-motion): the local error
!> estimate err_coef h^2 (qdd+ - qdd) (docs/theory.md section 6.1) against the true error of
!> one step, in the weighted RMS norm that the step control uses. The state at t0 = 0.25 s
!> (both joints accelerating) comes from a tight BDF run; one step of h is forced by loose
!> tolerances, and the truth is a BDF run (rtol 1e-12) over the same step from the same state.
program test_agalpha_benchmark
  use core_kinds, only: wp
  use core_error, only: error_t
  use core_strings, only: real_str
  use io_namelist, only: nml_file_t
  use model_scene, only: scene_t
  use dynamics_system, only: dynamics_t
  use integrators_system, only: integrator_options_t, integrator_stats_t, &
    INTEGRATOR_BDF, INTEGRATOR_GALPHA_ADAPTIVE, INTEGRATOR_NAMES
  use integrators_driver, only: integrate
  use testing, only: suite_t
  use test_scenes, only: source_dir, make_dynamics_from
  implicit none

  real(wp), parameter :: T0 = 0.25_wp
  !> The weights of the norm: those of rtol 1e-6, atol 1e-8 (the scene's).
  real(wp), parameter :: RTOL = 1.0e-6_wp, ATOL = 1.0e-8_wp
  type(suite_t) :: suite
  type(nml_file_t) :: f
  type(scene_t) :: scene
  type(dynamics_t) :: dyn
  type(error_t) :: err
  real(wp), allocatable :: q0(:), v0(:)
  integer :: i

  call suite%init('integrators: adaptive generalized-alpha on the two-link benchmark')
  call f%load(source_dir() // '/input/two_link.nml', err)
  if (err%ok()) call make_dynamics_from(f, scene, dyn, err)
  call suite%check(err%ok(), 'two-link builds ' // err%message)
  if (err%ok()) then
    allocate(q0(dyn%model%n_dy), v0(dyn%model%n_dy))
    q0 = 0.0_wp
    v0 = 0.0_wp
    call advance(dyn, bdf(1.0e-11_wp), 0.0_wp, T0, q0, v0)
    do i = 1, 3
      call one_step(2.0e-4_wp / 2**(i - 1))
    end do
  end if
  call suite%finish()

contains

  function bdf(tol) result(opts)
    real(wp), intent(in) :: tol
    type(integrator_options_t) :: opts
    opts = integrator_options_t(method=INTEGRATOR_BDF, max_order=5, rtol=tol, atol=tol)
  end function bdf

  !> Integrate from (ta, q, v) to tb; q and v become the state at tb.
  subroutine advance(dyn, opts, ta, tb, q, v)
    type(dynamics_t), intent(inout) :: dyn
    type(integrator_options_t), intent(in) :: opts
    real(wp), intent(in) :: ta, tb
    real(wp), intent(inout) :: q(:), v(:)
    type(integrator_stats_t) :: stats
    real(wp) :: no_breakpoints(0)
    call dyn%allocate_history(2)
    call integrate(dyn, opts, [ta, tb], q, v, no_breakpoints, stats, err)
    call suite%check(err%ok(), trim(INTEGRATOR_NAMES(opts%method)) // ' to t = ' // &
      real_str(tb) // ' ' // err%message)
    q = dyn%q_hist(:, 2)
    v = dyn%v_hist(:, 2)
  end subroutine advance

  subroutine one_step(h)
    real(wp), intent(in) :: h
    type(integrator_options_t) :: opts
    real(wp) :: q1(size(q0)), v1(size(q0)), qr(size(q0)), vr(size(q0))
    real(wp) :: a0(size(q0)), a1(size(q0)), w(size(q0)), rho, alpha_m, alpha_f, gamma, beta
    real(wp) :: estimate, truth, ratio
    integer :: status
    character(len=120) :: line
    rho = 0.8_wp
    opts = integrator_options_t(method=INTEGRATOR_GALPHA_ADAPTIVE, dt=h, rho_inf=rho, rtol=1.0_wp, &
      atol=1.0_wp)
    q1 = q0
    v1 = v0
    call advance(dyn, opts, T0, T0 + h, q1, v1)
    qr = q0
    vr = v0
    call advance(dyn, bdf(1.0e-12_wp), T0, T0 + h, qr, vr)
    call dyn%accel(T0, q0, v0, a0, status)
    call dyn%accel(T0 + h, q1, v1, a1, status)
    alpha_m = (2 * rho - 1) / (rho + 1)
    alpha_f = rho / (rho + 1)
    gamma = 0.5_wp + alpha_f - alpha_m
    beta = 0.25_wp * (gamma + 0.5_wp)**2
    w = ATOL + RTOL * max(abs(q0), abs(q1))
    estimate = rms(abs(beta - 0.5_wp * gamma + 1.0_wp / 12) * h**2 * (a1 - a0) / w)
    truth = rms((q1 - qr) / w)
    ratio = estimate / truth
    write(line, '(a,es9.2,a,es9.2,a,es9.2,a,f6.2)') 'h ', h, ': true local error ', truth, &
      ', estimate ', estimate, ', ratio ', ratio
    write(*, '(4x,a)') trim(line)
    ! The truth must stand clear of the reference's own error (rtol 1e-12 on q ~ 1e-3).
    call suite%check(truth > 1.0e-3_wp, 'the step error is resolved, ' // trim(line))
    call suite%check(ratio > 0.1_wp .and. ratio < 10, 'estimate within 10x of the true ' // &
      'local error, ' // trim(line))
  end subroutine one_step

  pure real(wp) function rms(x)
    real(wp), intent(in) :: x(:)
    rms = sqrt(sum(x**2) / size(x))
  end function rms
end program test_agalpha_benchmark
