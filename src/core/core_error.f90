!> Error object passed up from library code to the driver (library code never stops).
!>
!> Convention (as in fpm): a procedure that can fail has `type(error_t), intent(out) :: err`;
!> `err%ok()` is true when nothing went wrong. The message is a single line naming the file,
!> namelist group and variable where that applies.
module core_error
  use core_strings, only: printable
  implicit none
  private
  public :: error_t
  public :: ERR_NONE, ERR_INPUT, ERR_MODEL, ERR_NUMERIC, ERR_IO, ERR_INTERNAL

  integer, parameter :: ERR_NONE = 0     !< no error
  integer, parameter :: ERR_INPUT = 1    !< bad or missing input
  integer, parameter :: ERR_MODEL = 2    !< model is inconsistent (solvability, singular mass)
  integer, parameter :: ERR_NUMERIC = 3  !< numerical failure (no convergence, NaN)
  integer, parameter :: ERR_IO = 4       !< file system or HDF5 failure
  integer, parameter :: ERR_INTERNAL = 5 !< a bug in flexmor

  type :: error_t
    integer :: code = ERR_NONE
    character(len=:), allocatable :: message
  contains
    procedure :: ok => error_ok
    procedure :: set => error_set
    procedure :: prefix => error_prefix
    procedure :: clear => error_clear
  end type error_t

contains

  pure logical function error_ok(this)
    class(error_t), intent(in) :: this
    error_ok = this%code == ERR_NONE
  end function error_ok

  !> Record an error; the first one wins so the root cause is reported.
  subroutine error_set(this, code, message)
    class(error_t), intent(inout) :: this
    integer, intent(in) :: code
    character(len=*), intent(in) :: message
    if (this%code /= ERR_NONE) return
    this%code = code
    ! One line on a terminal whatever the input held: control characters shown escaped.
    this%message = printable(message)
  end subroutine error_set

  !> Add context in front of an existing message ("file.nml: " // message).
  subroutine error_prefix(this, context)
    class(error_t), intent(inout) :: this
    character(len=*), intent(in) :: context
    if (this%code == ERR_NONE) return
    this%message = printable(context) // this%message
  end subroutine error_prefix

  subroutine error_clear(this)
    class(error_t), intent(inout) :: this
    this%code = ERR_NONE
    if (allocated(this%message)) deallocate(this%message)
  end subroutine error_clear
end module core_error
