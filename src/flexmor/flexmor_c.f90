!> The C interface of flexmor (include/flexmor.h documents every function): a run behind an
!> opaque handle, user control laws as C callbacks, and the dynamic results of a node. Each
!> handle owns its run and its callbacks with their user_data; nothing here is module-level
!> mutable state, so several handles (a sweep) live side by side in one process.
module flexmor_c
  use, intrinsic :: iso_c_binding, only: c_ptr, c_funptr, c_int, c_double, c_char, c_null_ptr, &
    c_null_char, c_loc, c_f_pointer, c_f_procpointer, c_associated
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_INPUT
  use model_control, only: control_law_t
  use analysis_run, only: run_t
  use analysis_results, only: results_t
  implicit none
  private
  public :: c_open, c_set_controller, c_execute, c_write, c_close, c_n_times, c_node_position

  !> What a handle points to.
  type :: handle_t
    type(run_t) :: run
  end type handle_t

  !> A law that calls a C function with the data the program gave with it.
  type, extends(control_law_t) :: c_law_t
    type(c_funptr) :: callback
    type(c_ptr) :: user_data = c_null_ptr
  contains
    procedure :: evaluate => c_law_evaluate
  end type c_law_t

  abstract interface
    function c_callback(t, n_y, y, y_dot, n_x, x, x_out, n_u, u, user_data) result(status) &
        bind(C)
      import :: c_double, c_int, c_ptr
      real(c_double), value :: t
      integer(c_int), value :: n_y, n_x, n_u
      real(c_double), intent(in) :: y(*), y_dot(*), x(*)
      real(c_double), intent(out) :: x_out(*), u(*)
      type(c_ptr), value :: user_data
      integer(c_int) :: status
    end function c_callback
  end interface

