!> Names of a namelist group in the order given, with a hash index: adding a name and finding
!> one take constant time on average, so that a group of n variables parses in O(n). Appending
!> to an exactly sized array and searching it name by name made both O(n^2): a group of 20,000
!> variables took 45 s to parse.
module io_name_index
  implicit none
  private
  public :: name_index_t

  type :: key_t
    character(:), allocatable :: s
  end type key_t

  type :: name_index_t
    private
    type(key_t), allocatable :: keys(:)   ! keys(1:n) in the order added
    integer, allocatable :: slot(:)       ! open addressing: 0 empty, else an index into keys
    integer :: n = 0
  contains
    procedure :: add => index_add
    procedure :: find => index_find
    procedure :: size => index_size
    procedure :: capacity => index_capacity
  end type name_index_t

contains

  !> Position of `name` (1 .. size), 0 if it was not added.
  pure integer function index_find(this, name) result(k)
    class(name_index_t), intent(in) :: this
    character(*), intent(in) :: name
    integer :: h
    k = 0
    if (.not. allocated(this%slot)) return
    h = home(name, size(this%slot))
    do
      k = this%slot(h)
      if (k == 0) return
      if (this%keys(k)%s == name) return
      h = mod(h, size(this%slot)) + 1
    end do
  end function index_find

  !> Adds `name` (which must not be there yet: find first) as position size + 1.
  pure subroutine index_add(this, name)
    class(name_index_t), intent(inout) :: this
    character(*), intent(in) :: name
    type(key_t), allocatable :: tmp(:)
    if (.not. allocated(this%keys)) then
      allocate(this%keys(16), this%slot(64))
      this%slot = 0
    end if
    ! Capacity doubles, so the copies add up to O(n) over n additions.
    if (this%n == size(this%keys)) then
      allocate(tmp(2 * this%n))
      tmp(1:this%n) = this%keys(1:this%n)
      call move_alloc(tmp, this%keys)
    end if
    this%n = this%n + 1
    this%keys(this%n)%s = name
    ! At most a quarter full, so a probe sequence stays short.
    if (4 * this%n > size(this%slot)) then
      call rehash(this, 2 * size(this%slot))
    else
      call place(this, this%n)
    end if
  end subroutine index_add

  pure integer function index_size(this)
    class(name_index_t), intent(in) :: this
    index_size = this%n
  end function index_size

  !> Entries the index holds room for (names and slots): O(size), whatever the order of adds.
  pure integer function index_capacity(this)
    class(name_index_t), intent(in) :: this
    index_capacity = 0
    if (allocated(this%keys)) index_capacity = size(this%keys) + size(this%slot)
  end function index_capacity

  pure subroutine rehash(this, n_slots)
    type(name_index_t), intent(inout) :: this
    integer, intent(in) :: n_slots
    integer :: k
    deallocate(this%slot)
    allocate(this%slot(n_slots))
    this%slot = 0
    do k = 1, this%n
      call place(this, k)
    end do
  end subroutine rehash

  pure subroutine place(this, k)
    type(name_index_t), intent(inout) :: this
    integer, intent(in) :: k
    integer :: h
    h = home(this%keys(k)%s, size(this%slot))
    do while (this%slot(h) /= 0)
      h = mod(h, size(this%slot)) + 1
    end do
    this%slot(h) = k
  end subroutine place

  !> FNV-1a of the name, folded into 1 .. n_slots (in 64-bit integers that cannot overflow).
  pure integer function home(name, n_slots)
    character(*), intent(in) :: name
    integer, intent(in) :: n_slots
    integer, parameter :: i8 = selected_int_kind(18)
    integer(i8) :: h
    integer :: i
    h = 2166136261_i8
    do i = 1, len(name)
      h = modulo(ieor(h, int(iachar(name(i:i)), i8)) * 16777619_i8, 4294967296_i8)
    end do
    home = int(modulo(h, int(n_slots, i8))) + 1
  end function home
end module io_name_index
