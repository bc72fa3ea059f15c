!> The analysis groups of a scene file (&static, &modal, &buckling, &linear, &dynamic,
!> &reduction, &output) and &controller, read into the scene records (docs/input.md). io_scene
!> calls them group by group.
module io_scene_analyses
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_INPUT
  use core_strings, only: approx_str
  use io_namelist, only: nml_group_t
  use io_fields, only: rd_real, rd_int, rd_logical, rd_string, rd_choice, rd_enum, rd_label, &
    only_with, rd_labels, rd_reals, check_increasing
  use io_table, only: relative_to
  use model_scene, only: auto_integrator, scene_t, controller_rec_t, UPDATE_NAMES, UPDATE_NONE, &
    UPDATE_INTERVAL, UPDATE_MAC, JOINTS_NAMES, JOINTS_HELD, EVALUATION_NAMES, &
    EVALUATION_EXPANDED, ERROR_CHECK_NAMES, ERROR_CHECK_TOLERANCE, ERROR_CHECK_MODES, &
    STATIC_METHOD_NAMES, STATIC_ARC_LENGTH, INTEGRATOR_NAMES, INTEGRATOR_AUTO, INTEGRATOR_BDF, &
    INTEGRATOR_GALPHA, INTEGRATOR_GALPHA_ADAPTIVE, INTEGRATOR_ERK, JACOBIAN_NAMES, &
    JACOBIAN_INTERNAL
  implicit none
  private
  public :: read_static, read_modal, read_buckling, read_controller, read_linear, &
    read_dynamic, read_reduction, read_output

