!> Truss in the plane (dim = 2, the default) or in space (dim = 3): one mode, the elongation
!> e1 = l - l0. Coordinates x = (xp, yp, [zp], xq, yq, [zq]), dim per node.
!> Its consistent mass (linear interpolation) is constant, so it is passed on as a lumped
!> diagonal only when lumping is asked for; otherwise as a constant full matrix.
module elements_truss
  use core_kinds, only: wp
  use elements_base, only: element_t
  implicit none
  private
  public :: truss_t

  type, extends(element_t) :: truss_t
    integer :: dim = 2             !< components per node: 2 (planar) or 3 (spatial)
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
    real(wp) :: lv(this%dim), l
    integer :: n
    n = this%dim
    lv = x(n + 1:2 * n) - x(1:n)
    l = norm2(lv)
    e(1) = l - this%l0
    de(1, :) = [-lv / l, lv / l]
  end subroutine truss_evaluate

  pure subroutine truss_second(this, x, v, d2e)
    class(truss_t), intent(in) :: this
    real(wp), intent(in) :: x(:), v(:)
    real(wp), intent(out) :: d2e(:)
    real(wp) :: lv(this%dim), dv(this%dim), l
    integer :: n
    n = this%dim
    lv = x(n + 1:2 * n) - x(1:n)
    dv = v(n + 1:2 * n) - v(1:n)
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
    integer :: i, n
    m = 0.0_wp
    h = 0.0_wp
    if (.not. this%has_inertia()) return
    n = this%dim
    do i = 1, n
      m(i, i) = this%rho_a * this%l0 / 3
      m(i + n, i + n) = this%rho_a * this%l0 / 3
      m(i, i + n) = this%rho_a * this%l0 / 6
      m(i + n, i) = this%rho_a * this%l0 / 6
    end do
  end subroutine truss_inertia

  pure subroutine truss_weight(this, x, g, f, potential)
    class(truss_t), intent(in) :: this
    real(wp), intent(in) :: x(:), g(:)
    real(wp), intent(out) :: f(:), potential
    integer :: n
    f = 0.0_wp
    potential = 0.0_wp
    if (.not. this%has_inertia()) return
    ! The first dim components of gravity: a planar truss ignores a z component.
    n = this%dim
    f = this%rho_a * this%l0 / 2 * [g(1:n), g(1:n)]
    potential = -this%rho_a * this%l0 * dot_product(g(1:n), (x(1:n) + x(n + 1:2 * n)) / 2)
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
