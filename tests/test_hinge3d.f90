!> The spatial hinge (elements_hinge3d) at element level:
!>   - closed forms: e = 0 at the reference and for equal nodes; a pure twist a about the axis
!>     gives e = (a, 0, 0) for |a| up to 3 rad and beyond pi; a swing-twist rotation
!>     Rot(m, beta) Rot(n, phi) gives (phi, 2 tan(beta/2) m.t1, 2 tan(beta/2) m.t2); the same
!>     from rotation matrices alone (axis image and residual twist) for random relative
!>     rotations and non-unit Euler parameters;
!>   - small rotations about t1, t2 give e2, e3 equal to the angles to first order (error
!>     O(beta^3) without twist, O(|theta|^2) with it, observed order 2);
!>   - invariance under a common rotation of both nodes and under scaling of each lambda;
!>     a sign change of lambda_q shifts e1 by 2 pi and leaves e2, e3;
!>   - de against central FD, second against a 5-point FD, the Hessian by polarisation of
!>     second against FD of de, on random states (unit and non-unit lambda) with relative
!>     rotations up to 170 degrees; the linear limit at the reference; stiffness; set_axis.
!> Achieved errors are printed with every check and the worst per category at the end.
program test_hinge3d
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use core_kinds, only: wp
  use core_error, only: error_t
  use core_strings, only: real_str
  use testing, only: suite_t
  use fd_helpers, only: lcg_t, relerr, flat, random_rotvec
  use element_fd, only: modes, jacobian, second, expect_derivatives
  use elements_base, only: MODE_DYNAMIC, MODE_RIGID
  use elements_rotation, only: rotvec_to_euler, euler_to_matrix, euler_product, cross
  use elements_hinge3d, only: hinge3d_t, hinge3d_set_axis
  implicit none

  real(wp), parameter :: PI = 3.14159265358979323846_wp, EPS = epsilon(1.0_wp)
  real(wp), parameter :: ID4(4) = [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp]
  integer, parameter :: C_E = 1, C_SMALL = 2, C_INV = 3, C_DE = 4, C_D2 = 5, C_POL = 6, &
    C_LIN = 7, N_CAT = 7
  character(len=44), parameter :: CAT_NAME(N_CAT) = [character(len=44) :: &
    'e vs closed forms', 'small rotations: e vs angles', 'invariance of e', &
    'de vs central FD of e', 'second vs 5-point FD d2/ds2 e(x+sv)', &
    'Hessian by polarisation vs FD Hessian', 'linear limit at the reference']
  type(lcg_t) :: rng = lcg_t(seed=20260311)
  type(suite_t) :: ts
  type(hinge3d_t) :: hg

  call ts%init('hinge3d')
  hg = make_hinge([0.3_wp, -0.5_wp, 0.8_wp])
  call frame_tests()
  call closed_forms()
  call small_rotations()
  call invariance()
  call derivative_tests()
  call linear_limit()
  call ts%print_worst(CAT_NAME)
  call ts%finish()

