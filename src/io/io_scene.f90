!> Reads a scene file (namelist syntax) into scene records. The groups, their variables,
!> units and defaults are documented in docs/input.md; keep the two in step.
!>
!> Every message names the file, line, group and variable. Values are range-checked here when
!> the check needs no other record; cross-references are checked by model_build.
module io_scene
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_INPUT
  use core_strings, only: approx_str
  use io_namelist, only: nml_file_t, nml_group_t, string_t
  use io_schema, only: SCENE_GROUPS, SINGLE_GROUPS
  use io_fields, only: rd_real, rd_int, rd_logical, rd_string, rd_choice, rd_choices, &
    rd_classes, rd_label, only_with, rd_fixed_list, first_given, rd_reals
  use io_scene_analyses, only: read_static, read_modal, read_buckling, read_controller, &
    read_linear, read_dynamic, read_reduction, read_output
  use model_scene, only: scene_t, node_rec_t, link_rec_t, hinge_rec_t, truss_rec_t, mass_rec_t, &
    force_rec_t, slider_rec_t, UPDATE_NONE
  use elements_rotation, only: euler_to_matrix, rotvec_to_euler, orthonormal_frame
  use io_scene_motion, only: read_motion
  implicit none
  private
  public :: read_scene, load_scene, SCENE_GROUPS

  interface
    !> Variables and groups of the other dimension than &scene dimension are errors
    !> (submodule io_scene_dimension).
    module subroutine check_dimension(scene, err)
      type(scene_t), intent(in) :: scene
      type(error_t), intent(inout) :: err
    end subroutine check_dimension
  end interface

