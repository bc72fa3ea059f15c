!> Inertia and weight of the spatial beam (elements_beam3d, submodule elements_beam3d_mass):
!>
!>   - M symmetric; h against Lagrange's form from central differences of M on random deformed
!>     states with large rigid and nodal rotations, also with |lambda| /= 1;
!>   - M against the kinetic energy of the centroid field by differences of beam3d_centroid,
!>     and the centroid against the formula rebuilt here from e, R(lambda) and the chord;
!>   - kinetic energy of a rigid motion = rigid-body energy of a uniform bar with the section's
!>     rotary inertia; rotary energy at deformed states against body angular velocities from
!>     differences of the rotation matrices; frame invariance of M, h, f and the potential
!>     under a large 3D rotation;
!>   - linear limit: M in (u, theta) = textbook 12x12 consistent mass (cubic transverse, linear
!>     axial and torsion, linearly interpolated rotary inertia) in a general orientation;
!>   - reduction to the planar beam (elements_beam) for planar motion in either bending plane:
!>     M, h, weight and potential mapped through the planar coordinates;
!>   - weight: f = -dV/dx by differences, V = -rho_a l0 int g.r by quadrature of the
!>     centroid, undeformed f = textbook consistent load (q l / 2 and q l^2 / 12);
!>   - the lumped option: constant translations, nodal rotary inertia, no weight.
!> Both bending forms. Achieved errors are printed with every check, the worst per category
!> at the end.
program test_beam3d_mass
  use core_kinds, only: wp
  use core_error, only: error_t
  use testing, only: suite_t
  use beam3d_fixture, only: make_beam3d, beam3d_state, space_frame
  use fd_helpers, only: lcg_t, relerr, flat, random_rotvec
  use elements_base, only: MODE_RIGID, MODE_DYNAMIC
  use elements_rotation, only: rot_apply, rotvec_to_euler, euler_to_matrix, euler_product, skew
  use elements_beam3d, only: beam3d_t, BENDING_ANGLE, BENDING_SINE, beam3d_set_geometry, &
    beam3d_centroid
  use elements_beam, only: beam_t
  implicit none

  real(wp), parameter :: PI = 3.14159265358979323846_wp
  integer, parameter :: C_SYM = 1, C_LAG = 2, C_FIELD = 3, C_RIG = 4, C_INV = 5, C_LIN = 6, &
    C_PLANE = 7, C_W = 8, C_LUMP = 9, N_CAT = 9
  character(len=44), parameter :: CAT_NAME(N_CAT) = [character(len=44) :: &
    'M symmetric', 'h vs Lagrange form from FD of M', 'M, centroid vs field / FD of r', &
    'rigid motion T vs bar; rotary T vs R^T dR/dt', 'frame invariance', &
    'linear limit vs textbook 12x12', &
    'planar motion vs planar beam', 'weight: FD of V, quadrature, textbook', &
    'lumped option']
  !> 4-point Gauss-Legendre on [0, 1] for the test's own quadratures of the centroid field.
  real(wp), parameter :: GXI(4) = [0.0694318442029737_wp, 0.3300094782075719_wp, &
                                   0.6699905217924281_wp, 0.9305681557970263_wp]
  real(wp), parameter :: GW(4) = [0.1739274225687269_wp, 0.3260725774312731_wp, &
                                  0.3260725774312731_wp, 0.1739274225687269_wp]
  type(lcg_t) :: rng = lcg_t(seed=20251126)
  type(suite_t) :: ts

  call ts%init('beam3d_mass')
  call deformed_tests(BENDING_ANGLE, 'angle')
  call deformed_tests(BENDING_SINE, 'sine')
  call rigid_motion_tests()
  call linear_limit_tests()
  call planar_tests(BENDING_ANGLE, 'angle')
  call planar_tests(BENDING_SINE, 'sine')
  call lumped_tests()
  call ts%print_worst(CAT_NAME)
  call ts%finish()

