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
    procedure :: stiffness => beam_stiffness
    procedure, nopass :: type_name => beam_type_name
    procedure :: has_inertia => beam_has_inertia
    procedure :: inertia => beam_inertia
    procedure :: weight => beam_weight
    procedure :: lumped_mass => beam_lumped_mass
  end type beam_t

  !> Chord geometry and tangent rotations shared by all evaluations.
  type :: chord_t
    real(wp) :: lv(2), l, el(2), nl(2), theta(2)
  end type chord_t

contains

  pure function chord(this, x) result(c)
    class(beam_t), intent(in) :: this
    real(wp), intent(in) :: x(6)
    type(chord_t) :: c
    real(wp) :: a, t(2)
    integer :: k
    c%lv = x(4:5) - x(1:2)
    c%l = norm2(c%lv)
    c%el = c%lv / c%l
    c%nl = [-c%el(2), c%el(1)]
    do k = 1, 2
      a = this%alpha0 + x(3 * k) - this%phi0(k)
      t = [cos(a), sin(a)]
      c%theta(k) = atan2(c%el(1) * t(2) - c%el(2) * t(1), dot_product(c%el, t))
    end do
  end function chord

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
    type(chord_t) :: c
    real(wp) :: g(2), g1(2), g2(2), dtheta(6, 2)
    integer :: k
    c = chord(this, x)
    do k = 1, 2
      call bend_measure(this, c%theta(k), g(k), g1(k), g2(k))
      ! theta_k = alpha0 + phi_k - phi_k0 - beta(chord); d beta / d x_q = nl / l
      dtheta(:, k) = [c%nl / c%l, 0.0_wp, -c%nl / c%l, 0.0_wp]
      dtheta(3 * k, k) = 1.0_wp
    end do
    e(2) = this%l0 * g(1)
    e(3) = -this%l0 * g(2)
    de(2, :) = this%l0 * g1(1) * dtheta(:, 1)
    de(3, :) = -this%l0 * g1(2) * dtheta(:, 2)
    e(1) = c%l - this%l0 + arc_term(this, e(2), e(3))
    de(1, :) = [-c%el, 0.0_wp, c%el, 0.0_wp] &
      + ((4 * e(2) + e(3)) * de(2, :) + (e(2) + 4 * e(3)) * de(3, :)) / (30 * this%l0)
  end subroutine beam_evaluate

  pure real(wp) function arc_term(this, e2, e3)
    class(beam_t), intent(in) :: this
    real(wp), intent(in) :: e2, e3
    arc_term = (2 * e2**2 + e2 * e3 + 2 * e3**2) / (30 * this%l0)
  end function arc_term

  pure subroutine beam_second(this, x, v, d2e)
    class(beam_t), intent(in) :: this
    real(wp), intent(in) :: x(:), v(:)
    real(wp), intent(out) :: d2e(:)
    type(chord_t) :: c
    real(wp) :: dv(2), a, b, d2beta, g, g1, g2, dth, de(3), e(3)
    integer :: k
    c = chord(this, x)
    dv = v(4:5) - v(1:2)
    a = dot_product(c%el, dv)
    b = dot_product(c%nl, dv)
    d2beta = -2 * a * b / c%l**2
    do k = 1, 2
      call bend_measure(this, c%theta(k), g, g1, g2)
      dth = v(3 * k) - b / c%l
      e(k + 1) = this%l0 * g
      de(k + 1) = this%l0 * g1 * dth
      d2e(k + 1) = this%l0 * (g1 * (-d2beta) + g2 * dth**2)
    end do
    e(3) = -e(3); de(3) = -de(3); d2e(3) = -d2e(3)
    d2e(1) = (dot_product(dv, dv) - a**2) / c%l &
      + ((4 * e(2) + e(3)) * d2e(2) + (e(2) + 4 * e(3)) * d2e(3) &
         + 4 * de(2)**2 + 2 * de(2) * de(3) + 4 * de(3)**2) / (30 * this%l0)
  end subroutine beam_second

  pure subroutine beam_stiffness(this, s)
    class(beam_t), intent(in) :: this
    real(wp), intent(out) :: s(:, :)
    real(wp) :: p, kb
    p = this%shear_p
    kb = this%ei / (this%l0**3 * (1 + p))
    s = 0.0_wp
    s(1, 1) = this%ea / this%l0
    s(2, 2) = kb * (4 + p)
    s(3, 3) = kb * (4 + p)
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

  !> Material point r(xi) = x_p + xi lv + c perp(lv), c = (H2 e2 - H4 e3) / l0 (cubic Hermite
  !> bending shape scaled with the current chord). Returns r, dr/dx (2, 6), and the gradient
  !> of c, needed for the second derivative.
  pure subroutine material_point(this, x, e, de, xi, r, jac, dc, cval)
    class(beam_t), intent(in) :: this
    real(wp), intent(in) :: x(6), e(3), de(3, 6), xi
    real(wp), intent(out) :: r(2), jac(2, 6), dc(6), cval
    real(wp) :: h2, h4, lv(2)
    h2 = xi - 2 * xi**2 + xi**3
    h4 = xi**3 - xi**2
    cval = (h2 * e(2) - h4 * e(3)) / this%l0
    dc = (h2 * de(2, :) - h4 * de(3, :)) / this%l0
    lv = x(4:5) - x(1:2)
    r = x(1:2) + xi * lv + cval * perp(lv)
    jac(:, 1) = [1 - xi, -cval]
    jac(:, 2) = [cval, 1 - xi]
    jac(:, 3) = 0.0_wp
    jac(:, 4) = [xi, cval]
    jac(:, 5) = [-cval, xi]
    jac(:, 6) = 0.0_wp
    jac = jac + spread(perp(lv), 2, 6) * spread(dc, 1, 2)
  end subroutine material_point

  pure function perp(a) result(p)
    real(wp), intent(in) :: a(2)
    real(wp) :: p(2)
    p = [-a(2), a(1)]
  end function perp

  pure subroutine beam_inertia(this, x, xd, m, h)
    class(beam_t), intent(in) :: this
    real(wp), intent(in) :: x(:), xd(:)
    real(wp), intent(out) :: m(:, :), h(:)
    real(wp) :: r(2), jac(2, 6), dc(6), cval, d2e(3), d2c, d2r(2), h2, h4, dlv(2), lv(2)
    real(wp) :: e(3), de(3, 6)
    integer :: i
    m = 0.0_wp
    h = 0.0_wp
    if (.not. this%has_inertia()) return
    call this%evaluate(x, e, de)
    call this%second(x, xd, d2e)
    lv = x(4:5) - x(1:2)
    dlv = xd(4:5) - xd(1:2)
    do i = 1, size(GAUSS_XI)
      call material_point(this, x, e, de, GAUSS_XI(i), r, jac, dc, cval)
      h2 = GAUSS_XI(i) - 2 * GAUSS_XI(i)**2 + GAUSS_XI(i)**3
      h4 = GAUSS_XI(i)**3 - GAUSS_XI(i)**2
      d2c = (h2 * d2e(2) - h4 * d2e(3)) / this%l0
      d2r = d2c * perp(lv) + 2 * dot_product(dc, xd) * perp(dlv)
      m = m + GAUSS_W(i) * matmul(transpose(jac), jac)
      h = h + GAUSS_W(i) * matmul(transpose(jac), d2r)
    end do
    m = this%rho_a * this%l0 * m
    h = this%rho_a * this%l0 * h
  end subroutine beam_inertia

  pure subroutine beam_weight(this, x, g, f, potential)
    class(beam_t), intent(in) :: this
    real(wp), intent(in) :: x(:), g(2)
    real(wp), intent(out) :: f(:), potential
    real(wp) :: r(2), jac(2, 6), dc(6), cval, e(3), de(3, 6)
    integer :: i
    f = 0.0_wp
    potential = 0.0_wp
    if (.not. this%has_inertia()) return
    call this%evaluate(x, e, de)
    do i = 1, size(GAUSS_XI)
      call material_point(this, x, e, de, GAUSS_XI(i), r, jac, dc, cval)
      f = f + GAUSS_W(i) * matmul(g, jac)
      potential = potential - GAUSS_W(i) * dot_product(g, r)
    end do
    f = this%rho_a * this%l0 * f
    potential = this%rho_a * this%l0 * potential
  end subroutine beam_weight
  pure function beam_type_name() result(name)
    character(len=:), allocatable :: name
    name = 'beam'
  end function beam_type_name
end module elements_beam
