!> The rotation vector of one spatial node's rotation: the hidden element that makes a free
!> node rotation (&node dynamic = 'rotation') three degrees of freedom. Coordinates x = lambda
!> (4), the node's Euler parameters relative to its reference orientation (1, 0, 0, 0); three
!> modes, the components of
!>   psi = 2 atan2(|lv|, l0) lv / |lv| = f(l0, |lv|^2) lv,
!> the logarithm of the rotation: a turn by |psi| about psi / |psi|. Like hinge3d's angle it is
!> scale-free (degree 0 in lambda), so the rigid normalisation (elements_euler) fixes |lambda|
!> and these modes the rest. psi covers every orientation once in the open ball |psi| < 2 pi
!> (l0 > 0 inside |psi| < pi); the map is singular only on the sphere |psi| = 2 pi, a full
!> turn, where lambda = -(1, 0, 0, 0) and the axis is undefined (docs/theory.md 2.7).
!>
!> The chart moves with the body: the modes are the rotation vector of mu = conj(lambda_r)
!> lambda, the rotation from a reference orientation lambda_r (at first the identity), and a
!> full model's run moves lambda_r to the node's orientation at an output time where |psi|
!> exceeds RECENTRE_ABOVE (recentre), so a body may spin without bound. mu = P lambda is
!> linear (P orthogonal), so the derivatives are those in mu times P.
!>
!> f and its partial derivatives in (l0, s2 = |lv|^2) are in closed form, those in l0 free of
!> any cancellation (f_0 = -2 / |lambda|^2); near lv = 0 (with l0 > 0) the ones in s2 lose
!> digits as 1 / s2 and are summed as series in u = s2 / l0^2, exact at lv = 0.
module elements_rotvec
  use core_kinds, only: wp
  use core_strings, only: approx_str
  use elements_base, only: element_t
  use elements_rotation, only: skew
  implicit none
  private
  public :: rotvec_t, ROTVEC_LIMIT, RECENTRE_ABOVE

  !> Largest |psi| a run may reach: at |psi| the transverse gain of the map from the
  !> rotation to psi is (|psi| / 2) / sin(|psi| / 2), 19 at 1.9 pi (and infinite at 2 pi),
  !> so the mass matrix in psi is at most ~360 times worse conditioned than in angles and the
  !> kinematic Newton loses ~1.3 digits; beyond, both degrade without bound.
  real(wp), parameter :: ROTVEC_LIMIT = 1.9_wp * 3.14159265358979323846_wp
  !> Beyond |psi| = pi / 2 at an output time the chart moves (the transverse gain is then 1.11
  !> at most): a body may turn 1.4 pi between two output times before it meets the limit, and
  !> a steady spin restarts the integrator at most once per quarter turn.
  real(wp), parameter :: RECENTRE_ABOVE = 0.5_wp * 3.14159265358979323846_wp
  !> Below u = s2 / l0^2 = 0.1 the s2-derivatives come from the series: their closed forms lose
  !> eps / u and eps / u^2 (at most 2e-14 at the switch), the series' 24 terms leave u^22.
  real(wp), parameter :: U_SERIES = 0.1_wp
  integer, parameter :: N_SERIES = 24
  !> Floors of |lambda|^2 and, relative to it, of s2 (only reached at lambda = 0 or within
  !> 1e-15 rad of a full turn, where the modes are singular anyway): they keep the results
  !> finite (f_ss ~ 1 / s2^2.5 stays below 1e130).
  real(wp), parameter :: R2_FLOOR = 1.0e-20_wp, S2_FLOOR = 1.0e-30_wp

  type, extends(element_t) :: rotvec_t
    !> The chart's reference orientation lambda_r (unit) and P, with mu = P lambda.
    real(wp) :: reference(4) = [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp]
    real(wp) :: p(4, 4) = reshape([1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, 1.0_wp, 0.0_wp, &
      0.0_wp, 0.0_wp, 0.0_wp, 1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, 1.0_wp], [4, 4])
  contains
    procedure :: evaluate => rotvec_evaluate
    procedure :: second => rotvec_second
    procedure :: stiffness => rotvec_stiffness
    procedure, nopass :: type_name => rotvec_type_name
    procedure :: has_limit => rotvec_has_limit
    procedure :: limit_problem => rotvec_limit_problem
    procedure :: recentre => rotvec_recentre
    procedure :: chart => rotvec_chart
    procedure :: set_chart => rotvec_set_chart
  end type rotvec_t

