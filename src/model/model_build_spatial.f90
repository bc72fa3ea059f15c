!> The spatial scene (&scene dimension = 3; docs/theory.md 2.6): nodes with x, y, z and, where
!> a link ends, four Euler parameters (reference (1, 0, 0, 0)) with a rigid normalisation
!> unless the rotation is clamped; links meshed into spatial beams; point masses; forces and
!> moments fixed in space, constant or following time laws; hinges (elements_hinge3d: the
!> hinged link end gets four Euler parameters of its own); trusses; sliders; translations
!> as node inputs; node rotations as inputs, free (a hidden rotation-vector element) or driven
!> about a fixed axis (a hidden revolute hinge).
submodule (model_build) model_build_spatial
  use elements_beam3d, only: beam3d_t, beam3d_set_geometry, B3_ANGLE => BENDING_ANGLE, &
    B3_SINE => BENDING_SINE
  use elements_euler, only: euler_norm_t
  use elements_body3d, only: body3d_t
  use elements_hinge3d, only: hinge3d_t, hinge3d_set_axis
  use elements_rotvec, only: rotvec_t
  use core_linalg, only: sym_gen_eig
  use elements_beam, only: PLANAR_ANGLE => BENDING_ANGLE
  use model_system, only: COORD_Z, COORD_EULER
  implicit none

