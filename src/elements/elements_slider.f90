!> Planar slider (prismatic joint of a point on a straight guide): one mode, the distance of a
!> node from the line through its reference position x_ref along the unit `direction` d,
!> e1 = n . (x - x_ref) with n = (-d_y, d_x) the guide's unit normal. Coordinates x = (x, y).
!> The mode is linear in x, so its second derivative vanishes. A dynamic slider is a linear
!> guide spring of stiffness k [N/m] across the guide; a slider leaves the node's rotation
!> free (a prismatic joint on a body also needs the body's rotation held, e.g. fix_phi).
module elements_slider
  use core_kinds, only: wp
  use elements_base, only: element_t
  implicit none
  private
  public :: slider_t

  type, extends(element_t) :: slider_t
    real(wp) :: x_ref(2) = 0.0_wp                  !< a point of the guide [m]
    real(wp) :: normal(2) = [0.0_wp, 1.0_wp]       !< unit normal of the guide (guide along x)
    real(wp) :: k = 0.0_wp                         !< stiffness across the guide [N/m]
  contains
    procedure :: evaluate => slider_evaluate
    procedure :: second => slider_second
    procedure :: stiffness => slider_stiffness
    procedure, nopass :: type_name => slider_type_name
    procedure :: set_direction => slider_set_direction
  end type slider_t

contains

  !> Guide along `direction` (any length > 0; the caller refuses a zero vector).
  pure subroutine slider_set_direction(this, direction)
    class(slider_t), intent(inout) :: this
    real(wp), intent(in) :: direction(2)
    this%normal = [-direction(2), direction(1)] / norm2(direction)
  end subroutine slider_set_direction

  pure subroutine slider_evaluate(this, x, e, de)
    class(slider_t), intent(in) :: this
    real(wp), intent(in) :: x(:)
    real(wp), intent(out) :: e(:), de(:, :)
    e(1) = dot_product(this%normal, x(1:2) - this%x_ref)
    de(1, :) = this%normal
  end subroutine slider_evaluate

  pure subroutine slider_second(this, x, v, d2e)
    class(slider_t), intent(in) :: this
    real(wp), intent(in) :: x(:), v(:)
    real(wp), intent(out) :: d2e(:)
    d2e = 0.0_wp
  end subroutine slider_second

  pure subroutine slider_stiffness(this, s)
    class(slider_t), intent(in) :: this
    real(wp), intent(out) :: s(:, :)
    s(1, 1) = this%k
  end subroutine slider_stiffness

  pure function slider_type_name() result(name)
    character(len=:), allocatable :: name
    name = 'slider'
  end function slider_type_name
end module elements_slider
