!> Sorting of the small integer lists the sparse set-ups order (entries of a column by row, a
!> block's outside columns): stable insertion sort, since the lists are short.
module core_sort
  implicit none
  private
  public :: sort_by_key

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
end module core_sort
