!> A planar multibody model: nodal coordinates with their classes, elements with their mode
!> classes, masses, loads and prescribed motions, plus the bookkeeping that maps deformation
!> modes to rows of the kinematic equations and to the generalised coordinates
!> q = (q_rh, q_dy) (prescribed first, then dynamic).
!>
!> A model is built with the add_* procedures and then `finalize`d, which checks the counting
!> condition for solvability. Every model owns all its data: many live in one process.
module model_system
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_MODEL, ERR_INPUT
  use elements_base, only: element_t, element_slot_t, MODE_RIGID, MODE_RELEASED, &
    MODE_PRESCRIBED, MODE_DYNAMIC
  use motion_law, only: motion_t
  implicit none
  private
  public :: model_t, mode_ref_t, COORD_X, COORD_Y, COORD_PHI

  integer, parameter :: COORD_X = 1, COORD_Y = 2, COORD_PHI = 3

  !> One deformation mode of one element.
  type :: mode_ref_t
    integer :: element = 0
    integer :: local = 0        !< mode number within the element
    integer :: class = 0        !< MODE_*
    integer :: row = 0          !< row in the kinematic equations, 0 for released modes
    integer :: q = 0            !< index in q for prescribed and dynamic modes, else 0
    integer :: motion = 0       !< motion index for prescribed modes
  end type mode_ref_t

  type :: model_t
    integer :: n_x = 0
    real(wp), allocatable :: x0(:)            !< reference coordinates
    logical, allocatable :: fixed(:)
    integer, allocatable :: coord_kind(:)     !< COORD_X, COORD_Y or COORD_PHI
    character(len=64), allocatable :: coord_name(:)
    type(element_slot_t), allocatable :: elements(:)
    integer :: n_elements = 0
    integer, allocatable :: mode_first(:)     !< per element: index of its first mode in modes(:)
    type(mode_ref_t), allocatable :: modes(:)
    real(wp), allocatable :: lumped(:)        !< constant diagonal mass per coordinate
    real(wp), allocatable :: force(:)         !< constant nodal loads [N, N m]
    real(wp) :: gravity(2) = 0.0_wp           !< [m/s^2]
    type(motion_t), allocatable :: motions(:)
    integer :: n_motions = 0
    !> Named points for output: label and coordinate indices (x, y, phi; phi 0 if none).
    character(len=64), allocatable :: node_label(:)
    integer, allocatable :: node_coord(:, :)
    ! Derived by finalize:
    integer :: n_c = 0, n_rigid = 0, n_rh = 0, n_dy = 0, n_q = 0
    integer, allocatable :: calc_index(:)     !< coordinate -> calculable index (0 if fixed)
    integer, allocatable :: calc_coord(:)     !< calculable index -> coordinate
    integer, allocatable :: row_q(:)          !< kinematic row -> q index (0 for rigid rows)
    integer, allocatable :: q_mode(:)         !< q index -> mode index
    integer, allocatable :: lumped_rows(:)    !< coordinates that carry a lumped mass
    real(wp) :: newton_tol = 1.0e-11_wp       !< kinematic residual tolerance [m or rad]
    logical :: finalized = .false.
  contains
    procedure :: init => model_init
    procedure :: add_coord => model_add_coord
    procedure :: add_element => model_add_element
    procedure :: add_motion => model_add_motion
    procedure :: add_node_label => model_add_node_label
    procedure :: find_node => model_find_node
    procedure :: finalize => model_finalize
    procedure :: mode_name => model_mode_name
    procedure :: q_name => model_q_name
    procedure :: mode_values => model_mode_values
  end type model_t

