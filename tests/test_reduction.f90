!> Reduced dynamic analysis on a small two-link arm (2 beams per link, 8 dynamic coordinates),
!> run end to end through run_t: the full basis reproduces the full model, the basis is
!> M0-orthonormal, the error indicator vanishes for the full basis and grows as k shrinks,
!> basis updates keep the trajectory continuous, and the explicit integrator agrees.
program test_reduction
  use core_kinds, only: wp
  use core_error, only: error_t
  use analysis_run, only: run_t
  use reduction_modal, only: modal_result_t, modal_analysis
  use test_scenes, only: itxt, node_distance
  use testing, only: suite_t
  implicit none
  type(suite_t) :: suite
  type(run_t) :: full
  real(wp) :: freqs(8)          !< frequencies at the initial configuration [Hz]
  integer, parameter :: N_DY = 8
  character(len=*), parameter :: DYN_TIGHT = &
    "&dynamic t_end = 0.5, output_dt = 2e-3, integrator = 'bdf', rtol = 1e-9, atol = 1e-11 /"
  character(len=*), parameter :: DYN = "&dynamic t_end = 0.5, output_dt = 2e-3, " &
    // "integrator = 'bdf', rtol = 1e-7, atol = 1e-9 /"

  call suite%init('reduction: reduced two-link arm')
  call run_scene('full', scene(DYN_TIGHT), full)
  call check_full_basis()
  call check_orthonormal_basis()
  call check_indicator_and_static_correction()
  call check_updates()
  call check_explicit()
  call check_selection()
  call suite%finish()

