!> Normalisation of the Euler parameters of one spatial node: the single mode
!> e = lambda . lambda - 1, meant to be rigid, so that the homogeneous quadratic rotation
!> matrix of elements_rotation is a proper rotation. Coordinates x = lambda (4).
module elements_euler
  use core_kinds, only: wp
  use elements_base, only: element_t
  implicit none
  private
  public :: euler_norm_t

  !> One mode, no stiffness: only the rigid class makes sense for it.
  type, extends(element_t) :: euler_norm_t
  contains
    procedure :: evaluate => euler_evaluate
    procedure :: second => euler_second
    procedure :: stiffness => euler_stiffness
    procedure, nopass :: type_name => euler_type_name
  end type euler_norm_t

contains

  pure subroutine euler_evaluate(this, x, e, de)
    class(euler_norm_t), intent(in) :: this
    real(wp), intent(in) :: x(:)
    real(wp), intent(out) :: e(:), de(:, :)
    e(1) = dot_product(x(1:4), x(1:4)) - 1
    de(1, 1:4) = 2 * x(1:4)
  end subroutine euler_evaluate

  !> The mode is quadratic: its second directional derivative 2 v.v does not depend on x.
  pure subroutine euler_second(this, x, v, d2e)
    class(euler_norm_t), intent(in) :: this
    real(wp), intent(in) :: x(:), v(:)
    real(wp), intent(out) :: d2e(:)
    d2e(1) = 2 * dot_product(v(1:4), v(1:4))
  end subroutine euler_second

  pure subroutine euler_stiffness(this, s)
    class(euler_norm_t), intent(in) :: this
    real(wp), intent(out) :: s(:, :)
    s = 0.0_wp
  end subroutine euler_stiffness

  pure function euler_type_name() result(name)
    character(len=:), allocatable :: name
    name = 'euler'
  end function euler_type_name
end module elements_euler
