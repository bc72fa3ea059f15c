!> Tokens and value lists of the namelist reader (io_namelist): the lexer shared by
!> the file parser and by the sweeps' text overrides (nml_group_t%set_raw).
module io_namelist_lexer
  use core_strings, only: lower_case
  implicit none
  private
  public :: item_t, token_t, next_token, parse_values, check_name, is_name, describe, at, &
    itoa
  public :: TK_EOF, TK_ERR, TK_AMP, TK_SLASH, TK_EQ, TK_COMMA, TK_WORD, TK_STRING, WHITE

  !> One value of a list; `rep` comes from a repeat count such as `3*0.0`.
  type :: item_t
    character(:), allocatable :: text   ! string contents (unquoted) or the bare token
    logical :: quoted = .false.
    integer :: rep = 1
  end type item_t

  integer, parameter :: TK_EOF = 0, TK_ERR = 1, TK_AMP = 2, TK_SLASH = 3, TK_EQ = 4, &
    TK_COMMA = 5, TK_WORD = 6, TK_STRING = 7

  type :: token_t
    integer :: kind = TK_EOF
    integer :: line = 0
    integer :: rep = 1
    character(:), allocatable :: text   ! word, string contents, group name or error message
  end type token_t

  character(*), parameter :: WHITE = ' ' // achar(9) // achar(10) // achar(13)
  character(*), parameter :: NAME_CHARS = 'abcdefghijklmnopqrstuvwxyz0123456789_'
  !> Values of one variable after repeat counts: far above any scene's lists (a table of a
  !> million points), far below what `2000000000*0.0` would allocate (16 GB, or an integer
  !> overflow of the count when several such items add up).
  integer, parameter :: MAX_VALUES = 10000000