contains

  !> f(l0, s2) = 2 atan2(sqrt(s2), l0) / sqrt(s2) and its partial derivatives: d(1) = f,
  !> d(2) = f_0, d(3) = f_s, d(4) = f_00, d(5) = f_0s, d(6) = f_ss (s: d/ds2).
  pure function f_and_derivatives(l0, s2_in) result(d)
    real(wp), intent(in) :: l0, s2_in
    real(wp) :: d(6)
    real(wp) :: r2, s2, u, a(0:2), t
    integer :: k
    r2 = max(l0**2 + s2_in, R2_FLOOR)
    s2 = max(s2_in, S2_FLOOR * r2)
    d(2) = -2 / r2
    d(4) = 4 * l0 / r2**2
    d(5) = 2 / r2**2
    if (l0 > 0 .and. s2 < U_SERIES * l0**2) then
      ! A(u) = atan(sqrt(u)) / sqrt(u) = sum (-u)^k / (2k + 1) and its first two derivatives;
      ! f = 2 A / l0, f_s = 2 A' / l0^3, f_ss = 2 A'' / l0^5.
      u = s2_in / l0**2
      a = 0.0_wp
      do k = N_SERIES, 0, -1
        t = real(1 - 2 * mod(k, 2), wp) / (2 * k + 1)
        a(0) = a(0) * u + t
        if (k >= 1) a(1) = a(1) * u + k * t
        if (k >= 2) a(2) = a(2) * u + k * (k - 1) * t
      end do
      d(1) = 2 * a(0) / l0
      d(3) = 2 * a(1) / l0**3
      d(6) = 2 * a(2) / l0**5
    else
      d(1) = 2 * atan2(sqrt(s2), l0) / sqrt(s2)
      d(3) = (l0 / r2 - d(1) / 2) / s2
      d(6) = (-l0 / r2**2 - 1.5_wp * d(3)) / s2
    end if
  end function f_and_derivatives

  !> psi = f mv: dpsi/dm0 = f_0 mv, dpsi/dmv = f I + 2 f_s mv mv^T; dpsi/dlambda = that P.
  pure subroutine rotvec_evaluate(this, x, e, de)
    class(rotvec_t), intent(in) :: this
    real(wp), intent(in) :: x(:)
    real(wp), intent(out) :: e(:), de(:, :)
    real(wp) :: d(6), mu(4), dm(3, 4)
    integer :: i
    mu = matmul(this%p, x(1:4))
    d = f_and_derivatives(mu(1), dot_product(mu(2:4), mu(2:4)))
    e(1:3) = d(1) * mu(2:4)
    dm(:, 1) = d(2) * mu(2:4)
    dm(:, 2:4) = 2 * d(3) * spread(mu(2:4), 2, 3) * spread(mu(2:4), 1, 3)
    do i = 1, 3
      dm(i, i + 1) = dm(i, i + 1) + d(1)
    end do
    de(1:3, 1:4) = matmul(dm, this%p)
  end subroutine rotvec_evaluate

  !> Along w = P v = (w0, wv), with p = mv.wv: f' = f_0 w0 + 2 f_s p, f'' = f_00 w0^2
  !> + 4 f_0s w0 p + 4 f_ss p^2 + 2 f_s wv.wv, and psi'' = f'' mv + 2 f' wv.
  pure subroutine rotvec_second(this, x, v, d2e)
    class(rotvec_t), intent(in) :: this
    real(wp), intent(in) :: x(:), v(:)
    real(wp), intent(out) :: d2e(:)
    real(wp) :: d(6), p, f1, f2, mu(4), w(4)
    mu = matmul(this%p, x(1:4))
    w = matmul(this%p, v(1:4))
    d = f_and_derivatives(mu(1), dot_product(mu(2:4), mu(2:4)))
    p = dot_product(mu(2:4), w(2:4))
    f1 = d(2) * w(1) + 2 * d(3) * p
    f2 = d(4) * w(1)**2 + 4 * d(5) * w(1) * p + 4 * d(6) * p**2 &
      + 2 * d(3) * dot_product(w(2:4), w(2:4))
    d2e(1:3) = f2 * mu(2:4) + 2 * f1 * w(2:4)
  end subroutine rotvec_second

  !> No stiffness: a free rotation has no preferred orientation.
  pure subroutine rotvec_stiffness(this, s)
    class(rotvec_t), intent(in) :: this
    real(wp), intent(out) :: s(:, :)
    s = 0.0_wp
  end subroutine rotvec_stiffness

  pure function rotvec_type_name() result(name)
    character(len=:), allocatable :: name
    name = 'rotvec'
  end function rotvec_type_name

  pure logical function rotvec_has_limit(this)
    class(rotvec_t), intent(in) :: this
    rotvec_has_limit = .true.
  end function rotvec_has_limit

  !> The full-turn limit on the mode values e = psi (see ROTVEC_LIMIT).
  pure function rotvec_limit_problem(this, e) result(msg)
    class(rotvec_t), intent(in) :: this
    real(wp), intent(in) :: e(:)
    character(len=:), allocatable :: msg
    real(wp) :: a
    msg = ''
    a = norm2(e(1:3))
    if (a <= ROTVEC_LIMIT) return
    msg = this%label // ': the free rotation has turned ' // approx_str(a) // ' rad (' // &
      approx_str(a / (2 * 3.14159265358979323846_wp)) // ' turns) from its chart''s ' // &
      'reference orientation; its rotation-vector coordinates are singular at a full turn ' // &
      '(2 pi rad), so a run stops at 1.9 pi (5.97 rad). A full model''s run moves the ' // &
      'reference at output times: give output times closer together (&dynamic output_dt). ' &
      // 'A reduced model keeps its first reference: model a spin of more turns with a ' // &
      'hinge (&hinge type = ''spherical'' or ''revolute'' about the spin axis)'
  end function rotvec_limit_problem
  !> Beyond RECENTRE_ABOVE the reference becomes the orientation x itself (normalised), and
  !> P the left product with its conjugate: conj(r) lambda = P lambda.
  pure subroutine rotvec_recentre(this, x, e, moved)
    class(rotvec_t), intent(inout) :: this
    real(wp), intent(in) :: x(:), e(:)
    logical, intent(out) :: moved
    moved = norm2(e(1:3)) > RECENTRE_ABOVE
    if (moved) call this%set_chart(x(1:4) / norm2(x(1:4)))
  end subroutine rotvec_recentre

  pure function rotvec_chart(this) result(c)
    class(rotvec_t), intent(in) :: this
    real(wp), allocatable :: c(:)
    c = this%reference
  end function rotvec_chart

  !> (conj(r) lambda)_0 = r0 l0 + rv.lv, (conj(r) lambda)_v = r0 lv - l0 rv - rv x lv.
  pure subroutine rotvec_set_chart(this, c)
    class(rotvec_t), intent(inout) :: this
    real(wp), intent(in) :: c(:)
    integer :: i
    this%reference = c(1:4)
    this%p(1, 1) = c(1)
    this%p(1, 2:4) = c(2:4)
    this%p(2:4, 1) = -c(2:4)
    this%p(2:4, 2:4) = -skew(c(2:4))
    do i = 2, 4
      this%p(i, i) = this%p(i, i) + c(1)
    end do
  end subroutine rotvec_set_chart
end module elements_rotvec
