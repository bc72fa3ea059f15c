!> The abstract planar element: deformation modes e = D(x) of its nodal coordinates, their
!> first derivatives, second directional derivatives, stiffness and (optionally) inertia.
!>
!> Elements see only their own coordinates x_e (gathered by the model through `dofs`); every
!> mode carries a class (rigid, released, prescribed, dynamic, elastic) chosen per mode by the
!> user.
module elements_base
  use core_kinds, only: wp
  implicit none
  private
  public :: element_t, element_slot_t
  public :: MODE_RIGID, MODE_RELEASED, MODE_PRESCRIBED, MODE_DYNAMIC, MODE_ELASTIC
  public :: mode_class_name, mode_has_stress

  integer, parameter :: MODE_RIGID = 1      !< e = 0
  integer, parameter :: MODE_RELEASED = 2   !< free, no stiffness, follows from the others
  integer, parameter :: MODE_PRESCRIBED = 3 !< e = e(t), a driven input
  integer, parameter :: MODE_DYNAMIC = 4    !< a degree of freedom with stiffness
  !> Calculable like a released mode (it follows from the others, e = D(x)) but with its
  !> stiffness and damping: how statically indeterminate structures are closed.
  integer, parameter :: MODE_ELASTIC = 5

  type, abstract :: element_t
    character(len=:), allocatable :: label
    integer, allocatable :: dofs(:)        !< global indices of the element's coordinates
    integer, allocatable :: mode_class(:)  !< MODE_* per deformation mode
    real(wp) :: damping = 0.0_wp           !< stiffness-proportional damping time constant [s]
  contains
    procedure(evaluate_iface), deferred :: evaluate
    procedure(second_iface), deferred :: second
    procedure(stiffness_iface), deferred :: stiffness
    !> 'beam', 'hinge', 'truss': names the element type in result files.
    procedure(type_name_iface), deferred, nopass :: type_name
    procedure :: n_modes => element_n_modes
    procedure :: mode_period => element_no_period
    procedure :: has_inertia => element_no_inertia
    procedure :: inertia => element_zero_inertia
    procedure :: second_inertia => element_second_inertia
    procedure :: second_many => element_second_many
    procedure :: convective_many => element_convective_many
    procedure :: weight => element_zero_weight
    procedure :: lumped_mass => element_no_lumped_mass
    procedure :: has_limit => element_no_limit
    procedure :: limit_problem => element_no_limit_problem
    procedure :: recentre => element_no_recentre
    procedure :: chart => element_no_chart
    procedure :: set_chart => element_set_no_chart
  end type element_t

  !> Container so that a model holds elements of different types in one array.
  type :: element_slot_t
    class(element_t), allocatable :: e
  end type element_slot_t

  abstract interface
    !> Deformations e (n_modes) and their Jacobian de = dD/dx (n_modes, n_coords).
    pure subroutine evaluate_iface(this, x, e, de)
      import :: element_t, wp
      class(element_t), intent(in) :: this
      real(wp), intent(in) :: x(:)
      real(wp), intent(out) :: e(:), de(:, :)
    end subroutine evaluate_iface

    !> Second directional derivative d2/ds2 D(x + s v) at s = 0 for every mode.
    pure subroutine second_iface(this, x, v, d2e)
      import :: element_t, wp
      class(element_t), intent(in) :: this
      real(wp), intent(in) :: x(:), v(:)
      real(wp), intent(out) :: d2e(:)
    end subroutine second_iface

    !> Stiffness matrix S (n_modes, n_modes): sigma = S e.
    pure subroutine stiffness_iface(this, s)
      import :: element_t, wp
      class(element_t), intent(in) :: this
      real(wp), intent(out) :: s(:, :)
    end subroutine stiffness_iface
    pure function type_name_iface() result(name)
      character(len=:), allocatable :: name
    end function type_name_iface
  end interface

