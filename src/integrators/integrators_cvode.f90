!> CVODE (BDF, Newton, dense direct solver) on the first-order form of q'' = a(t, q, v):
!>     y = (q, v),   y' = (v, a(t, q, v)).
!>
!> This module, integrators_arkode and integrators_sundials (what the two share: the bridge
!> object behind CVODE's user_data, the right-hand side and error-handler callbacks, the packing
!> of y) are the only ones that talk to SUNDIALS, so that the move to SUNDIALS 7 (SUNComm,
!> fsundials_core_mod) stays in three files.
module integrators_cvode
  use, intrinsic :: iso_c_binding, only: c_ptr, c_null_ptr, c_int, c_long, c_double, c_int64_t, &
    c_loc, c_funloc, c_f_pointer, c_associated
  use core_kinds, only: wp, i8
  use core_strings, only: real_str
  use core_error, only: error_t, ERR_NUMERIC, ERR_INTERNAL
  use integrators_system, only: ode2_system_t, integrator_options_t, integrator_stats_t, &
    bdf_order, JACOBIAN_INTERNAL
  use integrators_base, only: integrator_t
  use integrators_sundials, only: sundials_bridge_t, new_bridge, open_sundials, close_sundials, &
    sundials_rhs, sundials_error_handler, clamped, note_status, sundials_status, put_state, &
    get_state, check, set_failure, cvode_return_flag_name
  use fsundials_nvector_mod, only: N_Vector, FN_VGetArrayPointer
  use fsundials_matrix_mod, only: SUNMatrix, FSUNMatDestroy
  use fsundials_linearsolver_mod, only: SUNLinearSolver, FSUNLinSolFree
  use fsunmatrix_dense_mod, only: FSUNDenseMatrix, FSUNDenseMatrix_Data
  use fsunlinsol_dense_mod, only: FSUNLinSol_Dense
  use fcvode_mod, only: CV_BDF, CV_NORMAL, CV_ONE_STEP, FCVodeCreate, FCVodeInit, &
    FCVodeReInit, FCVodeFree, FCVode, FCVodeGetDky, FCVodeSStolerances, FCVodeSetUserData, FCVodeSetErrHandlerFn, &
    FCVodeSetLinearSolver, FCVodeSetJacFn, FCVodeSetMaxOrd, FCVodeSetMaxStep, FCVodeSetMinStep, &
    FCVodeSetMaxNumSteps, FCVodeSetStopTime, FCVodeGetNumSteps, FCVodeGetNumJacEvals, &
    FCVodeGetNumLinSolvSetups, &
    FCVodeGetNumErrTestFails, FCVodeGetNumNonlinSolvConvFails, FCVodeGetCurrentTime
  implicit none
  private
  public :: cvode_solver_t

  !> The name of this solver in the error messages.
  character(len=*), parameter :: solver = 'CVODE'

  !> One CVODE integration of one system. Call `finish` when done (gfortran 12 does not
  !> finalize local variables reliably, so there is no final procedure to rely on).
  type, extends(integrator_t) :: cvode_solver_t
    private
    type(c_ptr) :: ctx = c_null_ptr
    type(c_ptr) :: mem = c_null_ptr
    type(N_Vector), pointer :: y => null()
    type(SUNMatrix), pointer :: jmat => null()
    type(SUNLinearSolver), pointer :: ls => null()
    type(sundials_bridge_t), pointer :: bridge => null()
    integer :: n = 0
    integer(i8) :: max_steps = 0
    !> Counters of the segments before the last CVodeReInit, which resets CVODE's own.
    type(integrator_stats_t) :: done
  contains
    procedure :: start => cvode_start
    procedure :: advance => cvode_advance
    procedure :: restart => cvode_restart
    procedure :: get_stats => cvode_get_stats
    procedure :: finish => cvode_finish
  end type cvode_solver_t

