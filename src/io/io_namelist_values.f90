!> Conversion of namelist values to reals and integers, with messages that show the value
!> as the user wrote it.
module io_namelist_values
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use core_kinds, only: wp
  use core_strings, only: lower_case
  use io_namelist_lexer, only: item_t
  implicit none
  private
  public :: to_real, to_int, shown

  !> No scene quantity in SI units comes near it, while a product or a square of two such
  !> inputs (a mass times gravity, a coordinate squared in a length) still stays finite: at
  !> 1e300 those overflowed into a floating-point trap or a NaN deep in the model.
  real(wp), parameter :: MAX_MAGNITUDE = 1.0e100_wp

contains

  subroutine to_real(it, x, msg)
    type(item_t), intent(in) :: it
    real(wp), intent(out) :: x
    character(:), allocatable, intent(out) :: msg
    character(:), allocatable :: t
    integer :: ios
    x = 0
    msg = ''
    t = lower_case(it%text)
    select case (t(max(verify(t, '+-'), 1):))   ! sign stripped
    case ('nan', 'inf', 'infinity')
      if (.not. it%quoted) then
        msg = 'expected a finite real number, got ' // shown(it)
        return
      end if
    end select
    if (it%quoted .or. .not. is_real_syntax(t)) then
      msg = 'expected a real number, got ' // shown(it)
      return
    end if
    ! strtod would raise the overflow trap of debug builds, so reject huge values first
    if (decimal_exponent(t) > 308) then
      msg = 'real number out of range: ' // shown(it)
      return
    end if
    read(t, *, iostat=ios) x
    if (ios /= 0 .or. .not. ieee_is_finite(x)) then
      msg = 'expected a finite real number, got ' // shown(it)
    else if (abs(x) > MAX_MAGNITUDE) then
      msg = 'real number out of range: ' // shown(it) // ' (magnitudes above 1e100 are ' // &
        'not accepted)'
    end if
  end subroutine to_real

  subroutine to_int(it, x, msg)
    type(item_t), intent(in) :: it
    integer, intent(out) :: x
    character(:), allocatable, intent(out) :: msg
    integer :: ios
    x = 0
    msg = ''
    if (it%quoted .or. .not. is_int_syntax(it%text, signed=.true.)) then
      msg = 'expected an integer, got ' // shown(it)
      return
    end if
    read(it%text, *, iostat=ios) x
    if (ios /= 0) msg = 'integer out of range: ' // shown(it)
  end subroutine to_int

  pure logical function is_int_syntax(s, signed)
    character(*), intent(in) :: s
    logical, intent(in) :: signed
    integer :: i0
    i0 = 1
    if (signed .and. len(s) > 0) then
      if (scan(s(1:1), '+-') > 0) i0 = 2
    end if
    is_int_syntax = len(s) >= i0 .and. verify(s(i0:), '0123456789') == 0
  end function is_int_syntax

  !> [sign] digits [. digits] [(e|d) [sign] digits], with at least one mantissa digit.
  pure logical function is_real_syntax(s)
    character(*), intent(in) :: s   ! lower case
    integer :: i, n, nd
    n = len(s)
    is_real_syntax = .false.
    i = 1
    if (n == 0) return
    if (scan(s(1:1), '+-') > 0) i = 2
    nd = 0
    call digits(i, nd)
    if (i <= n) then
      if (s(i:i) == '.') then
        i = i + 1
        call digits(i, nd)
      end if
    end if
    if (nd == 0) return
    if (i <= n) then
      if (scan(s(i:i), 'ed') == 0) return
      i = i + 1
      if (i <= n) then
        if (scan(s(i:i), '+-') > 0) i = i + 1
      end if
      nd = 0
      call digits(i, nd)
      if (nd == 0) return
    end if
    is_real_syntax = i > n
  contains
    pure subroutine digits(i, nd)
      integer, intent(inout) :: i, nd
      do while (i <= n)
        if (scan(s(i:i), '0123456789') == 0) exit
        i = i + 1
        nd = nd + 1
      end do
    end subroutine digits
  end function is_real_syntax

  !> E such that |x| < 10**E (0 for zero) for text that passed is_real_syntax; capped so
  !> absurd exponents cannot overflow the integer.
  pure integer function decimal_exponent(s) result(e)
    character(*), intent(in) :: s
    integer :: i, k, dot, first, ex
    k = scan(s, 'ed')
    ex = 0
    if (k > 0) then
      do i = k + 1, len(s)
        if (scan(s(i:i), '0123456789') > 0) ex = min(ex * 10 + iachar(s(i:i)) - iachar('0'), 100000)
      end do
      if (scan(s(k + 1:), '-') > 0) ex = -ex
    else
      k = len(s) + 1
    end if
    dot = index(s(:k - 1), '.')
    if (dot == 0) dot = k
    first = scan(s(:k - 1), '123456789')
    e = 0
    if (first == 0) return
    if (first < dot) then
      e = ex + (dot - first)
    else
      e = ex - (first - dot - 1)
    end if
  end function decimal_exponent

  function shown(it) result(s)
    type(item_t), intent(in) :: it
    character(:), allocatable :: s
    if (it%quoted) then
      s = "string '" // it%text // "'"
    else
      s = "'" // it%text // "'"
    end if
  end function shown
end module io_namelist_values
