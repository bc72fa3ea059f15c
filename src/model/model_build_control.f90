!> &controller groups: where each controller measures and acts, resolved on the built model.
submodule (model_build) model_build_control
  use model_control, only: controller_t, ACT_MODE, ACT_COORD, MEAS_MODE, MEAS_COORD, LAW_USER, &
    LAW_PID, controller_sizes
  use model_scene, only: controller_rec_t, label_t
  use model_control_c, only: c_law_t, load_library_law
  use core_strings, only: int_str
  use elements_base, only: mode_class_name
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

  !> The rigid-body model of the scene for the controllers' feedforward: links, trusses,
  !> sliders and spring joints rigid, the joints of the feedforward controllers the only degrees
  !> of freedom, no controllers. ff_q(k): the rigid model's dynamic coordinate (index in q_dy)
  !> that controller k drives, 0 for a controller without feedforward.
  module procedure build_rigid_model
    type(scene_t) :: s
    integer :: i, k, iel
    logical :: driven
    character(len=*), parameter :: ctx = 'feedforward (rigid-body inverse dynamics): '
    s = scene
    do i = 1, size(s%links)
      s%links(i)%elongation = [label_t('rigid')]
      s%links(i)%bending = [label_t('rigid')]
      s%links(i)%damping = 0.0_wp
    end do
    do i = 1, size(s%trusses)
      driven = feedforward_drives(model, s%trusses(i)%label)
      if (.not. driven .and. s%trusses(i)%mode /= 'prescribed') s%trusses(i)%mode = 'rigid'
      if (.not. driven) s%trusses(i)%damping = 0.0_wp
    end do
    do i = 1, size(s%sliders)
      if (s%sliders(i)%mode /= 'prescribed') s%sliders(i)%mode = 'rigid'
      s%sliders(i)%stiffness = 0.0_wp
      s%sliders(i)%damping = 0.0_wp
    end do
    do i = 1, size(s%hinges)
      associate (h => s%hinges(i))
        driven = feedforward_drives(model, h%label)
        h%kp = 0.0_wp
        h%kd = 0.0_wp
        if (driven .or. h%mode == 'prescribed' .or. h%mode == 'rigid' .or. &
            h%mode == 'released') cycle
        if (h%mode == 'dynamic' .and. h%stiffness == 0 .and. scene%hinges(i)%kp == 0) then
          call err%set(ERR_INPUT, ctx // 'hinge ''' // h%label // ''' turns freely and ' // &
            'no feedforward controller drives it: the references alone do not determine the motion')
          return
        end if
        h%mode = 'rigid'
        h%stiffness = 0.0_wp
        h%damping = 0.0_wp
      end associate
    end do
    do i = 1, size(s%nodes)
      if (any(s%nodes(i)%dynamic)) then
        call err%set(ERR_INPUT, ctx // 'node ''' // s%nodes(i)%label // ''' has coordinates ' // &
          'that are degrees of freedom: the references alone do not determine the motion')
        return
      end if
    end do
    deallocate(s%controllers)
    allocate(s%controllers(0))
    call build_model(s, rigid, err)
    if (.not. err%ok()) then
      call err%prefix(ctx // 'the rigid model: ')
      return
    end if
    allocate(ff_q(size(model%controllers)))
    ff_q = 0
    do k = 1, size(model%controllers)
      associate (c => model%controllers(k))
        if (.not. c%feedforward) cycle
        iel = model%modes(c%act_index(1))%element
        do i = 1, rigid%n_elements
          if (rigid%elements(i)%e%label == model%elements(iel)%e%label) &
            ff_q(k) = rigid%modes(rigid%mode_first(i))%q - rigid%n_rh
        end do
      end associate
    end do
    if (rigid%n_dy /= count(ff_q > 0)) call err%set(ERR_INPUT, ctx // 'the rigid model ' // &
      'has ' // int_str(rigid%n_dy) // ' degrees of freedom but ' // int_str(count(ff_q > 0)) // &
      ' feedforward controllers drive joints: every free joint needs one')
  end procedure build_rigid_model

  !> Whether a controller with feedforward drives element `label` (as resolved on the model).
  pure logical function feedforward_drives(model, label)
    type(model_t), intent(in) :: model
    character(len=*), intent(in) :: label
    integer :: k
    feedforward_drives = .false.
    do k = 1, size(model%controllers)
      associate (c => model%controllers(k))
        if (c%feedforward) feedforward_drives = feedforward_drives .or. &
          model%elements(model%modes(c%act_index(1))%element)%e%label == label
      end associate
    end do
  end function feedforward_drives

  subroutine controller_of(scene, model, r, c, err)
    type(scene_t), intent(in) :: scene
    type(model_t), intent(in) :: model
    type(controller_rec_t), intent(in) :: r
    type(controller_t), intent(out) :: c
    type(error_t), intent(inout) :: err
    character(len=:), allocatable :: where
    integer :: i, h
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
    do i = 1, size(r%actuator)
      if (any([(scene%hinges(h)%kp > 0 .and. r%actuator(i)%s == scene%hinges(h)%label // &
                '.torque', h = 1, size(scene%hinges))])) then
        call err%set(ERR_INPUT, where // ': variable ''actuator'': the hinge has a PD of ' // &
          'its own (&hinge kp): give the law in one place')
        return
      end if
    end do
    if (allocated(r%library)) call library_law(r, where, c, err)
    if (.not. r%feedforward .or. .not. err%ok()) return
    ! The rigid model's inverse dynamics gives the torque (force) of a joint that follows its
    ! reference: the controller must drive the joint it measures.
    c%feedforward = .true.
    if (c%law_kind /= LAW_PID) then
      call err%set(ERR_INPUT, where // ': variable ''feedforward'' is for law = ''pid''')
    else if (c%act_kind(1) /= ACT_MODE .or. c%meas_kind(1) /= MEAS_MODE .or. &
        c%act_index(1) /= c%meas_index(1)) then
      call err%set(ERR_INPUT, where // ': variable ''feedforward'' needs the controller to ' // &
        'measure the hinge (truss) it drives')
    else if (c%reference == 0) then
      call err%set(ERR_INPUT, where // ': variable ''feedforward'' needs a ''reference''')
    end if
  end subroutine controller_of

  !> The law of a scene's `library` and `symbol`, with `params`: the model's, as a PID's gains
  !> are, so that every run of the scene has it (the flexmor program, each sweep case, the
  !> error check's second run). A law the program sets later replaces it.
  subroutine library_law(r, where, c, err)
    type(controller_rec_t), intent(in) :: r
    character(len=*), intent(in) :: where
    type(controller_t), intent(inout) :: c
    type(error_t), intent(inout) :: err
    type(c_law_t) :: law
    type(error_t) :: e
    call load_library_law(r%library, r%symbol, r%params, law, e)
    if (e%ok()) then
      allocate(c%user_law, source=law)
    else
      call err%set(e%code, where // ': ' // e%message)
    end if
  end subroutine library_law

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

  !> A mode of element iel: the first mode of a hinge (its angle, driven by a torque) or a truss
  !> (its elongation, driven by a force along it: a linear actuator between two nodes), or, to
  !> be measured, mode j of any element as 'e<j>' (a leaf's bending at its root). Its q must be
  !> a degree of freedom for an actuator, and exist (dynamic or prescribed) to be measured.
  subroutine joint_point(model, iel, comp, acts, ctx, index, err)
    type(model_t), intent(in) :: model
    integer, intent(in) :: iel
    character(len=*), intent(in) :: comp, ctx
    logical, intent(in) :: acts
    integer, intent(out) :: index
    type(error_t), intent(inout) :: err
    character(len=10) :: want
    logical :: truss
    integer :: j, ios
    index = model%mode_first(iel)
    associate (el => model%elements(iel)%e)
      if (.not. acts .and. len(comp) > 1 .and. comp(1:1) == 'e' .and. &
          verify(comp(2:), '0123456789') == 0) then
        read(comp(2:), *, iostat=ios) j
        if (ios /= 0 .or. j < 1 .or. j > el%n_modes()) then
          call err%set(ERR_INPUT, ctx // ': element ''' // el%label // ''' (' // &
            el%type_name() // ') has modes e1 to e' // int_str(el%n_modes()))
        else if (model%modes(index + j - 1)%q == 0) then
          call err%set(ERR_INPUT, ctx // ': that mode is ' // &
            mode_class_name(model%modes(index + j - 1)%class) // ', not a coordinate: ' // &
            'a measured mode must be dynamic or prescribed')
        end if
        index = index + j - 1
        return
      end if
      truss = el%type_name() == 'truss'
      if (.not. (truss .or. el%type_name() == 'hinge' .or. el%type_name() == 'hinge3d')) then
        if (acts) then
          call err%set(ERR_INPUT, ctx // ': ''' // el%label // ''' is no hinge or truss')
        else
          call err%set(ERR_INPUT, ctx // ': ''' // el%label // ''' is no hinge or truss ' // &
            '(any element''s mode j is measured as ''e<j>'')')
        end if
        return
      end if
    end associate
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
