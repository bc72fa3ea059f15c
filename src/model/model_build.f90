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
  use model_system, only: model_t, COORD_X, COORD_Y, COORD_PHI
  use model_scene, only: scene_t, node_rec_t, link_rec_t, force_rec_t, mass_rec_t, hinge_rec_t, label_t
  use elements_beam, only: beam_t
  implicit none
  private
  public :: build_model, mode_class_from_name, unused_motions, MAX_COORDINATES, build_rigid_model

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

  ! The elements (links, hinges, trusses, sliders) and the motions are built in the
  ! submodules model_build_elements and model_build_motions; the look-ups they share with
  ! this module live in model_build_lookup (gfortran gives private procedures of a module
  ! internal linkage, so submodules can reach only separate module procedures).
  interface
    module subroutine add_links(scene, model, b, err)
      type(scene_t), intent(in) :: scene
      type(model_t), intent(inout) :: model
      type(builder_t), intent(inout) :: b
      type(error_t), intent(inout) :: err
    end subroutine add_links
    module subroutine add_hinges(scene, model, b, err)
      type(scene_t), intent(in) :: scene
      type(model_t), intent(inout) :: model
      type(builder_t), intent(inout) :: b
      type(error_t), intent(inout) :: err
    end subroutine add_hinges
    !> Trusses between nodes whose translations start at node_x (dim of them: 2 or 3).
    module subroutine add_trusses(scene, model, node_x, dim, err)
      type(scene_t), intent(in) :: scene
      type(model_t), intent(inout) :: model
      integer, intent(in) :: node_x(:), dim
      type(error_t), intent(inout) :: err
    end subroutine add_trusses
    !> Sliders on nodes whose translations start at node_x (dim of them: 2 or 3).
    module subroutine add_sliders(scene, model, node_x, dim, err)
      type(scene_t), intent(in) :: scene
      type(model_t), intent(inout) :: model
      integer, intent(in) :: node_x(:), dim
      type(error_t), intent(inout) :: err
    end subroutine add_sliders
    !> Beam properties and mode classes shared by all elements of a link (checked).
    module subroutine link_beam(r, where, beam, err)
      type(link_rec_t), intent(in) :: r
      character(len=*), intent(in) :: where
      type(beam_t), intent(out) :: beam
      type(error_t), intent(inout) :: err
    end subroutine link_beam
    !> A link's mode classes: 1 or n_elements keywords (bending: also 2 n_elements), each
    !> rigid, released, dynamic or elastic (a beam mode cannot be driven).
    module subroutine check_classes(classes, n, where, var, err)
      type(label_t), intent(in) :: classes(:)
      integer, intent(in) :: n
      character(len=*), intent(in) :: where, var
      type(error_t), intent(inout) :: err
    end subroutine check_classes
    !> Class of mode j (1 or 2: a bending pair's side) of element k of n.
    module function class_of(classes, n, k, j) result(c)
      type(label_t), intent(in) :: classes(:)
      integer, intent(in) :: n, k, j
      integer :: c
    end function class_of
    !> Link i: a unique label, existing end nodes (ia, ib) and checked beam properties.
    module subroutine link_header(scene, i, where, ia, ib, beam, err)
      type(scene_t), intent(in) :: scene
      integer, intent(in) :: i
      character(len=*), intent(in) :: where
      integer, intent(out) :: ia, ib
      type(beam_t), intent(out) :: beam
      type(error_t), intent(inout) :: err
    end subroutine link_header
    !> Hinge, truss and slider labels name elements (controllers, &linear): each once; node
    !> labels are not those of links' interior nodes.
    module subroutine check_element_labels(scene, err)
      type(scene_t), intent(in) :: scene
      type(error_t), intent(inout) :: err
    end subroutine check_element_labels
    !> Node i's label is not defined by an earlier node.
    module subroutine check_node_label(scene, i, err)
      type(scene_t), intent(in) :: scene
      integer, intent(in) :: i
      type(error_t), intent(inout) :: err
    end subroutine check_node_label
    !> A free coordinate that no element uses cannot be solved for (model_build_lookup).
    module subroutine check_connected(model, err)
      type(model_t), intent(in) :: model
      type(error_t), intent(inout) :: err
    end subroutine check_connected
    !> The spatial scene (&scene dimension = 3), in submodule model_build_spatial.
    module subroutine build_spatial(scene, model, err)
      type(scene_t), intent(in) :: scene
      type(model_t), intent(inout) :: model
      type(error_t), intent(inout) :: err
    end subroutine build_spatial
    !> Index of the node, link or motion of that label in the scene, 0 if there is none.
    pure module function node_index(scene, label) result(idx)
      type(scene_t), intent(in) :: scene
      character(len=*), intent(in) :: label
      integer :: idx
    end function node_index
    pure module function link_index(scene, label) result(idx)
      type(scene_t), intent(in) :: scene
      character(len=*), intent(in) :: label
      integer :: idx
    end function link_index
    pure module function motion_index(scene, label) result(idx)
      type(scene_t), intent(in) :: scene
      character(len=*), intent(in) :: label
      integer :: idx
    end function motion_index
    !> The motion a force follows in time (its `time_law`), 0 if it is constant; an input
    !> error naming `where` if no &motion has that label.
    module subroutine time_law_of(scene, r, where, im, err)
      type(scene_t), intent(in) :: scene
      type(force_rec_t), intent(in) :: r
      character(len=*), intent(in) :: where
      integer, intent(out) :: im
      type(error_t), intent(inout) :: err
    end subroutine time_law_of
    !> Each hinge names a node and a link that ends there, at most one hinge per (link, node).
    module subroutine check_hinge_ends(scene, err)
      type(scene_t), intent(in) :: scene
      type(error_t), intent(inout) :: err
    end subroutine check_hinge_ends
    !> A hinge's mode class and motion (0 unless prescribed), with the checks of its mode,
    !> motion, stiffness and damping.
    module subroutine hinge_class(scene, r, where, c, im, err)
      type(scene_t), intent(in) :: scene
      type(hinge_rec_t), intent(in) :: r
      character(len=*), intent(in) :: where
      integer, intent(out) :: c, im
      type(error_t), intent(inout) :: err
    end subroutine hinge_class
    !> Label of the motion prescribing coordinate k (x, y, phi, z) of a node, '' if none.
    pure module function node_motion(n, k) result(label)
      type(node_rec_t), intent(in) :: n
      integer, intent(in) :: k
      character(len=:), allocatable :: label
    end function node_motion
    !> Nodal coordinates that are inputs (`dynamic`, `motion_*` of &node): x, y, z from the
    !> first translation node_x of each node, phi from node_rot (0: the node has none). A
    !> rotation exists only when an element uses it, so this runs after all elements.
    module subroutine add_node_inputs(scene, model, node_x, node_rot, err)
      type(scene_t), intent(in) :: scene
      type(model_t), intent(inout) :: model
      integer, intent(in) :: node_x(:), node_rot(:)
      type(error_t), intent(inout) :: err
    end subroutine add_node_inputs
    !> The motion a variable `var` of a group names (`label`; not allocated or '': none, 0);
    !> an input error naming `where` and `var` if no &motion has that label.
    module subroutine motion_named(scene, label, where, var, im, err)
      type(scene_t), intent(in) :: scene
      character(len=:), allocatable, intent(in) :: label
      character(len=*), intent(in) :: where, var
      integer, intent(out) :: im
      type(error_t), intent(inout) :: err
    end subroutine motion_named
    !> A hinge's spring [N m/rad] and damping time constant [s]: `stiffness` and `damping`,
    !> or those of its PD controller, kp and kd/kp (add_hinge_actuator adds the rest).
    pure module function hinge_spring(r) result(spring)
      type(hinge_rec_t), intent(in) :: r
      real(wp) :: spring(2)
    end function hinge_spring
    !> The hinge's actuator (`torque`, `torque_law`) on element `element`, if it has one.
    module subroutine add_hinge_actuator(scene, model, r, where, element, err)
      type(scene_t), intent(in) :: scene
      type(model_t), intent(inout) :: model
      type(hinge_rec_t), intent(in) :: r
      character(len=*), intent(in) :: where
      integer, intent(in) :: element
      type(error_t), intent(inout) :: err
    end subroutine add_hinge_actuator
    !> The node `label` names, or an input error naming `where` and `var`.
    module subroutine require_node(scene, label, where, var, idx, err)
      type(scene_t), intent(in) :: scene
      character(len=*), intent(in) :: label, where, var
      integer, intent(out) :: idx
      type(error_t), intent(inout) :: err
    end subroutine require_node
    !> Rotation coordinate of node i, created on first use.
    module function node_rotation(scene, model, b, i) result(idx)
      type(scene_t), intent(in) :: scene
      type(model_t), intent(inout) :: model
      type(builder_t), intent(inout) :: b
      integer, intent(in) :: i
      integer :: idx
    end function node_rotation
    !> An input error naming `where` and `var` unless value > 0.
    module subroutine require_positive(value, where, var, err)
      real(wp), intent(in) :: value
      character(len=*), intent(in) :: where, var
      type(error_t), intent(inout) :: err
    end subroutine require_positive
    !> The &controller groups of a built model: what each measures and drives (checked).
    module subroutine add_controllers(scene, model, err)
      type(scene_t), intent(in) :: scene
      type(model_t), intent(inout) :: model
      type(error_t), intent(inout) :: err
    end subroutine add_controllers
    module subroutine build_rigid_model(scene, model, rigid, ff_q, err)
      type(scene_t), intent(in) :: scene
      type(model_t), intent(in) :: model
      type(model_t), intent(out) :: rigid
      integer, allocatable, intent(out) :: ff_q(:)
      type(error_t), intent(inout) :: err
    end subroutine build_rigid_model
    module subroutine add_motions(scene, model, err)
      type(scene_t), intent(in) :: scene
      type(model_t), intent(inout) :: model
      type(error_t), intent(inout) :: err
    end subroutine add_motions
  end interface

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
    call check_element_labels(scene, err); if (.not. err%ok()) return
    call model%init()
    model%gravity = scene%gravity
    if (scene%dimension == 3) then
      call add_motions(scene, model, err); if (.not. err%ok()) return
      call build_spatial(scene, model, err)
      if (err%ok()) call add_controllers(scene, model, err)
      return
    end if
    call add_nodes(scene, model, b, err); if (.not. err%ok()) return
    call add_motions(scene, model, err); if (.not. err%ok()) return
    call check_hinges(scene, b, err); if (.not. err%ok()) return
    call add_links(scene, model, b, err); if (.not. err%ok()) return
    call add_hinges(scene, model, b, err); if (.not. err%ok()) return
    call add_trusses(scene, model, b%node_xy, 2, err); if (.not. err%ok()) return
    call add_sliders(scene, model, b%node_xy, 2, err); if (.not. err%ok()) return
    call add_masses_and_loads(scene, model, b, err); if (.not. err%ok()) return
    call add_node_inputs(scene, model, b%node_xy, b%node_rot, err)
    if (.not. err%ok()) return
    call check_connected(model, err); if (.not. err%ok()) return
    do i = 1, size(scene%nodes)
      call model%add_node_label(scene%nodes(i)%label, [b%node_xy(i), b%node_xy(i) + 1, &
        b%node_rot(i)])
    end do
    call model%finalize(err)
    if (err%ok()) call add_controllers(scene, model, err)
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
          k = 1, 4)])
        if (allocated(scene%nodes(h)%motion_rotation)) used(i) = used(i) .or. &
          scene%nodes(h)%motion_rotation == scene%motions(i)%label
      end do
      do h = 1, size(scene%forces)
        if (allocated(scene%forces(h)%time_law)) used(i) = used(i) .or. &
          scene%forces(h)%time_law == scene%motions(i)%label
      end do
      do h = 1, size(scene%hinges)
        if (allocated(scene%hinges(h)%torque_law)) used(i) = used(i) .or. &
          scene%hinges(h)%torque_law == scene%motions(i)%label
        if (allocated(scene%hinges(h)%reference)) used(i) = used(i) .or. &
          scene%hinges(h)%reference == scene%motions(i)%label
      end do
      do h = 1, size(scene%controllers)
        if (allocated(scene%controllers(h)%reference)) used(i) = used(i) .or. &
          scene%controllers(h)%reference == scene%motions(i)%label
      end do
      do h = 1, size(scene%trusses)
        if (allocated(scene%trusses(h)%force_law)) used(i) = used(i) .or. &
          scene%trusses(h)%force_law == scene%motions(i)%label
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
        call check_node_label(scene, i, err)
        if (.not. err%ok()) return
        ix = model%add_coord(n%x, COORD_X, n%fix_x, 'node ''' // n%label // ''' x')
        iy = model%add_coord(n%y, COORD_Y, n%fix_y, 'node ''' // n%label // ''' y')
        b%node_xy(i) = ix
      end associate
    end do
  end subroutine add_nodes

  !> Every hinge names an existing node and a link that ends there, once.
  subroutine check_hinges(scene, b, err)
    type(scene_t), intent(in) :: scene
    type(builder_t), intent(inout) :: b
    type(error_t), intent(inout) :: err
    allocate(b%hinge_rot(size(scene%hinges)))
    b%hinge_rot = 0
    call check_hinge_ends(scene, err)
  end subroutine check_hinges

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
        call time_law_of(scene, r, 'group &force #' // int_str(i), im, err)
        if (.not. err%ok()) return
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


end module model_build