contains

  subroutine model_init(this)
    class(model_t), intent(inout) :: this
    this%n_x = 0
    this%n_elements = 0
    this%n_motions = 0
    allocate(this%x0(0), this%fixed(0), this%coord_kind(0), this%coord_name(0))
    allocate(this%lumped(0), this%force(0), this%elements(0), this%motions(0))
    allocate(this%node_label(0), this%node_coord(3, 0))
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
    this%coord_kind = [this%coord_kind, kind]
    this%coord_name = [character(len=64) :: this%coord_name, name]
    this%lumped = [this%lumped, 0.0_wp]
    this%force = [this%force, 0.0_wp]
  end function model_add_coord

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
      modes(j) = mode_ref_t(element=idx, local=j, class=elem%mode_class(j), motion=motion(j))
    end do
    this%modes = [this%modes, modes]
  end function model_add_element

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
    integer, intent(in) :: coords(3)
    integer, allocatable :: grown(:, :)
    this%node_label = [character(len=64) :: this%node_label, label]
    allocate(grown(3, size(this%node_label)))
    grown(:, 1:size(this%node_label) - 1) = this%node_coord
    grown(:, size(this%node_label)) = coords
    call move_alloc(grown, this%node_coord)
  end subroutine model_add_node_label

  !> Index of a named point, 0 if there is none.
  pure integer function model_find_node(this, label) result(idx)
    class(model_t), intent(in) :: this
    character(len=*), intent(in) :: label
    do idx = 1, size(this%node_label)
      if (this%node_label(idx) == label) return
    end do
    idx = 0
  end function model_find_node

  !> Number the calculable coordinates, kinematic rows and generalised coordinates, and check
  !> that there are as many kinematic equations as calculable coordinates.
  subroutine model_finalize(this, err)
    class(model_t), intent(inout) :: this
    type(error_t), intent(out) :: err
    integer :: i, m, n_rel, n_rows, iq_rh, iq_dy
    character(len=300) :: msg
    if (.not. allocated(this%modes)) allocate(this%modes(0), this%mode_first(0))
    allocate(this%calc_index(this%n_x))
    this%calc_index = 0
    this%n_c = 0
    do i = 1, this%n_x
      if (.not. this%fixed(i)) then
        this%n_c = this%n_c + 1
        this%calc_index(i) = this%n_c
      end if
    end do
    this%calc_coord = pack([(i, i=1, this%n_x)], .not. this%fixed)
    this%lumped_rows = pack([(i, i=1, this%n_x)], this%lumped > 0)
    this%n_rigid = count(this%modes%class == MODE_RIGID)
    this%n_rh = count(this%modes%class == MODE_PRESCRIBED)
    this%n_dy = count(this%modes%class == MODE_DYNAMIC)
    n_rel = count(this%modes%class == MODE_RELEASED)
    this%n_q = this%n_rh + this%n_dy
    n_rows = this%n_rigid + this%n_q
    if (this%n_dy == 0) then
      call err%set(ERR_MODEL, 'the model has no dynamic deformation mode: nothing to compute')
      return
    end if
    if (n_rows /= this%n_c) then
      write(msg, '(a,i0,a,i0,a,i0,a,i0,a,i0,a)') 'the coordinate classes do not solve: ', &
        this%n_c, ' free nodal coordinates but ', n_rows, ' kinematic conditions (', &
        this%n_rigid, ' rigid + ', this%n_rh, ' prescribed + ', this%n_dy, ' dynamic modes)'
      if (n_rows < this%n_c) then
        call err%set(ERR_MODEL, trim(msg) // '; the model is a mechanism: make more modes ' // &
          'rigid, dynamic or prescribed, or fix more coordinates')
      else
        call err%set(ERR_MODEL, trim(msg) // '; the model is over-constrained: release ' // &
          'modes or free coordinates')
      end if
      return
    end if
    allocate(this%row_q(n_rows), this%q_mode(this%n_q))
    n_rows = 0
    iq_rh = 0
    iq_dy = this%n_rh
    do m = 1, size(this%modes)
      associate (mode => this%modes(m))
        if (mode%class == MODE_RELEASED) cycle
        n_rows = n_rows + 1
        mode%row = n_rows
        this%row_q(n_rows) = 0
        if (mode%class == MODE_PRESCRIBED) then
          if (mode%motion < 1 .or. mode%motion > this%n_motions) then
            call err%set(ERR_INPUT, 'prescribed mode ' // this%mode_name(m) // ' has no motion')
            return
          end if
          iq_rh = iq_rh + 1
          mode%q = iq_rh
        else if (mode%class == MODE_DYNAMIC) then
          iq_dy = iq_dy + 1
          mode%q = iq_dy
        end if
        if (mode%q > 0) then
          this%row_q(n_rows) = mode%q
          this%q_mode(mode%q) = m
        end if
      end associate
    end do
    this%finalized = .true.
  end subroutine model_finalize

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
    name = this%mode_name(this%q_mode(iq))
  end function model_q_name

  !> Values of an element's modes from the generalised coordinates: rigid 0, prescribed and
  !> dynamic from q (exactly, not recomputed from x: see docs/theory.md section 5); released
  !> modes carry no stress and are returned as 0.
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
end module model_system
