module model_kinematics
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_NUMERIC, ERR_MODEL
  use core_linalg, only: lu_factor, lu_solve
  use core_strings, only: approx_str
  use core_sparse, only: sparse_lu_t, entries_t
  use model_system, only: model_t, COORD_EULER
  implicit none
  private
  public :: kinematics_t, kin_state_t

  integer, parameter :: MAX_NEWTON = 25
  !> Pivots this much smaller than the largest mean a singular kinematic Jacobian.
  real(wp), parameter :: SINGULAR_PIVOT = 1.0e-12_wp
  !> Iterates of the kinematic Newton that have run away (kin_newton).
  real(wp), parameter :: X_DIVERGED = 1.0e50_wp, EULER_DIVERGED = 1.0e6_wp

  !> What a caller keeps to go on from a kinematic solution after evaluating elsewhere (a basis
  !> computation); the factors are not kept: the next solve makes new ones.
  type :: kin_state_t
    real(wp), allocatable :: x(:), q(:)
  end type kin_state_t

  !> The time derivatives of a solution along a trajectory at time t (note_rates): q's and x's
  !> velocities and accelerations, x_dd = D2F qd qd + DF qdd for the qdd given.
  type :: kin_rates_t
    logical :: valid = .false.
    real(wp) :: t = 0
    real(wp), allocatable :: qd(:), qdd(:), xd(:), xdd(:)
  end type kin_rates_t

  !> The Jacobian J_c is factorised dense (LAPACK) or sparse (KLU, `sparse`): its few entries per
  !> element make the sparse factors O(n), the dense ones O(n^3). Either way DF and D2F are
  !> applied through solves with the one factorisation (apply_df, apply_dft, second); the dense
  !> DF matrix is formed only on request (transfer), for the analyses that need all of it.
  type :: kinematics_t
    real(wp), allocatable :: x(:)        !< nodal coordinates at the last solution
    real(wp), allocatable :: q(:)        !< generalised coordinates of that solution
    logical :: sparse = .false.
    real(wp), allocatable :: lu(:, :)    !< dense LU factors of J_c at x
    integer, allocatable :: ipiv(:)
    type(sparse_lu_t) :: jac_sp          !< sparse J_c and its factors
    !> d(residual)/d(q) through the nodal coordinates that are inputs: entries (in_row, in_q)
    integer, allocatable :: in_row(:), in_q(:)
    real(wp), allocatable :: in_val(:)
    !> Sparse mode: the element Jacobians dD/dx of the last factorisation, flat (element iel
    !> from de_offset(iel), n_modes x n_dofs), for the sparse equations of motion to reuse.
    integer, allocatable :: de_offset(:)
    real(wp), allocatable :: de_val(:)
      !> The element loops' index lookups, flat and made once (kin_init): per element its mode
    !> and coordinate counts; per mode (model numbering) its kinematic row, the q index that
    !> row equals (0: none) and the period; per entry of J_c its position in de_val, row,
    !> column and sparse value slot, and per input entry (in_val's order) its position in
    !> de_val, so that kin_residual assembles after its element pass in flat loops.
    integer, allocatable :: el_nm(:), el_nd(:)
    integer, allocatable :: mode_row(:), mode_q(:)
    real(wp), allocatable :: mode_period(:)
    integer, allocatable :: jac_src(:), jac_row(:), jac_col(:), jac_slot(:), in_src(:)
    !> The residual from the mode values e_val(0:n_modes) of the element pass (e_val(0) = 0):
    !> row i is e_val(row_mode(i)) (0 if no mode has row i), less q on the rows q_rows.
    real(wp), allocatable :: e_val(:)
    integer, allocatable :: row_mode(:), q_rows(:)
    !> Sparse: the entries split into each slot's first one in element order (jac_set_*:
    !> assigned) and the others (jac_add_*: added, in element order), so that the assembly
    !> needs no zeroing pass over the values and sums in the same order as before.
    integer, allocatable :: jac_set_src(:), jac_set_slot(:), jac_add_src(:), jac_add_slot(:)
    real(wp), allocatable :: df(:, :)    !< DF_x (n_x, n_q) from transfer (allocated there)
    logical :: has_df = .false.          !< df belongs to x
    logical :: has_factors = .false.     !< the factors belong to x (up to the last correction)
    !> On a failed Newton solve, retry in steps from the last solution (kin_solve). Off where a
    !> failure must reach the caller: arc-length and the integrators cut their own steps, and
    !> continuation could land on another branch of a snapping structure.
    logical :: continuation = .false.
    !> Where a failed solve leaves x: the last solution (the default: an integrator that tried
    !> a wild step then retries a shorter one from where the model was), or, when set, the
    !> failed attempt's predicted guess, which lets arc-length continuation cross a fold of the
    !> kinematics (a von Mises truss passing flat).
    logical :: keep_failed_guess = .false.
    integer :: n_solves = 0, n_iterations = 0
    !> An estimate of ||J_c^-1|| at the first solution (-1 before it). Where it grows by orders
    !> of magnitude along a motion, the mechanism nears a singular configuration (links
    !> aligned at a dead point), which the messages of failed solves then name; a singular J_c
    !> at the first solution is a model error (mode classes, supports). (Pivot ratios of the
    !> factors do not serve: on the spatial two-link they fall from 0.36 at the reference to
    !> 8e-7 at the first step, far from any singularity.)
    real(wp) :: inv_norm_first = -1.0_wp
    !> The rates of the last solution, when its caller noted them: the next solve at a later
    !> time then predicts by their Taylor series (model_kinematics_rates).
    type(kin_rates_t) :: rates
    !> e_val holds the mode values at x: the last solve ended on its residual pass (no
    !> correction after it, as with elastic modes), so an element pass at x may take them.
    logical :: modes_at_x = .false.
  contains
    procedure :: init => kin_init
    procedure :: solve => kin_solve
    procedure :: transfer => kin_transfer
    procedure :: apply_df => kin_apply_df
    procedure :: apply_df_many => kin_apply_df_many
    procedure :: apply_dft => kin_apply_dft
    procedure :: second => kin_second
    procedure :: second_solve => kin_second_solve
    procedure :: residual => kin_residual
    procedure :: jacobian_solve => kin_jacobian_solve
    procedure :: note_rates => kin_note_rates
    procedure :: predict => kin_predict
    procedure :: restart_from => kin_restart_from
    procedure :: save_state => kin_save_state
    procedure :: restore_state => kin_restore_state
    procedure, private :: free_modes_moved => kin_free_modes_moved
    procedure, private :: singular_message => kin_singular_message
    !> ' (...)' when the last solution is near a singular configuration, else ''
    !> (model_kinematics_diagnostics).
    procedure :: configuration_hint => kin_configuration_hint
    procedure, private :: inverse_norm => kin_inverse_norm
    !> Type-bound so that the submodules link to it: gfortran 12 emits no symbol for a
    !> private module procedure it has inlined.
    procedure, private :: factor => factor_jacobian
  end type kinematics_t

  interface
    !> Size the arrays for a model and record the entry patterns of J_c (sparse only) and of
    !> the input-coordinate columns, in the order in which kin_residual visits them
    !> (model_kinematics_residual).
    module subroutine kin_init(this, model, sparse)
      class(kinematics_t), intent(inout) :: this
      type(model_t), intent(in) :: model
      logical, intent(in), optional :: sparse
    end subroutine kin_init
    !> Note the time derivatives of the last solution, reached at time t along a trajectory:
    !> velocities qd, xd = DF qd and accelerations qdd, xdd = D2F qd qd + DF qdd.
    module subroutine kin_note_rates(this, t, qd, qdd, xd, xdd)
      class(kinematics_t), intent(inout) :: this
      real(wp), intent(in) :: t, qd(:), qdd(:), xd(:), xdd(:)
    end subroutine kin_note_rates
    !> x := the predicted solution at q (time t if known) from the last one, whose factors
    !> are at hand; the noted rates are used up unless t is theirs.
    module subroutine kin_predict(this, model, q, t)
      class(kinematics_t), intent(inout) :: this
      type(model_t), intent(in) :: model
      real(wp), intent(in) :: q(:)
      real(wp), intent(in), optional :: t
    end subroutine kin_predict
    !> dx = DF_x dq (n_x) at the last solution, by one solve.
    module subroutine kin_apply_df(this, model, dq, dx)
      class(kinematics_t), intent(inout) :: this
      type(model_t), intent(in) :: model
      real(wp), intent(in) :: dq(:)
      real(wp), intent(out) :: dx(:)
    end subroutine kin_apply_df
    !> dx = DF_x dq for several columns (n_q, k) -> (n_x, k), by one solve with k right-hand
    !> sides (KLU takes them together, cheaper than k solves).
    module subroutine kin_apply_df_many(this, model, dq, dx)
      class(kinematics_t), intent(inout) :: this
      type(model_t), intent(in) :: model
      real(wp), intent(in) :: dq(:, :)
      real(wp), intent(out) :: dx(:, :)
    end subroutine kin_apply_df_many
    !> g_q = DF_x^T g (n_q) for nodal forces g (n_x), by one transposed solve.
    module subroutine kin_apply_dft(this, model, g, g_q)
      class(kinematics_t), intent(inout) :: this
      type(model_t), intent(in) :: model
      real(wp), intent(in) :: g(:)
      real(wp), intent(out) :: g_q(:)
    end subroutine kin_apply_dft
    !> First-order transfer function DF_x = dx/dq at the last solution, as a dense matrix.
    module subroutine kin_transfer(this, model)
      class(kinematics_t), intent(inout) :: this
      type(model_t), intent(in) :: model
    end subroutine kin_transfer
    !> Second-order transfer function contracted twice with qd: D2F_x qd qd (n_x), plus
    !> DF_x qdd when qdd is given (the prescribed accelerations: one solve for both).
    !> With x_dot = DF qd (given as xd when known), J_c (D2F qd qd) = -D2D(x_dot, x_dot) over
    !> the kinematic rows.
    module subroutine kin_second(this, model, qd, d2x, xd_known, qdd)
      class(kinematics_t), intent(inout) :: this
      type(model_t), intent(in) :: model
      real(wp), intent(in) :: qd(:)
      real(wp), intent(out) :: d2x(:)
      real(wp), intent(in), optional :: xd_known(:), qdd(:)
    end subroutine kin_second
    !> The solve of kin_second for element terms evaluated by the caller: d2e holds D2D(x_dot,
    !> x_dot) of every mode (model numbering), so that an evaluation gets them in its own pass
    !> over the elements (with the inertia, at the same x and x_dot).
    module subroutine kin_second_solve(this, model, d2e, d2x, qdd)
      class(kinematics_t), intent(inout) :: this
      type(model_t), intent(in) :: model
      real(wp), intent(in) :: d2e(:)
      real(wp), intent(out) :: d2x(:)
      real(wp), intent(in), optional :: qdd(:)
    end subroutine kin_second_solve
    !> Residual r (n_c) of the kinematic equations at this%x and, with `jacobian`, their
    !> Jacobian J_c (into the dense or sparse storage) and the input-coordinate entries.
    module subroutine kin_residual(this, model, q, r, jacobian)
      class(kinematics_t), intent(inout) :: this
      type(model_t), intent(in) :: model
      real(wp), intent(in) :: q(:)
      real(wp), intent(out) :: r(:)
      logical, intent(in), optional :: jacobian
    end subroutine kin_residual
    !> ' (...)' naming a singular configuration where ||J_c^-1|| at the last solution (x, q),
    !> refactorised there, exceeds NEAR_SINGULAR times the first solution's; '' otherwise.
    module function kin_configuration_hint(this, model) result(hint)
      class(kinematics_t), intent(inout) :: this
      type(model_t), intent(in) :: model
      character(len=:), allocatable :: hint
    end function kin_configuration_hint
    !> An estimate of ||J_c^-1||_2 with the current factors (a few solves).
    module function kin_inverse_norm(this, model) result(norm)
      class(kinematics_t), intent(inout) :: this
      type(model_t), intent(in) :: model
      real(wp) :: norm
    end function kin_inverse_norm
    !> Why J_c is singular, from a dense factorisation (model_kinematics_diagnostics).
    module function kin_singular_message(this, model, q) result(msg)
      class(kinematics_t), intent(inout) :: this
      type(model_t), intent(in) :: model
      real(wp), intent(in) :: q(:)
      character(len=:), allocatable :: msg
    end function kin_singular_message
    !> The elastic and released modes that the undetermined motion of pivot k changes.
    module function kin_free_modes_moved(this, model, k) result(hint)
      class(kinematics_t), intent(in) :: this
      type(model_t), intent(in) :: model
      integer, intent(in) :: k
      character(len=:), allocatable :: hint
    end function kin_free_modes_moved
    !> The flat entry lists (jac_src, ...) from kin_init's per-entry arrays.
    module subroutine flat_entries(this, model, ent_col, ent_slot, ent_in)
      type(kinematics_t), intent(inout) :: this
      type(model_t), intent(in) :: model
      integer, intent(in) :: ent_col(:), ent_slot(:), ent_in(:)
    end subroutine flat_entries
    !> jac_set_* and jac_add_* from jac_slot and jac_src. A slot without entries keeps the zero
    !> of sparse_setup: nothing else writes the values.
    module subroutine gather_lists(this)
      type(kinematics_t), intent(inout) :: this
    end subroutine gather_lists
  end interface

