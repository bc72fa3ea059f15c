!> Planar truss: one mode, the elongation e1 = l - l0. Coordinates x = (xp, yp, xq, yq).
!> Its consistent mass (linear interpolation) is constant, so it is passed on as a lumped
!> diagonal only when lumping is asked for; otherwise as a constant full matrix.
module elements_truss
  use core_kinds, only: wp
  use elements_base, only: element_t
  implicit none
  private
  public :: truss_t

  type, extends(element_t) :: truss_t
    real(wp) :: l0 = 1.0_wp
    real(wp) :: ea = 0.0_wp, rho_a = 0.0_wp
    logical :: consistent = .true.
  contains
    procedure :: evaluate => truss_evaluate
    procedure :: second => truss_second
    procedure :: stiffness => truss_stiffness
    procedure, nopass :: type_name => truss_type_name
    procedure :: has_inertia => truss_has_inertia
    procedure :: inertia => truss_inertia
    procedure :: weight => truss_weight
    procedure :: lumped_mass => truss_lumped_mass
  end type truss_t

contains

  pure subroutine truss_evaluate(this, x, e, de)
    class(truss_t), intent(in) :: this
    real(wp), intent(in) :: x(:)
    real(wp), intent(out) :: e(:), de(:, :)
    real(wp) :: lv(2), l
    lv = x(3:4) - x(1:2)
    l = norm2(lv)
    e(1) = l - this%l0
    de(1, :) = [-lv / l, lv / l]
  end subroutine truss_evaluate

  pure subroutine truss_second(this, x, v, d2e)
    class(truss_t), intent(in) :: this
    real(wp), intent(in) :: x(:), v(:)
    real(wp), intent(out) :: d2e(:)
    real(wp) :: lv(2), dv(2), l
    lv = x(3:4) - x(1:2)
    dv = v(3:4) - v(1:2)
    l = norm2(lv)
    d2e(1) = (dot_product(dv, dv) - (dot_product(lv, dv) / l)**2) / l
  end subroutine truss_second

  pure subroutine truss_stiffness(this, s)
    class(truss_t), intent(in) :: this
    real(wp), intent(out) :: s(:, :)
    s(1, 1) = this%ea / this%l0
  end subroutine truss_stiffness

  pure logical function truss_has_inertia(this)
    class(truss_t), intent(in) :: this
    truss_has_inertia = this%consistent .and. this%rho_a > 0
  end function truss_has_inertia

  pure subroutine truss_inertia(this, x, xd, m, h)
    class(truss_t), intent(in) :: this
    real(wp), intent(in) :: x(:), xd(:)
    real(wp), intent(out) :: m(:, :), h(:)
    integer :: i
    m = 0.0_wp
    h = 0.0_wp
    if (.not. this%has_inertia()) return
    do i = 1, 2
      m(i, i) = this%rho_a * this%l0 / 3
      m(i + 2, i + 2) = this%rho_a * this%l0 / 3
      m(i, i + 2) = this%rho_a * this%l0 / 6
      m(i + 2, i) = this%rho_a * this%l0 / 6
    end do
  end subroutine truss_inertia

  pure subroutine truss_weight(this, x, g, f, potential)
    class(truss_t), intent(in) :: this
    real(wp), intent(in) :: x(:), g(:)
    real(wp), intent(out) :: f(:), potential
    f = 0.0_wp
    potential = 0.0_wp
    if (.not. this%has_inertia()) return
    ! A planar element: the first two components of gravity.
    f = this%rho_a * this%l0 / 2 * [g(1:2), g(1:2)]
    potential = -this%rho_a * this%l0 * dot_product(g(1:2), (x(1:2) + x(3:4)) / 2)
  end subroutine truss_weight

  pure subroutine truss_lumped_mass(this, diag)
    class(truss_t), intent(in) :: this
    real(wp), intent(out) :: diag(:)
    diag = 0.0_wp
    if (.not. this%consistent) diag = this%rho_a * this%l0 / 2
  end subroutine truss_lumped_mass
  pure function truss_type_name() result(name)
    character(len=:), allocatable :: name
    name = 'truss'
  end function truss_type_name
end module elements_truss
