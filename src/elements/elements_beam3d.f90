!> Spatial beam (docs/theory.md section 2.6). Coordinates x (14) =
!> (xp, yp, zp, lambda_p(4), xq, yq, zq, lambda_q(4)); lambda of a node is its rotation
!> relative to the reference orientation ((1,0,0,0) undeformed), acting on the reference
!> section axes ex0 (chord), ey0, ez0: ey_p = R(lambda_p) ey0 etc., with the homogeneous R of
!> elements_rotation (the Euler normalisation is a separate element).
!>
!> Modes e_bar (6): elongation e1_bar = l - l0 + (2e3^2 + e3e4 + 2e4^2 + 2e5^2 + e5e6
!> + 2e6^2)/(30 l0); torsion e2_bar = e2 - (e3 e6 - e4 e5)/l0 with (sine form) e2 =
!> (l0/2)(ez_p.ey_q - ey_p.ez_q); bending e3, e4 in the x-z plane (EI_y), e5, e6 in the x-y plane (EI_z).
!> The minus sign of the torsion correction is the one for which e2_bar vanishes to second
!> order for bending without twist (rotation-minimising section frames along a non-planar
!> cubic centreline); tests/test_elements3d.f90 checks it, the other sign leaves O(e^2).
!>
!> Bending with c = (ex.e_l, ey.e_l, ez.e_l) in the section frame of a node:
!>   sine form  (e3, e5) = l0 (-cz, cy) at p, (e4, e6) = l0 (cz, -cy) at q;
!>   angle form the same times h = alpha / s, s = |(cy, cz)|, alpha = atan2(s, cx): the
!>              (y, z) components of the rotation vector turning the nodal tangent onto the
!>              chord, so |(e3, e5)| = l0 alpha. It is the planar angle form of elements_beam
!>              in every bending plane, independent of the orientation of the section axes
!>              in that plane (per-plane atan2 angles are not), and scale-free in |lambda|.
!> Both forms have the same linear limit (h = 1 + O(alpha^2)) and the same Hessian at the
!> undeformed state. Torsion likewise: the sine form takes e2 above, the angle form
!> (l0/2) |(S, C)| atan2(S, C) with S = ez_p.ey_q - ey_p.ez_q, C = ey_p.ey_q + ez_p.ez_q:
!> l0 times the relative twist angle in pure twist (see bar_modes).
!>
!> Inertia and weight (consistent by default; submodule elements_beam3d_mass) follow from the
!> centroid line r(xi) = x_p + xi l_v + (c_z u_z - c_y u_y) / l0 with the cubic Hermite
!> offsets c_z = H2 e3 - H4 e4, c_y = H2 e5 - H4 e6 and u_z = l_v x m_y, u_y = m_z x l_v
!> (m = mean of the nodal section axes), and from the section angular velocity interpolated
!> linearly between the nodal body angular velocities 2 G(lambda) lambda'.
module elements_beam3d
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_INPUT
  use elements_base, only: element_t
  use elements_rotation, only: rot_apply, rot_apply_jac, rot_apply_second, orthonormal_frame
  use elements_sd, only: sd_t, sd_lin, sd_scale, sd_mul, sd_atan2, sd_sqrt, N_X
  implicit none
  private
  public :: beam3d_t, BENDING_ANGLE, BENDING_SINE, beam3d_set_geometry, beam3d_centroid

  integer, parameter :: BENDING_ANGLE = 1
  integer, parameter :: BENDING_SINE = 2
  !> First coordinate of the position and of the Euler parameters of node p (1), q (2).
  integer, parameter :: IPOS(2) = [1, 8], ILAM(2) = [4, 11]
  !> Floor of the squared in-plane norm of c in the angle form: only reached at a bending
  !> angle of pi (tangent opposite to the chord), where the angle form is singular anyway,
  !> or for a collapsed chord or lambda = 0; it keeps those results finite.
  real(wp), parameter :: S2_FLOOR = 1.0e-30_wp

  type, extends(element_t) :: beam3d_t
    real(wp) :: l0 = 1.0_wp                  !< undeformed length [m]
    real(wp) :: ex0(3) = [1.0_wp, 0.0_wp, 0.0_wp]   !< reference chord direction
    real(wp) :: ey0(3) = [0.0_wp, 1.0_wp, 0.0_wp]   !< reference section axis y
    real(wp) :: ez0(3) = [0.0_wp, 0.0_wp, 1.0_wp]   !< reference section axis z = ex0 x ey0
    real(wp) :: ea = 0.0_wp, gj = 0.0_wp, ei_y = 0.0_wp, ei_z = 0.0_wp, rho_a = 0.0_wp
    !> Rotary inertia of the cross-section per length [kg m]: rho J_polar about the axis
    !> (torsion), rho I_y and rho I_z about the section axes y and z.
    real(wp) :: rho_j = 0.0_wp, rho_iy = 0.0_wp, rho_iz = 0.0_wp
    real(wp) :: shear_xz = 0.0_wp  !< 12 EI_y / (k G A l0^2) of the (e3, e4) plane; 0 = E-B
    real(wp) :: shear_xy = 0.0_wp  !< 12 EI_z / (k G A l0^2) of the (e5, e6) plane
    integer :: bending = BENDING_ANGLE
    !> Consistent (configuration-dependent) mass, or lumped: rho_a l0 / 2 per node and
    !> translation plus the rotary inertia of each half element, rigidly fixed to its node.
    logical :: consistent = .true.
  contains
    procedure :: evaluate => beam3d_evaluate
    procedure :: second => beam3d_second
    procedure :: stiffness => beam3d_stiffness
    procedure, nopass :: type_name => beam3d_type_name
    procedure :: has_inertia => beam3d_has_inertia
    procedure :: inertia => beam3d_inertia
    procedure :: weight => beam3d_weight
    procedure :: lumped_mass => beam3d_lumped_mass
  end type beam3d_t

  !> Current chord and nodal axes with their derivatives (d1, d2: along v, zero without v).
  type :: geom_t
    real(wp) :: l, inv_l, el(3), dl1, dl2, del1(3), del2(3)
    real(wp) :: ax(3, 3, 2), jac(3, 4, 3, 2), dax1(3, 3, 2), dax2(3, 3, 2)
  end type geom_t

  interface
    !> Mass matrix M = d2T/dxd2 and convective force h = (dM/dt) xd - dT/dx (submodule).
    pure module subroutine beam3d_inertia(this, x, xd, m, h)
      class(beam3d_t), intent(in) :: this
      real(wp), intent(in) :: x(:), xd(:)
      real(wp), intent(out) :: m(:, :), h(:)
    end subroutine beam3d_inertia

    !> Gravity g (3) on the consistent mass: potential = -int rho_a g . r, f = -dV/dx.
    pure module subroutine beam3d_weight(this, x, g, f, potential)
      class(beam3d_t), intent(in) :: this
      real(wp), intent(in) :: x(:), g(:)
      real(wp), intent(out) :: f(:), potential
    end subroutine beam3d_weight

    !> The centroid r(xi) of the mass interpolation, xi in [0, 1] from p to q.
    pure module function beam3d_centroid(this, x, xi) result(r)
      class(beam3d_t), intent(in) :: this
      real(wp), intent(in) :: x(:), xi
      real(wp) :: r(3)
    end function beam3d_centroid
  end interface

