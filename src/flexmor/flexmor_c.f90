!> The C interface of flexmor (include/flexmor.h documents every function): a run behind an
!> opaque handle, user control laws as C callbacks, and the dynamic results of a node. Each
!> handle owns its run and its callbacks with their user_data; nothing here is module-level
!> mutable state, so several handles (a sweep) live side by side in one process.
module flexmor_c
  use, intrinsic :: iso_c_binding, only: c_ptr, c_funptr, c_int, c_double, c_char, c_null_ptr, &
    c_null_char, c_loc, c_f_pointer, c_associated
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_INPUT
  use model_control_c, only: c_law_t
  use analysis_run, only: run_t
  use analysis_results, only: results_t
  implicit none
  private
  public :: c_open, c_set_controller, c_execute, c_write, c_close, c_n_times, c_node_position

  !> What a handle points to.
  type :: handle_t
    type(run_t) :: run
  end type handle_t

contains

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
    if (of_handle(handle, h, err, 'flexmor_set_controller')) call h%run%set_control_law( &
      from_c(label), c_law_t(callback=callback, user_data=user_data), err)
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
