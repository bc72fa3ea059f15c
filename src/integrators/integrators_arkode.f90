!> ARKODE ERKStep (explicit embedded Runge-Kutta, adaptive step) on the first-order form of
!> q'' = a(t, q, v):   y = (q, v),   y' = (v, a(t, q, v)).
!>
!> Meant for reduced models, which are not stiff: no Jacobian, no linear solver. Together with
!> integrators_cvode this is the only module of flexmor that talks to SUNDIALS (SUNDIALS 7
!> changes ARKODE's API too). The system is reached from the C callbacks through ARKODE's
!> user_data, a heap-allocated bridge object: no module variables, so several models can run in
!> one process.
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
  use, intrinsic :: iso_c_binding, only: c_ptr, c_null_ptr, c_int, c_long, c_double, c_int64_t, &
    c_char, c_size_t, c_loc, c_funloc, c_f_pointer, c_associated
  use core_kinds, only: wp, i8
  use core_strings, only: int_str, real_str
  use core_error, only: error_t, ERR_NUMERIC, ERR_INTERNAL
  use integrators_system, only: ode2_system_t, integrator_options_t, integrator_stats_t
  use fsundials_context_mod, only: FSUNContext_Create, FSUNContext_Free
  use fsundials_nvector_mod, only: N_Vector, FN_VDestroy, FN_VGetArrayPointer
  use fnvector_serial_mod, only: FN_VNew_Serial
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

  !> What the C callbacks need; lives on the heap so its address (ARKODE's user_data) is fixed.
  type :: erk_bridge_t
    class(ode2_system_t), pointer :: sys => null()
    integer :: n = 0
    !> accel is evaluated at times clamped into [t_lo, t_hi], strictly inside the segment
    !> between breakpoints, so that a(t) jumping at a breakpoint is seen from the right side.
    real(wp) :: t_lo = -huge(1.0_wp), t_hi = huge(1.0_wp)
    integer(i8) :: n_accel = 0
    !> The last non-zero status of accel, for the retry decision and the error message.
    integer :: bad_status = 0
    real(wp) :: bad_time = 0
    !> ARKODE's own message of its last error (from the error handler).
    character(len=:), allocatable :: arkode_message
  end type erk_bridge_t

  !> One ERKStep integration of one system. Call `finish` when done (gfortran 12 does not
  !> finalize local variables reliably, so there is no final procedure to rely on).
  type :: erk_solver_t
    private
    type(c_ptr) :: ctx = c_null_ptr
    type(c_ptr) :: mem = c_null_ptr
    type(N_Vector), pointer :: y => null()
    type(erk_bridge_t), pointer :: bridge => null()
    integer(i8) :: max_steps = 0
    !> The last accepted step: where a recoverable failure is retried from.
    real(wp) :: t = 0
    real(wp), allocatable :: y_accepted(:)
    real(wp) :: t_stop = 0
    !> Retries since the solution last got past t_trouble, the latest recoverable status.
    integer :: n_retries = 0
    real(wp) :: t_trouble = 0
    !> Counters of the segments before the last ERKStepReInit, which resets ARKODE's own.
    type(integrator_stats_t) :: done
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

  interface
    function c_strlen(s) bind(C, name='strlen') result(n)
      import :: c_ptr, c_size_t
      type(c_ptr), value :: s
      integer(c_size_t) :: n
    end function c_strlen

    subroutine c_free(p) bind(C, name='free')
      import :: c_ptr
      type(c_ptr), value :: p
    end subroutine c_free

    !> Called directly: the string is malloc'ed, and the Fortran wrapper of SUNDIALS 6.4
    !> (FERKStepGetReturnFlagName) never frees it.
    function erk_return_flag_name(flag) bind(C, name='ERKStepGetReturnFlagName') result(name)
      import :: c_ptr, c_long
      integer(c_long), value :: flag
      type(c_ptr) :: name
    end function erk_return_flag_name
  end interface

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
    this%done = integrator_stats_t()
    this%t = t0
    this%y_accepted = [q, v]
    this%t_stop = t_stop
    this%n_retries = 0
    allocate(this%bridge)
    this%bridge%sys => sys
    this%bridge%n = size(q)
    this%bridge%t_lo = t_lo
    this%bridge%t_hi = t_hi

    call check(FSUNContext_Create(c_null_ptr, this%ctx), 'SUNContext_Create', err)
    if (.not. err%ok()) return
    this%y => FN_VNew_Serial(int(2 * size(q), c_int64_t), this%ctx)
    if (.not. associated(this%y)) then
      call err%set(ERR_INTERNAL, 'ARKODE: could not create the state vector')
      return
    end if
    call put_state(this%y, this%y_accepted)
    this%mem = FERKStepCreate(c_funloc(erk_rhs), t0, this%y, this%ctx)
    if (.not. c_associated(this%mem)) then
      call err%set(ERR_INTERNAL, 'ARKODE: ERKStepCreate failed')
      return
    end if
    call check(FERKStepSetUserData(this%mem, c_loc(this%bridge)), 'ERKStepSetUserData', err)
    call check(FERKStepSetErrHandlerFn(this%mem, c_funloc(erk_error_handler), &
      c_loc(this%bridge)), 'ERKStepSetErrHandlerFn', err)
    call check(FERKStepSStolerances(this%mem, opts%rtol, opts%atol), 'ERKStepSStolerances', err)
    call set_method(this%mem, opts%erk_order, err)
    if (opts%max_step > 0) then
      call check(FERKStepSetMaxStep(this%mem, opts%max_step), 'ERKStepSetMaxStep', err)
    end if
    call check(FERKStepSetStopTime(this%mem, t_stop), 'ERKStepSetStopTime', err)
  end subroutine erk_start

  !> Integrate to t_target (at most the stop time) and return the state there.
  subroutine erk_advance(this, t_target, q, v, err)
    class(erk_solver_t), intent(inout) :: this
    real(wp), intent(in) :: t_target
    real(wp), intent(out) :: q(:), v(:)
    type(error_t), intent(inout) :: err

    do while (this%t < t_target)
      call take_step(this, t_target, err)
      if (.not. err%ok()) return
    end do
    if (this%t == t_target) then
      q = this%y_accepted(:size(q))
      v = this%y_accepted(size(q) + 1:)
      return
    end if
    ! The last step went past t_target: ARKODE's interpolant gives the state there.
    call check(FERKStepGetDky(this%mem, t_target, 0_c_int, this%y), 'ERKStepGetDky', err)
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
      call copy_state(this%y, this%y_accepted)
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
    call check(FERKStepGetCurrentStep(this%mem, h), 'ERKStepGetCurrentStep', err)
    call reinit(this, 0.25_wp * h(1), err)
  end subroutine retry_smaller

  !> Start again at (t, q, v) after a jump of a(t, ...): the step size chosen for the old
  !> segment says nothing about the new one.
  subroutine erk_restart(this, t, q, v, t_stop, t_lo, t_hi, err)
    class(erk_solver_t), intent(inout) :: this
    real(wp), intent(in) :: t, q(:), v(:), t_stop, t_lo, t_hi
    type(error_t), intent(inout) :: err
    this%bridge%t_lo = t_lo
    this%bridge%t_hi = t_hi
    this%t = t
    this%y_accepted = [q, v]
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
    call put_state(this%y, this%y_accepted)
    call check(FERKStepReInit(this%mem, c_funloc(erk_rhs), this%t, this%y), 'ERKStepReInit', &
      err)
    call check(FERKStepSetInitStep(this%mem, h0), 'ERKStepSetInitStep', err)
    ! ReInit clears the stop time (SUNDIALS >= 6.3).
    call check(FERKStepSetStopTime(this%mem, this%t_stop), 'ERKStepSetStopTime', err)
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
    integer(c_int) :: flag
    if (c_associated(this%mem)) call FERKStepFree(this%mem)
    this%mem = c_null_ptr
    if (associated(this%y)) call FN_VDestroy(this%y)
    this%y => null()
    if (c_associated(this%ctx)) flag = FSUNContext_Free(this%ctx)
    this%ctx = c_null_ptr
    if (associated(this%bridge)) deallocate(this%bridge)
  end subroutine erk_finish

  subroutine report_failure(this, flag, t_target, err)
    type(erk_solver_t), intent(in) :: this
    integer(c_int), intent(in) :: flag
    real(wp), intent(in) :: t_target
    type(error_t), intent(inout) :: err
    character(len=:), allocatable :: msg
    type(c_ptr) :: flag_name

    msg = 'ARKODE (ERKStep) failed at t = ' // real_str(this%t) // ' (integrating to ' // &
      real_str(t_target) // '): flag ' // int_str(int(flag))
    flag_name = erk_return_flag_name(int(flag, c_long))
    msg = msg // ' ' // c_string(flag_name)
    call c_free(flag_name)
    if (this%bridge%bad_status /= 0) msg = msg // '; accel returned status ' // &
      int_str(this%bridge%bad_status) // ' at t = ' // real_str(this%bridge%bad_time)
    if (this%n_retries >= max_retries) msg = msg // ', still after ' // int_str(max_retries) // &
      ' retries with smaller steps'
    if (allocated(this%bridge%arkode_message)) msg = msg // '; ' // this%bridge%arkode_message
    call err%set(ERR_NUMERIC, msg)
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
      call check(FERKStepSetTable(mem, fsal_table), 'ERKStepSetTable', err)
      call FARKodeButcherTable_Free(fsal_table)
    else
      call check(FERKStepSetTable(mem, table), 'ERKStepSetTable', err)
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
    real(c_double), allocatable :: a(:, :)
    real(c_double), pointer :: c(:), b(:), d(:)
    real(c_double), allocatable :: a_rows(:), c_new(:), b_new(:), d_new(:)
    integer :: s, i

    fsal_table = c_null_ptr
    call c_f_pointer(table, tab)
    s = int(tab%stages)
    call c_f_pointer(tab%c, c, [s])
    call c_f_pointer(tab%b, b, [s])
    call c_f_pointer(tab%d, d, [s])
    a = table_matrix(tab%a, s)
    if (abs(c(s) - 1) > 10 * epsilon(1.0_c_double) .or. &
      all(abs(a(s, :) - b) <= 10 * epsilon(1.0_c_double))) return
    ! Row-major, as ARKodeButcherTable_Create wants A: the old rows padded with 0, then b.
    allocate(a_rows((s + 1)**2), source=0.0_c_double)
    do i = 1, s
      a_rows((i - 1) * (s + 1) + 1:(i - 1) * (s + 1) + s) = a(i, :)
    end do
    a_rows(s * (s + 1) + 1:s * (s + 1) + s) = b
    ! Variables, not expressions: the SWIG wrapper declares them intent(inout).
    c_new = [c, 1.0_c_double]
    b_new = [b, 0.0_c_double]
    d_new = [d, 0.0_c_double]
    fsal_table = FARKodeButcherTable_Create(int(s + 1, c_int), tab%q, tab%p, c_new, a_rows, &
      b_new, d_new)
  end function with_fsal_stage

  !> A of a loaded table (stored as s pointers to rows) as an s x s array.
  function table_matrix(rows_ptr, s) result(a)
    type(c_ptr), intent(in) :: rows_ptr
    integer, intent(in) :: s
    real(c_double) :: a(s, s)
    type(c_ptr), pointer :: rows(:)
    real(c_double), pointer :: row(:)
    integer :: i
    call c_f_pointer(rows_ptr, rows, [s])
    do i = 1, s
      call c_f_pointer(rows(i), row, [s])
      a(i, :) = row
    end do
  end function table_matrix

  ! ---- C callbacks --------------------------------------------------------------------------

  !> f(t, y) = (v, a(t, q, v))
  integer(c_int) function erk_rhs(t, y_nv, ydot_nv, user_data) result(ierr) bind(C)
    real(c_double), value :: t
    type(N_Vector) :: y_nv, ydot_nv
    type(c_ptr), value :: user_data
    type(erk_bridge_t), pointer :: b
    real(c_double), pointer :: y(:), ydot(:)
    integer :: n, status

    call c_f_pointer(user_data, b)
    n = b%n
    y => FN_VGetArrayPointer(y_nv)
    ydot => FN_VGetArrayPointer(ydot_nv)
    ydot(1:n) = y(n + 1:2 * n)
    call b%sys%accel(min(max(real(t, wp), b%t_lo), b%t_hi), y(1:n), y(n + 1:2 * n), &
      ydot(n + 1:2 * n), status)
    b%n_accel = b%n_accel + 1
    if (status /= 0) then
      b%bad_status = status
      b%bad_time = t
    end if
    ! Our convention (> 0 recoverable, < 0 fatal) is SUNDIALS'; only the size differs.
    ierr = int(sign(1, status), c_int)
    if (status == 0) ierr = 0
  end function erk_rhs

  !> Keep ARKODE's message for our error instead of letting it print to stderr.
  subroutine erk_error_handler(error_code, module_name, function_name, msg, user_data) bind(C)
    integer(c_int), value :: error_code
    type(c_ptr), value :: module_name, function_name, msg, user_data
    type(erk_bridge_t), pointer :: b
    if (error_code >= 0) return
    call c_f_pointer(user_data, b)
    b%arkode_message = c_string(function_name) // ': ' // c_string(msg)
  end subroutine erk_error_handler

  ! ---- helpers ------------------------------------------------------------------------------

  subroutine put_state(y_nv, y_in)
    type(N_Vector), intent(inout) :: y_nv
    real(wp), intent(in) :: y_in(:)
    real(c_double), pointer :: y(:)
    y => FN_VGetArrayPointer(y_nv)
    y = y_in
  end subroutine put_state

  subroutine copy_state(y_nv, y_out)
    type(N_Vector), intent(inout) :: y_nv
    real(wp), intent(out) :: y_out(:)
    real(c_double), pointer :: y(:)
    y => FN_VGetArrayPointer(y_nv)
    y_out = y
  end subroutine copy_state

  subroutine get_state(y_nv, q, v)
    type(N_Vector), intent(inout) :: y_nv
    real(wp), intent(out) :: q(:), v(:)
    real(c_double), pointer :: y(:)
    y => FN_VGetArrayPointer(y_nv)
    q = y(1:size(q))
    v = y(size(q) + 1:)
  end subroutine get_state

  subroutine check(flag, what, err)
    integer(c_int), intent(in) :: flag
    character(len=*), intent(in) :: what
    type(error_t), intent(inout) :: err
    if (flag /= 0) call err%set(ERR_INTERNAL, 'ARKODE: ' // what // ' returned ' // &
      int_str(int(flag)))
  end subroutine check

  function c_string(p) result(s)
    type(c_ptr), intent(in) :: p
    character(len=:), allocatable :: s
    character(kind=c_char), pointer :: chars(:)
    integer :: i, n
    if (.not. c_associated(p)) then
      s = ''
      return
    end if
    n = int(c_strlen(p))
    call c_f_pointer(p, chars, [n])
    allocate(character(len=n) :: s)
    do i = 1, n
      s(i:i) = chars(i)
    end do
  end function c_string
end module integrators_arkode
