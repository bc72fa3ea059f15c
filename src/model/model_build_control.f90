!> &controller groups: where each controller measures and acts, resolved on the built model.
submodule (model_build) model_build_control
  use model_control, only: controller_t, ACT_MODE, ACT_COORD, MEAS_MODE, MEAS_COORD, LAW_USER, &
    LAW_PID, controller_sizes
  use model_scene, only: controller_rec_t
  implicit none

  !> Node components by name, as rows of model%node_coord (x, y, phi, z).
  character(len=6), parameter :: NODE_FORCES(4) = ['fx    ', 'fy    ', 'moment', 'fz    ']
  character(len=6), parameter :: NODE_MEASURES(4) = ['x  ', 'y  ', 'phi', 'z  ']

contains

  module procedure add_controllers
    type(controller_t) :: c
    integer :: i, k
    do i = 1, size(scene%controllers)
      associate (r => scene%controllers(i))
        if (any([(scene%controllers(i)%label == scene%controllers(k)%label, &
                  k = 1, i - 1)])) then
          call err%set(ERR_INPUT, 'group &controller ''' // r%label // ''': variable ' // &
            '''label'': defined twice')
          return
        end if
        call controller_of(scene, model, r, c, err)
        if (.not. err%ok()) return
        call controller_sizes(model%controllers, c%u_offset, c%y_offset, c%x_offset)
        model%controllers = [model%controllers, c]
      end associate
    end do
  end procedure add_controllers

  subroutine controller_of(scene, model, r, c, err)
    type(scene_t), intent(in) :: scene
    type(model_t), intent(in) :: model
    type(controller_rec_t), intent(in) :: r
    type(controller_t), intent(out) :: c
    type(error_t), intent(inout) :: err
    character(len=:), allocatable :: where
    integer :: i
    where = 'group &controller ''' // r%label // ''''
    c%label = r%label
    c%law_kind = merge(LAW_USER, LAW_PID, r%law == 'user')
    c%n_states = r%n_states
    c%kp = r%kp
    c%ki = r%ki
    c%kd = r%kd
    c%period = r%period
    c%u_min = r%u_min
    c%u_max = r%u_max
    call motion_named(scene, r%reference, where, 'reference', c%reference, err)
    if (.not. err%ok()) return
    allocate(c%act_kind(size(r%actuator)), c%act_index(size(r%actuator)))
    allocate(c%meas_kind(size(r%measure)), c%meas_index(size(r%measure)))
    do i = 1, size(r%actuator)
      call point_of(model, r%actuator(i)%s, where, 'actuator', c%act_kind(i), c%act_index(i), &
        err)
      if (.not. err%ok()) return
    end do
    do i = 1, size(r%measure)
      call point_of(model, r%measure(i)%s, where, 'measure', c%meas_kind(i), c%meas_index(i), &
        err)
      if (.not. err%ok()) return
    end do
  end subroutine controller_of

  !> 'name.component' of an actuator (var = 'actuator') or a measured output: a joint's mode
  !> ('hinge.torque' / 'hinge.angle', 'truss.force' / 'truss.elongation') or a node's
  !> coordinate ('node.fx' / 'node.x', ...). kind is ACT_MODE or ACT_COORD (the MEAS_*
  !> values are the same numbers), index into model%modes or the coordinates.
  subroutine point_of(model, name, where, var, kind, index, err)
    type(model_t), intent(in) :: model
    character(len=*), intent(in) :: name, where, var
    integer, intent(out) :: kind, index
    type(error_t), intent(inout) :: err
    character(len=:), allocatable :: owner, comp, ctx
    logical :: acts
    integer :: dot, iel, in, k
    kind = 0
    index = 0
    acts = var == 'actuator'
    ctx = where // ': variable ''' // var // ''': '''// name // ''''
    dot = index_of_dot(name)
    owner = name(1:max(dot - 1, 0))
    comp = name(dot + 1:)
    if (dot <= 1 .or. len(comp) == 0) then
      call err%set(ERR_INPUT, ctx // ' is not name.component')
      return
    end if
    do iel = 1, model%n_elements
      if (model%elements(iel)%e%label /= owner) cycle
      call joint_point(model, iel, comp, acts, ctx, index, err)
      kind = ACT_MODE
      return
    end do
    in = model%find_node(owner)
    if (in == 0) then
      call err%set(ERR_INPUT, ctx // ': no hinge, truss or node is called ''' // owner // '''')
      return
    end if
    if (acts) then
      k = findloc([(trim(NODE_FORCES(k)) == comp, k = 1, 4)], .true., 1)
    else
      k = findloc([(trim(NODE_MEASURES(k)) == comp, k = 1, 4)], .true., 1)
    end if
    ! A spatial node's rotation is four Euler parameters: no single coordinate to act on.
    if (k == 0 .or. (model%dim == 3 .and. k == 3) .or. (model%dim == 2 .and. k == 4)) then
      call err%set(ERR_INPUT, ctx // ': a node''s component is one of ' // &
        trim(component_list(model%dim, acts)))
      return
    end if
    index = model%node_coord(k, in)
    kind = ACT_COORD
    if (index == 0) then
      call err%set(ERR_INPUT, ctx // ': node ''' // owner // ''' has no rotation')
    else if (model%fixed(index) .or. model%coord_input(index) == MODE_PRESCRIBED) then
      call err%set(ERR_INPUT, ctx // ': that coordinate of node ''' // owner // &
        ''' is fixed or prescribed')
    end if
  end subroutine point_of

  !> The first mode of element iel, a hinge (its angle, driven by a torque) or a truss (its
  !> elongation, driven by a force along it: a linear actuator between two nodes). Its q must
  !> be a degree of freedom for an actuator, and exist (dynamic or prescribed) to be measured.
  subroutine joint_point(model, iel, comp, acts, ctx, index, err)
    type(model_t), intent(in) :: model
    integer, intent(in) :: iel
    character(len=*), intent(in) :: comp, ctx
    logical, intent(in) :: acts
    integer, intent(out) :: index
    type(error_t), intent(inout) :: err
    character(len=10) :: want
    logical :: truss
    index = model%mode_first(iel)
    truss = model%elements(iel)%e%type_name() == 'truss'
    if (.not. (truss .or. model%elements(iel)%e%type_name() == 'hinge' .or. &
               model%elements(iel)%e%type_name() == 'hinge3d')) then
      call err%set(ERR_INPUT, ctx // ': ''' // model%elements(iel)%e%label // &
        ''' is no hinge or truss')
      return
    end if
    if (acts) then
      want = merge('force     ', 'torque    ', truss)
    else
      want = merge('elongation', 'angle     ', truss)
    end if
    if (comp /= trim(want)) then
      call err%set(ERR_INPUT, ctx // ': the component is ''' // trim(want) // '''')
    else if (acts .and. model%modes(index)%class /= MODE_DYNAMIC) then
      call err%set(ERR_INPUT, ctx // ': the ' // merge('truss', 'joint', truss) // &
        ' is not dynamic (a controller drives a degree of freedom: mode = ''dynamic'')')
    else if (.not. acts .and. model%modes(index)%q == 0) then
      call err%set(ERR_INPUT, ctx // ': its mode is neither dynamic nor prescribed')
    end if
  end subroutine joint_point

  pure function component_list(dim, acts) result(list)
    integer, intent(in) :: dim
    logical, intent(in) :: acts
    character(len=16) :: list
    if (acts) then
      list = merge('fx, fy, moment', 'fx, fy, fz    ', dim == 2)
    else
      list = merge('x, y, phi', 'x, y, z  ', dim == 2)
    end if
  end function component_list

  pure integer function index_of_dot(name)
    character(len=*), intent(in) :: name
    index_of_dot = index(name, '.', back=.true.)
  end function index_of_dot
end submodule model_build_control
