!> Planar hinge: one mode, the relative rotation e1 = (phi_q - phi_q0) - (phi_p - phi_p0).
!> Coordinates x = (phi_p, phi_q). Dynamic hinges are torsion springs of stiffness k.
module elements_hinge
  use core_kinds, only: wp
  use elements_base, only: element_t
  implicit none
  private
  public :: hinge_t

  type, extends(element_t) :: hinge_t
    real(wp) :: phi0(2) = 0.0_wp   !< rotations in the reference state [rad]
    real(wp) :: k = 0.0_wp         !< torsion stiffness [N m / rad]
  contains
    procedure :: evaluate => hinge_evaluate
    procedure :: second => hinge_second
    procedure :: stiffness => hinge_stiffness
    procedure, nopass :: type_name => hinge_type_name
  end type hinge_t

contains

  pure subroutine hinge_evaluate(this, x, e, de)
    class(hinge_t), intent(in) :: this
    real(wp), intent(in) :: x(:)
    real(wp), intent(out) :: e(:), de(:, :)
    e(1) = (x(2) - this%phi0(2)) - (x(1) - this%phi0(1))
    de(1, :) = [-1.0_wp, 1.0_wp]
  end subroutine hinge_evaluate

  pure subroutine hinge_second(this, x, v, d2e)
    class(hinge_t), intent(in) :: this
    real(wp), intent(in) :: x(:), v(:)
    real(wp), intent(out) :: d2e(:)
    d2e = 0.0_wp
  end subroutine hinge_second

  pure subroutine hinge_stiffness(this, s)
    class(hinge_t), intent(in) :: this
    real(wp), intent(out) :: s(:, :)
    s(1, 1) = this%k
  end subroutine hinge_stiffness
  pure function hinge_type_name() result(name)
    character(len=:), allocatable :: name
    name = 'hinge'
  end function hinge_type_name
end module elements_hinge
