!> Integration of a reduced model, with a basis that follows the configuration when asked
!> (adaptive modal integration, Aarts and Jonker 2002).
!>
!> The run is cut into segments at the check times t0 + j * interval. At each check the modes
!> at the current configuration are computed and matched to the basis by MAC; with
!> update = 'interval' the basis is replaced every time, with 'mac' only when the smallest MAC
!> of a kept mode falls below the threshold. On replacement the state is re-projected: the
!> current deformation becomes the new reference (q_ref = q_dy, eta = 0, so positions are
!> continuous) and eta_dot = V_new^T M v_dy (the M-orthogonal projection of the velocity).
module reduction_adaptive
  use core_kinds, only: wp
  use core_strings, only: real_str
  use core_error, only: error_t
  use model_scene, only: UPDATE_NONE, UPDATE_INTERVAL
  use integrators_system, only: integrator_options_t, integrator_stats_t
  use integrators_driver, only: integrate
  use reduction_modal, only: modal_result_t, modal_analysis, modal_mass_times
  use reduction_basis, only: track_modes, held_joint_basis, keep_stiffness
  use reduction_system, only: reduced_t
  use dynamics_control, only: controlled_t
  implicit none
  private
  public :: update_spec_t, update_log_t, integrate_reduced

  type :: update_spec_t
    integer :: mode = UPDATE_NONE             !< UPDATE_* (model_scene)
    real(wp) :: interval = 0.0_wp             !< time between checks [s]
    real(wp) :: mac_threshold = 0.9_wp
    character(len=8) :: eigensolver = 'auto'
    !> Joints held in the basis (reduction_basis's held_joint_basis); empty: free modes.
    integer, allocatable :: held(:)
  end type update_spec_t

  !> One entry per check.
  type :: update_log_t
    real(wp), allocatable :: time(:), min_mac(:)
    logical, allocatable :: updated(:)
    real(wp), allocatable :: frequency_hz(:, :)   !< (k, n_checks) basis after the check
    integer :: n_updates = 0
  end type update_log_t

contains

  !> Integrate the reduced model over t_out from eta = 0, eta_dot = 0 and record every output.
  !> `control`: the reduced model with its controllers (initialised on red), integrated instead.
  subroutine integrate_reduced(red, spec, opts, t_out, breakpoints, stats, log, err, control)
    type(reduced_t), intent(inout), target :: red
    type(update_spec_t), intent(in) :: spec
    type(integrator_options_t), intent(in) :: opts
    real(wp), intent(in) :: t_out(:), breakpoints(:)
    type(integrator_stats_t), intent(out) :: stats
    type(update_log_t), intent(out) :: log
    type(error_t), intent(out) :: err
    type(controlled_t), intent(inout), optional :: control
    real(wp), allocatable :: checks(:), t_seg(:), eta(:), eta_dot(:)
    type(integrator_stats_t) :: seg
    real(wp) :: seg_start, seg_end
    integer :: iseg, k, nt
    integer, allocatable :: all_index(:)
    logical, allocatable :: inside(:)

    nt = size(t_out)
    k = red%basis%k()
    allocate(log%time(0), log%min_mac(0), log%updated(0), log%frequency_hz(k, 0))
    checks = check_times(spec, t_out, breakpoints)
    red%last_eta = [(0.0_wp, iseg = 1, k)]
    red%last_eta_dot = red%last_eta
    all_index = [(iseg, iseg = 1, nt)]
    seg_start = t_out(1)
    if (associated(opts%progress) .and. spec%mode /= UPDATE_NONE) opts%progress%n_updates = 0
    do iseg = 1, size(checks) + 1
      seg_end = t_out(nt)
      if (iseg <= size(checks)) seg_end = checks(iseg)
      inside = t_out > seg_start .and. t_out <= seg_end
      t_seg = [seg_start, pack(t_out, inside)]
      red%out_index = [merge(1, 0, iseg == 1), pack(all_index, inside)]
      if (t_seg(size(t_seg)) < seg_end) then
        t_seg = [t_seg, seg_end]
        red%out_index = [red%out_index, 0]
      end if
      if (present(control)) then
        call control%state(red%last_eta, red%last_eta_dot, eta, eta_dot)
        control%out_index = red%out_index
        call integrate(control, opts, t_seg, eta, eta_dot, breakpoints, seg, err)
      else
        eta = red%last_eta
        eta_dot = red%last_eta_dot
        call integrate(red, opts, t_seg, eta, eta_dot, breakpoints, seg, err)
      end if
      call add_stats(stats, seg)
      if (.not. err%ok()) return
      if (iseg <= size(checks)) call check_basis(red, spec, seg_end, log, err)
      if (.not. err%ok()) return
      if (associated(opts%progress) .and. spec%mode /= UPDATE_NONE) then
        opts%progress%n_updates = log%n_updates
        call opts%progress%skip_pause()
      end if
      seg_start = seg_end
    end do
    if (red%expanded) call red%check_expansions()
  end subroutine integrate_reduced

  !> Check times t0 + j interval inside the run, snapped onto an output time within round-off;
  !> one that falls on a breakpoint is moved just past it, so that the segment before it ends
  !> on the left side of the jump and the driver restarts there as usual.
  function check_times(spec, t_out, breakpoints) result(checks)
    type(update_spec_t), intent(in) :: spec
    real(wp), intent(in) :: t_out(:), breakpoints(:)
    real(wp), allocatable :: checks(:)
    real(wp) :: t, tiny_t
    integer :: j, i
    allocate(checks(0))
    if (spec%mode == UPDATE_NONE) return
    tiny_t = 1.0e-9_wp * (t_out(size(t_out)) - t_out(1))
    j = 1
    do
      t = t_out(1) + j * spec%interval
      if (t >= t_out(size(t_out)) - tiny_t) exit
      i = minloc(abs(t_out - t), dim=1)
      if (abs(t_out(i) - t) <= tiny_t) t = t_out(i)
      if (any(abs(breakpoints - t) <= tiny_t)) t = t + 1.0e-6_wp * spec%interval
      checks = [checks, t]
      j = j + 1
    end do
  end function check_times

  subroutine add_stats(total, seg)
    type(integrator_stats_t), intent(inout) :: total
    type(integrator_stats_t), intent(in) :: seg
    total%n_steps = total%n_steps + seg%n_steps
    total%n_rhs_evals = total%n_rhs_evals + seg%n_rhs_evals
    total%n_jac_evals = total%n_jac_evals + seg%n_jac_evals
    total%n_factorisations = total%n_factorisations + seg%n_factorisations
    total%n_err_test_fails = total%n_err_test_fails + seg%n_err_test_fails
    total%n_nonlin_fails = total%n_nonlin_fails + seg%n_nonlin_fails
    total%n_restarts = total%n_restarts + seg%n_restarts
  end subroutine add_stats

  !> Modes at the current configuration, matched to the basis; replace the basis when asked.
  subroutine check_basis(red, spec, t, log, err)
    type(reduced_t), intent(inout) :: red
    type(update_spec_t), intent(in) :: spec
    real(wp), intent(in) :: t
    type(update_log_t), intent(inout) :: log
    type(error_t), intent(inout) :: err
    type(modal_result_t) :: modes
    real(wp), allocatable :: q_dy(:), v_dy(:), tracked(:, :), mac(:)
    integer, allocatable :: pick(:)
    integer :: k, n_dy
    logical :: replace, controls_on, held_joints_given

    ! The expansions of this basis are compared with the exact model first, while they are
    ! kept: the checks evaluate the model elsewhere, and the modal analysis below leaves it
    ! prepared at this state for the modal masses.
    if (red%expanded) call red%check_expansions()
    k = red%basis%k()
    n_dy = red%dyn%model%n_dy
    allocate(q_dy(n_dy), v_dy(n_dy), tracked(n_dy, k), mac(k), pick(k))
    call red%full_state(red%last_eta, red%last_eta_dot, q_dy, v_dy)
    ! Two spare candidates let tracking follow modes that swap order with their neighbours.
    ! The basis is the open-loop plant's, as at the start.
    controls_on = red%dyn%controls_on
    red%dyn%controls_on = .false.
    held_joints_given = .false.
    if (allocated(spec%held)) held_joints_given = size(spec%held) > 0
    call modal_analysis(red%dyn, t, q_dy, min(n_dy, k + 2), modes, err, &
      solver=spec%eigensolver, dense=held_joints_given, for_basis=.true.)
    red%dyn%controls_on = controls_on
    ! A held-joint basis is replaced by the one of the new configuration, k columns (spare
    ! candidates would let tracking drop part of the joints' motions from the span).
    if (err%ok() .and. allocated(spec%held)) then
      if (size(spec%held) > 0) call held_joint_basis(modes%k0, modes%m0, spec%held, k, &
        spec%eigensolver, modes%shapes, modes%frequency_hz, err)
    end if
    if (err%ok()) call track_modes(red%basis%v, modes%shapes, &
      modal_mass_times(red%dyn, modes, red%basis%v), &
      modal_mass_times(red%dyn, modes, modes%shapes), tracked, mac, pick, err)
    if (.not. err%ok()) then
      call err%prefix('basis update at t = ' // real_str(t) // ': ')
      return
    end if
    replace = spec%mode == UPDATE_INTERVAL .or. minval(mac) < spec%mac_threshold
    if (replace) then
      red%last_eta_dot = matmul(transpose(tracked), &
        reshape(modal_mass_times(red%dyn, modes, reshape(v_dy, [n_dy, 1])), [n_dy]))
      red%last_eta = 0.0_wp
      red%basis%v = tracked
      red%basis%frequency_hz = modes%frequency_hz(pick)
      red%basis%q_ref = q_dy
      red%basis%time = t
      call red%expansions%forget()
      call keep_stiffness(red%basis, red%dyn, modes)
      call red%keep_basis()
      log%n_updates = log%n_updates + 1
    end if
    log%time = [log%time, t]
    log%min_mac = [log%min_mac, minval(mac)]
    log%updated = [log%updated, replace]
    log%frequency_hz = reshape([log%frequency_hz, red%basis%frequency_hz], &
      [k, size(log%time)])
  end subroutine check_basis
end module reduction_adaptive
