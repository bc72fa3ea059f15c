!> Number-to-text helpers for messages, and case folding of keywords.
module core_strings
  use core_kinds, only: wp
  implicit none
  private
  public :: int_str, real_str, approx_str, hz_list, lower_case, after_bom, printable

contains

  !> ASCII lower case (keywords: mode classes, laws, coordinate names).
  pure function lower_case(text) result(s)
    character(len=*), intent(in) :: text
    character(len=len(text)) :: s
    integer :: i
    s = text
    do i = 1, len(s)
      if (s(i:i) >= 'A' .and. s(i:i) <= 'Z') s(i:i) = achar(iachar(s(i:i)) + 32)
    end do
  end function lower_case

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
    integer :: e, m
    write(buf, '(g0.10)') x
    s = trim(adjustl(buf))
    ! Trailing zeros of the mantissa say nothing: 50.00000000 -> 50, 0.1000E-02 -> 0.1E-02.
    e = scan(s, 'Ee')
    if (e == 0) e = len(s) + 1
    if (index(s(:e - 1), '.') == 0) return
    m = verify(s(:e - 1), '0', back=.true.)
    if (s(m:m) == '.') m = m - 1
    s = s(:m) // s(e:)
  end function real_str

  !> Frequencies for the progress lines, three decimals, comma-separated: '0.000, 4.866'.
  !> The f0.3 edit descriptor leaves the leading zero out ('.000', '-.000' for the rounding
  !> of a rigid-body mode), which read like a lost digit.
  pure function hz_list(f) result(s)
    real(wp), intent(in) :: f(:)
    character(len=:), allocatable :: s
    character(len=48) :: buf
    integer :: i, dot
    s = ''
    do i = 1, size(f)
      write(buf, '(f0.3)') f(i)
      dot = index(buf, '.')
      ! f0.3 of a frequency is far shorter than buf: the prefixed digit drops only blanks.
      if (dot == 1) then
        buf = '0' // buf(:len(buf) - 1)
      else if (dot == 2 .and. buf(1:1) == '-') then
        buf = '-0' // buf(2:len(buf) - 1)
      end if
      if (i > 1) s = s // ', '
      s = s // trim(buf)
    end do
  end function hz_list

  !> About three significant digits, for estimates in messages: 192, 13.3, 0.0441, 1.20E+09.
  pure function approx_str(x) result(s)
    real(wp), intent(in) :: x
    character(len=:), allocatable :: s
    character(len=32) :: buf, fmt
    integer :: decimals
    if (x == 0.0_wp) then
      s = '0'
    else if (abs(x) >= 1.0e-2_wp .and. abs(x) < 1.0e6_wp) then
      decimals = max(0, 2 - floor(log10(abs(x))))
      write(fmt, '(a,i0,a)') '(f0.', decimals, ')'
      write(buf, fmt) x
      s = trim(buf)
      if (s(1:1) == '.') s = '0' // s
      if (s(len(s):len(s)) == '.') s = s(:len(s) - 1)
    else if (abs(x) >= 9.9e99_wp .or. abs(x) < 1.0e-99_wp) then
      ! es10.2 drops the 'E' of a three-digit exponent ('3.00+298'): give it the room.
      write(buf, '(es12.2e3)') x
      s = trim(adjustl(buf))
    else
      write(buf, '(es10.2)') x
      s = trim(adjustl(buf))
    end if
  end function approx_str
  !> Where the text starts after a UTF-8 byte order mark (1 without one): Windows editors put
  !> it before scenes and tables, and the user cannot see it.
  pure integer function after_bom(text) result(pos)
    character(len=*), intent(in) :: text
    pos = 1
    if (len(text) < 3) return
    if (text(1:3) == char(239) // char(187) // char(191)) pos = 4
  end function after_bom

  !> Text with its control characters escaped (\t, \n, \r, \f, \v, else <0xNN>): messages
  !> quote what the user wrote, and a raw form feed, carriage return or escape byte from an
  !> input file garbles the terminal line or hides the message's start.
  pure function printable(text) result(s)
    character(len=*), intent(in) :: text
    character(len=:), allocatable :: s
    character(len=*), parameter :: HEX = '0123456789ABCDEF'
    integer :: i, c, n
    n = 0
    do i = 1, len(text)
      c = iachar(text(i:i))
      if (c < 32 .or. c == 127) n = n + 1
    end do
    if (n == 0) then
      s = text
      return
    end if
    s = ''
    do i = 1, len(text)
      c = iachar(text(i:i))
      select case (c)
      case (9); s = s // '\t'
      case (10); s = s // '\n'
      case (11); s = s // '\v'
      case (12); s = s // '\f'
      case (13); s = s // '\r'
      case (0:8, 14:31, 127)
        s = s // '<0x' // HEX(c / 16 + 1:c / 16 + 1) // HEX(mod(c, 16) + 1:mod(c, 16) + 1) // '>'
      case default; s = s // text(i:i)
      end select
    end do
  end function printable
end module core_strings
