!> Equations of motion of a model (docs/theory.md section 5) as an `ode2_system_t`:
!>   Mbar a = DF_dy^T [f - M (D2F qd qd + DF_rh qdd_rh) - h] - sigma_dy
!> sigma_dy are the stress resultants of the dynamic modes, sigma = S e + beta S e_dot, with the
!> mode values taken from q itself (DF_e restricted to the dynamic columns is the identity on
!> dynamic modes and zero elsewhere, so DF_e^T sigma reduces to sigma_dy).
!> Elements with an elastic (calculable, stressed) mode instead have e = D(x) evaluated and
!> their stresses applied as nodal forces -D_x^T sigma, which DF_dy^T projects to
!> DF_e,dy^T sigma over all their stressed modes (docs/theory.md section 5.3).
module dynamics_system
  use core_kinds, only: wp, i8
  use core_error, only: error_t, ERR_MODEL, ERR_NUMERIC, ERR_INPUT
  use core_linalg, only: chol_factor, chol_solve
  use model_system, only: model_t, COORD_X, COORD_Y, COORD_Z, COORD_PHI, COORD_EULER
  use model_control, only: controller_sizes
  use elements_rotation, only: euler_e
  use model_kinematics, only: kinematics_t
  use dynamics_augmented, only: augmented_t, element_mass_t
  use elements_base, only: MODE_DYNAMIC, mode_has_stress
  use integrators_system, only: ode2_system_t, system_fd_jacobian, JACOBIAN_LINEARISED
  implicit none
  private
  public :: dynamics_t, check_finite

  !> Above this many nodal coordinates `auto` takes the sparse path (see dyn_init): measured on
  !> the two-link benchmark, it is faster from 2 beam elements per link (17 coordinates) on.
  integer, parameter :: SPARSE_ABOVE = 12

  type, extends(ode2_system_t) :: dynamics_t
    type(model_t) :: model
    type(kinematics_t) :: kin
    real(wp) :: load_factor = 1.0_wp          !< scales nodal loads and gravity (static steps)
    logical :: locked = .false.               !< prescribed modes held still (statics, modes)
    !> When allocated, the prescribed coordinates take these values instead of their motions
    !> (a configuration named in the input, e.g. for a reduced basis); rates are then zero.
    real(wp), allocatable :: held_rh(:)
    !> Sparse path: kinematics and accelerations by KLU (O(n) per evaluation), no dense Mbar.
    logical :: sparse = .false.
    type(augmented_t) :: aug
    type(element_mass_t) :: mass              !< element mass matrices of the last evaluation
    real(wp), allocatable :: mbar(:, :)       !< reduced mass matrix of the last assembly
    real(wp), allocatable :: gen_force(:)     !< right-hand side of the last assembly
    !> Nodal forces of the last evaluation before projection (n_x): loads, weight, inertia
    !> terms and the stresses of elastic elements; reactions are computed from it. After a
    !> Newton correction (prepare with qdd_dy) it also holds -M DF_dy qdd_dy.
    real(wp), allocatable :: nodal_force(:)
    !> Full q, qd, x_dot and sigma_dy of the last evaluation.
    real(wp), allocatable :: q_now(:), qd_now(:), xd_now(:), sigma_now(:)
    !> Statics (displacement control): the prescribed coordinates take load_factor times their
    !> values, so that they are stepped together with the loads.
    logical :: ramp_prescribed = .false.
    !> Constant loads: nodal forces plus gravity on the lumped masses (consistent masses get
    !> their weight from the elements, as it depends on the configuration).
    real(wp), allocatable :: load(:)
    !> Jacobian for implicit integrators (integrators_system's JACOBIAN_*): JACOBIAN_LINEARISED
    !> (-Mbar^-1 K0, -Mbar^-1 D0 at the current state: the stiff structural part, exact enough
    !> for Newton) or JACOBIAN_FD (forward differences).
    integer :: jacobian_kind = JACOBIAN_LINEARISED
    integer(i8) :: n_evals = 0                !< evaluations of the equations of motion
    ! History at the output times (filled by record):
    real(wp), allocatable :: x_hist(:, :), q_hist(:, :), v_hist(:, :), energy_hist(:, :)
    !> The elements' charts (dynamics_system_chart) at the output times: q_hist's meaning.
    real(wp), allocatable :: chart_hist(:, :)
    type(error_t) :: last_error               !< why the last callback returned non-zero
    !> Feedback controllers (model%controllers) act only where a run switches them on (dynamic
    !> runs); statics, modal analysis and &linear see the open-loop plant.
    logical :: controls_on = .false.
    !> Controller states, set by the run (dynamics_control) before each evaluation, over all
    !> controllers (model_control's offsets): their states (a PID's integral of its error, a
    !> user law's own) and the held outputs of sampled ones, per actuator.
    real(wp), allocatable :: ctrl_x(:), ctrl_held(:)
    !> Of the last evaluation, per controller: a PID's error r - y, its rate and the unlimited
    !> output of its law; per actuator the applied output (limited, or held); per measured
    !> output y and y'; per state a continuous user law's dx/dt.
    !> Per actuator (u_offset): the feedforward at the time of the evaluation (0: none), and
    !> an extra output that probes how the accelerations depend on the actuator (Jacobians).
    real(wp), allocatable :: ctrl_ff(:), ctrl_probe(:)
    real(wp), allocatable :: ctrl_error(:), ctrl_error_rate(:), ctrl_law(:), ctrl_u(:)
    real(wp), allocatable :: ctrl_y(:), ctrl_y_dot(:), ctrl_x_rate(:)
    !> The terms of sigma_dy = S (e + beta e_dot) over the elements without elastic modes,
    !> indexed once (dyn_init): element iel's from st_first(iel) to st_first(iel + 1) - 1,
    !> each sigma_dy(st_row) += S(st_i, st_j) (q + beta qd)(st_col). S itself is asked of the
    !> element in every evaluation: a caller may change an element's stiffness after init.
    integer, allocatable :: st_first(:), st_row(:), st_col(:), st_i(:), st_j(:)
  contains
    procedure :: init => dyn_init
    procedure :: prescribed => dyn_prescribed
    procedure :: full_q => dyn_full_q
    procedure :: prepare => dyn_prepare
    procedure :: assemble => dyn_assemble
    procedure :: generalised_force => dyn_generalised_force
    procedure :: evaluate => dyn_evaluate
    procedure :: evaluate_dense => dyn_evaluate_dense
    procedure :: accel => dyn_accel
    procedure :: report => dyn_report
    procedure :: record => dyn_record
    procedure :: store => dyn_store
    procedure :: jacobian => dyn_jacobian
    procedure :: has_iteration_solver => dyn_has_iteration_solver
    procedure :: iteration_factor => dyn_iteration_factor
    procedure :: newton_correction => dyn_newton_correction
    procedure :: error_norm => dyn_error_norm
    procedure :: energy => dyn_energy
    procedure :: energy_at => dyn_energy_at
    procedure :: stresses => dyn_stresses
    procedure :: loads_at => dyn_loads_at
    procedure :: mode_stiffness => dyn_mode_stiffness
    procedure :: structural_stiffness => dyn_structural_stiffness
    procedure :: structural_action => dyn_structural_action
    procedure :: elastic_forces => dyn_elastic_forces
    procedure :: allocate_history => dyn_allocate_history
    procedure :: apply_controllers => dyn_apply_controllers
    procedure :: user_law => dyn_user_law
    procedure :: rechart => dyn_rechart
    procedure :: charts => dyn_charts
    procedure :: use_charts => dyn_use_charts
  end type dynamics_t

  interface
    !> The controllers' outputs at time t from the state of the evaluation under way (q_now,
    !> qd_now, xd_now, kin%x): applied as nodal forces (nodal_force) or on their dynamic
    !> modes (sigma_now), with their errors kept in ctrl_*. dynamics_system_control.
    module subroutine dyn_apply_controllers(this, t, err)
      class(dynamics_t), intent(inout) :: this
      real(wp), intent(in) :: t
      type(error_t), intent(inout) :: err
    end subroutine dyn_apply_controllers
    !> Controller k's user law at time t on the measured ctrl_y, ctrl_y_dot and the states
    !> ctrl_x: its output u (unlimited) and x_out (dx/dt, or the states after a sample). A
    !> failure or a non-finite result is an error naming the controller: recoverable
    !> (ERR_NUMERIC) unless the law says it is fatal (ERR_INPUT).
    module subroutine dyn_user_law(this, k, t, x_out, u, err)
      class(dynamics_t), intent(in) :: this
      integer, intent(in) :: k
      real(wp), intent(in) :: t
      real(wp), intent(out) :: x_out(:), u(:)
      type(error_t), intent(inout) :: err
    end subroutine dyn_user_law
    !> -Mbar^-1 [K0, D0]: by Cholesky of Mbar (dense path) or by solves with the factors of
    !> the augmented system (sparse path, O(n) per column).
    module subroutine dyn_jacobian(this, t, q, v, dadq, dadv, status)
      class(dynamics_t), intent(inout) :: this
      real(wp), intent(in) :: t, q(:), v(:)
      real(wp), intent(out) :: dadq(:, :), dadv(:, :)
      integer, intent(out) :: status
    end subroutine dyn_jacobian
    !> The sparse path solves the Newton systems of implicit integrators itself, in O(n)
    !> (docs/theory.md 5.2), instead of handing them a dense n_dy x n_dy Jacobian.
    module logical function dyn_has_iteration_solver(this)
      class(dynamics_t), intent(in) :: this
    end function dyn_has_iteration_solver
    !> Factor I - c_q da/dq - c_v da/dv = Mbar^-1 (Mbar + c_q K0 + c_v D0) (linearised Jacobian)
    !> at the state of the last evaluation (its element masses and the kinematics' element
    !> Jacobians), whether an accel or a newton_correction made it.
    module subroutine dyn_iteration_factor(this, c_q, c_v, status)
      class(dynamics_t), intent(inout) :: this
      real(wp), intent(in) :: c_q, c_v
      integer, intent(out) :: status
    end subroutine dyn_iteration_factor
    !> One Newton correction dx = (Mbar_s + c_q K0_s + c_v D0_s)^-1 r with the factors of the
    !> last iteration_factor (state s) and the residual of eq. (1) at the current state,
    !>   r = DF_dy^T (f - M DF_dy x) - sigma_dy,
    !> by two solves with the kinematic factors: no factorisation of the augmented mass system
    !> per iteration (the default, accelerations then a solve, needs one). r is projected with
    !> the current DF (its zero is eq. 1); the stale factors only change how fast it converges.
    module subroutine dyn_newton_correction(this, t, q, v, x, dx, status)
      class(dynamics_t), intent(inout) :: this
      real(wp), intent(in) :: t, q(:), v(:), x(:)
      real(wp), intent(out) :: dx(:)
      integer, intent(out) :: status
    end subroutine dyn_newton_correction
    !> The local error of the nodal coordinates, dx = DF_dy dq at the last kinematic solution,
    !> in the largest-entry norm with weights atol + rtol s, s the largest motion of a
    !> translation (or rotation) that the dynamic coordinates make, DF_dy q at the step's start
    !> or end: an error bound on where the nodes are, the same on every mesh. (A norm on q
    !> itself depends on the mesh: bending modes are l0 times angles, and an RMS over many of
    !> them dilutes the error of the few that move the tip.)
    module subroutine dyn_error_norm(this, dq, q_old, q_new, rtol, atol, norm)
      class(dynamics_t), intent(inout) :: this
      real(wp), intent(in) :: dq(:), q_old(:), q_new(:), rtol, atol
      real(wp), intent(out) :: norm
    end subroutine dyn_error_norm
  end interface

  interface
    !> Stresses of the elements with elastic modes, from e = D(x) and e_dot = D_x x_dot at the
    !> last kinematic solution, subtracted from the nodal forces f as -D_x^T sigma.
    module subroutine dyn_elastic_forces(this, xd, f)
      class(dynamics_t), intent(in) :: this
      real(wp), intent(in) :: xd(:)
      real(wp), intent(inout) :: f(:)
    end subroutine dyn_elastic_forces
    !> Structural stiffness and damping on the dynamic coordinates, K0 and D0, at the last
    !> evaluation: the constant part of the dynamic modes plus DF_e^T S DF_e (and its damping)
    !> of the elastic elements (the K0 part; their geometric part sigma D2F is left to the
    !> difference tangent of statics). Assembled here, for the Jacobians that ask for it, not
    !> in every evaluation.
    module subroutine dyn_structural_stiffness(this, k0, d0)
      class(dynamics_t), intent(inout) :: this
      real(wp), intent(out) :: k0(:, :), d0(:, :)
    end subroutine dyn_structural_stiffness
    !> K0 v and D0 v for a few vectors v (n_dy, k) whose nodal shapes w = DF_dy v are given
    !> (n_x, k), without forming K0: the dynamic modes element by element, the elastic elements
    !> as nodal forces D_x^T S D_x w projected by DF_dy^T (k transposed solves). O(n k).
    module subroutine dyn_structural_action(this, v, w, kv, dv)
      class(dynamics_t), intent(inout) :: this
      real(wp), intent(in) :: v(:, :), w(:, :)
      real(wp), intent(out) :: kv(:, :), dv(:, :)
    end subroutine dyn_structural_action
  end interface

  interface
    !> Move the charts of limited elements near their limit to the state (t, q, v), changing
    !> q and v to the same state's coordinates in the new charts (ode2_system_t%rechart).
    module subroutine dyn_rechart(this, t, q, v, changed, status)
      class(dynamics_t), intent(inout) :: this
      real(wp), intent(in) :: t
      real(wp), intent(inout) :: q(:), v(:)
      logical, intent(out) :: changed
      integer, intent(out) :: status
    end subroutine dyn_rechart
    !> The limited elements' charts, one after the other (empty without any).
    module function dyn_charts(this) result(c)
      class(dynamics_t), intent(in) :: this
      real(wp), allocatable :: c(:)
    end function dyn_charts
    !> Restore charts given by `charts` (e.g. chart_hist(:, k), to read q_hist(:, k)).
    module subroutine dyn_use_charts(this, c)
      class(dynamics_t), intent(inout) :: this
      real(wp), intent(in) :: c(:)
    end subroutine dyn_use_charts
  end interface

  interface
    module subroutine dyn_allocate_history(this, nt)
      class(dynamics_t), intent(inout) :: this
      integer, intent(in) :: nt
    end subroutine dyn_allocate_history
    module subroutine dyn_record(this, k, t, q, v, status)
      class(dynamics_t), intent(inout) :: this
      integer, intent(in) :: k
      real(wp), intent(in) :: t, q(:), v(:)
      integer, intent(out) :: status
    end subroutine dyn_record
    !> Output k from the last kinematic solution, which must belong to (t, q).
    module subroutine dyn_store(this, k, t, q, v, x, energy)
      class(dynamics_t), intent(inout) :: this
      integer, intent(in) :: k
      real(wp), intent(in) :: t, q(:), v(:)
      !> The nodal coordinates and energies when the caller has them (a reduced model's
      !> expansion); otherwise the last kinematic solution's and dyn_energy's.
      real(wp), intent(in), optional :: x(:), energy(2)
    end subroutine dyn_store
    !> Kinetic and potential energy (elastic, loads and gravity) at the last kinematic solution,
    !> which must belong to (t, q_dy).
    module function dyn_energy(this, t, q_dy, v_dy) result(en)
      class(dynamics_t), intent(inout) :: this
      real(wp), intent(in) :: t, q_dy(:), v_dy(:)
      real(wp) :: en(2)
    end function dyn_energy
    !> Kinetic and potential energy at (t, q_dy) with nodal positions x and velocities xd.
    module function dyn_energy_at(this, t, q_dy, x, xd) result(en)
      class(dynamics_t), intent(inout) :: this
      real(wp), intent(in) :: t, q_dy(:), x(:), xd(:)
      real(wp) :: en(2)
    end function dyn_energy_at
  end interface

  interface
    !> Kinematics and nodal forces at a state: solves x, x_dot = DF qd, the convective part
    !> conv = D2F qd qd + DF_rh qdd_rh of the accelerations, the element mass matrices and
    !> nodal_force = f - M conv - h (+ weight, - elastic stresses); q_now, qd_now, xd_now and
    !> sigma_now. Everything by solves with the factors of J_c: no dense DF. With qdd_dy (the
    !> Newton correction's iterate), conv also holds DF_dy qdd_dy, so that nodal_force is the
    !> residual force f - M (conv + DF_dy qdd_dy) - h: the term comes with the convective
    !> one's solve and the element masses' pass, where a separate DF_dy qdd_dy and M product
    !> cost a right-hand side and a pass over the element blocks.
    module subroutine dyn_prepare(this, t, q_dy, v_dy, err, qdd_dy)
      class(dynamics_t), intent(inout) :: this
      real(wp), intent(in) :: t, q_dy(:), v_dy(:)
      type(error_t), intent(out) :: err
      real(wp), intent(in), optional :: qdd_dy(:)
    end subroutine dyn_prepare
    !> The generalised force g = DF_dy^T f - sigma_dy at a state (the right-hand side of eq. (1),
    !> also left in gen_force) by one transposed solve: O(n) on the sparse path, no Mbar. Statics
    !> differences it for the tangent stiffness.
    module subroutine dyn_generalised_force(this, t, q_dy, v_dy, g, err)
      class(dynamics_t), intent(inout) :: this
      real(wp), intent(in) :: t, q_dy(:), v_dy(:)
      real(wp), intent(out) :: g(:)
      type(error_t), intent(out) :: err
    end subroutine dyn_generalised_force
    !> Mass matrix mbar and generalised force gen_force (the right-hand side) at a state:
    !>   mbar a = gen_force, with the dense DF (O(n^2) memory, O(n^3) work: for statics, modal
    !> analysis and small models).
    module subroutine dyn_assemble(this, t, q_dy, v_dy, err)
      class(dynamics_t), intent(inout) :: this
      real(wp), intent(in) :: t, q_dy(:), v_dy(:)
      type(error_t), intent(out) :: err
    end subroutine dyn_assemble
  end interface

  interface
    !> The terms of sigma_dy = S (e + beta e_dot) over q (dyn_stresses), element by element
    !> in the order of S's rows and columns (elements with elastic modes excluded).
    !> dynamics_system_stresses.
    module subroutine stress_entries(this)
      class(dynamics_t), intent(inout) :: this
    end subroutine stress_entries
    !> Stress resultants of the dynamic modes, sigma_dy = S (e + beta e_dot), in q_dy order,
    !> for full q = (q_rh, q_dy) (elements with elastic modes excluded: their stresses act as
    !> nodal forces).
    module function dyn_stresses(this, q, qd) result(sigma)
      class(dynamics_t), intent(in) :: this
      real(wp), intent(in) :: q(:), qd(:)
      real(wp) :: sigma(this%model%n_dy)
    end function dyn_stresses
    !> The constant part of K0 and D0: dsigma_dy/dq_dy and dsigma_dy/dv_dy of the dynamic
    !> modes (block diagonal by element).
    module subroutine dyn_mode_stiffness(this, k0, d0)
      class(dynamics_t), intent(in) :: this
      real(wp), intent(out) :: k0(:, :), d0(:, :)
    end subroutine dyn_mode_stiffness
  end interface

contains

  !> Take ownership of a finalised model and solve the kinematics in its initial state, which
  !> also checks that the coordinate classes determine every calculable coordinate.
  !> linear_solver: 'dense' (LAPACK on J_c and Mbar), 'sparse' (KLU on J_c and the augmented
  !> system) or 'auto' (the default: sparse above SPARSE_ABOVE nodal coordinates).
  subroutine dyn_init(this, model, t0, q_dy0, err, linear_solver)
    class(dynamics_t), intent(inout) :: this
    type(model_t), intent(in) :: model
    real(wp), intent(in) :: t0, q_dy0(:)
    type(error_t), intent(out) :: err
    character(len=*), intent(in), optional :: linear_solver
    real(wp) :: a(model%n_dy)
    integer :: i, n_u, n_y, n_x
    this%model = model
    this%load = model%force
    where (model%coord_kind == COORD_X) this%load = this%load + model%lumped * model%gravity(1)
    where (model%coord_kind == COORD_Y) this%load = this%load + model%lumped * model%gravity(2)
    where (model%coord_kind == COORD_Z) this%load = this%load + model%lumped * model%gravity(3)
    this%sparse = model%n_x > SPARSE_ABOVE
    if (present(linear_solver)) then
      if (linear_solver == 'dense') this%sparse = .false.
      if (linear_solver == 'sparse') this%sparse = .true.
    end if
    call this%kin%init(this%model, this%sparse)
    if (this%sparse) call this%aug%init(this%model, this%kin%de_offset, size(this%kin%de_val))
    call this%mass%init(this%model)
    if (allocated(this%gen_force)) deallocate(this%gen_force)
    if (allocated(this%mbar)) deallocate(this%mbar)
    this%n_evals = 0
    allocate(this%gen_force(model%n_dy))
    call controller_sizes(model%controllers, n_u, n_y, n_x)
    this%ctrl_error = [(0.0_wp, i = 1, size(model%controllers))]
    this%ctrl_error_rate = this%ctrl_error
    this%ctrl_law = this%ctrl_error
    this%ctrl_x = [(0.0_wp, i = 1, n_x)]
    this%ctrl_x_rate = this%ctrl_x
    this%ctrl_held = [(0.0_wp, i = 1, n_u)]
    this%ctrl_u = this%ctrl_held
    this%ctrl_y = [(0.0_wp, i = 1, n_y)]
    this%ctrl_y_dot = this%ctrl_y
    this%ctrl_ff = this%ctrl_held
    this%ctrl_probe = this%ctrl_held
    call stress_entries(this)
    call this%evaluate(t0, q_dy0, 0.0_wp * q_dy0, a, err)
    if (.not. err%ok()) call err%prefix('initial configuration: ')
  end subroutine dyn_init

  !> Prescribed coordinates and their first two time derivatives at t.
  subroutine dyn_prescribed(this, t, p, pd, pdd)
    class(dynamics_t), intent(in) :: this
    real(wp), intent(in) :: t
    real(wp), intent(out) :: p(:), pd(:), pdd(:)
    integer :: i
    do i = 1, this%model%n_rh
      call this%model%motions(this%model%q_motion(i))%eval(t, p(i), pd(i), pdd(i))
    end do
    if (allocated(this%held_rh)) p = this%held_rh
    if (this%ramp_prescribed) p = this%load_factor * p
    if (this%locked .or. allocated(this%held_rh)) then
      pd = 0.0_wp
      pdd = 0.0_wp
    end if
  end subroutine dyn_prescribed

  !> Full q = (q_rh(t), q_dy).
  function dyn_full_q(this, t, q_dy) result(q)
    class(dynamics_t), intent(in) :: this
    real(wp), intent(in) :: t, q_dy(:)
    real(wp) :: q(this%model%n_q), pd(this%model%n_rh), pdd(this%model%n_rh)
    call this%prescribed(t, q(1:this%model%n_rh), pd, pdd)
    q(this%model%n_rh + 1:) = q_dy
  end function dyn_full_q

  !> Nodal loads and the weight of lumped masses at time t (load_factor not applied).
  pure function dyn_loads_at(this, t) result(f)
    class(dynamics_t), intent(in) :: this
    real(wp), intent(in) :: t
    real(wp) :: f(this%model%n_x)
    f = this%load
    if (size(this%model%load_motion) > 0) f = f + this%model%loads_at(t) - this%model%force
  end function dyn_loads_at

  !> Accelerations of the dynamic coordinates, by the sparse or the dense path.
  subroutine dyn_evaluate(this, t, q_dy, v_dy, a, err)
    class(dynamics_t), intent(inout) :: this
    real(wp), intent(in) :: t, q_dy(:), v_dy(:)
    real(wp), intent(out) :: a(:)
    type(error_t), intent(out) :: err
    real(wp) :: f(this%model%n_x, 1), a2(size(a), 1)
    integer :: info
    if (.not. this%sparse) then
      call this%evaluate_dense(t, q_dy, v_dy, a, err)
      return
    end if
    call this%prepare(t, q_dy, v_dy, err)
    if (.not. err%ok()) return
    call this%aug%factor(this%model, this%kin%de_val, this%mass, info)
    if (info /= 0) then
      ! Singular means Mbar is singular (or nearly): the dense path names the coordinate
      ! without inertia, or, if Cholesky gets through, gives the accelerations after all.
      call this%evaluate_dense(t, q_dy, v_dy, a, err)
      return
    end if
    f(:, 1) = this%nodal_force
    f = f - this%aug%nodal_equivalent(this%model, reshape(this%sigma_now, [size(a), 1]))
    call this%aug%accelerations(this%model, f, a2)
    a = a2(:, 1)
    call check_finite(a, t, err)
  end subroutine dyn_evaluate

  !> Accelerations by the dense path, which also leaves mbar and gen_force for the analyses
  !> that need them (statics, modal analysis, buckling).
  subroutine dyn_evaluate_dense(this, t, q_dy, v_dy, a, err)
    class(dynamics_t), intent(inout) :: this
    real(wp), intent(in) :: t, q_dy(:), v_dy(:)
    real(wp), intent(out) :: a(:)
    type(error_t), intent(out) :: err
    real(wp) :: chol(this%model%n_dy, this%model%n_dy)
    integer :: info
    character(len=120) :: msg
    call this%assemble(t, q_dy, v_dy, err)
    if (.not. err%ok()) return
    a = this%gen_force
    chol = this%mbar
    call chol_factor(chol, info)
    if (info /= 0) then
      write(msg, '(a,i0,a)') 'the mass matrix is singular (dynamic coordinate ', info, ', '
      call err%set(ERR_MODEL, trim(msg) // ' ' // this%model%q_name(this%model%n_rh + info) &
        // ', has no inertia: add mass or rotary inertia, or make that mode rigid)')
      return
    end if
    call chol_solve(chol, a)
    call check_finite(a, t, err)
  end subroutine dyn_evaluate_dense

  !> Accelerations that overflowed or became NaN are an error, never an output.
  subroutine check_finite(a, t, err)
    real(wp), intent(in) :: a(:), t
    type(error_t), intent(inout) :: err
    character(len=120) :: msg
    if (any(a /= a) .or. any(abs(a) > huge(1.0_wp) / 4)) then
      write(msg, '(a,es12.5)') 'accelerations are not finite at t = ', t
      call err%set(ERR_NUMERIC, trim(msg))
    end if
  end subroutine check_finite

  subroutine dyn_accel(this, t, q, v, a, status)
    class(dynamics_t), intent(inout) :: this
    real(wp), intent(in) :: t, q(:), v(:)
    real(wp), intent(out) :: a(:)
    integer, intent(out) :: status
    type(error_t) :: err
    call this%evaluate(t, q, v, a, err)
    call this%report(err, status)
    if (status /= 0) a = 0.0_wp
  end subroutine dyn_accel

  !> The integrator callback status of an evaluation's outcome; the error is kept for the
  !> message. A kinematic solve that fails may succeed with a smaller step: recoverable;
  !> a model error (singular mass) is not, nor a control law's fatal status.
  subroutine dyn_report(this, err, status)
    class(dynamics_t), intent(inout) :: this
    type(error_t), intent(in) :: err
    integer, intent(out) :: status
    status = 0
    if (err%ok()) return
    status = 1
    ! ERR_INPUT: a user control law that declared itself failed for good.
    if (err%code == ERR_MODEL .or. err%code == ERR_INPUT) status = -1
    call this%last_error%clear()
    call this%last_error%set(err%code, err%message)
  end subroutine dyn_report


end module dynamics_system
