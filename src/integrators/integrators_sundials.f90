!> What the two SUNDIALS solvers (integrators_cvode: CVODE BDF, integrators_arkode: ARKODE
!> ERKStep) have in common: both integrate the first-order form of q'' = a(t, q, v),
!>     y = (q, v),   y' = (v, a(t, q, v)),
!> with the same right-hand side callback, so the bridge object that the C callbacks reach, the
!> callbacks themselves, the packing of y and the error messages are written once, here.
!>
!> This module, integrators_cvode and integrators_arkode are the only ones of flexmor that talk
!> to SUNDIALS, so that the move to SUNDIALS 7 (SUNComm, fsundials_core_mod, ARKODE's new API)
!> stays in three files. The system is reached from the C callbacks through user_data, which
!> points to a heap-allocated bridge object: no module variables, so several models can run in
!> one process.
module integrators_sundials
  use, intrinsic :: iso_c_binding, only: c_ptr, c_null_ptr, c_int, c_long, c_double, c_int64_t, &
    c_char, c_size_t, c_f_pointer, c_associated
  use core_kinds, only: wp, i8
  use core_strings, only: int_str, real_str
  use core_error, only: error_t, ERR_NUMERIC, ERR_INTERNAL
  use integrators_system, only: ode2_system_t
  use core_progress, only: progress_t
  use fsundials_context_mod, only: FSUNContext_Create, FSUNContext_Free
  use fsundials_nvector_mod, only: N_Vector, FN_VDestroy, FN_VGetArrayPointer
  use fnvector_serial_mod, only: FN_VNew_Serial
  implicit none
  private
  public :: sundials_bridge_t, new_bridge, open_sundials, close_sundials, sundials_rhs, &
    sundials_error_handler, clamped, note_status, sundials_status, put_state, get_state, check, &
    set_failure, cvode_return_flag_name, erk_return_flag_name

  !> What the C callbacks need; lives on the heap so its address (the user_data) is fixed.
  type :: sundials_bridge_t
    class(ode2_system_t), pointer :: sys => null()
    integer :: n = 0
    !> accel is evaluated at times clamped into [t_lo, t_hi], strictly inside the segment
    !> between breakpoints, so that a(t) jumping at a breakpoint is seen from the right side.
    real(wp) :: t_lo = -huge(1.0_wp), t_hi = huge(1.0_wp)
    integer(i8) :: n_accel = 0
    !> The last non-zero status of a callback, for the error message (and ERKStep's retries).
    integer :: bad_status = 0
    real(wp) :: bad_time = 0
    character(len=8) :: bad_where = ''
    !> SUNDIALS' own message of its last error (from the error handler).
    character(len=:), allocatable :: message
    !> Work arrays of CVODE's Jacobian callback, allocated only with the system's Jacobian.
    real(wp), allocatable :: dadq(:, :), dadv(:, :)
    !> Progress lines from inside a long solver call (CVODE polls per right-hand side): the
    !> solver's memory to count its steps, and the steps before its last re-initialisation.
    type(progress_t), pointer :: progress => null()
    type(c_ptr) :: mem = c_null_ptr
    integer(i8) :: steps_before = 0
  end type sundials_bridge_t

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

    !> The names of the flags, called directly: the strings are malloc'ed (set_failure frees
    !> them), and the Fortran wrappers of SUNDIALS 6.4 (FCVodeGetReturnFlagName,
    !> FERKStepGetReturnFlagName) never free them.
    function cvode_return_flag_name(flag) bind(C, name='CVodeGetReturnFlagName') result(name)
      import :: c_ptr, c_long
      integer(c_long), value :: flag
      type(c_ptr) :: name
    end function cvode_return_flag_name

    function erk_return_flag_name(flag) bind(C, name='ERKStepGetReturnFlagName') result(name)
      import :: c_ptr, c_long
      integer(c_long), value :: flag
      type(c_ptr) :: name
    end function erk_return_flag_name
  end interface

contains

  !> On the heap, for its address to stay fixed while SUNDIALS holds it; close_sundials frees it.
  function new_bridge(sys, n, t_lo, t_hi) result(b)
    class(ode2_system_t), intent(inout), target :: sys
    integer, intent(in) :: n
    real(wp), intent(in) :: t_lo, t_hi
    type(sundials_bridge_t), pointer :: b
    allocate(b)
    b%sys => sys
    b%n = n
    b%t_lo = t_lo
    b%t_hi = t_hi
  end function new_bridge

  !> A SUNDIALS context and the state vector y = (q, v) in it; `solver` names the solver in
  !> the error messages.
  subroutine open_sundials(solver, q, v, ctx, y, err)
    character(len=*), intent(in) :: solver
    real(wp), intent(in) :: q(:), v(:)
    type(c_ptr), intent(inout) :: ctx
    type(N_Vector), pointer, intent(inout) :: y
    type(error_t), intent(inout) :: err
    call check(solver, FSUNContext_Create(c_null_ptr, ctx), 'SUNContext_Create', err)
    if (.not. err%ok()) return
    y => FN_VNew_Serial(int(size(q) + size(v), c_int64_t), ctx)
    if (.not. associated(y)) then
      call err%set(ERR_INTERNAL, solver // ': could not create the state vector')
      return
    end if
    call put_state(y, q, v)
  end subroutine open_sundials

  !> Free what open_sundials and new_bridge made, after the solver's own memory; safe to call
  !> more than once.
  subroutine close_sundials(ctx, y, bridge)
    type(c_ptr), intent(inout) :: ctx
    type(N_Vector), pointer, intent(inout) :: y
    type(sundials_bridge_t), pointer, intent(inout) :: bridge
    integer(c_int) :: flag
    if (associated(y)) call FN_VDestroy(y)
    y => null()
    if (c_associated(ctx)) flag = FSUNContext_Free(ctx)
    ctx = c_null_ptr
    if (associated(bridge)) deallocate(bridge)
  end subroutine close_sundials

  !> The error of a failed CVode or ERKStepEvolve call. flag_name is SUNDIALS' malloc'ed name of
  !> the flag, freed here; `note` goes before SUNDIALS' own message.
  subroutine set_failure(solver, t_now, t_target, flag, flag_name, b, note, err)
    character(len=*), intent(in) :: solver
    real(wp), intent(in) :: t_now, t_target
    integer(c_int), intent(in) :: flag
    type(c_ptr), intent(in) :: flag_name
    type(sundials_bridge_t), intent(in) :: b
    character(len=*), intent(in) :: note
    type(error_t), intent(inout) :: err
    character(len=:), allocatable :: msg

    msg = solver // ' failed at t = ' // real_str(t_now) // ' (integrating to ' // &
      real_str(t_target) // '): flag ' // int_str(int(flag)) // ' ' // c_string(flag_name)
    call c_free(flag_name)
    if (b%bad_status /= 0) msg = msg // '; ' // trim(b%bad_where) // ' returned status ' // &
      int_str(b%bad_status) // ' at t = ' // real_str(b%bad_time)
    msg = msg // note
    if (allocated(b%message)) msg = msg // '; ' // b%message
    call err%set(ERR_NUMERIC, msg)
  end subroutine set_failure

  ! ---- C callbacks --------------------------------------------------------------------------

  !> f(t, y) = (v, a(t, q, v)): CVRhsFn and ARKRhsFn alike.
  integer(c_int) function sundials_rhs(t, y_nv, ydot_nv, user_data) result(ierr) bind(C)
    real(c_double), value :: t
    type(N_Vector) :: y_nv, ydot_nv
    type(c_ptr), value :: user_data
    type(sundials_bridge_t), pointer :: b
    real(c_double), pointer :: y(:), ydot(:)
    integer :: n, status

    call c_f_pointer(user_data, b)
    n = b%n
    y => FN_VGetArrayPointer(y_nv)
    ydot => FN_VGetArrayPointer(ydot_nv)
    ydot(1:n) = y(n + 1:2 * n)
    call b%sys%accel(clamped(b, t), y(1:n), y(n + 1:2 * n), ydot(n + 1:2 * n), status)
    b%n_accel = b%n_accel + 1
    call note_status(b, status, t, 'accel')
    ierr = sundials_status(status)
  end function sundials_rhs

  !> Keep SUNDIALS' message for our error instead of letting it print to stderr.
  subroutine sundials_error_handler(error_code, module_name, function_name, msg, user_data) bind(C)
    integer(c_int), value :: error_code
    type(c_ptr), value :: module_name, function_name, msg, user_data
    type(sundials_bridge_t), pointer :: b
    if (error_code >= 0) return
    call c_f_pointer(user_data, b)
    b%message = c_string(function_name) // ': ' // c_string(msg)
  end subroutine sundials_error_handler

  ! ---- helpers ------------------------------------------------------------------------------

  pure real(wp) function clamped(b, t)
    type(sundials_bridge_t), intent(in) :: b
    real(c_double), intent(in) :: t
    clamped = min(max(real(t, wp), b%t_lo), b%t_hi)
  end function clamped

  subroutine note_status(b, status, t, where)
    type(sundials_bridge_t), intent(inout) :: b
    integer, intent(in) :: status
    real(c_double), intent(in) :: t
    character(len=*), intent(in) :: where
    if (status == 0) return
    b%bad_status = status
    b%bad_time = t
    b%bad_where = where
  end subroutine note_status

  !> Our callbacks' convention (> 0 recoverable, < 0 fatal) is SUNDIALS'; only the size differs.
  pure integer(c_int) function sundials_status(status)
    integer, intent(in) :: status
    sundials_status = int(sign(1, status), c_int)
    if (status == 0) sundials_status = 0
  end function sundials_status

  subroutine put_state(y_nv, q, v)
    type(N_Vector), intent(inout) :: y_nv
    real(wp), intent(in) :: q(:), v(:)
    real(c_double), pointer :: y(:)
    y => FN_VGetArrayPointer(y_nv)
    y(1:size(q)) = q
    y(size(q) + 1:) = v
  end subroutine put_state

  subroutine get_state(y_nv, q, v)
    type(N_Vector), intent(inout) :: y_nv
    real(wp), intent(out) :: q(:), v(:)
    real(c_double), pointer :: y(:)
    y => FN_VGetArrayPointer(y_nv)
    q = y(1:size(q))
    v = y(size(q) + 1:)
  end subroutine get_state

  !> The calls checked here fail only on arguments we got wrong: ERR_INTERNAL, naming the
  !> solver and the call.
  subroutine check(solver, flag, what, err)
    character(len=*), intent(in) :: solver
    integer(c_int), intent(in) :: flag
    character(len=*), intent(in) :: what
    type(error_t), intent(inout) :: err
    if (flag /= 0) call err%set(ERR_INTERNAL, solver // ': ' // what // ' returned ' // &
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
end module integrators_sundials