contains

  !> The law's arguments go through copies of C's double: wp need not be that kind.
  subroutine c_law_evaluate(this, t, y, y_dot, x, x_out, u, status)
    class(c_law_t), intent(in) :: this
    real(wp), intent(in) :: t, y(:), y_dot(:), x(:)
    real(wp), intent(out) :: x_out(:), u(:)
    integer, intent(out) :: status
    procedure(c_callback), pointer :: f
    ! At least one element each: C gets a valid pointer even for n_x = 0.
    real(c_double) :: yc(max(1, size(y))), ydc(max(1, size(y))), xc(max(1, size(x))), &
      xo(max(1, size(x))), uc(max(1, size(u)))
    call c_f_procpointer(this%callback, f)
    yc(1:size(y)) = real(y, c_double)
    ydc(1:size(y)) = real(y_dot, c_double)
    xc = 0.0_c_double
    xc(1:size(x)) = real(x, c_double)
    xo = 0.0_c_double
    uc = 0.0_c_double
    status = int(f(real(t, c_double), int(size(y), c_int), yc, ydc, int(size(x), c_int), xc, &
      xo, int(size(u), c_int), uc, this%user_data))
    x_out = real(xo(1:size(x)), wp)
    u = real(uc(1:size(u)), wp)
  end subroutine c_law_evaluate

  function c_open(path, errbuf, errlen) result(handle) bind(C, name='flexmor_open')
    character(kind=c_char), intent(in) :: path(*)
    character(kind=c_char), intent(out) :: errbuf(*)
    integer(c_int), value :: errlen
    type(c_ptr) :: handle
    type(handle_t), pointer :: h
    type(error_t) :: err
    integer(c_int) :: code
    allocate(h)
    call h%run%load(from_c(path), err)
    code = to_c(err, errbuf, errlen)
    if (code == 0) then
      handle = c_loc(h)
    else
      deallocate(h)
      handle = c_null_ptr
    end if
  end function c_open

  function c_set_controller(handle, label, callback, user_data, errbuf, errlen) result(code) &
      bind(C, name='flexmor_set_controller')
    type(c_ptr), value :: handle, user_data
    character(kind=c_char), intent(in) :: label(*)
    type(c_funptr), value :: callback
    character(kind=c_char), intent(out) :: errbuf(*)
    integer(c_int), value :: errlen
    integer(c_int) :: code
    type(handle_t), pointer :: h
    type(error_t) :: err
    if (of_handle(handle, h, err, 'flexmor_set_controller')) &
      call h%run%set_control_law(from_c(label), c_law_t(callback, user_data), err)
    code = to_c(err, errbuf, errlen)
  end function c_set_controller

  function c_execute(handle, errbuf, errlen) result(code) bind(C, name='flexmor_execute')
    type(c_ptr), value :: handle
    character(kind=c_char), intent(out) :: errbuf(*)
    integer(c_int), value :: errlen
    integer(c_int) :: code
    type(handle_t), pointer :: h
    type(error_t) :: err
    if (of_handle(handle, h, err, 'flexmor_execute')) call h%run%execute(err)
    code = to_c(err, errbuf, errlen)
  end function c_execute

  function c_write(handle, path, errbuf, errlen) result(code) bind(C, name='flexmor_write')
    type(c_ptr), value :: handle
    character(kind=c_char), intent(in) :: path(*)
    character(kind=c_char), intent(out) :: errbuf(*)
    integer(c_int), value :: errlen
    integer(c_int) :: code
    type(handle_t), pointer :: h
    type(error_t) :: err
    if (of_handle(handle, h, err, 'flexmor_write')) call h%run%write(from_c(path), err)
    code = to_c(err, errbuf, errlen)
  end function c_write

  subroutine c_close(handle) bind(C, name='flexmor_close')
    type(c_ptr), value :: handle
    type(handle_t), pointer :: h
    if (.not. c_associated(handle)) return
    call c_f_pointer(handle, h)
    deallocate(h)
  end subroutine c_close

  function c_n_times(handle) result(n) bind(C, name='flexmor_n_times')
    type(c_ptr), value :: handle
    integer(c_int) :: n
    type(handle_t), pointer :: h
    n = 0
    if (.not. c_associated(handle)) return
    call c_f_pointer(handle, h)
    if (allocated(h%run%time) .and. allocated(h%run%dyn%x_hist)) n = int(size(h%run%time), c_int)
  end function c_n_times

  function c_node_position(handle, node, n, time, x, y, errbuf, errlen) result(code) &
      bind(C, name='flexmor_node_position')
    type(c_ptr), value :: handle
    character(kind=c_char), intent(in) :: node(*)
    integer(c_int), value :: n, errlen
    real(c_double), intent(out) :: time(*), x(*), y(*)
    character(kind=c_char), intent(out) :: errbuf(*)
    integer(c_int) :: code
    type(handle_t), pointer :: h
    type(results_t) :: res
    type(error_t) :: err
    real(wp), allocatable :: pos(:, :)
    if (of_handle(handle, h, err, 'flexmor_node_position')) then
      call res%from_run(h%run)
      call res%node_position(from_c(node), 'dynamic', pos, err)
      if (err%ok() .and. n /= size(res%time)) call err%set(ERR_INPUT, &
        'flexmor_node_position: n must be flexmor_n_times(handle)')
      if (err%ok()) then
        time(1:n) = real(res%time, c_double)
        x(1:n) = real(pos(1, :), c_double)
        y(1:n) = real(pos(2, :), c_double)
      end if
    end if
    code = to_c(err, errbuf, errlen)
  end function c_node_position

  !> The run behind a handle; false (and an error) for NULL.
  logical function of_handle(handle, h, err, fn)
    type(c_ptr), intent(in) :: handle
    type(handle_t), pointer, intent(out) :: h
    type(error_t), intent(inout) :: err
    character(len=*), intent(in) :: fn
    h => null()
    of_handle = c_associated(handle)
    if (of_handle) then
      call c_f_pointer(handle, h)
    else
      call err%set(ERR_INPUT, fn // ': the handle is NULL (did flexmor_open fail?)')
    end if
  end function of_handle

  !> A NUL-terminated C string as a Fortran string.
  function from_c(s) result(f)
    character(kind=c_char), intent(in) :: s(*)
    character(len=:), allocatable :: f
    integer :: n, i
    n = 0
    do while (s(n + 1) /= c_null_char)
      n = n + 1
    end do
    allocate(character(len=n) :: f)
    do i = 1, n
      f(i:i) = s(i)
    end do
  end function from_c

  !> The error's code, its message into errbuf (NUL-terminated, cut to errlen - 1
  !> characters; '' when ok; nothing when errlen < 1).
  integer(c_int) function to_c(err, errbuf, errlen) result(code)
    type(error_t), intent(in) :: err
    character(kind=c_char), intent(out) :: errbuf(*)
    integer(c_int), intent(in) :: errlen
    integer :: i, n
    code = int(err%code, c_int)
    if (errlen < 1) return
    n = 0
    if (.not. err%ok()) n = min(len(err%message), errlen - 1)
    do i = 1, n
      errbuf(i) = err%message(i:i)
    end do
    errbuf(n + 1) = c_null_char
  end function to_c
end module flexmor_c