contains

  !> A hinge about a general axis (frame from the axis alone), distinct stiffnesses.
  function make_hinge(axis) result(h)
    real(wp), intent(in) :: axis(3)
    type(hinge3d_t) :: h
    type(error_t) :: err
    integer :: k
    h%label = 'hinge3d'
    h%dofs = [(k, k=1, 8)]
    h%mode_class = [MODE_DYNAMIC, MODE_RIGID, MODE_RIGID]
    h%k = 37.0_wp
    h%k_b = [5.0e3_wp, 7.0e3_wp]
    call hinge3d_set_axis(h, axis, err)
    call ts%check(err%ok(), 'hinge3d_set_axis accepts a general axis')
  end function make_hinge

  !> Node q turned relative to node p by the rotation vector rel (in p's reference axes).
  function state(lp, rel) result(x)
    real(wp), intent(in) :: lp(4), rel(3)
    real(wp) :: x(8)
    x(1:4) = lp
    x(5:8) = euler_product(lp, rotvec_to_euler(rel))
  end function state

  !> e from rotation matrices only: the relative rotation Rr = R_p^T R_q turns the axis n onto
  !> a; the bending rotation is the smallest one doing that (angle beta about m ~ n x a), and
  !> the twist is what Rot(m, -beta) Rr does to t1. Principal twist in (-pi, pi].
  function expected_modes(h, x) result(e)
    type(hinge3d_t), intent(in) :: h
    real(wp), intent(in) :: x(8)
    real(wp) :: e(3), rp(3, 3), rq(3, 3), rr(3, 3), a(3), m(3), b(3), beta, sb
    rp = euler_to_matrix(x(1:4))
    rq = euler_to_matrix(x(5:8))
    rr = matmul(transpose(rp), rq)
    a = matmul(rr, h%axis)
    m = cross(h%axis, a)
    sb = norm2(m)
    beta = atan2(sb, dot_product(h%axis, a))
    e(2:3) = 0.0_wp
    b = matmul(rr, h%perp1)
    if (sb > 0) then
      m = m / sb
      b = cos(beta) * b - sin(beta) * cross(m, b) + (1 - cos(beta)) * dot_product(m, b) * m
      e(2:3) = 2 * tan(beta / 2) * [dot_product(m, h%perp1), dot_product(m, h%perp2)]
    end if
    e(1) = atan2(dot_product(b, h%perp2), dot_product(b, h%perp1))
  end function expected_modes

  ! ------------------------------------------------------------------ frame

  subroutine frame_tests()
    type(hinge3d_t) :: h
    type(error_t) :: err
    real(wp) :: f(3, 3), id(3, 3), s(3, 3)
    integer :: i
    id = 0.0_wp
    do i = 1, 3
      id(i, i) = 1.0_wp
    end do
    f = reshape([hg%axis, hg%perp1, hg%perp2], [3, 3])
    ! Normalisation and one Gram-Schmidt step on O(1) numbers: a few eps; bound 20 eps.
    call ts%check(maxval(abs(matmul(transpose(f), f) - id)) < 20 * EPS .and. &
      maxval(abs(cross(hg%axis, hg%perp1) - hg%perp2)) < 20 * EPS .and. &
      maxval(abs(hg%axis - [0.3_wp, -0.5_wp, 0.8_wp] / norm2([0.3_wp, -0.5_wp, 0.8_wp]))) &
      < 20 * EPS, 'set_axis: orthonormal right-handed frame on the given axis')
    call hinge3d_set_axis(h, [0.0_wp, 0.0_wp, 2.0_wp], err)
    call ts%check(err%ok() .and. all(h%perp1 == [1.0_wp, 0.0_wp, 0.0_wp]) .and. &
      all(h%perp2 == [0.0_wp, 1.0_wp, 0.0_wp]), 'set_axis(z): the default frame (x, y)')
    call hinge3d_set_axis(h, [0.3_wp, -0.5_wp, 0.8_wp], err, perp=[1.0_wp, 1.0_wp, 0.0_wp])
    call ts%check(err%ok() .and. abs(dot_product(h%perp1, [1.0_wp, -1.0_wp, 0.0_wp])) > 0.1_wp &
      .and. abs(dot_product(h%perp1, h%axis)) < 20 * EPS .and. &
      dot_product(h%perp1, [1.0_wp, 1.0_wp, 0.0_wp]) > 0, 'set_axis with perp: t1 from perp')
    call hinge3d_set_axis(h, [0.0_wp, 0.0_wp, 0.0_wp], err)
    call ts%check(.not. err%ok(), 'set_axis: zero axis refused')
    call hinge3d_set_axis(h, [0.0_wp, 1.0_wp, 0.0_wp], err, perp=[0.0_wp, -3.0_wp, 1.0e-9_wp])
    call ts%check(.not. err%ok(), 'set_axis: perp parallel to the axis refused')
    call ts%check(hg%n_modes() == 3 .and. hg%type_name() == 'hinge3d' .and. &
      .not. hg%has_inertia(), 'hinge3d: 3 modes, type name, no inertia')
    call hg%stiffness(s)
    call ts%check(all(s == reshape([hg%k, 0.0_wp, 0.0_wp, 0.0_wp, hg%k_b(1), 0.0_wp, 0.0_wp, &
      0.0_wp, hg%k_b(2)], [3, 3])), 'hinge3d stiffness = diag(k, k_b)')
  end subroutine frame_tests

  ! ------------------------------------------------------------------ closed forms

  subroutine closed_forms()
    real(wp), parameter :: twists(12) = [-3.0_wp, -2.0_wp, -0.5_wp, 0.5_wp, 1.0_wp, 2.5_wp, &
      3.0_wp, 170 * PI / 180, -170 * PI / 180, 4.0_wp, -5.0_wp, 6.0_wp]
    real(wp) :: x(8), lp(4), e(3), ee(3), phi, beta, g, m(3), sp, sq, err, de(3, 8), v(8), d2(3)
    integer :: k
    e = modes(hg, [ID4, ID4])
    call ts%check(all(e == 0), 'e = 0 exactly at the reference')
    ! Rounding of O(1) quaternion products, projections and atan2: a few tens of eps at most
    ! (|z| >= cos(1) here); bounds 1e-13 = 450 eps.
    do k = 1, size(twists)
      lp = rotvec_to_euler(random_rotvec(rng, PI))
      x = state(lp, twists(k) * hg%axis)
      e = modes(hg, x)
      call ts%expect('pure twist ' // real_str(twists(k)) // ': e = (a, 0, 0)', &
        maxval(abs(e - [twists(k), 0.0_wp, 0.0_wp])), 1.0e-13_wp, C_E)
    end do
    do k = 1, 10
      lp = rotvec_to_euler(random_rotvec(rng, PI))
      e = modes(hg, [lp, lp] * rng%uniform(0.5_wp, 1.5_wp))
      call ts%expect('equal nodes (random, scaled): e = 0', maxval(abs(e)), 1.0e-14_wp, C_E)
    end do
    ! Swing-twist: lambda_q = lambda_p sigma tau, tau the twist phi about n, sigma the bending
    ! beta about m in the plane of t1, t2; twists past pi included.
    err = 0.0_wp
    do k = 1, 40
      phi = rng%uniform(-3.0_wp, 3.0_wp)
      if (k > 30) phi = sign(rng%uniform(PI, 6.0_wp), phi)
      beta = rng%uniform(0.0_wp, 2.0_wp)
      g = rng%uniform(-PI, PI)
      m = cos(g) * hg%perp1 + sin(g) * hg%perp2
      lp = rotvec_to_euler(random_rotvec(rng, PI))
      x(1:4) = lp
      x(5:8) = euler_product(lp, euler_product(rotvec_to_euler(beta * m), &
        rotvec_to_euler(phi * hg%axis)))
      ee = [phi, 2 * tan(beta / 2) * cos(g), 2 * tan(beta / 2) * sin(g)]
      err = max(err, maxval(abs(modes(hg, x) - ee)))
    end do
    call ts%expect('swing-twist Rot(m, beta) Rot(n, phi): e = (phi, 2 tan(beta/2) m)', err, &
      1.0e-13_wp, C_E)
    ! Matrices only, non-unit lambda (scale-free), relative rotations up to 170 degrees.
    err = 0.0_wp
    do k = 1, 40
      x = state(rotvec_to_euler(random_rotvec(rng, PI)), random_rotvec(rng, 170 * PI / 180))
      sp = rng%uniform(0.6_wp, 1.4_wp)
      sq = rng%uniform(0.6_wp, 1.4_wp)
      x = [sp * x(1:4), sq * x(5:8)]
      ee = expected_modes(hg, x)
      ! |e2, e3| reach 2 tan(85 deg) = 23 with derivatives ~ 1 / cos^2(85 deg): relative bound.
      err = max(err, maxval(abs(modes(hg, x) - ee)) / max(1.0_wp, maxval(abs(ee)))**2)
    end do
    call ts%expect('random relative rotations to 170 deg: e = matrix closed form', err, &
      1.0e-12_wp, C_E)
    ! Bending of exactly pi about t1: z = 0, the floor keeps everything finite.
    x = state(rotvec_to_euler(random_rotvec(rng, PI)), PI * hg%perp1)
    x(5:8) = euler_product(x(1:4), [0.0_wp, hg%perp1])
    e = modes(hg, x)
    de = jacobian(hg, x)
    v = rng%uniform_vec(8, -1.0_wp, 1.0_wp)
    d2 = second(hg, x, v)
    call ts%check(all(ieee_is_finite(e)) .and. all(ieee_is_finite(de)) .and. &
      all(ieee_is_finite(d2)), 'bending of pi (z = 0): e, de, second finite')
  end subroutine closed_forms


  ! ------------------------------------------------------------------ small rotations

  subroutine small_rotations()
    real(wp) :: x(8), th(3), b(3), e(3), ang, errs(2)
    integer :: k, j
    do k = 1, 6
      b = rng%uniform_vec(3, -1.0_wp, 1.0_wp)
      ang = 1.0e-2_wp
      ! Bending only: e = 2 tan(beta/2) m = theta + theta beta^2 / 12 + ..., e1 = 0.
      th = ang * (b(2) * hg%perp1 + b(3) * hg%perp2)
      x = state(rotvec_to_euler(random_rotvec(rng, PI)), th)
      e = modes(hg, x)
      ! Leading term beta^3 / 12 < 2.3e-7 (beta < 1.5e-2); bound 10x, plus round-off.
      call ts%expect('small bending about t1, t2: (e2, e3) = angles + O(beta^3)', &
        maxval(abs(e(2:3) - ang * b(2:3))) / (10 * norm2(th)**3 / 12 + 1.0e-14_wp), 1.0_wp, &
        C_SMALL)
      call ts%expect('small bending about t1, t2: e1 = 0', abs(e(1)), 1.0e-15_wp, C_SMALL)
      ! With a twist: Rot(theta) = Rot(beta m) Rot(phi n) + O(|theta|^2); the BCH term
      ! phi beta / 2 <= |theta|^2 / 4 bounds the difference: bound 10x, 2.5 |theta|^2.
      do j = 1, 2
        th = ang / j * (b(1) * hg%axis + b(2) * hg%perp1 + b(3) * hg%perp2)
        x = state(rotvec_to_euler(random_rotvec(rng, PI)), th)
        e = modes(hg, x)
        errs(j) = maxval(abs(e - ang / j * b))
        call ts%expect('small general rotation: e = (theta.n, theta.t1, theta.t2) + O(th^2)', &
          errs(j) / (2.5_wp * norm2(th)**2), 1.0_wp, C_SMALL)
      end do
      call ts%order(errs(1), errs(2), 2, 'small general rotation: error order in |theta|')
    end do
  end subroutine small_rotations

  ! ------------------------------------------------------------------ invariance

  subroutine invariance()
    real(wp) :: x(8), y(8), e(3), r(4), err(4), d(3)
    integer :: k
    err = 0.0_wp
    do k = 1, 30
      x = state(rotvec_to_euler(random_rotvec(rng, PI)), random_rotvec(rng, 2.8_wp))
      e = modes(hg, x)
      r = rotvec_to_euler(random_rotvec(rng, PI))
      y = [euler_product(r, x(1:4)), euler_product(r, x(5:8))]
      err(1) = max(err(1), maxval(abs(modes(hg, y) - e)))
      y = [rng%uniform(0.5_wp, 2.0_wp) * x(1:4), rng%uniform(0.5_wp, 2.0_wp) * x(5:8)]
      err(2) = max(err(2), maxval(abs(modes(hg, y) - e)))
      y = [x(1:4), -x(5:8)]
      d = modes(hg, y) - e
      err(3) = max(err(3), abs(abs(d(1)) - 2 * PI), abs(d(2)), abs(d(3)))
      ! Degree 0 in each lambda (Euler's theorem): de(:, 1:4) lambda_p = de(:, 5:8) lambda_q = 0.
      y = x
      err(4) = max(err(4), maxval(abs(matmul(jacobian(hg, y), [x(1:4), 0 * x(5:8)]))), &
        maxval(abs(matmul(jacobian(hg, y), [0 * x(1:4), x(5:8)]))))
    end do
    ! Same rounding as the closed forms (|z| >= cos(1.4) = 0.17 here): bounds 1e-12.
    call ts%expect('e invariant under a common rotation of both nodes', err(1), 1.0e-12_wp, &
      C_INV)
    call ts%expect('e invariant under scaling of each lambda', err(2), 1.0e-12_wp, C_INV)
    call ts%expect('lambda_q -> -lambda_q: e1 shifts by 2 pi, e2, e3 unchanged', err(3), &
      1.0e-12_wp, C_INV)
    call ts%expect('de(:, p) lambda_p = de(:, q) lambda_q = 0 (scale-free)', err(4), &
      1.0e-12_wp, C_INV)
  end subroutine invariance

  ! ------------------------------------------------------------------ derivatives


  !> The modes are smooth on the scale zs = cos(beta/2) (the distance to their singularity at
  !> a bending angle of pi), so the steps of expect_derivatives are multiples of zs and the
  !> errors relative; |e| <= 2 pi bounds the round-off.
  subroutine derivative_tests()
    real(wp) :: x(8), v(8), rel(3), z
    character(len=48) :: what
    integer :: k
    do k = 1, 12
      write(what, '(a,i0)') 'state ', k
      rel = random_rotvec(rng, 2.5_wp)
      if (k == 1) rel = 170 * PI / 180 * hg%axis            ! twist of 170 degrees
      if (k == 2) rel = -170 * PI / 180 * (0.6_wp * hg%axis + 0.8_wp * hg%perp2)
      if (k == 3) rel = 170 * PI / 180 * hg%perp1           ! bending of 170 degrees
      if (k == 4) rel = [0.0_wp, 0.0_wp, 0.0_wp]
      x = state(rotvec_to_euler(random_rotvec(rng, PI)), rel)
      ! Every other state off the unit sphere: the forms hold for any lambda /= 0.
      if (mod(k, 2) == 0) x = [rng%uniform(0.6_wp, 1.4_wp) * x(1:4), &
        rng%uniform(0.6_wp, 1.4_wp) * x(5:8)]
      ! |v| scaled with cos(beta/2) (from 2 tan(beta/2) = |(e2, e3)|) keeps the singularity
      ! of the modes at beta = pi (z = 0) beyond s = 1 along v.
      z = 1 / sqrt(1 + sum(expected_modes(hg, x) ** 2 * [0.0_wp, 0.25_wp, 0.25_wp]))
      z = max(z, 0.05_wp)
      v = 0.3_wp * z * rng%uniform_vec(8, -1.0_wp, 1.0_wp)
      call expect_derivatives(ts, hg, x, v, z, trim(what), &
        C_DE, C_D2, C_POL)
    end do
  end subroutine derivative_tests

  !> At the reference e = (n, t1, t2) . (theta_q - theta_p) to first order, theta = 2 lambda_v.
  subroutine linear_limit()
    real(wp) :: de(3, 8), want(3, 8)
    de = jacobian(hg, [ID4, ID4])
    want = 0.0_wp
    want(:, 2:4) = -2 * transpose(reshape([hg%axis, hg%perp1, hg%perp2], [3, 3]))
    want(:, 6:8) = -want(:, 2:4)
    call ts%expect('de at the reference = 2 [0 -F^T 0 F^T]', relerr(flat(de), flat(want), &
      1.0_wp), 10 * EPS, C_LIN)
  end subroutine linear_limit
end program test_hinge3d