contains

  subroutine inertia(b, x, xd, m, h)
    type(beam3d_t), intent(in) :: b
    real(wp), intent(in) :: x(14), xd(14)
    real(wp), intent(out) :: m(14, 14), h(14)
    call b%inertia(x, xd, m, h)
  end subroutine inertia

  function mass(b, x) result(m)
    type(beam3d_t), intent(in) :: b
    real(wp), intent(in) :: x(14)
    real(wp) :: m(14, 14), h(14)
    call b%inertia(x, spread(0.0_wp, 1, 14), m, h)
  end function mass

  real(wp) function potential(b, x, g) result(v)
    type(beam3d_t), intent(in) :: b
    real(wp), intent(in) :: x(14), g(3)
    real(wp) :: f(14)
    call b%weight(x, g, f, v)
  end function potential

  !> h_i = sum_jk (dM_ij/dx_k - 1/2 dM_jk/dx_i) xd_j xd_k, central differences of M.
  function lagrange_h(b, x, xd, s) result(h)
    type(beam3d_t), intent(in) :: b
    real(wp), intent(in) :: x(14), xd(14), s
    real(wp) :: h(14), dm(14, 14, 14), xp(14)
    integer :: k
    do k = 1, 14
      xp = x
      xp(k) = x(k) + s
      dm(:, :, k) = mass(b, xp)
      xp(k) = x(k) - s
      dm(:, :, k) = (dm(:, :, k) - mass(b, xp)) / (2 * s)
    end do
    h = 0.0_wp
    do k = 1, 14
      h = h + matmul(dm(:, :, k), xd) * xd(k)
      h(k) = h(k) - 0.5_wp * dot_product(xd, matmul(dm(:, :, k), xd))
    end do
  end function lagrange_h

  !> The centroid field rebuilt from the modes, R(lambda) of the reference axes and the chord.
  function field(b, x, xi) result(r)
    type(beam3d_t), intent(in) :: b
    real(wp), intent(in) :: x(14), xi
    real(wp) :: r(3), e(6), de(6, 14), lv(3), my(3), mz(3), h2, h4
    call b%evaluate(x, e, de)
    lv = x(8:10) - x(1:3)
    my = (rot_apply(x(4:7), b%ey0) + rot_apply(x(11:14), b%ey0)) / 2
    mz = (rot_apply(x(4:7), b%ez0) + rot_apply(x(11:14), b%ez0)) / 2
    h2 = xi - 2 * xi**2 + xi**3
    h4 = xi**3 - xi**2
    r = x(1:3) + xi * lv + ((h2 * e(3) - h4 * e(4)) * matmul(skew(lv), my) &
      - (h2 * e(5) - h4 * e(6)) * matmul(skew(mz), lv)) / b%l0
  end function field

  ! ------------------------------------------------------------------ deformed states

  subroutine deformed_tests(form, fname)
    integer, intent(in) :: form
    character(len=*), intent(in) :: fname
    integer, parameter :: N_CFG = 6
    type(beam3d_t) :: b
    real(wp) :: x(14), xd(14), m(14, 14), h(14), y(14), yd(14), my(14, 14), hy(14), p(14, 14)
    real(wp) :: sig(4), q(3, 3), d(3), g(3), f(14), fy(14), v, vy, ffd(14), rd(3), t1, t2
    real(wp) :: rel, xp(14), err
    character(len=60) :: what
    integer :: k, j, ig
    b = make_beam3d(form, 0.8_wp, [0.6_wp, -0.3_wp, 0.74_wp], [0.2_wp, 0.9_wp, -0.1_wp], ts)
    do k = 1, N_CFG
      write(what, '(a,a,a,i0)') 'beam3d/', fname, ' cfg ', k
      x = beam3d_state(b, rng%uniform_vec(3, -2.0_wp, 2.0_wp), random_rotvec(rng, PI), &
        b%l0 * rng%uniform(0.9_wp, 1.1_wp), random_rotvec(rng, 0.4_wp), random_rotvec(rng, 1.0_wp), &
        random_rotvec(rng, 1.0_wp))
      if (k == N_CFG) then
        ! Off the unit sphere: M and h are exact derivatives of T in all of R^14.
        x(4:7) = 1.07_wp * x(4:7)
        x(11:14) = 0.93_wp * x(11:14)
        what = trim(what) // ' |lambda| /= 1'
      end if
      xd = rng%uniform_vec(14, -1.0_wp, 1.0_wp)
      call inertia(b, x, xd, m, h)
      ! J^T J is symmetric exactly (the same products, commuted), 4 G^T (C G) to a rounding of
      ! its small rotary entries: observed < 1e-17 of max |M|.
      call ts%expect(trim(what) // ' M symmetric', maxval(abs(m - transpose(m))) / maxval(abs(m)), &
        1.0e-16_wp, C_SYM)
      ! Central differences of M at s = 1e-5: truncation ~ s^2, round-off ~ eps / s; observed
      ! < 4e-11 of max |M| |xd|^2.
      call ts%expect(trim(what) // ' h = Lagrange form (FD of M)', relerr(h, lagrange_h(b, x, xd, &
        1.0e-5_wp), maxval(abs(m)) * dot_product(xd, xd)), 1.0e-9_wp, C_LAG)
      ! Translational M against 1/2 rho_a l0 sum w |dr/dt|^2 by central differences of the
      ! centroid (s = 1e-5): the mass really is that of the field r (observed < 2e-10).
      b%rho_j = 0; b%rho_iy = 0; b%rho_iz = 0
      t1 = 0.5_wp * dot_product(xd, matmul(mass(b, x), xd))
      t2 = 0.0_wp
      err = 0.0_wp
      do ig = 1, 4
        rd = (beam3d_centroid(b, x + 1.0e-5_wp * xd, GXI(ig)) - beam3d_centroid(b, x &
          - 1.0e-5_wp * xd, GXI(ig))) / 2.0e-5_wp
        t2 = t2 + 0.5_wp * b%rho_a * b%l0 * GW(ig) * dot_product(rd, rd)
        err = max(err, maxval(abs(beam3d_centroid(b, x, GXI(ig)) - field(b, x, GXI(ig)))))
      end do
      b = make_beam3d(form, 0.8_wp, [0.6_wp, -0.3_wp, 0.74_wp], [0.2_wp, 0.9_wp, -0.1_wp], ts)
      call ts%expect(trim(what) // ' xd^T M_trans xd / 2 = T of FD of r', abs(t1 - t2) / t2, &
        1.0e-8_wp, C_FIELD)
      if (k < N_CFG) call check_rotary(b, x, xd, trim(what))
      ! Roundings of O(|x|) ~ 3 terms: observed < 5e-16.
      call ts%expect(trim(what) // ' centroid = field rebuilt from e, R, chord', err, &
        1.0e-14_wp, C_FIELD)
      ! Rigid rotation q (sig) and translation d of the state, the velocity rotated with it.
      sig = rotvec_to_euler(random_rotvec(rng, PI))
      q = euler_to_matrix(sig)
      d = rng%uniform_vec(3, -3.0_wp, 3.0_wp)
      p = 0.0_wp
      p(1:3, 1:3) = q
      p(8:10, 8:10) = q
      do j = 1, 4
        xp = 0.0_wp
        xp(j) = 1.0_wp
        p(4:7, 3 + j) = euler_product(sig, xp(1:4))
        p(11:14, 10 + j) = p(4:7, 3 + j)
      end do
      y = matmul(p, x)
      y(1:3) = y(1:3) + d
      y(8:10) = y(8:10) + d
      yd = matmul(p, xd)
      call inertia(b, y, yd, my, hy)
      call ts%expect(trim(what) // ' M(Px) = P M(x) P^T (rigid motion)', relerr(flat(my), &
        flat(matmul(p, matmul(m, transpose(p)))), maxval(abs(m))), 1.0e-14_wp, C_INV)
      call ts%expect(trim(what) // ' h(Px, Pxd) = P h(x, xd)', relerr(hy, matmul(p, h), &
        maxval(abs(m)) * dot_product(xd, xd)), 1.0e-14_wp, C_INV)
      ! Weight: f = -dV/dx (central FD, s = 1e-6; observed < 5e-10), V = -rho_a l0 sum w g . r
      ! (Gauss 4 is exact for the cubic r), invariance with g rotated along (roundings of the
      ! rotated state: observed < 1e-15, so 1e-14).
      g = rng%uniform_vec(3, -10.0_wp, 10.0_wp)
      call b%weight(x, g, f, v)
      do j = 1, 14
        xp = x
        xp(j) = x(j) + 1.0e-6_wp
        ffd(j) = potential(b, xp, g)
        xp(j) = x(j) - 1.0e-6_wp
        ffd(j) = -(ffd(j) - potential(b, xp, g)) / 2.0e-6_wp
      end do
      rel = b%rho_a * b%l0 * norm2(g)
      call ts%expect(trim(what) // ' weight f = -dV/dx (FD)', relerr(f, ffd, rel), 1.0e-8_wp, C_W)
      t2 = 0.0_wp
      do ig = 1, 4
        t2 = t2 - b%rho_a * b%l0 * GW(ig) * dot_product(g, field(b, x, GXI(ig)))
      end do
      call ts%expect(trim(what) // ' V = -rho_a l0 int g.r (quadrature of the field)', &
        abs(v - t2) / (rel * maxval(abs(x))), 1.0e-14_wp, C_W)
      call b%weight(y, matmul(q, g), fy, vy)
      call ts%expect(trim(what) // ' f(Px, Qg) = P f(x, g)', relerr(fy, matmul(p, f), rel), &
        1.0e-14_wp, C_INV)
      call ts%expect(trim(what) // ' V(Px + d, Qg) = V(x, g) - m Qg.d', abs(vy - (v - b%rho_a * &
        b%l0 * dot_product(matmul(q, g), d))) / (rel * (maxval(abs(x)) + norm2(d))), &
        1.0e-14_wp, C_INV)
    end do
  end subroutine deformed_tests

  !> Rotary T at a deformed state (nodal frames apart) against l0/6 (wp W wp + wp W wq +
  !> wq W wq), W = A0 J_cs A0^T, with the body angular velocities w_k = vee(R_k^T R_k')
  !> from central differences (s = 1e-6) of the rotation matrices, independent of G.
  subroutine check_rotary(b0, x, xd, what)
    type(beam3d_t), intent(in) :: b0
    real(wp), intent(in) :: x(14), xd(14)
    character(len=*), intent(in) :: what
    type(beam3d_t) :: b
    real(wp) :: a0(3, 3), jcs(3, 3), w(3, 3), om(3, 2), r(3, 3), rd(3, 3), t, tref
    integer :: k, i0
    b = b0
    b%rho_a = 0
    a0 = reshape([b%ex0, b%ey0, b%ez0], [3, 3])
    jcs = 0.0_wp
    jcs(1, 1) = b%rho_j; jcs(2, 2) = b%rho_iy; jcs(3, 3) = b%rho_iz
    w = matmul(a0, matmul(jcs, transpose(a0)))
    do k = 1, 2
      i0 = 4 + 7 * (k - 1)
      r = euler_to_matrix(x(i0:i0 + 3))
      rd = (euler_to_matrix(x(i0:i0 + 3) + 1.0e-6_wp * xd(i0:i0 + 3)) &
        - euler_to_matrix(x(i0:i0 + 3) - 1.0e-6_wp * xd(i0:i0 + 3))) / 2.0e-6_wp
      r = matmul(transpose(r), rd)
      om(:, k) = [r(3, 2), r(1, 3), r(2, 1)]
    end do
    t = 0.5_wp * dot_product(xd, matmul(mass(b, x), xd))
    tref = b%l0 / 6 * (dot_product(om(:, 1), matmul(w, om(:, 1))) + dot_product(om(:, 1), &
      matmul(w, om(:, 2))) + dot_product(om(:, 2), matmul(w, om(:, 2))))
    call ts%expect(what // ' rotary T = l0/6 (wp W wp + wp W wq + wq W wq), w = vee(R^T dR/dt)', &
      abs(t - tref) / tref, 1.0e-8_wp, C_RIG)
  end subroutine check_rotary

  ! ------------------------------------------------------------------ rigid motion

  !> T of a rigid motion of the undeformed beam = 1/2 m v_c^2 + 1/2 Omega^T J Omega with
  !> J = rho_a l0^3/12 (I - e e^T) + l0 R A0 J_cs A0^T R^T about the centre of the bar.
  subroutine rigid_motion_tests()
    type(beam3d_t) :: b
    real(wp) :: x(14), xd(14), sig(4), r(3, 3), a0(3, 3), jcs(3, 3), jbar(3, 3), e(3), c(3)
    real(wp) :: vc(3), om(3), t, texact, xp(3)
    integer :: form, k, j
    character(len=60) :: what
    do form = BENDING_ANGLE, BENDING_SINE
      b = make_beam3d(form, 0.7_wp, [-0.2_wp, 0.5_wp, 0.9_wp], [1.0_wp, 0.3_wp, 0.2_wp], ts)
      a0 = reshape([b%ex0, b%ey0, b%ez0], [3, 3])
      jcs = 0.0_wp
      jcs(1, 1) = b%rho_j; jcs(2, 2) = b%rho_iy; jcs(3, 3) = b%rho_iz
      do k = 1, 3
        write(what, '(a,i0,a,i0)') 'beam3d form ', form, ' rigid motion ', k
        sig = rotvec_to_euler(random_rotvec(rng, PI))
        r = euler_to_matrix(sig)
        xp = rng%uniform_vec(3, -2.0_wp, 2.0_wp)
        x(1:3) = xp
        x(8:10) = xp + b%l0 * matmul(r, b%ex0)
        x(4:7) = sig
        x(11:14) = sig
        vc = rng%uniform_vec(3, -1.0_wp, 1.0_wp)
        om = rng%uniform_vec(3, -2.0_wp, 2.0_wp)
        c = (x(1:3) + x(8:10)) / 2
        xd(1:3) = vc + matmul(skew(om), x(1:3) - c)
        xd(8:10) = vc + matmul(skew(om), x(8:10) - c)
        ! lambda' = 1/2 (0, Omega) lambda for the spatial angular velocity Omega.
        xd(4:7) = 0.5_wp * euler_product([0.0_wp, om], sig)
        xd(11:14) = xd(4:7)
        t = 0.5_wp * dot_product(xd, matmul(mass(b, x), xd))
        e = matmul(r, b%ex0)
        jbar = -b%rho_a * b%l0**3 / 12 * spread(e, 2, 3) * spread(e, 1, 3)
        do j = 1, 3
          jbar(j, j) = jbar(j, j) + b%rho_a * b%l0**3 / 12
        end do
        jbar = jbar + b%l0 * matmul(r, matmul(a0, matmul(jcs, matmul(transpose(a0), &
          transpose(r)))))
        texact = 0.5_wp * b%rho_a * b%l0 * dot_product(vc, vc) + 0.5_wp * dot_product(om, &
          matmul(jbar, om))
        ! Sums of O(1) products: a few eps relative (observed < 1e-15).
        call ts%expect(trim(what) // ': T = 1/2 m vc^2 + 1/2 Om^T J_bar Om', abs(t - texact) &
          / texact, 2.0e-14_wp, C_RIG)
      end do
    end do
  end subroutine rigid_motion_tests

  ! ------------------------------------------------------------------ linear limit

  !> Planar consistent mass on (v1, theta1, v2, theta2), theta = dv/dx, plus the rotary
  !> inertia rho I of linearly interpolated rotations on (theta1, theta2).
  pure function planar_m(rho_a, rho_i, l) result(m)
    real(wp), intent(in) :: rho_a, rho_i, l
    real(wp) :: m(4, 4)
    m = rho_a * l / 420 * reshape([156 * l**0, 22 * l, 54 * l**0, -13 * l, &
      22 * l, 4 * l**2, 13 * l, -3 * l**2, 54 * l**0, 13 * l, 156 * l**0, -22 * l, &
      -13 * l, -3 * l**2, -22 * l, 4 * l**2], [4, 4])
    m([2, 4], [2, 4]) = m([2, 4], [2, 4]) + rho_i * l / 6 * reshape([2, 1, 1, 2], [2, 2])
  end function planar_m

  !> d x / d(u, theta) at lambda = (1, 0, 0, 0): lambda = (1, theta / 2) to first order.
  pure function jm_map() result(jm)
    real(wp) :: jm(14, 12)
    integer :: i
    jm = 0.0_wp
    do i = 1, 3
      jm(i, i) = 1; jm(4 + i, 3 + i) = 0.5_wp; jm(7 + i, 6 + i) = 1; jm(11 + i, 9 + i) = 0.5_wp
    end do
  end function jm_map

  subroutine linear_limit_tests()
    type(beam3d_t) :: b
    real(wp) :: x0(14), jm(14, 12), t(12, 12), lam3(3, 3), mw(12, 12), mref(12, 12), l, ql(3)
    real(wp) :: g(3), f(14), v, fw(12), floc(12), ax(2, 2)
    integer :: form, i
    character(len=40) :: what
    jm = jm_map()
    do form = BENDING_ANGLE, BENDING_SINE
      write(what, '(a,i0)') 'beam3d form ', form
      b = make_beam3d(form, 0.65_wp, [-0.4_wp, 0.8_wp, 0.45_wp], [0.7_wp, 0.1_wp, 0.5_wp], ts)
      l = b%l0
      lam3 = transpose(reshape([b%ex0, b%ey0, b%ez0], [3, 3]))
      t = 0.0_wp
      do i = 0, 3
        t(3 * i + 1:3 * i + 3, 3 * i + 1:3 * i + 3) = lam3
      end do
      x0 = 0.0_wp
      x0(1:3) = [0.1_wp, 0.2_wp, -0.3_wp]
      x0(8:10) = x0(1:3) + l * b%ex0
      x0(4) = 1.0_wp
      x0(11) = 1.0_wp
      mw = matmul(transpose(jm), matmul(mass(b, x0), jm))
      ax = reshape([2, 1, 1, 2], [2, 2]) * l / 6
      mref = space_frame(b%rho_a * ax, b%rho_j * ax, planar_m(b%rho_a, b%rho_iz, l), &
        planar_m(b%rho_a, b%rho_iy, l))
      mref = matmul(transpose(t), matmul(mref, t))
      ! Gauss sums and direction cosines of O(1): a few eps of the largest entry.
      call ts%expect(trim(what) // ' M(u, theta) = textbook 12x12 consistent mass', &
        relerr(flat(mw), flat(mref), maxval(abs(mref))), 1.0e-14_wp, C_LIN)
      ! Uniform load q = rho_a g: q l / 2 per node, moments q l^2 / 12 (x-y plane: +tz at p,
      ! -tz at q; x-z plane with ty = -dw/dx: -ty at p, +ty at q).
      g = [3.0_wp, -9.81_wp, 1.7_wp]
      call b%weight(x0, g, f, v)
      fw = matmul(f, jm)
      ql = b%rho_a * matmul(lam3, g)
      floc = 0.0_wp
      floc(1:3) = ql * l / 2
      floc(7:9) = ql * l / 2
      floc(6) = ql(2) * l**2 / 12
      floc(12) = -ql(2) * l**2 / 12
      floc(5) = -ql(3) * l**2 / 12
      floc(11) = ql(3) * l**2 / 12
      call ts%expect(trim(what) // ' undeformed weight = textbook consistent load', &
        relerr(fw, matmul(transpose(t), floc), b%rho_a * l * norm2(g)), 1.0e-14_wp, C_W)
      call ts%expect(trim(what) // ' undeformed V = -m g.r_centre', abs(v + b%rho_a * l * &
        dot_product(g, (x0(1:3) + x0(8:10)) / 2)) / (b%rho_a * l * norm2(g)), 1.0e-14_wp, C_W)
    end do
  end subroutine linear_limit_tests

  ! ------------------------------------------------------------------ planar motion

  !> Planar motion in the global x-y plane, the beam's x-y (iplane = 1) or x-z (2) bending
  !> plane: M_2D = Jq^T M Jq, h_2D = Jq^T (h + M x''(q)), f_2D = Jq^T f, V_2D = V, with
  !> x(q) = (xp, yp, 0, lambda(phi_p), xq, yq, 0, lambda(phi_q)), lambda(phi) = (cos phi/2,
  !> 0, 0, sin phi/2), x''(q) on lambda = -lambda phi'^2 / 4.
  subroutine planar_tests(form, fname)
    integer, intent(in) :: form
    character(len=*), intent(in) :: fname
    type(beam3d_t) :: b
    type(beam_t) :: pb
    type(error_t) :: err
    real(wp) :: q(6), qd(6), x(14), xd(14), xdd(14), jq(14, 6), m3(14, 14), h3(14), m2(6, 6)
    real(wp) :: h2(6), f3(14), f2(6), v3, v2, alpha0, e0(3), orient(3), l0, g3(3), mref
    integer :: iplane, k
    character(len=60) :: what
    l0 = 0.9_wp
    alpha0 = 0.4_wp
    e0 = [cos(alpha0), sin(alpha0), 0.0_wp]
    pb%l0 = l0
    pb%alpha0 = alpha0
    pb%rho_a = 2.7_wp
    pb%ea = 1.0_wp; pb%ei = 1.0_wp
    pb%bending = form
    pb%dofs = [(k, k=1, 6)]
    pb%mode_class = [(MODE_DYNAMIC, k=1, 3)]
    do iplane = 1, 2
      orient = [-sin(alpha0), cos(alpha0), 0.0_wp]
      if (iplane == 2) orient = [0.0_wp, 0.0_wp, 1.0_wp]
      call beam3d_set_geometry(b, [0.0_wp, 0.0_wp, 0.0_wp], l0 * e0, orient, err)
      b%rho_a = pb%rho_a
      b%bending = form
      b%dofs = [(k, k=1, 14)]
      b%mode_class = [MODE_RIGID, (MODE_DYNAMIC, k=1, 5)]
      do k = 1, 3
        write(what, '(a,a,a,i0,a,i0)') 'beam3d/', fname, ' planar, plane ', iplane, &
          ' cfg ', k
        ! Chord turned by up to 2 rad, tangents up to ~1.3 rad from it, l /= l0.
        q(1:2) = rng%uniform_vec(2, -1.0_wp, 1.0_wp)
        q(3) = rng%uniform(-2.0_wp, 2.0_wp)
        q(4:5) = q(1:2) + l0 * rng%uniform(0.9_wp, 1.1_wp) * [cos(alpha0 + q(3) + 0.3_wp), &
          sin(alpha0 + q(3) + 0.3_wp)]
        q(3) = q(3) + rng%uniform(-1.0_wp, 1.0_wp)
        q(6) = q(3) + rng%uniform(-2.0_wp, 2.0_wp)
        qd = rng%uniform_vec(6, -1.0_wp, 1.0_wp)
        x = 0.0_wp
        x([1, 2, 8, 9]) = q([1, 2, 4, 5])
        x(4:7) = [cos(q(3) / 2), 0.0_wp, 0.0_wp, sin(q(3) / 2)]
        x(11:14) = [cos(q(6) / 2), 0.0_wp, 0.0_wp, sin(q(6) / 2)]
        jq = 0.0_wp
        jq(1, 1) = 1; jq(2, 2) = 1; jq(8, 4) = 1; jq(9, 5) = 1
        jq(4:7, 3) = [-sin(q(3) / 2), 0.0_wp, 0.0_wp, cos(q(3) / 2)] / 2
        jq(11:14, 6) = [-sin(q(6) / 2), 0.0_wp, 0.0_wp, cos(q(6) / 2)] / 2
        xd = matmul(jq, qd)
        xdd = 0.0_wp
        xdd(4:7) = -x(4:7) * qd(3)**2 / 4
        xdd(11:14) = -x(11:14) * qd(6)**2 / 4
        call inertia(b, x, xd, m3, h3)
        call pb%inertia(q, qd, m2, h2)
        mref = maxval(abs(m2))
        ! Two Gauss sums of the same field in different algebra: roundings of O(1) terms.
        call ts%expect(trim(what) // ' M = planar beam M', relerr(flat(matmul(transpose(jq), &
          matmul(m3, jq))), flat(m2), mref), 1.0e-14_wp, C_PLANE)
        call ts%expect(trim(what) // ' h = planar beam h', relerr(matmul(h3 + matmul(m3, xdd), &
          jq), h2, mref * dot_product(qd, qd)), 1.0e-14_wp, C_PLANE)
        g3 = [1.3_wp, -9.81_wp, 0.0_wp]
        call b%weight(x, g3, f3, v3)
        call pb%weight(q, g3(1:2), f2, v2)
        call ts%expect(trim(what) // ' weight = planar beam weight', relerr(matmul(f3, jq), f2, &
          pb%rho_a * l0 * norm2(g3)), 1.0e-14_wp, C_PLANE)
        call ts%expect(trim(what) // ' V = planar beam V', abs(v3 - v2) / (pb%rho_a * l0 &
          * norm2(g3) * maxval(abs(q))), 1.0e-14_wp, C_PLANE)
      end do
    end do
  end subroutine planar_tests

  ! ------------------------------------------------------------------ lumped

  subroutine lumped_tests()
    type(beam3d_t) :: b
    real(wp) :: diag(14), x(14), xd(14), m(14, 14), h(14), f(14), v, jm(14, 12), mw(12, 12)
    real(wp) :: a0(3, 3), jn(3, 3), wn(3, 3), x0(14), mref(12, 12)
    integer :: k
    b = make_beam3d(BENDING_ANGLE, 0.75_wp, [0.3_wp, -0.7_wp, 0.2_wp], [0.1_wp, 0.2_wp, 1.0_wp], ts)
    call b%lumped_mass(diag)
    call ts%check(all(diag == 0) .and. b%has_inertia(), &
      'beam3d consistent: no lumped diagonal, has_inertia')
    b%consistent = .false.
    call b%lumped_mass(diag)
    call ts%check(all(diag([1, 2, 3, 8, 9, 10]) == b%rho_a * b%l0 / 2) .and. &
      all(diag([4, 5, 6, 7, 11, 12, 13, 14]) == 0) .and. b%has_inertia(), &
      'beam3d lumped: rho_a l0/2 per translation, rotary inertia through inertia()')
    do k = 1, 3
      x = beam3d_state(b, rng%uniform_vec(3, -2.0_wp, 2.0_wp), random_rotvec(rng, PI), b%l0, &
        random_rotvec(rng, 0.4_wp), random_rotvec(rng, 1.0_wp), random_rotvec(rng, 1.0_wp))
      xd = rng%uniform_vec(14, -1.0_wp, 1.0_wp)
      call inertia(b, x, xd, m, h)
      ! M is quadratic in lambda here: FD truncation vanishes, round-off ~ eps / s remains
      ! (observed < 4e-12).
      call ts%expect('beam3d lumped: h = Lagrange form (FD of M)', relerr(h, lagrange_h(b, x, &
        xd, 1.0e-5_wp), maxval(abs(m)) * dot_product(xd, xd)), 1.0e-10_wp, C_LUMP)
      call ts%check(all(m(:, [1, 2, 3, 8, 9, 10]) == 0) .and. all(h([1, 2, 3, 8, 9, 10]) == 0), &
        'beam3d lumped: inertia() has no translational part')
      call b%weight(x, [1.0_wp, 2.0_wp, 3.0_wp], f, v)
      call ts%check(all(f == 0) .and. v == 0, 'beam3d lumped: weight on the model''s lumped masses')
    end do
    ! At lambda = 1: each node carries Wn = A0 (l0/2 J_cs + rho_a l0^3/24 diag(0,1,1)) A0^T.
    a0 = reshape([b%ex0, b%ey0, b%ez0], [3, 3])
    jn = 0.0_wp
    jn(1, 1) = b%rho_j * b%l0 / 2
    jn(2, 2) = b%rho_iy * b%l0 / 2 + b%rho_a * b%l0**3 / 24
    jn(3, 3) = b%rho_iz * b%l0 / 2 + b%rho_a * b%l0**3 / 24
    wn = matmul(a0, matmul(jn, transpose(a0)))
    x0 = 0.0_wp
    x0(8:10) = b%l0 * b%ex0
    x0(4) = 1.0_wp
    x0(11) = 1.0_wp
    jm = jm_map()
    mw = matmul(transpose(jm), matmul(mass(b, x0), jm))
    mref = 0.0_wp
    mref(4:6, 4:6) = wn
    mref(10:12, 10:12) = wn
    call ts%expect('beam3d lumped: nodal rotary inertia in (u, theta)', relerr(flat(mw), &
      flat(mref), maxval(abs(wn))), 1.0e-14_wp, C_LUMP)
    b%rho_a = 0; b%rho_j = 0; b%rho_iy = 0; b%rho_iz = 0
    call inertia(b, x, xd, m, h)
    call ts%check(.not. b%has_inertia() .and. all(m == 0) .and. all(h == 0), &
      'beam3d without densities: no inertia')
  end subroutine lumped_tests
end program test_beam3d_mass
