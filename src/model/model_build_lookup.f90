!> Look-ups by label and small checks shared by model_build and its other submodules.
submodule (model_build) model_build_lookup
  implicit none

contains

  module procedure node_index
    do idx = 1, size(scene%nodes)
      if (scene%nodes(idx)%label == label) return
    end do
    idx = 0
  end procedure node_index

  module procedure link_index
    do idx = 1, size(scene%links)
      if (scene%links(idx)%label == label) return
    end do
    idx = 0
  end procedure link_index

  module procedure motion_index
    do idx = 1, size(scene%motions)
      if (scene%motions(idx)%label == label) return
    end do
    idx = 0
  end procedure motion_index

  module procedure time_law_of
    call motion_named(scene, r%time_law, where, 'time_law', im, err)
  end procedure time_law_of

  module procedure check_hinge_ends
    integer :: h, k, il, in
    do h = 1, size(scene%hinges)
      associate (r => scene%hinges(h), where => 'group &hinge ''' // scene%hinges(h)%label // '''')
        call require_node(scene, r%node, where, 'node', in, err)
        if (.not. err%ok()) return
        il = link_index(scene, r%link)
        if (il == 0) then
          call err%set(ERR_INPUT, where // ': variable ''link'': link ''' // r%link // &
            ''' is not defined (no &link with that label)')
          return
        end if
        if (scene%links(il)%from /= r%node .and. scene%links(il)%to /= r%node) then
          call err%set(ERR_INPUT, where // ': link ''' // r%link // ''' does not end at node ''' &
            // r%node // '''')
          return
        end if
        do k = 1, h - 1
          if (scene%hinges(k)%node == r%node .and. scene%hinges(k)%link == r%link) then
            call err%set(ERR_INPUT, where // ': link ''' // r%link // ''' already has a hinge ' &
              // 'at node ''' // r%node // '''')
            return
          end if
        end do
      end associate
    end do
  end procedure check_hinge_ends

  module procedure hinge_class
    c = mode_class_from_name(r%mode)
    im = 0
    if (c == 0) then
      call err%set(ERR_INPUT, where // ': variable ''mode'': ''' // r%mode // &
        ''' is not rigid, released, prescribed, dynamic or elastic')
      return
    end if
    if (c == MODE_PRESCRIBED) then
      im = motion_index(scene, r%motion)
      if (im == 0) then
        call err%set(ERR_INPUT, where // ': variable ''motion'': motion ''' // r%motion // &
          ''' is not defined (no &motion with that label)')
        return
      end if
    end if
    if (r%stiffness < 0 .or. r%damping < 0) then
      call err%set(ERR_INPUT, where // ': stiffness and damping must not be negative')
      return
    end if
    ! Damping is stiffness-proportional (sigma = k (e + damping e_dot)): on a free hinge
    ! it would silently do nothing.
    if (r%damping > 0 .and. (r%stiffness == 0 .or. (c /= MODE_DYNAMIC .and. &
        c /= MODE_ELASTIC))) then
      call err%set(ERR_INPUT, where // ': variable ''damping'' (a time constant, ' // &
        'sigma = k (e + damping de/dt)) needs a dynamic or elastic hinge with stiffness > 0')
    end if
  end procedure hinge_class

  module procedure node_motion
    label = ''
    if (allocated(n%motion(k)%s)) label = n%motion(k)%s
  end procedure node_motion

  module procedure add_node_inputs
    character(len=3), parameter :: names(4) = ['x  ', 'y  ', 'phi', 'z  ']
    integer, parameter :: OFFSET(4) = [0, 1, -1, 2]
    integer :: i, k, idx, im
    do i = 1, size(scene%nodes)
      associate (n => scene%nodes(i), where => 'group &node ''' // scene%nodes(i)%label // '''')
        do k = 1, 4
          if (.not. n%dynamic(k) .and. len(node_motion(n, k)) == 0) cycle
          if (k == 3) then
            idx = node_rot(i)
          else
            idx = node_x(i) + OFFSET(k)
          end if
          if (idx == 0) then
            call err%set(ERR_INPUT, where // ': coordinate phi is dynamic or prescribed but ' // &
              'the node has no rotation (no link end without a hinge and no hinge there)')
            return
          end if
          if (n%dynamic(k)) then
            call model%set_coord_input(idx, MODE_DYNAMIC, 0)
            cycle
          end if
          im = motion_index(scene, node_motion(n, k))
          if (im == 0) then
            call err%set(ERR_INPUT, where // ': variable ''motion_' // trim(names(k)) // &
              ''': motion ''' // node_motion(n, k) // ''' is not defined (no &motion with ' // &
              'that label)')
            return
          end if
          call model%set_coord_input(idx, MODE_PRESCRIBED, im)
        end do
      end associate
    end do
  end procedure add_node_inputs

  module procedure motion_named
    im = 0
    if (.not. allocated(label)) return
    if (len(label) == 0) return
    im = motion_index(scene, label)
    if (im == 0) call err%set(ERR_INPUT, where // ': variable ''' // var // ''': motion ''' // &
      label // ''' is not defined (no &motion with that label)')
  end procedure motion_named

  module procedure hinge_spring
    spring = [r%stiffness, r%damping]
    if (r%kp > 0) spring = [r%kp, r%kd / r%kp]
  end procedure hinge_spring

  module procedure add_hinge_actuator
    integer :: im
    call motion_named(scene, r%torque_law, where, 'torque_law', im, err)
    if (.not. err%ok()) return
    if (r%torque /= 0 .or. im > 0) call model%add_actuator(element, r%torque, im)
    if (r%kp > 0) then
      call motion_named(scene, r%reference, where, 'reference', im, err)
      if (.not. err%ok()) return
      ! The PD law kp (r - e) + kd (r' - e'): the hinge's spring and damping take -kp e -
      ! kd e', the actuator kp r + kd r' (with no reference, r = 0).
      if (im > 0) call model%add_actuator(element, r%kp, im, r%kd)
    end if
  end procedure add_hinge_actuator

  module procedure require_node
    idx = node_index(scene, label)
    if (idx == 0) call err%set(ERR_INPUT, where // ': variable ''' // var // &
      ''': node ''' // label // ''' is not defined (no &node with that label)')
  end procedure require_node

  !> Rotation coordinate of a node, created on first use.
  module procedure node_rotation
    if (b%node_rot(i) == 0) b%node_rot(i) = model%add_coord(0.0_wp, COORD_PHI, &
      scene%nodes(i)%fix_phi, 'node ''' // scene%nodes(i)%label // ''' phi')
    idx = b%node_rot(i)
  end procedure node_rotation

  module procedure require_positive
    character(len=40) :: buf
    if (value > 0.0_wp) return
    write(buf, '(g0)') value
    call err%set(ERR_INPUT, where // ': variable ''' // var // ''' must be positive, got ' // &
      trim(buf))
  end procedure require_positive

  !> A free coordinate that no element uses cannot be solved for.
  module procedure check_connected
    logical :: used(model%n_x)
    integer :: i
    used = model%fixed .or. model%coord_input /= 0
    do i = 1, model%n_elements
      used(model%elements(i)%e%dofs) = .true.
    end do
    do i = 1, model%n_x
      if (.not. used(i)) then
        call err%set(ERR_MODEL, 'coordinate ' // trim(model%coord_name(i)) // &
          ' is free but no element uses it: fix it or connect the node')
        return
      end if
    end do
  end procedure check_connected

  !> Link i: a unique label, existing end nodes (ia, ib) and checked beam properties.
  module procedure link_header
    if (link_index(scene, scene%links(i)%label) /= i) then
      call err%set(ERR_INPUT, 'group &link: label ''' // scene%links(i)%label // &
        ''' is defined twice')
      return
    end if
    call require_node(scene, scene%links(i)%from, where, 'from', ia, err)
    if (err%ok()) call require_node(scene, scene%links(i)%to, where, 'to', ib, err)
    if (err%ok()) call link_beam(scene%links(i), where, beam, err)
  end procedure link_header

  !> A second element of the same label was silently shadowed by the first wherever a
  !> controller or &linear names it ('j1.torque' drove whichever hinge came first).
  module procedure check_element_labels
    type(label_t), allocatable :: labels(:), groups(:)
    integer :: i, k, n, j
    n = size(scene%hinges) + size(scene%trusses) + size(scene%sliders)
    allocate(labels(n), groups(n))
    do i = 1, size(scene%hinges)
      labels(i)%s = scene%hinges(i)%label
      groups(i)%s = '&hinge #' // int_str(i)
    end do
    k = size(scene%hinges)
    do i = 1, size(scene%trusses)
      labels(k + i)%s = scene%trusses(i)%label
      groups(k + i)%s = '&truss #' // int_str(i)
    end do
    k = k + size(scene%trusses)
    do i = 1, size(scene%sliders)
      labels(k + i)%s = scene%sliders(i)%label
      groups(k + i)%s = '&slider #' // int_str(i)
    end do
    do i = 2, n
      do k = 1, i - 1
        if (labels(i)%s == labels(k)%s) then
          call err%set(ERR_INPUT, 'group ' // groups(i)%s // ': label ''' // labels(i)%s // &
            ''' is defined twice (also ' // groups(k)%s // '): hinges, trusses and sliders ' // &
            'need labels of their own')
          return
        end if
      end do
    end do
    ! A &node named like a link's interior node ('arm.1') made '&output nodes' and the
    ! controllers' 'arm.1.y' take whichever came first.
    do i = 1, size(scene%nodes)
      associate (label => scene%nodes(i)%label)
        k = index(label, '.', back=.true.)
        if (k <= 1 .or. k == len(label)) cycle
        if (verify(label(k + 1:), '0123456789') /= 0 .or. len(label) - k > 6) cycle
        n = link_index(scene, label(:k - 1))
        if (n == 0) cycle
        read(label(k + 1:), *) j
        if (j >= 1 .and. j < scene%links(n)%n_elements) then
          call err%set(ERR_INPUT, 'group &node #' // int_str(i) // ': label ''' // label // &
            ''' is the name of interior node ' // int_str(j) // ' of &link ''' // &
            scene%links(n)%label // ''': give the node another label')
          return
        end if
      end associate
    end do
  end procedure check_element_labels

  !> Node i's label is its first.
  module procedure check_node_label
    if (node_index(scene, scene%nodes(i)%label) /= i) call err%set(ERR_INPUT, &
      'group &node: label ''' // scene%nodes(i)%label // ''' is defined twice')
  end procedure check_node_label
end submodule model_build_lookup
