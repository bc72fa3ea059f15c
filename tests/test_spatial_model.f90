!> Spatial beams in the model: kinematics, statics and modal analysis, built through the
!> library API (the scene groups for spatial models do not exist yet). Nodes carry (x, y, z)
!> and four Euler parameters, each free rotation with a rigid normalisation element:
!>   - small tip forces on a cantilever along x: deflection P L^3 / (3 EI) in both planes
!>     (EI_y for z, EI_z for y) and the tip rotation P L^2 / (2 EI);
!>   - a large tip force in a plane tilted about the beam axis gives the planar model's
!>     large-deflection answer (same mesh, angle form) in that plane, without twist;
!>   - clamped-free bending frequencies in both planes and the torsional one (modal analysis);
!>   - released from a large deflection in both planes, the undamped beam keeps its energy
!>     (consistent mass with rotary inertia, its convective forces, Euler parameters);
!>   - an end moment: small, M L / EI and M L^2 / (2 EI); 2 pi EI / L rolls the cantilever
!>     into a full circle, its tip back at the root with its orientation (closed form).
program test_spatial_model
  use core_kinds, only: wp
  use core_error, only: error_t
  use model_system, only: model_t, COORD_X, COORD_Y, COORD_Z, COORD_EULER
  use elements_base, only: MODE_RIGID, MODE_DYNAMIC
  use elements_beam3d, only: beam3d_t, beam3d_set_geometry, BENDING_ANGLE
  use elements_euler, only: euler_norm_t
  use elements_rotation, only: euler_to_matrix
  use dynamics_system, only: dynamics_t
  use dynamics_static, only: static_solve
  use model_scene, only: scene_t
  use reduction_modal, only: modal_result_t, modal_analysis
  use integrators_system, only: integrator_options_t, integrator_stats_t, &
    INTEGRATOR_GALPHA_ADAPTIVE
  use integrators_driver, only: integrate
  use testing, only: suite_t
  use test_scenes, only: rtxt, itxt, make_dynamics
  implicit none

  real(wp), parameter :: LEN = 1.5_wp, E_MOD = 7.0e10_wp, G_MOD = 2.6e10_wp
  real(wp), parameter :: AREA = 1.0e-4_wp, I_Y = 2.0e-9_wp, I_Z = 0.8e-9_wp, J_T = 1.5e-9_wp
  type(suite_t) :: ts

  call ts%init('spatial model: statics, modal analysis, dynamics')
  call small_deflection()
  call tilted_plane()
  call frequencies()
  call free_vibration()
  call roll_up()
  call bad_models()
  call ts%finish()

