!> Reader for scene files in (a hand-written subset of) Fortran namelist syntax.
!>
!> We parse ourselves rather than use `read(u, nml=...)`: gfortran names the offending value,
!> not the variable, on a type error and reads a missing group as end of file. Here every
!> message is one line naming file, line, group (with its occurrence) and variable.
!>
!> Values are kept as raw tokens and converted only by the typed getters, so one parse serves
!> every caller and a parameter sweep can override a value by text (`set_raw`) before use.
module io_namelist
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_INPUT
  use core_strings, only: lower_case, after_bom
  use io_namelist_lexer, only: item_t, token_t, next_token, parse_values, check_name, describe, &
    at, itoa, TK_EOF, TK_ERR, TK_AMP, TK_SLASH, TK_EQ, TK_COMMA, TK_WORD, WHITE
  use io_namelist_values, only: to_real, to_int, shown
  use io_name_index, only: name_index_t
  implicit none
  private
  public :: nml_file_t, nml_group_t, string_t

  type :: string_t
    character(:), allocatable :: s
  end type string_t

  type :: var_t
    character(:), allocatable :: name
    type(item_t), allocatable :: items(:)
    integer :: line = 0
    logical :: used = .false.
    logical :: overridden = .false.
  end type var_t

  type :: nml_group_t
    character(:), allocatable :: name
    integer :: line = 0
    integer :: occurrence = 0
    character(:), allocatable :: path
    type(var_t), allocatable, private :: vars(:)
  contains
    procedure :: has => group_has
    procedure :: get_real => group_get_real
    procedure :: get_int => group_get_int
    procedure :: get_logical => group_get_logical
    procedure :: get_string => group_get_string
    procedure :: get_real_array => group_get_real_array
    procedure :: get_int_array => group_get_int_array
    procedure :: get_string_array => group_get_string_array
    procedure :: check_all_used => group_check_all_used
    procedure :: where => group_where
    !> where for another line of the group (a variable's), and a variable's index (0: absent)
    procedure :: where_line => where_at
    procedure :: index_of => find_var
    procedure :: set_raw => group_set_raw
    procedure :: unset => group_unset
  end type nml_group_t

  type :: nml_file_t
    character(:), allocatable :: path, text
    type(nml_group_t), allocatable :: groups(:)
  contains
    procedure :: load => file_load
    procedure :: parse => file_parse
    procedure :: count => file_count
    procedure :: group_index => file_group_index
    procedure :: check_known_groups => file_check_known_groups
  end type nml_file_t

  interface
    !> The typed getters (submodule io_namelist_getters).
    module subroutine group_get_real(this, var, value, err, default)
      class(nml_group_t), intent(inout) :: this
      character(*), intent(in) :: var
      real(wp), intent(out) :: value
      type(error_t), intent(out) :: err
      real(wp), intent(in), optional :: default
    end subroutine group_get_real
    module subroutine group_get_int(this, var, value, err, default)
      class(nml_group_t), intent(inout) :: this
      character(*), intent(in) :: var
      integer, intent(out) :: value
      type(error_t), intent(out) :: err
      integer, intent(in), optional :: default
    end subroutine group_get_int
    module subroutine group_get_logical(this, var, value, err, default)
      class(nml_group_t), intent(inout) :: this
      character(*), intent(in) :: var
      logical, intent(out) :: value
      type(error_t), intent(out) :: err
      logical, intent(in), optional :: default
    end subroutine group_get_logical
    module subroutine group_get_string(this, var, value, err, default)
      class(nml_group_t), intent(inout) :: this
      character(*), intent(in) :: var
      character(:), allocatable, intent(out) :: value
      type(error_t), intent(out) :: err
      character(*), intent(in), optional :: default
    end subroutine group_get_string
    module subroutine group_get_real_array(this, var, values, err, default)
      class(nml_group_t), intent(inout) :: this
      character(*), intent(in) :: var
      real(wp), allocatable, intent(out) :: values(:)
      type(error_t), intent(out) :: err
      real(wp), intent(in), optional :: default(:)
    end subroutine group_get_real_array
    module subroutine group_get_int_array(this, var, values, err, default)
      class(nml_group_t), intent(inout) :: this
      character(*), intent(in) :: var
      integer, allocatable, intent(out) :: values(:)
      type(error_t), intent(out) :: err
      integer, intent(in), optional :: default(:)
    end subroutine group_get_int_array
    module subroutine group_get_string_array(this, var, values, err, default)
      class(nml_group_t), intent(inout) :: this
      character(*), intent(in) :: var
      type(string_t), allocatable, intent(out) :: values(:)
      type(error_t), intent(out) :: err
      type(string_t), intent(in), optional :: default(:)
    end subroutine group_get_string_array
  end interface


contains

  ! ---------------------------------------------------------------- file level

  subroutine file_load(this, path, err)
    class(nml_file_t), intent(inout) :: this
    character(*), intent(in) :: path
    type(error_t), intent(out) :: err
    character(256) :: msg
    character(:), allocatable :: text
    integer :: u, ios, n

    open(newunit=u, file=path, status='old', access='stream', form='unformatted', &
      action='read', iostat=ios, iomsg=msg)
    if (ios /= 0) then
      call err%set(ERR_INPUT, "cannot open input file '" // path // "': " // system_part(msg))
      return
    end if
    inquire(unit=u, size=n)
    allocate(character(max(n, 0)) :: text)
    if (n > 0) read(u, iostat=ios, iomsg=msg) text
    close(u)
    if (ios /= 0 .or. n < 0) then
      if (n < 0) msg = 'size unknown'
      call err%set(ERR_INPUT, "cannot read input file '" // path // "': " // system_part(msg))
      return
    end if
    call this%parse(text, path, err)
  end subroutine file_load

  !> gfortran's iomsg repeats the file name ("Cannot open file 'x': No such ..."); keep the reason.
  function system_part(msg) result(r)
    character(*), intent(in) :: msg
    character(:), allocatable :: r
    integer :: k
    k = index(msg, "': ", back=.true.)
    r = trim(msg(merge(k + 3, 1, k > 0):))
  end function system_part

  subroutine file_parse(this, text, path, err)
    class(nml_file_t), intent(inout) :: this
    character(*), intent(in) :: text, path
    type(error_t), intent(out) :: err
    type(nml_group_t), allocatable :: groups(:), tmp(:)
    type(nml_group_t) :: g
    type(token_t) :: tok
    integer :: pos, line, n, k

    this%path = path
    this%text = text
    if (allocated(this%groups)) deallocate(this%groups)
    ! Groups are collected in `groups`, grown geometrically, and handed over at every exit:
    ! appending one at a time deep-copied all earlier groups each time (a 2000-link scene
    ! took 11 s to parse).
    allocate(groups(16))
    n = 0
    line = 1
    ! A UTF-8 byte order mark is no text outside a group: refusing it would name nothing the
    ! user wrote.
    pos = after_bom(text)
    do
      ! Outside groups only blanks, '!' comments and the '&' of the next group may stand:
      ! anything else is text the user meant to say something with (a group whose '&' is
      ! missing, a value after the closing '/'), and dropping it silently changes the model.
      do while (pos <= len(text))
        if (text(pos:pos) == '&') exit
        if (text(pos:pos) == '!') then
          do while (pos <= len(text))
            if (text(pos:pos) == achar(10)) exit
            pos = pos + 1
          end do
          cycle
        end if
        if (scan(text(pos:pos), WHITE) == 0) then
          call err%set(ERR_INPUT, at(path, line) // outside_message(text, pos))
          call hand_over()
          return
        end if
        if (text(pos:pos) == achar(10)) line = line + 1
        pos = pos + 1
      end do
      if (pos > len(text)) exit
      call next_token(text, pos, line, tok)
      if (tok%kind == TK_ERR) then
        call err%set(ERR_INPUT, at(path, tok%line) // tok%text)
        exit
      end if
      ! component by component: gfortran 12 has ICEs on constructors with such components
      g%name = tok%text
      g%line = tok%line
      g%path = path
      g%occurrence = 1
      do k = 1, n
        if (groups(k)%name == g%name) g%occurrence = g%occurrence + 1
      end do
      if (allocated(g%vars)) deallocate(g%vars)
      allocate(g%vars(0))
      call parse_group_body(g, text, pos, line, err)
      if (.not. err%ok()) exit
      if (n == size(groups)) then
        allocate(tmp(2 * n))
        tmp(1:n) = groups
        call move_alloc(tmp, groups)
      end if
      n = n + 1
      groups(n) = g
    end do
    call hand_over()
  contains
    subroutine hand_over()
      allocate(this%groups(n))
      this%groups = groups(1:n)
    end subroutine hand_over
  end subroutine file_parse

  !> Why the text at `pos`, outside every group, is refused (it shows the rest of the line).
  function outside_message(text, pos) result(msg)
    character(*), intent(in) :: text
    integer, intent(in) :: pos
    character(:), allocatable :: msg, rest
    integer :: eol
    eol = index(text(pos:), achar(10))
    if (eol == 0) eol = len(text) - pos + 2
    rest = trim(text(pos:pos + eol - 2))
    if (len(rest) > 0) then
      if (rest(len(rest):len(rest)) == achar(13)) rest = rest(:len(rest) - 1)
    end if
    if (len(rest) > 40) rest = rest(:37) // '...'
    if (text(pos:pos) == '$') then
      msg = "'$' group syntax is not supported: write &name ... / ('" // rest // "')"
    else
      msg = "text outside a group: '" // rest // "' (a group starts with '&name' and " // &
        "ends with '/'; notes belong in '!' comments)"
    end if
  end function outside_message

  subroutine parse_group_body(g, text, pos, line, err)
    type(nml_group_t), intent(inout) :: g
    character(*), intent(in) :: text
    integer, intent(inout) :: pos, line
    type(error_t), intent(inout) :: err
    type(token_t) :: tok
    type(var_t) :: v
    type(var_t), allocatable :: vars(:), tmp(:)
    type(name_index_t) :: names
    character(:), allocatable :: msg
    integer :: k, eline, n

    ! Variables are collected in `vars`, grown geometrically, and found by a hash index:
    ! appending to g%vars one at a time and searching it made a group O(n^2) (20,000
    ! variables: 45 s). g%vars gets them, exactly sized, when the group ends.
    allocate(vars(16))
    n = 0
    do
      call next_token(text, pos, line, tok)
      select case (tok%kind)
      case (TK_SLASH)
        call hand_over()
        return
      case (TK_COMMA)
        cycle
      case (TK_EOF)
        call err%set(ERR_INPUT, g%where() // ": missing closing '/'")
        return
      case (TK_AMP)
        if (tok%text == 'end') then   ! old-style '&end' terminator
          call hand_over()
          return
        end if
        call err%set(ERR_INPUT, g%where() // ": missing closing '/' before &" // tok%text // &
          ' on line ' // itoa(tok%line))
        return
      case (TK_ERR)
        call err%set(ERR_INPUT, where_at(g, tok%line) // ': ' // tok%text)
        return
      case (TK_WORD)
        continue
      case default
        call err%set(ERR_INPUT, where_at(g, tok%line) // ': expected a variable name, got ' // &
          describe(tok))
        return
      end select

      v%name = lower_case(tok%text)
      v%line = tok%line
      call check_name(v%name, msg)
      if (len(msg) == 0) then
        call next_token(text, pos, line, tok)
        if (tok%kind /= TK_EQ) msg = "'=' missing after '" // v%name // "'"
      end if
      if (len(msg) > 0) then
        call err%set(ERR_INPUT, where_at(g, v%line) // ': ' // msg)
        return
      end if
      k = names%find(v%name)
      if (k > 0) then
        call err%set(ERR_INPUT, where_at(g, v%line) // ": variable '" // v%name // &
          "' assigned twice (first on line " // itoa(vars(k)%line) // ')')
        return
      end if
      call parse_values(text, pos, line, v%items, msg, eline)
      if (len(msg) > 0) then
        call err%set(ERR_INPUT, where_at(g, eline) // ": variable '" // v%name // "': " // msg)
        return
      end if
      if (n == size(vars)) then
        allocate(tmp(2 * n))
        tmp(1:n) = vars(1:n)
        call move_alloc(tmp, vars)
      end if
      n = n + 1
      vars(n) = v
      call names%add(v%name)
    end do
  contains
    subroutine hand_over()
      g%vars = vars(1:n)
    end subroutine hand_over
  end subroutine parse_group_body

  !> Collect values up to the next `name =`, '/', '&' or end of text.

  integer function file_count(this, name) result(n)
    class(nml_file_t), intent(in) :: this
    character(*), intent(in) :: name
    integer :: i
    n = 0
    if (.not. allocated(this%groups)) return
    do i = 1, size(this%groups)
      if (this%groups(i)%name == lower_case(trim(name))) n = n + 1
    end do
  end function file_count

  integer function file_group_index(this, name, k) result(idx)
    class(nml_file_t), intent(in) :: this
    character(*), intent(in) :: name
    integer, intent(in) :: k
    integer :: i, seen
    idx = 0
    if (.not. allocated(this%groups)) return
    seen = 0
    do i = 1, size(this%groups)
      if (this%groups(i)%name == lower_case(trim(name))) then
        seen = seen + 1
        if (seen == k) then
          idx = i
          return
        end if
      end if
    end do
  end function file_group_index

  subroutine file_check_known_groups(this, names, err)
    class(nml_file_t), intent(in) :: this
    character(*), intent(in) :: names(:)
    type(error_t), intent(out) :: err
    integer :: i, j
    logical :: known
    if (.not. allocated(this%groups)) return
    do i = 1, size(this%groups)
      known = .false.
      do j = 1, size(names)
        known = known .or. this%groups(i)%name == lower_case(trim(names(j)))
      end do
      if (.not. known) then
        call err%set(ERR_INPUT, at(this%path, this%groups(i)%line) // 'unknown group &' // &
          this%groups(i)%name)
        return
      end if
    end do
  end subroutine file_check_known_groups

  ! ---------------------------------------------------------------- group level

  !> "scene.nml:12: group &link #2"
  function group_where(this) result(s)
    class(nml_group_t), intent(in) :: this
    character(:), allocatable :: s
    s = where_at(this, this%line)
  end function group_where

  function where_at(g, line) result(s)
    class(nml_group_t), intent(in) :: g
    integer, intent(in) :: line
    character(:), allocatable :: s
    s = at(g%path, line) // 'group &' // g%name // ' #' // itoa(g%occurrence)
  end function where_at

  logical function group_has(this, var)
    class(nml_group_t), intent(in) :: this
    character(*), intent(in) :: var
    group_has = find_var(this, lower_case(trim(var))) > 0
  end function group_has


  subroutine group_check_all_used(this, err)
    class(nml_group_t), intent(in) :: this
    type(error_t), intent(out) :: err
    integer :: k
    if (.not. allocated(this%vars)) return
    do k = 1, size(this%vars)
      if (.not. this%vars(k)%used) then
        call err%set(ERR_INPUT, where_at(this, this%vars(k)%line) // ": unknown variable '" // &
          this%vars(k)%name // "'")
        return
      end if
    end do
  end subroutine group_check_all_used

  !> Replace or add `var` with the values written in `text` (as after '=' in the file).
  subroutine group_set_raw(this, var, text, err)
    class(nml_group_t), intent(inout) :: this
    character(*), intent(in) :: var, text
    type(error_t), intent(out) :: err
    type(item_t), allocatable :: items(:)
    type(token_t) :: tok
    type(var_t) :: new
    character(:), allocatable :: name, msg
    integer :: pos, line, eline, k

    name = lower_case(trim(var))
    call check_name(name, msg)
    if (len(msg) > 0) then
      call err%set(ERR_INPUT, this%where() // ': ' // msg)
      return
    end if
    pos = 1
    line = 1
    call parse_values(text, pos, line, items, msg, eline)
    if (len(msg) == 0) then
      call next_token(text, pos, line, tok)
      if (tok%kind /= TK_EOF) msg = 'unexpected ' // describe(tok)
    end if
    if (len(msg) > 0) then
      call err%set(ERR_INPUT, this%where() // ": variable '" // name // "': bad value '" // &
        text // "': " // msg)
      return
    end if
    k = find_var(this, name)
    if (k == 0) then
      new%name = name
      new%line = this%line
      call add_var(this, new)
      k = size(this%vars)
    end if
    this%vars(k)%items = items
    this%vars(k)%overridden = .true.
  end subroutine group_set_raw

  !> Remove variable `var` (if given), as if it had not been written (a run's error check
  !> replaces cutoff_hz by n_modes).
  subroutine group_unset(this, var)
    class(nml_group_t), intent(inout) :: this
    character(*), intent(in) :: var
    integer :: k
    k = find_var(this, lower_case(trim(var)))
    if (k > 0) this%vars = [this%vars(:k - 1), this%vars(k + 1:)]
  end subroutine group_unset

  ! ---------------------------------------------------------------- helpers

  pure integer function find_var(g, name) result(k)
    class(nml_group_t), intent(in) :: g
    character(*), intent(in) :: name
    if (allocated(g%vars)) then
      do k = 1, size(g%vars)
        if (g%vars(k)%name == name) return
      end do
    end if
    k = 0
  end function find_var

  subroutine add_var(g, v)
    type(nml_group_t), intent(inout) :: g
    type(var_t), intent(in) :: v
    type(var_t), allocatable :: tmp(:)
    integer :: n
    if (.not. allocated(g%vars)) allocate(g%vars(0))
    n = size(g%vars)
    allocate(tmp(n + 1))
    tmp(1:n) = g%vars
    tmp(n + 1) = v
    call move_alloc(tmp, g%vars)
  end subroutine add_var
end module io_namelist