contains

  subroutine parse_values(text, pos, line, items, msg, eline)
    character(*), intent(in) :: text
    integer, intent(inout) :: pos, line
    type(item_t), allocatable, intent(out) :: items(:)
    character(:), allocatable, intent(out) :: msg
    integer, intent(out) :: eline
    type(token_t) :: tok, after
    type(item_t) :: it
    type(item_t), allocatable :: tmp(:)
    integer :: pos0, line0, p, l, star, n, total
    logical :: want_value

    allocate(items(4))
    n = 0
    total = 0
    msg = ''
    eline = line
    want_value = .true.
    do
      pos0 = pos
      line0 = line
      call next_token(text, pos, line, tok)
      select case (tok%kind)
      case (TK_ERR)
        msg = tok%text
        eline = tok%line
        return
      case (TK_COMMA)
        if (want_value) then
          msg = 'empty value'
          eline = tok%line
          return
        end if
        want_value = .true.
        cycle
      case (TK_WORD)
        p = pos
        l = line
        call next_token(text, p, l, after)
        if (after%kind == TK_EQ) exit                 ! the word names the next variable
        it%text = tok%text
        it%quoted = .false.
        it%rep = 1
        star = index(tok%text, '*')
        if (star > 0) then
          eline = tok%line
          it%rep = repeat_count(tok%text(:star - 1))
          it%text = tok%text(star + 1:)
          if (it%rep < 1) then
            msg = "bad repeat count in '" // tok%text // "'"
            return
          else if (len(it%text) == 0) then
            msg = "empty value in '" // tok%text // "'"
            return
          end if
        end if
      case (TK_STRING)
        it%text = tok%text
        it%quoted = .true.
        it%rep = tok%rep
      case default
        exit
      end select
      if (it%rep > MAX_VALUES - total) then
        msg = 'more than ' // itoa(MAX_VALUES) // ' values (repeat counts included), at ' // &
          itoa(it%rep) // '*'
        eline = tok%line
        return
      end if
      total = total + it%rep
      if (n == size(items)) then   ! grow geometrically: long arrays stay linear
        allocate(tmp(2 * n))
        tmp(1:n) = items
        call move_alloc(tmp, items)
      end if
      n = n + 1
      items(n) = it
      want_value = .false.
    end do
    pos = pos0
    line = line0
    items = items(1:n)
    if (n == 0) msg = 'empty value'
  end subroutine parse_values

  subroutine next_token(text, pos, line, tok)
    character(*), intent(in) :: text
    integer, intent(inout) :: pos, line
    type(token_t), intent(out) :: tok
    integer :: start, n
    character :: c

    n = len(text)
    do while (pos <= n)
      c = text(pos:pos)
      if (c == '!') then
        do while (pos <= n)
          if (text(pos:pos) == achar(10)) exit
          pos = pos + 1
        end do
      else if (index(WHITE, c) > 0) then
        if (c == achar(10)) line = line + 1
        pos = pos + 1
      else
        exit
      end if
    end do
    tok%line = line
    tok%text = ''
    if (pos > n) return
    c = text(pos:pos)
    pos = pos + 1
    select case (c)
    case ('/')
      tok%kind = TK_SLASH
    case ('=')
      tok%kind = TK_EQ
    case (',')
      tok%kind = TK_COMMA
    case ('&')
      start = pos
      do while (pos <= n)
        if (index(NAME_CHARS, lower_case(text(pos:pos))) == 0) exit
        pos = pos + 1
      end do
      tok%text = lower_case(text(start:pos - 1))
      tok%kind = TK_AMP
      if (.not. is_name(tok%text)) then
        tok%kind = TK_ERR
        tok%text = "expected a group name after '&'"
      end if
    case ("'", '"')
      call read_string(text, pos, c, tok)
    case default
      start = pos - 1
      do while (pos <= n)
        if (scan(text(pos:pos), WHITE // ',=/!&''"') > 0) exit
        pos = pos + 1
      end do
      tok%kind = TK_WORD
      tok%text = text(start:pos - 1)
      ! `2*'abc'`: a repeat count written against a quoted string
      if (pos <= n .and. pos - start >= 2) then
        if (scan(text(pos:pos), '''"') > 0 .and. text(pos - 1:pos - 1) == '*' .and. &
            verify(text(start:pos - 2), '0123456789') == 0) then
          tok%rep = repeat_count(text(start:pos - 2))
          c = text(pos:pos)
          pos = pos + 1
          call read_string(text, pos, c, tok)
          if (tok%rep < 1 .and. tok%kind == TK_STRING) then
            tok%kind = TK_ERR
            tok%text = 'bad repeat count'
          end if
        end if
      end if
    end select
  end subroutine next_token

  !> Quoted string starting after the opening quote `q`; it must close on the same line.
  subroutine read_string(text, pos, q, tok)
    character(*), intent(in) :: text
    integer, intent(inout) :: pos
    character, intent(in) :: q
    type(token_t), intent(inout) :: tok
    character(:), allocatable :: s
    integer :: n

    n = len(text)
    s = ''
    do while (pos <= n)
      if (text(pos:pos) == achar(10)) exit
      if (text(pos:pos) == q) then
        if (pos < n) then
          if (text(pos + 1:pos + 1) == q) then   ! doubled quote stands for one
            s = s // q
            pos = pos + 2
            cycle
          end if
        end if
        pos = pos + 1
        tok%kind = TK_STRING
        tok%text = s
        return
      end if
      ! Control characters cannot be seen in the file and do not survive as text: a NUL cut
      ! a title short in the result file and made two labels one HDF5 name.
      if (iachar(text(pos:pos)) < 32 .and. text(pos:pos) /= achar(9) .and. &
          text(pos:pos) /= achar(13)) then
        tok%kind = TK_ERR
        tok%text = 'a string may not contain control characters (byte ' // &
          itoa(iachar(text(pos:pos))) // ')'
        return
      end if
      s = s // text(pos:pos)
      pos = pos + 1
    end do
    tok%kind = TK_ERR
    tok%text = 'unterminated string (a string must end on the line where it starts)'
  end subroutine read_string

  !> Empty msg when `name` is a valid variable name.
  subroutine check_name(name, msg)
    character(*), intent(in) :: name
    character(:), allocatable, intent(out) :: msg
    msg = ''
    if (index(name, '(') > 0) then
      msg = "indexed assignment '" // name // "' is not supported: give the whole array, " // &
        "e.g. x = 1.0, 2.0, 3.0"
    else if (.not. is_name(name)) then
      msg = "invalid variable name '" // name // "'"
    end if
  end subroutine check_name

  !> A letter followed by letters, digits or underscores (lower case).
  pure logical function is_name(s)
    character(*), intent(in) :: s
    is_name = .false.
    if (len(s) == 0) return
    is_name = index(NAME_CHARS(1:26), s(1:1)) > 0 .and. verify(s, NAME_CHARS) == 0
  end function is_name

  !> The n of `n*value`; 0 when it is not a positive integer.
  integer function repeat_count(s) result(n)
    character(*), intent(in) :: s
    integer :: ios
    n = 0
    if (len(s) == 0 .or. verify(s, '0123456789') /= 0) return
    read(s, *, iostat=ios) n
    if (ios /= 0) n = 0
  end function repeat_count

  function describe(tok) result(s)
    type(token_t), intent(in) :: tok
    character(:), allocatable :: s
    select case (tok%kind)
    case (TK_SLASH)
      s = "'/'"
    case (TK_EQ)
      s = "'='"
    case (TK_COMMA)
      s = "','"
    case (TK_AMP)
      s = "'&" // tok%text // "'"
    case (TK_STRING)
      s = "string '" // tok%text // "'"
    case default
      s = "'" // tok%text // "'"
    end select
  end function describe

  !> "path:line: "
  function at(path, line) result(s)
    character(*), intent(in) :: path
    integer, intent(in) :: line
    character(:), allocatable :: s
    s = path // ':' // itoa(line) // ': '
  end function at

  pure function itoa(i) result(s)
    integer, intent(in) :: i
    character(:), allocatable :: s
    character(24) :: buf
    write(buf, '(i0)') i
    s = trim(buf)
  end function itoa
end module io_namelist_lexer