contains

  function scene(tail) result(text)
    character(len=*), intent(in) :: tail
    character(len=:), allocatable :: text
    text = "&node label = 'base', x = 0, y = 0, fixed = .true. /" // new_line('a') // &
      "&node label = 'elbow', x = 0.545, y = 0 /" // new_line('a') // &
      "&node label = 'tip', x = 1.22, y = 0 /" // new_line('a') // &
      "&link label = 'l1', from = 'base', to = 'elbow', n_elements = 2, E = 7.3e10, " // &
      "A = 9e-4, I = 1.69e-8, rho = 2700 /" // new_line('a') // &
      "&link label = 'l2', from = 'elbow', to = 'tip', n_elements = 2, E = 7.3e10, " // &
      "A = 4e-4, I = 3.33e-9, rho = 2700 /" // new_line('a') // &
      "&hinge label = 'j1', node = 'base', link = 'l1', mode = 'prescribed', motion = 'p1' /" &
      // new_line('a') // &
      "&hinge label = 'j2', node = 'elbow', link = 'l2', mode = 'prescribed', motion = 'p2' /" &
      // new_line('a') // &
      "&motion label = 'p1', law = 'cubic', end = 1.5707963, duration = 0.4 /" // &
      new_line('a') // &
      "&motion label = 'p2', law = 'cubic', end = 1.5707963, duration = 0.4 /" // &
      new_line('a') // "&mass node = 'elbow', m = 1 /" // new_line('a') // &
      "&mass node = 'tip', m = 3 /" // new_line('a') // "&output nodes = 'tip' /" // &
      new_line('a') // tail // new_line('a')
  end function scene

  subroutine run_scene(name, text, run)
    character(len=*), intent(in) :: name, text
    type(run_t), intent(out) :: run
    type(error_t) :: err
    integer :: u
    open(newunit=u, file='test_reduction_' // name // '.nml', status='replace', action='write')
    write(u, '(a)') text
    close(u)
    run%verbose = .false.
    call run%load('test_reduction_' // name // '.nml', err)
    if (err%ok()) call run%execute(err)
    call suite%check(err%ok(), name // ' runs')
    if (.not. err%ok()) then
      write(*, '(a)') '    ' // err%message
      call suite%finish()
    end if
  end subroutine run_scene


  subroutine check_full_basis()
    type(run_t) :: red
    character(len=80) :: line
    real(wp) :: d
    call run_scene('all_modes', scene(DYN_TIGHT // " &reduction n_modes = " // itxt(N_DY) // &
      " /"), red)
    d = node_distance(red, full, 'tip')
    write(line, '(a,es9.2,a)') 'all modes reproduce the full run (tip difference ', d, ' m)'
    call suite%check(d < 1.0e-7_wp, trim(line))
    ! With k = 1 the residual reaches about 5e2 on this scene.
    write(line, '(a,es9.2,a)') 'all modes: residual at round-off level (', &
      maxval(red%red%residual), ')'
    call suite%check(maxval(red%red%residual) < 1.0e-6_wp, trim(line))
    write(line, '(a,es9.2,a)') 'all modes: error estimate below 1 nm (', &
      maxval(red%red%estimate), ' m)'
    call suite%check(maxval(red%red%estimate) < 1.0e-9_wp, trim(line))
  end subroutine check_full_basis

  subroutine check_orthonormal_basis()
    type(modal_result_t) :: modes
    type(error_t) :: err
    real(wp) :: g(N_DY, N_DY)
    integer :: i
    call modal_analysis(full%dyn, 0.0_wp, [(0.0_wp, i = 1, N_DY)], 0, modes, err)
    call suite%check(err%ok(), 'modal analysis at the basis configuration')
    freqs = modes%frequency_hz
    g = matmul(transpose(modes%shapes), matmul(modes%m0, modes%shapes))
    do i = 1, N_DY
      g(i, i) = g(i, i) - 1.0_wp
    end do
    call suite%check(maxval(abs(g)) < 1.0e-10_wp, 'V^T M0 V = I to 1e-10 (' // &
      es(maxval(abs(g))) // ')')
  end subroutine check_orthonormal_basis

  subroutine check_indicator_and_static_correction()
    ! Allocated rather than local arrays of run_t: gfortran -O2 warns that the temporary of
    ! a local array's default initialisation is used uninitialised (a false positive).
    type(run_t), allocatable :: red(:), corrected
    real(wp) :: res(4), est(4), err_tip(4), err_corr
    character(len=120) :: line
    integer :: k
    allocate(red(4), corrected)
    do k = 1, 4
      call run_scene('k' // itxt(k), scene(DYN // " &reduction n_modes = " // itxt(k) // &
        " /"), red(k))
      res(k) = maxval(red(k)%red%residual)
      est(k) = maxval(red(k)%red%estimate)
      err_tip(k) = node_distance(red(k), full, 'tip')
      write(line, '(a,i0,a,es9.2,a,es9.2,a,es9.2,a)') 'k = ', k, ': residual ', res(k), &
        ', estimate ', est(k), ' m, tip error ', err_tip(k), ' m'
      write(*, '(4x,a)') trim(line)
    end do
    call suite%check(all(est(2:) < est(:3)), 'the error estimate shrinks as k grows')
    call suite%check(all(err_tip(2:) < err_tip(:3)), 'the tip error shrinks as k grows')
    call suite%check(all(est > 0.1_wp * err_tip .and. est < 10 * err_tip), &
      'the error estimate is within a factor 10 of the true tip error')
    call run_scene('k1_corrected', scene(DYN // " &reduction n_modes = 1, " // &
      "static_correction = .true. /"), corrected)
    err_corr = node_distance(corrected, full, 'tip')
    write(line, '(a,es9.2,a,es9.2,a)') 'statically corrected 1-mode tip error ', err_corr, &
      ' m (uncorrected ', err_tip(1), ' m): the same order, the error is dynamic'
    call suite%check(err_corr < 2 * err_tip(1), trim(line))
    call check_static_limit()
  end subroutine check_indicator_and_static_correction

  !> A damped cantilever under a tip load comes to rest: with one mode it settles on the
  !> projection of the static solution, with the static correction on the static solution
  !> itself (mode-acceleration: V eta + K0^-1 (f - K0 V eta) = K0^-1 f), up to the element's
  !> geometric non-linearity, which K0 leaves out. The reference is the static analysis of the
  !> full model under the same load; the damping is strong enough that every mode has decayed.
  subroutine check_static_limit()
    type(run_t) :: stat, ref, plain, corrected
    character(len=*), parameter :: beam = &
      "&node label = 'base', x = 0, y = 0, fixed = .true. / &node label = 'tip', x = 1, y = 0 /" &
      // " &link label = 'arm', from = 'base', to = 'tip', n_elements = 4, E = 7e10, " // &
      "A = 1e-4, I = 1e-9, rho = 2700, damping = 2e-2 / &force node = 'tip', fy = -0.5 /" // &
      " &output nodes = 'tip' /"
    real(wp), parameter :: T_END = 1.0_wp, BETA = 2.0e-2_wp, RTOL = 1.0e-10_wp, &
      ATOL = 1.0e-13_wp, STATIC_TOL = 1.0e-12_wp, LEN = 1.0_wp
    character(len=*), parameter :: dyn = " &dynamic t_end = 1.0, output_dt = 0.01, " // &
      "rtol = 1e-10, atol = 1e-13 /"
    real(wp) :: y_st, e_full, e_plain, e_corr, omega1, zeta1, rate, transient, solver, &
      theta, bound
    character(len=200) :: line
    integer :: ic(3), nt
    call run_scene('beam_static', beam // " &static tol = 1e-12 /", stat)
    call run_scene('beam_full', beam // dyn, ref)
    call run_scene('beam_k1', beam // dyn // " &reduction n_modes = 1 /", plain)
    call run_scene('beam_k1_corrected', beam // dyn // " &reduction n_modes = 1, " // &
      "static_correction = .true. /", corrected)
    ic = ref%dyn%model%node_coord(1:3, ref%dyn%model%find_node('tip'))
    nt = size(ref%time)
    y_st = stat%x_static(ic(2), size(stat%x_static, 2))
    e_full = abs(ref%dyn%x_hist(ic(2), nt) - y_st)
    e_plain = abs(plain%dyn%x_hist(ic(2), nt) - y_st)
    e_corr = abs(corrected%dyn%x_hist(ic(2), nt) - y_st)
    ! Residual transient: with stiffness-proportional damping a mode decays at beta omega^2 / 2
    ! (underdamped) or at least 1 / beta (overdamped), so mode 1 (or 1 / beta) is the slowest;
    ! its step-response envelope is |y_st| exp(-rate t) / sqrt(1 - zeta^2).
    omega1 = 2 * acos(-1.0_wp) * plain%red%basis%frequency_hz(1)
    zeta1 = BETA * omega1 / 2
    rate = min(BETA * omega1**2 / 2, 1 / BETA)
    transient = abs(y_st) * exp(-rate * T_END) / sqrt(max(1 - zeta1**2, 1.0e-2_wp))
    ! What the solvers leave: the integrator's rtol |y| + atol, the static Newton tol x L.
    solver = RTOL * abs(y_st) + ATOL + STATIC_TOL * LEN
    write(line, '(a,es9.2,a,es9.2,a,es9.2,a)') 'settled full run on the static solution (off by ', &
      e_full, ' m; 10 x (transient ', transient, ' m + solver tolerances ', solver, ' m))'
    call suite%check(e_full < 10 * (transient + solver), trim(line))
    ! A linear correction leaves the geometric non-linearity: second order in the tip rotation
    ! theta ~ |y_st| / L of the dropped part, 100 theta^2 e_plain allows an O(10) coefficient.
    theta = abs(y_st) / LEN
    bound = 100 * theta**2 * e_plain + 10 * (transient + solver)
    write(line, '(a,es9.2,a,es9.2,a,es9.2,a,es9.2,a)') 'settled tip: 1 mode off by ', e_plain, &
      ' m, corrected ', e_corr, ' m (bound ', bound, ' m; deflection ', abs(y_st), ' m)'
    call suite%check(e_corr < bound .and. e_plain > 1.0e-3_wp * abs(y_st), trim(line))
  end subroutine check_static_limit

  !> Positions are continuous across basis updates: the second difference of q_dy at the
  !> output right after each check is no larger than elsewhere on the trajectory.
  subroutine check_updates()
    type(run_t) :: upd, mac_low, mac_high, fixed
    real(wp), allocatable :: d2(:)
    real(wp) :: jump, smooth, d_fixed, d_upd
    character(len=160) :: line
    integer :: i, j, nt
    logical, allocatable :: at_check(:)
    call run_scene('fixed_k2', scene(DYN // " &reduction n_modes = 2 /"), fixed)
    call run_scene('interval', scene(DYN // " &reduction n_modes = 2, update = 'interval', " &
      // "update_interval = 0.025 /"), upd)
    call suite%check(upd%updates%n_updates == 19 .and. size(upd%updates%time) == 19, &
      'interval updates: one per check (' // itxt(upd%updates%n_updates) // ')')
    nt = size(upd%time)
    allocate(d2(2:nt - 1), at_check(2:nt - 1))
    do i = 2, nt - 1
      d2(i) = maxval(abs(upd%dyn%q_hist(:, i + 1) - 2 * upd%dyn%q_hist(:, i) + &
        upd%dyn%q_hist(:, i - 1)))
      at_check(i) = .false.
      do j = 1, size(upd%updates%time)
        at_check(i) = at_check(i) .or. (upd%time(i) < upd%updates%time(j) + 1.0e-12_wp .and. &
          upd%time(i + 1) > upd%updates%time(j))
      end do
    end do
    jump = maxval(d2, mask=at_check)
    smooth = maxval(d2, mask=.not. at_check)
    write(line, '(a,es9.2,a,es9.2,a)') 'trajectory continuous across updates (2nd difference ', &
      jump, ' at updates, ', smooth, ' elsewhere)'
    call suite%check(jump <= 1.5_wp * smooth, trim(line))
    d_fixed = node_distance(fixed, full, 'tip')
    d_upd = node_distance(upd, full, 'tip')
    write(line, '(a,es9.2,a,es9.2,a)') 'updated basis tip error ', d_upd, ' m (fixed ', &
      d_fixed, ' m) stays of the same order'
    call suite%check(d_upd < 3 * d_fixed, trim(line))
    call run_scene('mac_low', scene(DYN // " &reduction n_modes = 2, update = 'mac', " // &
      "update_interval = 0.025, mac_threshold = 0.05 /"), mac_low)
    ! The checks split the integration, so the step sequence differs: the paths agree to the
    ! integrator's global error, 100 rtol x 1.22 m reach (an update would move it ~1e-3 m).
    call suite%check(mac_low%updates%n_updates == 0 .and. size(mac_low%updates%time) == 19 &
      .and. node_distance(mac_low, fixed, 'tip') < 100 * 1.0e-7_wp * 1.22_wp, &
      'mac threshold never reached: checks without updates, same path as the fixed basis (' &
      // es(node_distance(mac_low, fixed, 'tip')) // ' m)')
    call run_scene('mac_high', scene(DYN // " &reduction n_modes = 2, update = 'mac', " // &
      "update_interval = 0.025, mac_threshold = 0.99999 /"), mac_high)
    write(line, '(a,i0,a,f8.5)') 'mac threshold 0.99999: ', mac_high%updates%n_updates, &
      ' updates, smallest MAC ', minval(mac_high%updates%min_mac)
    call suite%check(mac_high%updates%n_updates > 0 .and. mac_high%updates%n_updates < 19 &
      .and. all(mac_high%updates%updated .eqv. mac_high%updates%min_mac < 0.99999_wp), &
      trim(line))
  end subroutine check_updates

  subroutine check_explicit()
    type(run_t) :: bdf, erk
    character(len=120) :: line
    real(wp) :: d
    call run_scene('bdf_k2', scene(DYN_TIGHT // " &reduction n_modes = 2 /"), bdf)
    call run_scene('erk_k2', scene("&dynamic t_end = 0.5, output_dt = 2e-3, " // &
      "integrator = 'erk', rtol = 1e-9, atol = 1e-11 / &reduction n_modes = 2 /"), erk)
    d = node_distance(bdf, erk, 'tip')
    write(line, '(a,es9.2,a,i0,a,i0,a)') 'explicit RK agrees with BDF on 2 modes (', d, &
      ' m; steps ', erk%stats%n_steps, ' vs ', bdf%stats%n_steps, ')'
    call suite%check(d < 1.0e-7_wp, trim(line))
  end subroutine check_explicit

  subroutine check_selection()
    type(run_t) :: cut, auto
    associate (f => freqs)
    call run_scene('cutoff', scene(DYN // " &reduction cutoff_hz = " // &
      "50.0 /"), cut)
    call suite%check(cut%red%basis%k() == count(f <= 50.0_wp) .and. &
      index(cut%red%basis%reason, 'below') > 0, 'cutoff_hz keeps the modes below it (' // &
      itxt(cut%red%basis%k()) // '): ' // cut%red%basis%reason)
    call run_scene('auto', scene(DYN // " &reduction auto_factor = 1.0 /"), auto)
    call suite%check(auto%red%basis%k() >= 1 .and. auto%red%basis%bandwidth_hz > 0 .and. &
      all(auto%red%basis%frequency_hz <= max(auto%red%basis%cutoff_hz, f(1))), &
      'auto keeps the modes below auto_factor x bandwidth (' // itxt(auto%red%basis%k()) // &
      '): ' // auto%red%basis%reason)
    end associate
    call check_basis_configuration()
  end subroutine check_selection

  !> The basis at the end of the motion, named by time or by the joint angles themselves.
  subroutine check_basis_configuration()
    type(run_t) :: by_time, by_angles
    call run_scene('basis_time', scene(DYN // " &reduction n_modes = 3, basis_time = 0.45 /"), &
      by_time)
    call run_scene('basis_angles', scene(DYN // " &reduction n_modes = 3, " // &
      "basis_prescribed = 1.5707963, 1.5707963 /"), by_angles)
    call suite%close_array(by_angles%red%basis%frequency_hz, by_time%red%basis%frequency_hz, &
      1.0e-12_wp, 0.0_wp, 'basis_prescribed = the angles at basis_time gives the same modes')
    call suite%check(abs(by_time%red%basis%frequency_hz(2) / freqs(2) - 1) > 1.0e-3_wp, &
      'the basis at the end configuration differs from the initial one (f2 ' // &
      es(by_time%red%basis%frequency_hz(2)) // ' vs ' // es(freqs(2)) // ' Hz)')
  end subroutine check_basis_configuration
  function es(x) result(s)
    real(wp), intent(in) :: x
    character(len=9) :: s
    write(s, '(es9.2)') x
  end function es
end program test_reduction