contains

  !> Reference geometry from the undeformed node positions and an orientation vector in the
  !> x-y plane of the section (orthogonalised against the chord).
  subroutine beam3d_set_geometry(this, xp, xq, orient, err)
    class(beam3d_t), intent(inout) :: this
    real(wp), intent(in) :: xp(3), xq(3), orient(3)
    type(error_t), intent(out) :: err
    real(wp) :: lv(3), frame(3, 3)
    logical :: ok
    lv = xq - xp
    this%l0 = norm2(lv)
    if (.not. this%l0 > 0) then
      call err%set(ERR_INPUT, 'beam3d: the two nodes coincide in the reference state')
      return
    end if
    call orthonormal_frame(lv / this%l0, orient, frame, ok)
    if (.not. ok) then
      call err%set(ERR_INPUT, 'beam3d: the orientation vector is zero or (nearly) parallel '// &
        'to the beam axis')
      return
    end if
    this%ex0 = frame(:, 1)
    this%ey0 = frame(:, 2)
    this%ez0 = frame(:, 3)
  end subroutine beam3d_set_geometry

  pure function geometry(this, x, v) result(gm)
    class(beam3d_t), intent(in) :: this
    real(wp), intent(in) :: x(:)
    real(wp), intent(in), optional :: v(:)
    type(geom_t) :: gm
    real(wp) :: lv(3), a0(3, 3), d(3), dp(3), lam(4), mu(4), a
    integer :: k, i
    lv = x(IPOS(2):IPOS(2) + 2) - x(IPOS(1):IPOS(1) + 2)
    gm%l = norm2(lv)
    ! A collapsed chord (l = 0) has no direction: e_l = 0 keeps every result finite.
    gm%inv_l = 0.0_wp
    if (gm%l > 0) gm%inv_l = 1 / gm%l
    gm%el = lv * gm%inv_l
    a0(:, 1) = this%ex0
    a0(:, 2) = this%ey0
    a0(:, 3) = this%ez0
    do k = 1, 2
      lam = x(ILAM(k):ILAM(k) + 3)
      do i = 1, 3
        gm%ax(:, i, k) = rot_apply(lam, a0(:, i))
        gm%jac(:, :, i, k) = rot_apply_jac(lam, a0(:, i))
      end do
    end do
    gm%dl1 = 0.0_wp; gm%dl2 = 0.0_wp; gm%del1 = 0.0_wp; gm%del2 = 0.0_wp
    gm%dax1 = 0.0_wp; gm%dax2 = 0.0_wp
    if (.not. present(v)) return
    d = v(IPOS(2):IPOS(2) + 2) - v(IPOS(1):IPOS(1) + 2)
    a = dot_product(gm%el, d)
    dp = d - a * gm%el
    gm%dl1 = a
    gm%dl2 = dot_product(dp, dp) * gm%inv_l
    gm%del1 = dp * gm%inv_l
    gm%del2 = (-2 * a * dp - dot_product(dp, dp) * gm%el) * gm%inv_l**2
    do k = 1, 2
      mu = v(ILAM(k):ILAM(k) + 3)
      do i = 1, 3
        gm%dax1(:, i, k) = matmul(gm%jac(:, :, i, k), mu)
        gm%dax2(:, i, k) = rot_apply_second(mu, a0(:, i))
      end do
    end do
  end function geometry

  !> Axis i of node k dotted with the chord direction, s = a . e_l.
  pure function axis_chord(gm, i, k) result(s)
    type(geom_t), intent(in) :: gm
    integer, intent(in) :: i, k
    type(sd_t) :: s
    real(wp) :: a(3), gp(3)
    a = gm%ax(:, i, k)
    s%f = dot_product(a, gm%el)
    gp = (a - s%f * gm%el) * gm%inv_l
    s%g(IPOS(1):IPOS(1) + 2) = -gp
    s%g(IPOS(2):IPOS(2) + 2) = gp
    s%g(ILAM(k):ILAM(k) + 3) = matmul(gm%el, gm%jac(:, :, i, k))
    s%d1 = dot_product(gm%dax1(:, i, k), gm%el) + dot_product(a, gm%del1)
    s%d2 = dot_product(gm%dax2(:, i, k), gm%el) + 2 * dot_product(gm%dax1(:, i, k), gm%del1) &
      + dot_product(a, gm%del2)
  end function axis_chord

  !> Axis i of node p dotted with axis j of node q.
  pure function axis_axis(gm, i, j) result(s)
    type(geom_t), intent(in) :: gm
    integer, intent(in) :: i, j
    type(sd_t) :: s
    s%f = dot_product(gm%ax(:, i, 1), gm%ax(:, j, 2))
    s%g(ILAM(1):ILAM(1) + 3) = matmul(gm%ax(:, j, 2), gm%jac(:, :, i, 1))
    s%g(ILAM(2):ILAM(2) + 3) = matmul(gm%ax(:, i, 1), gm%jac(:, :, j, 2))
    s%d1 = dot_product(gm%dax1(:, i, 1), gm%ax(:, j, 2)) + dot_product(gm%ax(:, i, 1), &
      gm%dax1(:, j, 2))
    s%d2 = dot_product(gm%dax2(:, i, 1), gm%ax(:, j, 2)) + 2 * dot_product(gm%dax1(:, i, 1), &
      gm%dax1(:, j, 2)) + dot_product(gm%ax(:, i, 1), gm%dax2(:, j, 2))
  end function axis_axis

  !> h(c, q) = atan2(sqrt(q), c) / sqrt(q) and its derivatives hd = (h_c, h_q, h_cc, h_cq,
  !> h_qq). h_c = -1 / r^2 with r^2 = c^2 + q exactly; h_q and h_qq cancel badly in closed
  !> form when q << c^2, where h = A(u) / c with A(u) = atan(sqrt u) / sqrt u = sum (-u)^n /
  !> (2n + 1), u = q / c^2, is summed instead (u < 1/4: 40 terms reach eps for A'' too).
  pure subroutine angle_factor(c, q, h, hd)
    real(wp), intent(in) :: c, q
    real(wp), intent(out) :: h, hd(5)
    integer, parameter :: N_SERIES = 40
    real(wp) :: r2, u, a, a1, a2, s, alpha, hs, hss, t
    integer :: n
    r2 = max(c**2 + q, S2_FLOOR)
    hd(1) = -1 / r2
    hd(3) = 2 * c / r2**2
    hd(4) = 1 / r2**2
    ! c^2 + q = |lambda|^4 for a unit e_l: the floor only excludes a vanishing lambda.
    if (c > 0 .and. q < 0.25_wp * c**2 .and. c**2 > S2_FLOOR) then
      u = q / c**2
      a = 0.0_wp; a1 = 0.0_wp; a2 = 0.0_wp
      do n = N_SERIES, 0, -1
        t = real(1 - 2 * mod(n, 2), wp) / (2 * n + 1)
        a = a * u + t
        if (n >= 1) a1 = a1 * u + n * t
        if (n >= 2) a2 = a2 * u + n * (n - 1) * t
      end do
      h = a / c
      hd(2) = a1 / c**3
      hd(5) = a2 / c**5
    else
      s = sqrt(max(q, S2_FLOOR))
      alpha = atan2(s, c)
      h = alpha / s
      hs = c / (s * r2) - alpha / s**2
      hss = -2 * c / (s**2 * r2) - 2 * c / r2**2 + 2 * alpha / s**3
      hd(2) = hs / (2 * s)
      hd(5) = (hss - hs / s) / (4 * s**2)
    end if
  end subroutine angle_factor

  !> f(c, q) as an sd_t, by the chain rule from its partial derivatives.
  pure function sd_angle_factor(c, q) result(s)
    type(sd_t), intent(in) :: c, q
    type(sd_t) :: s
    real(wp) :: hd(5)
    call angle_factor(c%f, q%f, s%f, hd)
    s%g = hd(1) * c%g + hd(2) * q%g
    s%d1 = hd(1) * c%d1 + hd(2) * q%d1
    s%d2 = hd(3) * c%d1**2 + 2 * hd(4) * c%d1 * q%d1 + hd(5) * q%d1**2 + hd(1) * c%d2 &
      + hd(2) * q%d2
  end function sd_angle_factor

  !> The six raw modes (e1 = l - l0, e2, e3 ... e6) and then e_bar.
  pure subroutine bar_modes(this, gm, eb)
    class(beam3d_t), intent(in) :: this
    type(geom_t), intent(in) :: gm
    type(sd_t), intent(out) :: eb(6)
    type(sd_t) :: e(6), cy(2), cz(2), h, q, quad, corr, s_tw, c_tw
    integer :: k
    real(wp) :: l0
    l0 = this%l0
    e(1)%f = gm%l - l0
    e(1)%g(IPOS(1):IPOS(1) + 2) = -gm%el
    e(1)%g(IPOS(2):IPOS(2) + 2) = gm%el
    e(1)%d1 = gm%dl1
    e(1)%d2 = gm%dl2
    ! Twist: with S = ez_p.ey_q - ey_p.ez_q and C = ey_p.ey_q + ez_p.ez_q, the relative
    ! rotation split into a twist psi about the section x axis and a bend beta gives
    ! S = 2 cos^2(beta/2) sin psi, C = 2 cos^2(beta/2) cos psi. The sine form takes l0 S / 2,
    ! whose pure-twist moment GJ sin(psi) cos(psi) peaks at 45 degrees per element (a
    ! cantilever twisted to 1 rad by 4 elements came out 1.047; 0.5 rad per element was a
    ! limit point). The angle form takes l0 cos^2(beta/2) psi = (l0/2) |(S, C)| atan2(S, C):
    ! exact in pure twist, and with the sine form's cos^2(beta/2) under bending, which
    ! converged best on the bend, the helix and the elbow (plain l0 psi: up to 2.4 times the
    ! sine form's error at 8 elements on the bend; this form 1.1 times, and 0.6 to 0.97 times
    ! on the helix).
    s_tw = sd_lin(axis_axis(gm, 3, 2), 1.0_wp, axis_axis(gm, 2, 3), -1.0_wp)
    if (this%bending == BENDING_SINE) then
      e(2) = sd_scale(s_tw, l0 / 2)
    else
      c_tw = sd_lin(axis_axis(gm, 2, 2), 1.0_wp, axis_axis(gm, 3, 3), 1.0_wp)
      e(2) = sd_scale(sd_mul(sd_atan2(s_tw, c_tw), sd_sqrt(sd_lin(sd_mul(s_tw, s_tw), 1.0_wp, &
        sd_mul(c_tw, c_tw), 1.0_wp))), l0 / 2)
    end if
    do k = 1, 2
      cy(k) = axis_chord(gm, 2, k)
      cz(k) = axis_chord(gm, 3, k)
      if (this%bending /= BENDING_SINE) then
        q = sd_lin(sd_mul(cy(k), cy(k)), 1.0_wp, sd_mul(cz(k), cz(k)), 1.0_wp)
        h = sd_angle_factor(axis_chord(gm, 1, k), q)
        cy(k) = sd_mul(cy(k), h)
        cz(k) = sd_mul(cz(k), h)
      end if
    end do
    e(3) = sd_scale(cz(1), -l0)
    e(4) = sd_scale(cz(2), l0)
    e(5) = sd_scale(cy(1), l0)
    e(6) = sd_scale(cy(2), -l0)
    quad = sd_lin(sd_lin(sd_mul(e(3), e(3)), 2.0_wp, sd_mul(e(3), e(4)), 1.0_wp), 1.0_wp, &
                  sd_lin(sd_mul(e(4), e(4)), 2.0_wp, sd_mul(e(5), e(5)), 2.0_wp), 1.0_wp)
    quad = sd_lin(quad, 1.0_wp, sd_lin(sd_mul(e(5), e(6)), 1.0_wp, sd_mul(e(6), e(6)), &
                  2.0_wp), 1.0_wp)
    eb(1) = sd_lin(e(1), 1.0_wp, quad, 1 / (30 * l0))
    corr = sd_lin(sd_mul(e(3), e(6)), 1.0_wp, sd_mul(e(4), e(5)), -1.0_wp)
    eb(2) = sd_lin(e(2), 1.0_wp, corr, -1 / l0)
    eb(3:6) = e(3:6)
  end subroutine bar_modes

  pure subroutine beam3d_evaluate(this, x, e, de)
    class(beam3d_t), intent(in) :: this
    real(wp), intent(in) :: x(:)
    real(wp), intent(out) :: e(:), de(:, :)
    type(sd_t) :: eb(6)
    integer :: m
    call bar_modes(this, geometry(this, x), eb)
    do m = 1, 6
      e(m) = eb(m)%f
      de(m, :) = eb(m)%g
    end do
  end subroutine beam3d_evaluate

  pure subroutine beam3d_second(this, x, v, d2e)
    class(beam3d_t), intent(in) :: this
    real(wp), intent(in) :: x(:), v(:)
    real(wp), intent(out) :: d2e(:)
    type(sd_t) :: eb(6)
    integer :: m
    call bar_modes(this, geometry(this, x, v), eb)
    do m = 1, 6
      d2e(m) = eb(m)%d2
    end do
  end subroutine beam3d_second

  !> S on e_bar: EA/l0, GJ/l0^3 and per bending plane EI/(l0^3 (1 + P)) [[4+P, -(2-P)],
  !> [-(2-P), 4+P]] (P = 0: Euler-Bernoulli), as for the planar beam. The torsion mode is
  !> l0 times the relative twist angle, like the bending modes l0 times angles, hence GJ/l0^3
  !> (GJ/l0 would give l0^2 times the textbook GJ/L).
  pure subroutine beam3d_stiffness(this, s)
    class(beam3d_t), intent(in) :: this
    real(wp), intent(out) :: s(:, :)
    s = 0.0_wp
    s(1, 1) = this%ea / this%l0
    s(2, 2) = this%gj / this%l0**3
    s(3:4, 3:4) = bending_block(this%ei_y, this%shear_xz, this%l0)
    s(5:6, 5:6) = bending_block(this%ei_z, this%shear_xy, this%l0)
  end subroutine beam3d_stiffness

  pure function bending_block(ei, p, l0) result(b)
    real(wp), intent(in) :: ei, p, l0
    real(wp) :: b(2, 2)
    real(wp) :: kb
    kb = ei / (l0**3 * (1 + p))
    b = kb * reshape([4 + p, -(2 - p), -(2 - p), 4 + p], [2, 2])
  end function bending_block

  !> Both mass options have a configuration-dependent part: the lumped one its nodal rotary
  !> inertia 4 G^T J G (not a constant diagonal in Euler parameters).
  pure logical function beam3d_has_inertia(this)
    class(beam3d_t), intent(in) :: this
    beam3d_has_inertia = this%rho_a > 0 .or. this%rho_j > 0 .or. this%rho_iy > 0 &
      .or. this%rho_iz > 0
  end function beam3d_has_inertia

  !> Lumped option: half the mass on the translations of each node (its rotary inertia is in
  !> beam3d_inertia); nothing for the consistent mass.
  pure subroutine beam3d_lumped_mass(this, diag)
    class(beam3d_t), intent(in) :: this
    real(wp), intent(out) :: diag(:)
    diag = 0.0_wp
    if (this%consistent) return
    diag(IPOS(1):IPOS(1) + 2) = this%rho_a * this%l0 / 2
    diag(IPOS(2):IPOS(2) + 2) = this%rho_a * this%l0 / 2
  end subroutine beam3d_lumped_mass

  pure function beam3d_type_name() result(name)
    character(len=:), allocatable :: name
    name = 'beam3d'
  end function beam3d_type_name
end module elements_beam3d
