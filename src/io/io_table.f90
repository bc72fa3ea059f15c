!> Two-column tables (time, value) from CSV files, for tabulated motions (`&motion law =
!> 'table', file = ...`). One point per line, the two numbers separated by a comma, semicolon or
!> blanks; blank lines are skipped and the first line may be a header (text that is not two
!> numbers). Errors name the file and line.
module io_table
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_INPUT
  use core_strings, only: int_str
  implicit none
  private
  public :: read_table_csv, relative_to

contains

  !> `path` as seen from the folder of the file `base` (absolute paths stay as they are).
  pure function relative_to(base, path) result(full)
    character(len=*), intent(in) :: base, path
    character(len=:), allocatable :: full
    if (len(path) > 0) then
      if (path(1:1) == '/') then
        full = path
        return
      end if
    end if
    full = base(1:index(base, '/', back=.true.)) // path
  end function relative_to

  !> Read the columns of the CSV file `path` into `times` and `values`.
  subroutine read_table_csv(path, times, values, err)
    character(len=*), intent(in) :: path
    real(wp), allocatable, intent(out) :: times(:), values(:)
    type(error_t), intent(out) :: err
    character(len=4096) :: line
    character(len=256) :: msg
    real(wp) :: x(2)
    integer :: u, ios, n_line
    logical :: ok
    allocate(times(0), values(0))
    open(newunit=u, file=path, status='old', action='read', iostat=ios, iomsg=msg)
    if (ios /= 0) then
      call err%set(ERR_INPUT, 'cannot open table file ''' // path // ''': ' // &
        reason(msg))
      return
    end if
    n_line = 0
    do
      read(u, '(a)', iostat=ios, iomsg=msg) line
      if (is_iostat_end(ios)) exit
      n_line = n_line + 1
      if (ios /= 0) then
        call err%set(ERR_INPUT, '''' // path // ''' line ' // int_str(n_line) // ': ' // &
          reason(msg))
        exit
      end if
      if (len_trim(line) == 0) cycle
      call two_numbers(line, x, ok)
      if (ok) then
        times = [times, x(1)]
        values = [values, x(2)]
      else if (n_line > 1 .or. size(times) > 0) then
        call err%set(ERR_INPUT, '''' // path // ''' line ' // int_str(n_line) // &
          ': expected two finite numbers (time, value), got ''' // trim(line) // '''')
        exit
      end if
    end do
    close(u)
  end subroutine read_table_csv

  !> The two numbers of a line, if that is all it holds.
  subroutine two_numbers(line, x, ok)
    character(len=*), intent(in) :: line
    real(wp), intent(out) :: x(2)
    logical, intent(out) :: ok
    character(len=*), parameter :: SEP = ' ,;' // achar(9) // achar(13)
    integer :: pos, first, last, n, ios
    ok = .false.
    x = 0.0_wp
    n = 0
    pos = 1
    do
      first = verify(line(pos:), SEP)
      if (first == 0) exit
      first = pos + first - 1
      last = scan(line(first:), SEP)
      if (last == 0) then
        last = len(line)
      else
        last = first + last - 2
      end if
      n = n + 1
      if (n > 2) return
      ! A token list-directed input would read otherwise ('2*1', '1/') is not a number.
      if (scan(line(first:last), '*/') > 0) return
      read(line(first:last), *, iostat=ios) x(n)
      if (ios /= 0) return
      if (.not. ieee_is_finite(x(n))) return
      pos = last + 1
      if (pos > len(line)) exit
    end do
    ok = n == 2
  end subroutine two_numbers

  !> gfortran's iomsg repeats the file name; keep its reason.
  pure function reason(msg) result(r)
    character(len=*), intent(in) :: msg
    character(len=:), allocatable :: r
    integer :: k
    k = index(msg, ': ', back=.true.)
    r = trim(msg(k + 1:))
    if (k > 0) r = trim(msg(k + 2:))
  end function reason
end module io_table
