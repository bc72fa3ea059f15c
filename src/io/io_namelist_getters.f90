!> The typed getters of a namelist group: each converts the raw tokens of one variable,
!> marks it used and names file, line, group and variable in its errors.
submodule (io_namelist) io_namelist_getters
  implicit none

contains

  !> Prefix for messages about variable k: where it was written, or that an override set it.
  function var_where(g, k) result(s)
    class(nml_group_t), intent(in) :: g
    integer, intent(in) :: k
    character(:), allocatable :: s
    s = g%where_line(g%vars(k)%line) // ": variable '" // g%vars(k)%name // "'"
    if (g%vars(k)%overridden) s = s // ' (set by override)'
    s = s // ': '
  end function var_where

  !> Find `var` and mark it used. k = 0 when absent: an error unless a default exists.
  subroutine lookup(g, var, has_default, scalar, k, err)
    class(nml_group_t), intent(inout) :: g
    character(*), intent(in) :: var
    logical, intent(in) :: has_default, scalar
    integer, intent(out) :: k
    type(error_t), intent(inout) :: err
    integer :: n
    k = g%index_of(lower_case(trim(var)))
    if (k == 0) then
      if (.not. has_default) call err%set(ERR_INPUT, g%where() // &
        ": missing required variable '" // lower_case(trim(var)) // "'")
      return
    end if
    g%vars(k)%used = .true.
    n = sum(g%vars(k)%items%rep)
    if (scalar .and. n /= 1) then
      call err%set(ERR_INPUT, var_where(g, k) // 'expected one value, got ' // itoa(n))
      k = 0
    end if
  end subroutine lookup

  module procedure group_get_real
    character(:), allocatable :: msg
    integer :: k
    value = 0
    call lookup(this, var, present(default), .true., k, err)
    if (k == 0) then
      if (err%ok() .and. present(default)) value = default
      return
    end if
    call to_real(this%vars(k)%items(1), value, msg)
    if (len(msg) > 0) call err%set(ERR_INPUT, var_where(this, k) // msg)
  end procedure group_get_real

  module procedure group_get_int
    character(:), allocatable :: msg
    integer :: k
    value = 0
    call lookup(this, var, present(default), .true., k, err)
    if (k == 0) then
      if (err%ok() .and. present(default)) value = default
      return
    end if
    call to_int(this%vars(k)%items(1), value, msg)
    if (len(msg) > 0) call err%set(ERR_INPUT, var_where(this, k) // msg)
  end procedure group_get_int

  module procedure group_get_logical
    type(item_t) :: it
    integer :: k
    value = .false.
    call lookup(this, var, present(default), .true., k, err)
    if (k == 0) then
      if (err%ok() .and. present(default)) value = default
      return
    end if
    it = this%vars(k)%items(1)
    if (.not. it%quoted) then
      select case (lower_case(it%text))
      case ('.true.', '.t.', 't')
        value = .true.
        return
      case ('.false.', '.f.', 'f')
        return
      end select
    end if
    call err%set(ERR_INPUT, var_where(this, k) // 'expected a logical (.true. or .false.), got ' &
      // shown(it))
  end procedure group_get_logical

  module procedure group_get_string
    integer :: k
    value = ''
    call lookup(this, var, present(default), .true., k, err)
    if (k == 0) then
      if (err%ok() .and. present(default)) value = default
      return
    end if
    if (.not. this%vars(k)%items(1)%quoted) then
      call err%set(ERR_INPUT, var_where(this, k) // 'expected a quoted string, got ' // &
        shown(this%vars(k)%items(1)))
      return
    end if
    value = this%vars(k)%items(1)%text
  end procedure group_get_string

  module procedure group_get_real_array
    character(:), allocatable :: msg
    real(wp) :: x
    integer :: k, i, m
    call lookup(this, var, present(default), .false., k, err)
    if (k == 0) then
      allocate(values(0))
      if (err%ok() .and. present(default)) values = default
      return
    end if
    associate (items => this%vars(k)%items)
      allocate(values(sum(items%rep)))
      m = 0
      do i = 1, size(items)
        call to_real(items(i), x, msg)
        if (len(msg) > 0) then
          call err%set(ERR_INPUT, var_where(this, k) // 'value ' // itoa(m + 1) // ': ' // msg)
          return
        end if
        values(m + 1:m + items(i)%rep) = x
        m = m + items(i)%rep
      end do
    end associate
  end procedure group_get_real_array

  module procedure group_get_int_array
    character(:), allocatable :: msg
    integer :: k, i, m, x
    call lookup(this, var, present(default), .false., k, err)
    if (k == 0) then
      allocate(values(0))
      if (err%ok() .and. present(default)) values = default
      return
    end if
    associate (items => this%vars(k)%items)
      allocate(values(sum(items%rep)))
      m = 0
      do i = 1, size(items)
        call to_int(items(i), x, msg)
        if (len(msg) > 0) then
          call err%set(ERR_INPUT, var_where(this, k) // 'value ' // itoa(m + 1) // ': ' // msg)
          return
        end if
        values(m + 1:m + items(i)%rep) = x
        m = m + items(i)%rep
      end do
    end associate
  end procedure group_get_int_array

  module procedure group_get_string_array
    integer :: k, i, j, m
    call lookup(this, var, present(default), .false., k, err)
    if (k == 0) then
      allocate(values(0))
      if (err%ok() .and. present(default)) values = default
      return
    end if
    associate (items => this%vars(k)%items)
      allocate(values(sum(items%rep)))
      m = 0
      do i = 1, size(items)
        if (.not. items(i)%quoted) then
          call err%set(ERR_INPUT, var_where(this, k) // 'value ' // itoa(m + 1) // &
            ': expected a quoted string, got ' // shown(items(i)))
          deallocate(values)
          allocate(values(0))
          return
        end if
        do j = 1, items(i)%rep
          m = m + 1
          values(m)%s = items(i)%text
        end do
      end do
    end associate
  end procedure group_get_string_array
end submodule io_namelist_getters
