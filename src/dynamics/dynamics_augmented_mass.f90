!> Products with the element masses (element_mass_t): the lumped masses and the element
!> blocks, on transposed arrays so that an element's rows of every column are contiguous.
submodule (dynamics_augmented) dynamics_augmented_mass
  implicit none

contains

  !> M w for nodal vectors w (n_x, k): the lumped masses and the element blocks, in place
  !> on the flat blocks (no block copies), every column of an element's rows at once.
  module procedure mass_times
    ! Rows of w gathered per element as the contiguous rows of w_t: every column at once.
    real(wp) :: w_t(size(w, 2), size(w, 1)), mw_t(size(w, 2), size(w, 1))
    integer :: iel, nd, c, first, d0
    w_t = transpose(w)
    do c = 1, size(w, 1)
      mw_t(:, c) = model%lumped(c) * w_t(:, c)
    end do
    do iel = 1, model%n_elements
      first = this%offset(iel)
      if (first == 0) cycle
      d0 = this%dof_first(iel) - 1
      nd = this%dof_first(iel + 1) - 1 - d0
      call add_block(nd, size(w, 2), size(w, 1), this%val(first:first + nd * nd - 1), &
        this%dofs(d0 + 1:d0 + nd), w_t, mw_t)
    end do
    mw = transpose(mw_t)
  end procedure mass_times

  !> (M - M_base) w for the element blocks of this and base, two sets of element masses of the
  !> same model (the lumped masses cancel): a difference quotient of the mass along a motion.
  module procedure mass_difference_times
    real(wp) :: w_t(size(w, 2), size(w, 1)), dw_t(size(w, 2), size(w, 1))
    real(wp) :: dm(model%max_dofs**2)
    integer :: iel, nd, first, d0, i
    w_t = transpose(w)
    dw_t = 0.0_wp
    do iel = 1, model%n_elements
      first = this%offset(iel)
      if (first == 0) cycle
      d0 = this%dof_first(iel) - 1
      nd = this%dof_first(iel + 1) - 1 - d0
      do i = 1, nd * nd
        dm(i) = this%val(first + i - 1) - base%val(first + i - 1)
      end do
      call add_block(nd, size(w, 2), size(w, 1), dm, this%dofs(d0 + 1:d0 + nd), w_t, dw_t)
    end do
    dw = transpose(dw_t)
  end procedure mass_difference_times

  !> mw_t(:, dofs) += w_t(:, dofs) m^T for one element block m (nd x nd, symmetric), on
  !> transposed (columns x coordinates) arrays.
  pure subroutine add_block(nd, nc, n, m, dofs, w_t, mw_t)
    integer, intent(in) :: nd, nc, n, dofs(nd)
    ! Explicit shapes: contiguous columns, which the compiler vectorises.
    real(wp), intent(in) :: m(nd, nd), w_t(nc, n)
    real(wp), intent(inout) :: mw_t(nc, n)
    integer :: k, l
    do k = 1, nd
      do l = 1, nd
        mw_t(:, dofs(k)) = mw_t(:, dofs(k)) + m(k, l) * w_t(:, dofs(l))
      end do
    end do
  end subroutine add_block
end submodule dynamics_augmented_mass
