!> Elements of a scene: links meshed into beams (mode classes per element or per bending
!> mode), hinges, trusses and sliders, in that order (the order of the generalised coordinates).
submodule (model_build) model_build_elements
  use elements_base, only: MODE_RIGID, MODE_RELEASED, MODE_PRESCRIBED, MODE_DYNAMIC, &
    MODE_ELASTIC
  use elements_beam, only: beam_t, BENDING_ANGLE, BENDING_SINE
  use elements_hinge, only: hinge_t
  use elements_truss, only: truss_t
  use elements_slider, only: slider_t
  use model_scene, only: link_rec_t, label_t
  implicit none

contains

  module procedure add_links
    integer :: i, k, ia, ib, p(3), q(3), idx, first_rot, last_rot
    real(wp) :: xa(2), xb(2), xk(2)
    type(beam_t) :: beam
    character(len=12) :: num
    do i = 1, size(scene%links)
      associate (r => scene%links(i), where => 'group &link ''' // scene%links(i)%label // '''')
        call link_header(scene, i, where, ia, ib, beam, err)
        if (.not. err%ok()) return
        xa = [scene%nodes(ia)%x, scene%nodes(ia)%y]
        xb = [scene%nodes(ib)%x, scene%nodes(ib)%y]
        if (norm2(xb - xa) <= 1.0e-12_wp * max(1.0_wp, norm2(xa))) then
          call err%set(ERR_INPUT, where // ': nodes ''' // r%from // ''' and ''' // r%to // &
            ''' are at the same place: a link needs a positive length')
          return
        end if
        first_rot = link_end_rotation(scene, model, b, r%label, ia)
        last_rot = link_end_rotation(scene, model, b, r%label, ib)
        p = [b%node_xy(ia), b%node_xy(ia) + 1, first_rot]
        do k = 1, r%n_elements
          if (k < r%n_elements) then
            write(num, '(i0)') k
            xk = xa + (xb - xa) * real(k, wp) / r%n_elements
            q(1) = model%add_coord(xk(1), COORD_X, .false., r%label // '.' // trim(num) // ' x')
            q(2) = model%add_coord(xk(2), COORD_Y, .false., r%label // '.' // trim(num) // ' y')
            q(3) = model%add_coord(0.0_wp, COORD_PHI, .false., r%label // '.' // trim(num) // ' phi')
            call model%add_node_label(r%label // '.' // trim(num), q)
          else
            q = [b%node_xy(ib), b%node_xy(ib) + 1, last_rot]
          end if
          write(num, '(i0)') k
          beam%label = r%label // '#' // trim(num)
          beam%dofs = [p, q]
          beam%l0 = norm2(xb - xa) / r%n_elements
          beam%alpha0 = atan2(xb(2) - xa(2), xb(1) - xa(1))
          beam%phi0 = model%x0([p(3), q(3)])
          beam%mode_class = [class_of(r%elongation, r%n_elements, k, 1), &
            class_of(r%bending, r%n_elements, k, 1), class_of(r%bending, r%n_elements, k, 2)]
          if (r%shear_modulus > 0) beam%shear_p = 12 * beam%ei / (r%shear_factor * &
            r%shear_modulus * r%area * beam%l0**2)
          idx = model%add_element(beam, [0, 0, 0])
          p = q
        end do
      end associate
    end do
  end procedure add_links

  module procedure link_beam
    call require_positive(r%e_modulus, where, 'E', err)
    call require_positive(r%area, where, 'A', err)
    call require_positive(r%inertia, where, 'I', err)
    call require_positive(r%density, where, 'rho', err)
    if (r%n_elements < 1) call err%set(ERR_INPUT, where // ': variable ''n_elements'' must ' // &
      'be at least 1')
    if (r%damping < 0) call err%set(ERR_INPUT, where // ': variable ''damping'' must not be negative')
    if (r%shear_modulus < 0) call err%set(ERR_INPUT, where // ': variable ''G'' must not be negative')
    if (.not. err%ok()) return
    call check_classes(r%elongation, r%n_elements, where, 'elongation', err)
    call check_classes(r%bending, r%n_elements, where, 'bending', err)
    beam%ea = r%e_modulus * r%area
    beam%ei = r%e_modulus * r%inertia
    beam%rho_a = r%density * r%area
    beam%damping = r%damping
    select case (r%bending_form)
    case ('angle'); beam%bending = BENDING_ANGLE
    case ('sine'); beam%bending = BENDING_SINE
    case default
      call err%set(ERR_INPUT, where // ': variable ''bending_form'': ''' // r%bending_form // &
        ''' is neither angle nor sine')
    end select
    select case (r%mass)
    case ('consistent'); beam%consistent = .true.
    case ('lumped'); beam%consistent = .false.
    case default
      call err%set(ERR_INPUT, where // ': variable ''mass'': ''' // r%mass // &
        ''' is neither consistent nor lumped')
    end select
    beam%shear_p = 0.0_wp
  end procedure link_beam

  !> A link's mode classes: 1 or n_elements keywords, each rigid, released, dynamic or
  !> elastic (a beam mode cannot be driven).
  module procedure check_classes
    integer :: k, c
    if (.not. err%ok()) return
    if (size(classes) /= 1 .and. size(classes) /= n .and. &
        .not. (var == 'bending' .and. size(classes) == 2 * n)) then
      call err%set(ERR_INPUT, where // ': variable ''' // var // ''' needs 1 value or one ' // &
        'per element')
      return
    end if
    do k = 1, size(classes)
      c = mode_class_from_name(classes(k)%s)
      if (c == 0 .or. c == MODE_PRESCRIBED) then
        call err%set(ERR_INPUT, where // ': variable ''' // var // ''': ''' // classes(k)%s // &
          ''' is not rigid, released, dynamic or elastic')
        return
      end if
    end do
  end procedure check_classes

  !> Class of mode j (1 or 2: a bending pair's side) of element k of n from a list of 1, n or
  !> 2 n class keywords (checked by check_classes).
  module procedure class_of
    integer :: i
    i = 1
    if (size(classes) == n) i = k
    if (size(classes) == 2 * n) i = 2 * (k - 1) + j
    c = mode_class_from_name(classes(i)%s)
  end procedure class_of

  module procedure add_hinges
    type(hinge_t) :: hinge
    real(wp) :: spring(2)
    integer :: h, in, im, idx, c
    do h = 1, size(scene%hinges)
      associate (r => scene%hinges(h), where => 'group &hinge ''' // scene%hinges(h)%label // '''')
        in = node_index(scene, r%node)
        call hinge_class(scene, r, where, c, im, err)
        if (.not. err%ok()) return
        hinge%label = r%label
        hinge%dofs = [node_rotation(scene, model, b, in), b%hinge_rot(h)]
        hinge%phi0 = model%x0(hinge%dofs)
        hinge%mode_class = [c]
        spring = hinge_spring(r)
        hinge%k = spring(1)
        hinge%damping = spring(2)
        idx = model%add_element(hinge, [im])
        call add_hinge_actuator(scene, model, r, where, idx, err)
        if (.not. err%ok()) return
      end associate
    end do
  end procedure add_hinges

  module procedure add_trusses
    type(truss_t) :: truss
    integer :: i, ia, ib, idx, c, k, im
    do i = 1, size(scene%trusses)
      associate (r => scene%trusses(i), where => 'group &truss ''' // scene%trusses(i)%label // '''')
        call require_node(scene, r%from, where, 'from', ia, err)
        if (err%ok()) call require_node(scene, r%to, where, 'to', ib, err)
        if (err%ok()) call require_positive(r%e_modulus, where, 'E', err)
        if (err%ok()) call require_positive(r%area, where, 'A', err)
        if (.not. err%ok()) return
        c = mode_class_from_name(r%mode)
        if (c == 0 .or. c == MODE_PRESCRIBED) then
          call err%set(ERR_INPUT, where // ': variable ''mode'': ''' // r%mode // &
            ''' is not rigid, released, dynamic or elastic')
          return
        end if
        truss%label = r%label
        truss%dim = dim
        truss%dofs = [(node_x(ia) + k, k = 0, dim - 1), (node_x(ib) + k, k = 0, dim - 1)]
        truss%l0 = norm2(model%x0(truss%dofs(dim + 1:)) - model%x0(truss%dofs(1:dim)))
        if (truss%l0 <= 0) then
          call err%set(ERR_INPUT, where // ': nodes ''' // r%from // ''' and ''' // r%to // &
            ''' are at the same place: a truss needs a positive length')
          return
        end if
        truss%ea = r%e_modulus * r%area
        truss%rho_a = r%density * r%area
        truss%consistent = r%mass /= 'lumped'
        truss%damping = r%damping
        truss%mode_class = [c]
        idx = model%add_element(truss, [0])
        call motion_named(scene, r%force_law, where, 'force_law', im, err)
        if (.not. err%ok()) return
        if (r%force /= 0 .or. im > 0) call model%add_actuator(idx, r%force, im)
      end associate
    end do
  end procedure add_trusses

  !> Sliders, after the trusses (element order: docs/input.md). A scene made by a program may
  !> leave `sliders` unallocated: no sliders.
  module procedure add_sliders
    type(slider_t) :: slider
    integer :: i, in, idx, c, k
    if (.not. allocated(scene%sliders)) return
    do i = 1, size(scene%sliders)
      associate (r => scene%sliders(i), where => 'group &slider ''' // scene%sliders(i)%label // '''')
        call require_node(scene, r%node, where, 'node', in, err)
        if (.not. err%ok()) return
        c = mode_class_from_name(r%mode)
        if (c == 0 .or. c == MODE_PRESCRIBED) then
          call err%set(ERR_INPUT, where // ': variable ''mode'': ''' // r%mode // &
            ''' is not rigid, released, dynamic or elastic')
        else if (norm2(r%direction) == 0) then
          call err%set(ERR_INPUT, where // ': variable ''direction'' is the zero vector')
        else if (r%stiffness < 0 .or. r%damping < 0) then
          call err%set(ERR_INPUT, where // ': stiffness and damping must not be negative')
        else if ((r%stiffness > 0 .or. r%damping > 0) .and. c /= MODE_DYNAMIC .and. &
            c /= MODE_ELASTIC) then
          call err%set(ERR_INPUT, where // ': variable ''stiffness'' and ''damping'' apply ' // &
            'only with mode = ''dynamic'' or ''elastic''')
        else if (r%damping > 0 .and. r%stiffness == 0) then
          ! Stiffness-proportional damping (sigma = k (e + damping de/dt)) of a guide without
          ! a spring would silently do nothing.
          call err%set(ERR_INPUT, where // ': variable ''damping'' (a time constant, ' // &
            'sigma = k (e + damping de/dt)) needs stiffness > 0')
        end if
        if (.not. err%ok()) return
        slider%label = r%label
        slider%dofs = [(node_x(in) + k, k = 0, dim - 1)]
        slider%x_ref = model%x0(slider%dofs)
        call slider%set_direction(r%direction)
        slider%mode_class = [(c, k = 1, dim - 1)]
        slider%k = r%stiffness
        slider%damping = r%damping
        idx = model%add_element(slider, [(0, k = 1, dim - 1)])
      end associate
    end do
  end procedure add_sliders

  !> Rotation coordinate a link uses at one of its end nodes.
  integer function link_end_rotation(scene, model, b, link, node) result(idx)
    type(scene_t), intent(in) :: scene
    type(model_t), intent(inout) :: model
    type(builder_t), intent(inout) :: b
    character(len=*), intent(in) :: link
    integer, intent(in) :: node
    integer :: h
    do h = 1, size(scene%hinges)
      if (scene%hinges(h)%link == link .and. scene%hinges(h)%node == scene%nodes(node)%label) then
        if (b%hinge_rot(h) == 0) b%hinge_rot(h) = model%add_coord(0.0_wp, COORD_PHI, .false., &
          'link ''' // link // ''' phi at node ''' // scene%nodes(node)%label // '''')
        idx = b%hinge_rot(h)
        return
      end if
    end do
    idx = node_rotation(scene, model, b, node)
  end function link_end_rotation

end submodule model_build_elements
