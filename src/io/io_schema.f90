!> The scene schema: every input variable of a scene file declared once, with its group,
!> type, unit, default, range, choices and a short description. The scene reader (io_scene)
!> takes defaults, range checks and keyword choices from here, the sweep (sweep_spec) its type
!> checks, and a test compares it with the tables of docs/input.md (`flexmor --schema` prints
!> it). A variable that is read but not declared here is an internal error.
module io_schema
  use core_kinds, only: wp
  use core_strings, only: real_str, lower_case
  use io_schema_types, only: var_spec_t, SCENE_GROUPS, SINGLE_GROUPS, VK_REAL, VK_INT, &
    VK_LOGICAL, VK_STRING, VK_CHOICE, VK_REAL_LIST, VK_STRING_LIST, VK_CHOICE_LIST
  use io_schema_tables, only: SCHEMA
  implicit none
  private
  public :: var_spec_t, SCHEMA, SCENE_GROUPS, SINGLE_GROUPS, find_spec, kind_name, &
    bound_problem, range_text, choice_list, has_choice, write_schema
  public :: VK_REAL, VK_INT, VK_LOGICAL, VK_STRING, VK_CHOICE, VK_REAL_LIST, VK_STRING_LIST, &
    VK_CHOICE_LIST

contains

  !> Index of group%name in SCHEMA, 0 if it is not declared. Names are case-insensitive, as
  !> in the scene file (`E` and `e`).
  pure integer function find_spec(group, name) result(idx)
    character(len=*), intent(in) :: group, name
    do idx = 1, size(SCHEMA)
      if (SCHEMA(idx)%group == lower_case(group) .and. &
          lower_case(SCHEMA(idx)%name) == lower_case(name)) return
    end do
    idx = 0
  end function find_spec

  pure function kind_name(kind) result(name)
    integer, intent(in) :: kind
    character(len=:), allocatable :: name
    select case (kind)
    case (VK_REAL); name = 'real'
    case (VK_INT); name = 'int'
    case (VK_LOGICAL); name = 'logical'
    case (VK_STRING); name = 'string'
    case (VK_CHOICE); name = 'keyword'
    case (VK_REAL_LIST); name = 'real list'
    case (VK_STRING_LIST); name = 'string list'
    case (VK_CHOICE_LIST); name = 'keyword list'
    case default; name = 'unknown'
    end select
  end function kind_name

  !> '' if x lies in the declared range, else what is wrong ("must be positive, got -1").
  pure function bound_problem(spec, x) result(msg)
    type(var_spec_t), intent(in) :: spec
    real(wp), intent(in) :: x
    character(len=:), allocatable :: msg
    logical :: low, high, tiny_x
    msg = ''
    low = x < spec%lower .or. (spec%lower_open .and. x == spec%lower)
    high = x > spec%upper .or. (spec%upper_open .and. x == spec%upper)
    tiny_x = x /= 0 .and. abs(x) < spec%min_magnitude
    if (.not. (low .or. high .or. tiny_x)) return
    if (spec%min_magnitude > 0 .or. spec%upper < huge(1.0_wp)) then
      msg = range_text(spec)
      if (msg(1:1) /= '0') msg = 'in ' // msg
      ! 'positive' first where 0 and below are out: the usual slip is a 0 or a sign.
      if (x <= 0 .and. (spec%lower > 0 .or. (spec%lower == 0 .and. spec%lower_open))) then
        msg = 'must be positive, ' // msg
      else if (x < 0 .and. spec%lower >= 0) then
        msg = 'must not be negative (' // msg // ')'
      else
        msg = 'must be ' // msg
      end if
    else if (spec%lower == 0 .and. spec%lower_open) then
      msg = 'must be positive'
    else if (spec%lower == 0) then
      msg = 'must not be negative'
    else
      msg = 'must be at least ' // real_str(spec%lower)
    end if
    msg = msg // ', got ' // bound_str(x)
  end function bound_problem

  !> The declared range as text ('' for none): '[1e-30, 1e30]', '0 or in [1e-30, 1e30]',
  !> '0 or of magnitude in [1e-30, 1e30]', '(0, inf)'. Messages and `--schema` show the same.
  pure function range_text(spec) result(text)
    type(var_spec_t), intent(in) :: spec
    character(len=:), allocatable :: text
    real(wp) :: lo
    text = ''
    if (.not. (spec%lower > -huge(1.0_wp) .or. spec%upper < huge(1.0_wp))) return
    lo = spec%lower
    if (spec%min_magnitude > 0) then
      if (spec%lower < 0 .and. -spec%lower == spec%upper) then
        text = '0 or of magnitude in [' // bound_str(spec%min_magnitude) // ', ' // &
          bound_str(spec%upper) // ']'
        return
      end if
      if (spec%lower <= 0 .and. spec%upper >= 0) text = '0 or in '
      lo = max(spec%lower, spec%min_magnitude)
    end if
    text = text // merge('(', '[', spec%lower_open .and. lo == spec%lower) // bound_str(lo) // &
      ', ' // trim(merge('inf        ', bound_str_pad(spec%upper), spec%upper >= huge(1.0_wp))) &
      // merge(')', ']', spec%upper_open .or. spec%upper >= huge(1.0_wp))
  contains
    pure function bound_str_pad(x) result(t)
      real(wp), intent(in) :: x
      character(len=11) :: t
      t = bound_str(x)
    end function bound_str_pad
  end function range_text

  !> A bound as the schema writes it: 1e30, 1e-30, 0.5, 10000.
  pure function bound_str(x) result(s)
    real(wp), intent(in) :: x
    character(len=:), allocatable :: s
    character(len=32) :: buf
    integer :: e, m, ex
    if (x == 0 .or. (abs(x) >= 1.0e-3_wp .and. abs(x) < 1.0e6_wp)) then
      s = real_str(x)
      return
    end if
    write(buf, '(es22.14e3)') x
    s = trim(adjustl(buf))
    e = scan(s, 'Ee')
    read(s(e + 1:), *) ex
    m = verify(s(:e - 1), '0', back=.true.)
    if (s(m:m) == '.') m = m - 1
    write(buf, '(i0)') ex
    s = s(:m) // 'e' // trim(buf)
  end function bound_str

  !> The choices as text for messages: 'a, b or c'.
  pure function choice_list(spec) result(text)
    type(var_spec_t), intent(in) :: spec
    character(len=:), allocatable :: text, rest
    integer :: bar
    text = ''
    rest = trim(spec%choices)
    do
      bar = index(rest, '|')
      if (bar == 0) exit
      if (len(text) > 0) text = text // ', '
      text = text // rest(:bar - 1)
      rest = rest(bar + 1:)
    end do
    if (len(text) > 0) text = text // ' or '
    text = text // rest
  end function choice_list

  pure logical function has_choice(spec, value)
    type(var_spec_t), intent(in) :: spec
    character(len=*), intent(in) :: value
    has_choice = index('|' // trim(spec%choices) // '|', '|' // value // '|') > 0 .and. &
      len(value) > 0 .and. index(value, '|') == 0
  end function has_choice

  !> The schema as tab-separated text, one variable per line, with a header.
  subroutine write_schema(unit)
    integer, intent(in) :: unit
    integer :: i
    character(len=:), allocatable :: range
    type(var_spec_t) :: s
    write(unit, '(a)') 'group' // achar(9) // 'name' // achar(9) // 'type' // achar(9) // &
      'units' // achar(9) // 'default' // achar(9) // 'range' // achar(9) // 'choices' // &
      achar(9) // 'doc'
    do i = 1, size(SCHEMA)
      s = SCHEMA(i)
      range = range_text(s)
      write(unit, '(a)') trim(s%group) // achar(9) // trim(s%name) // achar(9) // &
          kind_name(s%kind) // achar(9) // trim(s%units) // achar(9) // &
          trim(merge('required        ', s%default, s%required)) // achar(9) // range // &
          achar(9) // trim(s%choices) // achar(9) // trim(s%doc)
    end do
  end subroutine write_schema
end module io_schema