contains

  !> Set up CVODE at (t0, q, v); it will not step past t_stop.
  subroutine cvode_start(this, sys, opts, t0, q, v, t_stop, t_lo, t_hi, err)
    class(cvode_solver_t), intent(inout) :: this
    class(ode2_system_t), intent(inout), target :: sys
    type(integrator_options_t), intent(in) :: opts
    real(wp), intent(in) :: t0, q(:), v(:), t_stop, t_lo, t_hi
    type(error_t), intent(inout) :: err

    call this%finish()
    this%n = size(q)
    this%max_steps = opts%max_steps
    this%done = integrator_stats_t()
    this%bridge => new_bridge(sys, this%n, t_lo, t_hi)
    call open_sundials(solver, q, v, this%ctx, this%y, err)
    if (.not. err%ok()) return
    this%mem = FCVodeCreate(CV_BDF, this%ctx)
    if (.not. c_associated(this%mem)) then
      call err%set(ERR_INTERNAL, 'CVODE: CVodeCreate failed')
      return
    end if
    this%bridge%progress => opts%progress
    this%bridge%mem = this%mem
    call check(solver, FCVodeInit(this%mem, c_funloc(cvode_rhs), t0, this%y), 'CVodeInit', err)
    call check(solver, FCVodeSetUserData(this%mem, c_loc(this%bridge)), 'CVodeSetUserData', err)
    call check(solver, FCVodeSetErrHandlerFn(this%mem, c_funloc(sundials_error_handler), &
      c_loc(this%bridge)), 'CVodeSetErrHandlerFn', err)
    call check(solver, FCVodeSStolerances(this%mem, opts%rtol, opts%atol), 'CVodeSStolerances', err)
    call check(solver, FCVodeSetMaxOrd(this%mem, int(bdf_order(opts%max_order, opts%rtol), c_int)), 'CVodeSetMaxOrd', err)
    if (opts%max_step > 0) then
      call check(solver, FCVodeSetMaxStep(this%mem, opts%max_step), 'CVodeSetMaxStep', err)
    end if
    call check(solver, FCVodeSetStopTime(this%mem, t_stop), 'CVodeSetStopTime', err)
    ! Steps below the round-off of t cannot move it: CVODE would only warn and go on until
    ! max_steps (a mechanism at a dead point took 10 million steps at t = 1.5e-4). The same
    ! limit as galpha_adaptive's.
    call check(solver, FCVodeSetMinStep(this%mem, 16 * spacing(max(abs(t_stop), 1.0_wp))), &
      'CVodeSetMinStep', err)
    if (.not. err%ok()) return
    call attach_dense_solver(this, opts%jacobian /= JACOBIAN_INTERNAL, err)
  end subroutine cvode_start

  subroutine attach_dense_solver(this, system_jacobian, err)
    type(cvode_solver_t), intent(inout) :: this
    logical, intent(in) :: system_jacobian
    type(error_t), intent(inout) :: err
    integer(c_int64_t) :: n2
    n2 = int(2 * this%n, c_int64_t)
    this%jmat => FSUNDenseMatrix(n2, n2, this%ctx)
    if (.not. associated(this%jmat)) then
      call err%set(ERR_INTERNAL, 'CVODE: could not create the dense matrix')
      return
    end if
    this%ls => FSUNLinSol_Dense(this%y, this%jmat, this%ctx)
    if (.not. associated(this%ls)) then
      call err%set(ERR_INTERNAL, 'CVODE: could not create the dense linear solver')
      return
    end if
    call check(solver, FCVodeSetLinearSolver(this%mem, this%ls, this%jmat), &
      'CVodeSetLinearSolver', err)
    if (system_jacobian) then
      allocate(this%bridge%dadq(this%n, this%n), this%bridge%dadv(this%n, this%n))
      call check(solver, FCVodeSetJacFn(this%mem, c_funloc(cvode_jac)), 'CVodeSetJacFn', err)
    end if
  end subroutine attach_dense_solver

  !> Integrate to t_target (at most the stop time) and return the state there.
  subroutine cvode_advance(this, sys, t_target, q, v, err)
    class(cvode_solver_t), intent(inout) :: this
    class(ode2_system_t), intent(inout) :: sys
    real(wp), intent(in) :: t_target
    real(wp), intent(out) :: q(:), v(:)
    type(error_t), intent(inout) :: err
    integer(c_int) :: flag
    real(c_double) :: t_reached(1)
    integer(c_long) :: n_steps_now(1)
    integer(i8) :: steps_left

    ! CVODE's step limit applies to one CVode call; ours to the whole run.
    call check(solver, FCVodeGetNumSteps(this%mem, n_steps_now), 'CVodeGetNumSteps', err)
    if (.not. err%ok()) return
    steps_left = this%max_steps - this%done%n_steps - int(n_steps_now(1), i8)
    if (steps_left < 1) then
      call err%set(ERR_NUMERIC, 'CVODE: max_steps reached before t = ' // real_str(t_target))
      return
    end if
    call check(solver, FCVodeSetMaxNumSteps(this%mem, int(steps_left, c_long)), &
      'CVodeSetMaxNumSteps', err)
    if (.not. err%ok()) return

    this%bridge%bad_status = 0
    if (.not. sys%wants_steps()) then
      flag = FCVode(this%mem, t_target, this%y, t_reached, CV_NORMAL)
      if (flag < 0) then
        call report_failure(this, flag, t_target, err)
        return
      end if
      call get_state(this%y, q, v)
      return
    end if
    ! Step by step, each accepted state to the system, then CVODE's interpolant at t_target
    ! (what CV_NORMAL does inside). The last call may have stepped past this target already.
    flag = FCVodeGetCurrentTime(this%mem, t_reached)
    if (flag < 0) then
      call report_failure(this, flag, t_target, err)
      return
    end if
    do while (t_reached(1) < t_target)
      if (steps_left < 1) then
        call err%set(ERR_NUMERIC, 'CVODE: max_steps reached before t = ' // real_str(t_target))
        return
      end if
      steps_left = steps_left - 1
      flag = FCVode(this%mem, t_target, this%y, t_reached, CV_ONE_STEP)
      if (flag < 0) then
        call report_failure(this, flag, t_target, err)
        return
      end if
      call get_state(this%y, q, v)
      call sys%step_accepted(t_reached(1), q, v)
    end do
    ! Also where a step ended on t_target: this%y may hold an earlier target's interpolant.
    flag = FCVodeGetDky(this%mem, t_target, 0_c_int, this%y)
    if (flag < 0) then
      call report_failure(this, flag, t_target, err)
      return
    end if
    call get_state(this%y, q, v)
  end subroutine cvode_advance

  !> Start again at (t, q, v) after a jump of a(t, ...): CVODE's history is no longer valid.
  subroutine cvode_restart(this, sys, t, q, v, t_stop, t_lo, t_hi, err)
    class(cvode_solver_t), intent(inout) :: this
    class(ode2_system_t), intent(inout) :: sys
    real(wp), intent(in) :: t, q(:), v(:), t_stop, t_lo, t_hi
    type(error_t), intent(inout) :: err
    type(integrator_stats_t) :: so_far
    ! Through a local: this%done is part of `this`, which get_stats also reads.
    call this%get_stats(so_far)
    this%done = so_far
    this%done%n_restarts = this%done%n_restarts + 1
    this%bridge%steps_before = this%done%n_steps
    this%bridge%t_lo = t_lo
    this%bridge%t_hi = t_hi
    call put_state(this%y, q, v)
    call check(solver, FCVodeReInit(this%mem, t, this%y), 'CVodeReInit', err)
    call check(solver, FCVodeSetStopTime(this%mem, t_stop), 'CVodeSetStopTime', err)
  end subroutine cvode_restart

  subroutine cvode_get_stats(this, stats)
    class(cvode_solver_t), intent(in) :: this
    type(integrator_stats_t), intent(out) :: stats
    integer(c_long) :: n(1)
    integer(c_int) :: flag

    stats = this%done
    if (.not. c_associated(this%mem)) return
    flag = FCVodeGetNumSteps(this%mem, n)
    if (flag == 0) stats%n_steps = stats%n_steps + int(n(1), i8)
    flag = FCVodeGetNumJacEvals(this%mem, n)
    if (flag == 0) stats%n_jac_evals = stats%n_jac_evals + int(n(1), i8)
    flag = FCVodeGetNumLinSolvSetups(this%mem, n)
    if (flag == 0) stats%n_factorisations = stats%n_factorisations + int(n(1), i8)
    flag = FCVodeGetNumErrTestFails(this%mem, n)
    if (flag == 0) stats%n_err_test_fails = stats%n_err_test_fails + int(n(1), i8)
    flag = FCVodeGetNumNonlinSolvConvFails(this%mem, n)
    if (flag == 0) stats%n_nonlin_fails = stats%n_nonlin_fails + int(n(1), i8)
    ! Counted by our callback: CVODE's own count leaves out its difference-quotient Jacobian.
    stats%n_rhs_evals = this%bridge%n_accel
  end subroutine cvode_get_stats

  !> Free all SUNDIALS memory; safe to call more than once.
  subroutine cvode_finish(this)
    class(cvode_solver_t), intent(inout) :: this
    integer(c_int) :: flag
    if (c_associated(this%mem)) call FCVodeFree(this%mem)
    this%mem = c_null_ptr
    if (associated(this%ls)) flag = FSUNLinSolFree(this%ls)
    this%ls => null()
    if (associated(this%jmat)) call FSUNMatDestroy(this%jmat)
    this%jmat => null()
    call close_sundials(this%ctx, this%y, this%bridge)
  end subroutine cvode_finish

  subroutine report_failure(this, flag, t_target, err)
    type(cvode_solver_t), intent(in) :: this
    integer(c_int), intent(in) :: flag
    real(wp), intent(in) :: t_target
    type(error_t), intent(inout) :: err
    real(c_double) :: t_now(1)

    t_now(1) = t_target
    if (FCVodeGetCurrentTime(this%mem, t_now) /= 0) t_now(1) = t_target
    call set_failure(solver, t_now(1), t_target, flag, &
      cvode_return_flag_name(int(flag, c_long)), this%bridge, '', err)
  end subroutine report_failure

  ! ---- C callbacks --------------------------------------------------------------------------

  !> sundials_rhs, and the progress line when one is due: polled per evaluation, as one CVode
  !> call may take very many steps between two output times.
  integer(c_int) function cvode_rhs(t, y_nv, ydot_nv, user_data) result(ierr) bind(C)
    real(c_double), value :: t
    type(N_Vector) :: y_nv, ydot_nv
    type(c_ptr), value :: user_data
    type(sundials_bridge_t), pointer :: b
    integer(c_long) :: n(1)
    ierr = sundials_rhs(t, y_nv, ydot_nv, user_data)
    call c_f_pointer(user_data, b)
    if (.not. associated(b%progress)) return
    if (.not. b%progress%due()) return
    if (FCVodeGetNumSteps(b%mem, n) /= 0) n = 0
    call b%progress%report_time(real(t, wp), b%steps_before + int(n(1), i8))
  end function cvode_rhs

  !> J = df/dy = [[0, I], [da/dq, da/dv]], column-major in CVODE's dense matrix.
  integer(c_int) function cvode_jac(t, y_nv, fy_nv, jac_sm, user_data, tmp1, tmp2, tmp3) &
      result(ierr) bind(C)
    real(c_double), value :: t
    type(N_Vector) :: y_nv, fy_nv, tmp1, tmp2, tmp3
    type(SUNMatrix) :: jac_sm
    type(c_ptr), value :: user_data
    type(sundials_bridge_t), pointer :: b
    real(c_double), pointer :: y(:), jac(:, :)
    integer :: n, i, status

    call c_f_pointer(user_data, b)
    n = b%n
    y => FN_VGetArrayPointer(y_nv)
    call b%sys%jacobian(clamped(b, t), y(1:n), y(n + 1:2 * n), b%dadq, b%dadv, status)
    call note_status(b, status, t, 'jacobian')
    ierr = sundials_status(status)
    if (status /= 0) return
    jac => dense_matrix_data(jac_sm, 2 * n)
    jac(1:n, :) = 0
    do i = 1, n
      jac(i, n + i) = 1
    end do
    jac(n + 1:2 * n, 1:n) = b%dadq
    jac(n + 1:2 * n, n + 1:2 * n) = b%dadv
  end function cvode_jac

  ! ---- helpers ------------------------------------------------------------------------------

  !> FSUNDenseMatrix_Data of SUNDIALS 6.4 returns a pointer of size 1: rebuild it with the
  !> real shape.
  function dense_matrix_data(mat, m) result(a)
    type(SUNMatrix), intent(inout), target :: mat
    integer, intent(in) :: m
    real(c_double), pointer :: a(:, :)
    real(c_double), pointer :: first(:)
    first => FSUNDenseMatrix_Data(mat)
    call c_f_pointer(c_loc(first(1)), a, [m, m])
  end function dense_matrix_data
end module integrators_cvode
