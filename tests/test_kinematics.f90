!> Kinematics (docs/theory.md section 4) and equations of motion (section 5) against finite
!> differences of full Newton solves, on models built from namelist text:
!>   - the two-link manipulator of input/two_link.nml (as is, and with gravity and loads added),
!>   - a driven crank with two spring trusses (truss/hinge mechanism, gravity, lumped and
!>     consistent truss masses).
!> At deformed states (nonzero prescribed and dynamic coordinates) it checks
!>   - the solved x satisfies the kinematic equations (kin%residual and element by element);
!>   - DF against central FD of x(q), every FD point a full Newton solve;
!>   - D2F qd qd (kin%second) against a 5-point FD of d2/ds2 x(q + s qd);
!>   - dyn%mbar against DF_dy^T M DF_dy assembled here with the FD transfer function;
!>   - zero velocity and no loads: gen_force = -sigma and a = -Mbar^-1 sigma;
!>   - Lagrange's equations d/dt dT/dqd_dy - dT/dq_dy + dV/dq_dy = 0 for the accelerations of
!>     dynamics_t%evaluate, with T = 1/2 xd^T M(x) xd and V (elastic + loads + gravity)
!>     differentiated numerically along the motion (this validates h, D2F and the assembly);
!>   - models whose classes do not solve give clear errors.
program test_kinematics
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_MODEL, ERR_NUMERIC
  use testing, only: suite_t
  use test_scenes, only: source_dir, make_dynamics_from
  use fd_helpers, only: lcg_t, relerr, flat
  use io_namelist, only: nml_file_t
  use io_scene, only: read_scene
  use model_scene, only: scene_t
  use model_build, only: build_model
  use model_system, only: model_t, COORD_X, COORD_Y
  use model_kinematics, only: kinematics_t
  use dynamics_system, only: dynamics_t
  use elements_base, only: MODE_RELEASED
  implicit none

  !> A crank driven through a prescribed hinge, carrying node C on two spring trusses; the
  !> lengths let the crank turn fully (|B - D| stays between the difference and the sum of
  !> the truss lengths).
  character(len=*), parameter :: NL = achar(10)
  character(len=*), parameter :: CRANK_TEXT = &
    "&scene title = 'crank with two spring trusses', gravity = 0.0, -9.81 /" // NL // &
    "&node label = 'A', x = 0.0, y = 0.0, fixed = .true. /" // NL // &
    "&node label = 'B', x = 0.2, y = 0.0 /" // NL // &
    "&node label = 'C', x = 0.4, y = 0.7 /" // NL // &
    "&node label = 'D', x = 0.8, y = 0.3, fixed = .true. /" // NL // &
    "&link label = 'crank', from = 'A', to = 'B', E = 2.1e11, A = 1.0e-4, I = 1.0e-9," // &
    " rho = 7800, elongation = 'rigid', bending = 'rigid' /" // NL // &
    "&hinge label = 'drive', node = 'A', link = 'crank', mode = 'prescribed'," // &
    " motion = 'turn' /" // NL // &
    "&motion label = 'turn', law = 'quintic', start = 0.0, end = 1.2, duration = 0.4 /" // NL // &
    "&truss label = 'bc', from = 'B', to = 'C', E = 2.0e9, A = 1.0e-5, rho = 1200 /" // NL // &
    "&truss label = 'cd', from = 'C', to = 'D', E = 1.0e9, A = 1.0e-5, rho = 1200," // &
    " mass = 'lumped' /" // NL // &
    "&mass node = 'C', m = 0.5 /" // NL // &
    "&mass node = 'B', m = 0.2 /" // NL

  !> FD points are solved to this residual (the default is 1e-11 m: too coarse for FD).
  real(wp), parameter :: FD_NEWTON_TOL = 1.0e-14_wp

  type(suite_t) :: ts
  character(len=:), allocatable :: two_link
  type(lcg_t) :: rng = lcg_t(seed=777)

  call ts%init('kinematics')
  call load_two_link(two_link)
  if (len(two_link) > 0) then
    call two_link_tests(two_link)
  end if
  call crank_tests()
  call error_tests(two_link)
  call singular_configuration_tests()
  call regular_spatial_configuration()
  call ts%finish()

