!> Number-to-text helpers for messages.
module core_strings
  use core_kinds, only: wp
  implicit none
  private
  public :: int_str, real_str

contains

  pure function int_str(i) result(s)
    integer, intent(in) :: i
    character(len=:), allocatable :: s
    character(len=16) :: buf
    write(buf, '(i0)') i
    s = trim(buf)
  end function int_str

  pure function real_str(x) result(s)
    real(wp), intent(in) :: x
    character(len=:), allocatable :: s
    character(len=32) :: buf
    write(buf, '(g0.10)') x
    s = trim(adjustl(buf))
  end function real_str
end module core_strings