contains

  !> Load and read a scene file.
  subroutine load_scene(path, file, scene, err)
    character(len=*), intent(in) :: path
    type(nml_file_t), intent(out) :: file
    type(scene_t), intent(out) :: scene
    type(error_t), intent(out) :: err
    call file%load(path, err)
    if (err%ok()) call read_scene(file, scene, err)
  end subroutine load_scene

  subroutine read_scene(file, scene, err)
    type(nml_file_t), intent(inout) :: file
    type(scene_t), intent(out) :: scene
    type(error_t), intent(out) :: err
    integer :: i, k
    call file%check_known_groups(SCENE_GROUPS, err)
    if (.not. err%ok()) return
    do i = 1, size(SCENE_GROUPS)
      if (any(SCENE_GROUPS(i) == SINGLE_GROUPS) .and. &
          file%count(trim(SCENE_GROUPS(i))) > 1) then
        call err%set(ERR_INPUT, file%path // ': group &' // trim(SCENE_GROUPS(i)) // &
          ' may appear only once')
        return
      end if
    end do
    if (file%count('node') == 0) then
      call err%set(ERR_INPUT, file%path // ': the scene has no &node group')
      return
    end if
    allocate(scene%nodes(file%count('node')), scene%links(file%count('link')))
    allocate(scene%hinges(file%count('hinge')), scene%trusses(file%count('truss')))
    allocate(scene%masses(file%count('mass')), scene%forces(file%count('force')))
    allocate(scene%motions(file%count('motion')), scene%sliders(file%count('slider')))
    allocate(scene%controllers(file%count('controller')))
    do i = 1, size(file%groups)
      associate (g => file%groups(i))
        select case (g%name)
        case ('scene'); call read_scene_group(g, scene, err)
        case ('node'); call read_node(g, scene%nodes(g%occurrence), err)
        case ('link'); call read_link(g, scene%links(g%occurrence), err)
        case ('hinge'); call read_hinge(g, scene%hinges(g%occurrence), err)
        case ('truss'); call read_truss(g, scene%trusses(g%occurrence), err)
        case ('slider'); call read_slider(g, scene%sliders(g%occurrence), err)
        case ('mass'); call read_mass(g, scene%masses(g%occurrence), err)
        case ('force'); call read_force(g, scene%forces(g%occurrence), err)
        case ('motion'); call read_motion(g, scene%motions(g%occurrence), err)
        case ('controller'); call read_controller(g, scene%controllers(g%occurrence), err)
        case ('static'); call read_static(g, scene, err)
        case ('modal'); call read_modal(g, scene, err)
        case ('buckling'); call read_buckling(g, scene, err)
        case ('linear'); call read_linear(g, scene, err)
        case ('dynamic'); call read_dynamic(g, scene, err)
        case ('reduction'); call read_reduction(g, scene, err)
        case ('output'); call read_output(g, scene, err)
        end select
        if (err%ok()) call g%check_all_used(err)
      end associate
      if (.not. err%ok()) return
    end do
    if (.not. allocated(scene%output_nodes)) then
      allocate(scene%output_nodes(size(scene%nodes)))
      do i = 1, size(scene%nodes)
        scene%output_nodes(i)%s = scene%nodes(i)%label
      end do
    end if
    if (.not. allocated(scene%title)) scene%title = ''
    if (.not. allocated(scene%compliance_nodes)) allocate(scene%compliance_nodes(0))
    ! A compliance belongs to a node path: compliance nodes are output nodes too.
    do i = 1, size(scene%compliance_nodes)
      if (any([(scene%output_nodes(k)%s == scene%compliance_nodes(i)%s, &
          k = 1, size(scene%output_nodes))])) cycle
      scene%output_nodes = [scene%output_nodes, scene%compliance_nodes(i)]
    end do
    if (size(scene%compliance_nodes) > 0 .and. .not. scene%static%active) call err%set( &
      ERR_INPUT, file%path // ': group &output: variable ''compliance_nodes'' needs a ' // &
      '&static group (the compliance is computed at its equilibria)')
    if (scene%reduction%active .and. .not. scene%dynamic%active) call err%set(ERR_INPUT, &
      file%path // ': group &reduction needs a &dynamic group (it reduces the dynamic analysis)')
    ! A run checks its basis every update_interval: one far below t_end never ended (an
    ! interval below the round-off of t does not move it). The limit is the run's step limit.
    if (err%ok() .and. scene%reduction%active .and. scene%reduction%update /= UPDATE_NONE) then
      if (scene%dynamic%t_end / scene%reduction%update_interval > 1.0e7_wp) call err%set( &
        ERR_INPUT, file%path // ': group &reduction: variable ''update_interval'': t_end / ' &
        // 'update_interval gives ' // approx_str(scene%dynamic%t_end / &
        scene%reduction%update_interval) // ' basis checks, more than the 1e7 steps a run may ' // &
        'take: raise update_interval')
    end if
    ! Every sample of a sampled controller is a breakpoint where the integrator restarts.
    do i = 1, size(scene%controllers)
      if (.not. (err%ok() .and. scene%dynamic%active)) exit
      associate (c => scene%controllers(i))
        if (c%period > 0) then
          if (scene%dynamic%t_end / c%period > 1.0e7_wp) call err%set(ERR_INPUT, file%path // &
            ': group &controller ''' // c%label // ''': variable ''period'': t_end / period ' &
            // 'gives ' // approx_str(scene%dynamic%t_end / c%period) // ' samples, each a ' // &
            'restart of the integrator, more than the 1e7 steps a run may take: raise period')
        end if
      end associate
    end do
    if (err%ok()) then
      call check_dimension(scene, err)
      if (.not. err%ok()) call err%prefix(file%path // ': ')
    end if
  end subroutine read_scene

  subroutine read_scene_group(g, scene, err)
    type(nml_group_t), intent(inout) :: g
    type(scene_t), intent(inout) :: scene
    type(error_t), intent(inout) :: err
    real(wp), allocatable :: gravity(:)
    type(error_t) :: e
    integer :: i
    call rd_string(g, 'title', scene%title, err)
    if (.not. err%ok()) return
    call rd_choice(g, 'linear_solver', scene%linear_solver, err)
    call rd_int(g, 'dimension', scene%dimension, err)
    if (.not. err%ok()) return
    call rd_reals(g, 'gravity', gravity, e, default=[(0.0_wp, i = 1, scene%dimension)])
    if (.not. e%ok()) then
      err = e
    else if (size(gravity) /= scene%dimension) then
      call err%set(ERR_INPUT, g%where() // ': variable ''gravity'' needs ' // &
        trim(merge('2 values (gx, gy)    ', '3 values (gx, gy, gz)', scene%dimension == 2)))
    else
      scene%gravity(1:scene%dimension) = gravity
    end if
  end subroutine read_scene_group

  subroutine read_node(g, n, err)
    type(nml_group_t), intent(inout) :: g
    type(node_rec_t), intent(out) :: n
    type(error_t), intent(inout) :: err
    logical :: fixed
    call rd_label(g, n%label, err)
    call rd_real(g, 'x', n%x, err)
    call rd_real(g, 'y', n%y, err)
    call rd_logical(g, 'fixed', fixed, err)
    call rd_logical(g, 'fix_x', n%fix_x, err, default=fixed)
    call rd_logical(g, 'fix_y', n%fix_y, err, default=fixed)
    call rd_logical(g, 'fix_phi', n%fix_phi, err, default=fixed)
    call rd_real(g, 'z', n%z, err)
    call rd_logical(g, 'fix_z', n%fix_z, err, default=fixed)
    call rd_logical(g, 'fix_rotation', n%fix_rotation, err, default=fixed)
    call read_node_inputs(g, n, err)
    call read_node_rotation(g, n, err)
    n%spatial_var = first_given(g, [character(len=16) :: 'z', 'fix_z', 'fix_rotation', &
      'motion_z', 'motion_rotation', 'rotation_axis'])
    if (len(n%spatial_var) == 0 .and. (n%dynamic(4) .or. n%free_rotation)) &
      n%spatial_var = 'dynamic'
    ! phi is the planar rotation angle; a spatial node's rotation is an input through
    ! 'rotation' and motion_rotation (read_node_rotation).
    n%planar_var = first_given(g, [character(len=12) :: 'fix_phi', 'motion_phi'])
    if (len(n%planar_var) == 0 .and. n%dynamic(3)) n%planar_var = 'dynamic'
  end subroutine read_node

  !> Coordinates of a node that are inputs: `dynamic = 'x', 'phi'` makes them degrees of
  !> freedom, `motion_x = 'label'` (and _y, _phi, _z) prescribes them. A coordinate that is fixed
  !> cannot be either, nor both.
  subroutine read_node_inputs(g, n, err)
    type(nml_group_t), intent(inout) :: g
    type(node_rec_t), intent(inout) :: n
    type(error_t), intent(inout) :: err
    character(len=3), parameter :: names(4) = ['x  ', 'y  ', 'phi', 'z  ']
    type(string_t), allocatable :: dyn(:)
    logical :: fixed(4)
    integer :: i, k
    if (.not. err%ok()) return
    call rd_choices(g, 'dynamic', dyn, err, unique=.true.)
    if (.not. err%ok()) return
    do i = 1, size(dyn)
      do k = 1, 4
        if (trim(names(k)) == dyn(i)%s) n%dynamic(k) = .true.
      end do
      if (dyn(i)%s == 'rotation') n%free_rotation = .true.
    end do
    fixed = [n%fix_x, n%fix_y, n%fix_phi, n%fix_z]
    do k = 1, 4
      call rd_string(g, 'motion_' // trim(names(k)), n%motion(k)%s, err)
      if (.not. err%ok()) return
      if (fixed(k) .and. (n%dynamic(k) .or. len(n%motion(k)%s) > 0)) then
        call err%set(ERR_INPUT, g%where() // ': coordinate ' // trim(names(k)) // ' is fixed ' // &
          'and cannot also be dynamic or prescribed (set fix_' // trim(names(k)) // ' = .false.)')
      else if (n%dynamic(k) .and. len(n%motion(k)%s) > 0) then
        call err%set(ERR_INPUT, g%where() // ': coordinate ' // trim(names(k)) // ' is both ' // &
          'dynamic and prescribed (motion_' // trim(names(k)) // ')')
      end if
      if (.not. err%ok()) return
    end do
  end subroutine read_node_inputs

  !> A spatial node's rotation as an input: free (dynamic = 'rotation') or driven by
  !> motion_rotation about rotation_axis (both needed together); neither with fix_rotation.
  subroutine read_node_rotation(g, n, err)
    type(nml_group_t), intent(inout) :: g
    type(node_rec_t), intent(inout) :: n
    type(error_t), intent(inout) :: err
    if (.not. err%ok()) return
    call rd_string(g, 'motion_rotation', n%motion_rotation, err)
    call rd_fixed_list(g, 'rotation_axis', 3, ' (ax, ay, az: the axis fixed in space the ' // &
      'node turns about)', n%rotation_axis, err)
    if (.not. err%ok()) return
    if (n%fix_rotation .and. (n%free_rotation .or. len(n%motion_rotation) > 0)) then
      call err%set(ERR_INPUT, g%where() // ': the rotation is fixed (fix_rotation, or ' // &
        'fixed) and cannot also be dynamic or driven (set fix_rotation = .false.)')
    else if (n%free_rotation .and. len(n%motion_rotation) > 0) then
      call err%set(ERR_INPUT, g%where() // ': the rotation is both dynamic (dynamic = ' // &
        '''rotation'') and driven (motion_rotation)')
    else if (len(n%motion_rotation) > 0 .and. .not. allocated(n%rotation_axis)) then
      call err%set(ERR_INPUT, g%where() // ': variable ''motion_rotation'' needs ' // &
        '''rotation_axis'' (3 values: the axis fixed in space the node turns about)')
    else if (len(n%motion_rotation) == 0 .and. allocated(n%rotation_axis)) then
      call err%set(ERR_INPUT, g%where() // ': variable ''rotation_axis'' is given without ' // &
        '''motion_rotation'' (the motion that drives the rotation about it)')
    else if (allocated(n%rotation_axis)) then
      if (.not. norm2(n%rotation_axis) > 0) call err%set(ERR_INPUT, g%where() // &
        ': variable ''rotation_axis'' must not be zero')
    end if
  end subroutine read_node_rotation

  subroutine read_link(g, r, err)
    type(nml_group_t), intent(inout) :: g
    type(link_rec_t), intent(out) :: r
    type(error_t), intent(inout) :: err
    call rd_label(g, r%label, err)
    call rd_string(g, 'from', r%from, err)
    call rd_string(g, 'to', r%to, err)
    call rd_int(g, 'n_elements', r%n_elements, err)
    call rd_real(g, 'E', r%e_modulus, err)
    call rd_real(g, 'A', r%area, err)
    call rd_real(g, 'I', r%inertia, err)
    call rd_real(g, 'rho', r%density, err)
    call rd_real(g, 'G', r%shear_modulus, err)
    call rd_real(g, 'shear_factor', r%shear_factor, err, default=5.0_wp / 6.0_wp)
    call rd_classes(g, 'elongation', r%n_elements, r%elongation, err)
    call rd_classes(g, 'bending', r%n_elements, r%bending, err)
    call rd_choice(g, 'bending_form', r%bending_form, err)
    call rd_choice(g, 'mass', r%mass, err)
    call rd_real(g, 'damping', r%damping, err)
    if (g%has('Iy')) call rd_real(g, 'Iy', r%inertia_y, err)
    if (g%has('J')) call rd_real(g, 'J', r%torsion, err)
    call rd_fixed_list(g, 'orientation', 3, '', r%orientation, err)
    call rd_fixed_list(g, 'rotary_inertia', 3, ' (per length, about the beam axis, section y ' &
      // 'and section z)', r%rotary_inertia, err)
    if (err%ok() .and. allocated(r%rotary_inertia)) then
      if (any(r%rotary_inertia < 0)) call err%set(ERR_INPUT, g%where() // ': variable ' // &
        '''rotary_inertia'' must not be negative')
    end if
    r%spatial_var = first_given(g, [character(len=16) :: 'Iy', 'J', 'orientation', &
      'rotary_inertia'])
  end subroutine read_link

  subroutine read_hinge(g, r, err)
    type(nml_group_t), intent(inout) :: g
    type(hinge_rec_t), intent(out) :: r
    type(error_t), intent(inout) :: err
    real(wp), allocatable :: axis(:)
    call rd_label(g, r%label, err)
    call rd_string(g, 'node', r%node, err)
    call rd_string(g, 'link', r%link, err)
    call rd_choice(g, 'mode', r%mode, err)
    if (err%ok()) then
      call only_with(g, ['motion'], r%mode == 'prescribed', 'with mode = ''prescribed''', err)
      call only_with(g, ['stiffness', 'damping  '], r%mode == 'dynamic' .or. &
        r%mode == 'elastic', 'with mode = ''dynamic'' or ''elastic''', err)
      call only_with(g, ['torque    ', 'torque_law', 'kp        ', 'kd        ', &
        'reference '], r%mode == 'dynamic', &
        'with mode = ''dynamic'' (the driven angle is a degree of freedom)', err)
    end if
    call rd_string(g, 'motion', r%motion, err)
    call rd_real(g, 'stiffness', r%stiffness, err)
    call rd_real(g, 'damping', r%damping, err)
    if (err%ok() .and. r%mode == 'prescribed' .and. len(r%motion) == 0) call err%set(ERR_INPUT, &
      g%where() // ': variable ''motion'' is required when mode = ''prescribed''')
    call rd_fixed_list(g, 'axis', 3, '', axis, err)
    if (err%ok() .and. allocated(axis)) then
      if (.not. norm2(axis) > 0) then
        call err%set(ERR_INPUT, g%where() // ': variable ''axis'' must not be zero')
      else
        r%axis = axis
      end if
    end if
    call rd_real(g, 'torque', r%torque, err)
    call rd_string(g, 'torque_law', r%torque_law, err)
    call rd_real(g, 'kp', r%kp, err)
    call rd_real(g, 'kd', r%kd, err)
    call rd_string(g, 'reference', r%reference, err)
    if (err%ok() .and. (g%has('kd') .or. g%has('reference') .or. g%has('kp')) .and. &
        .not. r%kp > 0) call err%set(ERR_INPUT, g%where() // ': a PD controller (''kp'', ' // &
      '''kd'', ''reference'') needs ''kp'' > 0')
    if (err%ok() .and. g%has('kp') .and. (g%has('stiffness') .or. g%has('damping'))) &
      call err%set(ERR_INPUT, g%where() // ': ''kp'' and ''kd'' are the controlled hinge''s ' &
      // 'stiffness and damping: give them, or ''stiffness'' and ''damping'', not both')
    call rd_choice(g, 'type', r%joint_type, err)
    if (err%ok() .and. r%joint_type /= 'revolute' .and. r%mode == 'prescribed') &
      call err%set(ERR_INPUT, g%where() // ': variable ''type'': a ' // r%joint_type // &
      ' joint cannot be prescribed (one motion cannot drive two or three rotations)')
    r%spatial_var = first_given(g, [character(len=12) :: 'axis', 'type'])
  end subroutine read_hinge

  subroutine read_truss(g, r, err)
    type(nml_group_t), intent(inout) :: g
    type(truss_rec_t), intent(out) :: r
    type(error_t), intent(inout) :: err
    call rd_label(g, r%label, err)
    call rd_string(g, 'from', r%from, err)
    call rd_string(g, 'to', r%to, err)
    call rd_real(g, 'E', r%e_modulus, err)
    call rd_real(g, 'A', r%area, err)
    call rd_real(g, 'rho', r%density, err)
    call rd_choice(g, 'mode', r%mode, err)
    call rd_choice(g, 'mass', r%mass, err)
    call rd_real(g, 'damping', r%damping, err)
    if (err%ok()) call only_with(g, ['force    ', 'force_law'], r%mode == 'dynamic', &
      'with mode = ''dynamic'' (an actuator drives a degree of freedom)', err)
    call rd_real(g, 'force', r%force, err)
    call rd_string(g, 'force_law', r%force_law, err)
  end subroutine read_truss

  !> A slider; the node and the guide's length are checked by model_build (add_sliders).
  subroutine read_slider(g, r, err)
    type(nml_group_t), intent(inout) :: g
    type(slider_rec_t), intent(out) :: r
    type(error_t), intent(inout) :: err
    real(wp), allocatable :: direction(:)
    type(error_t) :: e
    call rd_label(g, r%label, err)
    call rd_string(g, 'node', r%node, err)
    call rd_choice(g, 'mode', r%mode, err)
    call only_with(g, ['stiffness', 'damping  '], r%mode == 'dynamic' .or. r%mode == 'elastic', &
      'with mode = ''dynamic'' or ''elastic''', err)
    call rd_real(g, 'stiffness', r%stiffness, err)
    call rd_real(g, 'damping', r%damping, err)
    if (.not. err%ok()) return
    call rd_reals(g, 'direction', direction, e)
    if (.not. e%ok()) then
      err = e
    else if (size(direction) /= 2 .and. size(direction) /= 3) then
      call err%set(ERR_INPUT, g%where() // ': variable ''direction'' needs 2 values (dx, dy; ' &
        // '3 in a spatial scene)')
    else if (norm2(direction) == 0) then
      call err%set(ERR_INPUT, g%where() // ': variable ''direction'' is the zero vector: ' // &
        'give the guide''s direction (dx, dy), e.g. 1, 0 for a guide along x')
    else
      r%direction = direction
    end if
  end subroutine read_slider

  subroutine read_mass(g, r, err)
    type(nml_group_t), intent(inout) :: g
    type(mass_rec_t), intent(out) :: r
    type(error_t), intent(inout) :: err
    call rd_string(g, 'node', r%node, err)
    call rd_real(g, 'm', r%m, err)
    call rd_real(g, 'J', r%j, err)
    call rd_fixed_list(g, 'inertia', 6, ' (Jxx, Jyy, Jzz, Jxy, Jxz, Jyz)', r%inertia, err)
    call read_body_axes(g, allocated(r%inertia), r%axes, err)
    r%planar_var = first_given(g, [character(len=12) :: 'J'])
    r%spatial_var = first_given(g, [character(len=12) :: 'inertia', 'rotation', 'axes'])
  end subroutine read_mass

  !> The axes a body's inertia is given in, as a matrix whose columns are the body's x, y, z
  !> axes in reference coordinates: from `rotation` (an axis and an angle) or from `axes` (the
  !> body's x axis and a vector in its x-y plane, orthogonalised; z = x cross y).
  subroutine read_body_axes(g, has_inertia, axes, err)
    type(nml_group_t), intent(inout) :: g
    logical, intent(in) :: has_inertia
    real(wp), allocatable, intent(out) :: axes(:, :)
    type(error_t), intent(inout) :: err
    real(wp), allocatable :: rotation(:), two(:)
    logical :: ok
    character(len=:), allocatable :: name
    call rd_fixed_list(g, 'rotation', 4, ' (an axis ax, ay, az and an angle in rad)', &
      rotation, err)
    call rd_fixed_list(g, 'axes', 6, ' (the body x axis ax, ay, az and a vector bx, by, bz ' &
      // 'in its x-y plane)', two, err)
    if (.not. err%ok() .or. .not. (allocated(rotation) .or. allocated(two))) return
    name = 'axes'
    if (allocated(rotation)) name = 'rotation'
    if (allocated(rotation) .and. allocated(two)) then
      call err%set(ERR_INPUT, g%where() // ': variables ''rotation'' and ''axes'' both give ' &
        // 'the axes of ''inertia'': give one')
    else if (.not. has_inertia) then
      call err%set(ERR_INPUT, g%where() // ': variable ''' // name // ''' turns the axes ' // &
        'of ''inertia'', which is not given')
    else if (allocated(rotation)) then
      if (.not. norm2(rotation(1:3)) > 0) then
        call err%set(ERR_INPUT, g%where() // ': variable ''rotation'': the axis is zero')
        return
      end if
      axes = euler_to_matrix(rotvec_to_euler(rotation(4) * rotation(1:3) / &
        norm2(rotation(1:3))))
    else
      allocate(axes(3, 3))
      ok = norm2(two(1:3)) > 0
      if (ok) call orthonormal_frame(two(1:3) / norm2(two(1:3)), two(4:6), axes, ok)
      if (.not. ok) call err%set(ERR_INPUT, g%where() // ': variable ''axes'': the x axis ' // &
        '(first 3 values) must not be zero and the second vector must not be zero or ' // &
        'parallel to it')
    end if
  end subroutine read_body_axes

  subroutine read_force(g, r, err)
    type(nml_group_t), intent(inout) :: g
    type(force_rec_t), intent(out) :: r
    type(error_t), intent(inout) :: err
    call rd_string(g, 'node', r%node, err)
    call rd_real(g, 'fx', r%fx, err)
    call rd_real(g, 'fy', r%fy, err)
    call rd_real(g, 'moment', r%moment, err)
    call rd_string(g, 'time_law', r%time_law, err)
    call rd_real(g, 'fz', r%fz, err)
    call rd_real(g, 'mx', r%m_xyz(1), err)
    call rd_real(g, 'my', r%m_xyz(2), err)
    call rd_real(g, 'mz', r%m_xyz(3), err)
    r%spatial_var = first_given(g, [character(len=12) :: 'fz', 'mx', 'my', 'mz'])
    r%planar_var = first_given(g, [character(len=12) :: 'moment'])
  end subroutine read_force
end module io_scene
