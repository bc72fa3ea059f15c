!> A rigid body on one spatial node (docs/theory.md, spatial elements): its mass m at the
!> translational coordinates and its rotary inertia J (body frame, about the node) at the
!> Euler parameters lambda = (l0, l1, l2, l3) of the node's rotation. Coordinates
!> x = (x, y, z, l0, l1, l2, l3). No deformation modes: the body only carries inertia.
!>
!> With the body angular velocity omega = 2 G(lambda) lambda', the kinetic energy
!> 1/2 m |v|^2 + 1/2 omega^T J omega gives the mass matrix blockdiag(m I, 4 G^T J G) and the
!> convective force 8 G(lambda')^T J G(lambda) lambda' (Lagrange's equations with
!> G(a) a = 0 and G(a) b = -G(b) a; the test checks it against differences of the mass).
module elements_body3d
  use core_kinds, only: wp
  use elements_base, only: element_t
  use elements_rotation, only: euler_g
  implicit none
  private
  public :: body3d_t

  type, extends(element_t) :: body3d_t
    real(wp) :: mass = 0.0_wp                 !< [kg]
    real(wp) :: inertia_tensor(3, 3) = 0.0_wp !< J in the body frame, about the node [kg m^2]
  contains
    procedure :: evaluate => body_evaluate
    procedure :: second => body_second
    procedure :: stiffness => body_stiffness
    procedure, nopass :: type_name => body_type_name
    procedure :: has_inertia => body_has_inertia
    procedure :: inertia => body_inertia
  end type body3d_t

contains

  !> No modes: nothing to evaluate (the arrays have size zero).
  pure subroutine body_evaluate(this, x, e, de)
    class(body3d_t), intent(in) :: this
    real(wp), intent(in) :: x(:)
    real(wp), intent(out) :: e(:), de(:, :)
    e = 0.0_wp
    de = 0.0_wp
  end subroutine body_evaluate

  pure subroutine body_second(this, x, v, d2e)
    class(body3d_t), intent(in) :: this
    real(wp), intent(in) :: x(:), v(:)
    real(wp), intent(out) :: d2e(:)
    d2e = 0.0_wp
  end subroutine body_second

  pure subroutine body_stiffness(this, s)
    class(body3d_t), intent(in) :: this
    real(wp), intent(out) :: s(:, :)
    s = 0.0_wp
  end subroutine body_stiffness

  pure function body_type_name() result(name)
    character(len=:), allocatable :: name
    name = 'body3d'
  end function body_type_name

  pure logical function body_has_inertia(this)
    class(body3d_t), intent(in) :: this
    body_has_inertia = .true.
  end function body_has_inertia

  !> m (7 x 7) = blockdiag(m I, 4 G^T J G) and h = (0, 8 G(lambda')^T J G(lambda) lambda').
  pure subroutine body_inertia(this, x, xd, m, h)
    class(body3d_t), intent(in) :: this
    real(wp), intent(in) :: x(:), xd(:)
    real(wp), intent(out) :: m(:, :), h(:)
    real(wp) :: g(3, 4), jg(3, 4), gd(3, 4)
    integer :: i
    g = euler_g(x(4:7))
    gd = euler_g(xd(4:7))
    jg = matmul(this%inertia_tensor, g)
    m = 0.0_wp
    do i = 1, 3
      m(i, i) = this%mass
    end do
    m(4:7, 4:7) = 4 * matmul(transpose(g), jg)
    h(1:3) = 0.0_wp
    h(4:7) = 8 * matmul(transpose(gd), matmul(jg, xd(4:7)))
  end subroutine body_inertia
end module elements_body3d
