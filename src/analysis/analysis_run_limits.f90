!> What a scene may ask, checked before its analyses run: output nodes that exist, memory
!> and time within limits (a failed allocation or a run that cannot end is no message).
submodule (analysis_run) analysis_run_limits
  use model_scene, only: ERROR_CHECK_TOLERANCE
  implicit none

contains

  module procedure check_history_size
    real(wp), parameter :: MAX_HISTORY_BYTES = 4.0e9_wp
    type(integrator_options_t) :: defaults
    real(wp) :: n_out, bytes, n_fixed, max_steps
    n_out = d%t_end / d%output_dt + 2.0_wp
    ! A fixed-step run takes t_end / dt steps (its check run error_check_factor times more):
    ! beyond the integrators' step limit it failed only when the limit was reached, minutes
    ! later (the limit was 1e9 here, 1e7 there).
    max_steps = real(defaults%max_steps, wp)
    n_fixed = d%t_end / d%dt
    if (d%error_check == ERROR_CHECK_TOLERANCE) n_fixed = n_fixed * d%error_check_factor
    ! Per output time: all coordinates, q and qd, energies (8 bytes each).
    bytes = 8.0_wp * n_out * real(model%n_x + 2 * model%n_q + 4, wp)
    if (bytes > MAX_HISTORY_BYTES) then
      call err%set(ERR_INPUT, 'group &dynamic: variable ''output_dt'': t_end / output_dt ' // &
        'gives ' // approx_str(n_out) // ' output times, whose histories would need ' // &
        approx_str(bytes / 1.0e9_wp) // ' GB (limit 4 GB): increase output_dt or shorten t_end')
    else if (d%integrator == INTEGRATOR_GALPHA .and. n_fixed > max_steps) then
      call err%set(ERR_INPUT, 'group &dynamic: variable ''dt'': t_end / dt gives ' // &
        approx_str(n_fixed) // ' fixed steps' // trim(merge(' (with the error check)', &
        '                       ', d%error_check == ERROR_CHECK_TOLERANCE)) // &
        ', more than the ' // int_str(int(defaults%max_steps)) // ' a run may take: ' // &
        'increase dt or shorten t_end')
    end if
  end procedure check_history_size

  !> As check_history_size: a failed allocation is a runtime error, not a message.
  module procedure check_static_size
    real(wp), parameter :: MAX_STATIC_BYTES = 4.0e9_wp
    real(wp) :: bytes
    ! Per step: nodal coordinates, q_dy, the load factor and stability, the frequencies and
    ! each output node's position, rotation, reaction and compliance (8 bytes each). More
    ! frequencies than dynamic coordinates are refused with their own message.
    bytes = 8.0_wp * real(scene%static%n_steps, wp) * real(model%n_x + model%n_dy + 2 + &
      min(scene%static%n_frequencies, model%n_dy) + 2 * NODE_SLOTS * &
      (size(scene%output_nodes) + NODE_SLOTS * size(scene%compliance_nodes)), wp)
    if (bytes > MAX_STATIC_BYTES) call err%set(ERR_INPUT, 'group &static: variable ' // &
      '''n_steps'' = ' // int_str(scene%static%n_steps) // ': the results of that many ' // &
      'steps would need ' // approx_str(bytes / 1.0e9_wp) // ' GB (limit 4 GB): take fewer steps')
  end procedure check_static_size

  module procedure check_output_nodes
    integer :: i, j
    ! Compliance nodes first: they are also output nodes (io_scene adds them).
    do i = 1, size(scene%compliance_nodes)
      associate (label => scene%compliance_nodes(i)%s)
        if (any([(scene%compliance_nodes(j)%s == label, j = 1, i - 1)])) then
          call err%set(ERR_INPUT, 'group &output: variable ''compliance_nodes'': node ''' // &
            label // ''' is listed twice')
          return
        end if
        j = model%find_node(label)
        if (j == 0) then
          call err%set(ERR_INPUT, 'group &output: variable ''compliance_nodes'': node ''' // &
            label // ''' is not defined')
        else if (.not. any(pack(model%calc_index(max(1, model%node_coord(:, j))) > 0 .or. &
            model%coord_input(max(1, model%node_coord(:, j))) == MODE_DYNAMIC, &
            model%node_coord(:, j) > 0))) then
          call err%set(ERR_INPUT, 'group &output: variable ''compliance_nodes'': node ''' // &
            label // ''' has no free coordinate (all fixed or prescribed): its compliance ' // &
            'would be zero')
        end if
        if (.not. err%ok()) return
      end associate
    end do
    do i = 1, size(scene%output_nodes)
      do j = 1, i - 1
        if (scene%output_nodes(j)%s == scene%output_nodes(i)%s) then
          call err%set(ERR_INPUT, 'group &output: variable ''nodes'': node ''' // &
            scene%output_nodes(i)%s // ''' is listed twice')
          return
        end if
      end do
      if (model%find_node(scene%output_nodes(i)%s) == 0) then
        call err%set(ERR_INPUT, 'group &output: variable ''nodes'': node ''' // &
          scene%output_nodes(i)%s // ''' is not defined')
        return
      end if
    end do
  end procedure check_output_nodes
end submodule analysis_run_limits