contains

  ! ------------------------------------------------------------------ utilities

  !> Gaussian elimination with partial pivoting (kept here, independent of core_linalg).
  subroutine gauss_solve(a_in, b, info)
    real(wp), intent(in) :: a_in(:, :)
    real(wp), intent(inout) :: b(:)
    integer, intent(out) :: info
    real(wp) :: a(size(b), size(b)), row(size(b)), t
    integer :: n, k, p, i
    n = size(b)
    a = a_in
    info = 0
    do k = 1, n
      p = k - 1 + maxloc(abs(a(k:, k)), 1)
      if (a(p, k) == 0) then
        info = k
        return
      end if
      row = a(k, :); a(k, :) = a(p, :); a(p, :) = row
      t = b(k); b(k) = b(p); b(p) = t
      do i = k + 1, n
        t = a(i, k) / a(k, k)
        a(i, k:) = a(i, k:) - t * a(k, k:)
        b(i) = b(i) - t * b(k)
      end do
    end do
    do k = n, 1, -1
      b(k) = (b(k) - dot_product(a(k, k + 1:), b(k + 1:))) / a(k, k)
    end do
  end subroutine gauss_solve

  subroutine expect(what, err, tol)
    character(len=*), intent(in) :: what
    real(wp), intent(in) :: err, tol
    character(len=60) :: buf
    write(buf, '(a,es9.2,a,es8.1,a)') ': rel err ', err, ' (tol ', tol, ')'
    call ts%check(err <= tol .and. err == err, what // trim(buf))
  end subroutine expect

  subroutine expect_ok(err, what)
    type(error_t), intent(in) :: err
    character(len=*), intent(in) :: what
    if (err%ok()) then
      call ts%check(.true., what)
    else
      call ts%check(.false., what // ': ' // err%message)
    end if
  end subroutine expect_ok

  !> Error expected whose message contains every one of `words`.
  subroutine expect_error(err, code, words, what)
    type(error_t), intent(in) :: err
    integer, intent(in) :: code
    character(len=*), intent(in) :: words(:), what
    logical :: good
    integer :: i
    good = .not. err%ok()
    if (good) then
      good = err%code == code
      do i = 1, size(words)
        good = good .and. index(err%message, trim(words(i))) > 0
      end do
      call ts%check(good, what // ' -> "' // err%message // '"')
    else
      call ts%check(.false., what // ': no error reported')
    end if
  end subroutine expect_error

  !> input/two_link.nml, relative to the working directory (CTest runs in the source tree) or
  !> to $FLEXMOR_SOURCE_DIR. Returns its text ('' after a failed check).
  subroutine load_two_link(text)
    character(len=:), allocatable, intent(out) :: text
    type(nml_file_t) :: f
    type(error_t) :: err
    character(len=4096) :: dir
    integer :: n, stat
    call f%load('input/two_link.nml', err)
    if (.not. err%ok()) then
      call get_environment_variable('FLEXMOR_SOURCE_DIR', dir, n, stat)
      if (stat == 0 .and. n > 0) call f%load(dir(1:n) // '/input/two_link.nml', err)
    end if
    call expect_ok(err, 'load input/two_link.nml')
    text = ''
    if (err%ok()) text = f%text
  end subroutine load_two_link

  subroutine model_from_text(text, label, model, err)
    character(len=*), intent(in) :: text, label
    type(model_t), intent(out) :: model
    type(error_t), intent(out) :: err
    type(nml_file_t) :: f
    type(scene_t) :: scene
    call f%parse(text, label, err)
    if (err%ok()) call read_scene(f, scene, err)
    if (err%ok()) call build_model(scene, model, err)
  end subroutine model_from_text

  !> text with `old` replaced by `new` (first occurrence; must be there).
  function replaced(text, old, new) result(r)
    character(len=*), intent(in) :: text, old, new
    character(len=:), allocatable :: r
    integer :: k
    k = index(text, old)
    if (k == 0) then
      call ts%check(.false., 'test set-up: text "' // old // '" not found')
      r = text
      return
    end if
    r = text(1:k - 1) // new // text(k + len(old):)
  end function replaced

  ! ------------------------------------------------------------------ model-level helpers

  !> Solve along a straight path from the current solution to q (continuation; keeps Newton
  !> on the right branch), leaving the transfer function at q.
  subroutine solve_path(kin, model, q, err)
    type(kinematics_t), intent(inout) :: kin
    type(model_t), intent(in) :: model
    real(wp), intent(in) :: q(:)
    type(error_t), intent(out) :: err
    real(wp) :: q0(size(q))
    integer :: k
    integer, parameter :: N_STEPS = 8
    q0 = kin%q
    do k = 1, N_STEPS
      call kin%solve(model, q0 + (q - q0) * real(k, wp) / N_STEPS, err)
      if (.not. err%ok()) return
      call kin%transfer(model)
    end do
  end subroutine solve_path

  !> x(q) (and DF there) by a full Newton solve started from a copy of a solved state.
  subroutine solved(kin0, model, q, x, nfail, df)
    type(kinematics_t), intent(in) :: kin0
    type(model_t), intent(in) :: model
    real(wp), intent(in) :: q(:)
    real(wp), intent(out) :: x(:)
    integer, intent(inout) :: nfail
    real(wp), intent(out), optional :: df(:, :)
    type(kinematics_t) :: kin
    type(error_t) :: err
    kin = kin0
    call kin%solve(model, q, err)
    if (.not. err%ok()) nfail = nfail + 1
    x = kin%x
    if (present(df)) then
      call kin%transfer(model)
      df = kin%df
    end if
  end subroutine solved

  !> DF by central differences of solved x(q); h(j) per generalised coordinate.
  function fd_transfer(kin0, model, q, h, nfail) result(df)
    type(kinematics_t), intent(in) :: kin0
    type(model_t), intent(in) :: model
    real(wp), intent(in) :: q(:), h(:)
    integer, intent(inout) :: nfail
    real(wp) :: df(model%n_x, size(q)), xp(model%n_x), xm(model%n_x), qp(size(q))
    integer :: j
    do j = 1, size(q)
      qp = q
      qp(j) = q(j) + h(j)
      call solved(kin0, model, qp, xp, nfail)
      qp(j) = q(j) - h(j)
      call solved(kin0, model, qp, xm, nfail)
      df(:, j) = (xp - xm) / (2 * h(j))
    end do
  end function fd_transfer

  !> 5-point FD of d2/ds2 x(q + s qd) at s = 0.
  function fd_second(kin0, model, q, qd, s, nfail) result(d2x)
    type(kinematics_t), intent(in) :: kin0
    type(model_t), intent(in) :: model
    real(wp), intent(in) :: q(:), qd(:), s
    integer, intent(inout) :: nfail
    real(wp) :: d2x(model%n_x), x(model%n_x, -2:2)
    integer :: k
    do k = -2, 2
      call solved(kin0, model, q + k * s * qd, x(:, k), nfail)
    end do
    d2x = (-x(:, 2) + 16 * x(:, 1) - 30 * x(:, 0) + 16 * x(:, -1) - x(:, -2)) / (12 * s**2)
  end function fd_second

  !> Full mass matrix at x: lumped diagonal plus the element (consistent) masses.
  function full_mass(model, x) result(m)
    type(model_t), intent(in) :: model
    real(wp), intent(in) :: x(:)
    real(wp) :: m(model%n_x, model%n_x)
    real(wp), allocatable :: me(:, :), he(:)
    integer :: i
    m = 0.0_wp
    do i = 1, model%n_x
      m(i, i) = model%lumped(i)
    end do
    do i = 1, model%n_elements
      associate (el => model%elements(i)%e)
        allocate(me(size(el%dofs), size(el%dofs)), he(size(el%dofs)))
        call el%inertia(x(el%dofs), 0 * x(el%dofs), me, he)
        m(el%dofs, el%dofs) = m(el%dofs, el%dofs) + me
        deallocate(me, he)
      end associate
    end do
  end function full_mass

  !> Potential of the constant loads and gravity (lumped and consistent masses).
  real(wp) function external_potential(model, x) result(v)
    type(model_t), intent(in) :: model
    real(wp), intent(in) :: x(:)
    real(wp), allocatable :: fe(:)
    real(wp) :: pot
    integer :: i
    v = -dot_product(model%force, x)
    do i = 1, model%n_x
      if (model%coord_kind(i) == COORD_X) v = v - model%lumped(i) * model%gravity(1) * x(i)
      if (model%coord_kind(i) == COORD_Y) v = v - model%lumped(i) * model%gravity(2) * x(i)
    end do
    do i = 1, model%n_elements
      associate (el => model%elements(i)%e)
        allocate(fe(size(el%dofs)))
        call el%weight(x(el%dofs), model%gravity(1:model%dim), fe, pot)
        v = v + pot
        deallocate(fe)
      end associate
    end do
  end function external_potential

  !> Stress resultants sigma = S (e + beta e_dot) of the dynamic modes, with e and e_dot from
  !> q and qd (conjugate to e_bar), in q_dy order.
  function dynamic_stresses(model, q, qd) result(sigma)
    type(model_t), intent(in) :: model
    real(wp), intent(in) :: q(:), qd(:)
    real(wp) :: sigma(model%n_dy)
    real(wp), allocatable :: s(:, :), e(:)
    integer :: iel, j, nm, m0
    sigma = 0.0_wp
    do iel = 1, model%n_elements
      nm = model%elements(iel)%e%n_modes()
      m0 = model%mode_first(iel) - 1
      allocate(s(nm, nm), e(nm))
      call model%elements(iel)%e%stiffness(s)
      e = 0.0_wp
      do j = 1, nm
        if (model%modes(m0 + j)%q > 0) e(j) = q(model%modes(m0 + j)%q) + &
          model%elements(iel)%e%damping * qd(model%modes(m0 + j)%q)
      end do
      e = matmul(s, e)
      do j = 1, nm
        if (model%modes(m0 + j)%q > model%n_rh) sigma(model%modes(m0 + j)%q - model%n_rh) = e(j)
      end do
      deallocate(s, e)
    end do
  end function dynamic_stresses

  ! ------------------------------------------------------------------ generic checks

  !> Kinematic checks at q with velocities qd: residual, DF, D2F (model already solved there
  !> in kin, with transfer done).
  subroutine check_kinematics(kin, model, q, qd, hq, s2, what)
    type(kinematics_t), intent(inout) :: kin
    type(model_t), intent(in) :: model
    real(wp), intent(in) :: q(:), qd(:), hq(:), s2
    character(len=*), intent(in) :: what
    type(model_t) :: mfd
    real(wp) :: r(model%n_c), dffd(model%n_x, model%n_q), d2x(model%n_x), d2fd(model%n_x)
    real(wp), allocatable :: e(:), de(:, :)
    real(wp) :: worst
    integer :: nfail, iel, j, iq
    character(len=80) :: buf
    call kin%residual(model, q, r)
    write(buf, '(a,es9.2,a,es9.2)') ': max |r| ', maxval(abs(r)), ' <= tol ', model%newton_tol
    call ts%check(maxval(abs(r)) <= model%newton_tol, what // ' kinematic residual' // trim(buf))
    ! The same, element by element: rigid modes 0, prescribed and dynamic modes equal to q.
    worst = 0.0_wp
    do iel = 1, model%n_elements
      associate (el => model%elements(iel)%e)
        allocate(e(el%n_modes()), de(el%n_modes(), size(el%dofs)))
        call el%evaluate(kin%x(el%dofs), e, de)
        do j = 1, el%n_modes()
          associate (mode => model%modes(model%mode_first(iel) + j - 1))
            if (mode%class == MODE_RELEASED) cycle
            iq = mode%q
            if (iq > 0) then
              worst = max(worst, abs(e(j) - q(iq)))
            else
              worst = max(worst, abs(e(j)))
            end if
          end associate
        end do
        deallocate(e, de)
      end associate
    end do
    write(buf, '(a,es9.2)') ': max |e(x) - e(q)| ', worst
    call ts%check(worst <= model%newton_tol, what // ' modes of the solved x' // trim(buf))
    ! Transfer functions against FD of full Newton solves.
    mfd = model
    mfd%newton_tol = FD_NEWTON_TOL
    nfail = 0
    dffd = fd_transfer(kin, mfd, q, hq, nfail)
    call expect(what // ' DF vs FD of x(q)', relerr(flat(kin%df), flat(dffd), 1.0_wp), 1.0e-7_wp)
    call kin%second(model, qd, d2x)
    d2fd = fd_second(kin, mfd, q, qd, s2, nfail)
    call expect(what // ' D2F qd qd vs FD d2/ds2 x(q + s qd)', relerr(d2x, d2fd, &
      1.0e-3_wp * maxval(abs(d2fd))), 1.0e-6_wp)
    call ts%check(nfail == 0, what // ' every FD point solved')
  end subroutine check_kinematics

  !> Mass and static checks at a state with zero velocity and no loads (prescribed motion at
  !> rest): Mbar = DF_dy^T M DF_dy, gen_force = -sigma, a = -Mbar^-1 sigma.
  subroutine check_rest(dyn, t, q_dy, hq, what)
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: t, q_dy(:), hq(:)
    character(len=*), intent(in) :: what
    type(model_t) :: mfd
    type(error_t) :: err
    real(wp) :: q(dyn%model%n_q), a(size(q_dy)), sigma(size(q_dy)), mb(size(q_dy), size(q_dy))
    real(wp) :: dffd(dyn%model%n_x, dyn%model%n_q), b(size(q_dy))
    integer :: nfail, info, nr
    call dyn%evaluate_dense(t, q_dy, 0 * q_dy, a, err)
    call expect_ok(err, what // ' evaluate at rest')
    if (.not. err%ok()) return
    nr = dyn%model%n_rh
    q = dyn%full_q(t, q_dy)
    mfd = dyn%model
    mfd%newton_tol = FD_NEWTON_TOL
    nfail = 0
    dffd = fd_transfer(dyn%kin, mfd, q, hq, nfail)
    mb = matmul(transpose(dffd(:, nr + 1:)), matmul(full_mass(dyn%model, dyn%kin%x), &
      dffd(:, nr + 1:)))
    call expect(what // ' Mbar = DF_dy^T M DF_dy (FD DF)', relerr(flat(dyn%mbar), flat(mb), &
      1.0_wp), 1.0e-7_wp)
    sigma = dynamic_stresses(dyn%model, q, 0 * q)
    call ts%check(maxval(abs(sigma)) > 0, what // ' stresses are nonzero (test set-up)')
    call expect(what // ' gen_force = -sigma', relerr(dyn%gen_force, -sigma, 1.0_wp), 1.0e-12_wp)
    b = -sigma
    call gauss_solve(dyn%mbar, b, info)
    call ts%check(info == 0, what // ' Mbar regular')
    call expect(what // ' a = -Mbar^-1 sigma', relerr(a, b, 1.0e-12_wp), 1.0e-8_wp)
    ! Mbar is ill-conditioned (stiff high modes): a is large, so the small FD error of Mbar_fd
    ! shows up magnified here; the check is on the backward error only.
    call expect(what // ' Mbar_fd a + sigma = 0 (backward)', relerr(matmul(mb, a), -sigma, &
      1.0e-12_wp), 1.0e-5_wp)
    call ts%check(nfail == 0, what // ' every FD point solved')
  end subroutine check_rest

  !> Lagrange's equations for the accelerations of dyn%evaluate at (t, q_dy, v_dy):
  !>   d/dt (dT/dqd_dy) - dT/dq_dy + dV/dq_dy + beta S e_dot = 0,
  !>   T = 1/2 xd^T M(x) xd,  xd = DF qd,  V = 1/2 e^T S e + load and gravity potential,
  !> with d/dt along q(tau) = q + tau qd + tau^2/2 qdd (qdd = (q_rh'', a)) and dT/dq, dV/dq by
  !> central differences of full Newton solves.
  subroutine check_lagrange(dyn, t, q_dy, v_dy, hq, dtau, what)
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: t, q_dy(:), v_dy(:), hq(:), dtau
    character(len=*), intent(in) :: what
    type(model_t) :: mfd
    type(error_t) :: err
    integer :: n, nr, nd, j, k, nfail
    real(wp) :: q(dyn%model%n_q), qd(dyn%model%n_q), qdd(dyn%model%n_q), a(size(q_dy))
    real(wp) :: x(dyn%model%n_x), df(dyn%model%n_x, dyn%model%n_q), xd(dyn%model%n_x)
    real(wp) :: p(size(q_dy), -2:2), dpdt(size(q_dy)), dtdq(size(q_dy)), dvdq(size(q_dy))
    real(wp) :: tq(2), vq(2), qq(dyn%model%n_q), tau, res(size(q_dy)), scale
    character(len=100) :: buf
    n = dyn%model%n_x
    nr = dyn%model%n_rh
    nd = dyn%model%n_dy
    call dyn%evaluate_dense(t, q_dy, v_dy, a, err)
    call expect_ok(err, what // ' evaluate')
    if (.not. err%ok()) return
    call dyn%prescribed(t, q(1:nr), qd(1:nr), qdd(1:nr))
    q(nr + 1:) = q_dy
    qd(nr + 1:) = v_dy
    qdd(nr + 1:) = a
    mfd = dyn%model
    mfd%newton_tol = FD_NEWTON_TOL
    nfail = 0
    ! d/dt of the generalised momentum p = DF_dy^T M(x) DF qd along the motion (5 points).
    do k = -2, 2
      tau = k * dtau
      call solved(dyn%kin, mfd, q + tau * qd + tau**2 / 2 * qdd, x, nfail, df)
      xd = matmul(df, qd + tau * qdd)
      p(:, k) = matmul(transpose(df(:, nr + 1:)), matmul(full_mass(mfd, x), xd))
    end do
    dpdt = (-p(:, 2) + 8 * p(:, 1) - 8 * p(:, -1) + p(:, -2)) / (12 * dtau)
    ! dT/dq_dy and dV/dq_dy at fixed qd.
    do j = 1, nd
      do k = 1, 2
        qq = q
        qq(nr + j) = q(nr + j) + (3 - 2 * k) * hq(nr + j)
        call solved(dyn%kin, mfd, qq, x, nfail, df)
        xd = matmul(df, qd)
        tq(k) = 0.5_wp * dot_product(xd, matmul(full_mass(mfd, x), xd))
        vq(k) = external_potential(mfd, x)
      end do
      dtdq(j) = (tq(1) - tq(2)) / (2 * hq(nr + j))
      dvdq(j) = (vq(1) - vq(2)) / (2 * hq(nr + j))
    end do
    dvdq = dvdq + dynamic_stresses(dyn%model, q, qd)
    res = dpdt - dtdq + dvdq
    scale = max(maxval(abs(dpdt)), maxval(abs(dtdq)), maxval(abs(dvdq)))
    write(buf, '(a,3es9.2)') ' (|dp/dt|, |dT/dq|, |dV/dq| = ', maxval(abs(dpdt)), &
      maxval(abs(dtdq)), maxval(abs(dvdq))
    call expect(what // ' Lagrange residual' // trim(buf) // ')', maxval(abs(res)) / scale, &
      1.0e-6_wp)
    call ts%check(maxval(abs(dtdq)) > 1.0e-3_wp * scale, what // &
      ' dT/dq is significant (the test sees the convective terms)')
    call ts%check(nfail == 0, what // ' every FD point solved')
  end subroutine check_lagrange

  !> Drive a dynamics_t from its initial state to (t, q_dy) in small steps.
  subroutine walk(dyn, t0, t, q_dy, err)
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: t0, t, q_dy(:)
    type(error_t), intent(out) :: err
    real(wp) :: a(size(q_dy)), s
    integer :: k
    do k = 1, 8
      s = real(k, wp) / 8
      call dyn%evaluate_dense(t0 + s * (t - t0), s * q_dy, 0 * q_dy, a, err)
      if (.not. err%ok()) return
    end do
  end subroutine walk

  ! ------------------------------------------------------------------ the models

  subroutine two_link_tests(text)
    character(len=*), intent(in) :: text
    type(model_t) :: model
    type(error_t) :: err
    type(kinematics_t) :: kin
    type(dynamics_t) :: dyn, dyn2
    real(wp), allocatable :: q(:), qd(:), hq(:), q_dy(:), v_dy(:)
    integer :: nr, nd, i
    call model_from_text(text, 'two_link.nml', model, err)
    call expect_ok(err, 'two-link: build from input/two_link.nml')
    if (.not. err%ok()) return
    call ts%check(model%n_rh == 2 .and. model%n_dy == 12 .and. model%n_c == model%n_rigid + &
      model%n_q, 'two-link: 2 prescribed + 12 dynamic coordinates, counts solve')
    nr = model%n_rh
    nd = model%n_dy
    call ts%check(point_mass(model, 'elbow') == 1.0_wp .and. point_mass(model, 'tip') == &
      3.0_wp .and. point_mass(model, 'link1.1') == 0.0_wp, &
      'two-link: point masses 1 kg (elbow) and 3 kg (tip), none elsewhere')
    ! Kinematics at a deformed state.
    q = [0.7_wp, -1.1_wp, rng%uniform_vec(nd, -4.0e-3_wp, 4.0e-3_wp)]
    qd = [2.0_wp, -3.0_wp, rng%uniform_vec(nd, -0.05_wp, 0.05_wp)]
    hq = [[1, 1] * 1.0e-5_wp, [(1.0e-6_wp, i = 1, nd)]]
    call kin%init(model)
    call solve_path(kin, model, q, err)
    call expect_ok(err, 'two-link: kinematics solved at a deformed q')
    if (err%ok()) call check_kinematics(kin, model, q, qd, hq, 1.0e-3_wp, 'two-link')
    ! Dynamics: at rest after the motion (t = 0.6 s), then during it with velocities.
    call dyn%init(model, 0.0_wp, [(0.0_wp, i = 1, nd)], err)
    call expect_ok(err, 'two-link: dynamics initialised')
    if (.not. err%ok()) return
    q_dy = rng%uniform_vec(nd, -2.0e-3_wp, 2.0e-3_wp)
    call walk(dyn, 0.0_wp, 0.6_wp, q_dy, err)
    call expect_ok(err, 'two-link: walked to t = 0.6')
    if (err%ok()) call check_rest(dyn, 0.6_wp, q_dy, hq, 'two-link at rest')
    q_dy = rng%uniform_vec(nd, -3.0e-4_wp, 3.0e-4_wp)
    v_dy = rng%uniform_vec(nd, -0.05_wp, 0.05_wp)
    call walk(dyn, 0.6_wp, 0.2_wp, q_dy, err)
    if (err%ok()) call check_lagrange(dyn, 0.2_wp, q_dy, v_dy, hq, 1.0e-5_wp, &
      'two-link t = 0.2')
    ! The same with gravity and nodal loads (forces and a moment) added.
    call model_from_text(replaced(text, '&scene title', '&scene gravity = 0.0, -9.81, title') &
      // "&force node = 'tip', fx = 5.0, fy = -3.0, moment = 0.8 /" // NL // &
      "&force node = 'elbow', fy = 2.0 /" // NL, 'two_link+loads', model, err)
    call expect_ok(err, 'two-link + gravity + loads: build')
    if (.not. err%ok()) return
    call dyn2%init(model, 0.0_wp, [(0.0_wp, i = 1, nd)], err)
    call walk(dyn2, 0.0_wp, 0.3_wp, q_dy, err)
    call expect_ok(err, 'two-link + gravity + loads: walked to t = 0.3')
    if (err%ok()) call check_lagrange(dyn2, 0.3_wp, q_dy, v_dy, hq, 1.0e-5_wp, &
      'two-link + loads t = 0.3')
    call two_link_variant(text)
  end subroutine two_link_tests

  !> Lumped translational mass at a named point.
  real(wp) function point_mass(model, label) result(m)
    type(model_t), intent(in) :: model
    character(len=*), intent(in) :: label
    integer :: k
    m = -1.0_wp
    k = model%find_node(label)
    if (k > 0) m = model%lumped(model%node_coord(1, k))
  end function point_mass

  !> Two-link with link 2 in the sine form, lumped mass and dynamic elongation, and
  !> stiffness-proportional damping in link 1.
  subroutine two_link_variant(text)
    character(len=*), intent(in) :: text
    type(model_t) :: model
    type(error_t) :: err
    type(kinematics_t) :: kin
    type(dynamics_t) :: dyn
    real(wp), allocatable :: q(:), qd(:), hq(:), q_dy(:), v_dy(:)
    integer :: nr, nd, iq
    call model_from_text(replaced(replaced(text, "to = 'tip', n_elements = 3,", &
      "to = 'tip', n_elements = 3, bending_form = 'sine', elongation = 'dynamic', " // &
      "mass = 'lumped',"), "to = 'elbow', n_elements = 3,", &
      "to = 'elbow', n_elements = 3, damping = 2.0e-4,"), 'two_link variant', model, err)
    call expect_ok(err, 'two-link variant (sine, lumped, dynamic elongation, damping): build')
    if (.not. err%ok()) return
    nr = model%n_rh
    nd = model%n_dy
    call ts%check(nd == 15, 'two-link variant: 15 dynamic coordinates')
    q_dy = rng%uniform_vec(nd, -3.0e-4_wp, 3.0e-4_wp)
    v_dy = rng%uniform_vec(nd, -0.05_wp, 0.05_wp)
    ! Elongations are stiff (EA/l0 ~ 1e8 N/m): keep their values small.
    do iq = nr + 1, nr + nd
      if (model%modes(model%q_mode(iq))%local == 1) then
        q_dy(iq - nr) = q_dy(iq - nr) * 1.0e-3_wp
        v_dy(iq - nr) = v_dy(iq - nr) * 1.0e-2_wp
      end if
    end do
    q = [-0.9_wp, 2.1_wp, 10 * q_dy]
    qd = [-1.5_wp, 2.5_wp, v_dy]
    hq = [[1, 1] * 1.0e-5_wp, [(1.0e-6_wp, iq = 1, nd)]]
    call kin%init(model)
    call solve_path(kin, model, q, err)
    call expect_ok(err, 'two-link variant: kinematics solved')
    if (err%ok()) call check_kinematics(kin, model, q, qd, hq, 1.0e-3_wp, 'two-link variant')
    call dyn%init(model, 0.0_wp, 0 * q_dy, err)
    call expect_ok(err, 'two-link variant: dynamics initialised')
    if (.not. err%ok()) return
    call walk(dyn, 0.0_wp, 0.35_wp, q_dy, err)
    ! The stiff elongations make qdd large: a short time step keeps the O(dtau^4) error small.
    if (err%ok()) call check_lagrange(dyn, 0.35_wp, q_dy, v_dy, hq, 1.0e-6_wp, &
      'two-link variant t = 0.35')
  end subroutine two_link_variant

  subroutine crank_tests()
    type(model_t) :: model
    type(error_t) :: err
    type(kinematics_t) :: kin
    type(dynamics_t) :: dyn, dyn2
    real(wp) :: q(3), qd(3), hq(3)
    call model_from_text(CRANK_TEXT, 'crank', model, err)
    call expect_ok(err, 'crank: build')
    if (.not. err%ok()) return
    call ts%check(model%n_rh == 1 .and. model%n_dy == 2, 'crank: 1 prescribed + 2 dynamic')
    q = [2.4_wp, 3.0e-3_wp, -2.0e-3_wp]
    qd = [4.0_wp, 0.2_wp, -0.3_wp]
    hq = [1.0e-5_wp, 1.0e-6_wp, 1.0e-6_wp]
    call kin%init(model)
    call solve_path(kin, model, q, err)
    call expect_ok(err, 'crank: kinematics solved (crank beyond 90 deg)')
    if (err%ok()) call check_kinematics(kin, model, q, qd, hq, 1.0e-3_wp, 'crank')
    call dyn%init(model, 0.0_wp, [0.0_wp, 0.0_wp], err)
    call expect_ok(err, 'crank: dynamics initialised')
    if (.not. err%ok()) return
    call walk(dyn, 0.0_wp, 0.13_wp, [1.0e-4_wp, -2.0e-4_wp], err)
    if (err%ok()) call check_lagrange(dyn, 0.13_wp, [1.0e-4_wp, -2.0e-4_wp], &
      [0.05_wp, 0.08_wp], hq, 1.0e-4_wp, 'crank t = 0.13')
    ! At rest without gravity.
    model%gravity = 0.0_wp
    call dyn2%init(model, 0.0_wp, [0.0_wp, 0.0_wp], err)
    call walk(dyn2, 0.0_wp, 0.5_wp, [1.0e-3_wp, 5.0e-4_wp], err)
    if (err%ok()) call check_rest(dyn2, 0.5_wp, [1.0e-3_wp, 5.0e-4_wp], hq, 'crank at rest')
  end subroutine crank_tests

  ! ------------------------------------------------------------------ models that do not solve

  subroutine error_tests(text)
    character(len=*), intent(in) :: text
    type(model_t) :: model
    type(error_t) :: err
    type(dynamics_t) :: dyn, dyn2
    if (len(text) > 0) then
      call model_from_text(text // "&node label = 'lonely', x = 2.0, y = 1.0 /" // NL, &
        'free node', model, err)
      call expect_error(err, ERR_MODEL, [character(len=20) :: "'lonely'", 'free'], &
        'error: a free node that no element uses')
      call model_from_text(text // "&truss label = 'extra', from = 'base', to = 'tip', " // &
        "E = 1.0e9, A = 1.0e-6 /" // NL, 'extra truss', model, err)
      call expect_error(err, ERR_MODEL, [character(len=20) :: 'do not solve', &
        'over-constrained', '20 free'], 'error: one dynamic mode too many')
      call model_from_text(replaced(text, "mode = 'prescribed', motion = 'phi1'", &
        "mode = 'released'"), 'released joint', model, err)
      call expect_error(err, ERR_MODEL, [character(len=20) :: 'do not solve', 'mechanism'], &
        'error: a released joint makes a mechanism')
    end if
    ! Counts that match but a singular Jacobian: C between A and B on a straight line.
    call model_from_text( &
      "&node label = 'A', x = 0.0, y = 0.0, fixed = .true. /" // NL // &
      "&node label = 'C', x = 0.5, y = 0.0 /" // NL // &
      "&node label = 'B', x = 1.0, y = 0.0, fixed = .true. /" // NL // &
      "&truss label = 'ac', from = 'A', to = 'C', E = 1.0e9, A = 1.0e-6 /" // NL // &
      "&truss label = 'cb', from = 'C', to = 'B', E = 1.0e9, A = 1.0e-6 /" // NL // &
      "&mass node = 'C', m = 1.0 /" // NL, 'collinear', model, err)
    call expect_ok(err, 'collinear trusses: counts solve')
    if (.not. err%ok()) return
    call dyn%init(model, 0.0_wp, [0.0_wp, 0.0_wp], err)
    call expect_error(err, ERR_MODEL, [character(len=30) :: 'singular', "node 'C' y"], &
      'error: collinear trusses leave C y undetermined')
    ! A dynamic mode without inertia: massless trusses, no point mass.
    call model_from_text( &
      "&node label = 'A', x = 0.0, y = 0.0, fixed = .true. /" // NL // &
      "&node label = 'C', x = 0.5, y = 0.4 /" // NL // &
      "&node label = 'B', x = 1.0, y = 0.0, fixed = .true. /" // NL // &
      "&truss label = 'ac', from = 'A', to = 'C', E = 1.0e9, A = 1.0e-6 /" // NL // &
      "&truss label = 'cb', from = 'C', to = 'B', E = 1.0e9, A = 1.0e-6 /" // NL, &
      'massless', model, err)
    call expect_ok(err, 'massless trusses: counts solve')
    if (.not. err%ok()) return
    call dyn2%init(model, 0.0_wp, [0.0_wp, 0.0_wp], err)
    call expect_error(err, ERR_MODEL, [character(len=30) :: 'mass matrix is singular', &
      "'ac'"], 'error: a dynamic mode without inertia')
  end subroutine error_tests

  !> A model regular where it starts that comes close to singular along a motion: C above the
  !> line A-B, the trusses' elongations dynamic. Lengths 0.5 each put C on the line (J_c
  !> singular, as in the collinear model above). Solved with C 1e-5 above it, ||J_c^-1|| has
  !> grown about l / (2 y) = 2.5e4 times (the hint's threshold: 1e3), and the kinematics names
  !> a singular configuration; a solve beyond (shorter trusses: C cannot reach) fails as a
  !> numerical failure that says so, not as a model error.
  subroutine singular_configuration_tests()
    type(model_t) :: model
    type(error_t) :: err
    type(kinematics_t) :: kin
    real(wp) :: l0, y
    call model_from_text( &
      "&node label = 'A', x = 0.0, y = 0.0, fixed = .true. /" // NL // &
      "&node label = 'C', x = 0.5, y = 0.4 /" // NL // &
      "&node label = 'B', x = 1.0, y = 0.0, fixed = .true. /" // NL // &
      "&truss label = 'ac', from = 'A', to = 'C', E = 1.0e9, A = 1.0e-6 /" // NL // &
      "&truss label = 'cb', from = 'C', to = 'B', E = 1.0e9, A = 1.0e-6 /" // NL // &
      "&mass node = 'C', m = 1.0 /" // NL, 'lowered', model, err)
    call expect_ok(err, 'lowered node: build')
    if (.not. err%ok()) return
    l0 = sqrt(0.25_wp + 0.16_wp)
    call kin%init(model)
    call kin%solve(model, [0.0_wp, 0.0_wp], err)
    call expect_ok(err, 'lowered node: solved where it starts')
    call ts%check(kin%configuration_hint(model) == '', 'lowered node: no hint where it starts')
    y = 1.0e-5_wp
    call solve_path(kin, model, spread(sqrt(0.25_wp + y**2) - l0, 1, 2), err)
    call expect_ok(err, 'lowered node: solved 1e-5 above the line')
    call ts%check(index(kin%configuration_hint(model), 'singular configuration') > 0, &
      'lowered node: the hint names a singular configuration near the line')
    call kin%solve(model, spread(0.499_wp - l0, 1, 2), err)
    call expect_error(err, ERR_NUMERIC, [character(len=30) :: 'nearly singular', &
      'singular configuration'], 'lowered node: beyond the line, a numerical failure')
  end subroutine singular_configuration_tests

  !> No hint far from a singular configuration: input/two_link_spatial.nml with both joints
  !> turned 0.3 rad. The pivot ratio of its blocked factors (the measure the hint first used)
  !> falls from 0.36 at the reference to 8e-7 as soon as the joints turn (measured along its
  !> run); ||J_c^-1|| stays as it was.
  subroutine regular_spatial_configuration()
    type(nml_file_t) :: f
    type(scene_t) :: scene
    type(dynamics_t) :: dyn
    type(error_t) :: err
    real(wp), allocatable :: q(:)
    call f%load(source_dir() // '/input/two_link_spatial.nml', err)
    if (err%ok()) call make_dynamics_from(f, scene, dyn, err)
    call expect_ok(err, 'spatial two-link: built')
    if (.not. err%ok()) return
    allocate(q(dyn%model%n_q))
    q = 0.0_wp
    q(1:dyn%model%n_rh) = 0.3_wp
    call dyn%kin%solve(dyn%model, q, err)
    call expect_ok(err, 'spatial two-link: solved with the joints turned')
    call ts%check(dyn%kin%configuration_hint(dyn%model) == '', &
      'spatial two-link: no singular configuration named where there is none')
  end subroutine regular_spatial_configuration
end program test_kinematics
