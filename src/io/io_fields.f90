!> Typed getters of scene variables: each reads one variable of a namelist group, keeps the
!> first error, and takes the variable's default, range and keyword choices from the scene
!> schema (io_schema). Messages name the file, line, group and variable.
module io_fields
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_INPUT, ERR_INTERNAL
  use core_strings, only: lower_case, int_str, real_str
  use io_namelist, only: nml_group_t, string_t
  use io_schema, only: var_spec_t, SCHEMA, find_spec, bound_problem, choice_list, has_choice
  use io_name_index, only: name_index_t
  use model_scene, only: label_t
  implicit none
  private
  public :: rd_real, rd_int, rd_logical, rd_string, rd_choice, rd_enum, rd_choices, rd_classes, &
    rd_label, only_with, rd_fixed_list, rd_labels, first_given, rd_reals, check_entries, &
    check_unique, check_increasing

  !> Longest label: the longest name the model derives from one, 'node ''<label>'' rotation',
  !> then fills the 64 characters it keeps names in (model_system).
  integer, parameter :: MAX_LABEL = 48

contains

  ! Getter wrappers that keep the first error and skip work after it. Each takes the variable's
  ! default, range and choices from the scene schema (io_schema); `default` overrides the
  ! schema's where it depends on other variables (fix_x on fixed, a motion's end on start).

  !> The schema entry of a variable of g's group; reading an undeclared one is a bug.
  function spec_of(g, var, err) result(spec)
    type(nml_group_t), intent(in) :: g
    character(len=*), intent(in) :: var
    type(error_t), intent(inout) :: err
    type(var_spec_t) :: spec
    integer :: k
    k = find_spec(g%name, var)
    spec = SCHEMA(max(k, 1))
    if (k == 0) call err%set(ERR_INTERNAL, 'variable ''' // var // ''' of &' // g%name // &
      ' is not declared in the scene schema (io_schema)')
  end function spec_of

  !> Range check of a number read for `spec`.
  subroutine check_bounds(g, spec, x, err)
    type(nml_group_t), intent(in) :: g
    type(var_spec_t), intent(in) :: spec
    real(wp), intent(in) :: x
    type(error_t), intent(inout) :: err
    character(len=:), allocatable :: msg
    if (.not. err%ok()) return
    msg = bound_problem(spec, x)
    if (len(msg) > 0) call err%set(ERR_INPUT, g%where() // ': variable ''' // &
      trim(spec%name) // ''' ' // msg)
  end subroutine check_bounds

  subroutine rd_real(g, var, value, err, default)
    type(nml_group_t), intent(inout) :: g
    character(len=*), intent(in) :: var
    real(wp), intent(inout) :: value
    type(error_t), intent(inout) :: err
    real(wp), intent(in), optional :: default
    type(var_spec_t) :: spec
    type(error_t) :: e
    real(wp) :: fallback
    integer :: ios
    if (.not. err%ok()) return
    spec = spec_of(g, var, err)
    if (.not. err%ok()) return
    read(spec%default, *, iostat=ios) fallback
    if (present(default)) then
      call g%get_real(var, value, e, default)
    else if (spec%required .or. ios /= 0) then
      call g%get_real(var, value, e)
    else
      call g%get_real(var, value, e, fallback)
    end if
    if (.not. e%ok()) err = e
    ! Only a value the scene gives: a default stands for 'none' where it is (u_min = -huge).
    if (g%has(var)) call check_bounds(g, spec, value, err)
  end subroutine rd_real

  !> A list of reals, each entry in the schema's range of the variable (an entry beyond it is
  !> named by its position: the list's product with other inputs overflows like a scalar's).
  subroutine rd_reals(g, var, values, err, default)
    type(nml_group_t), intent(inout) :: g
    character(len=*), intent(in) :: var
    real(wp), allocatable, intent(out) :: values(:)
    type(error_t), intent(inout) :: err
    real(wp), intent(in), optional :: default(:)
    type(error_t) :: e
    allocate(values(0))
    if (.not. err%ok()) return
    call g%get_real_array(var, values, e, default)
    if (.not. e%ok()) then
      err = e
      return
    end if
    call check_entries(g, var, values, err)
  end subroutine rd_reals

  !> Range check of the entries of a list of var (read from the group or, `source`, from a
  !> file it names).
  subroutine check_entries(g, var, values, err, source)
    type(nml_group_t), intent(in) :: g
    character(len=*), intent(in) :: var
    real(wp), intent(in) :: values(:)
    type(error_t), intent(inout) :: err
    character(len=*), intent(in), optional :: source
    type(var_spec_t) :: spec
    character(len=:), allocatable :: msg
    integer :: i
    if (.not. err%ok()) return
    spec = spec_of(g, var, err)
    do i = 1, size(values)
      if (.not. err%ok()) return
      msg = bound_problem(spec, values(i))
      if (len(msg) == 0) cycle
      if (present(source)) msg = source // ' ' // msg
      call err%set(ERR_INPUT, g%where() // ': variable ''' // trim(spec%name) // ''': value ' &
        // int_str(i) // ' ' // msg)
    end do
  end subroutine check_entries

  subroutine rd_int(g, var, value, err, default)
    type(nml_group_t), intent(inout) :: g
    character(len=*), intent(in) :: var
    integer, intent(inout) :: value
    type(error_t), intent(inout) :: err
    integer, intent(in), optional :: default
    type(var_spec_t) :: spec
    type(error_t) :: e
    integer :: fallback, ios
    if (.not. err%ok()) return
    spec = spec_of(g, var, err)
    if (.not. err%ok()) return
    read(spec%default, *, iostat=ios) fallback
    if (present(default)) then
      call g%get_int(var, value, e, default)
    else if (spec%required .or. ios /= 0) then
      call g%get_int(var, value, e)
    else
      call g%get_int(var, value, e, fallback)
    end if
    if (.not. e%ok()) err = e
    call check_bounds(g, spec, real(value, wp), err)
    if (err%ok() .and. len_trim(spec%choices) > 0) then
      if (.not. has_choice(spec, int_str(value))) call err%set(ERR_INPUT, g%where() // &
        ': variable ''' // var // ''' must be ' // choice_list(spec) // ', got ' // &
        int_str(value))
    end if
  end subroutine rd_int

  subroutine rd_logical(g, var, value, err, default)
    type(nml_group_t), intent(inout) :: g
    character(len=*), intent(in) :: var
    logical, intent(inout) :: value
    type(error_t), intent(inout) :: err
    logical, intent(in), optional :: default
    type(var_spec_t) :: spec
    type(error_t) :: e
    if (.not. err%ok()) return
    spec = spec_of(g, var, err)
    if (.not. err%ok()) return
    if (present(default)) then
      call g%get_logical(var, value, e, default)
    else if (spec%required) then
      call g%get_logical(var, value, e)
    else
      call g%get_logical(var, value, e, spec%default == '.true.')
    end if
    if (.not. e%ok()) err = e
  end subroutine rd_logical

  !> A string: free text, a label or a file name ('' by default unless required).
  subroutine rd_string(g, var, value, err, default)
    type(nml_group_t), intent(inout) :: g
    character(len=*), intent(in) :: var
    character(len=:), allocatable, intent(inout) :: value
    type(error_t), intent(inout) :: err
    character(len=*), intent(in), optional :: default
    type(var_spec_t) :: spec
    type(error_t) :: e
    if (.not. err%ok()) return
    spec = spec_of(g, var, err)
    if (.not. err%ok()) return
    if (present(default)) then
      call g%get_string(var, value, e, default)
    else if (spec%required) then
      call g%get_string(var, value, e)
    else
      call g%get_string(var, value, e, trim(spec%default))
    end if
    if (.not. e%ok()) err = e
  end subroutine rd_string

  !> A keyword (mode class, law, solver, ...): folded to lower case and checked against
  !> the schema's choices.
  subroutine rd_choice(g, var, value, err)
    type(nml_group_t), intent(inout) :: g
    character(len=*), intent(in) :: var
    character(len=:), allocatable, intent(inout) :: value
    type(error_t), intent(inout) :: err
    type(var_spec_t) :: spec
    type(error_t) :: e
    if (.not. err%ok()) return
    spec = spec_of(g, var, err)
    if (.not. err%ok()) return
    call g%get_string(var, value, e, trim(spec%default))
    if (.not. e%ok()) then
      err = e
      return
    end if
    value = lower_case(value)
    if (.not. has_choice(spec, value)) call err%set(ERR_INPUT, g%where() // ': variable ''' // &
      var // ''': ''' // value // ''' is not ' // choice_list(spec))
  end subroutine rd_choice

  !> A keyword as an enum: its position in names, the program's names of its constants
  !> (model_scene's UPDATE_NAMES, ...). These must be the schema's choices: a difference is a
  !> bug, reported whenever the variable is read.
  subroutine rd_enum(g, var, names, value, err)
    type(nml_group_t), intent(inout) :: g
    character(len=*), intent(in) :: var, names(:)
    integer, intent(inout) :: value
    type(error_t), intent(inout) :: err
    character(len=:), allocatable :: word
    type(var_spec_t) :: spec
    integer :: i, n_choices
    if (.not. err%ok()) return
    spec = spec_of(g, var, err)
    if (.not. err%ok()) return
    n_choices = 1 + count([(spec%choices(i:i) == '|', i = 1, len_trim(spec%choices))])
    if (n_choices /= size(names) .or. .not. all([(has_choice(spec, trim(names(i))), i = 1, &
        size(names))])) then
      call err%set(ERR_INTERNAL, g%where() // ': variable ''' // var // ''': the schema''s ' // &
        'choices ' // choice_list(spec) // ' are not the program''s')
      return
    end if
    call rd_choice(g, var, word, err)
    if (.not. err%ok()) return
    value = findloc([(trim(names(i)) == word, i = 1, size(names))], .true., 1)
  end subroutine rd_enum

  !> Keywords, each checked against the schema's choices (default: the schema's, if any);
  !> `unique`: each at most once.
  subroutine rd_choices(g, var, values, err, unique)
    type(nml_group_t), intent(inout) :: g
    character(len=*), intent(in) :: var
    type(string_t), allocatable, intent(out) :: values(:)
    type(error_t), intent(inout) :: err
    logical, intent(in), optional :: unique
    type(var_spec_t) :: spec
    type(string_t), allocatable :: fallback(:)
    type(error_t) :: e
    integer :: i
    allocate(values(0))
    if (.not. err%ok()) return
    spec = spec_of(g, var, err)
    if (.not. err%ok()) return
    allocate(fallback(merge(1, 0, len_trim(spec%default) > 0)))
    if (size(fallback) > 0) fallback(1)%s = trim(spec%default)
    call g%get_string_array(var, values, e, default=fallback)
    if (.not. e%ok()) then
      err = e
      return
    end if
    do i = 1, size(values)
      values(i)%s = lower_case(values(i)%s)
      if (.not. has_choice(spec, values(i)%s)) then
        call err%set(ERR_INPUT, g%where() // ': variable ''' // var // ''': ''' // &
          values(i)%s // ''' is not ' // choice_list(spec))
        return
      end if
    end do
    if (present(unique)) then
      if (unique) call check_unique(g, var, values, err)
    end if
  end subroutine rd_choices

  !> Mode classes of a link: one keyword for every element, one per element (n of them) or,
  !> for bending, one per bending mode (2 n: each element's `from` side, then its `to` side).
  subroutine rd_classes(g, var, n, classes, err)
    type(nml_group_t), intent(inout) :: g
    character(len=*), intent(in) :: var
    integer, intent(in) :: n
    type(label_t), allocatable, intent(out) :: classes(:)
    type(error_t), intent(inout) :: err
    type(string_t), allocatable :: values(:)
    allocate(classes(0))
    call rd_choices(g, var, values, err)
    if (.not. err%ok()) return
    if (size(values) /= 1 .and. size(values) /= n .and. &
        .not. (var == 'bending' .and. size(values) == 2 * n)) then
      call err%set(ERR_INPUT, g%where() // ': variable ''' // var // ''' needs 1 value (all ' // &
        'elements) or one per element (n_elements = ' // int_str(n) // ')' // &
        trim(merge(' or one per bending mode (2 n_elements)', '                                       ', &
        var == 'bending')) // ', got ' // int_str(size(values)))
      return
    end if
    classes = as_labels(values)
  end subroutine rd_classes

  !> A label names a node, link, ... in references and in the result file's paths: it must be
  !> non-empty and must not contain '/' (an HDF5 path separator) or leading/trailing blanks.
  subroutine rd_label(g, label, err)
    type(nml_group_t), intent(inout) :: g
    character(len=:), allocatable, intent(inout) :: label
    type(error_t), intent(inout) :: err
    call rd_string(g, 'label', label, err)
    if (.not. err%ok()) return
    if (len_trim(label) == 0) then
      call err%set(ERR_INPUT, g%where() // ': variable ''label'' must not be empty')
    ! Not label /= trim(adjustl(label)): Fortran compares blank-padded, so 'tip ' passed.
    else if (index(label, '/') > 0 .or. label(1:1) == ' ' .or. len_trim(label) < len(label)) then
      call err%set(ERR_INPUT, g%where() // ': variable ''label'': ''' // label // &
        ''' may not contain ''/'' or start or end with a blank')
    ! The model keeps node, coordinate and element names in 64 characters ('node ''<label>''
    ! rotation', '<link>.<k>'): a longer label was cut there, so that a node of a 70-character
    ! label was 'not defined' for &output and labels alike in their first 64 characters met.
    else if (len(label) > MAX_LABEL) then
      call err%set(ERR_INPUT, g%where() // ': variable ''label'': ''' // label(:20) // &
        '...'' is ' // int_str(len(label)) // ' characters long, more than ' // &
        int_str(MAX_LABEL))
    end if
  end subroutine rd_label

  !> An option of one setting that is given with another (`dt` with integrator = 'bdf') would be
  !> ignored without a word: refuse it, saying when it applies.
  subroutine only_with(g, vars, applies, when, err)
    type(nml_group_t), intent(in) :: g
    character(len=*), intent(in) :: vars(:), when
    logical, intent(in) :: applies
    type(error_t), intent(inout) :: err
    integer :: i
    if (.not. err%ok() .or. applies) return
    do i = 1, size(vars)
      if (g%has(trim(vars(i)))) then
        call err%set(ERR_INPUT, g%where() // ': variable ''' // trim(vars(i)) // &
          ''' applies only ' // when // ': remove it or change that setting')
        return
      end if
    end do
  end subroutine only_with

  !> An optional list of exactly n reals: left unallocated when the group does not give it;
  !> `hint` (after 'needs n values') says what they are.
  subroutine rd_fixed_list(g, name, n, hint, values, err)
    type(nml_group_t), intent(inout) :: g
    character(len=*), intent(in) :: name, hint
    integer, intent(in) :: n
    real(wp), allocatable, intent(out) :: values(:)
    type(error_t), intent(inout) :: err
    type(error_t) :: e
    if (.not. g%has(name) .or. .not. err%ok()) return
    call g%get_real_array(name, values, e)
    if (e%ok()) call check_entries(g, name, values, e)
    if (.not. e%ok()) then
      err = e
    else if (size(values) /= n) then
      call err%set(ERR_INPUT, g%where() // ': variable ''' // name // ''' needs ' // &
        int_str(n) // ' values' // hint)
    end if
  end subroutine rd_fixed_list

  !> A list of strings as labels; `optional_list`: missing is the empty list (else an error).
  subroutine rd_labels(g, name, labels, err, optional_list)
    type(nml_group_t), intent(inout) :: g
    character(len=*), intent(in) :: name
    type(label_t), allocatable, intent(out) :: labels(:)
    type(error_t), intent(inout) :: err
    logical, intent(in), optional :: optional_list
    type(string_t), allocatable :: values(:)
    type(error_t) :: e
    allocate(labels(0))
    if (.not. err%ok()) return
    if (present(optional_list)) then
      if (optional_list .and. .not. g%has(name)) return
    end if
    call g%get_string_array(name, values, e)
    if (.not. e%ok()) then
      err = e
      return
    end if
    call check_unique(g, name, values, err)
    labels = as_labels(values)
  end subroutine rd_labels

  !> Each entry of a list of names at most once: a node output twice, an input or actuator
  !> named twice, a motion added to itself by `terms = 'a', 'a'` is a slip, never meant (the
  !> sum would double the term without a word). Hashed: lists may be long.
  subroutine check_unique(g, var, values, err)
    type(nml_group_t), intent(in) :: g
    character(len=*), intent(in) :: var
    type(string_t), intent(in) :: values(:)
    type(error_t), intent(inout) :: err
    type(name_index_t) :: seen
    integer :: i, k
    if (.not. err%ok()) return
    do i = 1, size(values)
      k = seen%find(values(i)%s)
      if (k > 0) then
        call err%set(ERR_INPUT, g%where() // ': variable ''' // var // ''': ''' // &
          values(i)%s // ''' is given twice (entries ' // int_str(k) // ' and ' // &
          int_str(i) // '); each entry must be different')
        return
      end if
      call seen%add(values(i)%s)
    end do
  end subroutine check_unique

  !> A list of times strictly increasing (what is done at each, in order, would otherwise
  !> silently come out in another order than the time or twice).
  subroutine check_increasing(g, var, values, err)
    type(nml_group_t), intent(in) :: g
    character(len=*), intent(in) :: var
    real(wp), intent(in) :: values(:)
    type(error_t), intent(inout) :: err
    integer :: i
    if (.not. err%ok()) return
    do i = 2, size(values)
      if (values(i) > values(i - 1)) cycle
      call err%set(ERR_INPUT, g%where() // ': variable ''' // var // ''' must be strictly ' // &
        'increasing: entry ' // int_str(i) // ' (' // real_str(values(i)) // ') is not ' // &
        'after entry ' // int_str(i - 1) // ' (' // real_str(values(i - 1)) // ')')
      return
    end do
  end subroutine check_increasing

  pure function as_labels(values) result(labels)
    type(string_t), intent(in) :: values(:)
    type(label_t) :: labels(size(values))
    integer :: i
    do i = 1, size(values)
      labels(i)%s = values(i)%s
    end do
  end function as_labels
  !> The first of `names` the group gives, '' if none.
  function first_given(g, names) result(name)
    type(nml_group_t), intent(inout) :: g
    character(len=*), intent(in) :: names(:)
    character(len=:), allocatable :: name
    integer :: i
    name = ''
    do i = 1, size(names)
      if (g%has(trim(names(i)))) then
        name = trim(names(i))
        return
      end if
    end do
  end function first_given
end module io_fields
