!> A &parameter's name: which scene variable (and which entry of a list) it sets, checked
!> against the scene schema before the base scene is read.
submodule (sweep_spec) sweep_spec_names
  use io_namelist_lexer, only: is_name
  use io_schema, only: SCENE_GROUPS, SINGLE_GROUPS, SCHEMA, find_spec, kind_name, &
    bound_problem, VK_REAL, VK_INT, VK_REAL_LIST
  implicit none

contains

  module procedure key_var
    if (group == 'mass' .or. group == 'force') then
      v = 'node'
    else
      v = 'label'
    end if
  end procedure key_var

  !> 'group.variable' or 'group.key.variable' into its parts; a key may itself contain dots
  !> (everything between the first and the last dot). A trailing '(k)' picks entry k of a list.
  module procedure split_name
    character(len=:), allocatable :: name
    integer :: d1, d2, k

    name = trim(adjustl(p%name))
    call split_entry(p, name, err)
    if (.not. err%ok()) return
    d1 = index(name, '.')
    d2 = index(name, '.', back=.true.)
    if (d1 == 0) then
      call err%set(ERR_INPUT, p%origin // ": a name has the form 'group.variable' or " // &
        "'group.key.variable' (e.g. 'dynamic.rtol', 'link.link1.E')")
      return
    end if
    p%group = lower_case(name(1:d1 - 1))
    p%var = lower_case(name(d2 + 1:))
    p%key = ''
    if (d2 > d1) p%key = name(d1 + 1:d2 - 1)

    if (all(SCENE_GROUPS /= p%group)) then
      call err%set(ERR_INPUT, p%origin // ": unknown group '" // p%group // "' (scene groups: " &
        // join(SCENE_GROUPS) // ')')
      return
    end if
    if (any(SINGLE_GROUPS == p%group)) then
      if (d2 > d1) then
        call err%set(ERR_INPUT, p%origin // ': group &' // p%group // ' appears at most ' // &
          "once and takes no key: write '" // name(1:d1 - 1) // '.' // name(d2 + 1:) // "'")
        return
      end if
    else if (d2 == d1) then
      call err%set(ERR_INPUT, p%origin // ': group &' // p%group // ' may repeat: name ' // &
        "one by its " // key_var(p%group) // ", '" // name(1:d1 - 1) // '.<' // &
        key_var(p%group) // '>.' // name(d2 + 1:) // "'")
      return
    else if (len(p%key) == 0) then
      call err%set(ERR_INPUT, p%origin // ': the key (the group''s ' // key_var(p%group) // &
        ') is empty')
      return
    end if
    if (.not. is_name(p%var)) then
      call err%set(ERR_INPUT, p%origin // ": '" // p%var // "' is not a variable name")
      return
    end if

    k = find_spec(p%group, p%var)
    if (k == 0) then
      call err%set(ERR_INPUT, p%origin // ": &" // p%group // " has no variable '" // p%var // &
        "' (docs/input.md lists them)")
      return
    end if
    select case (SCHEMA(k)%kind)
    case (VK_REAL, VK_INT)
      if (p%entry > 0) call err%set(ERR_INPUT, p%origin // ": variable '" // p%var // &
        "' of &" // p%group // " is one number, not a list: write it without '(" // &
        int_str(p%entry) // ")'")
    case (VK_REAL_LIST)
      if (p%entry == 0) call err%set(ERR_INPUT, p%origin // ": variable '" // p%var // &
        "' of &" // p%group // ' is a real list: name one entry, e.g. ' // "'" // &
        name // "(1)' (entries count from 1)")
    case default
      call err%set(ERR_INPUT, p%origin // ": variable '" // p%var // "' of &" // p%group // &
        ' is a ' // kind_name(SCHEMA(k)%kind) // ', not a number or a list of numbers: ' // &
        'it cannot be swept')
    end select
    p%is_int = SCHEMA(k)%kind == VK_INT
    p%spec = k
  end procedure split_name

  ! The same variable twice would let the second silently overwrite the first: two
  ! &parameter groups, or a tied name (&parameter name = 'a', 'b') that another group or the
  ! same one also sets.
  module procedure check_targets
    integer :: i, k, m, n
    n = size(params)
    do k = 0, size(params(n)%tied)
      do i = 1, n
        do m = 0, size(params(i)%tied)
          if (i == n .and. m >= k) exit
          if (.not. same(i, m, n, k)) cycle
          if (i == n) then
            call err%set(ERR_INPUT, text_of(n, k, .false.) // ': the same scene variable is ' // &
              'named twice in this &parameter')
          else
            call err%set(ERR_INPUT, text_of(n, k, .false.) // ': the same scene variable ' // &
              'as &parameter #' // int_str(i) // " '" // text_of(i, m, .true.) // "'")
          end if
          return
        end do
      end do
    end do
  contains
    ! Entry m of parameter i: the parameter itself (m = 0) or its tied name m. Compared in
    ! place: with copies of param_t (tied names nested in it) the spec's names came out wrong
    ! afterwards (test_sweep_spec 'names as given', gfortran 12).
    logical function same(i, m, j, k)
      integer, intent(in) :: i, m, j, k
      if (m == 0 .and. k == 0) then
        same = same_target(params(i), params(j))
      else if (m == 0) then
        same = same_target(params(i), params(j)%tied(k))
      else if (k == 0) then
        same = same_target(params(i)%tied(m), params(j))
      else
        same = same_target(params(i)%tied(m), params(j)%tied(k))
      end if
    end function same
    !> Its origin (where it is written) or, `name_only`, its name.
    function text_of(i, m, name_only) result(s)
      integer, intent(in) :: i, m
      logical, intent(in) :: name_only
      character(len=:), allocatable :: s
      if (m == 0) then
        s = merge(params(i)%name // repeat(' ', len(params(i)%origin)), &
          params(i)%origin // repeat(' ', len(params(i)%name)), name_only)
      else
        s = merge(params(i)%tied(m)%name // repeat(' ', len(params(i)%tied(m)%origin)), &
          params(i)%tied(m)%origin // repeat(' ', len(params(i)%tied(m)%name)), name_only)
      end if
      s = trim(s)
    end function text_of
  end procedure check_targets

  module procedure check_ranges
    integer :: i, j, k
    do j = 1, size(this%params)
      do i = 1, size(this%values, 1)
        call check_one(this%params(j), i, this%values(i, j), err)
        do k = 1, size(this%params(j)%tied)
          call check_one(this%params(j)%tied(k), i, this%values(i, j), err)
        end do
        if (.not. err%ok()) return
      end do
    end do
  contains
    subroutine check_one(p, icase, x, err)
      type(param_t), intent(in) :: p
      integer, intent(in) :: icase
      real(wp), intent(in) :: x
      type(error_t), intent(inout) :: err
      character(len=:), allocatable :: msg
      if (.not. err%ok()) return
      msg = bound_problem(SCHEMA(p%spec), x)
      if (len(msg) > 0) call err%set(ERR_INPUT, p%origin // ': case ' // int_str(icase) // &
        ": '" // trim(SCHEMA(p%spec)%name) // "' of &" // p%group // ' ' // msg)
    end subroutine check_one
  end procedure check_ranges

  !> A trailing '(k)' of the name into p%entry, and the name without it; p%entry = 0 without.
  subroutine split_entry(p, name, err)
    type(param_t), intent(inout) :: p
    character(len=:), allocatable, intent(inout) :: name
    type(error_t), intent(inout) :: err
    character(len=:), allocatable :: digits
    integer :: lp

    p%entry = 0
    if (len(name) == 0) return
    if (name(len(name):) /= ')') return
    lp = index(name, '(', back=.true.)
    if (lp == 0) then
      call err%set(ERR_INPUT, p%origin // ": ')' without '(': one entry of a list is " // &
        "written 'group.variable(k)', e.g. 'scene.gravity(2)'")
      return
    end if
    digits = trim(adjustl(name(lp + 1:len(name) - 1)))
    ! Digits alone: a read of '2.5' or '2, 3' into an integer would take the 2.
    if (len(digits) == 0 .or. len(digits) > 9 .or. verify(digits, '0123456789') > 0) then
      call err%set(ERR_INPUT, p%origin // ": the entry '(" // name(lp + 1:len(name) - 1) // &
        ")' must be a whole number, at least 1 (entries count from 1)")
      return
    end if
    read(digits, *) p%entry
    if (p%entry < 1) then
      call err%set(ERR_INPUT, p%origin // ': entry ' // int_str(p%entry) // &
        ' does not exist: entries count from 1')
      return
    end if
    name = trim(name(:lp - 1))
  end subroutine split_entry

  !> The same variable, and the same entry of a list; two entries of one list are two targets.
  module procedure same_target
    same_target = a%group == b%group .and. a%key == b%key .and. a%var == b%var .and. &
      a%entry == b%entry
  end procedure same_target

  function join(items) result(s)
    character(len=*), intent(in) :: items(:)
    character(len=:), allocatable :: s
    integer :: i
    s = ''
    do i = 1, size(items)
      if (i > 1) s = s // ', '
      s = s // trim(items(i))
    end do
  end function join
end submodule sweep_spec_names
