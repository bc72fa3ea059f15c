!> Planar beam (docs/theory.md section 2.1). Coordinates x = (xp, yp, phi_p, xq, yq, phi_q);
!> modes e_bar = (e1_bar, e2, e3): elongation with the second-order arc-shortening term, and
!> the two bending modes in the angle form (e2 = l0 theta_p, e3 = -l0 theta_q, default) or the
!> sine form (l0 sin theta). theta is the rotation of a nodal tangent relative to the chord.
!>
!> The angle form is the default: on the two-link benchmark it converges far faster with the
!> mesh (docs/theory.md section 2.1), and its linear limit is identical.
module elements_beam
  use core_kinds, only: wp
  use elements_base, only: element_t
  implicit none
  private
  public :: beam_t, BENDING_ANGLE, BENDING_SINE

  integer, parameter :: BENDING_ANGLE = 1
  integer, parameter :: BENDING_SINE = 2

  !> 4-point Gauss-Legendre on [0, 1]: exact for the degree-6 integrand of the mass matrix.
  real(wp), parameter :: GAUSS_XI(4) = [0.0694318442029737_wp, 0.3300094782075719_wp, &
                                         0.6699905217924281_wp, 0.9305681557970263_wp]
  real(wp), parameter :: GAUSS_W(4) = [0.1739274225687269_wp, 0.3260725774312731_wp, &
                                        0.3260725774312731_wp, 0.1739274225687269_wp]
  !> Hermite bending shapes H2, H4 at the Gauss points (docs/theory.md 2.1, consistent mass).
  real(wp), parameter :: GAUSS_H2(4) = GAUSS_XI - 2 * GAUSS_XI**2 + GAUSS_XI**3
  real(wp), parameter :: GAUSS_H4(4) = GAUSS_XI**3 - GAUSS_XI**2
  !> Quadrature moments sum_i w_i f(xi_i). The material point is affine in c(xi) and its
  !> gradient, so mass, convective force and weight are sums of these configuration-independent
  !> moments times products of e, de, d2e, lv and dlv: closed forms, no Gauss-point loop.
  real(wp), parameter :: M_1 = sum(GAUSS_W), M_X = sum(GAUSS_W * GAUSS_XI)
  real(wp), parameter :: M_P = sum(GAUSS_W * (1 - GAUSS_XI))
  real(wp), parameter :: M_PP = sum(GAUSS_W * (1 - GAUSS_XI)**2)
  real(wp), parameter :: M_PX = sum(GAUSS_W * (1 - GAUSS_XI) * GAUSS_XI)
  real(wp), parameter :: M_XX = sum(GAUSS_W * GAUSS_XI**2)
  real(wp), parameter :: M_2 = sum(GAUSS_W * GAUSS_H2), M_4 = sum(GAUSS_W * GAUSS_H4)
  real(wp), parameter :: M_P2 = sum(GAUSS_W * (1 - GAUSS_XI) * GAUSS_H2)
  real(wp), parameter :: M_P4 = sum(GAUSS_W * (1 - GAUSS_XI) * GAUSS_H4)
  real(wp), parameter :: M_X2 = sum(GAUSS_W * GAUSS_XI * GAUSS_H2)
  real(wp), parameter :: M_X4 = sum(GAUSS_W * GAUSS_XI * GAUSS_H4)
  real(wp), parameter :: M_22 = sum(GAUSS_W * GAUSS_H2**2)
  real(wp), parameter :: M_24 = sum(GAUSS_W * GAUSS_H2 * GAUSS_H4)
  real(wp), parameter :: M_44 = sum(GAUSS_W * GAUSS_H4**2)

  real(wp), parameter :: PI = 3.14159265358979323846_wp, TWO_PI = 2 * PI
  !> 2 pi split so that n * TWO_PI_HI is exact for |n| < 2**22 (Cody-Waite reduction).
  real(wp), parameter :: TWO_PI_HI = 6.28318530693650245668_wp
  real(wp), parameter :: TWO_PI_LO = 2.430840202602476899728e-10_wp

  type, extends(element_t) :: beam_t
    real(wp) :: l0 = 1.0_wp          !< undeformed length [m]
    real(wp) :: alpha0 = 0.0_wp      !< undeformed chord angle [rad]
    real(wp) :: phi0(2) = 0.0_wp     !< nodal rotations in the undeformed state [rad]
    real(wp) :: ea = 0.0_wp, ei = 0.0_wp, rho_a = 0.0_wp
    real(wp) :: shear_p = 0.0_wp     !< 12 EI / (k G A l0^2); 0 = Euler-Bernoulli
    integer :: bending = BENDING_ANGLE
    logical :: consistent = .true.   !< consistent (deformation-dependent) or lumped mass
  contains
    procedure :: evaluate => beam_evaluate
    procedure :: second => beam_second
    procedure :: second_many => beam_second_many
    procedure :: convective_many => beam_convective_many
    procedure :: stiffness => beam_stiffness
    procedure, nopass :: type_name => beam_type_name
    procedure :: has_inertia => beam_has_inertia
    procedure :: inertia => beam_inertia
    procedure :: second_inertia => beam_second_inertia
    procedure :: weight => beam_weight
    procedure :: lumped_mass => beam_lumped_mass
  end type beam_t

  !> Chord geometry and tangent rotations shared by all evaluations; rl = 1 / l, since a
  !> division costs several products' time and the kernels divide by l often.
  type :: chord_t
    real(wp) :: lv(2), l, rl, el(2), nl(2), theta(2)
  end type chord_t

