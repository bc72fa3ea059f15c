!> The result file of one run (layout: docs/output.md): the writers of analysis_run.
submodule (analysis_run) analysis_run_output
  use model_system, only: COORD_PHI, COORD_Y, COORD_Z, COORD_EULER, NODE_SLOTS
  use model_control, only: LAW_PID
  use model_scene, only: UPDATE_NAMES, EVALUATION_NAMES, ERROR_CHECK_NAMES
  use integrators_system, only: INTEGRATOR_NAMES, JACOBIAN_NAMES
  implicit none

contains

  !> Write the result file (temporary name, renamed on success).
  module subroutine run_write(this, path, err)
    class(run_t), intent(inout) :: this
    character(len=*), intent(in) :: path
    type(error_t), intent(out) :: err
    type(h5_writer_t) :: h5
    call h5%open(path, err)
    if (err%ok()) call write_attributes(this, h5, err)
    if (err%ok()) call write_model(this%dyn%model, h5, err)
    if (err%ok() .and. this%scene%static%active) call write_static(this, h5, err)
    if (err%ok() .and. this%scene%modal%active) call write_modal(this, h5, err)
    if (err%ok() .and. this%scene%buckling%active) call write_buckling(this, h5, err)
    if (err%ok() .and. this%scene%linear%active) call write_linear(this, h5, err)
    if (err%ok() .and. this%scene%dynamic%active) call write_dynamic(this, h5, err)
    if (err%ok() .and. allocated(this%red)) call write_reduction(this, h5, err)
    if (err%ok() .and. allocated(this%check_distance)) call write_error_check(this, h5, err)
    if (err%ok()) call h5%commit(err)
    if (.not. err%ok()) call h5%abort()
  end subroutine run_write

  subroutine write_attributes(this, h5, err)
    type(run_t), intent(in) :: this
    type(h5_writer_t), intent(inout) :: h5
    type(error_t), intent(inout) :: err
    call h5%write_string_attr('/', 'flexmor_version', FLEXMOR_VERSION, err)
    if (err%ok()) call h5%write_string_attr('/', 'input', this%file%text, err)
    if (err%ok()) call h5%write_string_attr('/', 'input_file', this%file%path, err)
    if (err%ok() .and. allocated(this%input_overrides)) call h5%write_string_attr('/', &
      'input_overrides', this%input_overrides, err)
    if (err%ok()) call h5%write_string_attr('/', 'title', this%scene%title, err)
    if (err%ok()) call h5%write_string_attr('/', 'status', 'ok', err)
    if (err%ok()) call h5%write_real_attr('/', 'wall_time_s', this%wall_time_s, err)
    if (err%ok()) call h5%write_real_attr('/', 'cpu_time_s', this%cpu_time_s, err)
    if (err%ok()) call h5%write_int_attr('/', 'n_dynamic_coordinates', this%dyn%model%n_dy, err)
    if (err%ok()) call h5%write_int_attr('/', 'n_elements', this%dyn%model%n_elements, err)
    if (err%ok()) call h5%write_int_attr('/', 'n_kinematic_solves', this%dyn%kin%n_solves, err)
    if (err%ok()) call h5%write_string_attr('/', 'linear_solver', &
      trim(merge('sparse', 'dense ', this%dyn%sparse)), err)
    if (.not. this%scene%dynamic%active) return
    associate (s => this%stats, d => this%scene%dynamic)
      if (err%ok()) call h5%write_string_attr('/', 'integrator', &
        trim(INTEGRATOR_NAMES(d%integrator)), err)
      if (err%ok() .and. allocated(this%integrator_choice)) call h5%write_string_attr('/', &
        'integrator_choice', this%integrator_choice, err)
      if (err%ok()) call h5%write_real_attr('/', 'rtol', d%rtol, err)
      if (err%ok()) call h5%write_real_attr('/', 'atol', d%atol, err)
      if (err%ok()) call h5%write_int_attr('/', 'n_steps', s%n_steps, err)
      if (err%ok()) call h5%write_int_attr('/', 'n_rhs_evals', s%n_rhs_evals, err)
      if (err%ok()) call h5%write_int_attr('/', 'n_jac_evals', s%n_jac_evals, err)
      if (err%ok()) call h5%write_int_attr('/', 'n_factorisations', s%n_factorisations, err)
      if (err%ok()) call h5%write_int_attr('/', 'n_err_test_fails', s%n_err_test_fails, err)
      if (err%ok()) call h5%write_int_attr('/', 'n_nonlin_fails', s%n_nonlin_fails, err)
      if (err%ok()) call h5%write_int_attr('/', 'n_restarts', s%n_restarts, err)
      if (err%ok()) call h5%write_int_attr('/', 'n_model_evals', this%dyn%n_evals, err)
      if (err%ok()) call h5%write_string_attr('/', 'jacobian', trim(JACOBIAN_NAMES(d%jacobian)), &
        err)
    end associate
  end subroutine write_attributes

  !> The reference geometry and connectivity (/model), so that a result file alone can draw the
  !> mechanism: every node with its coordinates, every element with its coordinates and nodes.
  subroutine write_model(model, h5, err)
    type(model_t), intent(in) :: model
    type(h5_writer_t), intent(inout) :: h5
    type(error_t), intent(inout) :: err
    character(len=*), parameter :: g = '/model'
    integer :: n_nodes, i, j, k, owner
    integer, allocatable :: coord_node(:), el_coords(:, :), el_nodes(:, :)
    character(len=16), allocatable :: el_type(:)
    character(len=64), allocatable :: el_label(:)
    real(wp), allocatable :: pos(:, :)

    n_nodes = size(model%node_label)
    ! Which node each coordinate belongs to: positions and own rotations from the node table,
    ! a rotation an element carries after its node's x and y (beam: x1 y1 phi1 x2 y2 phi2)
    ! from that node; a hinge then finds its rotations among them.
    allocate(coord_node(model%n_x), source=0)
    do i = 1, n_nodes
      do j = 1, NODE_SLOTS
        if (model%node_coord(j, i) > 0) coord_node(model%node_coord(j, i)) = i
      end do
    end do
    allocate(el_coords(max(6, model%max_dofs), model%n_elements), source=0)
    allocate(el_nodes(2, model%n_elements), source=0)
    allocate(el_type(model%n_elements), el_label(model%n_elements))
    do i = 1, model%n_elements
      associate (e => model%elements(i)%e)
        el_type(i) = e%type_name()
        el_label(i) = e%label
        el_coords(1:size(e%dofs), i) = e%dofs
        owner = 0
        do j = 1, size(e%dofs)
          if (all(model%coord_kind(e%dofs(j)) /= [COORD_PHI, COORD_EULER])) &
            owner = coord_node(e%dofs(j))
          if (model%coord_kind(e%dofs(j)) == COORD_PHI .and. owner > 0 .and. &
              coord_node(e%dofs(j)) == 0) coord_node(e%dofs(j)) = owner
        end do
      end associate
    end do
    do i = 1, model%n_elements
      associate (e => model%elements(i)%e)
        k = 0
        do j = 1, size(e%dofs)
          if (k == 2) exit
          ! An element's nodes: those of its positions, or of its rotations if it has none.
          if (model%coord_kind(e%dofs(j)) == COORD_PHI .and. any(model%coord_kind(e%dofs) /= &
              COORD_PHI)) cycle
          if (any(model%coord_kind(e%dofs(j)) == [COORD_Y, COORD_Z, COORD_EULER])) cycle
          k = k + 1
          el_nodes(k, i) = coord_node(e%dofs(j))
        end do
        ! A one-node element (slider) names its node twice, like a hinge.
        if (k == 1) el_nodes(2, i) = el_nodes(1, i)
      end associate
    end do
    allocate(pos(3, n_nodes))
    do i = 1, n_nodes
      pos(1:2, i) = model%x0(model%node_coord(1:2, i))
      pos(3, i) = 0.0_wp
      if (model%node_coord(4, i) > 0) pos(3, i) = model%x0(model%node_coord(4, i))
    end do
    call h5%write_string_1d(g // '/coordinates/name', model%coord_name, err)
    if (err%ok()) call h5%write_real_1d(g // '/coordinates/reference', model%x0, err)
    if (err%ok()) call h5%write_int_1d(g // '/coordinates/kind', model%coord_kind, err)
    if (err%ok()) call h5%write_string_1d(g // '/nodes/label', model%node_label, err)
    if (err%ok()) call h5%write_real_2d(g // '/nodes/position', pos, err, units='m')
    ! Planar files keep their (x, y, phi) table; spatial ones add z and the first lambda.
    if (err%ok()) call h5%write_int_2d(g // '/nodes/coordinates', &
      model%node_coord(1:merge(3, NODE_SLOTS, model%dim == 2), :), err)
    if (err%ok()) call h5%write_string_1d(g // '/elements/label', el_label, err)
    if (err%ok()) call h5%write_string_1d(g // '/elements/type', el_type, err)
    if (err%ok()) call h5%write_int_2d(g // '/elements/coordinates', el_coords, err)
    if (err%ok()) call h5%write_int_2d(g // '/elements/nodes', el_nodes, err)
    if (err%ok()) call h5%write_int_attr(g, 'n_nodes', n_nodes, err)
    if (err%ok()) call h5%write_int_attr(g, 'n_elements', model%n_elements, err)
    if (err%ok()) call h5%write_int_attr(g, 'dimension', model%dim, err)
    if (err%ok()) call h5%write_int_attr(g, 'n_coordinates', model%n_x, err)
  end subroutine write_model

  !> Node positions (n, 3) and rotations (n) of the output nodes from coordinate histories.
  subroutine write_nodes(this, h5, group, x, err)
    type(run_t), intent(in) :: this
    type(h5_writer_t), intent(inout) :: h5
    character(len=*), intent(in) :: group
    real(wp), intent(in) :: x(:, :)
    type(error_t), intent(inout) :: err
    real(wp) :: pos(3, size(x, 2))
    integer :: i, in, ic(NODE_SLOTS)
    do i = 1, size(this%scene%output_nodes)
      associate (label => this%scene%output_nodes(i)%s)
        in = this%dyn%model%find_node(label)
        ic = this%dyn%model%node_coord(:, in)
        pos(1, :) = x(ic(1), :)
        pos(2, :) = x(ic(2), :)
        pos(3, :) = 0.0_wp
        if (ic(4) > 0) pos(3, :) = x(ic(4), :)
        if (err%ok()) call h5%write_real_2d(group // '/nodes/' // label // '/position', pos, &
          err, units='m')
        if (ic(3) > 0 .and. err%ok()) call h5%write_real_1d(group // '/nodes/' // label // &
          '/rotation', x(ic(3), :), err, units='rad')
        if (ic(5) > 0 .and. err%ok()) call h5%write_real_2d(group // '/nodes/' // label // &
          '/orientation', x(ic(5):ic(5) + 3, :), err)
      end associate
    end do
  end subroutine write_nodes

  subroutine write_static(this, h5, err)
    type(run_t), intent(in) :: this
    type(h5_writer_t), intent(inout) :: h5
    type(error_t), intent(inout) :: err
    integer :: i
    call h5%write_real_1d('/static/load_factor', this%static_load_factor, err)
    if (err%ok()) call h5%write_real_1d('/static/q', this%q_static, err)
    if (err%ok()) call h5%write_real_2d('/static/x', this%x_static, err)
    if (err%ok()) call h5%write_int_1d('/static/stable', merge(1, 0, this%static_stable), err)
    call write_nodes(this, h5, '/static', this%x_static, err)
    associate (r => this%static_response, sc => this%scene)
      if (sc%static%n_frequencies > 0 .and. err%ok()) call h5%write_real_2d( &
        '/static/frequency_hz', r%frequency_hz, err, units='Hz')
      do i = 1, size(sc%output_nodes)
        if (err%ok()) call h5%write_real_2d('/static/nodes/' // sc%output_nodes(i)%s // &
          '/reaction', r%reaction(:, i, :), err, units=trim(merge('N, N, N m             ', &
          'N, N, N, N m, N m, N m', r%n_comp == 3)))
      end do
      do i = 1, size(sc%compliance_nodes)
        if (err%ok()) call h5%write_real_3d('/static/nodes/' // sc%compliance_nodes(i)%s // &
          '/compliance', r%compliance(:, :, i, :), err, units='m/N, rad/(N m)')
      end do
    end associate
  end subroutine write_static

  !> Output node i's x, y, z (0 in the plane) rows of nodal shapes (n_x, n_shapes).
  function node_shape(this, i, node_shapes) result(shape)
    type(run_t), intent(in) :: this
    integer, intent(in) :: i
    real(wp), intent(in) :: node_shapes(:, :)
    real(wp) :: shape(3, size(node_shapes, 2))
    integer :: ic(NODE_SLOTS)
    ic = this%dyn%model%node_coord(:, this%dyn%model%find_node(this%scene%output_nodes(i)%s))
    shape(1, :) = node_shapes(ic(1), :)
    shape(2, :) = node_shapes(ic(2), :)
    shape(3, :) = 0.0_wp
    if (ic(4) > 0) shape(3, :) = node_shapes(ic(4), :)
  end function node_shape

  subroutine write_modal(this, h5, err)
    type(run_t), intent(in) :: this
    type(h5_writer_t), intent(inout) :: h5
    type(error_t), intent(inout) :: err
    integer :: i
    call h5%write_real_1d('/modal/frequency_hz', this%modal%frequency_hz, err, units='Hz')
    if (err%ok()) call h5%write_real_2d('/modal/shapes', this%modal%shapes, err)
    if (err%ok()) call h5%write_real_attr('/modal', 'time', this%scene%modal%time, err)
    if (err%ok()) call h5%write_string_attr('/modal', 'eigensolver', trim(this%modal%solver), &
      err)
    do i = 1, size(this%scene%output_nodes)
      if (err%ok()) call h5%write_real_2d('/modal/nodes/' // this%scene%output_nodes(i)%s // &
        '/shape', node_shape(this, i, this%modal%node_shapes(:, :, 1)), err, units='m')
    end do
  end subroutine write_modal

  !> Multipliers and shapes of the linearised buckling analysis (possibly none).
  subroutine write_buckling(this, h5, err)
    type(run_t), intent(in) :: this
    type(h5_writer_t), intent(inout) :: h5
    type(error_t), intent(inout) :: err
    integer :: i
    associate (b => this%buckling)
      call h5%write_real_1d('/buckling/load_factor', b%load_factor, err)
      if (err%ok()) call h5%write_real_2d('/buckling/shapes', b%shapes, err)
      if (err%ok()) call h5%write_real_attr('/buckling', 'reference_load_factor', &
        b%reference_load_factor, err)
      if (err%ok()) call h5%write_int_attr('/buckling', 'n_negative', b%n_negative, err)
      do i = 1, size(this%scene%output_nodes)
        if (err%ok()) call h5%write_real_2d('/buckling/nodes/' // &
          this%scene%output_nodes(i)%s // '/shape', node_shape(this, i, b%node_shapes), err)
      end do
    end associate
  end subroutine write_buckling

  subroutine write_dynamic(this, h5, err)
    type(run_t), intent(in) :: this
    type(h5_writer_t), intent(inout) :: h5
    type(error_t), intent(inout) :: err
    call h5%write_real_1d('/time', this%time, err, units='s')
    call write_nodes(this, h5, '', this%dyn%x_hist, err)
    if (err%ok()) call h5%write_real_2d('/x', this%dyn%x_hist, err)
    if (err%ok()) call h5%write_real_2d('/q', this%dyn%q_hist, err)
    if (err%ok()) call h5%write_real_2d('/qd', this%dyn%v_hist, err)
    if (err%ok()) call h5%write_real_1d('/energy/kinetic', this%dyn%energy_hist(1, :), err, &
      units='J')
    if (err%ok()) call h5%write_real_1d('/energy/potential', this%dyn%energy_hist(2, :), err, &
      units='J')
    if (err%ok()) call write_controllers(this, h5, err)
  end subroutine write_dynamic

  !> /controllers/<label>/input (the applied u) and /measure (y) at the output times, one
  !> column per actuator or measured output when there are several; /error (e = r - y) of a
  !> PID.
  subroutine write_controllers(this, h5, err)
    type(run_t), intent(in) :: this
    type(h5_writer_t), intent(inout) :: h5
    type(error_t), intent(inout) :: err
    integer :: k
    associate (c => this%dyn%model%controllers)
      if (.not. allocated(this%control%error_hist)) return
      do k = 1, size(c)
        if (err%ok() .and. c(k)%law_kind == LAW_PID) call h5%write_real_1d('/controllers/' // &
          c(k)%label // '/error', this%control%error_hist(k, :), err)
        call write_channels('/controllers/' // c(k)%label // '/input', &
          this%control%u_hist(c(k)%u_offset + 1:c(k)%u_offset + size(c(k)%act_index), :))
        call write_channels('/controllers/' // c(k)%label // '/measure', &
          this%control%y_hist(c(k)%y_offset + 1:c(k)%y_offset + size(c(k)%meas_index), :))
      end do
    end associate
  contains
    subroutine write_channels(name, hist)
      character(len=*), intent(in) :: name
      real(wp), intent(in) :: hist(:, :)
      if (.not. err%ok()) return
      if (size(hist, 1) == 1) then
        call h5%write_real_1d(name, hist(1, :), err)
      else
        call h5%write_real_2d(name, hist, err)
      end if
    end subroutine write_channels
  end subroutine write_controllers

  !> The reduced analysis: basis, reduced coordinates, error indicator and basis updates.
  subroutine write_reduction(this, h5, err)
    type(run_t), intent(in) :: this
    type(h5_writer_t), intent(inout) :: h5
    type(error_t), intent(inout) :: err
    character(len=*), parameter :: g = '/reduction'
    associate (b => this%initial_basis, red => this%red, r => this%scene%reduction)
      call h5%write_real_2d(g // '/eta', red%eta_hist, err)
      if (err%ok()) call h5%write_real_2d(g // '/eta_dot', red%eta_dot_hist, err)
      if (err%ok()) call h5%write_real_2d(g // '/basis', b%v, err)
      if (err%ok()) call h5%write_real_1d(g // '/frequency_hz', b%frequency_hz, err, units='Hz')
      if (err%ok()) call h5%write_real_1d(g // '/residual', red%residual, err)
      if (err%ok() .and. red%has_estimate) call h5%write_real_1d(g // '/error_estimate', &
        red%estimate, err, units='m')
      if (err%ok()) call h5%write_int_attr(g, 'n_modes', b%k(), err)
      if (err%ok()) call h5%write_string_attr(g, 'selection', r%selection, err)
      if (err%ok()) call h5%write_string_attr(g, 'reason', b%reason, err)
      if (err%ok()) call h5%write_real_attr(g, 'cutoff_hz', b%cutoff_hz, err)
      if (err%ok()) call h5%write_real_attr(g, 'motion_bandwidth_hz', b%bandwidth_hz, err)
      if (err%ok()) call h5%write_real_attr(g, 'basis_time', r%basis_time, err)
      if (err%ok()) call h5%write_string_attr(g, 'eigensolver', trim(b%solver), err)
      if (err%ok()) call h5%write_string_attr(g, 'static_correction', &
        trim(merge('yes', 'no ', r%static_correction)), err)
      if (err%ok()) call h5%write_real_attr(g, 'residual_max', red%residual_max(), err)
      if (err%ok() .and. red%has_estimate) call h5%write_real_attr(g, 'error_estimate_max', &
        red%estimate_max(), err)
      if (err%ok()) call h5%write_string_attr(g, 'evaluation', &
        trim(EVALUATION_NAMES(r%evaluation)), err)
      if (err%ok() .and. red%expanded) call h5%write_int_attr(g, 'n_expansions', &
        red%expansions%n_expansions, err)
      if (err%ok() .and. red%expanded) call h5%write_int_attr(g, 'n_expansions_exact_turns', &
        red%expansions%n_exact_turns, err)
      if (err%ok() .and. red%expanded) call h5%write_real_attr(g, 'manifold_error_max', &
        red%expansions%manifold_error, err)
      if (err%ok() .and. red%expanded) call write_measured(h5, red, err)
      if (err%ok()) call h5%write_string_attr(g, 'update', trim(UPDATE_NAMES(r%update)), err)
      if (err%ok()) call h5%write_int_attr(g, 'n_updates', this%updates%n_updates, err)
      if (err%ok() .and. size(this%updates%time) > 0) then
        call h5%write_real_1d(g // '/checks/time', this%updates%time, err, units='s')
        if (err%ok()) call h5%write_real_1d(g // '/checks/min_mac', this%updates%min_mac, err)
        if (err%ok()) call h5%write_int_1d(g // '/checks/updated', &
          merge(1, 0, this%updates%updated), err)
        if (err%ok()) call h5%write_real_2d(g // '/checks/frequency_hz', &
          this%updates%frequency_hz, err, units='Hz')
      end if
    end associate
  end subroutine write_reduction

  !> &dynamic error_check: the distance and rotation of the second run's nodes (/error_check).
  subroutine write_error_check(this, h5, err)
    type(run_t), intent(in) :: this
    type(h5_writer_t), intent(inout) :: h5
    type(error_t), intent(inout) :: err
    character(len=*), parameter :: g = '/error_check'
    call h5%write_real_1d(g // '/distance', this%check_distance, err, units='m')
    if (err%ok()) call h5%write_string_attr(g, 'kind', &
      trim(ERROR_CHECK_NAMES(this%scene%dynamic%error_check)), err)
    if (err%ok()) call h5%write_string_attr(g, 'second_run', this%check_rerun, err)
    if (err%ok()) call h5%write_real_attr(g, 'distance_max', maxval(this%check_distance), err)
    if (err%ok()) call h5%write_string_attr(g, 'node_max', this%check_node, err)
    if (err%ok()) call h5%write_int_attr(g, 'n_steps', this%check_steps, err)
    if (err%ok()) call h5%write_real_attr(g, 'cpu_time_s', this%check_cpu_s, err)
    if (.not. allocated(this%check_rotation)) return
    if (err%ok()) call h5%write_real_1d(g // '/rotation', this%check_rotation, err, units='rad')
    if (err%ok()) call h5%write_real_attr(g, 'rotation_max', maxval(this%check_rotation), err)
    if (err%ok()) call h5%write_string_attr(g, 'rotation_node_max', this%check_rotation_node, &
      err)
  end subroutine write_error_check

  !> The exact measurements of an expanded run's error indicators (/reduction/measured).
  subroutine write_measured(h5, red, err)
    type(h5_writer_t), intent(inout) :: h5
    type(reduced_t), intent(in) :: red
    type(error_t), intent(inout) :: err
    character(len=*), parameter :: g = '/reduction/measured'
    integer :: n
    n = red%measured%n
    call h5%write_int_attr('/reduction', 'n_measured', n, err)
    if (n == 0) return
    if (err%ok()) call h5%write_real_1d(g // '/time', red%measured%time(1:n), err, units='s')
    if (err%ok()) call h5%write_real_1d(g // '/residual', red%measured%residual(1:n), err)
    if (err%ok() .and. red%has_estimate) call h5%write_real_1d(g // '/error_estimate', &
      red%measured%estimate(1:n), err, units='m')
    if (err%ok()) call h5%write_int_1d(g // '/kind', red%measured%kind(1:n), err)
  end subroutine write_measured
end submodule analysis_run_output
