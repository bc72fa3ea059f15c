!> Turns a scene (plain records) into a finalised model: meshes links into beams, gives
!> hinged link ends rotations of their own, places masses, loads and motions, and checks
!> references and values. Messages name the group, the record's label and the variable; the
!> caller puts the file name in front.
module model_build
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_INPUT, ERR_MODEL
  use core_strings, only: int_str, approx_str
  use elements_base, only: MODE_RIGID, MODE_RELEASED, MODE_PRESCRIBED, MODE_DYNAMIC, &
    MODE_ELASTIC
  use elements_beam, only: beam_t, BENDING_ANGLE, BENDING_SINE
  use elements_hinge, only: hinge_t
  use elements_truss, only: truss_t
  use elements_slider, only: slider_t
  use motion_law, only: motion_t, law_from_name, motion_sum, motion_table, table_problem, &
    LAW_CONSTANT, LAW_RAMP, LAW_HARMONIC, LAW_SUM, LAW_TABLE, BANDWIDTH_UNBOUNDED
  use model_system, only: model_t, COORD_X, COORD_Y, COORD_PHI
  use model_scene, only: scene_t, link_rec_t, label_t, node_rec_t
  implicit none
  private
  public :: build_model, mode_class_from_name, unused_motions, MAX_COORDINATES

  !> Largest model built: every analysis works on dense matrices of the coordinates, so memory
  !> grows as n^2 (about DENSE_BYTES_PER_N2 n^2 bytes: 13 GB at the limit) and a step's cost as
  !> n^2 to n^3; beyond this a run would not end in any reasonable time.
  integer, parameter :: MAX_COORDINATES = 10000
  real(wp), parameter :: DENSE_BYTES_PER_N2 = 128.0_wp

  !> Work data of one build; lives only during build_model.
  type :: builder_t
    integer, allocatable :: node_xy(:)      !< first coordinate (x) of each scene node
    integer, allocatable :: node_rot(:)     !< rotation coordinate of each node, 0 until used
    integer, allocatable :: hinge_rot(:)    !< rotation coordinate of each hinged link end
  end type builder_t