contains

  subroutine read_static(g, scene, err)
    type(nml_group_t), intent(inout) :: g
    type(scene_t), intent(inout) :: scene
    type(error_t), intent(inout) :: err
    scene%static%active = .true.
    call rd_int(g, 'n_steps', scene%static%n_steps, err)
    call rd_real(g, 'tol', scene%static%tol, err)
    call rd_int(g, 'max_iter', scene%static%max_iter, err)
    call rd_int(g, 'n_frequencies', scene%static%n_frequencies, err)
    call rd_enum(g, 'method', STATIC_METHOD_NAMES, scene%static%method, err)
    if (err%ok()) call only_with(g, ['arc_length     ', 'max_load_factor'], &
      scene%static%method == STATIC_ARC_LENGTH, 'with method = ''arc_length''', err)
    if (g%has('arc_length')) call rd_real(g, 'arc_length', scene%static%arc_length, err)
    if (g%has('max_load_factor')) call rd_real(g, 'max_load_factor', &
      scene%static%max_load_factor, err)
    call rd_choice(g, 'solver', scene%static%solver, err)
  end subroutine read_static

  subroutine read_modal(g, scene, err)
    type(nml_group_t), intent(inout) :: g
    type(scene_t), intent(inout) :: scene
    type(error_t), intent(inout) :: err
    scene%modal%active = .true.
    call rd_int(g, 'n_modes', scene%modal%n_modes, err)
    call rd_real(g, 'time', scene%modal%time, err)
    call rd_logical(g, 'along_motion', scene%modal%along_motion, err)
    call rd_choice(g, 'solver', scene%modal%solver, err)
  end subroutine read_modal

  subroutine read_buckling(g, scene, err)
    type(nml_group_t), intent(inout) :: g
    type(scene_t), intent(inout) :: scene
    type(error_t), intent(inout) :: err
    scene%buckling%active = .true.
    call rd_int(g, 'n_modes', scene%buckling%n_modes, err)
    call rd_real(g, 'load_factor', scene%buckling%load_factor, err)
    call rd_choice(g, 'solver', scene%buckling%solver, err)
  end subroutine read_buckling

  subroutine read_controller(g, r, err)
    type(nml_group_t), intent(inout) :: g
    type(controller_rec_t), intent(out) :: r
    type(error_t), intent(inout) :: err
    logical :: pid
    call rd_label(g, r%label, err)
    call rd_choice(g, 'law', r%law, err)
    call rd_labels(g, 'actuator', r%actuator, err)
    call rd_labels(g, 'measure', r%measure, err)
    call rd_string(g, 'reference', r%reference, err)
    call rd_real(g, 'kp', r%kp, err)
    call rd_real(g, 'ki', r%ki, err)
    call rd_real(g, 'kd', r%kd, err)
    call rd_int(g, 'n_states', r%n_states, err)
    call rd_real(g, 'period', r%period, err)
    call rd_real(g, 'u_min', r%u_min, err, -huge(1.0_wp))
    call rd_real(g, 'u_max', r%u_max, err, huge(1.0_wp))
    call rd_logical(g, 'feedforward', r%feedforward, err)
    if (.not. err%ok()) return
    pid = r%law == 'pid'
    ! A user law computes its own errors: gains and a reference would be silently unused.
    call only_with(g, [character(len=9) :: 'kp', 'ki', 'kd', 'reference'], pid, &
      'with law = ''pid''', err)
    call only_with(g, [character(len=8) :: 'n_states', 'library', 'symbol', 'params'], &
      .not. pid, 'with law = ''user''', err)
    if (.not. pid) call read_library_law(g, r, err)
    if (err%ok() .and. pid .and. (size(r%actuator) /= 1 .or. size(r%measure) /= 1)) &
      call err%set(ERR_INPUT, g%where() // ': law = ''pid'' takes one ''actuator'' and ' // &
      'one ''measure'' (several: law = ''user'')')
    if (err%ok() .and. pid .and. .not. (r%kp > 0 .or. r%ki > 0 .or. r%kd > 0)) &
      call err%set(ERR_INPUT, g%where() // ': a controller needs a gain: ''kp'', ''ki'' ' // &
      'or ''kd'' > 0')
    if (err%ok() .and. .not. r%u_min < r%u_max) call err%set(ERR_INPUT, g%where() // &
      ': ''u_min'' must be below ''u_max''')
  end subroutine read_controller

  !> law = 'user' from a shared library: `library` (relative to the scene file's folder, as a
  !> table's `file`) and `symbol` go together; `params` only go to such a law (a law the
  !> program gives gets the program's own data).
  subroutine read_library_law(g, r, err)
    type(nml_group_t), intent(inout) :: g
    type(controller_rec_t), intent(inout) :: r
    type(error_t), intent(inout) :: err
    type(error_t) :: e
    character(len=:), allocatable :: path
    call rd_string(g, 'library', path, err)
    call rd_string(g, 'symbol', r%symbol, err)
    if (.not. err%ok()) return
    if (g%has('library') .and. .not. g%has('symbol')) then
      call err%set(ERR_INPUT, g%where() // ': variable ''library'' needs ''symbol'', the ' // &
        'name of the law''s function in it')
    else if (g%has('symbol') .and. .not. g%has('library')) then
      call err%set(ERR_INPUT, g%where() // ': variable ''symbol'' needs ''library'', the ' // &
        'shared library that has it')
    else if (g%has('library') .and. len_trim(path) == 0) then
      call err%set(ERR_INPUT, g%where() // ': variable ''library'' must not be empty')
    else if (g%has('symbol') .and. len_trim(r%symbol) == 0) then
      call err%set(ERR_INPUT, g%where() // ': variable ''symbol'' must not be empty')
    else if (g%has('params') .and. .not. g%has('library')) then
      call err%set(ERR_INPUT, g%where() // ': variable ''params'' goes to a law from ' // &
        '''library'' and ''symbol'' (a law the program gives gets the program''s own data)')
    end if
    if (.not. err%ok() .or. .not. g%has('library')) return
    r%library = relative_to(g%path, path)
    if (.not. g%has('params')) return
    call g%get_real_array('params', r%params, e)
    if (.not. e%ok()) err = e
  end subroutine read_library_law

  subroutine read_linear(g, scene, err)
    type(nml_group_t), intent(inout) :: g
    type(scene_t), intent(inout) :: scene
    type(error_t), intent(inout) :: err
    type(error_t) :: e
    scene%linear%active = .true.
    call rd_real(g, 'time', scene%linear%time, err)
    call rd_logical(g, 'along_motion', scene%linear%along_motion, err)
    call rd_labels(g, 'inputs', scene%linear%inputs, err)
    call rd_labels(g, 'outputs', scene%linear%outputs, err)
    if (g%has('times') .and. err%ok()) then
      call rd_reals(g, 'times', scene%linear%times, e)
      call check_increasing(g, 'times', scene%linear%times, e)
      if (.not. e%ok()) then
        err = e
      else if (g%has('time') .or. g%has('along_motion')) then
        call err%set(ERR_INPUT, g%where() // ': variable ''times'' (states along the ' // &
          'dynamic run) excludes ''time'' and ''along_motion'' (one configuration)')
      end if
    end if
  end subroutine read_linear

  subroutine read_dynamic(g, scene, err)
    type(nml_group_t), intent(inout) :: g
    type(scene_t), intent(inout) :: scene
    type(error_t), intent(inout) :: err
    associate (d => scene%dynamic)
      d%active = .true.
      call rd_real(g, 't_end', d%t_end, err)
      call rd_real(g, 'output_dt', d%output_dt, err)
      call rd_real(g, 'rtol', d%rtol, err)
      call rd_enum(g, 'integrator', INTEGRATOR_NAMES, d%integrator, err)
      if (err%ok() .and. d%integrator == INTEGRATOR_AUTO) d%integrator = auto_integrator(d%rtol)
      ! Still 'auto' (tight rtol): the run chooses by the model's stiffness, unless BDF's own
      ! option says which one is meant.
      if (err%ok() .and. d%integrator == INTEGRATOR_AUTO .and. g%has('max_order')) &
        d%integrator = INTEGRATOR_BDF
      if (err%ok()) then
        associate (m => d%integrator, when => 'with integrator = ')
          call only_with(g, ['dt     ', 'rho_inf'], &
            any(m == [INTEGRATOR_GALPHA, INTEGRATOR_GALPHA_ADAPTIVE]), &
            when // '''galpha'' or ''galpha_adaptive''' // auto_note(m), err)
          call only_with(g, ['max_order'], m == INTEGRATOR_BDF, when // '''bdf''', err)
          call only_with(g, ['erk_order'], m == INTEGRATOR_ERK, &
            when // '''erk''' // auto_note(m), err)
          call only_with(g, ['max_step'], m /= INTEGRATOR_GALPHA, &
            when // '''bdf'', ''galpha_adaptive'' or ''erk''', err)
          call only_with(g, ['jacobian'], m /= INTEGRATOR_ERK, &
            when // '''bdf'', ''galpha'' or ''galpha_adaptive''', err)
        end associate
      end if
      call rd_enum(g, 'jacobian', JACOBIAN_NAMES, d%jacobian, err)
      call rd_real(g, 'atol', d%atol, err)
      call rd_real(g, 'max_step', d%max_step, err)
      call rd_int(g, 'max_order', d%max_order, err)
      call rd_int(g, 'erk_order', d%erk_order, err)
      call rd_real(g, 'dt', d%dt, err)
      call rd_real(g, 'rho_inf', d%rho_inf, err)
      call rd_enum(g, 'error_check', ERROR_CHECK_NAMES, d%error_check, err)
      if (err%ok()) then
        call only_with(g, ['error_check_factor'], d%error_check == ERROR_CHECK_TOLERANCE, &
          'with error_check = ''tolerance''', err)
        call only_with(g, ['error_check_modes'], d%error_check == ERROR_CHECK_MODES, &
          'with error_check = ''modes''', err)
      end if
      call rd_real(g, 'error_check_factor', d%error_check_factor, err)
      call rd_int(g, 'error_check_modes', d%error_check_modes, err)
      if (.not. err%ok()) return
      ! A step limit that forces more steps than a run may take (10^7), or one below the
      ! round-off of the time, which the integrators cannot step (CVODE refused its options:
      ! an internal error), fails before the run.
      if (d%max_step > 0) then
        if (d%t_end / d%max_step > 1.0e7_wp) then
          call err%set(ERR_INPUT, g%where() // ': variable ''max_step'': t_end / max_step ' // &
            'gives ' // approx_str(d%t_end / d%max_step) // ' steps, more than a run may ' // &
            'take (1e7): raise max_step')
        else if (d%max_step < 16 * spacing(max(d%t_end, 1.0_wp))) then
          call err%set(ERR_INPUT, g%where() // ': variable ''max_step'': ' // &
            approx_str(d%max_step) // ' s is below the round-off of the time: raise max_step')
        end if
        if (.not. err%ok()) return
      end if
      if (d%jacobian == JACOBIAN_INTERNAL .and. d%integrator /= INTEGRATOR_BDF) &
        call err%set(ERR_INPUT, g%where() // ': variable ''jacobian'': ''internal'' (CVODE''s ' &
        // 'difference quotients) needs integrator = ''bdf''' // auto_note(d%integrator))
    end associate
  end subroutine read_dynamic

  subroutine read_reduction(g, scene, err)
    type(nml_group_t), intent(inout) :: g
    type(scene_t), intent(inout) :: scene
    type(error_t), intent(inout) :: err
    type(error_t) :: e
    integer :: n_given
    associate (r => scene%reduction)
      r%active = .true.
      n_given = count([g%has('n_modes'), g%has('cutoff_hz'), g%has('auto_factor')])
      if (n_given /= 1) then
        call err%set(ERR_INPUT, g%where() // ': give exactly one of n_modes (a count), ' // &
          'cutoff_hz (a frequency) or auto_factor (a multiple of the motion bandwidth)')
        return
      end if
      if (g%has('n_modes')) then
        r%selection = 'count'
        call rd_int(g, 'n_modes', r%n_modes, err)
      else if (g%has('cutoff_hz')) then
        r%selection = 'cutoff'
        call rd_real(g, 'cutoff_hz', r%cutoff_hz, err)
      else
        r%selection = 'auto'
        call rd_real(g, 'auto_factor', r%auto_factor, err)
      end if
      call rd_real(g, 'basis_time', r%basis_time, err)
      if (g%has('basis_prescribed') .and. err%ok()) then
        call rd_reals(g, 'basis_prescribed', r%basis_prescribed, e)
        if (.not. e%ok()) err = e
      end if
      call rd_logical(g, 'static_correction', r%static_correction, err)
      call rd_enum(g, 'update', UPDATE_NAMES, r%update, err)
      if (err%ok()) then
        call only_with(g, ['update_interval'], r%update == UPDATE_INTERVAL .or. &
          r%update == UPDATE_MAC, 'with update = ''interval'' or ''mac''', err)
        call only_with(g, ['mac_threshold'], r%update == UPDATE_MAC, &
          'with update = ''mac''', err)
      end if
      call rd_real(g, 'mac_threshold', r%mac_threshold, err)
      call rd_choice(g, 'eigensolver', r%eigensolver, err)
      if (r%update /= UPDATE_NONE) call rd_real(g, 'update_interval', r%update_interval, err)
      call rd_enum(g, 'joints', JOINTS_NAMES, r%joints, err)
      call rd_enum(g, 'evaluation', EVALUATION_NAMES, r%evaluation, err)
      if (err%ok()) call only_with(g, ['expansion_tol   ', 'exact_turns     ', &
        'estimate_samples'], r%evaluation == EVALUATION_EXPANDED, &
        'with evaluation = ''expanded''', err)
      call rd_real(g, 'expansion_tol', r%expansion_tol, err)
      call rd_logical(g, 'exact_turns', r%exact_turns, err)
      call rd_int(g, 'estimate_samples', r%estimate_samples, err)
      if (err%ok() .and. r%joints == JOINTS_HELD) then
        if (r%selection /= 'count') call err%set(ERR_INPUT, g%where() // ': variable ' // &
          '''joints'': ''held'' takes n_modes (cutoff_hz and auto_factor are not built for it)')
      end if
    end associate
  end subroutine read_reduction

  subroutine read_output(g, scene, err)
    type(nml_group_t), intent(inout) :: g
    type(scene_t), intent(inout) :: scene
    type(error_t), intent(inout) :: err
    if (.not. err%ok()) return
    ! Without 'nodes' output_nodes stays unallocated: every node.
    if (g%has('nodes')) call rd_labels(g, 'nodes', scene%output_nodes, err)
    call rd_labels(g, 'compliance_nodes', scene%compliance_nodes, err, optional_list=.true.)
  end subroutine read_output

  !> Why an option of one integrator is refused when the integrator is still 'auto'.
  function auto_note(method) result(note)
    integer, intent(in) :: method
    character(len=:), allocatable :: note
    note = ''
    if (method == INTEGRATOR_AUTO) note = ' (below rtol 1e-6 integrator = ''auto'' chooses ' &
      // 'by the model''s stiffness when the run starts: name the integrator)'
  end function auto_note
end module io_scene_analyses
