!> Groups with very many variables parse in time linear in their number: the name index grows
!> geometrically and finds every name, and a group of 100,000 variables parses (at the old
!> O(n^2), 20,000 took 45 s, so this one would take about 19 min and hit the CTest timeout).
program test_namelist_large
  use core_error, only: error_t
  use core_strings, only: int_str
  use io_namelist, only: nml_file_t
  use io_name_index, only: name_index_t
  use testing, only: suite_t
  implicit none
  character(*), parameter :: NL = new_line('a')
  type(suite_t) :: t

  call t%init('namelist: large groups')
  call test_index_growth()
  call test_many_small_indices()
  call test_large_group()
  call t%finish()

contains

  subroutine test_index_growth()
    type(name_index_t) :: idx
    integer, parameter :: N = 200000
    integer :: i, worst_capacity, misses
    misses = 0
    worst_capacity = 0
    do i = 1, N
      call idx%add(name(i))
      ! Room is at most 8 slots per name beyond the first allocation: names (doubling, at
      ! most 2 per name) and slots (at most a quarter full after doubling, at most 8).
      worst_capacity = max(worst_capacity, idx%capacity() - 10 * idx%size())
    end do
    call t%check(idx%size() == N, 'every name added')
    call t%check(worst_capacity <= 80, 'room grows in proportion to the names')
    do i = 1, N
      if (idx%find(name(i)) /= i) misses = misses + 1
    end do
    call t%check(misses == 0, 'every name found at its position')
    call t%check(idx%find('absent') == 0 .and. idx%find('v') == 0, 'an absent name is 0')
  end subroutine test_index_growth

  !> Fresh indices on reused memory: the slots of the first allocation were not cleared, so
  !> that a group parsed after others probed garbage (a segmentation fault in test_kinematics).
  subroutine test_many_small_indices()
    integer :: round, i, misses, k
    type :: dirt_t
      integer, allocatable :: a(:)
    end type dirt_t
    type(dirt_t) :: dirt(8)
    misses = 0
    do round = 1, 300
      ! Dirty the blocks an index allocates first (its slots, and its names' descriptors).
      do k = 1, size(dirt)
        allocate(dirt(k)%a(16 * (1 + mod(k - 1, 4))))
        dirt(k)%a = 7 + round
      end do
      do k = 1, size(dirt)
        deallocate(dirt(k)%a)
      end do
      block
        type(name_index_t) :: idx
        do i = 1, 1 + mod(round, 40)
          if (idx%find(name(i)) /= 0) misses = misses + 1
          call idx%add(name(i))
        end do
        do i = 1, 1 + mod(round, 40)
          if (idx%find(name(i)) /= i) misses = misses + 1
        end do
      end block
    end do
    call t%check(misses == 0, 'fresh indices start empty')
  end subroutine test_many_small_indices

  subroutine test_large_group()
    integer, parameter :: N = 100000
    character(:), allocatable :: text, line
    type(nml_file_t) :: f
    type(error_t) :: err
    integer :: i, pos
    ! Written into a buffer of its final size: appending line by line is O(N^2) itself.
    allocate(character(16 * N) :: text)
    text(1:3) = '&g' // NL
    pos = 4
    do i = 1, N
      line = name(i) // ' = 1' // NL
      text(pos:pos + len(line) - 1) = line
      pos = pos + len(line)
    end do
    text = text(:pos - 1)
    call f%parse(text // '/' // NL, 'big.nml', err)
    call t%check(err%ok(), '100,000 variables parse')
    if (err%ok()) then
      call t%check(f%groups(1)%has(name(1)) .and. f%groups(1)%has(name(N)) .and. &
        .not. f%groups(1)%has('v0'), 'all kept')
    end if
    call err%clear()
    call f%parse(text // name(N / 2) // ' = 2 /' // NL, 'big.nml', err)
    call t%check(index(err%message, "variable '" // name(N / 2) // "' assigned twice " // &
      '(first on line 50001)') > 0, 'a repeat among them is found')
    if (.not. err%ok()) write(*, '(a)') '        -> ' // err%message
  end subroutine test_large_group

  pure function name(i) result(s)
    integer, intent(in) :: i
    character(:), allocatable :: s
    s = 'v' // int_str(i)
  end function name
end program test_namelist_large