contains

  pure integer function mode_class_from_name(name) result(c)
    character(len=*), intent(in) :: name
    select case (name)
    case ('rigid'); c = MODE_RIGID
    case ('released'); c = MODE_RELEASED
    case ('prescribed'); c = MODE_PRESCRIBED
    case ('dynamic'); c = MODE_DYNAMIC
    case ('elastic'); c = MODE_ELASTIC
    case default; c = 0
    end select
  end function mode_class_from_name

  subroutine build_model(scene, model, err)
    type(scene_t), intent(in) :: scene
    type(model_t), intent(out) :: model
    type(error_t), intent(out) :: err
    type(builder_t) :: b
    integer :: i
    call check_size(scene, err); if (.not. err%ok()) return
    call model%init()
    model%gravity = scene%gravity
    call add_nodes(scene, model, b, err); if (.not. err%ok()) return
    call add_motions(scene, model, err); if (.not. err%ok()) return
    call check_hinges(scene, b, err); if (.not. err%ok()) return
    call add_links(scene, model, b, err); if (.not. err%ok()) return
    call add_hinges(scene, model, b, err); if (.not. err%ok()) return
    call add_trusses(scene, model, b, err); if (.not. err%ok()) return
    call add_sliders(scene, model, b, err); if (.not. err%ok()) return
    call add_masses_and_loads(scene, model, b, err); if (.not. err%ok()) return
    call add_node_inputs(scene, model, b, err); if (.not. err%ok()) return
    call check_connected(model, err); if (.not. err%ok()) return
    do i = 1, size(scene%nodes)
      call model%add_node_label(scene%nodes(i)%label, [b%node_xy(i), b%node_xy(i) + 1, &
        b%node_rot(i)])
    end do
    call model%finalize(err)
  end subroutine build_model

  !> Labels of the motions no hinge refers to, directly or as a term of a sum it uses: a
  !> forgotten or misspelt reference, or a joint released for a trial. Not an error, but the
  !> user hears of it (analysis_run warns).
  function unused_motions(scene) result(labels)
    type(scene_t), intent(in) :: scene
    character(len=:), allocatable :: labels
    logical :: used(size(scene%motions)), grew
    integer :: i, h, k, j
    do i = 1, size(scene%motions)
      used(i) = any([(scene%hinges(h)%motion == scene%motions(i)%label, h = 1, size(scene%hinges))])
      do h = 1, size(scene%nodes)
        used(i) = used(i) .or. any([(node_motion(scene%nodes(h), k) == scene%motions(i)%label, &
          k = 1, 3)])
      end do
      do h = 1, size(scene%forces)
        if (allocated(scene%forces(h)%time_law)) used(i) = used(i) .or. &
          scene%forces(h)%time_law == scene%motions(i)%label
      end do
    end do
    grew = .true.
    do while (grew)
      grew = .false.
      do i = 1, size(scene%motions)
        if (.not. used(i) .or. .not. allocated(scene%motions(i)%terms)) cycle
        do k = 1, size(scene%motions(i)%terms)
          j = motion_index(scene, scene%motions(i)%terms(k)%s)
          if (j == 0) cycle
          grew = grew .or. .not. used(j)
          used(j) = .true.
        end do
      end do
    end do
    labels = ''
    do i = 1, size(scene%motions)
      if (used(i)) cycle
      if (len(labels) > 0) labels = labels // ', '
      labels = labels // '''' // scene%motions(i)%label // ''''
    end do
  end function unused_motions

  !> Refuse a scene too large for dense linear algebra before anything is allocated. The count
  !> is an upper bound from the records (reals: n_elements may be near huge()).
  subroutine check_size(scene, err)
    type(scene_t), intent(in) :: scene
    type(error_t), intent(out) :: err
    real(wp) :: n
    integer :: i
    ! Every node x, y, phi; per link 3 per inner node; per hinge a link-end rotation.
    n = 3.0_wp * size(scene%nodes) + 2.0_wp * size(scene%hinges)
    do i = 1, size(scene%links)
      n = n + 3.0_wp * (real(scene%links(i)%n_elements, wp) - 1.0_wp)
    end do
    if (n <= MAX_COORDINATES) return
    call err%set(ERR_INPUT, 'the scene is too large: about ' // approx_str(n) // &
      ' nodal coordinates, limit ' // int_str(MAX_COORDINATES) // ' (dense matrices would ' // &
      'need about ' // approx_str(DENSE_BYTES_PER_N2 * n**2 / 1.0e9_wp) // &
      ' GB; reduce n_elements of the &link groups)')
  end subroutine check_size

  integer function node_index(scene, label) result(idx)
    type(scene_t), intent(in) :: scene
    character(len=*), intent(in) :: label
    do idx = 1, size(scene%nodes)
      if (scene%nodes(idx)%label == label) return
    end do
    idx = 0
  end function node_index

  integer function link_index(scene, label) result(idx)
    type(scene_t), intent(in) :: scene
    character(len=*), intent(in) :: label
    do idx = 1, size(scene%links)
      if (scene%links(idx)%label == label) return
    end do
    idx = 0
  end function link_index

  integer function motion_index(scene, label) result(idx)
    type(scene_t), intent(in) :: scene
    character(len=*), intent(in) :: label
    do idx = 1, size(scene%motions)
      if (scene%motions(idx)%label == label) return
    end do
    idx = 0
  end function motion_index

  !> Error unless value > 0.
  subroutine require_positive(value, where, var, err)
    real(wp), intent(in) :: value
    character(len=*), intent(in) :: where, var
    type(error_t), intent(inout) :: err
    character(len=40) :: buf
    if (value > 0.0_wp) return
    write(buf, '(g0)') value
    call err%set(ERR_INPUT, where // ': variable ''' // var // ''' must be positive, got ' // &
      trim(buf))
  end subroutine require_positive

  subroutine require_node(scene, label, where, var, idx, err)
    type(scene_t), intent(in) :: scene
    character(len=*), intent(in) :: label, where, var
    integer, intent(out) :: idx
    type(error_t), intent(inout) :: err
    idx = node_index(scene, label)
    if (idx == 0) call err%set(ERR_INPUT, where // ': variable ''' // var // &
      ''': node ''' // label // ''' is not defined (no &node with that label)')
  end subroutine require_node

  subroutine add_nodes(scene, model, b, err)
    type(scene_t), intent(in) :: scene
    type(model_t), intent(inout) :: model
    type(builder_t), intent(inout) :: b
    type(error_t), intent(inout) :: err
    integer :: i, ix, iy
    allocate(b%node_xy(size(scene%nodes)), b%node_rot(size(scene%nodes)))
    b%node_rot = 0
    do i = 1, size(scene%nodes)
      associate (n => scene%nodes(i))
        if (node_index(scene, n%label) /= i) then
          call err%set(ERR_INPUT, 'group &node: label ''' // n%label // ''' is defined twice')
          return
        end if
        ix = model%add_coord(n%x, COORD_X, n%fix_x, 'node ''' // n%label // ''' x')
        iy = model%add_coord(n%y, COORD_Y, n%fix_y, 'node ''' // n%label // ''' y')
        b%node_xy(i) = ix
      end associate
    end do
  end subroutine add_nodes

  !> Rotation coordinate of a node, created on first use.
  integer function node_rotation(scene, model, b, i) result(idx)
    type(scene_t), intent(in) :: scene
    type(model_t), intent(inout) :: model
    type(builder_t), intent(inout) :: b
    integer, intent(in) :: i
    if (b%node_rot(i) == 0) b%node_rot(i) = model%add_coord(0.0_wp, COORD_PHI, &
      scene%nodes(i)%fix_phi, 'node ''' // scene%nodes(i)%label // ''' phi')
    idx = b%node_rot(i)
  end function node_rotation

  subroutine add_motions(scene, model, err)
    type(scene_t), intent(in) :: scene
    type(model_t), intent(inout) :: model
    type(error_t), intent(inout) :: err
    type(motion_t) :: mo
    integer :: i, idx
    do i = 1, size(scene%motions)
      if (motion_index(scene, scene%motions(i)%label) /= i) then
        call err%set(ERR_INPUT, 'group &motion: label ''' // scene%motions(i)%label // &
          ''' is defined twice')
        return
      end if
    end do
    do i = 1, size(scene%motions)
      call make_motion(scene, i, [integer ::], mo, err)
      if (.not. err%ok()) return
      ! The fraction does not matter here: a velocity step has no finite bandwidth at all.
      if (scene%reduction%active .and. scene%reduction%auto_factor > 0) then
        if (mo%bandwidth_hz(0.5_wp) == BANDWIDTH_UNBOUNDED) then
          call err%set(ERR_INPUT, 'group &motion ''' // mo%label // ''': its velocity steps ' &
            // '(law ''ramp''), which has no finite bandwidth: &reduction auto_factor cannot ' &
            // 'use it; give n_modes or cutoff_hz')
          return
        end if
      end if
      idx = model%add_motion(mo)
    end do
  end subroutine add_motions

  !> The motion of scene%motions(i); `chain` holds the sums that lead to it, to refuse cycles.
  recursive subroutine make_motion(scene, i, chain, mo, err)
    type(scene_t), intent(in) :: scene
    integer, intent(in) :: i, chain(:)
    type(motion_t), intent(out) :: mo
    type(error_t), intent(inout) :: err
    type(motion_t), allocatable :: terms(:)
    character(len=:), allocatable :: msg
    integer :: k, j
    associate (r => scene%motions(i), where => 'group &motion ''' // scene%motions(i)%label // '''')
      select case (law_from_name(r%law))
      case (-1)
        call err%set(ERR_INPUT, where // ': variable ''law'': unknown law ''' // r%law // &
          ''' (use constant, cubic, quintic, cycloidal, ramp, harmonic, spin_up, sum or table)')
      case (LAW_SUM)
        if (.not. allocated(r%terms)) allocate(terms(0))
        if (allocated(r%terms)) allocate(terms(size(r%terms)))
        if (size(terms) == 0) call err%set(ERR_INPUT, where // ': variable ''terms'' is empty')
        do k = 1, size(terms)
          j = motion_index(scene, r%terms(k)%s)
          msg = where // ': variable ''terms'': motion ''' // r%terms(k)%s // ''''
          if (j == 0) then
            call err%set(ERR_INPUT, msg // ' is not defined (no &motion with that label)')
          else if (j == i .or. any(chain == j)) then
            call err%set(ERR_INPUT, msg // ' is this sum or contains it: a sum may not ' // &
              'contain itself (' // cycle_text(scene, [chain, i, j]) // ')')
          else
            call make_motion(scene, j, [chain, i], terms(k), err)
          end if
          if (.not. err%ok()) return
        end do
        if (err%ok()) mo = motion_sum(r%label, terms)
      case (LAW_TABLE)
        msg = 'a table needs times and values'
        if (allocated(r%times) .and. allocated(r%values)) msg = table_problem(r%times, r%values)
        if (len(msg) > 0) then
          call err%set(ERR_INPUT, where // ': variable ''times'': ' // msg)
        else
          mo = motion_table(r%label, r%times, r%values)
        end if
      case default
        mo = motion_t(law=law_from_name(r%law), start=r%start, end=r%end, &
          t0=r%t0, duration=r%duration, rate=r%rate, amplitude=r%amplitude, &
          frequency=r%frequency, phase=r%phase)
        if (all(mo%law /= [LAW_CONSTANT, LAW_RAMP, LAW_HARMONIC])) &
          call require_positive(r%duration, where, 'duration', err)
        if (mo%law == LAW_HARMONIC) call require_positive(r%frequency, where, 'frequency', err)
      end select
    end associate
    ! Outside the associate: gfortran 12 loses a deferred-length component given there.
    mo%label = scene%motions(i)%label
  end subroutine make_motion

  !> 'a' -> 'b' -> 'a': the labels of the motions `chain` from where its cycle starts.
  function cycle_text(scene, chain) result(s)
    type(scene_t), intent(in) :: scene
    integer, intent(in) :: chain(:)
    character(len=:), allocatable :: s
    integer :: k
    s = ''
    do k = findloc(chain, chain(size(chain)), dim=1), size(chain)
      if (len(s) > 0) s = s // ' -> '
      s = s // '''' // scene%motions(chain(k))%label // ''''
    end do
  end function cycle_text

  !> Every hinge names an existing node and a link that ends there, once.
  subroutine check_hinges(scene, b, err)
    type(scene_t), intent(in) :: scene
    type(builder_t), intent(inout) :: b
    type(error_t), intent(inout) :: err
    integer :: h, k, il, in
    allocate(b%hinge_rot(size(scene%hinges)))
    b%hinge_rot = 0
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
  end subroutine check_hinges

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

  subroutine add_links(scene, model, b, err)
    type(scene_t), intent(in) :: scene
    type(model_t), intent(inout) :: model
    type(builder_t), intent(inout) :: b
    type(error_t), intent(inout) :: err
    integer :: i, k, ia, ib, p(3), q(3), idx, first_rot, last_rot
    real(wp) :: xa(2), xb(2), xk(2)
    type(beam_t) :: beam
    character(len=12) :: num
    do i = 1, size(scene%links)
      associate (r => scene%links(i), where => 'group &link ''' // scene%links(i)%label // '''')
        if (link_index(scene, r%label) /= i) then
          call err%set(ERR_INPUT, 'group &link: label ''' // r%label // ''' is defined twice')
          return
        end if
        call require_node(scene, r%from, where, 'from', ia, err)
        if (err%ok()) call require_node(scene, r%to, where, 'to', ib, err)
        if (err%ok()) call link_beam(r, where, beam, err)
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
  end subroutine add_links

  !> Beam properties and mode classes shared by all elements of a link.
  subroutine link_beam(r, where, beam, err)
    type(link_rec_t), intent(in) :: r
    character(len=*), intent(in) :: where
    type(beam_t), intent(out) :: beam
    type(error_t), intent(inout) :: err
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
  end subroutine link_beam

  !> A link's mode classes: 1 or n_elements keywords, each rigid, released, dynamic or
  !> elastic (a beam mode cannot be driven).
  subroutine check_classes(classes, n, where, var, err)
    type(label_t), intent(in) :: classes(:)
    integer, intent(in) :: n
    character(len=*), intent(in) :: where, var
    type(error_t), intent(inout) :: err
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
  end subroutine check_classes

  !> Class of mode j (1 or 2: a bending pair's side) of element k of n from a list of 1, n or
  !> 2 n class keywords (checked by check_classes).
  integer function class_of(classes, n, k, j)
    type(label_t), intent(in) :: classes(:)
    integer, intent(in) :: n, k, j
    integer :: i
    i = 1
    if (size(classes) == n) i = k
    if (size(classes) == 2 * n) i = 2 * (k - 1) + j
    class_of = mode_class_from_name(classes(i)%s)
  end function class_of

  subroutine add_hinges(scene, model, b, err)
    type(scene_t), intent(in) :: scene
    type(model_t), intent(inout) :: model
    type(builder_t), intent(inout) :: b
    type(error_t), intent(inout) :: err
    type(hinge_t) :: hinge
    integer :: h, in, im, idx, c
    do h = 1, size(scene%hinges)
      associate (r => scene%hinges(h), where => 'group &hinge ''' // scene%hinges(h)%label // '''')
        in = node_index(scene, r%node)
        c = mode_class_from_name(r%mode)
        if (c == 0) then
          call err%set(ERR_INPUT, where // ': variable ''mode'': ''' // r%mode // &
            ''' is not rigid, released, prescribed, dynamic or elastic')
          return
        end if
        im = 0
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
          return
        end if
        hinge%label = r%label
        hinge%dofs = [node_rotation(scene, model, b, in), b%hinge_rot(h)]
        hinge%phi0 = model%x0(hinge%dofs)
        hinge%mode_class = [c]
        hinge%k = r%stiffness
        hinge%damping = r%damping
        idx = model%add_element(hinge, [im])
      end associate
    end do
  end subroutine add_hinges

  subroutine add_trusses(scene, model, b, err)
    type(scene_t), intent(in) :: scene
    type(model_t), intent(inout) :: model
    type(builder_t), intent(in) :: b
    type(error_t), intent(inout) :: err
    type(truss_t) :: truss
    integer :: i, ia, ib, idx, c
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
        truss%dofs = [b%node_xy(ia), b%node_xy(ia) + 1, b%node_xy(ib), b%node_xy(ib) + 1]
        truss%l0 = norm2(model%x0(truss%dofs(3:4)) - model%x0(truss%dofs(1:2)))
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
      end associate
    end do
  end subroutine add_trusses

  !> Sliders, after the trusses (element order: docs/input.md). A scene made by a program may
  !> leave `sliders` unallocated: no sliders.
  subroutine add_sliders(scene, model, b, err)
    type(scene_t), intent(in) :: scene
    type(model_t), intent(inout) :: model
    type(builder_t), intent(in) :: b
    type(error_t), intent(inout) :: err
    type(slider_t) :: slider
    integer :: i, in, idx, c
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
        slider%dofs = [b%node_xy(in), b%node_xy(in) + 1]
        slider%x_ref = model%x0(slider%dofs)
        call slider%set_direction(r%direction)
        slider%mode_class = [c]
        slider%k = r%stiffness
        slider%damping = r%damping
        idx = model%add_element(slider, [0])
      end associate
    end do
  end subroutine add_sliders

  subroutine add_masses_and_loads(scene, model, b, err)
    type(scene_t), intent(in) :: scene
    type(model_t), intent(inout) :: model
    type(builder_t), intent(inout) :: b
    type(error_t), intent(inout) :: err
    integer :: i, in, ix, ir, im
    real(wp), allocatable :: diag(:)
    real(wp) :: shape(model%n_x)
    do i = 1, size(scene%masses)
      associate (r => scene%masses(i))
        call require_node(scene, r%node, 'group &mass #' // int_str(i), 'node', in, err)
        if (.not. err%ok()) return
        if (r%m < 0 .or. r%j < 0) then
          call err%set(ERR_INPUT, 'group &mass #' // int_str(i) // ' (node ''' // r%node // &
            '''): m and J must not be negative')
          return
        end if
        ix = b%node_xy(in)
        model%lumped(ix:ix + 1) = model%lumped(ix:ix + 1) + r%m
        if (r%j > 0) then
          ir = b%node_rot(in)
          if (ir == 0) then
            call err%set(ERR_INPUT, 'group &mass #' // int_str(i) // ': node ''' // r%node // &
              ''' has no rotation (no beam or hinge ends there), so J cannot be placed')
            return
          end if
          model%lumped(ir) = model%lumped(ir) + r%j
        end if
      end associate
    end do
    do i = 1, size(scene%forces)
      associate (r => scene%forces(i))
        call require_node(scene, r%node, 'group &force #' // int_str(i), 'node', in, err)
        if (.not. err%ok()) return
        shape = 0.0_wp
        ix = b%node_xy(in)
        shape(ix:ix + 1) = [r%fx, r%fy]
        if (r%moment /= 0) then
          if (b%node_rot(in) == 0) then
            call err%set(ERR_INPUT, 'group &force #' // int_str(i) // ': node ''' // r%node // &
              ''' has no rotation, so a moment cannot be applied')
            return
          end if
          shape(b%node_rot(in)) = r%moment
        end if
        im = 0
        if (allocated(r%time_law)) then
          if (len(r%time_law) > 0) then
            im = motion_index(scene, r%time_law)
            if (im == 0) then
              call err%set(ERR_INPUT, 'group &force #' // int_str(i) // ': variable ' // &
                '''time_law'': motion ''' // r%time_law // ''' is not defined (no &motion ' // &
                'with that label)')
              return
            end if
          end if
        end if
        if (im == 0) then
          model%force = model%force + shape
        else
          call model%add_timed_load(shape, im)
        end if
      end associate
    end do
    do i = 1, model%n_elements
      allocate(diag(size(model%elements(i)%e%dofs)))
      call model%elements(i)%e%lumped_mass(diag)
      model%lumped(model%elements(i)%e%dofs) = model%lumped(model%elements(i)%e%dofs) + diag
      deallocate(diag)
    end do
    model%newton_tol = 1.0e-11_wp * max(1.0e-3_wp, maxval(abs(model%x0)))
  end subroutine add_masses_and_loads

  !> Label of the motion prescribing coordinate k (x, y, phi) of a node, '' if none.
  pure function node_motion(n, k) result(label)
    type(node_rec_t), intent(in) :: n
    integer, intent(in) :: k
    character(len=:), allocatable :: label
    label = ''
    if (allocated(n%motion(k)%s)) label = n%motion(k)%s
  end function node_motion

  !> Nodal coordinates that are inputs (`dynamic`, `motion_*` of &node). A rotation exists
  !> only when an element uses it, so this runs after all elements are added.
  subroutine add_node_inputs(scene, model, b, err)
    type(scene_t), intent(in) :: scene
    type(model_t), intent(inout) :: model
    type(builder_t), intent(in) :: b
    type(error_t), intent(inout) :: err
    character(len=3), parameter :: names(3) = ['x  ', 'y  ', 'phi']
    integer :: i, k, idx, im
    do i = 1, size(scene%nodes)
      associate (n => scene%nodes(i), where => 'group &node ''' // scene%nodes(i)%label // '''')
        do k = 1, 3
          if (.not. n%dynamic(k) .and. len(node_motion(n, k)) == 0) cycle
          idx = b%node_xy(i) + k - 1
          if (k == 3) idx = b%node_rot(i)
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
  end subroutine add_node_inputs

  !> A free coordinate that no element uses cannot be solved for.
  subroutine check_connected(model, err)
    type(model_t), intent(in) :: model
    type(error_t), intent(inout) :: err
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
  end subroutine check_connected

end module model_build
