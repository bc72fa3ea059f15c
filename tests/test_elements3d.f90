!> Spatial elements (docs/theory.md section 2.6): Euler-parameter utilities, the
!> spatial beam in both bending forms (angle, sine) and the Euler normalisation element.
!>
!>   - R(lambda) orthogonal with det 1, rotation vector -> lambda -> R = Rodrigues, matrix ->
!>     lambda, quaternion product, d(R a)/dlambda and d2(R a) against central FD;
!>   - beam: e against closed forms built from Rodrigues matrices, de against central FD,
!>     second against a 5-point FD and the polarised Hessian against FD of de, on deformed
!>     states with large rigid rotations and nodal deformation rotations up to ~2 rad;
!>   - rigid-body invariance (rotation composed into both lambdas, translation), e = 0
!>     undeformed; linear limit B^T S B = textbook 12x12 Euler-Bernoulli / Timoshenko frame
!>     stiffness for a general orientation, P Hess(e1_bar) = textbook geometric stiffness;
!>   - pure twist, and bending without twist (rotation-minimising frames along cubic
!>     centrelines): e2_bar = O(eps^4), which fixes the sign of the torsion correction.
!> Achieved errors are printed with every check and the worst per category at the end.
program test_elements3d
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use core_kinds, only: wp
  use core_error, only: error_t
  use testing, only: suite_t
  use beam3d_fixture, only: make_beam3d, beam3d_state, space_frame
  use fd_helpers, only: lcg_t, relerr, flat, random_rotvec
  use element_fd, only: modes, jacobian, second, fd_jacobian, fd_second, fd_hessian, &
    polar_hessian
  use elements_base, only: element_t, MODE_RIGID
  use elements_rotation, only: rot_matrix, rot_apply, rot_apply_jac, rot_apply_second, &
    rotvec_to_euler, euler_to_matrix, matrix_to_euler, euler_product, skew
  use elements_beam3d, only: beam3d_t, BENDING_ANGLE, BENDING_SINE, beam3d_set_geometry
  use elements_euler, only: euler_norm_t
  implicit none

  real(wp), parameter :: PI = 3.14159265358979323846_wp, EPS = epsilon(1.0_wp)
  !> The 2 x 2 stiffness pattern of a bar (axial, torsion) per unit stiffness.
  real(wp), parameter :: BAR(2, 2) = reshape([1.0_wp, -1.0_wp, -1.0_wp, 1.0_wp], [2, 2])
  integer, parameter :: C_ROT = 1, C_E = 2, C_DE = 3, C_D2FD = 4, C_POL = 5, C_INV = 6, &
    C_K = 7, C_KG = 8, C_TW = 9, N_CAT = 9
  character(len=44), parameter :: CAT_NAME(N_CAT) = [character(len=44) :: &
    'rotation utilities vs closed forms / FD', 'e vs closed form', 'de vs central FD of e', &
    'second vs 5-point FD d2/ds2 e(x+sv)', 'Hessian by polarisation vs FD Hessian', &
    'rigid-body invariance of e', 'B^T S B vs textbook 12x12 stiffness', &
    'P Hess(e1_bar) vs textbook Kg', 'pure twist / bending without twist']
  type(lcg_t) :: rng = lcg_t(seed=20251125)
  type(suite_t) :: ts

  call ts%init('elements3d')
  call rotation_tests()
  call beam_tests(BENDING_ANGLE, 'angle')
  call beam_tests(BENDING_SINE, 'sine')
  call linear_limit()
  call twist_tests(BENDING_ANGLE, 'angle')
  call twist_tests(BENDING_SINE, 'sine')
  call misc_tests()
  call ts%print_worst(CAT_NAME)
  call ts%finish()

