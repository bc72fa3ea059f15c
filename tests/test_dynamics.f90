!> Dynamics of whole models (docs/theory.md section 5; section 10, 'Energy conservation'):
!>  1. energy conservation of undamped free vibrations: the two-link of input/two_link.nml with
!>     both joints held (law = 'constant'), released from its static deflection under a tip
!>     load, with BDF (rtol 1e-8) and generalized-alpha (rho_inf = 1 conserves, rho_inf = 0.8
!>     dissipates: the energy may only decrease); a flexible pendulum (dynamic hinge without
!>     stiffness at a fixed base, gravity) released from horizontal through large rotations;
!>  2. the Jacobian options (linearised, fd, CVODE internal) give the same tip trajectory of
!>     the benchmark, and the linearised one needs the fewest model evaluations;
!>  3. stiffness-proportional damping (link damping = beta): the energy decreases between
!>     outputs, and the first mode decays at zeta_1 = beta omega_1 / 2;
!>  4. the benchmark itself past the end of the motion (0.5 s): the energy is constant once
!>     the joints stop, BDF restarts at the breakpoint, and generalized-alpha (dt = 5e-4)
!>     agrees with BDF (rtol 1e-9) on the tip position.
program test_dynamics
  use core_kinds, only: wp, i8
  use core_error, only: error_t
  use io_namelist, only: nml_file_t
  use model_scene, only: scene_t
  use dynamics_system, only: dynamics_t
  use dynamics_static, only: static_solve
  use reduction_modal, only: modal_result_t, modal_analysis
  use integrators_system, only: integrator_options_t, integrator_stats_t, &
    INTEGRATOR_BDF, INTEGRATOR_GALPHA, JACOBIAN_LINEARISED, JACOBIAN_FD, JACOBIAN_INTERNAL, &
    JACOBIAN_NAMES
  use integrators_driver, only: integrate
  use testing, only: suite_t
  use test_scenes, only: rtxt, source_dir, make_dynamics
  implicit none

  character(len=*), parameter :: NL = new_line('a')
  real(wp), parameter :: PI = 3.14159265358979323846_wp

  !> A flexible pendulum: one steel link on a free hinge (no stiffness) at a fixed base, a
  !> tip mass, gravity; horizontal in the reference state.
  character(len=*), parameter :: PENDULUM_TEXT = &
    "&scene title = 'flexible pendulum', gravity = 0.0, -9.81 /" // NL // &
    "&node label = 'base', x = 0.0, y = 0.0, fixed = .true. /" // NL // &
    "&node label = 'tip', x = 0.8, y = 0.0 /" // NL // &
    "&link label = 'arm', from = 'base', to = 'tip', n_elements = 2," // NL // &
    "      E = 2.1e11, A = 2.0e-4, I = 1.0e-9, rho = 7800 /" // NL // &
    "&hinge label = 'pivot', node = 'base', link = 'arm', mode = 'dynamic', stiffness = 0.0 /" &
    // NL // &
    "&mass node = 'tip', m = 0.5 /" // NL

  type(suite_t) :: suite
  character(len=:), allocatable :: two_link

  call suite%init('dynamics: energy conservation, Jacobians, damping, prescribed motion')
  call lap('')
  call load_two_link(two_link)
  if (len(two_link) > 0) then
    call free_vibration(two_link)
    call lap('free vibration')
    call damped_vibration(two_link)
    call lap('damping')
    call jacobian_options(two_link)
    call lap('jacobians')
    call benchmark_run(two_link)
    call lap('benchmark')
  end if
  call pendulum()
  call lap('pendulum')
  call suite%finish()

