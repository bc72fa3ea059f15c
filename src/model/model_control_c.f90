!> Control laws written in C (include/flexmor.h, flexmor_control_law): a function called with a
!> user_data pointer. Two routes give one, and the same C function serves both: a program
!> through the C interface (flexmor_set_controller: its function and its own user_data), and
!> a scene (&controller library, symbol, params: a function of a shared library, whose
!> user_data points to the params). Everything a law needs is in its object, so many models
!> with their laws live in one process (a sweep).
module model_control_c
  use, intrinsic :: iso_c_binding, only: c_ptr, c_funptr, c_int, c_double, c_char, &
    c_null_ptr, c_null_funptr, c_null_char, c_loc, c_f_pointer, c_f_procpointer, &
    c_associated
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_INPUT
  use core_strings, only: int_str
  use model_control, only: control_law_t
  implicit none
  private
  public :: c_law_t, load_library_law

  !> A law that calls a C function with user_data: the caller's pointer (`user_data`), or,
  !> for a law from a shared library, a pointer to the values of `params` (allocated only
  !> then, with none given: NULL).
  type, extends(control_law_t) :: c_law_t
    type(c_funptr) :: callback = c_null_funptr
    type(c_ptr) :: user_data = c_null_ptr
    !> dlopen's handle of the law's library. Never closed: copies of the law (a run keeps its
    !> own; the error check's second run gets one) would each have to count it, which
    !> intrinsic assignment cannot, and closing it once too often unmaps a function that
    !> another run still calls. Opening the same file again only counts up the loader's
    !> reference count, so a sweep's many models map it once.
    type(c_ptr) :: library = c_null_ptr
    real(c_double), allocatable :: params(:)
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

  interface
    !> model_control_dl.c: dlopen, dlsym; on failure NULL and dlerror()'s text in msg.
    type(c_ptr) function dl_open(path, msg, len) bind(C, name='flexmor_dl_open')
      import :: c_ptr, c_char, c_int
      character(kind=c_char), intent(in) :: path(*)
      character(kind=c_char), intent(out) :: msg(*)
      integer(c_int), value :: len
    end function dl_open
    type(c_ptr) function dl_data(handle, symbol, msg, len) bind(C, name='flexmor_dl_data')
      import :: c_ptr, c_char, c_int
      type(c_ptr), value :: handle
      character(kind=c_char), intent(in) :: symbol(*)
      character(kind=c_char), intent(out) :: msg(*)
      integer(c_int), value :: len
    end function dl_data
    type(c_funptr) function dl_function(handle, symbol, msg, len) &
        bind(C, name='flexmor_dl_function')
      import :: c_ptr, c_funptr, c_char, c_int
      type(c_ptr), value :: handle
      character(kind=c_char), intent(in) :: symbol(*)
      character(kind=c_char), intent(out) :: msg(*)
      integer(c_int), value :: len
    end function dl_function
  end interface

contains

  !> The function `symbol` of the shared library at `path` as a law with `params`
  !> (unallocated: none). A path without a '/' is a file in the current folder (dlopen would
  !> search the system's library folders for it). When the library declares the count of
  !> the values its law reads (`const int <symbol>_n_params`), `params` must have that many.
  !> Errors name the scene's variable; the caller names its &controller.
  subroutine load_library_law(path, symbol, params, law, err)
    character(len=*), intent(in) :: path, symbol
    real(wp), allocatable, intent(in) :: params(:)
    type(c_law_t), intent(out) :: law
    type(error_t), intent(out) :: err
    character(kind=c_char, len=1024) :: msg
    character(len=:), allocatable :: file
    type(c_ptr) :: count_at
    integer(c_int), pointer :: n_params
    integer :: n_given
    file = path
    if (index(path, '/') == 0) file = './' // path
    law%library = dl_open(file // c_null_char, msg, len(msg, c_int))
    if (.not. c_associated(law%library)) then
      call err%set(ERR_INPUT, 'variable ''library'': cannot open ''' // file // ''': ' // &
        c_text(msg))
      return
    end if
    law%callback = dl_function(law%library, symbol // c_null_char, msg, len(msg, c_int))
    if (.not. c_associated(law%callback)) then
      call err%set(ERR_INPUT, 'variable ''symbol'': the library ''' // file // ''' has no ' // &
        'function ''' // symbol // ''' (' // c_text(msg) // ')')
      return
    end if
    n_given = 0
    if (allocated(params)) then
      law%params = real(params, c_double)
      n_given = size(params)
    end if
    count_at = dl_data(law%library, symbol // '_n_params' // c_null_char, msg, len(msg, c_int))
    if (.not. c_associated(count_at)) return
    call c_f_pointer(count_at, n_params)
    if (n_params /= n_given) call err%set(ERR_INPUT, 'variable ''params'': the law ''' // &
      symbol // ''' reads ' // int_str(int(n_params)) // ' values (' // symbol // &
      '_n_params in its library), ' // int_str(n_given) // ' are given')
  end subroutine load_library_law

  !> The law's arguments go through copies of C's double: wp need not be that kind.
  subroutine c_law_evaluate(this, t, y, y_dot, x, x_out, u, status)
    class(c_law_t), intent(in) :: this
    real(wp), intent(in) :: t, y(:), y_dot(:), x(:)
    real(wp), intent(out) :: x_out(:), u(:)
    integer, intent(out) :: status
    if (.not. allocated(this%params)) then
      call call_law(this%user_data)
      return
    end if
    ! A copy of the params for the call: `this` (intent(in), no target) cannot be pointed at,
    ! and a law that writes into its user_data leaves the scene's values as they are.
    block
      real(c_double), target :: values(max(1, size(this%params)))
      values(1:size(this%params)) = this%params
      call call_law(c_loc(values))
    end block

  contains

    subroutine call_law(user_data)
      type(c_ptr), intent(in) :: user_data
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
      status = int(f(real(t, c_double), int(size(y), c_int), yc, ydc, int(size(x), c_int), &
        xc, xo, int(size(u), c_int), uc, user_data))
      x_out = real(xo(1:size(x)), wp)
      u = real(uc(1:size(u)), wp)
    end subroutine call_law
  end subroutine c_law_evaluate

  !> The text of a NUL-terminated buffer.
  pure function c_text(buffer) result(text)
    character(kind=c_char, len=*), intent(in) :: buffer
    character(len=:), allocatable :: text
    integer :: n
    n = index(buffer, c_null_char) - 1
    if (n < 0) n = len_trim(buffer)
    text = buffer(1:n)
  end function c_text
end module model_control_c