contains

  !> Factorise the Jacobian just assembled; info /= 0 if it is singular, worst is then a
  !> column that is not determined (0 if unknown).
  subroutine factor_jacobian(this, info, worst)
    class(kinematics_t), intent(inout) :: this
    integer, intent(out) :: info, worst
    real(wp) :: rcond
    worst = 0
    if (this%sparse) then
      call this%jac_sp%factor(info, rcond)
    else
      call lu_factor(this%lu, this%ipiv, info, rcond, worst)
    end if
    if (rcond < SINGULAR_PIVOT) info = max(info, 1)
  end subroutine factor_jacobian

  !> b := J_c^-1 b (transposed: J_c^-T b) with the factors of the last solution.
  subroutine kin_jacobian_solve(this, b, transposed)
    class(kinematics_t), intent(inout) :: this
    real(wp), intent(inout), contiguous :: b(:, :)
    logical, intent(in), optional :: transposed
    if (size(b, 1) == 0) return
    if (this%sparse) then
      call this%jac_sp%solve_many(b, transposed)
    else
      call lu_solve(this%lu, this%ipiv, b, transposed)
    end if
  end subroutine kin_jacobian_solve

  !> Solve the kinematic equations for q, starting from the last solution moved along the
  !> first-order transfer function (a cheap predictor that keeps Newton on the right branch).
  !> On success the Jacobian at the solution is factorised and DF is NOT yet updated.
  !> The kinematic solution at q: Newton from the last solution (kin_newton). If that fails and
  !> `continuation` is on, the step from the last q is cut into 2, 4, ... 64 equal parts (at
  !> least one per MAX_PART of the largest jump, up to MAX_PARTS), each
  !> solved from the one before: a far jump, such as a modal analysis at a time when a shaft
  !> has turned 10 rad, defeats Newton from the reference but not in steps. The first
  !> failure's error is returned if no subdivision succeeds. t, the time of q, lets the
  !> predictor use the rates noted at the last solution (model_kinematics_rates).
  subroutine kin_solve(this, model, q, err, t)
    class(kinematics_t), intent(inout) :: this
    type(model_t), intent(in) :: model
    real(wp), intent(in) :: q(:)
    type(error_t), intent(out) :: err
    real(wp), intent(in), optional :: t
    real(wp), allocatable :: x_last(:), q_last(:)
    type(error_t) :: sub_err
    integer :: n, n_solves, n_min
    real(wp), parameter :: MAX_PART = 0.5_wp, MAX_PARTS = 2.0e4_wp, MAX_COARSE_PART = 1.0e3_wp
    real(wp) :: jump
    ! The usual path (every evaluation of a run) copies nothing.
    if (.not. this%continuation) then
      call kin_newton(this, model, q, err, t)
      return
    end if
    allocate(x_last, source=this%x)
    allocate(q_last, source=this%q)
    n_solves = this%n_solves
    ! Newton across a jump of many radians (a shaft 1e4 turns on) diverges, to a wrong
    ! 'singular Jacobian' or to overflow (a floating-point trap in Debug). Whether a part of
    ! many radians converges is luck (a blade spun 3e4 rad did in 64 parts, in 300 parts of
    ! 100 rad it did not): first the direct solve and 2 .. 64 parts where each is at most
    ! MAX_COARSE_PART (cheap, and enough for most), then parts of at most MAX_PART (safe,
    ! up to MAX_PARTS of them); a longer jump is refused.
    jump = maxval(abs(q - q_last))
    if (jump <= MAX_COARSE_PART) then
      call kin_newton(this, model, q, err, t)
      if (err%ok()) return
    end if
    n = 1
    do while (n < 64)
      n = 2 * n
      if (jump / n > MAX_COARSE_PART) cycle
      if (in_parts(n)) return
    end do
    if (.not. jump <= MAX_PART * MAX_PARTS) then
      call err%clear()
      call err%set(ERR_NUMERIC, 'kinematics: the coordinates jump by more than ' // &
        approx_str(MAX_PART * MAX_PARTS) // ' (m or rad) from the last solution, more than ' // &
        'the continuation follows in steps')
    else
      n_min = ceiling(jump / MAX_PART)
      if (n_min > 64) then
        if (in_parts(n_min)) return
      end if
    end if
    this%x = x_last
    this%q = q_last
    this%has_factors = .false.

  contains

    !> Solve the jump in n equal parts from the last solution; keeps the first failure.
    logical function in_parts(n) result(ok)
      integer, intent(in) :: n
      integer :: i
      this%x = x_last
      this%q = q_last
      this%has_factors = .false.
      do i = 1, n
        call kin_newton(this, model, q_last + (real(i, wp) / n) * (q - q_last), sub_err)
        if (.not. sub_err%ok()) exit
      end do
      ok = sub_err%ok()
      if (ok) then
        call err%clear()
        this%n_solves = n_solves + 1
      else if (err%ok()) then
        call err%set(sub_err%code, sub_err%message)
      end if
    end function in_parts
  end subroutine kin_solve

  !> Start the next solve from the nodal coordinates x (a known nearby solution), without the
  !> predictor from the last one: revisiting stored static steps in another order jumps too
  !> far for it (a spatial roll-up from its full turn back to its first step).
  subroutine kin_restart_from(this, x)
    class(kinematics_t), intent(inout) :: this
    real(wp), intent(in) :: x(:)
    this%x = x
    this%has_factors = .false.
    this%has_df = .false.
    this%rates%valid = .false.
    this%modes_at_x = .false.
  end subroutine kin_restart_from

  subroutine kin_newton(this, model, q, err, t)
    class(kinematics_t), intent(inout) :: this
    type(model_t), intent(in) :: model
    real(wp), intent(in) :: q(:)
    type(error_t), intent(out) :: err
    real(wp), intent(in), optional :: t
    real(wp) :: r(model%n_c), dx(model%n_c, 1), rmax, rprev
    real(wp) :: x_start(model%n_x), x_last(model%n_x)
    integer :: it, info, worst
    logical :: stale, diverged
    character(len=200) :: msg
    call model%check_limits(q, err)
    if (.not. err%ok()) return
    this%n_solves = this%n_solves + 1
    this%modes_at_x = .false.
    ! The factors of the previous solution serve for the predictor and for one chord step:
    ! close to it they contract nearly as well as fresh ones, and the solution then needs one
    ! factorisation (at the final x, for the transfer functions) instead of two.
    stale = this%has_factors
    x_last = this%x
    if (this%has_factors) then
      call this%predict(model, q, t)
    else
      this%rates%valid = .false.
    end if
    do it = 1, model%n_q
      if (model%q_coord(it) > 0) this%x(model%q_coord(it)) = model%x0(model%q_coord(it)) + q(it)
    end do
    x_start = this%x
    this%has_df = .false.
    this%has_factors = .false.
    rprev = huge(1.0_wp)
    diverged = .false.
    do it = 1, MAX_NEWTON
      ! A scene's coordinates and motions stay within 1e30 (the schema's ranges), Euler
      ! parameters near 1: iterates beyond X_DIVERGED, or Euler parameters beyond
      ! EULER_DIVERGED, have run away (loads of 1e30 on a spatial beam), and evaluating the
      ! elements there overflowed (the beam's rotation entries are squares of the parameters,
      ! its twist squares of their products: a floating-point trap in Debug) before the
      ! residual could say so.
      if (runaway(model, this%x)) then
        diverged = .true.
        exit
      end if
      ! Sparse: the Jacobian's values go into the matrix while KLU's stale factors stay
      ! usable, so where the predictor has already converged this element pass is the only
      ! one. Dense factors overwrite the matrix: there the stale pass skips the Jacobian.
      call this%residual(model, q, r, jacobian=this%sparse .or. .not. stale)
      rmax = 0.0_wp
      if (model%n_c > 0) rmax = maxval(abs(r))
      if (rmax /= rmax) exit
      if (stale) then
        stale = .false.
        if (rmax > model%newton_tol) then
          dx(:, 1) = -r
          call this%jacobian_solve(dx)
          call add_calculable(this, model, dx(:, 1))
          cycle
        end if
        if (.not. this%sparse) call this%residual(model, q, r, jacobian=.true.)
      end if
      call factor_jacobian(this, info, worst)
      if (info /= 0) then
        if (this%inv_norm_first < 0) then
          call err%set(ERR_MODEL, this%singular_message(model, q))
        else
          ! Regular at the first solution: a configuration reached along the motion, which a
          ! shorter step or another load increment may avoid (no dense diagnosis here: a run
          ! may pass this way many times).
          call err%set(ERR_NUMERIC, 'the kinematic Jacobian is singular here, not at the ' // &
            'first solution: a singular configuration of the mechanism, e.g. links aligned ' // &
            'at a dead point')
        end if
        this%x = x_start
        return
      end if
      dx(:, 1) = -r
      if (rmax > model%newton_tol .or. model%n_elastic > 0) call this%jacobian_solve(dx)
      if (rmax <= model%newton_tol) then
        ! With elastic modes, one more correction with these factors takes the error from
        ! rmax to about rmax^2: the stress of a stiff elastic mode is EA/l0 times its error,
        ! and statics differences such stresses. Without them rmax is all the accuracy x
        ! needs, and the factors then belong to x exactly.
        if (model%n_elastic > 0) call add_calculable(this, model, dx(:, 1))
        this%modes_at_x = model%n_elastic == 0
        this%q = q
        this%has_factors = .true.
        if (this%inv_norm_first < 0) this%inv_norm_first = this%inverse_norm(model)
        this%n_iterations = this%n_iterations + it - 1
        return
      end if
      if (it > 3 .and. rmax > rprev) exit
      rprev = rmax
      call add_calculable(this, model, dx(:, 1))
    end do
    ! es10.3 pads with a blank: 'residual  2.091E+02' read like a missing number.
    write(msg, '(a,i0,a,es9.3)') 'kinematic Newton iteration did not converge in ', it - 1, &
      ' iterations, residual ', rmax
    if (diverged) write(msg, '(a,i0,a)') 'kinematic Newton iteration diverged in ', it - 1, &
      ' iterations (coordinates beyond 1e50 or Euler parameters beyond 1e6)'
    this%x = merge(x_start, x_last, this%keep_failed_guess)
    ! The hint refactors at the last solution (not with a kept guess: arc-length's retries).
    if (this%keep_failed_guess) then
      call err%set(ERR_NUMERIC, trim(msg))
    else
      call err%set(ERR_NUMERIC, trim(msg) // this%configuration_hint(model))
    end if
  end subroutine kin_newton


  !> Whether a kinematic iterate has run away (see kin_newton).
  pure logical function runaway(model, x)
    type(model_t), intent(in) :: model
    real(wp), intent(in) :: x(:)
    integer :: i
    runaway = .true.
    do i = 1, size(x)
      if (abs(x(i)) > X_DIVERGED) return
      if (model%coord_kind(i) == COORD_EULER .and. abs(x(i)) > EULER_DIVERGED) return
    end do
    runaway = .false.
  end function runaway

  !> x := x + dx on the calculable coordinates (a loop: the vector-subscripted sum makes a
  !> temporary).
  pure subroutine add_calculable(this, model, dx)
    type(kinematics_t), intent(inout) :: this
    type(model_t), intent(in) :: model
    real(wp), intent(in) :: dx(:)
    integer :: i
    do i = 1, model%n_c
      this%x(model%calc_coord(i)) = this%x(model%calc_coord(i)) + dx(i)
    end do
  end subroutine add_calculable

  !> Keep the solution (x, q) to go on from it later with restore_state.
  subroutine kin_save_state(this, state)
    class(kinematics_t), intent(in) :: this
    type(kin_state_t), intent(out) :: state
    state%x = this%x
    state%q = this%q
  end subroutine kin_save_state

  !> Go back to a saved solution; the next solve starts there without a predictor.
  subroutine kin_restore_state(this, state)
    class(kinematics_t), intent(inout) :: this
    type(kin_state_t), intent(in) :: state
    this%x = state%x
    this%q = state%q
    this%has_factors = .false.
    this%has_df = .false.
    this%rates%valid = .false.
    this%modes_at_x = .false.
  end subroutine kin_restore_state
end module model_kinematics
