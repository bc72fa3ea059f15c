!> Static reference cases of docs/theory.md section 10, built from scene text:
!>  - small-deflection cantilever: tip deflection P L^3/(3EI), rotation P L^2/(2EI) (exact for
!>    cubic elements), axial stretch P L/(EA) when the elongation is dynamic;
!>  - Mattiasson's large-deflection cantilever (load keeping its direction, inextensible);
!>  - fixed-free buckling from the tangent stiffness K_T(P) = S - P G;
!>  - bad input of &static, and loads beyond buckling / on a mechanism-like model: converge or
!>    give a clear error, never NaN.
program test_verification_static
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use core_kinds, only: wp
  use core_error, only: error_t
  use core_linalg, only: sym_gen_eig
  use io_namelist, only: nml_file_t
  use io_scene, only: read_scene
  use model_scene, only: scene_t
  use dynamics_system, only: dynamics_t
  use dynamics_static, only: tangent_stiffness, static_solve
  use testing, only: suite_t
  use test_scenes, only: rtxt, itxt, make => make_dynamics
  implicit none

  character(len=*), parameter :: NL = new_line('a')
  real(wp), parameter :: PI = 3.14159265358979323846_wp
  ! Cross-section (aluminium strip); L is not 1 so that wrong powers of L show.
  real(wp), parameter :: LEN = 1.5_wp, E_MOD = 7.0e10_wp, AREA = 1.0e-4_wp, INER = 1.0e-9_wp, &
    RHO = 2700.0_wp
  real(wp), parameter :: EI = E_MOD * INER, EA = E_MOD * AREA

  type(suite_t) :: suite

  call suite%init('verification: statics (cantilever, Mattiasson, buckling)')
  call small_deflection()
  call mattiasson()
  call mattiasson_convergence()
  call buckling()
  call bad_input_and_beyond_buckling()
  call suite%finish()

