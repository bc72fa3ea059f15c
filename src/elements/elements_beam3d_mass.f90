!> Inertia and weight of the spatial beam (elements_beam3d).
!>
!> Translation. The centroid line, as the planar beam's in each bending plane:
!>   r(xi) = x_p + xi l_v + (c_z(xi) u_z - c_y(xi) u_y) / l0,
!>   c_z = H2 e3 - H4 e4,  c_y = H2 e5 - H4 e6,  H2 = xi - 2 xi^2 + xi^3,  H4 = xi^3 - xi^2,
!>   u_z = l_v x m_y,  u_y = m_z x l_v,  m_y = (ey_p + ey_q) / 2,  m_z = (ez_p + ez_q) / 2.
!> u_z and u_y are the chord times the unit normals in the two bending planes up to factors
!> 1 + O(e^2) (they are exactly l n for planar motion, where the section axis normal to the
!> plane is the same at both nodes: then r is the planar beam's field, in either plane).
!> Why this construction: it is built from the chord and the nodal axes only, so r moves
!> with any rigid motion (frame indifference); it is symmetric in p and q; it is a
!> polynomial (linear in l_v, quadratic in lambda), so its derivatives are short and exact,
!> with no normalisation that could divide by zero; and its departure from unit normals
!> multiplies e, so it only changes r at third order in the deformation.
!> The sign of c_y: e5 = l0 ey_p . e_l is minus l0 times the tangent's rotation towards +y.
!>
!> Rotation. The section angular velocity is interpolated linearly between the nodal body
!> angular velocities, omega(xi) = (1 - xi) omega_p + xi omega_q, omega_k = 2 G(lambda_k)
!> lambda_k'. Body components are taken along each node's own section axes, which are the
!> same reference axes (ex0, ey0, ez0) carried by each node: the common frame is the
!> reference section frame. They are unchanged by a superposed rigid rotation, exact for a
!> rigid motion (omega_p = omega_q), and differ from any exact interpolation of rotations
!> by O(relative nodal rotation^2) relative. Integrated in closed form:
!>   T_rot = 1/2 Omega^T C Omega, Omega = (omega_p, omega_q), C = l0/6 [[2W, W], [W, 2W]],
!> W = A0 J_cs A0^T with A0 = [ex0 ey0 ez0], J_cs = diag(rho_j, rho_iy, rho_iz). Its linear
!> limit is rho J l/6 [[2, 1], [1, 2]] for the twist and rho I l/6 [[2, 1], [1, 2]] on the
!> nodal bending rotations of each plane: the rotary inertia of linearly interpolated
!> (Timoshenko-type) rotations, not Przemieniecki's rho I/(30 l) [36, 3l, ...] from the slope
!> of the cubic. M_lambda = 4 Gb^T C Gb, h_lambda = 8 Gb(lambda')^T C Gb(lambda) lambda' as
!> for the rigid body (G(a) a = 0, G(a) b = -G(b) a), Gb = blockdiag(G(lambda_p), G(lambda_q)).
!>
!> Lumped option: C = blockdiag(Wn, Wn), the half element as a rigid body fixed to its node:
!> Wn = A0 (l0/2 J_cs + rho_a l0^3/24 diag(0, 1, 1)) A0^T (the planar lumped beam's
!> rho_a l0^3/24, so that bending keeps a mass); its translational mass is the constant
!> diagonal of beam3d_lumped_mass, and its weight is the model's (nodal forces on lumped
!> masses), so beam3d_weight gives none.
!>
!> Both M and h hold for any lambda, also |lambda| /= 1: T is a smooth function of x and xd
!> in all of R^14 (homogeneous R, G linear) and M, h are its exact derivatives.
submodule (elements_beam3d) elements_beam3d_mass
  use elements_rotation, only: skew, euler_g
  implicit none

  !> 4-point Gauss-Legendre on [0, 1]: exact for the degree-6 integrands J^T J and J^T r''.
  real(wp), parameter :: GAUSS_XI(4) = [0.0694318442029737_wp, 0.3300094782075719_wp, &
                                         0.6699905217924281_wp, 0.9305681557970263_wp]
  real(wp), parameter :: GAUSS_W(4) = [0.1739274225687269_wp, 0.3260725774312731_wp, &
                                        0.3260725774312731_wp, 0.1739274225687269_wp]
  !> Euler-parameter coordinates of both nodes, in the order of Gb's columns.
  integer, parameter :: ILAM8(8) = [ILAM(1), ILAM(1) + 1, ILAM(1) + 2, ILAM(1) + 3, &
                                    ILAM(2), ILAM(2) + 1, ILAM(2) + 2, ILAM(2) + 3]

  !> The bending modes e3 ... e6 (value, gradient, derivatives along the velocity), the
  !> chord l_v, the lateral directions u_z, u_y, their Jacobians and derivatives along the
  !> velocity.
  type :: field_t
    type(sd_t) :: e(3:6)
    real(wp) :: lv(3), uz(3), uy(3), bz(3, N_X), by(3, N_X)
    real(wp) :: uz1(3) = 0.0_wp, uy1(3) = 0.0_wp, uz2(3) = 0.0_wp, uy2(3) = 0.0_wp
  end type field_t

contains

  pure function cross(a, b) result(c)
    real(wp), intent(in) :: a(3), b(3)
    real(wp) :: c(3)
    c = [a(2) * b(3) - a(3) * b(2), a(3) * b(1) - a(1) * b(3), a(1) * b(2) - a(2) * b(1)]
  end function cross

  !> The field's ingredients at x (with derivatives along v when present). The modes come
  !> through the type-bound evaluate and second: gfortran 12 gives the parent's private
  !> procedures local linkage, so a submodule cannot call them directly.
  pure function field(this, x, v) result(fd)
    class(beam3d_t), intent(in) :: this
    real(wp), intent(in) :: x(:)
    real(wp), intent(in), optional :: v(:)
    type(field_t) :: fd
    real(wp) :: e(6), de(6, N_X), d2e(6), a0(3, 2), ax(3, 2, 2), jac(3, 4, 2, 2)
    real(wp) :: dax1(3, 2, 2), dax2(3, 2, 2), my(3), mz(3), my1(3), mz1(3), my2(3), mz2(3)
    real(wp) :: dlv(3), sl(3, 3), sk(3, 3), lam(4), mu(4)
    integer :: k, i
    call this%evaluate(x, e, de)
    d2e = 0.0_wp
    if (present(v)) call this%second(x, v, d2e)
    do i = 3, 6
      fd%e(i)%f = e(i)
      fd%e(i)%g = de(i, :)
      if (present(v)) fd%e(i)%d1 = dot_product(de(i, :), v)
      fd%e(i)%d2 = d2e(i)
    end do
    a0(:, 1) = this%ey0
    a0(:, 2) = this%ez0
    do k = 1, 2
      lam = x(ILAM(k):ILAM(k) + 3)
      do i = 1, 2
        ax(:, i, k) = rot_apply(lam, a0(:, i))
        jac(:, :, i, k) = rot_apply_jac(lam, a0(:, i))
      end do
    end do
    fd%lv = x(IPOS(2):IPOS(2) + 2) - x(IPOS(1):IPOS(1) + 2)
    my = (ax(:, 1, 1) + ax(:, 1, 2)) / 2
    mz = (ax(:, 2, 1) + ax(:, 2, 2)) / 2
    fd%uz = cross(fd%lv, my)
    fd%uy = cross(mz, fd%lv)
    fd%bz = 0.0_wp
    fd%by = 0.0_wp
    sk = skew(my)
    fd%bz(:, IPOS(1):IPOS(1) + 2) = sk
    fd%bz(:, IPOS(2):IPOS(2) + 2) = -sk
    sk = skew(mz)
    fd%by(:, IPOS(1):IPOS(1) + 2) = -sk
    fd%by(:, IPOS(2):IPOS(2) + 2) = sk
    sl = skew(fd%lv) / 2
    do k = 1, 2
      fd%bz(:, ILAM(k):ILAM(k) + 3) = matmul(sl, jac(:, :, 1, k))
      fd%by(:, ILAM(k):ILAM(k) + 3) = -matmul(sl, jac(:, :, 2, k))
    end do
    if (.not. present(v)) return
    do k = 1, 2
      mu = v(ILAM(k):ILAM(k) + 3)
      do i = 1, 2
        dax1(:, i, k) = matmul(jac(:, :, i, k), mu)
        dax2(:, i, k) = rot_apply_second(mu, a0(:, i))
      end do
    end do
    dlv = v(IPOS(2):IPOS(2) + 2) - v(IPOS(1):IPOS(1) + 2)
    my1 = (dax1(:, 1, 1) + dax1(:, 1, 2)) / 2
    mz1 = (dax1(:, 2, 1) + dax1(:, 2, 2)) / 2
    my2 = (dax2(:, 1, 1) + dax2(:, 1, 2)) / 2
    mz2 = (dax2(:, 2, 1) + dax2(:, 2, 2)) / 2
    fd%uz1 = cross(dlv, my) + cross(fd%lv, my1)
    fd%uy1 = cross(mz1, fd%lv) + cross(mz, dlv)
    ! l_v is linear in x: no second derivative of its own.
    fd%uz2 = 2 * cross(dlv, my1) + cross(fd%lv, my2)
    fd%uy2 = cross(mz2, fd%lv) + 2 * cross(mz1, dlv)
  end function field

  !> c(xi) = (H2 ea - H4 eb) / l0.
  pure function offset(ea, eb, xi, l0) result(c)
    type(sd_t), intent(in) :: ea, eb
    real(wp), intent(in) :: xi, l0
    type(sd_t) :: c
    c = sd_lin(ea, (xi - 2 * xi**2 + xi**3) / l0, eb, -(xi**3 - xi**2) / l0)
  end function offset

  pure module function beam3d_centroid(this, x, xi) result(r)
    class(beam3d_t), intent(in) :: this
    real(wp), intent(in) :: x(:), xi
    real(wp) :: r(3)
    type(field_t) :: fd
    type(sd_t) :: cz, cy
    fd = field(this, x)
    cz = offset(fd%e(3), fd%e(4), xi, this%l0)
    cy = offset(fd%e(5), fd%e(6), xi, this%l0)
    r = x(IPOS(1):IPOS(1) + 2) + xi * fd%lv + cz%f * fd%uz - cy%f * fd%uy
  end function beam3d_centroid

  pure module subroutine beam3d_inertia(this, x, xd, m, h)
    class(beam3d_t), intent(in) :: this
    real(wp), intent(in) :: x(:), xd(:)
    real(wp), intent(out) :: m(:, :), h(:)
    type(field_t) :: fd
    type(sd_t) :: cz, cy
    real(wp) :: jm(3, N_X), jtj(N_X, N_X), r2(3), xi, wl
    integer :: ig, i, j
    m = 0.0_wp
    h = 0.0_wp
    if (.not. this%has_inertia()) return
    call rotary_inertia(this, x, xd, m, h)
    if (.not. (this%consistent .and. this%rho_a > 0)) return
    fd = field(this, x, xd)
    ! J = dr/dx = A(xi) + c_z B_z - c_y B_y + u_z dc_z^T - u_y dc_y^T, and the part of the
    ! acceleration quadratic in xd: r'' = (c_z u_z)'' - (c_y u_y)'' along xd.
    do ig = 1, size(GAUSS_XI)
      xi = GAUSS_XI(ig)
      wl = GAUSS_W(ig) * this%rho_a * this%l0
      cz = offset(fd%e(3), fd%e(4), xi, this%l0)
      cy = offset(fd%e(5), fd%e(6), xi, this%l0)
      do j = 1, N_X
        jm(:, j) = cz%f * fd%bz(:, j) - cy%f * fd%by(:, j) + cz%g(j) * fd%uz - cy%g(j) * fd%uy
      end do
      do i = 1, 3
        jm(i, IPOS(1) + i - 1) = jm(i, IPOS(1) + i - 1) + (1 - xi)
        jm(i, IPOS(2) + i - 1) = jm(i, IPOS(2) + i - 1) + xi
      end do
      r2 = cz%d2 * fd%uz + 2 * cz%d1 * fd%uz1 + cz%f * fd%uz2 &
        - (cy%d2 * fd%uy + 2 * cy%d1 * fd%uy1 + cy%f * fd%uy2)
      jtj = matmul(transpose(jm), jm)
      m = m + wl * jtj
      h = h + wl * matmul(r2, jm)
    end do
  end subroutine beam3d_inertia

  !> The rotary part (consistent or lumped): M_lambda = 4 Gb^T C Gb and
  !> h_lambda = 8 Gb(lambda')^T C Gb(lambda) lambda', added to m and h.
  pure subroutine rotary_inertia(this, x, xd, m, h)
    class(beam3d_t), intent(in) :: this
    real(wp), intent(in) :: x(:), xd(:)
    real(wp), intent(inout) :: m(:, :), h(:)
    real(wp) :: a0(3, 3), jn(3, 3), w(3, 3), c(6, 6), gb(6, 8), gbd(6, 8), cg(6, 8)
    real(wp) :: gt(8, 6), gdt(8, 6), mr(8, 8), om(6), hr(8)
    integer :: i
    a0(:, 1) = this%ex0
    a0(:, 2) = this%ey0
    a0(:, 3) = this%ez0
    jn = 0.0_wp
    jn(1, 1) = this%rho_j
    jn(2, 2) = this%rho_iy
    jn(3, 3) = this%rho_iz
    c = 0.0_wp
    if (this%consistent) then
      w = matmul(a0, matmul(jn, transpose(a0)))
      c(1:3, 1:3) = this%l0 / 3 * w
      c(4:6, 4:6) = this%l0 / 3 * w
      c(1:3, 4:6) = this%l0 / 6 * w
      c(4:6, 1:3) = this%l0 / 6 * w
    else
      jn = this%l0 / 2 * jn
      jn(2, 2) = jn(2, 2) + this%rho_a * this%l0**3 / 24
      jn(3, 3) = jn(3, 3) + this%rho_a * this%l0**3 / 24
      w = matmul(a0, matmul(jn, transpose(a0)))
      c(1:3, 1:3) = w
      c(4:6, 4:6) = w
    end if
    gb = 0.0_wp
    gbd = 0.0_wp
    do i = 1, 2
      gb(3 * i - 2:3 * i, 4 * i - 3:4 * i) = euler_g(x(ILAM(i):ILAM(i) + 3))
      gbd(3 * i - 2:3 * i, 4 * i - 3:4 * i) = euler_g(xd(ILAM(i):ILAM(i) + 3))
    end do
    cg = matmul(c, gb)
    gt = transpose(gb)
    gdt = transpose(gbd)
    mr = 4 * matmul(gt, cg)
    om = matmul(cg, xd(ILAM8))
    hr = 8 * matmul(gdt, om)
    m(ILAM8, ILAM8) = m(ILAM8, ILAM8) + mr
    h(ILAM8) = h(ILAM8) + hr
  end subroutine rotary_inertia

  !> f = rho_a l0 int J^T g dxi in closed form: int H2 = 1/12, int H4 = -1/12, so
  !> int c = (ea + eb) / (12 l0), and int A = (I/2, 0, I/2, 0).
  pure module subroutine beam3d_weight(this, x, g, f, potential)
    class(beam3d_t), intent(in) :: this
    real(wp), intent(in) :: x(:), g(:)
    real(wp), intent(out) :: f(:), potential
    type(field_t) :: fd
    type(sd_t) :: cz, cy
    real(wp) :: gv(3), rho_l, gz, gy
    integer :: j
    f = 0.0_wp
    potential = 0.0_wp
    if (.not. (this%consistent .and. this%rho_a > 0)) return
    gv = g(1:3)
    fd = field(this, x)
    cz = sd_lin(fd%e(3), 1 / (12 * this%l0), fd%e(4), 1 / (12 * this%l0))
    cy = sd_lin(fd%e(5), 1 / (12 * this%l0), fd%e(6), 1 / (12 * this%l0))
    gz = dot_product(gv, fd%uz)
    gy = dot_product(gv, fd%uy)
    rho_l = this%rho_a * this%l0
    do j = 1, N_X
      f(j) = rho_l * (cz%f * dot_product(gv, fd%bz(:, j)) - cy%f * dot_product(gv, fd%by(:, j)) &
        + gz * cz%g(j) - gy * cy%g(j))
    end do
    f(IPOS(1):IPOS(1) + 2) = f(IPOS(1):IPOS(1) + 2) + rho_l / 2 * gv
    f(IPOS(2):IPOS(2) + 2) = f(IPOS(2):IPOS(2) + 2) + rho_l / 2 * gv
    potential = -rho_l * (dot_product(gv, x(IPOS(1):IPOS(1) + 2)) &
      + dot_product(gv, fd%lv) / 2 + cz%f * gz - cy%f * gy)
  end subroutine beam3d_weight
end submodule elements_beam3d_mass