contains

  ! ------------------------------------------------------------------ utilities

  !> CPU time since the last call, printed.
  subroutine lap(what)
    character(len=*), intent(in) :: what
    real(wp), save :: last = -1.0_wp
    real(wp) :: now
    call cpu_time(now)
    if (last >= 0) write(*, '(a,f6.2,a)') '    [' // what // ': ', now - last, ' s CPU]'
    last = now
  end subroutine lap

  subroutine load_two_link(text)
    character(len=:), allocatable, intent(out) :: text
    type(nml_file_t) :: f
    type(error_t) :: err
    character(len=:), allocatable :: path
    path = source_dir() // '/input/two_link.nml'
    call f%load(path, err)
    call suite%check(err%ok(), 'two-link: ' // path // ' loads')
    if (err%ok()) then
      text = f%text
    else
      write(*, '(a)') '    ' // err%message
      text = ''
    end if
  end subroutine load_two_link

  !> text with every occurrence of old replaced by new.
  function replaced(text, old, new) result(t)
    character(len=*), intent(in) :: text, old, new
    character(len=:), allocatable :: t
    integer :: p, k
    t = ''
    p = 1
    do
      k = index(text(p:), old)
      if (k == 0) exit
      t = t // text(p:p + k - 2) // new
      p = p + k - 1 + len(old)
    end do
    t = t // text(p:)
  end function replaced

  !> The two-link with both joints held at 0 (the motion laws replaced by constants).
  function held(text) result(t)
    character(len=*), intent(in) :: text
    character(len=:), allocatable :: t
    t = replaced(text, "law = 'cubic'", "law = 'constant'")
  end function held

  !> Parse, read, build and initialise at (t0, q0); q0 = 0 if absent.
  subroutine make(text, dyn, err, q0)
    character(len=*), intent(in) :: text
    type(dynamics_t), intent(out) :: dyn
    type(error_t), intent(out) :: err
    real(wp), intent(in), optional :: q0(:)
    type(scene_t) :: scene
    call make_dynamics(text, scene, dyn, err, q0)
  end subroutine make

  function linspace(a, b, n) result(t)
    real(wp), intent(in) :: a, b
    integer, intent(in) :: n
    real(wp) :: t(n)
    integer :: k
    do k = 1, n
      t(k) = a + (b - a) * real(k - 1, wp) / (n - 1)
    end do
    t(n) = b
  end function linspace

  !> Breakpoints of all motions of the model (as analysis_run collects them).
  function motion_breaks(dyn) result(b)
    type(dynamics_t), intent(in) :: dyn
    real(wp), allocatable :: b(:)
    integer :: i
    allocate(b(0))
    do i = 1, dyn%model%n_motions
      b = [b, dyn%model%motions(i)%breakpoints()]
    end do
  end function motion_breaks

  !> Integrate from (q0, v = 0) at the output times t; fills dyn's histories.
  subroutine run(dyn, opts, t, q0, stats, err)
    type(dynamics_t), intent(inout) :: dyn
    type(integrator_options_t), intent(in) :: opts
    real(wp), intent(in) :: t(:), q0(:)
    type(integrator_stats_t), intent(out) :: stats
    type(error_t), intent(out) :: err
    real(wp) :: v0(size(q0))
    v0 = 0.0_wp
    call dyn%allocate_history(size(t))
    call integrate(dyn, opts, t, q0, v0, motion_breaks(dyn), stats, err)
    if (.not. err%ok()) then
      write(*, '(a)') '    ' // err%message
      if (allocated(dyn%last_error%message)) write(*, '(a)') '    (' // &
        dyn%last_error%message // ')'
    end if
  end subroutine run

  !> Tip position history (2, nt).
  function tip_history(dyn) result(p)
    type(dynamics_t), intent(in) :: dyn
    real(wp), allocatable :: p(:, :)
    integer :: in, ic(3)
    in = dyn%model%find_node('tip')
    ic = dyn%model%node_coord(1:3, in)
    p = dyn%x_hist(ic(1:2), :)
  end function tip_history

  function total_energy(dyn) result(e)
    type(dynamics_t), intent(in) :: dyn
    real(wp), allocatable :: e(:)
    e = dyn%energy_hist(1, :) + dyn%energy_hist(2, :)
  end function total_energy

  !> Largest distance between two tip histories.
  real(wp) function tip_distance(a, b)
    real(wp), intent(in) :: a(:, :), b(:, :)
    tip_distance = maxval(norm2(a - b, dim=1))
  end function tip_distance

  subroutine expect_ok(err, what)
    type(error_t), intent(in) :: err
    character(len=*), intent(in) :: what
    call suite%check(err%ok(), what)
    if (.not. err%ok()) write(*, '(a)') '    ' // err%message
  end subroutine expect_ok

  !> Static deflection of the held two-link under a tip load fy [N].
  subroutine tip_deflection(text, fy, q, err)
    character(len=*), intent(in) :: text
    real(wp), intent(in) :: fy
    real(wp), allocatable, intent(out) :: q(:)
    type(error_t), intent(out) :: err
    type(dynamics_t) :: dyn
    real(wp), allocatable :: x_steps(:, :)
    integer :: iterations
    call make(held(text) // NL // "&force node = 'tip', fy = " // rtxt(fy) // " /" // NL, &
      dyn, err)
    if (.not. err%ok()) return
    allocate(q(dyn%model%n_dy), x_steps(dyn%model%n_x, 1))
    q = 0.0_wp
    call static_solve(dyn, 0.0_wp, 1, 1.0e-12_wp, 30, q, x_steps, iterations, err)
  end subroutine tip_deflection

  ! ------------------------------------------------------------------ 1. conservation

  subroutine free_vibration(text)
    character(len=*), intent(in) :: text
    type(dynamics_t) :: dyn
    type(integrator_options_t) :: opts
    type(integrator_stats_t) :: stats
    type(error_t) :: err
    real(wp), allocatable :: q0(:), t(:), e(:), tip_bdf(:, :)
    real(wp) :: e0, drift

    call tip_deflection(text, -10.0_wp, q0, err)
    call expect_ok(err, 'free vibration: static deflection under a 10 N tip load')
    if (.not. err%ok()) return
    call make(held(text), dyn, err, q0)
    call expect_ok(err, 'free vibration: held two-link initialises in the deflected state')
    if (.not. err%ok()) return
    t = linspace(0.0_wp, 0.3_wp, 31)

    ! BDF, tight tolerances.
    opts%method = INTEGRATOR_BDF
    opts%rtol = 1.0e-8_wp
    opts%atol = 1.0e-10_wp
    call run(dyn, opts, t, q0, stats, err)
    call expect_ok(err, 'free vibration: BDF rtol 1e-8 over 0.3 s')
    if (.not. err%ok()) return
    tip_bdf = tip_history(dyn)
    e = total_energy(dyn)
    e0 = e(1)
    drift = maxval(abs(e - e0)) / e0
    write(*, '(a,es10.3,a,es10.3,a,i0,a)') '    E0 = ', e0, ' J, tip deflection ', &
      tip_bdf(2, 1), ' m, BDF: ', stats%n_steps, ' steps'
    write(*, '(a,es10.3)') '    BDF rtol 1e-8: max |E - E0| / E0 = ', drift
    call suite%check(e0 > 0 .and. dyn%energy_hist(1, 1) == 0, &
      'free vibration: starts at rest with elastic energy only')
    call suite%check(maxval(dyn%energy_hist(1, :)) > 0.5_wp * e0, &
      'free vibration: the energy is exchanged (max kinetic > E0 / 2)')
    call suite%check(drift < 1.0e-6_wp, 'free vibration: BDF rtol 1e-8 conserves E to 1e-6')

    ! Generalized-alpha without numerical damping: trapezoidal rule, conserves for linear.
    opts%method = INTEGRATOR_GALPHA
    opts%dt = 1.0e-3_wp
    opts%rho_inf = 1.0_wp
    opts%rtol = 1.0e-10_wp
    opts%atol = 1.0e-12_wp
    call run(dyn, opts, t, q0, stats, err)
    call expect_ok(err, 'free vibration: generalized-alpha rho_inf = 1, dt = 1e-3')
    if (.not. err%ok()) return
    e = total_energy(dyn)
    drift = maxval(abs(e - e0)) / e0
    write(*, '(a,es10.3,a,es10.3,a)') '    galpha rho_inf = 1: max |E - E0| / E0 = ', drift, &
      ', tip vs BDF ', tip_distance(tip_history(dyn), tip_bdf), ' m'
    call suite%check(drift < 1.0e-6_wp, &
      'free vibration: generalized-alpha rho_inf = 1 conserves E to 1e-6')

    ! rho_inf = 0.8 damps the unresolved modes: the energy may only decrease.
    opts%rho_inf = 0.8_wp
    call run(dyn, opts, t, q0, stats, err)
    call expect_ok(err, 'free vibration: generalized-alpha rho_inf = 0.8, dt = 1e-3')
    if (.not. err%ok()) return
    e = total_energy(dyn)
    write(*, '(a,es10.3,a,es10.3)') '    galpha rho_inf = 0.8: (E0 - E_end) / E0 = ', &
      (e0 - e(size(e))) / e0, ', max (E - E0) / E0 = ', maxval(e - e0) / e0
    call suite%check(e(size(e)) < e0 .and. (e0 - e(size(e))) / e0 < 0.05_wp, &
      'free vibration: generalized-alpha rho_inf = 0.8 loses a little energy (< 5%)')
    call suite%check(maxval(e - e0) <= 1.0e-9_wp * e0, &
      'free vibration: generalized-alpha rho_inf = 0.8 never gains energy')
  end subroutine free_vibration

  !> A flexible pendulum released from horizontal: large rotations, gravity.
  subroutine pendulum()
    type(dynamics_t) :: dyn
    type(integrator_options_t) :: opts
    type(integrator_stats_t) :: stats
    type(error_t) :: err
    real(wp), allocatable :: t(:), e(:), q0(:), tip(:, :)
    real(wp) :: scale, drift, angle, drop

    call make(PENDULUM_TEXT, dyn, err)
    call expect_ok(err, 'pendulum: model builds and initialises')
    if (.not. err%ok()) return
    allocate(q0(dyn%model%n_dy))
    q0 = 0.0_wp
    t = linspace(0.0_wp, 0.6_wp, 31)
    opts%method = INTEGRATOR_BDF
    opts%rtol = 1.0e-8_wp
    opts%atol = 1.0e-10_wp
    call run(dyn, opts, t, q0, stats, err)
    call expect_ok(err, 'pendulum: BDF rtol 1e-8 over 0.6 s')
    if (.not. err%ok()) return
    e = total_energy(dyn)
    tip = tip_history(dyn)
    angle = maxval(atan2(-tip(2, :), tip(1, :)))
    scale = maxval(dyn%energy_hist(1, :))
    drift = maxval(abs(e - e(1))) / scale
    write(*, '(a,i0,a,f6.1,a,es10.3,a,es10.3)') '    ', dyn%model%n_dy, &
      ' dynamic coordinates, largest swing ', angle * 180 / PI, ' deg, max kinetic ', scale, &
      ' J, BDF: max |E - E0| / max T = ', drift
    call suite%check(angle > 60 * PI / 180, 'pendulum: swings through more than 60 degrees')
    ! Through the bottom the kinetic energy is the drop of the rigid pendulum (tip mass at
    ! 0.8 m, rod of 7800 * 2e-4 * 0.8 kg with its centre at 0.4 m); the link bends a little.
    drop = 9.81_wp * (0.5_wp * 0.8_wp + 7800 * 2.0e-4_wp * 0.8_wp * 0.4_wp)
    call suite%close(scale, drop, 1.0e-2_wp, 0.0_wp, &
      'pendulum: largest kinetic energy = potential drop of the rigid pendulum (1%)')
    call suite%check(drift < 1.0e-6_wp, 'pendulum: BDF rtol 1e-8 conserves E (with gravity) ' &
      // 'to 1e-6 of the largest kinetic energy')

    opts%method = INTEGRATOR_GALPHA
    opts%dt = 1.0e-3_wp
    opts%rho_inf = 1.0_wp
    opts%rtol = 1.0e-10_wp
    opts%atol = 1.0e-12_wp
    call run(dyn, opts, t, q0, stats, err)
    call expect_ok(err, 'pendulum: generalized-alpha rho_inf = 1, dt = 1e-3')
    if (.not. err%ok()) return
    e = total_energy(dyn)
    drift = maxval(abs(e - e(1))) / scale
    write(*, '(a,es10.3,a,es10.3,a)') '    galpha rho_inf = 1: max |E - E0| / max T = ', drift, &
      ', tip vs BDF ', tip_distance(tip_history(dyn), tip), ' m'
    ! Second order, not exactly conserving when nonlinear: C (omega dt)^2 with omega^2 = g / l
    ! (l = 0.8 m); bound 10 (omega dt)^2 (first order would give omega dt).
    call suite%check(drift < 10 * 9.81_wp / 0.8_wp * opts%dt**2, 'pendulum: generalized-' // &
      'alpha rho_inf = 1 keeps E to 10 (omega dt)^2 (nonlinear: not exactly conserving)')
  end subroutine pendulum

  ! ------------------------------------------------------------------ 3. damping

  subroutine damped_vibration(text)
    character(len=*), intent(in) :: text
    real(wp), parameter :: BETA = 5.0e-3_wp
    type(dynamics_t) :: dyn
    type(integrator_options_t) :: opts
    type(integrator_stats_t) :: stats
    type(error_t) :: err
    type(modal_result_t) :: modes
    real(wp), allocatable :: q0(:), t(:), e(:), zero(:)
    real(wp) :: omega, zeta, zeta_measured, t_d, amp0, amp1, eta, eta_d
    integer :: nt, in, ic(3)
    character(len=:), allocatable :: damped

    damped = replaced(held(text), 'rho = 2700 /', 'rho = 2700, damping = ' // rtxt(BETA) // ' /')
    call tip_deflection(text, -10.0_wp, q0, err)
    if (err%ok()) call make(damped, dyn, err, q0)
    call expect_ok(err, 'damping: damped two-link (beta = 5e-3 s) in the deflected state')
    if (.not. err%ok()) return

    ! Energy decreases monotonically from the static deflection (all modes excited).
    t = linspace(0.0_wp, 0.2_wp, 41)
    opts%method = INTEGRATOR_BDF
    opts%rtol = 1.0e-8_wp
    opts%atol = 1.0e-10_wp
    call run(dyn, opts, t, q0, stats, err)
    call expect_ok(err, 'damping: BDF from the static deflection over 0.2 s')
    if (.not. err%ok()) return
    e = total_energy(dyn)
    nt = size(e)
    write(*, '(a,es10.3,a,es10.3)') '    E(0.2) / E0 = ', e(nt) / e(1), &
      ', smallest decrease between outputs / E0 = ', minval(e(:nt - 1) - e(2:)) / e(1)
    call suite%check(all(e(2:) < e(:nt - 1)), &
      'damping: total energy decreases strictly between outputs')

    ! First mode: amplitude decay over one damped period.
    allocate(zero(dyn%model%n_dy))
    zero = 0.0_wp
    call modal_analysis(dyn, 0.0_wp, zero, 1, modes, err)
    call expect_ok(err, 'damping: modal analysis of the first mode')
    if (.not. err%ok()) return
    omega = sqrt(modes%omega2(1))
    zeta = BETA * omega / 2
    t_d = 2 * PI / (omega * sqrt(1 - zeta**2))
    in = dyn%model%find_node('tip')
    ic = dyn%model%node_coord(1:3, in)
    ! First mode shape scaled to 1 cm at the tip.
    q0 = modes%shapes(:, 1) * 0.01_wp / norm2(modes%node_shapes(ic(1:2), 1, 1))
    call make(damped, dyn, err, q0)
    if (err%ok()) then
      t = linspace(0.0_wp, t_d, 9)
      call run(dyn, opts, t, q0, stats, err)
    end if
    call expect_ok(err, 'damping: BDF from the first mode shape over one damped period')
    if (.not. err%ok()) return
    nt = size(t)
    eta = dot_product(modes%shapes(:, 1), matmul(modes%m0, dyn%q_hist(:, 1)))
    eta_d = dot_product(modes%shapes(:, 1), matmul(modes%m0, dyn%v_hist(:, 1)))
    amp0 = sqrt(eta**2 + (eta_d / omega)**2)
    eta = dot_product(modes%shapes(:, 1), matmul(modes%m0, dyn%q_hist(:, nt)))
    eta_d = dot_product(modes%shapes(:, 1), matmul(modes%m0, dyn%v_hist(:, nt)))
    amp1 = sqrt(eta**2 + (eta_d / omega)**2)
    ! Single mode starting at rest: after one damped period it is at rest again with the
    ! amplitude exp(-zeta omega T_d).
    zeta_measured = -log(amp1 / amp0) / (omega * t_d)
    write(*, '(a,f8.4,a,f8.5,a,f8.5,a,f8.5)') '    f1 = ', omega / (2 * PI), ' Hz, zeta1 = ', &
      zeta, ', measured ', zeta_measured, ', from energy ', &
      -log(total_energy_at(dyn, nt) / total_energy_at(dyn, 1)) / (2 * omega * t_d)
    call suite%close(zeta_measured, zeta, 0.05_wp, 0.0_wp, &
      'damping: first-mode decay zeta1 = beta omega1 / 2 (5%)')
  end subroutine damped_vibration

  real(wp) function total_energy_at(dyn, k)
    type(dynamics_t), intent(in) :: dyn
    integer, intent(in) :: k
    total_energy_at = dyn%energy_hist(1, k) + dyn%energy_hist(2, k)
  end function total_energy_at

  ! ------------------------------------------------------------------ 2. Jacobians

  subroutine jacobian_options(text)
    character(len=*), intent(in) :: text
    integer, parameter :: KINDS(3) = [JACOBIAN_LINEARISED, JACOBIAN_FD, JACOBIAN_INTERNAL]
    type(dynamics_t) :: dyn
    type(integrator_options_t) :: opts
    type(integrator_stats_t) :: stats(3)
    type(error_t) :: err
    real(wp), allocatable :: q0(:), t(:), tip(:, :, :)
    integer(i8) :: evals(3)
    integer :: j

    allocate(t, source=linspace(0.0_wp, 0.2_wp, 21))
    opts%method = INTEGRATOR_BDF
    opts%rtol = 1.0e-8_wp
    opts%atol = 1.0e-9_wp
    do j = 1, 3
      call make(text, dyn, err)
      if (.not. err%ok()) exit
      allocate(q0(dyn%model%n_dy))
      q0 = 0.0_wp
      ! As a run sets them from &dynamic jacobian.
      opts%jacobian = KINDS(j)
      dyn%jacobian_kind = KINDS(j)
      call run(dyn, opts, t, q0, stats(j), err)
      call expect_ok(err, 'jacobians: benchmark 0..0.2 s, BDF rtol 1e-8, jacobian ' // &
        trim(JACOBIAN_NAMES(KINDS(j))))
      if (.not. err%ok()) return
      if (.not. allocated(tip)) allocate(tip(2, size(t), 3))
      tip(:, :, j) = tip_history(dyn)
      evals(j) = dyn%n_evals
      write(*, '(a,a10,a,i6,a,i7,a,i5,a,i7)') '    ', JACOBIAN_NAMES(KINDS(j)), ': steps ', &
        stats(j)%n_steps, ', rhs evals ', stats(j)%n_rhs_evals, ', Jacobians ', &
        stats(j)%n_jac_evals, ', model evals ', evals(j)
      deallocate(q0)
    end do
    call expect_ok(err, 'jacobians: benchmark builds')
    if (.not. err%ok()) return
    write(*, '(a,es10.3,a,es10.3,a,es10.3,a)') '    tip at 0.2 s: (', tip(1, size(t), 1), ', ', &
      tip(2, size(t), 1), ') m; swing of the tip ', tip_distance(tip(:, :, 1), &
      spread(tip(:, 1, 1), 2, size(t))), ' m'
    call suite%check(tip_distance(tip(:, :, 1), tip(:, :, 2)) < 1.0e-6_wp, &
      'jacobians: fd and linearised tip trajectories agree to 1e-6 m' // dist_txt(tip, 1, 2))
    call suite%check(tip_distance(tip(:, :, 1), tip(:, :, 3)) < 1.0e-6_wp, &
      'jacobians: internal and linearised tip trajectories agree to 1e-6 m' // dist_txt(tip, 1, 3))
    call suite%check(evals(1) < evals(2) .and. evals(1) < evals(3), &
      'jacobians: linearised needs the fewest model evaluations')
  end subroutine jacobian_options

  function dist_txt(tip, a, b) result(s)
    real(wp), intent(in) :: tip(:, :, :)
    integer, intent(in) :: a, b
    character(len=:), allocatable :: s
    character(len=32) :: buf
    write(buf, '(a,es9.2,a)') ' (', tip_distance(tip(:, :, a), tip(:, :, b)), ')'
    s = trim(buf)
  end function dist_txt

  ! ------------------------------------------------------------------ 4. benchmark

  subroutine benchmark_run(text)
    character(len=*), intent(in) :: text
    type(dynamics_t) :: dyn
    type(integrator_options_t) :: opts
    type(integrator_stats_t) :: stats
    type(error_t) :: err
    real(wp), allocatable :: q0(:), t(:), e(:), tip_bdf(:, :), tip_fine(:, :)
    real(wp) :: drift, e_stop, dist, estimate
    integer :: k_stop

    call make(text, dyn, err)
    call expect_ok(err, 'benchmark: model builds')
    if (.not. err%ok()) return
    allocate(q0(dyn%model%n_dy))
    q0 = 0.0_wp
    t = linspace(0.0_wp, 0.6_wp, 61)
    opts%method = INTEGRATOR_BDF
    opts%rtol = 1.0e-9_wp
    opts%atol = 1.0e-9_wp
    call run(dyn, opts, t, q0, stats, err)
    call expect_ok(err, 'benchmark: BDF rtol 1e-9 over 0..0.6 s')
    if (.not. err%ok()) return
    tip_bdf = tip_history(dyn)
    e = total_energy(dyn)
    k_stop = minloc(abs(t - 0.5_wp), 1)
    e_stop = e(k_stop)
    drift = maxval(abs(e(k_stop:) - e_stop)) / e_stop
    write(*, '(a,i0,a,i0,a,i0,a,es10.3,a,es10.3)') '    BDF: ', stats%n_steps, ' steps, ', &
      stats%n_restarts, ' restarts, ', stats%n_rhs_evals, ' rhs evals; E(0.5) = ', e_stop, &
      ' J, max |E - E(0.5)| / E(0.5) over 0.5..0.6 s = ', drift
    call suite%check(stats%n_restarts >= 1, 'benchmark: BDF restarts at the end of the motion')
    call suite%check(e_stop > 0 .and. drift < 1.0e-6_wp, &
      'benchmark: energy constant to 1e-6 after the joints stop')
    call suite%check(maxval(abs(e(:k_stop) - e_stop)) > 1.0e3_wp * drift * e_stop, &
      'benchmark: the joints do work while they move')

    opts%method = INTEGRATOR_GALPHA
    opts%dt = 5.0e-4_wp
    opts%rho_inf = 0.8_wp
    opts%rtol = 1.0e-8_wp
    opts%atol = 1.0e-10_wp
    call run(dyn, opts, t, q0, stats, err)
    call expect_ok(err, 'benchmark: generalized-alpha dt = 5e-4 over 0..0.6 s')
    if (.not. err%ok()) return
    tip_fine = tip_history(dyn)
    dist = tip_distance(tip_fine, tip_bdf)
    write(*, '(a,i0,a,i0,a,es10.3,a)') '    galpha dt = 5e-4: ', stats%n_steps, ' steps, ', &
      stats%n_restarts, ' restarts; tip vs BDF rtol 1e-9: ', dist, ' m'
    call suite%check(stats%n_restarts >= 1, &
      'benchmark: generalized-alpha restarts at the end of the motion')
    ! galpha's own error at dt by Richardson (second order: |x(2 dt) - x(dt)| / 3); BDF at
    ! rtol 1e-9 is far more accurate, so the two agree to that estimate (10x margin).
    opts%dt = 1.0e-3_wp
    call run(dyn, opts, t, q0, stats, err)
    call expect_ok(err, 'benchmark: generalized-alpha dt = 1e-3 over 0..0.6 s')
    if (.not. err%ok()) return
    estimate = tip_distance(tip_history(dyn), tip_fine) / 3
    write(*, '(a,es10.3,a,es10.3,a)') '    galpha dt = 5e-4: tip vs BDF ', dist, &
      ' m, Richardson estimate of its error ', estimate, ' m'
    call suite%check(dist < 10 * estimate, &
      'benchmark: generalized-alpha dt = 5e-4 and BDF agree on the tip within 10x its own error')
  end subroutine benchmark_run
end program test_dynamics
