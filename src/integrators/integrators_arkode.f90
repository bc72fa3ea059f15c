!> ARKODE ERKStep (explicit embedded Runge-Kutta, adaptive step) on the first-order form of
!> q'' = a(t, q, v):   y = (q, v),   y' = (v, a(t, q, v)).
!>
!> Meant for reduced models, which are not stiff: no Jacobian, no linear solver. This module,
!> integrators_cvode and integrators_sundials (what the two share: the bridge object behind
!> ARKODE's user_data, the right-hand side and error-handler callbacks, the packing of y) are
!> the only ones of flexmor that talk to SUNDIALS, so that the move to SUNDIALS 7 (which changes
!> ARKODE's API too) stays in three files.
!>
!> Two things of ARKODE 6.4 are worked around here:
!> - ERKStep gives up on a recoverable (> 0) status of the right-hand side instead of retrying
!>   with a smaller step as CVODE does. So the solver steps in ARK_ONE_STEP mode, keeps the last
!>   accepted state and, after a recoverable status, re-initialises there with a quarter of the
!>   failed step (at most max_retries times before getting past the time of the failure).
!> - After each step ERKStep reuses the last stage's f for the next step whenever the last node
!>   is 1, even when the method is not FSAL (llnl/sundials#311). The default tables of orders
!>   2, 6 and 8 are such methods (order 6 drops to third order); they get one more stage that
!>   evaluates f at the new solution, which makes them FSAL for real at no extra cost.
module integrators_arkode
  use, intrinsic :: iso_c_binding, only: c_ptr, c_null_ptr, c_int, c_long, c_double, c_loc, &
    c_funloc, c_f_pointer, c_associated
  use core_kinds, only: wp, i8
  use core_strings, only: int_str, real_str
  use core_error, only: error_t, ERR_NUMERIC, ERR_INTERNAL
  use integrators_system, only: ode2_system_t, integrator_options_t, integrator_stats_t
  use integrators_base, only: integrator_t
  use core_progress, only: progress_t
  use integrators_sundials, only: sundials_bridge_t, new_bridge, open_sundials, close_sundials, &
    sundials_rhs, sundials_error_handler, put_state, get_state, check, set_failure, &
    erk_return_flag_name
  use fsundials_nvector_mod, only: N_Vector
  use farkode_mod, only: ARK_ONE_STEP, ARK_RHSFUNC_FAIL, ARK_REPTD_RHSFUNC_ERR, &
    ARK_UNREC_RHSFUNC_ERR, FARKodeButcherTable_LoadERK, FARKodeButcherTable_Create, &
    FARKodeButcherTable_Free
  use farkode_erkstep_mod, only: ERKSTEP_DEFAULT_2, ERKSTEP_DEFAULT_3, ERKSTEP_DEFAULT_4, &
    ERKSTEP_DEFAULT_5, ERKSTEP_DEFAULT_6, ERKSTEP_DEFAULT_8, FERKStepCreate, FERKStepReInit, &
    FERKStepFree, FERKStepEvolve, FERKStepGetDky, FERKStepSStolerances, FERKStepSetTable, &
    FERKStepSetMaxStep, FERKStepSetInitStep, FERKStepSetStopTime, FERKStepSetUserData, &
    FERKStepSetErrHandlerFn, FERKStepGetNumSteps, FERKStepGetNumErrTestFails, &
    FERKStepGetCurrentStep
  implicit none
  private
  public :: erk_solver_t

  !> Recoverable statuses of accel in a row, each retried with a quarter of the step, before
  !> giving up (CVODE allows as many).
  integer, parameter :: max_retries = 10

  !> The name of this solver in the error messages.
  character(len=*), parameter :: solver = 'ARKODE'

  !> One ERKStep integration of one system. Call `finish` when done (gfortran 12 does not
  !> finalize local variables reliably, so there is no final procedure to rely on).
  type, extends(integrator_t) :: erk_solver_t
    private
    type(c_ptr) :: ctx = c_null_ptr
    type(c_ptr) :: mem = c_null_ptr
    type(N_Vector), pointer :: y => null()
    type(sundials_bridge_t), pointer :: bridge => null()
    integer(i8) :: max_steps = 0
    !> The last accepted step: where a recoverable failure is retried from.
    real(wp) :: t = 0
    real(wp), allocatable :: q_accepted(:), v_accepted(:)
    real(wp) :: t_stop = 0
    !> Retries since the solution last got past t_trouble, the latest recoverable status.
    integer :: n_retries = 0
    real(wp) :: t_trouble = 0
    !> Counters of the segments before the last ERKStepReInit, which resets ARKODE's own.
    type(integrator_stats_t) :: done
    type(progress_t), pointer :: progress => null()   !< polled once per step
  contains
    procedure :: start => erk_start
    procedure :: advance => erk_advance
    procedure :: restart => erk_restart
    procedure :: get_stats => erk_get_stats
    procedure :: finish => erk_finish
  end type erk_solver_t

  !> ARKodeButcherTableMem of arkode_butcher.h, to read a table ARKODE loaded.
  type, bind(C) :: butcher_table_c_t
    integer(c_int) :: q, p, stages
    type(c_ptr) :: a, c, b, d
  end type butcher_table_c_t

contains

  !> Set up ERKStep at (t0, q, v); it will not step past t_stop.
  subroutine erk_start(this, sys, opts, t0, q, v, t_stop, t_lo, t_hi, err)
    class(erk_solver_t), intent(inout) :: this
    class(ode2_system_t), intent(inout), target :: sys
    type(integrator_options_t), intent(in) :: opts
    real(wp), intent(in) :: t0, q(:), v(:), t_stop, t_lo, t_hi
    type(error_t), intent(inout) :: err

    call this%finish()
    this%max_steps = opts%max_steps
    this%progress => opts%progress
    this%done = integrator_stats_t()
    this%t = t0
    this%q_accepted = q
    this%v_accepted = v
    this%t_stop = t_stop
    this%n_retries = 0
    this%bridge => new_bridge(sys, size(q), t_lo, t_hi)
    call open_sundials(solver, q, v, this%ctx, this%y, err)
    if (.not. err%ok()) return
    this%mem = FERKStepCreate(c_funloc(sundials_rhs), t0, this%y, this%ctx)
    if (.not. c_associated(this%mem)) then
      call err%set(ERR_INTERNAL, 'ARKODE: ERKStepCreate failed')
      return
    end if
    call check(solver, FERKStepSetUserData(this%mem, c_loc(this%bridge)), 'ERKStepSetUserData', err)
    call check(solver, FERKStepSetErrHandlerFn(this%mem, c_funloc(sundials_error_handler), &
      c_loc(this%bridge)), 'ERKStepSetErrHandlerFn', err)
    call check(solver, FERKStepSStolerances(this%mem, opts%rtol, opts%atol), &
      'ERKStepSStolerances', err)
    call set_method(this%mem, opts%erk_order, err)
    if (opts%max_step > 0) then
      call check(solver, FERKStepSetMaxStep(this%mem, opts%max_step), 'ERKStepSetMaxStep', err)
    end if
    call check(solver, FERKStepSetStopTime(this%mem, t_stop), 'ERKStepSetStopTime', err)
  end subroutine erk_start

  !> Integrate to t_target (at most the stop time) and return the state there.
  subroutine erk_advance(this, sys, t_target, q, v, err)
    class(erk_solver_t), intent(inout) :: this
    class(ode2_system_t), intent(inout) :: sys
    real(wp), intent(in) :: t_target
    real(wp), intent(out) :: q(:), v(:)
    type(error_t), intent(inout) :: err
    real(wp) :: t_before

    do while (this%t < t_target)
      t_before = this%t
      call take_step(this, t_target, err)
      if (.not. err%ok()) return
      ! Not after a retry from the last accepted state (take_step then did not advance).
      if (this%t > t_before) call sys%step_accepted(this%t, this%q_accepted, this%v_accepted)
      if (associated(this%progress)) call report_progress(this)
    end do
    if (this%t == t_target) then
      q = this%q_accepted
      v = this%v_accepted
      return
    end if
    ! The last step went past t_target: ARKODE's interpolant gives the state there.
    call check(solver, FERKStepGetDky(this%mem, t_target, 0_c_int, this%y), 'ERKStepGetDky', err)
    if (.not. err%ok()) return
    call get_state(this%y, q, v)
  end subroutine erk_advance

  !> One accepted step, or an error. A recoverable status of accel is retried from the last
  !> accepted state with a smaller step.
  subroutine take_step(this, t_target, err)
    type(erk_solver_t), intent(inout) :: this
    real(wp), intent(in) :: t_target
    type(error_t), intent(inout) :: err
    integer(c_int) :: flag
    real(c_double) :: t_reached(1)
    type(integrator_stats_t) :: stats

    call this%get_stats(stats)
    if (stats%n_steps >= this%max_steps) then
      call err%set(ERR_NUMERIC, 'ARKODE: max_steps reached at t = ' // real_str(this%t) // &
        ', before t = ' // real_str(t_target))
      return
    end if
    this%bridge%bad_status = 0
    flag = FERKStepEvolve(this%mem, t_target, this%y, t_reached, ARK_ONE_STEP)
    if (flag >= 0 .and. .not. t_reached(1) > this%t) then
      call err%set(ERR_INTERNAL, 'ARKODE: ERKStepEvolve did not advance from t = ' // &
        real_str(this%t))
    else if (flag >= 0) then
      this%t = t_reached(1)
      call get_state(this%y, this%q_accepted, this%v_accepted)
      ! Counted until past the trouble, or steps creeping up to it would never give up.
      if (this%t > this%t_trouble) this%n_retries = 0
    else if (recoverable(this, flag) .and. this%n_retries < max_retries) then
      this%n_retries = this%n_retries + 1
      this%t_trouble = this%bridge%bad_time
      call retry_smaller(this, err)
    else
      call report_failure(this, flag, t_target, err)
    end if
  end subroutine take_step

  subroutine report_progress(this)
    type(erk_solver_t), intent(in) :: this
    type(integrator_stats_t) :: stats
    if (.not. this%progress%due()) return
    call this%get_stats(stats)
    call this%progress%report_time(this%t, stats%n_steps)
  end subroutine report_progress

  logical function recoverable(this, flag)
    type(erk_solver_t), intent(in) :: this
    integer(c_int), intent(in) :: flag
    recoverable = this%bridge%bad_status > 0 .and. (flag == ARK_UNREC_RHSFUNC_ERR .or. &
      flag == ARK_RHSFUNC_FAIL .or. flag == ARK_REPTD_RHSFUNC_ERR)
  end function recoverable

  !> Start again from the last accepted state with a quarter of the step that failed.
  subroutine retry_smaller(this, err)
    type(erk_solver_t), intent(inout) :: this
    type(error_t), intent(inout) :: err
    real(c_double) :: h(1)
    call check(solver, FERKStepGetCurrentStep(this%mem, h), 'ERKStepGetCurrentStep', err)
    call reinit(this, 0.25_wp * h(1), err)
  end subroutine retry_smaller

  !> Start again at (t, q, v) after a jump of a(t, ...): the step size chosen for the old
  !> segment says nothing about the new one.
  subroutine erk_restart(this, sys, t, q, v, t_stop, t_lo, t_hi, err)
    class(erk_solver_t), intent(inout) :: this
    class(ode2_system_t), intent(inout) :: sys
    real(wp), intent(in) :: t, q(:), v(:), t_stop, t_lo, t_hi
    type(error_t), intent(inout) :: err
    this%bridge%t_lo = t_lo
    this%bridge%t_hi = t_hi
    this%t = t
    this%q_accepted = q
    this%v_accepted = v
    this%t_stop = t_stop
    this%n_retries = 0
    call reinit(this, 0.0_wp, err)
    this%done%n_restarts = this%done%n_restarts + 1
  end subroutine erk_restart

  !> ERKStepReInit at the last accepted state, first step h0 (0: ARKODE estimates it).
  subroutine reinit(this, h0, err)
    type(erk_solver_t), intent(inout) :: this
    real(wp), intent(in) :: h0
    type(error_t), intent(inout) :: err
    type(integrator_stats_t) :: so_far
    ! Through a copy: this%done as the intent(out) argument would alias `this`.
    call this%get_stats(so_far)
    this%done = so_far
    call put_state(this%y, this%q_accepted, this%v_accepted)
    call check(solver, FERKStepReInit(this%mem, c_funloc(sundials_rhs), this%t, this%y), &
      'ERKStepReInit', err)
    call check(solver, FERKStepSetInitStep(this%mem, h0), 'ERKStepSetInitStep', err)
    ! ReInit clears the stop time (SUNDIALS >= 6.3).
    call check(solver, FERKStepSetStopTime(this%mem, this%t_stop), 'ERKStepSetStopTime', err)
  end subroutine reinit

  subroutine erk_get_stats(this, stats)
    class(erk_solver_t), intent(in) :: this
    type(integrator_stats_t), intent(out) :: stats
    integer(c_long) :: n(1)
    integer(c_int) :: flag

    stats = this%done
    if (.not. c_associated(this%mem)) return
    flag = FERKStepGetNumSteps(this%mem, n)
    if (flag == 0) stats%n_steps = stats%n_steps + int(n(1), i8)
    flag = FERKStepGetNumErrTestFails(this%mem, n)
    if (flag == 0) stats%n_err_test_fails = stats%n_err_test_fails + int(n(1), i8)
    ! Counted by our callback, across ReInit, as for CVODE.
    stats%n_rhs_evals = this%bridge%n_accel
  end subroutine erk_get_stats

  !> Free all SUNDIALS memory; safe to call more than once.
  subroutine erk_finish(this)
    class(erk_solver_t), intent(inout) :: this
    if (c_associated(this%mem)) call FERKStepFree(this%mem)
    this%mem = c_null_ptr
    call close_sundials(this%ctx, this%y, this%bridge)
  end subroutine erk_finish

  subroutine report_failure(this, flag, t_target, err)
    type(erk_solver_t), intent(in) :: this
    integer(c_int), intent(in) :: flag
    real(wp), intent(in) :: t_target
    type(error_t), intent(inout) :: err
    character(len=:), allocatable :: note

    note = ''
    if (this%n_retries >= max_retries) note = ', still after ' // int_str(max_retries) // &
      ' retries with smaller steps'
    call set_failure('ARKODE (ERKStep)', this%t, t_target, flag, &
      erk_return_flag_name(int(flag, c_long)), this%bridge, note, err)
  end subroutine report_failure

  ! ---- method tables ------------------------------------------------------------------------

  !> Give ERKStep ARKODE's default table of the given order (2, 3, 4, 5, 6 or 8), made FSAL
  !> where ARKODE 6.4 would take it for one (see the module comment).
  subroutine set_method(mem, order, err)
    type(c_ptr), intent(in) :: mem
    integer, intent(in) :: order
    type(error_t), intent(inout) :: err
    type(c_ptr) :: table, fsal_table

    table = FARKodeButcherTable_LoadERK(default_table_id(order))
    if (.not. c_associated(table)) then
      call err%set(ERR_INTERNAL, 'ARKODE: no default table of order ' // int_str(order))
      return
    end if
    fsal_table = with_fsal_stage(table)
    ! ERKStepSetTable keeps a copy.
    if (c_associated(fsal_table)) then
      call check(solver, FERKStepSetTable(mem, fsal_table), 'ERKStepSetTable', err)
      call FARKodeButcherTable_Free(fsal_table)
    else
      call check(solver, FERKStepSetTable(mem, table), 'ERKStepSetTable', err)
    end if
    call FARKodeButcherTable_Free(table)
  end subroutine set_method

  integer(c_int) function default_table_id(order) result(id)
    integer, intent(in) :: order
    select case (order)
    case (2)
      id = ERKSTEP_DEFAULT_2
    case (3)
      id = ERKSTEP_DEFAULT_3
    case (4)
      id = ERKSTEP_DEFAULT_4
    case (6)
      id = ERKSTEP_DEFAULT_6
    case (8)
      id = ERKSTEP_DEFAULT_8
    case default
      id = ERKSTEP_DEFAULT_5
    end select
  end function default_table_id

  !> For a table whose last node is 1 but whose last row of A is not b: a new table with one
  !> more stage, at node 1 with row b (so its f is f at the new solution) and weight 0 in both
  !> b and the embedding d. Otherwise a null pointer: the table is fine as it is.
  function with_fsal_stage(table) result(fsal_table)
    type(c_ptr), intent(in) :: table
    type(c_ptr) :: fsal_table
    type(butcher_table_c_t), pointer :: tab
    type(c_ptr), pointer :: rows(:)
    real(c_double), pointer :: row(:), c(:), b(:), d(:)
    real(c_double), allocatable :: a_rows(:), c_new(:), b_new(:), d_new(:)
    integer :: s, i

    fsal_table = c_null_ptr
    call c_f_pointer(table, tab)
    s = int(tab%stages)
    ! A is stored as s pointers to rows.
    call c_f_pointer(tab%a, rows, [s])
    call c_f_pointer(rows(s), row, [s])
    call c_f_pointer(tab%c, c, [s])
    call c_f_pointer(tab%b, b, [s])
    call c_f_pointer(tab%d, d, [s])
    if (abs(c(s) - 1) > 10 * epsilon(1.0_c_double) .or. &
      all(abs(row - b) <= 10 * epsilon(1.0_c_double))) return
    ! Row-major, as ARKodeButcherTable_Create wants A: the old rows padded with 0, then b.
    allocate(a_rows((s + 1)**2), source=0.0_c_double)
    do i = 1, s
      call c_f_pointer(rows(i), row, [s])
      a_rows((i - 1) * (s + 1) + 1:(i - 1) * (s + 1) + s) = row
    end do
    a_rows(s * (s + 1) + 1:s * (s + 1) + s) = b
    ! Variables, not expressions: the SWIG wrapper declares them intent(inout).
    c_new = [c, 1.0_c_double]
    b_new = [b, 0.0_c_double]
    d_new = [d, 0.0_c_double]
    fsal_table = FARKodeButcherTable_Create(int(s + 1, c_int), tab%q, tab%p, c_new, a_rows, &
      b_new, d_new)
  end function with_fsal_stage
end module integrators_arkode
