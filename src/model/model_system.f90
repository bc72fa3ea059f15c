!> A planar multibody model: nodal coordinates with their classes, elements with their mode
!> classes, masses, loads and prescribed motions, plus the bookkeeping that maps deformation
!> modes to rows of the kinematic equations and to the generalised coordinates
!> q = (q_rh, q_dy) (prescribed first, then dynamic). Within each part the modes come first
!> (element order), then nodal coordinates that are inputs themselves (a shuttle translation
!> as a degree of freedom, a prescribed body rotation): those are x = x0 + q exactly.
!>
!> A model is built with the add_* procedures and then `finalize`d, which checks the counting
!> condition for solvability. Every model owns all its data: many live in one process.
module model_system
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_MODEL, ERR_INPUT, ERR_NUMERIC
  use core_strings, only: int_str
  use elements_base, only: element_t, element_slot_t, MODE_RIGID, MODE_RELEASED, &
    MODE_PRESCRIBED, MODE_DYNAMIC, MODE_ELASTIC
  use motion_law, only: motion_t
  use model_control, only: controller_t
  implicit none
  private
  public :: model_t, mode_ref_t, COORD_X, COORD_Y, COORD_PHI, COORD_Z, COORD_EULER, error_norm_of

  integer, parameter :: COORD_X = 1, COORD_Y = 2, COORD_PHI = 3
  !> Spatial models: the z translation, and the four Euler parameters of a node's rotation.
  integer, parameter :: COORD_Z = 4, COORD_EULER = 5
  !> Rows of node_coord: x, y, phi, z, first Euler parameter.
  integer, parameter, public :: NODE_SLOTS = 5

  !> One deformation mode of one element.
  type :: mode_ref_t
    integer :: element = 0
    integer :: local = 0        !< mode number within the element
    integer :: class = 0        !< MODE_*
    integer :: row = 0          !< row in the kinematic equations, 0 for released modes
    integer :: q = 0            !< index in q for prescribed and dynamic modes, else 0
    integer :: motion = 0       !< motion index for prescribed modes
    real(wp) :: period = 0.0_wp !< the mode's period in its coordinate (0: none)
  end type mode_ref_t

  type :: model_t
    integer :: n_x = 0
    real(wp), allocatable :: x0(:)            !< reference coordinates
    logical, allocatable :: fixed(:)
    !> MODE_PRESCRIBED or MODE_DYNAMIC for a coordinate that is itself an input, else 0;
    !> coord_motion the motion of a prescribed one.
    integer, allocatable :: coord_input(:), coord_motion(:)
    integer, allocatable :: coord_kind(:)     !< COORD_X, COORD_Y or COORD_PHI
    character(len=64), allocatable :: coord_name(:)
    type(element_slot_t), allocatable :: elements(:)
    integer :: n_elements = 0
    integer, allocatable :: mode_first(:)     !< per element: index of its first mode in modes(:)
    type(mode_ref_t), allocatable :: modes(:)
    real(wp), allocatable :: lumped(:)        !< constant diagonal mass per coordinate
    real(wp), allocatable :: force(:)         !< constant nodal loads [N, N m]
    !> Loads that follow a time law: load_shape(:, k) [N, N m] times the value of motion
    !> load_motion(k).
    real(wp), allocatable :: load_shape(:, :)
    !> Moments on spatial nodes, constant in the global frame [N m]: moment(:, k) on the node
    !> whose Euler parameters start at coordinate moment_lambda(k). Their generalised force
    !> 2 E(lambda)^T M depends on the rotation, so the dynamics adds it at each evaluation.
    !> moment_motion(k): the motion whose value scales moment k in time (0: constant).
    real(wp), allocatable :: moment(:, :)
    integer, allocatable :: moment_lambda(:), moment_motion(:)
    !> Actuators on the first mode of element actuator_element(k), a dynamic mode (a driven
    !> joint whose angle is a degree of freedom): the torque (force) actuator_value(k) [N m, N],
    !> constant or times the value p of motion actuator_motion(k), plus actuator_rate(k) times
    !> its rate p' (a PD controller's feed of its reference).
    integer, allocatable :: actuator_element(:), actuator_motion(:)
    real(wp), allocatable :: actuator_value(:), actuator_rate(:)
    !> Feedback controllers (model_control); their states belong to the run.
    type(controller_t), allocatable :: controllers(:)
    integer, allocatable :: load_motion(:)
    !> 2 (planar) or 3 (spatial): the components of gravity the elements see.
    integer :: dim = 2
    real(wp) :: gravity(3) = 0.0_wp           !< [m/s^2]; z unused in the plane
    type(motion_t), allocatable :: motions(:)
    integer :: n_motions = 0
    !> Named points for output: label and coordinate indices (x, y, phi, z, first Euler
    !> parameter; 0 where the node has none: phi only in the plane, z and lambda only in space).
    character(len=64), allocatable :: node_label(:)
    integer, allocatable :: node_coord(:, :)
    ! Derived by finalize:
    integer :: n_c = 0, n_rigid = 0, n_rh = 0, n_dy = 0, n_q = 0, n_elastic = 0
    integer, allocatable :: calc_index(:)     !< coordinate -> calculable index (0 if not)
    integer, allocatable :: calc_coord(:)     !< calculable index -> coordinate
    integer, allocatable :: row_q(:)          !< kinematic row -> q index (0 for rigid rows)
    integer, allocatable :: q_mode(:)         !< q index -> mode index (0 for a coordinate)
    integer, allocatable :: q_coord(:)        !< q index -> coordinate (0 for a mode)
    integer, allocatable :: q_motion(:)       !< prescribed q index -> motion index
    integer, allocatable :: input_q(:)        !< coordinate -> q index if an input, else 0
    !> Elements with an elastic mode: their stresses depend on x, not on q alone.
    logical, allocatable :: elastic_element(:)
    integer, allocatable :: lumped_rows(:)    !< coordinates that carry a lumped mass
    !> Most modes and nodal coordinates of any element: the size of work arrays that element
    !> loops reuse instead of allocating per element.
    integer :: max_modes = 0, max_dofs = 0
    real(wp) :: newton_tol = 1.0e-11_wp       !< kinematic residual tolerance [m or rad]
    !> Elements whose input modes have a limited range (element_t%has_limit): check_limits.
    integer, allocatable :: limited(:)
    logical :: finalized = .false.
  contains
    procedure :: init => model_init
    procedure :: add_coord => model_add_coord
    procedure :: set_coord_input => model_set_coord_input
    procedure :: add_element => model_add_element
    procedure :: add_motion => model_add_motion
    procedure :: add_timed_load => model_add_timed_load
    procedure :: add_moment => model_add_moment
    procedure :: moment_at => model_moment_at
    procedure :: add_actuator => model_add_actuator
    procedure :: actuator_forces => model_actuator_forces
    procedure :: loads_at => model_loads_at
    procedure :: add_node_label => model_add_node_label
    procedure :: find_node => model_find_node
    procedure :: translation => model_translation
    procedure :: largest_translation => model_largest_translation
    procedure :: error_norm => model_error_norm
    procedure :: error_kind => model_error_kind
    procedure :: finalize => model_finalize
    procedure :: count_message => model_count_message
    procedure :: mode_name => model_mode_name
    procedure :: q_name => model_q_name
    procedure :: mode_values => model_mode_values
    procedure :: check_limits => model_check_limits
  end type model_t

  interface
    !> Number the calculable coordinates, kinematic rows and generalised coordinates, and
    !> check that there are as many kinematic equations as calculable coordinates
    !> (model_system_finalize).
    module subroutine model_finalize(this, err)
      class(model_t), intent(inout) :: this
      type(error_t), intent(out) :: err
    end subroutine model_finalize
    !> Why the classes do not solve and what to change (model_system_finalize).
    module function model_count_message(this, n_rows) result(msg)
      class(model_t), intent(in) :: this
      integer, intent(in) :: n_rows
      character(len=:), allocatable :: msg
    end function model_count_message
  end interface

