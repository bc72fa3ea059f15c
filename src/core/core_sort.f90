!> Sorting of short index lists by integer keys (the sparse set-ups: entries of a column by row,
!> a block's outside columns) or real values (eigenvalues, Ritz values): stable insertion
!> sorts, since the lists are short. Two routines, not one: converting the sparse set-ups'
!> integer keys to reals would copy the whole key array per column.
module core_sort
  use core_kinds, only: wp
  implicit none
  private
  public :: sort_by_key, sort_by_value

contains

  !> Reorder idx so that keys(idx) ascends; equal keys keep their order.
  pure subroutine sort_by_key(idx, keys)
    integer, intent(inout) :: idx(:)
    integer, intent(in) :: keys(:)
    integer :: i, j, key
    do i = 2, size(idx)
      key = idx(i)
      j = i - 1
      do while (j >= 1)
        if (keys(idx(j)) <= keys(key)) exit
        idx(j + 1) = idx(j)
        j = j - 1
      end do
      idx(j + 1) = key
    end do
  end subroutine sort_by_key

  !> Reorder idx so that values(idx) ascends; equal values keep their order (for descending
  !> order pass -values).
  pure subroutine sort_by_value(idx, values)
    integer, intent(inout) :: idx(:)
    real(wp), intent(in) :: values(:)
    integer :: i, j, key
    do i = 2, size(idx)
      key = idx(i)
      j = i - 1
      do while (j >= 1)
        if (values(idx(j)) <= values(key)) exit
        idx(j + 1) = idx(j)
        j = j - 1
      end do
      idx(j + 1) = key
    end do
  end subroutine sort_by_value
end module core_sort
