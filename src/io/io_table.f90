!> Two-column tables (time, value) from CSV files, for tabulated motions (`&motion law =
!> 'table', file = ...`). One point per line, the two numbers separated by a comma, semicolon or
!> blanks; blank lines are skipped and the first line with text may be a header (text that is
!> not two numbers). Numbers follow the scene's syntax and limits. Errors name the file and line.
module io_table
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_INPUT
  use core_strings, only: int_str, after_bom
  use io_namelist_lexer, only: item_t
  use io_namelist_values, only: to_real
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
  !> The file is read whole, as the scene is: a line of fixed length cut long lines silently
  !> (a point after 4096 blanks was skipped as a blank line).
  subroutine read_table_csv(path, times, values, err)
    character(len=*), intent(in) :: path
    real(wp), allocatable, intent(out) :: times(:), values(:)
    type(error_t), intent(out) :: err
    character(len=256) :: msg
    character(len=:), allocatable :: text, why
    real(wp) :: x(2)
    real(wp), allocatable :: grown(:, :)
    integer :: u, ios, n_line, n, pos, eol, next
    logical :: header_allowed
    allocate(times(0), values(0))
    open(newunit=u, file=path, status='old', access='stream', form='unformatted', &
      action='read', iostat=ios, iomsg=msg)
    if (ios /= 0) then
      call err%set(ERR_INPUT, 'cannot open table file ''' // path // ''': ' // reason(msg))
      return
    end if
    inquire(unit=u, size=n)
    allocate(character(max(n, 0)) :: text)
    ios = 0
    if (n > 0) read(u, iostat=ios, iomsg=msg) text
    close(u)
    if (ios /= 0 .or. n < 0) then
      if (n < 0) msg = 'size unknown'
      call err%set(ERR_INPUT, 'cannot read table file ''' // path // ''': ' // reason(msg))
      return
    end if
    allocate(grown(2, 64))
    n = 0
    n_line = 0
    header_allowed = .true.
    ! A UTF-8 byte order mark made the first point look like a header, dropped silently.
    pos = after_bom(text)
    do while (pos <= len(text))
      call line_end(text, pos, eol, next)
      n_line = n_line + 1
      associate (line => text(pos:eol))
        if (verify(line, ' ' // achar(9)) > 0) then
          call two_numbers(line, x, why)
          if (len(why) == 0) then
            if (n == size(grown, 2)) grown = reshape(grown, [2, 2 * n], pad=[0.0_wp])
            n = n + 1
            grown(:, n) = x
          else if (.not. header_allowed .or. len_trim(why) > 0) then
            call err%set(ERR_INPUT, '''' // path // ''' line ' // int_str(n_line) // &
              ': expected two finite numbers (time, value), got ''' // shown_line(line) // &
              '''' // why)
            return
          end if
          ! Only the first line with text may be a header (not a number out of range).
          header_allowed = .false.
        end if
      end associate
      pos = next
    end do
    times = grown(1, 1:n)
    values = grown(2, 1:n)
  end subroutine read_table_csv

  !> The line starting at `pos` ends at `eol` (its last character); the next starts at `next`.
  !> A line ends at LF, CR LF or a lone CR (old Mac files).
  pure subroutine line_end(text, pos, eol, next)
    character(len=*), intent(in) :: text
    integer, intent(in) :: pos
    integer, intent(out) :: eol, next
    integer :: k
    k = scan(text(pos:), achar(10) // achar(13))
    if (k == 0) then
      eol = len(text)
      next = len(text) + 1
      return
    end if
    eol = pos + k - 2
    next = eol + 2
    if (text(eol + 1:eol + 1) == achar(13) .and. next <= len(text)) then
      if (text(next:next) == achar(10)) next = next + 1
    end if
  end subroutine line_end

  !> A line as the message shows it: trimmed, and cut when very long.
  pure function shown_line(line) result(s)
    character(len=*), intent(in) :: line
    character(len=:), allocatable :: s
    s = trim(adjustl(line))
    if (len(s) > 80) s = s(:77) // '...'
  end function shown_line

  !> The two numbers of a line (why = ''), or why /= '': ' ' for text that is not two numbers,
  !> ' (REASON)' for a number out of the scene reader's range.
  subroutine two_numbers(line, x, why)
    character(len=*), intent(in) :: line
    real(wp), intent(out) :: x(2)
    character(len=:), allocatable, intent(out) :: why
    character(len=*), parameter :: SEP = ' ,;' // achar(9)
    character(len=:), allocatable :: msg
    integer :: pos, first, last, n
    why = ' '
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
      ! The scene's own number syntax and limits: a list-directed read trapped on 1e400
      ! (overflow) and took forms the scene refuses.
      call to_real(item_t(text=line(first:last)), x(n), msg)
      if (len(msg) > 0) then
        if (index(msg, 'out of range') > 0) why = ' (' // msg // ')'
        return
      end if
      pos = last + 1
      if (pos > len(line)) exit
    end do
    if (n == 2) why = ''
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