contains

  pure integer function element_n_modes(this)
    class(element_t), intent(in) :: this
    element_n_modes = size(this%mode_class)
  end function element_n_modes

  !> Period of mode j in its coordinate (0: none). A mode that is an angle defined only up to
  !> whole turns (a spatial hinge's rotation) matches its coordinate modulo the period, so a
  !> joint can turn on without bound.
  pure real(wp) function element_no_period(this, j) result(p)
    class(element_t), intent(in) :: this
    integer, intent(in) :: j
    p = 0.0_wp
  end function element_no_period

  !> True when the element has a configuration-dependent (consistent) mass.
  pure logical function element_no_inertia(this)
    class(element_t), intent(in) :: this
    element_no_inertia = .false.
  end function element_no_inertia

  !> Mass matrix m(x) and convective force h(x, xd) = m-derivative terms, for consistent masses.
  pure subroutine element_zero_inertia(this, x, xd, m, h)
    class(element_t), intent(in) :: this
    real(wp), intent(in) :: x(:), xd(:)
    real(wp), intent(out) :: m(:, :), h(:)
    m = 0.0_wp
    h = 0.0_wp
  end subroutine element_zero_inertia

  !> second (d2e along xd) and inertia (m, h) at the same (x, xd) in one call: the evaluation's
  !> single pass over the elements with masses. An element whose two share their geometry
  !> (the planar beam's chord) overrides it to compute that once. e: the mode values at x when
  !> the caller has them (the kinematics' last pass), which an element may take its geometry
  !> from.
  pure subroutine element_second_inertia(this, x, xd, d2e, m, h, e)
    class(element_t), intent(in) :: this
    real(wp), intent(in) :: x(:), xd(:)
    real(wp), intent(out) :: d2e(:), m(:, :), h(:)
    real(wp), intent(in), optional :: e(:)
    call this%second(x, xd, d2e)
    call this%inertia(x, xd, m, h)
  end subroutine element_second_inertia

  !> second along each column of v at the same x, into the columns of d2e (a reduced model's
  !> expansion takes tens of directions at once). An element whose second derivatives share
  !> their geometry overrides it to compute that once.
  pure subroutine element_second_many(this, x, v, d2e)
    class(element_t), intent(in) :: this
    real(wp), intent(in) :: x(:), v(:, :)
    real(wp), intent(out) :: d2e(:, :)
    integer :: c
    do c = 1, size(v, 2)
      call this%second(x, v(:, c), d2e(:, c))
    end do
  end subroutine element_second_many

  !> The convective force h of inertia along each column of xd at the same x (a reduced
  !> model's expansion); an element that can skip its mass matrix for it overrides this.
  pure subroutine element_convective_many(this, x, xd, h)
    class(element_t), intent(in) :: this
    real(wp), intent(in) :: x(:), xd(:, :)
    real(wp), intent(out) :: h(:, :)
    real(wp) :: m(size(x), size(x))
    integer :: c
    do c = 1, size(xd, 2)
      call this%inertia(x, xd(:, c), m, h(:, c))
    end do
  end subroutine element_convective_many

  !> Nodal forces f (n_coords) of gravity g (2 components in the plane, 3 in space) on a
  !> consistent mass, and its potential energy.
  pure subroutine element_zero_weight(this, x, g, f, potential)
    class(element_t), intent(in) :: this
    real(wp), intent(in) :: x(:), g(:)
    real(wp), intent(out) :: f(:), potential
    f = 0.0_wp
    potential = 0.0_wp
  end subroutine element_zero_weight

  !> Constant diagonal mass per element coordinate (lumped masses).
  pure subroutine element_no_lumped_mass(this, diag)
    class(element_t), intent(in) :: this
    real(wp), intent(out) :: diag(:)
    diag = 0.0_wp
  end subroutine element_no_lumped_mass

  !> True when the element's modes (as inputs, from q) have a range beyond which its
  !> coordinates are singular: the model then checks them (limit_problem) before each
  !> kinematic solve.
  pure logical function element_no_limit(this)
    class(element_t), intent(in) :: this
    element_no_limit = .false.
  end function element_no_limit

  !> Why the mode values e are beyond the element's range, naming the element ('' if not).
  pure function element_no_limit_problem(this, e) result(msg)
    class(element_t), intent(in) :: this
    real(wp), intent(in) :: e(:)
    character(len=:), allocatable :: msg
    msg = ''
  end function element_no_limit_problem

  !> An element with limited modes may move the origin of its modes' chart (a free
  !> rotation's reference orientation) to x when their values e come near the limit; then
  !> `moved`, and the modes are to be re-evaluated at x (the caller's q changes, x does not).
  !> Default: no chart to move.
  pure subroutine element_no_recentre(this, x, e, moved)
    class(element_t), intent(inout) :: this
    real(wp), intent(in) :: x(:), e(:)
    logical, intent(out) :: moved
    moved = .false.
  end subroutine element_no_recentre

  !> The parameters of the element's chart (what recentre changes), to be kept with results
  !> that hold mode values and restored with set_chart. Default: none.
  pure function element_no_chart(this) result(c)
    class(element_t), intent(in) :: this
    real(wp), allocatable :: c(:)
    allocate(c(0))
  end function element_no_chart

  pure subroutine element_set_no_chart(this, c)
    class(element_t), intent(inout) :: this
    real(wp), intent(in) :: c(:)
  end subroutine element_set_no_chart

  pure function mode_class_name(c) result(name)
    integer, intent(in) :: c
    character(len=:), allocatable :: name
    select case (c)
    case (MODE_RIGID); name = 'rigid'
    case (MODE_RELEASED); name = 'released'
    case (MODE_PRESCRIBED); name = 'prescribed'
    case (MODE_DYNAMIC); name = 'dynamic'
    case (MODE_ELASTIC); name = 'elastic'
    case default; name = 'unknown'
    end select
  end function mode_class_name

  !> Whether a mode of class c carries a stress S e (+ damping) into the equations: rigid and
  !> prescribed modes carry reactions instead, released ones nothing.
  elemental logical function mode_has_stress(c)
    integer, intent(in) :: c
    mode_has_stress = c == MODE_DYNAMIC .or. c == MODE_ELASTIC
  end function mode_has_stress
end module elements_base