contains

  !> One atan2 for the chord angle beta instead of one atan2 and one sincos per node: theta_k
  !> = a_k - beta, a_k = alpha0 + phi_k - phi_k0, wrapped into (-pi, pi] as atan2 did.
  pure function chord(this, x) result(c)
    class(beam_t), intent(in) :: this
    real(wp), intent(in) :: x(6)
    type(chord_t) :: c
    real(wp) :: beta
    integer :: k
    c = chord_lengths(x)
    beta = atan2(c%lv(2), c%lv(1))
    do k = 1, 2
      ! Reducing a_k before subtracting beta keeps the rounding at the size of theta, not of a_k.
      c%theta(k) = wrap_angle(wrap_angle(this%alpha0 + x(3 * k) - this%phi0(k)) - beta)
    end do
  end function chord

  !> The chord's vector, length and directions (theta left to the caller).
  pure function chord_lengths(x) result(c)
    real(wp), intent(in) :: x(6)
    type(chord_t) :: c
    c%lv = x(4:5) - x(1:2)
    ! Element lengths are far from overflow: no need for norm2's scaling.
    c%l = sqrt(c%lv(1)**2 + c%lv(2)**2)
    c%rl = 1.0_wp / c%l
    c%el = c%lv * c%rl
    c%nl(1) = -c%el(2)
    c%nl(2) = c%el(1)
    c%theta = 0.0_wp
  end function chord_lengths

  !> a modulo 2 pi in (-pi, pi]. Nodal angles may have turned many times: the split 2 pi keeps
  !> the reduction exact, so theta is as accurate as with the former sin/cos + atan2.
  pure real(wp) function wrap_angle(a) result(r)
    real(wp), intent(in) :: a
    real(wp) :: n
    r = a
    if (abs(r) <= PI) return
    n = anint(r / TWO_PI)
    r = (r - n * TWO_PI_HI) - n * TWO_PI_LO
    if (r > PI) then
      r = r - TWO_PI
    else if (r <= -PI) then
      r = r + TWO_PI
    end if
  end function wrap_angle

  !> Bending measure g(theta) and its first two derivatives for the chosen form.
  pure subroutine bend_measure(this, theta, g, g1, g2)
    class(beam_t), intent(in) :: this
    real(wp), intent(in) :: theta
    real(wp), intent(out) :: g, g1, g2
    if (this%bending == BENDING_SINE) then
      g = sin(theta); g1 = cos(theta); g2 = -sin(theta)
    else
      g = theta; g1 = 1.0_wp; g2 = 0.0_wp
    end if
  end subroutine bend_measure

  pure subroutine beam_evaluate(this, x, e, de)
    class(beam_t), intent(in) :: this
    real(wp), intent(in) :: x(:)
    real(wp), intent(out) :: e(:), de(:, :)
    call modes(this, chord(this, x), e, de)
  end subroutine beam_evaluate

  !> e and de from the chord, shared by evaluate, inertia and weight.
  pure subroutine modes(this, c, e, de)
    class(beam_t), intent(in) :: this
    type(chord_t), intent(in) :: c
    real(wp), intent(out) :: e(3), de(3, 6)
    real(wp) :: g(2), g1(2), g2(2), nb(2), s2, s3, a2, a3, r30
    integer :: k, j
    do k = 1, 2
      call bend_measure(this, c%theta(k), g(k), g1(k), g2(k))
    end do
    ! theta_k = alpha0 + phi_k - phi_k0 - beta(chord); d beta / d x_q = nl / l
    nb = c%nl * c%rl
    s2 = this%l0 * g1(1)
    s3 = -this%l0 * g1(2)
    e(2) = this%l0 * g(1)
    e(3) = -this%l0 * g(2)
    ! Element-wise: array constructors into the assumed-shape de cost a temporary each.
    do j = 1, 2
      de(1, j) = -c%el(j)
      de(1, j + 3) = c%el(j)
      de(2, j) = s2 * nb(j)
      de(2, j + 3) = -s2 * nb(j)
      de(3, j) = s3 * nb(j)
      de(3, j + 3) = -s3 * nb(j)
    end do
    de(1, 3) = 0.0_wp; de(1, 6) = 0.0_wp
    de(2, 3) = s2; de(2, 6) = 0.0_wp
    de(3, 3) = 0.0_wp; de(3, 6) = s3
    e(1) = c%l - this%l0 + arc_term(this, e(2), e(3))
    r30 = 1.0_wp / (30 * this%l0)
    a2 = (4 * e(2) + e(3)) * r30
    a3 = (e(2) + 4 * e(3)) * r30
    do j = 1, 6
      de(1, j) = de(1, j) + a2 * de(2, j) + a3 * de(3, j)
    end do
  end subroutine modes

  pure real(wp) function arc_term(this, e2, e3)
    class(beam_t), intent(in) :: this
    real(wp), intent(in) :: e2, e3
    arc_term = (2 * e2**2 + e2 * e3 + 2 * e3**2) / (30 * this%l0)
  end function arc_term

  pure subroutine beam_second(this, x, v, d2e)
    class(beam_t), intent(in) :: this
    real(wp), intent(in) :: x(:), v(:)
    real(wp), intent(out) :: d2e(:)
    call second_modes(this, chord(this, x), v, d2e)
  end subroutine beam_second

  !> second along each column of v from one chord.
  pure subroutine beam_second_many(this, x, v, d2e)
    class(beam_t), intent(in) :: this
    real(wp), intent(in) :: x(:), v(:, :)
    real(wp), intent(out) :: d2e(:, :)
    type(chord_t) :: c
    integer :: col
    c = chord(this, x)
    do col = 1, size(v, 2)
      call second_modes(this, c, v(:, col), d2e(:, col))
    end do
  end subroutine beam_second_many

  !> The convective forces h along each column of xd from one chord (no mass matrices).
  pure subroutine beam_convective_many(this, x, xd, h)
    class(beam_t), intent(in) :: this
    real(wp), intent(in) :: x(:), xd(:, :)
    real(wp), intent(out) :: h(:, :)
    type(chord_t) :: c
    real(wp) :: d2e(3)
    integer :: col
    if (.not. this%has_inertia()) then
      h = 0.0_wp
      return
    end if
    c = chord(this, x)
    do col = 1, size(xd, 2)
      call second_modes(this, c, xd(:, col), d2e)
      call convective_at(this, c, xd(:, col), d2e, h(:, col))
    end do
  end subroutine beam_convective_many

  !> d2e along v from the chord, shared by second and inertia.
  pure subroutine second_modes(this, c, v, d2e)
    class(beam_t), intent(in) :: this
    type(chord_t), intent(in) :: c
    real(wp), intent(in) :: v(6)
    real(wp), intent(out) :: d2e(3)
    real(wp) :: dv(2), a, b, d2beta, g, g1, g2, dth, de(3), e(3)
    integer :: k
    dv = v(4:5) - v(1:2)
    a = dot_product(c%el, dv)
    b = dot_product(c%nl, dv)
    d2beta = -2 * a * b * c%rl**2
    do k = 1, 2
      call bend_measure(this, c%theta(k), g, g1, g2)
      dth = v(3 * k) - b * c%rl
      e(k + 1) = this%l0 * g
      de(k + 1) = this%l0 * g1 * dth
      d2e(k + 1) = this%l0 * (g1 * (-d2beta) + g2 * dth**2)
    end do
    e(3) = -e(3); de(3) = -de(3); d2e(3) = -d2e(3)
    d2e(1) = (dot_product(dv, dv) - a**2) * c%rl &
      + ((4 * e(2) + e(3)) * d2e(2) + (e(2) + 4 * e(3)) * d2e(3) &
         + 4 * de(2)**2 + 2 * de(2) * de(3) + 4 * de(3)**2) / (30 * this%l0)
  end subroutine second_modes

  pure subroutine beam_stiffness(this, s)
    class(beam_t), intent(in) :: this
    real(wp), intent(out) :: s(:, :)
    real(wp) :: p, kb
    p = this%shear_p
    kb = this%ei / (this%l0**3 * (1 + p))
    ! Entry by entry (s is 3 x 3): a whole-array zeroing costs a library call per evaluation.
    s(1, 1) = this%ea / this%l0
    s(2, 1) = 0.0_wp
    s(3, 1) = 0.0_wp
    s(1, 2) = 0.0_wp
    s(1, 3) = 0.0_wp
    s(2, 2) = kb * (4 + p)
    s(3, 3) = s(2, 2)
    s(2, 3) = -kb * (2 - p)
    s(3, 2) = s(2, 3)
  end subroutine beam_stiffness

  pure logical function beam_has_inertia(this)
    class(beam_t), intent(in) :: this
    beam_has_inertia = this%consistent .and. this%rho_a > 0
  end function beam_has_inertia

  pure subroutine beam_lumped_mass(this, diag)
    class(beam_t), intent(in) :: this
    real(wp), intent(out) :: diag(:)
    diag = 0.0_wp
    if (this%consistent) return
    diag([1, 2, 4, 5]) = this%rho_a * this%l0 / 2
    ! Rotary inertia of each half about its node, so that the bending modes keep a mass.
    diag([3, 6]) = this%rho_a * this%l0**3 / 24
  end subroutine beam_lumped_mass

  !> Mass matrix and convective force of the material point r(xi) = x_p + xi lv + c u, with
  !> u = perp(lv) and c = (H2 e2 - H4 e3) / l0 (cubic Hermite bending shape scaled with the
  !> current chord). Its Jacobian is J = A(xi, c) + u dc^T with the 2x2 blocks
  !> A_p = (1 - xi) I - c P, A_q = xi I + c P (P = perp), so that
  !>   J^T J = A^T A + A^T u dc^T + dc u^T A + |lv|^2 dc dc^T,
  !> A_p^T A_p = ((1 - xi)^2 + c^2) I, A_p^T A_q = ((1 - xi) xi - c^2) I + c P,
  !> A_q^T A_q = (xi^2 + c^2) I, A_p^T u = (1 - xi) u - c lv, A_q^T u = xi u + c lv.
  !> c, dc, d2c are linear in (H2, H4): every Gauss sum is a moment M_* times mode quantities.
  pure subroutine beam_inertia(this, x, xd, m, h)
    class(beam_t), intent(in) :: this
    real(wp), intent(in) :: x(:), xd(:)
    real(wp), intent(out) :: m(:, :), h(:)
    type(chord_t) :: c
    real(wp) :: d2e(3)
    if (.not. this%has_inertia()) then
      m = 0.0_wp
      h = 0.0_wp
      return
    end if
    c = chord(this, x)
    call second_modes(this, c, xd, d2e)
    call inertia_at(this, c, xd, d2e, m, h)
  end subroutine beam_inertia

  !> second and inertia from one chord (the evaluation's pass over the elements). With the
  !> mode values e at x and the angle form of bending, the tangent rotations are e2 / l0 and
  !> -e3 / l0: the chord then needs no atan2 (a latency of tens of cycles per element).
  pure subroutine beam_second_inertia(this, x, xd, d2e, m, h, e)
    class(beam_t), intent(in) :: this
    real(wp), intent(in) :: x(:), xd(:)
    real(wp), intent(out) :: d2e(:), m(:, :), h(:)
    real(wp), intent(in), optional :: e(:)
    type(chord_t) :: c
    real(wp) :: rl0
    if (present(e) .and. this%bending == BENDING_ANGLE) then
      c = chord_lengths(x)
      rl0 = 1.0_wp / this%l0
      c%theta(1) = e(2) * rl0
      c%theta(2) = -e(3) * rl0
    else
      c = chord(this, x)
    end if
    call second_modes(this, c, xd, d2e)
    if (this%has_inertia()) then
      call inertia_at(this, c, xd, d2e, m, h)
    else
      m = 0.0_wp
      h = 0.0_wp
    end if
  end subroutine beam_second_inertia

  !> The body of beam_inertia at the chord c, with d2e = second_modes along xd.
  !> The bending rows of de are d2 = de(2, :) / l0 = a w2 and d3 = de(3, :) / l0 = b w3 with
  !> w2 = (n, 1, -n, 0), w3 = (n, 0, -n, 1), n = nl / l: every vector of the closed form is
  !> (gamma n, alpha, -gamma n, beta), so each 2x2 block of M is a few 2-vectors times n and the
  !> 21 entries of the upper triangle are written out (no 6x6 outer products).
  pure subroutine inertia_at(this, c, xd, d2e, m, h)
    class(beam_t), intent(in) :: this
    type(chord_t), intent(in) :: c
    ! Explicit shapes: constant strides, where assumed shapes cost an index computation per
    ! access (the callers' arrays are contiguous, so they pass without a copy).
    real(wp), intent(in) :: xd(6), d2e(3)
    real(wp), intent(out) :: m(6, 6), h(6)
    real(wp) :: g(2), g1(2), g2(2), a, b, e2, e3, n(2)
    real(wp) :: u(2), ll, sc, scc, k2, k4, rho_l, t3, t6, tt
    real(wp) :: gp2, gp4, gq2, gq4, gc2, gc4, ap(2), aq(2)
    real(wp) :: mm(6, 6), cpp, cqq, cpq(2, 2)
    integer :: i, j, k
    do k = 1, 2
      call bend_measure(this, c%theta(k), g(k), g1(k), g2(k))
    end do
    ! c(xi) = H2 e2 - H4 e3 etc. with the 1 / l0 of c folded in.
    e2 = g(1); e3 = -g(2)
    a = g1(1); b = -g1(2)
    n = c%nl * c%rl
    u = perp(c%lv)
    ll = dot_product(c%lv, c%lv)
    ! sum w c, sum w c^2 and sum w c H2, sum w c H4 (k2, k4)
    sc = e2 * M_2 - e3 * M_4
    k2 = e2 * M_22 - e3 * M_24
    k4 = e2 * M_24 - e3 * M_44
    scc = e2 * k2 - e3 * k4
    ! The (alpha, beta) of sum w (1 - xi) dc, sum w xi dc and sum w c dc; gamma = alpha + beta.
    gp2 = M_P2 * a; gp4 = -M_P4 * b
    gq2 = M_X2 * a; gq4 = -M_X4 * b
    gc2 = k2 * a; gc4 = -k4 * b
    ! B = sum w A^T u dc^T: its translation rows are ap n^T, the rotation columns u and lv
    ! times alpha, beta (rows 3 and 6 vanish: A has no rotation columns).
    ap = (gp2 + gp4) * u - (gc2 + gc4) * c%lv
    aq = (gq2 + gq4) * u + (gc2 + gc4) * c%lv
    ! |lv|^2 sum w dc dc^T: tt n n^T on the translations, t3 n and t6 n beside them.
    t3 = ll * a * (M_22 * a - M_24 * b)
    t6 = ll * b * (M_44 * b - M_24 * a)
    tt = t3 + t6
    ! The configuration-independent moments and the sums of c on the translation blocks.
    cpp = M_PP + scc
    cqq = M_XX + scc
    cpq(:, 1) = [M_PX - scc, sc]
    cpq(:, 2) = [-sc, M_PX - scc]
    ! Both triangles written here: the scaling below is then one whole-array product.
    do j = 1, 2
      do i = 1, 2
        ! Symmetric bit for bit: sums and products of two operands commute exactly.
        mm(i, j) = ap(i) * n(j) + ap(j) * n(i) + tt * (n(i) * n(j))
        mm(i + 3, j + 3) = -aq(i) * n(j) - aq(j) * n(i) + tt * (n(i) * n(j))
        mm(i, j + 3) = aq(j) * n(i) - ap(i) * n(j) - tt * n(i) * n(j) + cpq(i, j)
        mm(j + 3, i) = mm(i, j + 3)
      end do
      mm(j, j) = mm(j, j) + cpp
      mm(j + 3, j + 3) = mm(j + 3, j + 3) + cqq
      mm(j, 3) = gp2 * u(j) - gc2 * c%lv(j) + t3 * n(j)
      mm(j, 6) = gp4 * u(j) - gc4 * c%lv(j) + t6 * n(j)
      mm(3, j + 3) = gq2 * u(j) + gc2 * c%lv(j) - t3 * n(j)
      mm(j + 3, 6) = gq4 * u(j) + gc4 * c%lv(j) - t6 * n(j)
      mm(3, j) = mm(j, 3)
      mm(6, j) = mm(j, 6)
      mm(j + 3, 3) = mm(3, j + 3)
      mm(6, j + 3) = mm(j + 3, 6)
    end do
    mm(3, 3) = ll * M_22 * a**2
    mm(3, 6) = -ll * M_24 * a * b
    mm(6, 3) = mm(3, 6)
    mm(6, 6) = ll * M_44 * b**2
    rho_l = this%rho_a * this%l0
    m = rho_l * mm
    call convective_at(this, c, xd, d2e, h)
  end subroutine inertia_at

  !> The convective force h of inertia_at alone (a reduced model's expansion asks it along
  !> many velocities at one chord).
  pure subroutine convective_at(this, c, xd, d2e, h)
    class(beam_t), intent(in) :: this
    type(chord_t), intent(in) :: c
    real(wp), intent(in) :: xd(6), d2e(3)
    real(wp), intent(out) :: h(6)
    real(wp) :: g(2), g1(2), g2(2), a, b, e2, e3, f2, f3, v2, v3, dxn, n(2), u(2), pd(2)
    real(wp) :: k2, k4, s2, s4, rho_l, sg2, sg3, hb, r2(2), r4(2), rc(2)
    integer :: k
    do k = 1, 2
      call bend_measure(this, c%theta(k), g(k), g1(k), g2(k))
    end do
    e2 = g(1); e3 = -g(2)
    a = g1(1); b = -g1(2)
    n = c%nl * c%rl
    f2 = d2e(2) / this%l0; f3 = d2e(3) / this%l0
    u = perp(c%lv)
    k2 = e2 * M_22 - e3 * M_24
    k4 = e2 * M_24 - e3 * M_44
    rho_l = this%rho_a * this%l0
    ! d2r(xi) = d2c u + 2 (dc . xd) perp(dlv) = H2 r2 - H4 r4, pd = perp(dlv)
    pd(1) = xd(2) - xd(5)
    pd(2) = xd(4) - xd(1)
    dxn = n(1) * (xd(1) - xd(4)) + n(2) * (xd(2) - xd(5))
    v2 = a * (dxn + xd(3))
    v3 = b * (dxn + xd(6))
    r2 = f2 * u + 2 * v2 * pd
    r4 = f3 * u + 2 * v3 * pd
    ! h = sum w (A^T d2r + dc (u . d2r)): sums of (1 - xi) d2r, xi d2r, c d2r, then the dc part
    rc = k2 * r2 - k4 * r4
    s2 = dot_product(u, r2)
    s4 = dot_product(u, r4)
    sg2 = a * (M_22 * s2 - M_24 * s4)
    sg3 = b * (M_44 * s4 - M_24 * s2)
    hb = sg2 + sg3
    h(1:2) = rho_l * (M_P2 * r2 - M_P4 * r4 + perp(rc) + hb * n)
    h(3) = rho_l * sg2
    h(4:5) = rho_l * (M_X2 * r2 - M_X4 * r4 - perp(rc) - hb * n)
    h(6) = rho_l * sg3
  end subroutine convective_at

  pure function perp(a) result(p)
    real(wp), intent(in) :: a(2)
    real(wp) :: p(2)
    p(1) = -a(2)
    p(2) = a(1)
  end function perp

  !> Gravity on the material points of beam_inertia: f = sum w J^T g, V = -sum w g . r.
  pure subroutine beam_weight(this, x, g, f, potential)
    class(beam_t), intent(in) :: this
    real(wp), intent(in) :: x(:), g(:)
    real(wp), intent(out) :: f(:), potential
    type(chord_t) :: c
    real(wp) :: e(3), de(3, 6), sc, u(2), pg(2), gu, rho_l, g2(2)
    f = 0.0_wp
    potential = 0.0_wp
    if (.not. this%has_inertia()) return
    g2 = g(1:2)
    c = chord(this, x)
    call modes(this, c, e, de)
    sc = (e(2) * M_2 - e(3) * M_4) / this%l0
    u = perp(c%lv)
    pg = perp(g2)
    gu = dot_product(g2, u)
    rho_l = this%rho_a * this%l0
    f(1:2) = M_P * g2 + sc * pg
    f(3) = 0.0_wp
    f(4:5) = M_X * g2 - sc * pg
    f(6) = 0.0_wp
    f = rho_l * (f + gu * (M_2 * de(2, :) - M_4 * de(3, :)) / this%l0)
    potential = -rho_l * (M_1 * dot_product(g2, x(1:2)) + M_X * dot_product(g2, c%lv) &
      + sc * gu)
  end subroutine beam_weight

  pure function beam_type_name() result(name)
    character(len=:), allocatable :: name
    name = 'beam'
  end function beam_type_name
end module elements_beam