contains

  module procedure build_spatial
    integer, allocatable :: node_x(:), node_lam(:), hinge_lam(:)
    integer :: i, ix
    model%dim = 3
    allocate(node_x(size(scene%nodes)), node_lam(size(scene%nodes)))
    node_lam = 0
    do i = 1, size(scene%nodes)
      associate (n => scene%nodes(i))
        call check_node_label(scene, i, err)
        if (.not. err%ok()) return
        node_x(i) = model%add_coord(n%x, COORD_X, n%fix_x, 'node ''' // n%label // ''' x')
        ix = model%add_coord(n%y, COORD_Y, n%fix_y, 'node ''' // n%label // ''' y')
        ix = model%add_coord(n%z, COORD_Z, n%fix_z, 'node ''' // n%label // ''' z')
      end associate
    end do
    call check_hinge_ends(scene, err)
    if (.not. err%ok()) return
    allocate(hinge_lam(size(scene%hinges)))
    hinge_lam = 0
    call add_spatial_links(scene, model, node_x, node_lam, hinge_lam, err)
    if (err%ok()) call add_spatial_hinges(scene, model, node_lam, hinge_lam, err)
    if (err%ok()) call add_node_rotations(scene, model, node_lam, err)
    if (err%ok()) call add_trusses(scene, model, node_x, 3, err)
    if (err%ok()) call add_sliders(scene, model, node_x, 3, err)
    if (err%ok()) call add_spatial_loads(scene, model, node_x, node_lam, err)
    if (.not. err%ok()) return
    ! Node rotations are never inputs in space (io_scene refuses phi): no rotation index.
    call add_node_inputs(scene, model, node_x, 0 * node_x, err)
    if (.not. err%ok()) return
    call check_connected(model, err)
    if (.not. err%ok()) return
    do i = 1, size(scene%nodes)
      call model%add_node_label(scene%nodes(i)%label, [node_x(i), node_x(i) + 1, 0, &
        node_x(i) + 2, node_lam(i)])
    end do
    call model%finalize(err)
  end procedure build_spatial

  !> The four Euler parameters of a node's rotation (created on first use, clamped or with
  !> their normalisation); returns the first.
  integer function euler_coords(model, label, clamped) result(first)
    type(model_t), intent(inout) :: model
    character(len=*), intent(in) :: label
    logical, intent(in) :: clamped
    type(euler_norm_t) :: norm
    integer :: k, idx
    character(len=2), parameter :: NAMES(4) = ['l0', 'l1', 'l2', 'l3']
    first = model%add_coord(1.0_wp, COORD_EULER, clamped, label // ' ' // NAMES(1))
    do k = 2, 4
      idx = model%add_coord(0.0_wp, COORD_EULER, clamped, label // ' ' // NAMES(k))
    end do
    if (clamped) return
    norm%label = label // ' |lambda|'
    norm%dofs = [(first + k, k = 0, 3)]
    norm%mode_class = [MODE_RIGID]
    idx = model%add_element(norm, [0])
  end function euler_coords

  subroutine add_spatial_links(scene, model, node_x, node_lam, hinge_lam, err)
    type(scene_t), intent(in) :: scene
    type(model_t), intent(inout) :: model
    integer, intent(in) :: node_x(:)
    integer, intent(inout) :: node_lam(:), hinge_lam(:)
    type(error_t), intent(inout) :: err
    type(beam_t) :: planar
    type(beam3d_t) :: beam
    real(wp) :: xa(3), xb(3), xk(3), orient(3), d(3)
    integer :: i, k, ia, ib, p(7), q(7), idx, m
    character(len=12) :: num
    do i = 1, size(scene%links)
      associate (r => scene%links(i), where => 'group &link ''' // scene%links(i)%label // '''')
        ! The planar checks of E, A, I, rho, n_elements, classes, form and mass apply as well.
        call link_header(scene, i, where, ia, ib, planar, err)
        if (.not. err%ok()) return
        xa = [scene%nodes(ia)%x, scene%nodes(ia)%y, scene%nodes(ia)%z]
        xb = [scene%nodes(ib)%x, scene%nodes(ib)%y, scene%nodes(ib)%z]
        d = xb - xa
        if (norm2(d) <= 1.0e-12_wp * max(1.0_wp, norm2(xa))) then
          call err%set(ERR_INPUT, where // ': nodes ''' // r%from // ''' and ''' // r%to // &
            ''' are at the same place: a link needs a positive length')
          return
        end if
        ! Default section y axis: global z x chord (in the x-y plane, as a planar beam's).
        if (allocated(r%orientation)) then
          orient = r%orientation
        else
          orient = [-d(2), d(1), 0.0_wp]
          if (norm2(orient) <= 1.0e-6_wp * norm2(d)) then
            call err%set(ERR_INPUT, where // ': the link is parallel to z: give ''orientation'' ' &
              // '(the direction of the section y axis)')
            return
          end if
        end if
        p = [(node_x(ia) + m, m = 0, 2), (end_rotation(ia, r%from) + m, m = 0, 3)]
        do k = 1, r%n_elements
          write(num, '(i0)') k
          if (k < r%n_elements) then
            xk = xa + d * real(k, wp) / r%n_elements
            q(1) = model%add_coord(xk(1), COORD_X, .false., r%label // '.' // trim(num) // ' x')
            q(2) = model%add_coord(xk(2), COORD_Y, .false., r%label // '.' // trim(num) // ' y')
            q(3) = model%add_coord(xk(3), COORD_Z, .false., r%label // '.' // trim(num) // ' z')
            q(4) = euler_coords(model, r%label // '.' // trim(num), .false.)
            q(5:7) = q(4) + [1, 2, 3]
            call model%add_node_label(r%label // '.' // trim(num), [q(1), q(2), 0, q(3), q(4)])
          else
            q = [(node_x(ib) + m, m = 0, 2), (end_rotation(ib, r%to) + m, m = 0, 3)]
          end if
          beam%label = r%label // '#' // trim(num)
          beam%dofs = [p, q]
          call beam3d_set_geometry(beam, model%x0(p(1:3)), model%x0(q(1:3)), orient, err)
          if (.not. err%ok()) then
            call err%prefix(where // ': variable ''orientation'': ')
            return
          end if
          call spatial_properties(r, planar, beam)
          ! Torsion follows the bending class: a rigid link is rigid in every mode.
          beam%mode_class = [class_of(r%elongation, r%n_elements, k, 1), &
            class_of(r%bending, r%n_elements, k, 1), class_of(r%bending, r%n_elements, k, 1), &
            class_of(r%bending, r%n_elements, k, 2), class_of(r%bending, r%n_elements, k, 1), &
            class_of(r%bending, r%n_elements, k, 2)]
          idx = model%add_element(beam, [(0, m = 1, 6)])
          p = q
        end do
      end associate
    end do

  contains

    !> First Euler parameter of the link's end at node `in`: its hinge's own rotation if a
    !> hinge names this (link, node), else the node's; created on first use.
    integer function end_rotation(in, label) result(first)
      integer, intent(in) :: in
      character(len=*), intent(in) :: label
      integer :: h
      do h = 1, size(scene%hinges)
        if (scene%hinges(h)%node == label .and. scene%hinges(h)%link == scene%links(i)%label) then
          if (hinge_lam(h) == 0) hinge_lam(h) = euler_coords(model, 'hinge ''' // &
            scene%hinges(h)%label // '''', .false.)
          first = hinge_lam(h)
          return
        end if
      end do
      if (node_lam(in) == 0) node_lam(in) = euler_coords(model, 'node ''' // label // '''', &
        scene%nodes(in)%fix_rotation)
      first = node_lam(in)
    end function end_rotation
  end subroutine add_spatial_links

  !> Spatial hinges between a node's rotation and the hinged link end's (elements_hinge3d):
  !> revolute, the rotation about the axis takes the hinge's mode and the two normal to it are
  !> rigid; universal, the other way round; spherical, all three take it.
  subroutine add_spatial_hinges(scene, model, node_lam, hinge_lam, err)
    type(scene_t), intent(in) :: scene
    type(model_t), intent(inout) :: model
    integer, intent(inout) :: node_lam(:)
    integer, intent(in) :: hinge_lam(:)
    type(error_t), intent(inout) :: err
    type(hinge3d_t) :: hinge
    real(wp) :: spring(2)
    integer :: h, in, c, im, idx, m
    do h = 1, size(scene%hinges)
      associate (r => scene%hinges(h), where => 'group &hinge ''' // scene%hinges(h)%label // '''')
        call hinge_class(scene, r, where, c, im, err)
        if (err%ok()) call hinge3d_set_axis(hinge, r%axis, err)
        if (.not. err%ok()) return
        in = node_index(scene, r%node)
        if (node_lam(in) == 0) node_lam(in) = euler_coords(model, 'node ''' // r%node // '''', &
          scene%nodes(in)%fix_rotation)
        hinge%label = r%label
        hinge%dofs = [(node_lam(in) + m, m = 0, 3), (hinge_lam(h) + m, m = 0, 3)]
        spring = hinge_spring(r)
        hinge%k = spring(1)
        hinge%damping = spring(2)
        select case (r%joint_type)
        case ('universal')
          hinge%mode_class = [MODE_RIGID, c, c]
          hinge%k_b = spring(1)
        case ('spherical')
          hinge%mode_class = [c, c, c]
          hinge%k_b = spring(1)
        case default
          hinge%mode_class = [c, MODE_RIGID, MODE_RIGID]
        end select
        idx = model%add_element(hinge, [im, 0, 0])
        call add_hinge_actuator(scene, model, r, where, idx, err)
        if (.not. err%ok()) return
      end associate
    end do
  end subroutine add_spatial_hinges

  !> Node rotations that are inputs, on the node's Euler parameters (created here for a node
  !> without links). Free (dynamic = 'rotation'): a hidden rotvec_t whose three dynamic modes
  !> are the rotation vector from the reference orientation. Driven (motion_rotation): a
  !> revolute hinge3d from a clamped hidden frame, its angle about rotation_axis (fixed in
  !> space, as the frame is) prescribed and the two rotations normal to it rigid; its angle
  !> is periodic, so the node can turn on without bound.
  subroutine add_node_rotations(scene, model, node_lam, err)
    type(scene_t), intent(in) :: scene
    type(model_t), intent(inout) :: model
    integer, intent(inout) :: node_lam(:)
    type(error_t), intent(inout) :: err
    type(rotvec_t) :: free
    type(hinge3d_t) :: driven
    integer :: i, im, frame, idx, m
    do i = 1, size(scene%nodes)
      associate (n => scene%nodes(i), where => 'group &node ''' // scene%nodes(i)%label // '''')
        call motion_named(scene, n%motion_rotation, where, 'motion_rotation', im, err)
        if (.not. err%ok()) return
        if (.not. n%free_rotation .and. im == 0) cycle
        if (node_lam(i) == 0) node_lam(i) = euler_coords(model, 'node ''' // n%label // &
          '''', .false.)
        if (n%free_rotation) then
          free%label = 'node ''' // n%label // ''' rotation'
          free%dofs = [(node_lam(i) + m, m = 0, 3)]
          free%mode_class = [MODE_DYNAMIC, MODE_DYNAMIC, MODE_DYNAMIC]
          idx = model%add_element(free, [0, 0, 0])
          cycle
        end if
        call hinge3d_set_axis(driven, n%rotation_axis, err)
        if (.not. err%ok()) then
          call err%prefix(where // ': variable ''rotation_axis'': ')
          return
        end if
        frame = euler_coords(model, 'node ''' // n%label // ''' frame', .true.)
        driven%label = 'node ''' // n%label // ''' rotation'
        driven%dofs = [(frame + m, m = 0, 3), (node_lam(i) + m, m = 0, 3)]
        driven%mode_class = [MODE_PRESCRIBED, MODE_RIGID, MODE_RIGID]
        idx = model%add_element(driven, [im, 0, 0])
      end associate
    end do
  end subroutine add_node_rotations

  !> Section properties: I about the section z axis (bending in the x-y plane, as in the
  !> plane), Iy about y (default I), torsion G J, rotary inertia rho (Iy + I) about the axis;
  !> G > 0 makes the bending shear-flexible as in the plane.
  subroutine spatial_properties(r, planar, beam)
    type(link_rec_t), intent(in) :: r
    type(beam_t), intent(in) :: planar
    type(beam3d_t), intent(inout) :: beam
    real(wp) :: iy
    iy = r%inertia
    if (r%inertia_y > 0) iy = r%inertia_y
    beam%ea = planar%ea
    beam%gj = r%shear_modulus * r%torsion
    beam%ei_z = r%e_modulus * r%inertia
    beam%ei_y = r%e_modulus * iy
    beam%rho_a = planar%rho_a
    beam%rho_j = r%density * (iy + r%inertia)
    beam%rho_iy = r%density * iy
    beam%rho_iz = r%density * r%inertia
    if (allocated(r%rotary_inertia)) then
      beam%rho_j = r%rotary_inertia(1)
      beam%rho_iy = r%rotary_inertia(2)
      beam%rho_iz = r%rotary_inertia(3)
    end if
    beam%consistent = planar%consistent
    beam%damping = planar%damping
    beam%bending = merge(B3_ANGLE, B3_SINE, planar%bending == PLANAR_ANGLE)
    beam%shear_xz = 0.0_wp
    beam%shear_xy = 0.0_wp
    if (r%shear_modulus > 0) then
      beam%shear_xz = 12 * beam%ei_y / (r%shear_factor * r%shear_modulus * r%area * beam%l0**2)
      beam%shear_xy = 12 * beam%ei_z / (r%shear_factor * r%shear_modulus * r%area * beam%l0**2)
    end if
  end subroutine spatial_properties

  !> Point masses on x, y, z; forces; moments (fixed in space) on nodes with a rotation; both
  !> constant or following a time law.
  subroutine add_spatial_loads(scene, model, node_x, node_lam, err)
    type(scene_t), intent(in) :: scene
    type(model_t), intent(inout) :: model
    integer, intent(in) :: node_x(:), node_lam(:)
    type(error_t), intent(inout) :: err
    real(wp) :: shape(model%n_x)
    integer :: i, in, im
    do i = 1, size(scene%masses)
      associate (r => scene%masses(i))
        call require_node(scene, r%node, 'group &mass', 'node', in, err)
        if (.not. err%ok()) return
        if (r%m < 0) then
          call err%set(ERR_INPUT, 'group &mass on node ''' // r%node // ''': variable ''m'' ' &
            // 'must not be negative')
          return
        end if
        model%lumped(node_x(in):node_x(in) + 2) = model%lumped(node_x(in):node_x(in) + 2) + r%m
        if (allocated(r%inertia)) call add_body(model, r, node_x(in), node_lam(in), err)
        if (.not. err%ok()) return
      end associate
    end do
    do i = 1, size(scene%forces)
      associate (r => scene%forces(i), where => 'group &force on node ''' // &
          scene%forces(i)%node // '''')
        call require_node(scene, r%node, 'group &force', 'node', in, err)
        if (err%ok()) call time_law_of(scene, r, where, im, err)
        if (.not. err%ok()) return
        if (im == 0) then
          model%force(node_x(in):node_x(in) + 2) = model%force(node_x(in):node_x(in) + 2) + &
            [r%fx, r%fy, r%fz]
        else if (any([r%fx, r%fy, r%fz] /= 0)) then
          shape = 0.0_wp
          shape(node_x(in):node_x(in) + 2) = [r%fx, r%fy, r%fz]
          call model%add_timed_load(shape, im)
        end if
        if (any(r%m_xyz /= 0)) then
          if (node_lam(in) == 0) then
            call err%set(ERR_INPUT, where // ': a moment needs a node with a rotation (the ' &
              // 'end of a link, or dynamic = ''rotation'')')
            return
          end if
          call model%add_moment(node_lam(in), r%m_xyz, im)
        end if
      end associate
    end do
  end subroutine add_spatial_loads

  !> A rigid body's rotary inertia on a node's rotation (its mass stays a point mass on the
  !> translations): the tensor must be that of a body, principal moments >= 0, each at most
  !> the sum of the other two.
  subroutine add_body(model, r, ix, ilam, err)
    type(model_t), intent(inout) :: model
    type(mass_rec_t), intent(in) :: r
    integer, intent(in) :: ix, ilam
    type(error_t), intent(inout) :: err
    type(body3d_t) :: body
    real(wp) :: j(3, 3), eye(3, 3), p(3), v(3, 3), tol
    integer :: info, k, idx
    character(len=:), allocatable :: where
    where = 'group &mass on node ''' // r%node // ''': variable ''inertia'''
    if (ilam == 0) then
      call err%set(ERR_INPUT, where // ': the node has no rotation (no link ends there); ' &
        // 'give it one with &node dynamic = ''rotation'' (a free rigid body)')
      return
    end if
    j = reshape([r%inertia(1), r%inertia(4), r%inertia(5), r%inertia(4), r%inertia(2), &
      r%inertia(6), r%inertia(5), r%inertia(6), r%inertia(3)], [3, 3])
    ! Given in axes turned by Q (columns: the body axes) from the reference ones: J_ref = Q J Q^T.
    if (allocated(r%axes)) j = matmul(r%axes, matmul(j, transpose(r%axes)))
    eye = 0
    do k = 1, 3
      eye(k, k) = 1
    end do
    call sym_gen_eig(j, eye, p, v, info)
    tol = 1.0e-12_wp * maxval(abs(r%inertia))
    if (info /= 0 .or. any(p < -tol) .or. p(3) > p(1) + p(2) + tol) then
      call err%set(ERR_INPUT, where // ' is not the inertia tensor of a body (principal ' // &
        'moments ' // approx_str(p(1)) // ', ' // approx_str(p(2)) // ', ' // &
        approx_str(p(3)) // ': each must be >= 0 and at most the sum of the other two)')
      return
    end if
    body%label = 'body on node ''' // r%node // ''''
    body%dofs = [ix, ix + 1, ix + 2, ilam, ilam + 1, ilam + 2, ilam + 3]
    allocate(body%mode_class(0))
    body%inertia_tensor = j
    idx = model%add_element(body, [integer ::])
  end subroutine add_body

end submodule model_build_spatial
