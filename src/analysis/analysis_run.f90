!> One flexmor run: read a scene file, build the model, run the analyses it asks for (static,
!> then modal, then dynamic, each optional) and write one HDF5 result file. The layout is
!> documented in docs/output.md. On any error nothing is left on disk.
module analysis_run
  use, intrinsic :: iso_fortran_env, only: output_unit
  use core_kinds, only: wp, i8
  use core_error, only: error_t, ERR_INPUT
  use core_version, only: FLEXMOR_VERSION
  use io_namelist, only: nml_file_t, string_t
  use io_scene, only: read_scene
  use model_scene, only: scene_t, dynamic_rec_t, label_t, auto_by_stiffness, &
    ERROR_CHECK_NONE, ERROR_CHECK_MODES, ERROR_CHECK_MESH, STATIC_ARC_LENGTH
  use io_hdf5, only: h5_writer_t
  use model_system, only: model_t, NODE_SLOTS
  use elements_base, only: MODE_DYNAMIC
  use model_build, only: build_model, unused_motions, build_rigid_model
  use dynamics_system, only: dynamics_t
  use dynamics_static, only: static_solve
  use dynamics_continuation, only: arc_length_solve
  use dynamics_response, only: static_response_t
  use reduction_modal, only: modal_result_t, modal_analysis
  use dynamics_buckling, only: buckling_result_t, buckling_analysis
  use dynamics_linear, only: linear_model_t
  use integrators_system, only: integrator_options_t, integrator_stats_t, INTEGRATOR_GALPHA
  use core_progress, only: progress_t
  use integrators_driver, only: integrate
  use core_strings, only: int_str, real_str, approx_str, hz_list
  use reduction_basis, only: basis_t, held_joints
  use reduction_system, only: reduced_t
  use reduction_expansion, only: expansion_unsupported
  use dynamics_control, only: controlled_t
  use model_control, only: control_law_t
  use reduction_adaptive, only: update_spec_t, update_log_t, integrate_reduced
  implicit none
  private
  public :: run_t

  !> integrator = 'auto' below rtol 1e-6 computes all modes of a full model up to this many
  !> dynamic coordinates (a dense eigenproblem, well under a second); larger ones are stiff.
  integer, parameter :: AUTO_MODAL_MAX = 400
  real(wp), parameter :: TWO_PI = 6.28318530717958647692_wp

  !> Everything one run computes, kept so that callers (the sweep) can take metrics from it.
  type :: run_t
    type(nml_file_t) :: file
    type(scene_t) :: scene
    type(dynamics_t) :: dyn
    type(modal_result_t) :: modal
    type(buckling_result_t) :: buckling
    type(linear_model_t), allocatable :: linear(:) !< the &linear state-space models
    real(wp), allocatable :: q_static(:), x_static(:, :)
    logical, allocatable :: static_stable(:)  !< per load step (dynamics_static: stable_tangent)
    real(wp), allocatable :: static_load_factor(:)  !< per load step
    !> Reactions of the output nodes and compliances of &output compliance_nodes, per step.
    type(static_response_t) :: static_response
    real(wp), allocatable :: time(:)
    type(integrator_stats_t) :: stats
    type(reduced_t), allocatable :: red       !< a reduced dynamic analysis
    !> The plant with its controllers (&controller) during a dynamic run, and their history.
    type(controlled_t) :: control
    type(basis_t) :: initial_basis            !< its basis at the start
    type(update_log_t) :: updates             !< its basis checks and updates
    !> Why integrator = 'auto' took the integrator it did, when the run chose ('' otherwise)
    character(len=:), allocatable :: integrator_choice
    integer :: static_iterations = 0
    real(wp) :: wall_time_s = 0.0_wp
    !> Processor time of the analyses [s]: beside the wall time, the measure that other jobs
    !> on a shared machine do not inflate (benchmarks compare it with other codes' process time).
    real(wp) :: cpu_time_s = 0.0_wp
    !> Summary lines on stdout, and progress lines on stderr during long analyses.
    logical :: verbose = .true.
    !> Warnings of the run (an unused motion, an unstable static equilibrium), one per element,
    !> without a program name: the flexmor program prints them once the run has succeeded (so
    !> a failure stays one line), a sweep's cases keep them to themselves.
    type(string_t), allocatable :: warnings(:)
    type(progress_t) :: progress
    !> Scene variables set over the file's text by the caller (a sweep case's parameters, as
    !> 'group.variable = value, ...'): the result file's root attribute input_overrides.
    character(len=:), allocatable :: input_overrides
    !> Progress lines without the summary lines (verbose = .false.), under their own name:
    !> the error check's second run reports as 'check'.
    logical :: progress_lines = .false.
    character(len=8) :: progress_kind = ''
    !> &dynamic error_check: the second run's settings in words, its steps and processor
    !> time [s], the largest distance [m] of the two runs' nodes and the largest angle [rad]
    !> between their orientations at each output time (check_rotation not allocated where no
    !> node has a rotation of its own), and the nodes of the largest of all.
    character(len=:), allocatable :: check_rerun, check_node, check_rotation_node
    integer :: check_steps = 0
    real(wp) :: check_cpu_s = 0.0_wp
    real(wp), allocatable :: check_distance(:), check_rotation(:)
  contains
    procedure :: load => run_load
    procedure :: load_text => run_load_text
    procedure :: load_parsed => run_load_parsed
    procedure :: execute => run_execute
    procedure :: write => run_write
    procedure :: set_control_law => run_set_control_law
  end type run_t

  interface
    !> Give the &controller `label` (law = 'user') its law, after load and before execute; the
    !> run keeps a copy (analysis_run_control).
    module subroutine run_set_control_law(this, label, law, err)
      class(run_t), intent(inout) :: this
      character(len=*), intent(in) :: label
      class(control_law_t), intent(in) :: law
      type(error_t), intent(out) :: err
    end subroutine run_set_control_law
    !> Every &controller with law = 'user' has its law (analysis_run_control).
    module subroutine check_control_laws(this, err)
      type(run_t), intent(in) :: this
      type(error_t), intent(inout) :: err
    end subroutine check_control_laws
    !> Write the result file (temporary name, renamed on success); layout in docs/output.md.
    module subroutine run_write(this, path, err)
      class(run_t), intent(inout) :: this
      character(len=*), intent(in) :: path
      type(error_t), intent(out) :: err
    end subroutine run_write
    !> &linear: the state-space model at the configuration of &modal (analysis_run_linear).
    module subroutine run_linear(this, err)
      type(run_t), intent(inout) :: this
      type(error_t), intent(out) :: err
    end subroutine run_linear
    !> The basis of &reduction at the configuration it names, for the reduced run and for
    !> &linear (analysis_run_linear).
    module subroutine reduction_basis(this, dyn, basis, err)
      type(run_t), intent(in) :: this
      type(dynamics_t), intent(inout) :: dyn
      type(basis_t), intent(out) :: basis
      type(error_t), intent(out) :: err
    end subroutine reduction_basis
    module subroutine write_linear(this, h5, err)
      type(run_t), intent(in) :: this
      type(h5_writer_t), intent(inout) :: h5
      type(error_t), intent(inout) :: err
    end subroutine write_linear
    !> &dynamic error_check: the second run and the distance of its nodes from the run's
    !> (analysis_run_check).
    module subroutine run_error_check(this, err)
      type(run_t), intent(inout) :: this
      type(error_t), intent(out) :: err
    end subroutine run_error_check
    !> Why error_check = 'mesh' cannot refine the scene's links ('' when it can;
    !> analysis_run_check).
    module function mesh_check_problem(scene) result(why)
      type(scene_t), intent(in) :: scene
      character(len=:), allocatable :: why
    end function mesh_check_problem
    !> &dynamic: the full or reduced model integrated (analysis_run_dynamic).
    !> Refuse, before the run, dynamic histories that would not fit in memory or fixed steps
    !> that would not end (analysis_run_limits; the limits are in docs/input.md).
    module subroutine check_history_size(d, model, err)
      type(dynamic_rec_t), intent(in) :: d
      type(model_t), intent(in) :: model
      type(error_t), intent(inout) :: err
    end subroutine check_history_size
    !> The &output nodes must exist in the model (analysis_run_limits).
    module subroutine check_output_nodes(scene, model, err)
      type(scene_t), intent(in) :: scene
      type(model_t), intent(in) :: model
      type(error_t), intent(inout) :: err
    end subroutine check_output_nodes
    !> Refuse load steps whose results would not fit in memory (analysis_run_limits).
    module subroutine check_static_size(scene, model, err)
      type(scene_t), intent(in) :: scene
      type(model_t), intent(in) :: model
      type(error_t), intent(inout) :: err
    end subroutine check_static_size
    module subroutine run_dynamic(this, err)
      type(run_t), intent(inout), target :: this
      type(error_t), intent(out) :: err
    end subroutine run_dynamic
    !> Reactions, compliances and frequencies at each converged static step
    !> (analysis_run_static).
    module subroutine static_responses(this, q_steps, ramped, err)
      type(run_t), intent(inout) :: this
      real(wp), intent(in) :: q_steps(:, :)
      logical, intent(in) :: ramped
      type(error_t), intent(out) :: err
    end subroutine static_responses
  end interface

