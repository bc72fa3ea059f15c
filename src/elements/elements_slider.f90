!> Slider (prismatic joint of a point on a straight guide), planar or spatial: the distances
!> of a node from the line through its reference position x_ref along the unit `direction` d,
!> e_k = n_k . (x - x_ref). In the plane one mode, n = (-d_y, d_x); in space two, along unit
!> normals n_1, n_2 = d x n_1. Coordinates x = (x, y) or (x, y, z). The modes are linear in
!> x, so their second derivatives vanish. A dynamic slider is a linear guide spring of
!> stiffness k [N/m] across the guide (each normal); a slider leaves the node's rotation free
!> (a prismatic joint on a body also needs the body's rotation held, e.g. fix_phi).
module elements_slider
  use core_kinds, only: wp
  use elements_base, only: element_t
  use elements_rotation, only: cross, unit_normal
  implicit none
  private
  public :: slider_t

  type, extends(element_t) :: slider_t
    real(wp), allocatable :: x_ref(:)              !< a point of the guide (dim) [m]
    !> Unit normals of the guide (dim, dim - 1); set_direction fills them.
    real(wp), allocatable :: normal(:, :)
    real(wp) :: k = 0.0_wp                         !< stiffness across the guide [N/m]
  contains
    procedure :: evaluate => slider_evaluate
    procedure :: second => slider_second
    procedure :: stiffness => slider_stiffness
    procedure, nopass :: type_name => slider_type_name
    procedure :: set_direction => slider_set_direction
  end type slider_t

contains

  !> Guide along `direction` (2 or 3 values, any length > 0; the caller refuses a zero
  !> vector). In space n_1 is orthogonalised from the coordinate axis least aligned with d.
  pure subroutine slider_set_direction(this, direction)
    class(slider_t), intent(inout) :: this
    real(wp), intent(in) :: direction(:)
    real(wp) :: d(3), t(3)
    if (size(direction) == 2) then
      this%normal = reshape([-direction(2), direction(1)] / norm2(direction), [2, 1])
      return
    end if
    d = direction / norm2(direction)
    t = unit_normal(d)
    this%normal = reshape([t, cross(d, t)], [3, 2])
  end subroutine slider_set_direction

  pure subroutine slider_evaluate(this, x, e, de)
    class(slider_t), intent(in) :: this
    real(wp), intent(in) :: x(:)
    real(wp), intent(out) :: e(:), de(:, :)
    integer :: k, n
    n = size(this%x_ref)
    do k = 1, size(e)
      e(k) = dot_product(this%normal(:, k), x(1:n) - this%x_ref)
      de(k, :) = this%normal(:, k)
    end do
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
    integer :: k
    s = 0.0_wp
    do k = 1, size(s, 1)
      s(k, k) = this%k
    end do
  end subroutine slider_stiffness

  pure function slider_type_name() result(name)
    character(len=:), allocatable :: name
    name = 'slider'
  end function slider_type_name
end module elements_slider