contains

  pure function rodrigues(phi) result(r)
    real(wp), intent(in) :: phi(3)
    real(wp) :: r(3, 3), t, k(3, 3)
    integer :: j
    t = norm2(phi)
    r = 0.0_wp
    do j = 1, 3
      r(j, j) = 1.0_wp
    end do
    if (t == 0) return
    k = skew(phi / t)
    r = r + sin(t) * k + (1 - cos(t)) * matmul(k, k)
  end function rodrigues

  !> The smallest rotation turning unit a onto unit b.
  pure function min_rotation(a, b) result(r)
    real(wp), intent(in) :: a(3), b(3)
    real(wp) :: r(3, 3), c(3)
    c = [a(2) * b(3) - a(3) * b(2), a(3) * b(1) - a(1) * b(3), a(1) * b(2) - a(2) * b(1)]
    r = rodrigues(c / max(norm2(c), tiny(1.0_wp)) * atan2(norm2(c), dot_product(a, b)))
  end function min_rotation

  ! ------------------------------------------------------------------ FD machinery

  !> de, second and the Hessian at x against FD. Steps: central differences at h = 1e-6 and
  !> a 5-point rule at s = 2e-3 are near their truncation/round-off balance for O(1) modes.
  subroutine check_derivatives(el, x, v, what, floor_d2)
    class(element_t), intent(in) :: el
    real(wp), intent(in) :: x(:), v(:), floor_d2
    character(len=*), intent(in) :: what
    real(wp), allocatable :: d2(:)
    real(wp) :: err
    integer :: m
    call ts%expect(what // ' de', relerr(flat(jacobian(el, x)), flat(fd_jacobian(el, x, 1.0e-6_wp)), &
      1.0_wp), 1.0e-8_wp, C_DE)
    d2 = second(el, x, v)
    call ts%expect(what // ' second vs FD d2/ds2', relerr(d2, fd_second(el, x, v, 2.0e-3_wp), &
      floor_d2), 1.0e-7_wp, C_D2FD)
    err = 0.0_wp
    do m = 1, el%n_modes()
      err = max(err, relerr(flat(polar_hessian(el, x, m)), flat(fd_hessian(el, x, m, &
        1.0e-5_wp)), floor_d2 / dot_product(v, v)))
    end do
    call ts%expect(what // ' Hessian (polarised second) vs FD, all modes', err, 1.0e-7_wp, C_POL)
  end subroutine check_derivatives

  ! ------------------------------------------------------------------ rotations

  subroutine rotation_tests()
    real(wp) :: lam(4), p(4), r(3, 3), a(3), mu(4), jfd(3, 4), d2fd(3), phi(3), err(7), id(3, 3)
    real(wp) :: det, h, s, nl
    integer :: k, j
    err = 0.0_wp
    id = rodrigues([0.0_wp, 0.0_wp, 0.0_wp])
    do k = 1, 50
      lam = rng%uniform_vec(4, -1.0_wp, 1.0_wp)
      lam = lam / norm2(lam)
      r = rot_matrix(lam)
      det = r(1, 1) * (r(2, 2) * r(3, 3) - r(2, 3) * r(3, 2)) - r(1, 2) * (r(2, 1) * r(3, 3) &
        - r(2, 3) * r(3, 1)) + r(1, 3) * (r(2, 1) * r(3, 2) - r(2, 2) * r(3, 1))
      err(1) = max(err(1), maxval(abs(matmul(transpose(r), r) - id)), abs(det - 1))
      ! Every fifth angle is tiny (series branch), every fifth near the switch at 1e-3.
      phi = random_rotvec(rng, 3.0_wp)
      if (mod(k, 5) == 1) phi = phi * 1.0e-5_wp
      if (mod(k, 5) == 2) phi = phi / norm2(phi) * 1.0e-3_wp * (1 + (k - 25) * 1.0e-3_wp)
      err(2) = max(err(2), maxval(abs(euler_to_matrix(rotvec_to_euler(phi)) - rodrigues(phi))))
      err(3) = max(err(3), abs(norm2(rotvec_to_euler(phi)) - 1))
      p = matrix_to_euler(rot_matrix(lam))
      err(4) = max(err(4), min(maxval(abs(p - lam)), maxval(abs(p + lam))))
      p = rotvec_to_euler(random_rotvec(rng, 3.0_wp))
      err(5) = max(err(5), maxval(abs(rot_matrix(euler_product(p, lam)) &
        - matmul(rot_matrix(p), rot_matrix(lam)))))
      ! Derivatives at a non-unit lambda: R a is a quadratic polynomial in all of R^4.
      nl = rng%uniform(0.7_wp, 1.3_wp)
      lam = nl * lam
      a = rng%uniform_vec(3, -1.0_wp, 1.0_wp)
      mu = rng%uniform_vec(4, -1.0_wp, 1.0_wp)
      h = 1.0e-4_wp
      do j = 1, 4
        p = 0.0_wp
        p(j) = h
        jfd(:, j) = (rot_apply(lam + p, a) - rot_apply(lam - p, a)) / (2 * h)
      end do
      err(6) = max(err(6), maxval(abs(rot_apply_jac(lam, a) - jfd)) / (nl * norm2(a)))
      s = 1.0e-2_wp
      d2fd = (-rot_apply(lam + 2 * s * mu, a) + 16 * rot_apply(lam + s * mu, a) &
        - 30 * rot_apply(lam, a) + 16 * rot_apply(lam - s * mu, a) &
        - rot_apply(lam - 2 * s * mu, a)) / (12 * s**2)
      err(7) = max(err(7), maxval(abs(rot_apply_second(mu, a) - d2fd)) / (nl**2 * norm2(a)))
    end do
    ! Closed forms: a few roundings of O(1) terms, 50 eps bounds (observed < 10 eps).
    call ts%expect('R(unit lambda): |R^T R - I|, |det R - 1|', err(1), 50 * EPS, C_ROT)
    call ts%expect('rotation vector -> lambda -> R = Rodrigues', err(2), 50 * EPS, C_ROT)
    call ts%expect('rotation vector -> lambda is unit', err(3), 50 * EPS, C_ROT)
    call ts%expect('matrix -> lambda = +-lambda', err(4), 50 * EPS, C_ROT)
    call ts%expect('R(p q) = R(p) R(q)', err(5), 50 * EPS, C_ROT)
    ! Polynomials of degree 2: central differences are exact up to round-off ~ eps |Ra| / h
    ! and eps |Ra| / s^2 (16 terms of the 5-point rule): bounds 100 eps / h, 300 eps / s^2.
    call ts%expect('d(R a)/dlambda vs central FD', err(6), 100 * EPS / 1.0e-4_wp, C_ROT)
    call ts%expect('d2(R a) along mu vs 5-point FD', err(7), 300 * EPS / 1.0e-2_wp**2, C_ROT)
  end subroutine rotation_tests

  ! ------------------------------------------------------------------ beam

  !> e_bar from Rodrigues matrices (nodal rotation R_rig R(th_k)), independent of the element.
  function beam_expected(b, x, rig, thp, thq) result(e)
    type(beam3d_t), intent(in) :: b
    real(wp), intent(in) :: x(14), rig(3), thp(3), thq(3)
    real(wp) :: e(6), el(3), ax(3, 3, 2), c(3), sn, f
    integer :: k
    el = (x(8:10) - x(1:3)) / norm2(x(8:10) - x(1:3))
    do k = 1, 2
      if (k == 1) ax(:, :, k) = matmul(rodrigues(rig), rodrigues(thp))
      if (k == 2) ax(:, :, k) = matmul(rodrigues(rig), rodrigues(thq))
      ax(:, :, k) = matmul(ax(:, :, k), reshape([b%ex0, b%ey0, b%ez0], [3, 3]))
      c = matmul(el, ax(:, :, k))
      f = 1.0_wp
      sn = norm2(c(2:3))
      if (b%bending == BENDING_ANGLE .and. sn > 0) f = atan2(sn, c(1)) / sn
      e(2 + k) = (2 * k - 3) * b%l0 * c(3) * f
      e(4 + k) = (3 - 2 * k) * b%l0 * c(2) * f
    end do
    e(1) = norm2(x(8:10) - x(1:3)) - b%l0 + (2 * e(3)**2 + e(3) * e(4) + 2 * e(4)**2 &
      + 2 * e(5)**2 + e(5) * e(6) + 2 * e(6)**2) / (30 * b%l0)
    ! Twist: sine form l0 S / 2, angle form (l0 / 2) atan2(S, C) |(S, C)| (S, C of the
    ! section axes).
    e(2) = dot_product(ax(:, 3, 1), ax(:, 2, 2)) - dot_product(ax(:, 2, 1), ax(:, 3, 2))
    if (b%bending == BENDING_ANGLE) then
      c(1) = dot_product(ax(:, 2, 1), ax(:, 2, 2)) + dot_product(ax(:, 3, 1), ax(:, 3, 2))
      e(2) = b%l0 / 2 * atan2(e(2), c(1)) * hypot(e(2), c(1))
    else
      e(2) = b%l0 / 2 * e(2)
    end if
    e(2) = e(2) - (e(3) * e(6) - e(4) * e(5)) / b%l0
  end function beam_expected

  subroutine beam_tests(form, fname)
    integer, intent(in) :: form
    character(len=*), intent(in) :: fname
    integer, parameter :: N_CFG = 7
    type(beam3d_t) :: b
    real(wp) :: x(14), v(14), y(14), rig(3), tilt(3), thp(3), thq(3), xp(3), l, sig(4), d(3)
    real(wp) :: e(6), x0(14)
    character(len=40) :: what
    integer :: k
    b = make_beam3d(form, 0.8_wp, [0.6_wp, -0.3_wp, 0.74_wp], [0.2_wp, 0.9_wp, -0.1_wp], ts)
    do k = 1, N_CFG
      write(what, '(a,a,a,i0)') 'beam3d/', fname, ' cfg ', k
      xp = rng%uniform_vec(3, -2.0_wp, 2.0_wp)
      rig = random_rotvec(rng, PI)
      l = b%l0 * rng%uniform(0.9_wp, 1.1_wp)
      tilt = random_rotvec(rng, 0.4_wp)
      thp = random_rotvec(rng, 1.0_wp)
      thq = random_rotvec(rng, 1.0_wp)
      ! Pure bending by 1 rad per node in a plane at 0.7 rad to the section axes; then
      ! tangent rotations past 90 degrees (angle form: closed-form branch with cx < 0).
      if (k == 1) then
        tilt = 0.0_wp
        thp = -1.0_wp * (cos(0.7_wp) * b%ey0 + sin(0.7_wp) * b%ez0)
        thq = -thp
      end if
      if (k == 2) thp = thp / norm2(thp) * 1.9_wp
      ! Small bending (angle form: series branch of alpha / s only).
      if (k == 3) then
        tilt = 0.1_wp * tilt; thp = 0.1_wp * thp; thq = 0.1_wp * thq
      end if
      ! Tangent-chord angles either side of atan(1/2), where the angle form switches from the
      ! series to the closed form: FD steps straddle the switch.
      if (k == 4) then
        tilt = 0.0_wp
        thp = -atan(0.5_wp) * (1 + 1.0e-7_wp) * (cos(0.3_wp) * b%ey0 + sin(0.3_wp) * b%ez0)
        thq = atan(0.5_wp) * (1 - 1.0e-7_wp) * (cos(1.1_wp) * b%ey0 + sin(1.1_wp) * b%ez0)
      end if
      x = beam3d_state(b, xp, rig, l, tilt, thp, thq)
      e = modes(b, x)
      call ts%expect(trim(what) // ' e vs closed form', relerr(e, beam_expected(b, x, rig, thp, &
        thq), b%l0), 1.0e-13_wp, C_E)
      v = rng%uniform_vec(14, -1.0_wp, 1.0_wp)
      call check_derivatives(b, x, v, trim(what), 1.0e-2_wp * b%l0 * dot_product(v, v))
      ! Rigid motion: positions rotated by sig about the origin and translated, sig composed
      ! in front of both nodal rotations.
      sig = rotvec_to_euler(random_rotvec(rng, PI))
      d = rng%uniform_vec(3, -3.0_wp, 3.0_wp)
      y = x
      y(1:3) = rot_apply(sig, x(1:3)) + d
      y(8:10) = rot_apply(sig, x(8:10)) + d
      y(4:7) = euler_product(sig, x(4:7))
      y(11:14) = euler_product(sig, x(11:14))
      call ts%expect(trim(what) // ' e invariant under rigid motion', relerr(modes(b, y), e, &
        b%l0), 1.0e-13_wp, C_INV)
    end do
    ! A non-unit lambda: the derivatives hold for the homogeneous form off the unit sphere.
    x(4:7) = 1.07_wp * x(4:7)
    x(11:14) = 0.95_wp * x(11:14)
    call check_derivatives(b, x, v, 'beam3d/' // fname // ' non-unit lambda', &
      1.0e-2_wp * b%l0 * dot_product(v, v))
    ! e = 0 undeformed, for any rigid placement of it.
    x0 = beam3d_state(b, [0.3_wp, -0.2_wp, 0.5_wp], [0.0_wp, 0.0_wp, 0.0_wp], b%l0, &
      [0.0_wp, 0.0_wp, 0.0_wp], [0.0_wp, 0.0_wp, 0.0_wp], [0.0_wp, 0.0_wp, 0.0_wp])
    do k = 1, 3
      sig = rotvec_to_euler(random_rotvec(rng, PI))
      d = rng%uniform_vec(3, -3.0_wp, 3.0_wp)
      y = x0
      y(1:3) = rot_apply(sig, x0(1:3)) + d
      y(8:10) = rot_apply(sig, x0(8:10)) + d
      y(4:7) = sig
      y(11:14) = sig
      ! Roundings of positions up to |x| ~ 5 in l and e_l: a few eps |x| / l0 ~ 1e-15.
      call ts%expect('beam3d/' // fname // ' e = 0 undeformed, rigidly placed', &
        maxval(abs(modes(b, y))) / b%l0, 5.0e-14_wp, C_INV)
    end do
  end subroutine beam_tests

  ! ------------------------------------------------------------------ linear limit

  !> Textbook planar bending stiffness on (v1, theta1, v2, theta2), theta = dv/dx; P = 0:
  !> Euler-Bernoulli, else Timoshenko with P = 12 EI / (k G A L^2).
  pure function planar_k(ei, l, p) result(k)
    real(wp), intent(in) :: ei, l, p
    real(wp) :: k(4, 4)
    k = ei / (l**3 * (1 + p)) * reshape([12 * l**0, 6 * l, -12 * l**0, 6 * l, &
      6 * l, (4 + p) * l**2, -6 * l, (2 - p) * l**2, -12 * l**0, -6 * l, 12 * l**0, -6 * l, &
      6 * l, (2 - p) * l**2, -6 * l, (4 + p) * l**2], [4, 4])
  end function planar_k

  !> Textbook planar consistent geometric stiffness for an axial force pa.
  pure function planar_kg(pa, l) result(k)
    real(wp), intent(in) :: pa, l
    real(wp) :: k(4, 4)
    k = pa / (30 * l) * reshape([36 * l**0, 3 * l, -36 * l**0, 3 * l, 3 * l, 4 * l**2, &
      -3 * l, -l**2, -36 * l**0, -3 * l, 36 * l**0, -3 * l, 3 * l, -l**2, -3 * l, 4 * l**2], [4, 4])
  end function planar_kg

  !> x(w) at the undeformed state x0 for w = (u_p, theta_p, u_q, theta_q), exact rotation map.
  function frame_coords(x0, w) result(x)
    real(wp), intent(in) :: x0(14), w(12)
    real(wp) :: x(14)
    x(1:3) = x0(1:3) + w(1:3)
    x(4:7) = rotvec_to_euler(w(4:6))
    x(8:10) = x0(8:10) + w(7:9)
    x(11:14) = rotvec_to_euler(w(10:12))
  end function frame_coords

  subroutine linear_limit()
    real(wp), parameter :: pforce = -1234.5_wp, shears(2) = [0.37_wp, 0.21_wp]
    type(beam3d_t) :: b
    real(wp) :: x0(14), jm(14, 12), t(12, 12), lam3(3, 3), s(6, 6), bm(6, 12), bs(6, 12)
    real(wp) :: k(12, 12), kref(12, 12), hx(14, 14), kg(12, 12), kgfd(12, 12), w(12), h, e1
    real(wp) :: de(6, 14), py, pz, fpp, fpm, fmp, fmm
    integer :: form, ishear, i, j
    character(len=60) :: what
    jm = 0.0_wp
    do i = 1, 3
      jm(i, i) = 1; jm(4 + i, 3 + i) = 0.5_wp; jm(7 + i, 6 + i) = 1; jm(11 + i, 9 + i) = 0.5_wp
    end do
    do form = BENDING_ANGLE, BENDING_SINE
      do ishear = 0, 1
        b = make_beam3d(form, 0.65_wp, [-0.4_wp, 0.8_wp, 0.45_wp], [0.7_wp, 0.1_wp, 0.5_wp], ts)
        py = ishear * shears(1); pz = ishear * shears(2)
        b%shear_xz = py; b%shear_xy = pz
        write(what, '(a,i0,a,f4.2,a,f4.2)') 'beam3d form ', form, ' shear xz ', py, ' xy ', pz
        lam3 = transpose(reshape([b%ex0, b%ey0, b%ez0], [3, 3]))
        t = 0.0_wp
        do i = 0, 3
          t(3 * i + 1:3 * i + 3, 3 * i + 1:3 * i + 3) = lam3
        end do
        x0 = frame_coords(beam3d_state(b, [0.1_wp, 0.2_wp, -0.3_wp], [0.0_wp, 0.0_wp, 0.0_wp], &
          b%l0, [0.0_wp, 0.0_wp, 0.0_wp], [0.0_wp, 0.0_wp, 0.0_wp], [0.0_wp, 0.0_wp, 0.0_wp]), &
          [(0.0_wp, i=1, 12)])
        de = jacobian(b, x0)
        bm = matmul(de, jm)
        call b%stiffness(s)
        k = matmul(transpose(bm), matmul(s, bm))
        kref = space_frame(b%ea / b%l0 * BAR, b%gj / b%l0 * BAR, planar_k(b%ei_z, b%l0, pz), &
          planar_k(b%ei_y, b%l0, py))
        kref = matmul(transpose(t), matmul(kref, t))
        ! Products of O(1) direction cosines: a few eps of the largest entry; bound 1e-13.
        call ts%expect(trim(what) // ' B^T S B = textbook 12x12', relerr(flat(k), flat(kref), &
          1.0_wp), 1.0e-13_wp, C_K)
        if (form == BENDING_ANGLE) bs = bm
        if (form == BENDING_SINE) call ts%expect(trim(what) // ' B(angle) = B(sine)', &
          relerr(flat(bm), flat(bs), 1.0_wp), 1.0e-14_wp, C_K)
        if (ishear == 1) cycle
        ! P Hess(e1_bar) in (u, theta): J^T H_x J plus de1/dlambda0 d2lambda0/dtheta2 = -I/4
        ! (lambda0 = cos(|theta|/2)); that term vanishes here (de1 = 0 on lambda).
        hx = polar_hessian(b, x0, 1)
        kg = matmul(transpose(jm), matmul(hx, jm))
        kg(4:6, 4:6) = kg(4:6, 4:6) - de(1, 4) / 4 * reshape([1, 0, 0, 0, 1, 0, 0, 0, 1], [3, 3])
        kg(10:12, 10:12) = kg(10:12, 10:12) - de(1, 11) / 4 * reshape([1, 0, 0, 0, 1, 0, 0, 0, &
          1], [3, 3])
        kg = pforce * kg
        ! The textbook torsion entries P Ip / (A L) are absent: e1_bar is the elongation of the
        ! beam axis, and the lengthening of off-axis fibres by twist (Wagner) is not a mode.
        kref = space_frame(0 * BAR, 0 * BAR, planar_kg(pforce, b%l0), planar_kg(pforce, b%l0))
        kref = matmul(transpose(t), matmul(kref, t))
        call ts%expect(trim(what) // ' P Hess(e1_bar) = textbook Kg (bending part)', &
          relerr(flat(kg), flat(kref), 1.0_wp), 1.0e-13_wp, C_KG)
        ! Independent of the chain rule: second differences of e1_bar(x(w)) through the exact
        ! rotation map, h = 1e-4: truncation ~h^2, round-off ~eps l0 / h^2 ~ 1e-8 relative.
        h = 1.0e-4_wp
        e1 = 0.0_wp
        do j = 1, 12
          do i = 1, 12
            w = 0.0_wp; w(i) = h; w(j) = w(j) + h
            fpp = modes_at(b, frame_coords(x0, w))
            w = 0.0_wp; w(i) = h; w(j) = w(j) - h
            fpm = modes_at(b, frame_coords(x0, w))
            w = 0.0_wp; w(i) = -h; w(j) = w(j) + h
            fmp = modes_at(b, frame_coords(x0, w))
            w = 0.0_wp; w(i) = -h; w(j) = w(j) - h
            fmm = modes_at(b, frame_coords(x0, w))
            kgfd(i, j) = pforce * (fpp - fpm - fmp + fmm) / (4 * h**2)
          end do
        end do
        call ts%expect(trim(what) // ' FD Hessian of P e1_bar(x(u, theta)) = textbook Kg', &
          relerr(flat(kgfd), flat(kref), 1.0_wp), 1.0e-6_wp, C_KG)
      end do
    end do
  end subroutine linear_limit

  real(wp) function modes_at(b, x) result(e1)
    type(beam3d_t), intent(in) :: b
    real(wp), intent(in) :: x(14)
    real(wp) :: e(6)
    e = modes(b, x)
    e1 = e(1)
  end function modes_at

  ! ------------------------------------------------------------------ twist

  !> A state bent without twist: centreline r(s) = p0 + A (s, v(s), w(s)), A = [ex0 ey0 ez0],
  !> (v, w) cubic Hermite with end slopes sp, sq and end offsets dq (v(0) = w(0) = 0); the
  !> section frames are carried along it by minimal rotations (no rotation about the tangent).
  function bishop_state(b, sp, sq, dq) result(x)
    type(beam3d_t), intent(in) :: b
    real(wp), intent(in) :: sp(2), sq(2), dq(2)
    integer, parameter :: N_STEP = 4000
    real(wp) :: x(14), a(3, 3), f(3, 3), t0(3), t1(3)
    integer :: k
    a = reshape([b%ex0, b%ey0, b%ez0], [3, 3])
    t0 = hermite_tangent(b%l0, sp, sq, dq, 0.0_wp)
    f = min_rotation([1.0_wp, 0.0_wp, 0.0_wp], t0)
    x(1:3) = [0.3_wp, -0.2_wp, 0.5_wp]
    x(4:7) = matrix_to_euler(matmul(a, matmul(f, transpose(a))))
    do k = 1, N_STEP
      t1 = hermite_tangent(b%l0, sp, sq, dq, real(k, wp) / N_STEP)
      f = matmul(min_rotation(t0, t1), f)
      t0 = t1
    end do
    x(8:10) = x(1:3) + matmul(a, [b%l0, dq])
    x(11:14) = matrix_to_euler(matmul(a, matmul(f, transpose(a))))
  end function bishop_state

  !> Unit tangent of that centreline at s = xi l0 (local axes).
  pure function hermite_tangent(l0, sp, sq, dq, xi) result(tv)
    real(wp), intent(in) :: l0, sp(2), sq(2), dq(2), xi
    real(wp) :: tv(3)
    tv(1) = 1.0_wp
    tv(2:3) = dq * (6 * xi - 6 * xi**2) / l0 + sp * (1 - 4 * xi + 3 * xi**2) &
      + sq * (3 * xi**2 - 2 * xi)
    tv = tv / norm2(tv)
  end function hermite_tangent

  subroutine twist_tests(form, fname)
    integer, intent(in) :: form
    character(len=*), intent(in) :: fname
    type(beam3d_t) :: b
    real(wp) :: x(14), e(6), phi, sig(4), eb(3), ealt(3), eps_b
    real(wp) :: sp(2), sq(2), dq(2), beta
    integer :: k, icase
    character(len=100) :: what
    b = make_beam3d(form, 0.8_wp, [0.3_wp, 0.5_wp, -0.8_wp], [1.0_wp, 0.2_wp, 0.4_wp], ts)
    ! Equal and opposite rotations about the chord, rigidly rotated: e2 = l0 phi (angle form)
    ! or l0 sin(phi) (sine form) exactly.
    do k = 1, 2
      phi = 1.0e-3_wp
      if (k == 2) phi = 0.9_wp
      x = beam3d_state(b, [0.1_wp, 0.0_wp, 0.2_wp], [0.0_wp, 0.0_wp, 0.0_wp], b%l0, &
        [0.0_wp, 0.0_wp, 0.0_wp], -phi / 2 * b%ex0, phi / 2 * b%ex0)
      sig = rotvec_to_euler([1.2_wp, -0.8_wp, 2.0_wp])
      x(1:3) = rot_apply(sig, x(1:3)); x(8:10) = rot_apply(sig, x(8:10))
      x(4:7) = euler_product(sig, x(4:7)); x(11:14) = euler_product(sig, x(11:14))
      e = modes(b, x)
      write(what, '(a,a,a,es8.1)') 'beam3d/', fname, ' pure twist phi ', phi
      if (form == BENDING_ANGLE) then
        call ts%expect(trim(what) // ': e2 = l0 phi', abs(e(2) - b%l0 * phi) / b%l0, &
          1.0e-14_wp, C_TW)
      else
        call ts%expect(trim(what) // ': e2 = l0 sin(phi)', abs(e(2) - b%l0 * sin(phi)) / &
          b%l0, 1.0e-14_wp, C_TW)
      end if
      call ts%expect(trim(what) // ': e1, e3..e6 = 0', maxval(abs(e([1, 3, 4, 5, 6]))) / b%l0, &
        1.0e-14_wp, C_TW)
      ! First order: e2 / (l0 phi) - 1 = -phi^2/6 + ... (sine); bound 2 phi^2 (12x).
      if (k == 1) call ts%expect(trim(what) // ': e2 = l0 phi to first order', &
        abs(e(2) / (b%l0 * phi) - 1), 2 * phi**2, C_TW)
    end do
    ! Bending without twist, e2_bar at eps, eps/2, eps/4. e2_bar is even in eps (eps -> -eps
    ! is a half turn about the chord), so vanishing to second order means O(eps^4); the
    ! other sign of the correction leaves an O(eps^2) e2_bar.
    do icase = 1, 3
      beta = 0.6_wp
      select case (icase)
      case (1)   ! both ends rotated, non-planar
        sp = [0.7_wp, 0.2_wp]; sq = [-0.3_wp, 0.9_wp]; dq = 0.0_wp
      case (2)   ! cantilever: tip force in the x-y plane, tip moment in the x-z plane
        sp = 0.0_wp; sq = [1.0_wp, 0.8_wp]; dq = [2 * b%l0 / 3, 0.4_wp * b%l0]
      case default   ! planar in a plane at beta to the section axes
        sp = 0.6_wp * [cos(beta), sin(beta)]; sq = -0.4_wp * [cos(beta), sin(beta)]
        dq = 0.1_wp * b%l0 * [cos(beta), sin(beta)]
      end select
      do k = 1, 3
        eps_b = 0.1_wp / 2**(k - 1)
        e = modes(b, bishop_state(b, eps_b * sp, eps_b * sq, eps_b * dq))
        eb(k) = abs(e(2))
        ealt(k) = abs(e(2) + 2 * (e(3) * e(6) - e(4) * e(5)) / b%l0)
      end do
      write(what, '(a,a,a,i0,a,3es10.2)') 'beam3d/', fname, ' no twist case ', icase, &
        ' |e2_bar| ', eb
      if (icase < 3) then
        call ts%order(eb(2), eb(3), 4, trim(what) // ' order')
        write(what, '(a,a,a,i0,a,3es10.2)') 'beam3d/', fname, ' no twist case ', icase, &
          ' other sign ', ealt
        call ts%order(ealt(2), ealt(3), 2, trim(what) // ' order')
      else
        ! Planar: e2 and the correction vanish identically; the transport's rounding remains.
        call ts%expect(trim(what) // ' = 0', maxval(eb) / b%l0, 1.0e-12_wp, C_TW)
      end if
    end do
  end subroutine twist_tests

  ! ------------------------------------------------------------------ misc

  subroutine misc_tests()
    type(beam3d_t) :: b
    type(euler_norm_t) :: en
    type(error_t) :: err
    real(wp) :: diag(14), lam(4), v(4), e(1)
    integer :: k
    call beam3d_set_geometry(b, [0.0_wp, 0.0_wp, 0.0_wp], [1.0_wp, 1.0_wp, 0.0_wp], &
      [2.0_wp, 2.0_wp + 1.0e-7_wp, 0.0_wp], err)
    call ts%check(.not. err%ok() .and. allocated(err%message), &
      'beam3d_set_geometry rejects an orientation nearly parallel to the chord')
    call beam3d_set_geometry(b, [0.0_wp, 0.0_wp, 0.0_wp], [0.0_wp, 0.0_wp, 0.0_wp], &
      [0.0_wp, 1.0_wp, 0.0_wp], err)
    call ts%check(.not. err%ok(), 'beam3d_set_geometry rejects coincident nodes')
    b = make_beam3d(BENDING_ANGLE, 0.9_wp, [1.0_wp, 2.0_wp, 3.0_wp], [0.0_wp, 0.0_wp, 1.0_wp], ts)
    ! Mass options in detail: tests/test_beam3d_mass.f90.
    b%consistent = .false.
    call b%lumped_mass(diag)
    call ts%check(all(diag([1, 2, 3, 8, 9, 10]) == b%rho_a * b%l0 / 2) .and. &
      all(diag([4, 5, 6, 7, 11, 12, 13, 14]) == 0), 'beam3d lumped: rhoA l0/2 per translation')
    call ts%check(b%has_inertia() .and. b%type_name() == 'beam3d' .and. &
      b%n_modes() == 6, 'beam3d: inertia, type name, 6 modes')
    ! Degenerate states (collapsed chord, lambda = 0) give finite numbers, not a trap.
    do k = BENDING_ANGLE, BENDING_SINE
      b%bending = k
      call ts%check(all(ieee_is_finite(collapsed(b))), 'beam3d: finite at l = 0 and lambda = 0')
    end do
    ! Euler normalisation: e = |lambda|^2 - 1 is quadratic, so FD are exact to round-off.
    en%label = 'euler'
    en%dofs = [1, 2, 3, 4]
    en%mode_class = [MODE_RIGID]
    call ts%check(en%type_name() == 'euler' .and. en%n_modes() == 1, 'euler: type name, 1 mode')
    do k = 1, 4
      lam = rng%uniform_vec(4, -1.0_wp, 1.0_wp)
      v = rng%uniform_vec(4, -1.0_wp, 1.0_wp)
      e = modes(en, lam)
      call ts%expect('euler e = |lambda|^2 - 1', abs(e(1) - (sum(lam**2) - 1)), 10 * EPS, C_E)
      ! Round-off only: eps |e| / h with h = 1e-6 and eps |e| / s^2 (5-point, s = 1e-2).
      call ts%expect('euler de vs FD', relerr(flat(jacobian(en, lam)), flat(fd_jacobian(en, lam, &
        1.0e-6_wp)), 1.0_wp), 100 * EPS / 1.0e-6_wp, C_DE)
      call ts%expect('euler second vs FD', relerr(second(en, lam, v), fd_second(en, lam, v, &
        1.0e-2_wp), 1.0_wp), 300 * EPS / 1.0e-4_wp, C_D2FD)
      e = modes(en, lam / norm2(lam))
      call ts%expect('euler e = 0 for unit lambda', abs(e(1)), 10 * EPS, C_INV)
    end do
  end subroutine misc_tests

  !> e, de and second at a state with both nodes at one point and lambda_q = 0.
  function collapsed(b) result(r)
    type(beam3d_t), intent(in) :: b
    real(wp) :: r(6 + 6 * 14 + 6), x(14), e(6), de(6, 14), d2(6)
    x = 0.0_wp
    x(4) = 1.0_wp
    call b%evaluate(x, e, de)
    call b%second(x, spread(1.0_wp, 1, 14), d2)
    r = [e, flat(de), d2]
  end function collapsed
end program test_elements3d