contains

  !> Read the scene file and build the model.
  subroutine run_load(this, path, err)
    class(run_t), intent(inout) :: this
    character(len=*), intent(in) :: path
    type(error_t), intent(out) :: err
    type(nml_file_t) :: file
    call file%load(path, err)
    if (err%ok()) call this%load_parsed(file, err)
  end subroutine run_load

  !> Parse scene text (the contents of a scene file, docs/input.md) and build the model;
  !> `name` stands for the file name in messages and in the result file's input_file.
  subroutine run_load_text(this, text, name, err)
    class(run_t), intent(inout) :: this
    character(len=*), intent(in) :: text, name
    type(error_t), intent(out) :: err
    type(nml_file_t) :: file
    call file%parse(text, name, err)
    if (err%ok()) call this%load_parsed(file, err)
  end subroutine run_load_text

  !> Build the model of an already parsed (and possibly edited, e.g. by a sweep) scene file.
  subroutine run_load_parsed(this, file, err)
    class(run_t), intent(inout) :: this
    type(nml_file_t), intent(in) :: file
    type(error_t), intent(out) :: err
    type(model_t) :: model
    this%file = file
    call read_scene(this%file, this%scene, err)
    if (.not. err%ok()) return
    call build_model(this%scene, model, err)
    if (err%ok()) call warn_unused_motions(this)
    if (err%ok()) call check_output_nodes(this%scene, model, err)
    if (err%ok() .and. this%scene%dynamic%active) call check_history_size(this%scene%dynamic, &
      model, err)
    if (err%ok() .and. this%scene%static%active) call check_static_size(this%scene, model, err)
    if (err%ok() .and. this%scene%dynamic%error_check == ERROR_CHECK_MODES .and. .not. &
      this%scene%reduction%active) call err%set(ERR_INPUT, 'group &dynamic: variable ' // &
      '''error_check'': ''modes'' checks a reduced run (&reduction); ''tolerance'' checks ' // &
      'the time integration of any run')
    if (err%ok() .and. this%scene%dynamic%error_check == ERROR_CHECK_MESH) then
      if (len(mesh_check_problem(this%scene)) > 0) call err%set(ERR_INPUT, &
        mesh_check_problem(this%scene))
    end if
    if (err%ok()) then
      allocate(this%q_static(model%n_dy))
      this%q_static = 0.0_wp
      ! A static analysis by load steps starts from the reference with the prescribed inputs
      ! at zero and steps them (displacement control): the undeformed model need not fit
      ! their full values (a tip pushed 0.3 m on a 1 m cantilever has no configuration
      ! without bending), so the initial configuration is solved where the steps start.
      if (this%scene%static%active .and. this%scene%static%method /= STATIC_ARC_LENGTH) then
        this%dyn%ramp_prescribed = .true.
        this%dyn%load_factor = 0.0_wp
      end if
      call this%dyn%init(model, 0.0_wp, this%q_static, err, this%scene%linear_solver)
      this%dyn%ramp_prescribed = .false.
      this%dyn%load_factor = 1.0_wp
    end if
    if (.not. err%ok()) call err%prefix(this%file%path // ': ')
  end subroutine run_load_parsed

  subroutine add_warning(this, text)
    type(run_t), intent(inout) :: this
    character(len=*), intent(in) :: text
    if (.not. allocated(this%warnings)) allocate(this%warnings(0))
    this%warnings = [this%warnings, string_t(text)]
  end subroutine add_warning

  subroutine warn_unused_motions(this)
    type(run_t), intent(inout) :: this
    character(len=:), allocatable :: labels
    labels = unused_motions(this%scene)
    if (len(labels) > 0) call add_warning(this, this%file%path // ': no &hinge or ' // &
      '&controller uses the &motion ' // labels // ' (prescribe it with motion = ''...'')')
  end subroutine warn_unused_motions

  !> Run the analyses the scene asks for.
  !> Recursive: &dynamic error_check runs a second run_t from within (analysis_run_check).
  recursive subroutine run_execute(this, err)
    class(run_t), intent(inout), target :: this
    type(error_t), intent(out) :: err
    integer(i8) :: c0, c1, rate
    real(wp) :: cpu0, cpu1
    this%progress%enabled = this%verbose .or. this%progress_lines
    call system_clock(c0, rate)
    call cpu_time(cpu0)
    call check_control_laws(this, err)
    if (err%ok()) call run_analyses(this, err)
    if (.not. err%ok()) then
      call err%prefix(this%file%path // ': ')
      return
    end if
    call system_clock(c1)
    call cpu_time(cpu1)
    this%wall_time_s = real(c1 - c0, wp) / real(rate, wp)
    this%cpu_time_s = cpu1 - cpu0
  end subroutine run_execute

  recursive subroutine run_analyses(this, err)
    type(run_t), intent(inout), target :: this
    type(error_t), intent(out) :: err
    if (this%scene%static%active) then
      call run_static(this, err)
      if (.not. err%ok()) return
    end if
    ! Each summary line reaches a log before the next, long analysis: an interrupt ends the
    ! program without flushing buffers.
    flush(output_unit)
    ! The modes and the state-space model are those of the static equilibrium, under the
    ! loads it is in equilibrium with: an arc-length path may end at any load factor (it
    ! stops at max_load_factor or after n_steps), and the tangent under the full loads at
    ! that configuration would be of no equilibrium (a column at 0.36 of a load twice
    ! critical came out unstable).
    this%dyn%load_factor = static_end_load_factor(this)
    if (this%scene%modal%active) then
      ! The modes may be asked for at a time far along the motions (a shaft turned many
      ! radians): the kinematics gets there in steps if it must.
      this%dyn%kin%continuation = .true.
      call modal_analysis(this%dyn, this%scene%modal%time, this%q_static, &
        this%scene%modal%n_modes, this%modal, err, solver=this%scene%modal%solver, &
        along_motion=this%scene%modal%along_motion)
      this%dyn%kin%continuation = .false.
      if (.not. err%ok()) then
        ! The kinematics refuses a time too far along the motions: say which variable.
        if (index(err%message, 'kinematics: the coordinates jump') == 1) &
          call err%prefix('group &modal: variable ''time'': ')
        return
      end if
      if (this%verbose) write(*, '(a)') 'modal: frequencies [Hz]: ' // &
        hz_list(this%modal%frequency_hz(1:min(6, size(this%modal%frequency_hz))))
      flush(output_unit)
    end if
    if (this%scene%buckling%active) then
      call run_buckling(this, err)
      if (.not. err%ok()) return
      flush(output_unit)
    end if
    ! &linear at one configuration comes before the dynamic run, along it after.
    if (this%scene%linear%active .and. .not. allocated(this%scene%linear%times)) then
      call run_linear(this, err)
      if (.not. err%ok()) return
    end if
    this%dyn%load_factor = 1.0_wp
    if (this%scene%dynamic%active) then
      if (abs(static_end_load_factor(this) - 1) > 1.0e-3_wp) call add_warning(this, &
        'static: the ' // &
        'arc-length path ends at load factor ' // real_str(static_end_load_factor(this)) // &
        ', not 1: &dynamic starts from that equilibrium under the full loads')
      call run_dynamic(this, err)
      if (.not. err%ok()) return
      if (this%scene%dynamic%error_check /= ERROR_CHECK_NONE) then
        call run_error_check(this, err)
        if (.not. err%ok()) return
      end if
    end if
    if (this%scene%linear%active .and. allocated(this%scene%linear%times)) &
      call run_linear(this, err)
  end subroutine run_analyses

  subroutine run_static(this, err)
    type(run_t), intent(inout) :: this
    type(error_t), intent(out) :: err
    real(wp), allocatable :: q_steps(:, :)
    integer :: k, n, products
    logical :: arc
    products = 0
    associate (s => this%scene%static)
      arc = s%method == STATIC_ARC_LENGTH
      allocate(this%x_static(this%dyn%model%n_x, s%n_steps), this%static_stable(s%n_steps))
      allocate(q_steps(this%dyn%model%n_dy, s%n_steps), this%static_load_factor(s%n_steps))
      call this%progress%start('static', 0.0_wp, 1.0_wp)
      if (arc) then
        call arc_length_solve(this%dyn, 0.0_wp, s%n_steps, s%arc_length, s%max_load_factor, &
          s%tol, s%max_iter, this%q_static, this%static_load_factor, this%x_static, q_steps, &
          this%static_stable, n, this%static_iterations, err, this%progress, s%solver, &
          products)
        ! Fewer steps when max_load_factor was reached: keep those taken.
        this%x_static = this%x_static(:, 1:n)
        this%static_stable = this%static_stable(1:n)
        this%static_load_factor = this%static_load_factor(1:n)
        q_steps = q_steps(:, 1:n)
      else
        this%static_load_factor = [(real(k, wp) / s%n_steps, k = 1, s%n_steps)]
        call static_solve(this%dyn, 0.0_wp, s%n_steps, s%tol, s%max_iter, this%q_static, &
          this%x_static, this%static_iterations, err, this%static_stable, this%progress, &
          q_steps, s%solver, products)
      end if
    end associate
    ! Reactions and compliances are planar (x, y, phi) so far: a spatial scene has none.
    if (err%ok()) call static_responses(this, q_steps, .not. arc, &
      err)
    if (.not. err%ok()) return
    if (this%verbose) write(*, '(a,i0,a,a,i0,a,a)') 'static: ', size(this%static_load_factor), &
      trim(merge(' arc-length steps', ' load steps      ', arc)), ', ', this%static_iterations, &
      ' Newton iterations', trim(krylov_note(products))
    call warn_unstable(this)
  end subroutine run_static

  !> The load factor of the static equilibrium the later analyses start from: the last of an
  !> arc-length path, else 1 (load steps end at 1; no &static: the reference).
  pure real(wp) function static_end_load_factor(this) result(lambda)
    type(run_t), intent(in) :: this
    lambda = 1.0_wp
    if (.not. this%scene%static%active) return
    if (this%scene%static%method /= STATIC_ARC_LENGTH) return
    if (.not. allocated(this%static_load_factor)) return
    if (size(this%static_load_factor) > 0) &
      lambda = this%static_load_factor(size(this%static_load_factor))
  end function static_end_load_factor

  !> ' (Newton-Krylov: n products with the tangent)' when there were any, else ''.
  pure function krylov_note(products) result(note)
    integer, intent(in) :: products
    character(len=:), allocatable :: note
    note = ''
    if (products > 0) note = ' (Newton-Krylov: ' // int_str(products) // &
      ' products with the tangent)'
  end function krylov_note


  !> Linearised buckling at the same state as &modal (the &static equilibrium, else the
  !> reference), prescribed modes held at t = 0 as in &static. Loads that compress nothing
  !> give an empty result and a warning, not an error.
  subroutine run_buckling(this, err)
    type(run_t), intent(inout) :: this
    type(error_t), intent(out) :: err
    call buckling_analysis(this%dyn, 0.0_wp, this%q_static, this%scene%buckling%n_modes, &
      this%scene%buckling%load_factor, this%buckling, err, solver=this%scene%buckling%solver)
    if (.not. err%ok()) return
    if (size(this%buckling%load_factor) == 0 .and. this%buckling%n_complex > 0) then
      call add_warning(this, 'buckling: no real positive load multiplier: the moments ' // &
        'fixed in space make K_G unsymmetric, and its ' // int_str(this%buckling%n_complex) &
        // ' complex ones are no static critical loads (no divergence); /buckling is empty')
    else if (size(this%buckling%load_factor) == 0 .and. &
        size(this%dyn%model%load_motion) > 0) then
      call add_warning(this, 'buckling: no positive load multiplier: the loads compress ' // &
        'nothing (tension only? loads with a time_law count at their value at t = 0); ' // &
        '/buckling is empty')
    else if (size(this%buckling%load_factor) == 0) then
      call add_warning(this, 'buckling: no positive load multiplier: the loads compress ' // &
        'nothing (tension only?); /buckling is empty')
    else if (this%verbose) then
      write(*, '(a,*(g0.6,:,", "))') 'buckling: load multipliers: ', &
        this%buckling%load_factor(1:min(6, size(this%buckling%load_factor)))
    end if
  end subroutine run_buckling

  !> One line naming the first load step whose equilibrium is unstable, if any. Arc-length
  !> continuation is meant to pass limit points, so there it reports the branch it followed
  !> instead of suggesting a cure.
  subroutine warn_unstable(this)
    type(run_t), intent(inout) :: this
    integer :: k, n
    character(len=:), allocatable :: where
    if (all(this%static_stable)) return
    n = size(this%static_stable)
    k = findloc(this%static_stable, .false., dim=1)
    where = ' from load step ' // int_str(k) // ' of ' // int_str(n) // ' (load factor ' // &
      approx_str(this%static_load_factor(k)) // ')'
    if (this%scene%static%method == STATIC_ARC_LENGTH) then
      call add_warning(this, 'static: the path passes unstable equilibria' // where // &
        ': past a limit point or a bifurcation (/static/stable marks each step)')
    else
      call add_warning(this, 'static: equilibrium unstable' // where // ': the tangent ' // &
        'stiffness is not positive definite (buckled? past a limit point? try a perturbation)')
    end if
  end subroutine warn_unstable
end module analysis_run