contains

  !> A cantilever along x from the origin, n beam3d elements (section y axis along global y),
  !> clamped at the root, force f at the tip. Returns the dynamics at q = 0.
  subroutine cantilever(n, f, dyn, err, moment)
    integer, intent(in) :: n
    real(wp), intent(in) :: f(3)
    type(dynamics_t), intent(out) :: dyn
    type(error_t), intent(out) :: err
    real(wp), intent(in), optional :: moment(3)   !< at the tip, fixed in space
    type(model_t) :: model
    type(beam3d_t) :: b
    type(euler_norm_t) :: en
    integer :: i, k, first(0:n), idx
    character(len=8) :: nm
    real(wp), allocatable :: q0(:)
    call model%init()
    model%dim = 3
    do i = 0, n
      write(nm, '(i0)') i
      first(i) = model%add_coord(LEN * i / n, COORD_X, i == 0, 'node ' // trim(nm) // ' x')
      k = model%add_coord(0.0_wp, COORD_Y, i == 0, 'node ' // trim(nm) // ' y')
      k = model%add_coord(0.0_wp, COORD_Z, i == 0, 'node ' // trim(nm) // ' z')
      k = model%add_coord(1.0_wp, COORD_EULER, i == 0, 'node ' // trim(nm) // ' l0')
      do k = 1, 3
        idx = model%add_coord(0.0_wp, COORD_EULER, i == 0, 'node ' // trim(nm) // ' l' // &
          achar(48 + k))
      end do
      if (i > 0) then
        en%label = 'norm ' // trim(nm)
        en%dofs = [(first(i) + 3 + k, k = 0, 3)]
        en%mode_class = [MODE_RIGID]
        idx = model%add_element(en, [0])
      end if
    end do
    do i = 1, n
      write(nm, '(i0)') i
      b%label = 'beam ' // trim(nm)
      b%dofs = [(first(i - 1) + k, k = 0, 6), (first(i) + k, k = 0, 6)]
      ! Inextensible, as the planar default: elongation rigid, the rest elastic.
      b%mode_class = [MODE_RIGID, (MODE_DYNAMIC, k = 1, 5)]
      call beam3d_set_geometry(b, model%x0(b%dofs(1:3)), model%x0(b%dofs(8:10)), &
        [0.0_wp, 1.0_wp, 0.0_wp], err)
      if (.not. err%ok()) return
      b%ea = E_MOD * AREA
      b%gj = G_MOD * J_T
      b%ei_y = E_MOD * I_Y
      b%ei_z = E_MOD * I_Z
      ! Statics needs no mass, but starting the model evaluates the accelerations once.
      b%rho_a = 2700 * AREA
      b%rho_j = 2700 * J_T
      b%rho_iy = 2700 * I_Y
      b%rho_iz = 2700 * I_Z
      b%bending = BENDING_ANGLE
      idx = model%add_element(b, [(0, k = 1, 6)])
    end do
    model%force(first(n):first(n) + 2) = f
    if (present(moment)) call model%add_moment(first(n) + 3, moment)
    call model%finalize(err)
    if (.not. err%ok()) return
    allocate(q0(model%n_dy))
    q0 = 0.0_wp
    call dyn%init(model, 0.0_wp, q0, err)
  end subroutine cantilever

  subroutine solve(dyn, n_steps, x, err)
    type(dynamics_t), intent(inout) :: dyn
    integer, intent(in) :: n_steps
    real(wp), allocatable, intent(out) :: x(:)
    type(error_t), intent(out) :: err
    real(wp), allocatable :: q(:), xs(:, :)
    integer :: iterations
    allocate(q(dyn%model%n_dy), xs(dyn%model%n_x, n_steps))
    q = 0.0_wp
    call static_solve(dyn, 0.0_wp, n_steps, 1.0e-10_wp, 50, q, xs, iterations, err)
    x = xs(:, n_steps)
  end subroutine solve

  !> Euler-Bernoulli cubic elements are exact for a tip force: deflection and rotation to
  !> the geometric non-linearity, relative (deflection / L)^2 ~ 1e-8 here; bounds 1e-6.
  subroutine small_deflection()
    type(dynamics_t) :: dyn
    type(error_t) :: err
    real(wp), allocatable :: x(:)
    real(wp) :: p, w_z, w_y, r(3, 3)
    integer :: it
    p = 1.0e-3_wp
    call cantilever(4, [0.0_wp, p, p], dyn, err)
    call ts%check(err%ok(), 'cantilever model builds and starts' // msg(err))
    if (.not. err%ok()) return
    call solve(dyn, 1, x, err)
    call ts%check(err%ok(), 'small tip force: static solution' // msg(err))
    if (.not. err%ok()) return
    it = dyn%model%n_x - 6
    w_y = p * LEN**3 / (3 * E_MOD * I_Z)
    w_z = p * LEN**3 / (3 * E_MOD * I_Y)
    call ts%close(x(it + 1), w_y, 1.0e-6_wp, 0.0_wp, 'tip deflection in y = P L^3 / (3 EI_z)')
    call ts%close(x(it + 2), w_z, 1.0e-6_wp, 0.0_wp, 'tip deflection in z = P L^3 / (3 EI_y)')
    r = euler_to_matrix(x(it + 3:it + 6))
    ! The tangent turns towards +y by P L^2/(2 EI_z) (about +z) and towards +z by
    ! P L^2/(2 EI_y) (about -y): the rotated x axis is (1, theta_z, theta_y) to first order.
    call ts%close(r(2, 1), p * LEN**2 / (2 * E_MOD * I_Z), 1.0e-6_wp, 0.0_wp, &
      'tip rotation towards y = P L^2 / (2 EI_z)')
    call ts%close(r(3, 1), p * LEN**2 / (2 * E_MOD * I_Y), 1.0e-6_wp, 0.0_wp, &
      'tip rotation towards z = P L^2 / (2 EI_y)')
  end subroutine small_deflection

  !> The beam with equal bending stiffness in both planes loaded in the plane at angle psi
  !> about x: its tip must follow the planar beam's large deflection in that plane.
  subroutine tilted_plane()
    type(dynamics_t) :: dyn, dyn2
    type(scene_t) :: scene
    type(error_t) :: err
    real(wp), allocatable :: x(:), x2(:)
    real(wp) :: p, psi, u(3), w, defl
    integer :: it, n, ic(3)
    character(len=:), allocatable :: text
    n = 6
    psi = 0.7_wp
    ! P L^2 / EI = 3: a large deflection (tip slope about 1 rad).
    p = 3.0_wp * E_MOD * I_Y / LEN**2
    call cantilever_equal(n, p * [0.0_wp, cos(psi), sin(psi)], dyn, err)
    call ts%check(err%ok(), 'equal-stiffness cantilever builds' // msg(err))
    if (.not. err%ok()) return
    call solve(dyn, 10, x, err)
    call ts%check(err%ok(), 'large tip force in a tilted plane: static solution' // msg(err))
    if (.not. err%ok()) return
    text = "&node label = 'root', x = 0, y = 0, fixed = .true. /" // new_line('a') // &
      "&node label = 'tip', x = " // rtxt(LEN) // ", y = 0 /" // new_line('a') // &
      "&link label = 'beam', from = 'root', to = 'tip', n_elements = " // itxt(n) // &
      ", E = " // rtxt(E_MOD) // ", A = " // rtxt(AREA) // ", I = " // rtxt(I_Y) // &
      ", rho = 1 /" // new_line('a') // &
      "&force node = 'tip', fy = " // rtxt(p) // " /" // new_line('a')
    call make_dynamics(text, scene, dyn2, err)
    call ts%check(err%ok(), 'planar reference builds' // msg(err))
    if (.not. err%ok()) return
    call solve(dyn2, 10, x2, err)
    call ts%check(err%ok(), 'planar reference solves' // msg(err))
    if (.not. err%ok()) return
    it = dyn%model%n_x - 6
    u = x(it:it + 2)
    ic = dyn2%model%node_coord(1:3, dyn2%model%find_node('tip'))
    defl = x2(ic(2))
    ! Same discrete equations in the plane; Newton converged to 1e-10: bound 1e-8 relative.
    call ts%close(u(1), x2(ic(1)), 1.0e-8_wp, 0.0_wp, &
      'tilted plane: tip x equals the planar model''s')
    call ts%close(cos(psi) * u(2) + sin(psi) * u(3), defl, 1.0e-8_wp, 0.0_wp, &
      'tilted plane: tip deflection in the plane equals the planar model''s')
    w = -sin(psi) * u(2) + cos(psi) * u(3)
    call ts%close(w, 0.0_wp, 0.0_wp, 1.0e-10_wp * LEN, 'tilted plane: no motion out of it')
  end subroutine tilted_plane

  subroutine cantilever_equal(n, f, dyn, err)
    integer, intent(in) :: n
    real(wp), intent(in) :: f(3)
    type(dynamics_t), intent(out) :: dyn
    type(error_t), intent(out) :: err
    integer :: i
    call cantilever(n, f, dyn, err)
    if (.not. err%ok()) return
    ! The same beams with EI_z = EI_y (rebuilt: the model owns copies of its elements).
    do i = 1, dyn%model%n_elements
      select type (el => dyn%model%elements(i)%e)
      type is (beam3d_t)
        el%ei_z = el%ei_y
      end select
    end do
  end subroutine cantilever_equal

  !> Clamped-free frequencies with the consistent mass: bending in both planes (cubic
  !> elements: 1.8751^2 sqrt(EI / (rho A L^4)), converged to about 1e-6 at 8 elements; rotary
  !> inertia shifts it by about (r / L)^2 ~ 1e-5) and the first torsional one,
  !> (pi / 2L) sqrt(G J / (rho I_p)) (linear interpolation: second order in the mesh).
  subroutine frequencies()
    type(dynamics_t) :: dyn
    type(modal_result_t) :: res
    type(error_t) :: err
    real(wp) :: rho, f_y, f_z, f_t, e_t(2), f(2)
    real(wp), allocatable :: q(:)
    integer :: k, n
    rho = 2700.0_wp
    f_y = 1.875104068711961_wp**2 * sqrt(E_MOD * I_Z / (rho * AREA * LEN**4)) / (2 * acos(-1.0_wp))
    f_z = 1.875104068711961_wp**2 * sqrt(E_MOD * I_Y / (rho * AREA * LEN**4)) / (2 * acos(-1.0_wp))
    f_t = sqrt(G_MOD * J_T / (rho * J_T)) / (4 * LEN)
    do k = 1, 2
      n = 8 * k
      call cantilever(n, [0.0_wp, 0.0_wp, 0.0_wp], dyn, err)
      if (.not. err%ok()) exit
      allocate(q(dyn%model%n_dy))
      q = 0.0_wp
      call modal_analysis(dyn, 0.0_wp, q, 0, res, err, 'lapack')
      deallocate(q)
      call ts%check(err%ok(), 'modal analysis of the spatial cantilever, ' // itxt(n) // &
        ' elements' // msg(err))
      if (.not. err%ok()) return
      f = res%frequency_hz(1:2)
      if (k == 1) then
        ! Observed 6e-6 and 1.8e-5: the rotary inertia, (r / L)^2 = I / (A L^2) ~ 1e-5.
        call ts%close(f(1), f_y, 3.0e-4_wp, 0.0_wp, 'first bending frequency (x-y plane, EI_z)')
        call ts%close(f(2), f_z, 3.0e-4_wp, 0.0_wp, 'first bending frequency (x-z plane, EI_y)')
      end if
      e_t(k) = minval(abs(res%frequency_hz - f_t)) / f_t
    end do
    if (.not. err%ok()) then
      call ts%check(.false., 'spatial cantilever for the modal analysis' // msg(err))
      return
    end if
    ! (pi / 16)^2 / 24 = 1.6e-3 for linear consistent elements; bound 2e-2.
    call ts%close(e_t(1), 0.0_wp, 0.0_wp, 2.0e-2_wp, &
      'first torsional frequency (8 elements), rel. error')
    call ts%order(e_t(1), e_t(2), 2, 'first torsional frequency converges at second order')
  end subroutine frequencies

  subroutine free_vibration()
    type(dynamics_t) :: dyn
    type(error_t) :: err
    type(integrator_options_t) :: opts
    type(integrator_stats_t) :: stats
    real(wp), allocatable :: q(:), v(:), xs(:, :), t_out(:), en(:)
    real(wp) :: p
    integer :: iterations, k, n_t
    ! A skew tip force of P L^2 / EI_z = 1 bends both planes (and stretches nothing: the
    ! elongation is rigid); the beam starts from that equilibrium at rest, unloaded.
    p = E_MOD * I_Z / LEN**2
    call cantilever(4, p * [0.1_wp, 0.8_wp, 0.6_wp], dyn, err)
    if (.not. err%ok()) then
      call ts%check(.false., 'free vibration: model' // msg(err))
      return
    end if
    allocate(q(dyn%model%n_dy), v(dyn%model%n_dy), xs(dyn%model%n_x, 5))
    q = 0.0_wp
    call static_solve(dyn, 0.0_wp, 5, 1.0e-10_wp, 50, q, xs, iterations, err)
    call ts%check(err%ok(), 'free vibration: deflected start' // msg(err))
    if (.not. err%ok()) return
    dyn%load_factor = 0.0_wp
    v = 0.0_wp
    n_t = 41
    t_out = [(0.2_wp * (k - 1) / (n_t - 1), k = 1, n_t)]
    call dyn%allocate_history(n_t)
    ! Generalized-alpha without numerical damping (rho_inf = 1): BDF's higher orders would
    ! be held to the fastest torsion and bending modes (stiff: see integrator 'auto').
    opts%method = INTEGRATOR_GALPHA_ADAPTIVE
    opts%rho_inf = 1.0_wp
    opts%dt = 1.0e-4_wp
    opts%rtol = 1.0e-6_wp
    opts%atol = 1.0e-8_wp
    call integrate(dyn, opts, t_out, q, v, [real(wp) ::], stats, err)
    call ts%check(err%ok(), 'free vibration: integration over 0.2 s' // msg(err))
    if (.not. err%ok()) return
    en = dyn%energy_hist(1, :) + dyn%energy_hist(2, :)
    ! rtol 1e-6 over 0.7 periods of the lowest mode: drift observed 6.7e-7 (2.8e-6 before
    ! the adaptive step was kept on small changes; 2.4e-11 with BDF at rtol 1e-10, which
    ! takes 30x longer); bound 3e-5. Without the translational
    ! convective force of the beam the drift is 4.7e-4, 15x the bound.
    call ts%close(maxval(abs(en - en(1))) / en(1), 0.0_wp, 0.0_wp, 3.0e-5_wp, &
      'free vibration: energy conserved, relative drift')
    call ts%check(maxval(dyn%energy_hist(1, :)) > 0.5_wp * en(1), &
      'free vibration: the energy goes through kinetic and back')
  end subroutine free_vibration

  subroutine roll_up()
    type(dynamics_t) :: dyn
    type(error_t) :: err
    real(wp), allocatable :: x(:)
    real(wp) :: m, r(3, 3), id(3, 3)
    integer :: it, k
    ! Small: tip rotation M L / EI_z about z, deflection M L^2 / (2 EI_z) in +y.
    m = 1.0e-4_wp * E_MOD * I_Z / LEN
    call cantilever(4, [0.0_wp, 0.0_wp, 0.0_wp], dyn, err, moment=[0.0_wp, 0.0_wp, m])
    if (err%ok()) call solve(dyn, 1, x, err)
    call ts%check(err%ok(), 'small end moment: static solution' // msg(err))
    if (.not. err%ok()) return
    it = dyn%model%n_x - 6
    r = euler_to_matrix(x(it + 3:it + 6))
    call ts%close(x(it + 1), m * LEN**2 / (2 * E_MOD * I_Z), 1.0e-6_wp, 0.0_wp, &
      'small end moment: tip deflection M L^2 / (2 EI)')
    call ts%close(r(2, 1), m * LEN / (E_MOD * I_Z), 1.0e-6_wp, 0.0_wp, &
      'small end moment: tip rotation M L / EI')
    ! Full circle: equal elements under equal moments form a closed regular polygon, so the
    ! tip returns to the root exactly (to the Newton tolerance, 1e-10), for any mesh.
    m = 2 * acos(-1.0_wp) * E_MOD * I_Z / LEN
    call cantilever(8, [0.0_wp, 0.0_wp, 0.0_wp], dyn, err, moment=[0.0_wp, 0.0_wp, m])
    if (err%ok()) call solve(dyn, 16, x, err)
    call ts%check(err%ok(), 'end moment 2 pi EI / L: static solution in 16 steps' // msg(err))
    if (.not. err%ok()) return
    it = dyn%model%n_x - 6
    call ts%close(norm2(x(it:it + 2)) / LEN, 0.0_wp, 0.0_wp, 1.0e-8_wp, &
      'roll-up: the tip is back at the root (distance / L)')
    r = euler_to_matrix(x(it + 3:it + 6))
    id = 0.0_wp
    do k = 1, 3
      id(k, k) = 1.0_wp
    end do
    call ts%close(maxval(abs(r - id)), 0.0_wp, 0.0_wp, 1.0e-8_wp, &
      'roll-up: the tip section has turned a full turn')
    ! Half way (moment pi EI / L would make a half circle): the middle node of the full
    ! circle is opposite the root, at 2 R = L / pi from it (polygon: to O(h^2)).
    ! Node 4 of 0..8 (7 coordinates a node, the root's included).
    call ts%close(norm2(x(29:31)), LEN / acos(-1.0_wp), 2.0e-2_wp, 0.0_wp, &
      'roll-up: the middle node is a diameter 2 EI / M away')
  end subroutine roll_up

  !> Mistakes of a model built through the API are clear errors, not wrong answers.
  subroutine bad_models()
    type(model_t) :: model, model2, model3
    type(error_t) :: err
    integer :: ix
    call model%init()
    ix = model%add_coord(0.0_wp, COORD_X, .false., 'a x')
    ix = model%add_coord(0.0_wp, COORD_Y, .false., 'a y')
    ix = model%add_coord(0.0_wp, COORD_Z, .false., 'a z')
    ix = model%add_coord(1.0_wp, COORD_EULER, .false., 'a l0')
    call model%add_moment(1, [0.0_wp, 0.0_wp, 1.0_wp])
    call model%finalize(err)
    call ts%check(.not. err%ok() .and. index(err%message, 'Euler parameters') > 0 .and. &
      index(err%message, 'a x') > 0, 'a moment on translations is refused: ' // err%message)
    call model2%init()
    model2%gravity = [0.0_wp, 0.0_wp, -9.81_wp]
    call model2%finalize(err)
    call ts%check(.not. err%ok() .and. index(err%message, 'z component') > 0, &
      'z gravity in a planar model is refused: ' // err%message)
    call model3%init()
    model3%dim = 4
    call model3%finalize(err)
    call ts%check(.not. err%ok() .and. index(err%message, 'dim') > 0, &
      'dim 4 is refused: ' // err%message)
  end subroutine bad_models

  function msg(err) result(s)
    type(error_t), intent(in) :: err
    character(len=:), allocatable :: s
    s = ''
    if (.not. err%ok()) s = ': ' // err%message
  end function msg
end program test_spatial_model