contains

  ! ------------------------------------------------------------------ scene text

  !> Cantilever along x: node 'root' at 0 (fixed), node 'tip' at LEN, one link of n beams,
  !> tip load (fx, fy); `extra` is appended (e.g. a &static group).
  function cantilever(n, elongation, fx, fy, extra, bending_form) result(t)
    integer, intent(in) :: n
    character(len=*), intent(in) :: elongation, extra
    real(wp), intent(in) :: fx, fy
    character(len=*), intent(in), optional :: bending_form
    character(len=:), allocatable :: t, form
    form = ''
    if (present(bending_form)) form = ", bending_form = '" // bending_form // "'"
    t = "&scene title = 'cantilever' /" // NL // &
      "&node label = 'root', x = 0.0, y = 0.0, fixed = .true. /" // NL // &
      "&node label = 'tip', x = " // rtxt(LEN) // ", y = 0.0 /" // NL // &
      "&link label = 'beam', from = 'root', to = 'tip', n_elements = " // itxt(n) // "," // NL // &
      "      E = " // rtxt(E_MOD) // ", A = " // rtxt(AREA) // ", I = " // rtxt(INER) // &
      ", rho = " // rtxt(RHO) // ", elongation = '" // elongation // "'" // form // " /" // NL // &
      "&force node = 'tip', fx = " // rtxt(fx) // ", fy = " // rtxt(fy) // " /" // NL // extra
  end function cantilever

  !> Tip (x, y, phi) in the nodal coordinates x.
  function tip_state(dyn, x) result(s)
    type(dynamics_t), intent(in) :: dyn
    real(wp), intent(in) :: x(:)
    real(wp) :: s(3)
    integer :: it
    it = dyn%model%find_node('tip')
    s = x(dyn%model%node_coord(1:3, it))
  end function tip_state

  ! ------------------------------------------------------------------ cases

  !> Linear cantilever: cubic elements are exact, so any mesh must give the textbook values.
  subroutine small_deflection()
    character(len=*), parameter :: ELONG(2) = [character(len=7) :: 'rigid', 'dynamic']
    integer, parameter :: MESH(2) = [1, 4]
    type(scene_t) :: scene
    type(dynamics_t) :: dyn
    type(error_t) :: err
    real(wp), allocatable :: q(:), xs(:, :)
    real(wp) :: p, s(3), w_ref, th_ref, u_ref
    integer :: ie, im, iters
    character(len=60) :: tag
    p = 3.0e-4_wp * EI / LEN**2          ! w / L = 1e-4: non-linear terms below 1e-8
    w_ref = p * LEN**3 / (3 * EI)
    th_ref = p * LEN**2 / (2 * EI)
    do ie = 1, 2
      do im = 1, 2
        write(tag, '(a,i0,a)') 'cantilever ' // trim(ELONG(ie)) // ', ', MESH(im), ' el.: '
        call make(cantilever(MESH(im), trim(ELONG(ie)), 0.0_wp, p, ''), scene, dyn, err)
        call suite%check(err%ok(), trim(tag) // 'builds')
        if (.not. err%ok()) then
          write(*, '(a)') '    ' // err%message
          cycle
        end if
        call suite%check(dyn%model%n_dy == merge(2, 3, ie == 1) * MESH(im), trim(tag) // &
          'dynamic coordinates = modes per element x elements')
        allocate(q(dyn%model%n_dy), xs(dyn%model%n_x, 1))
        q = 0.0_wp
        call static_solve(dyn, 0.0_wp, 1, 1.0e-12_wp, 20, q, xs, iters, err)
        call suite%check(err%ok(), trim(tag) // 'static_solve converges')
        if (err%ok()) then
          s = tip_state(dyn, xs(:, 1))
          call suite%close(s(2), w_ref, 1.0e-6_wp, 0.0_wp, trim(tag) // 'tip w = PL^3/3EI')
          call suite%close(s(3), th_ref, 1.0e-6_wp, 0.0_wp, trim(tag) // 'tip phi = PL^2/2EI')
          ! the transverse load does no axial work to first order: |u| ~ (3/5) w^2 / L
          call suite%check(abs(s(1) - LEN) < w_ref**2 / LEN, trim(tag) // &
            'tip axial displacement second order only')
          call suite%check(iters <= 4, trim(tag) // 'few Newton iterations')
        end if
        deallocate(q, xs)
      end do
    end do
    ! Axial stretch with the elongation dynamic: u = P L / (EA).
    p = 1.0e-4_wp * EA
    u_ref = p * LEN / EA
    call make(cantilever(3, 'dynamic', p, 0.0_wp, ''), scene, dyn, err)
    if (err%ok()) then
      allocate(q(dyn%model%n_dy), xs(dyn%model%n_x, 1))
      q = 0.0_wp
      call static_solve(dyn, 0.0_wp, 1, 1.0e-12_wp, 20, q, xs, iters, err)
      if (err%ok()) then
        s = tip_state(dyn, xs(:, 1))
        call suite%close(s(1) - LEN, u_ref, 1.0e-6_wp, 0.0_wp, &
          'cantilever dynamic elongation, axial load: u = PL/EA')
        call suite%check(abs(s(2)) + abs(s(3)) < 1.0e-14_wp, &
          'cantilever axial load: no bending')
      end if
    end if
    call suite%check(err%ok(), 'cantilever with axial load solves')
  end subroutine small_deflection

  !> Mattiasson (1981), inextensible, load keeping its direction: k = P L^2/EI = 1..10 reached
  !> in 10 load steps of one static_solve.
  subroutine mattiasson()
    real(wp), parameter :: REF(3, 10) = reshape([ &
      0.30172_wp, 0.05643_wp, 0.46135_wp,  0.49346_wp, 0.16064_wp, 0.78175_wp, &
      0.60325_wp, 0.25442_wp, 0.98602_wp,  0.66996_wp, 0.32894_wp, 1.12124_wp, &
      0.71379_wp, 0.38763_wp, 1.21537_wp,  0.74457_wp, 0.43459_wp, 1.28370_wp, &
      0.76737_wp, 0.47293_wp, 1.33496_wp,  0.78498_wp, 0.50483_wp, 1.37443_wp, &
      0.79906_wp, 0.53182_wp, 1.40547_wp,  0.81061_wp, 0.55500_wp, 1.43029_wp], [3, 10])
    integer, parameter :: N_EL = 20
    type(scene_t) :: scene
    type(dynamics_t) :: dyn
    type(error_t) :: err
    real(wp), allocatable :: q(:), xs(:, :)
    real(wp) :: p, s(3), got(3), rel(3), worst(3)
    integer :: k, iters
    character(len=80) :: tag
    p = 10 * EI / LEN**2
    call make(cantilever(N_EL, 'rigid', 0.0_wp, p, &
      '&static n_steps = 10, tol = 1.0e-10, max_iter = 30 /' // NL), scene, dyn, err)
    call suite%check(err%ok(), 'Mattiasson model builds')
    if (.not. err%ok()) return
    call suite%check(scene%static%active .and. scene%static%n_steps == 10, &
      'Mattiasson: &static group read (n_steps = 10)')
    allocate(q(dyn%model%n_dy), xs(dyn%model%n_x, scene%static%n_steps))
    q = 0.0_wp
    call static_solve(dyn, 0.0_wp, scene%static%n_steps, scene%static%tol, &
      scene%static%max_iter, q, xs, iters, err)
    call suite%check(err%ok(), 'Mattiasson: static_solve converges in 10 load steps')
    if (.not. err%ok()) then
      write(*, '(a)') '    ' // err%message
      return
    end if
    write(*, '(a,i0,a,i0,a)') '  Mattiasson, ', N_EL, ' elements (angle form), ', iters, &
      ' Newton iterations in all; relative errors:'
    write(*, '(a)') '     k     w/L        u/L        theta     err w/L    err u/L  err theta'
    worst = 0
    do k = 1, 10
      s = tip_state(dyn, xs(:, k))
      got = [s(2) / LEN, (LEN - s(1)) / LEN, s(3)]
      rel = abs(got - REF(:, k)) / REF(:, k)
      worst = max(worst, rel)
      write(*, '(i6,3f11.5,3es11.2)') k, got, rel
    end do
    write(*, '(a,3es11.2)') '   max relative error                ', worst
    do k = 1, 10
      s = tip_state(dyn, xs(:, k))
      got = [s(2) / LEN, (LEN - s(1)) / LEN, s(3)]
      write(tag, '(a,i0,a)') 'Mattiasson k = ', k, ': '
      call suite%close(got(1), REF(1, k), 5.0e-3_wp, 0.0_wp, trim(tag) // 'w/L')
      call suite%close(got(2), REF(2, k), 5.0e-3_wp, 0.0_wp, trim(tag) // 'u/L')
      call suite%close(got(3), REF(3, k), 5.0e-3_wp, 0.0_wp, trim(tag) // 'theta')
    end do
    ! The table has 5 digits (rounding 5e-6); the angle form at 20 elements is far better
    ! than the 0.5% asked: its own error is about 1e-6.
    worst = 0
    do k = 1, 10
      s = tip_state(dyn, xs(:, k))
      got = [s(2) / LEN, (LEN - s(1)) / LEN, s(3)]
      worst = max(worst, abs(got - REF(:, k)))
    end do
    ! Table rounding 5e-6 + the 20-element error (< 1e-5 relative on values < 1.5, see the
    ! mesh study) is < 2e-5; 6e-5 keeps 10x over the observed 5e-6, a formulation error fails.
    write(tag, '(a,es9.2,a)') ' (worst ', maxval(worst), ')'
    call suite%check(all(worst < 6.0e-5_wp), 'Mattiasson: all 30 values within 6e-5 absolute ' &
      // '(table rounding 5e-6)' // trim(tag))
    ! The arc length is kept (e1_bar = 0): the tip stays within L of the root.
    s = tip_state(dyn, xs(:, 10))
    call suite%check(norm2(s(1:2)) < LEN, 'Mattiasson: chord shorter than the arc')
  end subroutine mattiasson

  !> Mesh convergence of both bending forms at k = 10 (docs/theory.md 2.1: the angle form converges
  !> far faster and is the default).
  subroutine mattiasson_convergence()
    real(wp), parameter :: REF(3) = [0.81061_wp, 0.55500_wp, 1.43029_wp]
    character(len=5), parameter :: FORM(2) = ['angle', 'sine ']
    integer, parameter :: MESH(3) = [4, 8, 20]
    type(scene_t) :: scene
    type(dynamics_t) :: dyn
    type(error_t) :: err
    real(wp), allocatable :: q(:), xs(:, :)
    real(wp) :: s(3), rel(3, 3, 2)
    integer :: i, j, iters
    write(*, '(a)') '  Mattiasson k = 10, relative errors against the mesh:'
    write(*, '(a)') '   form   N    err w/L    err u/L  err theta'
    do j = 1, 2
      do i = 1, 3
        call make(cantilever(MESH(i), 'rigid', 0.0_wp, 10 * EI / LEN**2, '', trim(FORM(j))), &
          scene, dyn, err)
        if (err%ok()) then
          allocate(q(dyn%model%n_dy), xs(dyn%model%n_x, 10))
          q = 0.0_wp
          call static_solve(dyn, 0.0_wp, 10, 1.0e-10_wp, 30, q, xs, iters, err)
          if (err%ok()) s = tip_state(dyn, xs(:, 10))
          deallocate(q, xs)
        end if
        call suite%check(err%ok(), 'Mattiasson ' // trim(FORM(j)) // ' form, ' // &
          itxt(MESH(i)) // ' elements: solves')
        if (.not. err%ok()) then
          write(*, '(a)') '    ' // err%message
          return
        end if
        rel(:, i, j) = abs([s(2) / LEN, (LEN - s(1)) / LEN, s(3)] - REF) / REF
        write(*, '(a7,i4,3es11.2)') trim(FORM(j)), MESH(i), rel(:, i, j)
      end do
      call suite%check(all(rel(:, 2, j) < rel(:, 1, j)) .and. all(rel(:, 3, j) < rel(:, 2, j)), &
        'Mattiasson ' // trim(FORM(j)) // ' form: error decreases with the mesh')
    end do
    call suite%check(all(rel(:, :, 1) < rel(:, :, 2)), &
      'Mattiasson: the angle form beats the sine form on every mesh')
    call suite%check(all(rel(:, 2, 1) < 1.0e-3_wp), 'Mattiasson angle form: 8 elements within 0.1%')
    call suite%check(all(rel(:, 3, 2) < 5.0e-3_wp), 'Mattiasson sine form: 20 elements within 0.5%')
  end subroutine mattiasson_convergence

  !> Critical load of the compressed cantilever from K_T(P) = S - P G: largest mu of
  !> G v = mu S v, P_cr = 1/mu.
  real(wp) function critical_load(n, elongation, err) result(p_cr)
    integer, intent(in) :: n
    character(len=*), intent(in) :: elongation
    type(error_t), intent(out) :: err
    type(scene_t) :: scene
    type(dynamics_t) :: dyn
    real(wp), allocatable :: q(:), s(:, :), kt(:, :), g(:, :), mu(:), v(:, :)
    real(wp) :: p
    integer :: nd, info
    p_cr = 0
    p = EI / LEN**2
    call make(cantilever(n, elongation, -p, 0.0_wp, ''), scene, dyn, err)
    if (.not. err%ok()) return
    nd = dyn%model%n_dy
    allocate(q(nd), s(nd, nd), kt(nd, nd), g(nd, nd), mu(nd), v(nd, nd))
    q = 0.0_wp
    dyn%load_factor = 0.0_wp
    call tangent_stiffness(dyn, 0.0_wp, q, s, err)
    if (.not. err%ok()) return
    dyn%load_factor = 1.0_wp
    call tangent_stiffness(dyn, 0.0_wp, q, kt, err)
    if (.not. err%ok()) return
    g = (s - kt) / p
    call sym_gen_eig(g, s, mu, v, info)
    if (info /= 0 .or. mu(nd) <= 0) then
      call err%set(1, 'buckling eigenproblem failed')
      return
    end if
    p_cr = 1 / mu(nd)
  end function critical_load

  subroutine buckling()
    integer, parameter :: MESH(4) = [1, 2, 4, 8]
    real(wp) :: exact, one_el, pc, prev
    type(error_t) :: err
    integer :: i
    character(len=80) :: tag
    exact = PI**2 / 4                       ! in units of EI/L^2
    ! One cubic element: 12 - 156 m + 135 m^2 = 0, P = 30 m EI/L^2 (about 2.4860).
    one_el = (156 - sqrt(17856.0_wp)) / 9
    write(*, '(a)') '  fixed-free buckling load in EI/L^2 (exact pi^2/4 = 2.467401):'
    write(*, '(a)') '   elements  elongation   P_cr       rel. error'
    prev = huge(1.0_wp)
    do i = 1, size(MESH)
      pc = critical_load(MESH(i), 'rigid', err) / (EI / LEN**2)
      if (.not. err%ok()) then
        call suite%check(.false., 'buckling model: ' // err%message)
        return
      end if
      write(*, '(i9,a12,f12.6,es13.3)') MESH(i), 'rigid', pc, (pc - exact) / exact
      write(tag, '(a,i0,a)') 'buckling, ', MESH(i), ' el. rigid: '
      call suite%check(pc >= exact * (1 - 1.0e-9_wp) .and. pc < prev, trim(tag) // &
        'upper bound, decreasing with the mesh')
      if (MESH(i) == 1) call suite%close(pc, one_el, 1.0e-5_wp, 0.0_wp, trim(tag) // &
        'one-element value (2.4860)')
      if (MESH(i) >= 2) call suite%close(pc, exact, 1.0e-2_wp, 0.0_wp, trim(tag) // &
        'within 1% of pi^2/4')
      prev = pc
    end do
    call suite%close(one_el, 2.486_wp, 2.0e-4_wp, 0.0_wp, '1-element value quoted in ' // &
      'docs/theory.md (2.486)')
    do i = 3, 4
      pc = critical_load(MESH(i), 'dynamic', err) / (EI / LEN**2)
      if (.not. err%ok()) then
        call suite%check(.false., 'buckling model (dynamic): ' // err%message)
        return
      end if
      write(*, '(i9,a12,f12.6,es13.3)') MESH(i), 'dynamic', pc, (pc - exact) / exact
      write(tag, '(a,i0,a)') 'buckling, ', MESH(i), ' el. dynamic elongation: '
      call suite%close(pc, exact, 1.0e-2_wp, 0.0_wp, trim(tag) // 'within 1% of pi^2/4')
    end do
  end subroutine buckling

  subroutine bad_input_and_beyond_buckling()
    type(scene_t) :: scene
    type(dynamics_t) :: dyn
    type(error_t) :: err
    real(wp), allocatable :: q(:), xs(:, :)
    real(wp) :: p
    integer :: iters
    type(nml_file_t) :: f
    ! &static n_steps = 0 is refused by the scene reader, naming the group.
    call f%parse(cantilever(2, 'rigid', 0.0_wp, 1.0_wp, '&static n_steps = 0 /' // NL), &
      'bad.nml', err)
    call suite%check(err%ok(), 'bad &static: parses')
    call read_scene(f, scene, err)
    call suite%check(.not. err%ok(), '&static n_steps = 0 is an input error')
    if (.not. err%ok()) then
      write(*, '(a)') '    message: ' // err%message
      call suite%check(index(err%message, 'static') > 0 .and. index(err%message, 'n_steps') > 0, &
        '&static n_steps = 0: message names the group and variable')
    end if
    call f%parse(cantilever(2, 'rigid', 0.0_wp, 1.0_wp, '&static tol = -1.0 /' // NL), &
      'bad.nml', err)
    if (err%ok()) call read_scene(f, scene, err)
    call suite%check(.not. err%ok(), '&static tol = -1 is an input error')
    ! static_solve itself refuses n_steps = 0.
    call make(cantilever(2, 'rigid', 0.0_wp, 1.0_wp, ''), scene, dyn, err)
    if (err%ok()) then
      allocate(q(dyn%model%n_dy), xs(dyn%model%n_x, 1))
      q = 0.0_wp
      call static_solve(dyn, 0.0_wp, 0, 1.0e-10_wp, 30, q, xs, iters, err)
      call suite%check(.not. err%ok(), 'static_solve(n_steps = 0) gives an error')
      deallocate(q, xs)
    end if

    ! Three times the buckling load, with a small transverse imperfection: the post-buckled
    ! (elastica) branch, or a clear error; never NaN.
    p = 3 * PI**2 / 4 * EI / LEN**2
    call make(cantilever(8, 'rigid', -p, 1.0e-3_wp * p, ''), scene, dyn, err)
    call beyond(dyn, err, 'compressed to 3 P_cr with imperfection')
    ! Exactly on the trivial branch (no imperfection): q stays 0 or a clear error.
    call make(cantilever(8, 'rigid', -p, 0.0_wp, ''), scene, dyn, err)
    call beyond(dyn, err, 'compressed to 3 P_cr, perfect')
    ! A mechanism-like model: a hinge with zero stiffness at the root, transverse tip load. The
    ! tangent stiffness is singular at the start (the load's moment has no stiffness there).
    call make("&node label = 'root', x = 0.0, y = 0.0, fixed = .true. /" // NL // &
      "&node label = 'tip', x = " // rtxt(LEN) // ", y = 0.0 /" // NL // &
      "&link label = 'beam', from = 'root', to = 'tip', n_elements = 4," // NL // &
      "      E = " // rtxt(E_MOD) // ", A = " // rtxt(AREA) // ", I = " // rtxt(INER) // &
      ", rho = " // rtxt(RHO) // " /" // NL // &
      "&hinge label = 'pin', node = 'root', link = 'beam', mode = 'dynamic', stiffness = 0.0 /" &
      // NL // "&force node = 'tip', fy = 1.0 /" // NL, scene, dyn, err)
    call beyond(dyn, err, 'pinned (zero-stiffness hinge) with transverse load')
  end subroutine bad_input_and_beyond_buckling

  !> dyn was just made (err from make): run 10 load steps and accept either a finite
  !> equilibrium (small residual) or an error with a message.
  subroutine beyond(dyn, err, what)
    type(dynamics_t), intent(inout) :: dyn
    type(error_t), intent(in) :: err
    character(len=*), intent(in) :: what
    type(error_t) :: err2
    real(wp), allocatable :: q(:), xs(:, :), k(:, :)
    integer :: iters
    logical :: finite
    call suite%check(err%ok(), what // ': model builds')
    if (.not. err%ok()) then
      write(*, '(a)') '    ' // err%message
      return
    end if
    allocate(q(dyn%model%n_dy), xs(dyn%model%n_x, 10), k(dyn%model%n_dy, dyn%model%n_dy))
    q = 0.0_wp
    xs = 0.0_wp
    call static_solve(dyn, 0.0_wp, 10, 1.0e-10_wp, 30, q, xs, iters, err2)
    finite = all(ieee_is_finite(q))
    if (err2%ok()) then
      finite = finite .and. all(ieee_is_finite(xs))
      ! equilibrium: the generalised force vanishes at the last state
      dyn%load_factor = 1.0_wp
      dyn%locked = .true.
      call tangent_stiffness(dyn, 0.0_wp, q, k, err2)
      dyn%locked = .false.
      write(*, '(a,i0,a,es10.2,a,es10.2)') '    ' // what // ': converged, ', iters, &
        ' iterations, tip (x, y) = ', xs(dyn%model%node_coord(1, dyn%model%find_node('tip')), 10), &
        ', ', xs(dyn%model%node_coord(2, dyn%model%find_node('tip')), 10)
      call suite%check(finite .and. err2%ok(), what // ': converged to a finite state')
      if (err2%ok()) call suite%check(maxval(abs(dyn%gen_force)) <= 1.0e-6_wp * &
        max(1.0_wp, maxval(abs(dyn%model%force)) * LEN), what // ': equilibrium residual small')
    else
      write(*, '(a)') '    ' // what // ': error: ' // err2%message
      call suite%check(len_trim(err2%message) > 10 .and. index(err2%message, 'NaN') == 0, &
        what // ': clear error message')
      call suite%check(finite, what // ': no NaN left in q after the error')
    end if
  end subroutine beyond
end program test_verification_static