contains

  subroutine model_init(this)
    class(model_t), intent(inout) :: this
    this%n_x = 0
    this%n_elements = 0
    this%n_motions = 0
    allocate(this%x0(0), this%fixed(0), this%coord_kind(0), this%coord_name(0))
    allocate(this%coord_input(0), this%coord_motion(0))
    allocate(this%lumped(0), this%force(0), this%elements(0), this%motions(0))
    allocate(this%node_label(0), this%node_coord(NODE_SLOTS, 0))
    allocate(this%load_shape(0, 0), this%load_motion(0))
    allocate(this%moment(3, 0), this%moment_lambda(0), this%moment_motion(0))
    allocate(this%actuator_element(0), this%actuator_motion(0), this%actuator_value(0), &
      this%actuator_rate(0))
    allocate(this%controllers(0), this%limited(0))
    this%finalized = .false.
  end subroutine model_init

  !> Add one nodal coordinate; returns its index.
  integer function model_add_coord(this, value, kind, fixed, name) result(idx)
    class(model_t), intent(inout) :: this
    real(wp), intent(in) :: value
    integer, intent(in) :: kind
    logical, intent(in) :: fixed
    character(len=*), intent(in) :: name
    this%n_x = this%n_x + 1
    idx = this%n_x
    this%x0 = [this%x0, value]
    this%fixed = [this%fixed, fixed]
    this%coord_input = [this%coord_input, 0]
    this%coord_motion = [this%coord_motion, 0]
    this%coord_kind = [this%coord_kind, kind]
    this%coord_name = [character(len=64) :: this%coord_name, name]
    this%lumped = [this%lumped, 0.0_wp]
    this%force = [this%force, 0.0_wp]
  end function model_add_coord

  !> Make coordinate idx an input: MODE_DYNAMIC (a degree of freedom) or MODE_PRESCRIBED
  !> (following motion `motion`).
  subroutine model_set_coord_input(this, idx, class, motion)
    class(model_t), intent(inout) :: this
    integer, intent(in) :: idx, class, motion
    this%coord_input(idx) = class
    this%coord_motion(idx) = motion
  end subroutine model_set_coord_input

  !> Add an element (dofs, mode classes set); `motion` gives the motion index of each
  !> prescribed mode (0 elsewhere). Returns the element index.
  integer function model_add_element(this, elem, motion) result(idx)
    class(model_t), intent(inout) :: this
    class(element_t), intent(in) :: elem
    integer, intent(in) :: motion(:)
    type(element_slot_t), allocatable :: grown(:)
    type(mode_ref_t), allocatable :: modes(:)
    integer :: j
    allocate(grown(this%n_elements + 1))
    do j = 1, this%n_elements
      call move_alloc(this%elements(j)%e, grown(j)%e)
    end do
    allocate(grown(this%n_elements + 1)%e, source=elem)
    call move_alloc(grown, this%elements)
    this%n_elements = this%n_elements + 1
    idx = this%n_elements
    if (.not. allocated(this%modes)) allocate(this%modes(0), this%mode_first(0))
    this%mode_first = [this%mode_first, size(this%modes) + 1]
    allocate(modes(elem%n_modes()))
    do j = 1, elem%n_modes()
      modes(j) = mode_ref_t(element=idx, local=j, class=elem%mode_class(j), motion=motion(j), &
        period=elem%mode_period(j))
    end do
    this%modes = [this%modes, modes]
    if (.not. allocated(this%limited)) allocate(this%limited(0))
    if (elem%has_limit()) this%limited = [this%limited, idx]
  end function model_add_element

  !> A moment m (3, global frame) on the node whose Euler parameters start at coordinate
  !> first_lambda; constant, or times the value of motion `motion` (> 0) in time.
  subroutine model_add_moment(this, first_lambda, m, motion)
    class(model_t), intent(inout) :: this
    integer, intent(in) :: first_lambda
    real(wp), intent(in) :: m(3)
    integer, intent(in), optional :: motion
    integer :: law
    law = 0
    if (present(motion)) law = motion
    this%moment = reshape([reshape(this%moment, [size(this%moment)]), m], &
      [3, size(this%moment, 2) + 1])
    this%moment_lambda = [this%moment_lambda, first_lambda]
    this%moment_motion = [this%moment_motion, law]
  end subroutine model_add_moment

  !> An actuator: `value` (constant, or times motion `motion` > 0) on the first mode of
  !> element `element`, which must be dynamic (finalize checks).
  subroutine model_add_actuator(this, element, value, motion, rate)
    class(model_t), intent(inout) :: this
    integer, intent(in) :: element, motion
    real(wp), intent(in) :: value
    real(wp), intent(in), optional :: rate
    real(wp) :: d
    d = 0.0_wp
    if (present(rate)) d = rate
    this%actuator_element = [this%actuator_element, element]
    this%actuator_value = [this%actuator_value, value]
    this%actuator_rate = [this%actuator_rate, d]
    this%actuator_motion = [this%actuator_motion, motion]
  end subroutine model_add_actuator

  !> The actuators' generalised forces on q_dy at time t (their work on the modes they drive).
  pure function model_actuator_forces(this, t) result(f)
    class(model_t), intent(in) :: this
    real(wp), intent(in) :: t
    real(wp) :: f(this%n_dy), p, pd, pdd
    integer :: k, j
    f = 0.0_wp
    do k = 1, size(this%actuator_element)
      p = 1.0_wp
      pd = 0.0_wp
      if (this%actuator_motion(k) > 0) call this%motions(this%actuator_motion(k))%eval(t, p, pd, &
        pdd)
      j = this%modes(this%mode_first(this%actuator_element(k)))%q - this%n_rh
      f(j) = f(j) + p * this%actuator_value(k) + pd * this%actuator_rate(k)
    end do
  end function model_actuator_forces

  !> Moment k at time t [N m, global frame].
  pure function model_moment_at(this, k, t) result(m)
    class(model_t), intent(in) :: this
    integer, intent(in) :: k
    real(wp), intent(in) :: t
    real(wp) :: m(3), p, pd, pdd
    m = this%moment(:, k)
    if (this%moment_motion(k) == 0) return
    call this%motions(this%moment_motion(k))%eval(t, p, pd, pdd)
    m = p * m
  end function model_moment_at

  !> A nodal load `shape` (n_x) that follows motion `motion` in time.
  subroutine model_add_timed_load(this, shape, motion)
    class(model_t), intent(inout) :: this
    real(wp), intent(in) :: shape(:)
    integer, intent(in) :: motion
    real(wp), allocatable :: grown(:, :)
    integer :: n
    n = size(this%load_motion)
    allocate(grown(this%n_x, n + 1))
    grown = 0.0_wp
    if (n > 0) grown(1:size(this%load_shape, 1), 1:n) = this%load_shape
    grown(:, n + 1) = shape
    call move_alloc(grown, this%load_shape)
    this%load_motion = [this%load_motion, motion]
  end subroutine model_add_timed_load

  !> Nodal loads at time t: the constant ones plus those that follow time laws.
  pure function model_loads_at(this, t) result(f)
    class(model_t), intent(in) :: this
    real(wp), intent(in) :: t
    real(wp) :: f(this%n_x), p, pd, pdd
    integer :: k
    f = this%force
    do k = 1, size(this%load_motion)
      call this%motions(this%load_motion(k))%eval(t, p, pd, pdd)
      f = f + p * this%load_shape(:, k)
    end do
  end function model_loads_at

  integer function model_add_motion(this, motion) result(idx)
    class(model_t), intent(inout) :: this
    type(motion_t), intent(in) :: motion
    this%motions = [this%motions, motion]
    this%n_motions = this%n_motions + 1
    idx = this%n_motions
  end function model_add_motion

  subroutine model_add_node_label(this, label, coords)
    class(model_t), intent(inout) :: this
    character(len=*), intent(in) :: label
    integer, intent(in) :: coords(:)   !< x, y, phi (, z, lambda_0): missing ones are 0
    integer, allocatable :: grown(:, :)
    this%node_label = [character(len=64) :: this%node_label, label]
    allocate(grown(NODE_SLOTS, size(this%node_label)))
    grown(:, 1:size(this%node_label) - 1) = this%node_coord
    grown(:, size(this%node_label)) = 0
    grown(1:size(coords), size(this%node_label)) = coords
    call move_alloc(grown, this%node_coord)
  end subroutine model_add_node_label

  !> Whether a coordinate of this kind is (part of) a rotation.
  pure logical function is_rotation(kind)
    integer, intent(in) :: kind
    is_rotation = kind == COORD_PHI .or. kind == COORD_EULER
  end function is_rotation

  !> Largest translation over the nodes of a nodal displacement dx.
  pure real(wp) function model_largest_translation(this, dx) result(d)
    class(model_t), intent(in) :: this
    real(wp), intent(in) :: dx(:)
    integer :: i
    d = 0.0_wp
    do i = 1, size(this%node_coord, 2)
      d = max(d, this%translation(i, dx))
    end do
  end function model_largest_translation

  !> The integrators' error norm of a nodal error dx: its largest component over atol + rtol s,
  !> s the largest nodal motion (`motion`, per coordinate) among the rotations for a rotation
  !> and among the translations for a translation.
  pure real(wp) function model_error_norm(this, dx, motion, rtol, atol) result(norm)
    class(model_t), intent(in) :: this
    real(wp), intent(in) :: dx(:), motion(:), rtol, atol
    real(wp) :: largest(2), step(2)
    integer :: i, kind
    ! One loop, not masked intrinsics: this runs at every step of the integrators. Within a
    ! kind the scale is common, so the largest ratio is the largest step over it.
    largest = -huge(1.0_wp)
    step = 0.0_wp
    do i = 1, size(dx)
      kind = norm_kind(this%coord_kind(i))
      largest(kind) = max(largest(kind), motion(i))
      step(kind) = max(step(kind), abs(dx(i)))
    end do
    norm = error_norm_of(step, largest, rtol, atol)
  end function model_error_norm

  !> The error norm's kind of coordinate i: 1 for a rotation, 2 for a translation.
  pure integer function model_error_kind(this, i) result(kind)
    class(model_t), intent(in) :: this
    integer, intent(in) :: i
    kind = norm_kind(this%coord_kind(i))
  end function model_error_kind

  pure integer function norm_kind(coord_kind) result(kind)
    integer, intent(in) :: coord_kind
    kind = merge(1, 2, is_rotation(coord_kind))
  end function norm_kind

  !> model_t%error_norm from its terms per kind (model_t%error_kind): the largest step and the
  !> largest motion, for callers that form them without the nodal vectors.
  pure real(wp) function error_norm_of(step, largest, rtol, atol) result(norm)
    real(wp), intent(in) :: step(2), largest(2), rtol, atol
    integer :: kind
    norm = 0.0_wp
    do kind = 1, 2
      if (step(kind) > 0) norm = max(norm, step(kind) / (atol + rtol * largest(kind)))
    end do
  end function error_norm_of

  !> Length of the translation of node i in a nodal displacement dx (x, y and, in space, z).
  pure real(wp) function model_translation(this, i, dx) result(d)
    class(model_t), intent(in) :: this
    integer, intent(in) :: i
    real(wp), intent(in) :: dx(:)
    integer :: k, slot(3)
    d = 0.0_wp
    slot = [1, 2, 4]
    do k = 1, 3
      if (this%node_coord(slot(k), i) > 0) d = d + dx(this%node_coord(slot(k), i))**2
    end do
    d = sqrt(d)
  end function model_translation

  !> Index of a named point, 0 if there is none.
  pure integer function model_find_node(this, label) result(idx)
    class(model_t), intent(in) :: this
    character(len=*), intent(in) :: label
    do idx = 1, size(this%node_label)
      if (this%node_label(idx) == label) return
    end do
    idx = 0
  end function model_find_node

  !> "mode 2 of element 'link1.3'" for messages.
  function model_mode_name(this, m) result(name)
    class(model_t), intent(in) :: this
    integer, intent(in) :: m
    character(len=:), allocatable :: name
    character(len=12) :: buf
    write(buf, '(i0)') this%modes(m)%local
    name = 'mode ' // trim(buf) // ' of element ''' // &
      this%elements(this%modes(m)%element)%e%label // ''''
  end function model_mode_name

  function model_q_name(this, iq) result(name)
    class(model_t), intent(in) :: this
    integer, intent(in) :: iq
    character(len=:), allocatable :: name
    if (this%q_coord(iq) > 0) then
      name = 'coordinate ''' // trim(this%coord_name(this%q_coord(iq))) // ''''
    else
      name = this%mode_name(this%q_mode(iq))
    end if
  end function model_q_name

  !> Values of an element's modes from the generalised coordinates: rigid 0, prescribed and
  !> dynamic from q (exactly, not recomputed from x: see docs/theory.md section 5); released
  !> and elastic modes are calculable and returned as 0 (elastic ones are evaluated from x
  !> where their stress is needed).
  pure subroutine model_mode_values(this, iel, q, e)
    class(model_t), intent(in) :: this
    integer, intent(in) :: iel
    real(wp), intent(in) :: q(:)
    real(wp), intent(out) :: e(:)
    integer :: j, m
    do j = 1, size(e)
      m = this%mode_first(iel) + j - 1
      e(j) = 0.0_wp
      if (this%modes(m)%q > 0) e(j) = q(this%modes(m)%q)
    end do
  end subroutine model_mode_values

  !> An error (ERR_NUMERIC: a step that went too far may be retried shorter) when q puts an
  !> element's input modes beyond their range (a free rotation near a full turn), where its
  !> coordinates are singular and the kinematics would fail without saying why.
  subroutine model_check_limits(this, q, err)
    class(model_t), intent(in) :: this
    real(wp), intent(in) :: q(:)
    type(error_t), intent(inout) :: err
    real(wp) :: e(this%max_modes)
    integer :: k, nm
    character(len=:), allocatable :: msg
    if (.not. allocated(this%limited)) return
    do k = 1, size(this%limited)
      associate (el => this%elements(this%limited(k))%e)
        nm = el%n_modes()
        call this%mode_values(this%limited(k), q, e(1:nm))
        msg = el%limit_problem(e(1:nm))
      end associate
      if (len(msg) == 0) cycle
      call err%set(ERR_NUMERIC, msg)
      return
    end do
  end subroutine model_check_limits
end module model_system
