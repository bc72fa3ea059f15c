!> The dynamic analysis of a run: the integrator and its options, the full or reduced model,
!> the controllers' sampling times and feedforward.
submodule (analysis_run) analysis_run_dynamic
  use core_error, only: ERR_NUMERIC
  use model_scene, only: UPDATE_NONE, JOINTS_HELD, EVALUATION_EXPANDED, auto_by_stiffness
  use integrators_system, only: INTEGRATOR_AUTO, INTEGRATOR_GALPHA_ADAPTIVE, INTEGRATOR_ERK, &
    INTEGRATOR_NAMES
  implicit none

contains

  module procedure run_dynamic
    type(integrator_options_t) :: opts
    real(wp), allocatable :: breaks(:), v0(:), q_aug(:), v_aug(:)
    integer :: i
    this%time = output_times(this%scene%dynamic)
    opts = integrator_options(this%scene%dynamic)
    opts%progress => this%progress
    if (len_trim(this%progress_kind) > 0) then
      call this%progress%start(trim(this%progress_kind), this%time(1), this%time(size(this%time)))
    else
      call this%progress%start(merge('reduced', 'dynamic', this%scene%reduction%active), &
        this%time(1), this%time(size(this%time)))
    end if
    this%dyn%jacobian_kind = this%scene%dynamic%jacobian
    allocate(breaks(0))
    do i = 1, this%dyn%model%n_motions
      breaks = [breaks, this%dyn%model%motions(i)%breakpoints()]
    end do
    breaks = [breaks, sample_times(this%dyn%model, this%time(1), this%time(size(this%time)))]
    this%dyn%controls_on = size(this%dyn%model%controllers) > 0
    if (this%scene%reduction%active) then
      call run_reduced(this, opts, breaks, err)
    else
      if (opts%method == INTEGRATOR_AUTO) call choose_integrator(this, opts, full_omega_max(this))
      if (opts%method == INTEGRATOR_ERK) call warn_explicit_on_stiff(this, full_omega_max(this))
      call this%dyn%allocate_history(size(this%time))
      allocate(v0(this%dyn%model%n_dy))
      v0 = 0.0_wp
      if (this%dyn%controls_on) then
        call this%control%init(this%dyn, this%dyn, this%dyn%model%n_dy, this%time(1))
        call this%control%allocate_history(size(this%time))
        call add_feedforward(this, err)
        if (.not. err%ok()) return
        call this%control%state(this%q_static, v0, q_aug, v_aug)
        call this%control%check_sampling(this%time(1), q_aug, v_aug)
        call integrate(this%control, opts, this%time, q_aug, v_aug, breaks, this%stats, err)
      else
        call integrate(this%dyn, opts, this%time, this%q_static, v0, breaks, this%stats, err)
      end if
    end if
    this%dyn%controls_on = .false.
    if (.not. err%ok() .and. allocated(this%dyn%last_error%message)) &
      err%message = err%message // ' (' // this%dyn%last_error%message // ')'
    if (.not. err%ok()) call add_configuration_hint(this%dyn, err)
    if (.not. err%ok() .and. allocated(this%control%hint)) then
      if (len(this%control%hint) > 0) err%message = err%message // '. A sampled ' // &
        'controller may be unstable: ' // this%control%hint(3:)
    end if
    if (this%verbose .and. err%ok()) write(*, '(a,i0,a,i0,a,i0,a,i0,a)') 'dynamic: ', &
      this%stats%n_steps, ' steps, ', this%stats%n_rhs_evals, ' evaluations, ', &
      this%stats%n_jac_evals, ' Jacobians, ', this%stats%n_factorisations, ' factorisations'
  end procedure run_dynamic

  !> integrator = 'auto' below rtol 1e-6: BDF unless the model is stiff (model_scene's
  !> auto_by_stiffness); omega_max < 0: not known, taken as stiff. The choice and its reason
  !> go to the result (attributes integrator, integrator_choice) and the summary.
  subroutine choose_integrator(this, opts, omega_max)
    type(run_t), intent(inout) :: this
    type(integrator_options_t), intent(inout) :: opts
    real(wp), intent(in) :: omega_max
    real(wp) :: span
    span = this%time(size(this%time)) - this%time(1)
    if (omega_max < 0.0_wp) then
      opts%method = INTEGRATOR_GALPHA_ADAPTIVE
      this%integrator_choice = 'auto: the fastest mode is not computed for models of more ' // &
        'than ' // int_str(AUTO_MODAL_MAX) // ' dynamic coordinates; taken as stiff'
    else
      opts%method = auto_by_stiffness(omega_max, span)
      this%integrator_choice = 'auto: the fastest mode (' // approx_str(omega_max / TWO_PI) // &
        ' Hz) turns through ' // approx_str(omega_max * span) // ' rad over the run, ' // &
        trim(merge('stiff    ', 'not stiff', opts%method == INTEGRATOR_GALPHA_ADAPTIVE)) // &
        ' (limit 1000 rad)'
    end if
    this%scene%dynamic%integrator = opts%method
    if (this%verbose) write(*, '(a)') 'integrator: ' // trim(INTEGRATOR_NAMES(opts%method)) // &
      ' (' // this%integrator_choice // ')'
  end subroutine choose_integrator

  !> integrator = 'erk' on a model that 'auto' would call stiff: an explicit method's step is
  !> held to about 3 / omega_max by stability whatever rtol asks (stage_pid.nml, its 2 s at
  !> 'erk', ran for minutes), which the user should hear before waiting. omega_max < 0: not
  !> known, nothing said.
  subroutine warn_explicit_on_stiff(this, omega_max)
    type(run_t), intent(inout) :: this
    real(wp), intent(in) :: omega_max
    real(wp) :: span
    span = this%time(size(this%time)) - this%time(1)
    if (.not. omega_max > 0.0_wp) return
    if (auto_by_stiffness(omega_max, span) /= INTEGRATOR_GALPHA_ADAPTIVE) return
    ! Appended here: gfortran keeps the parent's private add_warning local to its object.
    if (.not. allocated(this%warnings)) allocate(this%warnings(0))
    this%warnings = [this%warnings, string_t('dynamic: integrator = ''erk'' on a stiff ' // &
      'model: its fastest mode (' // approx_str(omega_max / TWO_PI) // ' Hz) holds an ' // &
      'explicit step to about ' // approx_str(3.0_wp / omega_max) // ' s, some ' // &
      approx_str(span * omega_max / 3.0_wp) // ' steps over the run; ''galpha_adaptive'' ' // &
      'or ''bdf'' (or ''auto'') are not so limited')]
  end subroutine warn_explicit_on_stiff

  !> The fastest natural frequency [rad/s] of the full model at the start (joints locked), or
  !> -1 when the model is too large for all its modes or they cannot be computed (a singular
  !> mass matrix): then it is taken as stiff, which a large model is.
  real(wp) function full_omega_max(this) result(omega)
    type(run_t), intent(inout) :: this
    type(modal_result_t) :: modes
    type(error_t) :: err
    omega = -1.0_wp
    if (this%dyn%model%n_dy > AUTO_MODAL_MAX) return
    call modal_analysis(this%dyn, this%time(1), this%q_static, 0, modes, err, 'lapack')
    if (err%ok()) omega = sqrt(max(maxval(modes%omega2), 0.0_wp))
  end function full_omega_max

  !> Output every output_dt, and at t_end exactly (once, even when t_end is not a multiple).
  function output_times(d) result(time)
    type(dynamic_rec_t), intent(in) :: d
    real(wp), allocatable :: time(:)
    integer :: nt, k
    nt = floor(d%t_end / d%output_dt * (1 + 1.0e-12_wp)) + 1
    time = [((k - 1) * d%output_dt, k=1, nt)]
    if (d%t_end - time(nt) > 1.0e-9_wp * d%output_dt) then
      time = [time, d%t_end]
    else
      time(nt) = d%t_end
    end if
  end function output_times

  function integrator_options(d) result(opts)
    type(dynamic_rec_t), intent(in) :: d
    type(integrator_options_t) :: opts
    opts%method = d%integrator
    opts%rtol = d%rtol
    opts%atol = d%atol
    opts%max_step = d%max_step
    opts%max_order = d%max_order
    opts%erk_order = d%erk_order
    opts%jacobian = d%jacobian
    opts%dt = d%dt
    opts%rho_inf = d%rho_inf
  end function integrator_options

  !> The reduced dynamic analysis: basis at the configuration the input names, then the
  !> integration in eta. The full model's histories end up in this%dyn as for a full run.
  subroutine run_reduced(this, opts, breaks, err)
    type(run_t), intent(inout) :: this
    type(integrator_options_t), intent(in) :: opts
    real(wp), intent(in) :: breaks(:)
    type(error_t), intent(out) :: err
    type(update_spec_t) :: update
    type(integrator_options_t) :: run_opts
    associate (r => this%scene%reduction)
      update%mode = r%update
      update%interval = r%update_interval
      update%mac_threshold = r%mac_threshold
      update%eigensolver = r%eigensolver
      if (r%joints == JOINTS_HELD) call held_joints(this%dyn%model, update%held, err)
      if (.not. err%ok()) return
      if (allocated(this%red)) deallocate(this%red)
      allocate(this%red)
      this%red%dyn = this%dyn
      ! The basis is the open-loop plant's; the controllers act in the integration.
      this%red%dyn%controls_on = .false.
      this%red%static_correction = r%static_correction
      this%red%expanded = r%evaluation == EVALUATION_EXPANDED
      this%red%expansions%tol = r%expansion_tol
      this%red%expansions%use_frames = r%exact_turns
      this%red%estimate_samples = r%estimate_samples
      if (this%red%expanded) call check_expanded(this, err)
      if (.not. err%ok()) return
      ! &linear times linearises at the basis each sample was computed in.
      this%red%keep_bases = this%scene%linear%active .and. allocated(this%scene%linear%times)
      call reduction_basis(this, this%red%dyn, this%red%basis, err)
      if (.not. err%ok()) return
      if (r%static_correction .and. .not. this%red%basis%has_k0()) then
        call err%set(ERR_INPUT, 'group &reduction: static_correction needs a positive ' // &
          'definite stiffness at the basis configuration (a dynamic mode has no stiffness), ' &
          // "or, with loads, the dense tangent (eigensolver = 'auto', 'lapack' or 'arpack')")
        return
      end if
    end associate
    this%initial_basis = this%red%basis
    run_opts = opts
    if (run_opts%method == INTEGRATOR_AUTO) call choose_integrator(this, run_opts, &
      TWO_PI * maxval(this%red%basis%frequency_hz))
    if (run_opts%method == INTEGRATOR_ERK) call warn_explicit_on_stiff(this, &
      TWO_PI * maxval(this%red%basis%frequency_hz))
    if (this%verbose) write(*, '(a,i0,a)') 'reduction: ', &
      this%red%basis%k(), ' modes (' // this%red%basis%reason // '), [Hz]: ' // &
      hz_list(this%red%basis%frequency_hz)
    flush(output_unit)
    call this%red%allocate_history(size(this%time))
    this%red%dyn%controls_on = this%dyn%controls_on
    if (this%red%dyn%controls_on) then
      call this%control%init(this%red, this%red%dyn, this%red%basis%k(), this%time(1))
      call this%control%allocate_history(size(this%time))
      call add_feedforward(this, err)
      if (.not. err%ok()) return
      block
        real(wp), allocatable :: eta(:), eta_dot(:)
        call this%control%state(0.0_wp * this%red%basis%v(1, :), &
          0.0_wp * this%red%basis%v(1, :), eta, eta_dot)
        call this%control%check_sampling(this%time(1), eta, eta_dot)
      end block
      call integrate_reduced(this%red, update, run_opts, this%time, breaks, this%stats, &
        this%updates, err, this%control)
    else
      call integrate_reduced(this%red, update, run_opts, this%time, breaks, this%stats, &
        this%updates, err)
    end if
    if (.not. err%ok()) call add_configuration_hint(this%red%dyn, err)
    ! What follows (&linear along the run) analyses the open loop.
    this%red%dyn%controls_on = .false.
    this%dyn = this%red%dyn
    if (this%verbose .and. err%ok() .and. update%mode /= UPDATE_NONE) write(*, '(a,i0,a,i0,a)') &
      'reduction: ', this%updates%n_updates, ' basis updates in ', size(this%updates%time), &
      ' checks'
    if (this%verbose .and. err%ok()) call report_quality(this%red)
  end subroutine run_reduced

  !> The reduction's own error measures after the run, so that the trade of accuracy for
  !> speed shows without opening the result (the same as /reduction's attributes).
  subroutine report_quality(red)
    type(reduced_t), intent(in) :: red
    character(len=:), allocatable :: line
    ! The residual's units mix force and mass: shown only where no estimate in m exists.
    if (red%has_estimate) then
      line = 'reduction: error estimate up to ' // approx_str(red%estimate_max()) // ' m'
    else
      line = 'reduction: residual up to ' // approx_str(red%residual_max()) // &
        ' (no error estimate without a definite stiffness)'
    end if
    if (red%expanded) line = line // ' (measured at ' // int_str(red%measured%n) // &
      ' states: estimate_samples sets more)'
    if (red%expanded) line = line // '; ' // int_str(red%expansions%n_expansions) // &
      trim(merge(' expansion ', ' expansions', red%expansions%n_expansions == 1)) // ' (' // &
      int_str(red%expansions%n_exact_turns) // ' with exact turns), ' // 'up to ' // &
      approx_str(red%expansions%manifold_error) // ' m from the exact coordinates'
    if (red%expanded .and. red%expansions%n_unchecked > 0) line = line // ' (' // &
      int_str(red%expansions%n_unchecked) // ' states not compared: the exact model ' // &
      'could not be evaluated there)'
    write(*, '(a)') line
    if (.not. (red%expanded .and. red%has_estimate)) return
    ! The expansions' own error then outweighs what the modes leave out.
    if (red%expansions%manifold_error > red%estimate_max()) write(*, '(a)') 'reduction: ' // &
      'the expansions are farther from the exact coordinates than the error estimate; a ' // &
      'smaller expansion_tol (now ' // approx_str(red%expansions%tol) // ') makes more of ' // &
      'them, closer'
  end subroutine report_quality

  !> What evaluation = 'expanded' cannot take, as input errors before the basis is made.
  subroutine check_expanded(this, err)
    type(run_t), intent(in) :: this
    type(error_t), intent(inout) :: err
    character(len=:), allocatable :: why
    character(len=*), parameter :: g = "group &reduction: evaluation = 'expanded' "
    why = expansion_unsupported(this%dyn%model)
    if (this%dyn%controls_on) then
      call err%set(ERR_INPUT, g // 'does not take &controller groups (their sensors read ' // &
        "the full model); use evaluation = 'full'")
    else if (this%scene%reduction%static_correction) then
      call err%set(ERR_INPUT, g // 'has no static_correction (it needs a model pass at ' // &
        "every output); use evaluation = 'full'")
    else if (len(why) > 0) then
      call err%set(ERR_INPUT, g // 'does not represent ' // why // &
        "; use evaluation = 'full'")
    end if
  end subroutine check_expanded

  !> The rigid-body model for the controllers' feedforward, when one asks for it.
  subroutine add_feedforward(this, err)
    type(run_t), intent(inout) :: this
    type(error_t), intent(inout) :: err
    type(model_t) :: rigid
    integer, allocatable :: ff_q(:)
    if (.not. any(this%dyn%model%controllers%feedforward)) return
    call build_rigid_model(this%scene, this%dyn%model, rigid, ff_q, err)
    if (err%ok()) call this%control%set_feedforward(rigid, ff_q, err)
    if (.not. err%ok()) call err%prefix('group &controller: ')
  end subroutine add_feedforward

  !> A run that failed numerically where its last kinematic solution is near a singular
  !> configuration says so (the integrators' own messages, e.g. CVODE's error test failures
  !> at a dead point, do not), unless a failed solve there has said it already.
  subroutine add_configuration_hint(dyn, err)
    type(dynamics_t), intent(inout) :: dyn
    type(error_t), intent(inout) :: err
    if (err%code /= ERR_NUMERIC .or. index(err%message, 'singular') > 0) return
    err%message = err%message // dyn%kin%configuration_hint(dyn%model)
  end subroutine add_configuration_hint

  !> The sampling times of the sampled controllers within (t0, t_end], t0 + i T: breakpoints
  !> where the integrator restarts with the new held outputs.
  function sample_times(model, t0, t_end) result(times)
    type(model_t), intent(in) :: model
    real(wp), intent(in) :: t0, t_end
    real(wp), allocatable :: times(:)
    integer :: k, i, n
    allocate(times(0))
    do k = 1, size(model%controllers)
      associate (c => model%controllers(k))
        if (.not. c%sampled()) cycle
        n = floor((t_end - t0) / c%period)
        times = [times, [(t0 + i * c%period, i = 1, n)]]
      end associate
    end do
  end function sample_times

end submodule analysis_run_dynamic
