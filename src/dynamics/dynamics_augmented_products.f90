!> The products of the augmented form: nodal forces from generalised ones (J_d^T) and the
!> accelerations from the factors (J_d y after the solve).
submodule (dynamics_augmented) dynamics_augmented_products
  implicit none

contains

  module procedure aug_nodal_equivalent
    integer :: c, iq
    do c = 1, size(g, 2)
      call jd_transpose_times(size(this%dyn_q), size(this%jd_de), size(this%de_val), model%n_x, &
        size(g, 1), this%jd_first, this%dyn_q, this%jd_de, this%jd_coord, this%de_val, g(:, c), &
        f(:, c))
      do iq = model%n_rh + 1, model%n_q
        if (model%q_coord(iq) > 0) f(model%q_coord(iq), c) = f(model%q_coord(iq), c) + &
          g(iq - model%n_rh, c)
      end do
    end do
  end procedure aug_nodal_equivalent

  module procedure aug_accelerations
    real(wp) :: b(this%n_free + this%n_con, size(f, 2))
    integer :: i, c, iq
    do c = 1, size(f, 2)
      b(this%n_free + 1:, c) = 0.0_wp
      do i = 1, model%n_x
        if (this%free_index(i) > 0) b(this%free_index(i), c) = f(i, c)
      end do
    end do
    if (present(newton)) then
      if (newton) then
        call this%newton%solve_many(b)
      else
        call this%lu%solve_many(b)
      end if
    else
      call this%lu%solve_many(b)
    end if
    ! y = DF_dy a is b on the free coordinates (zero elsewhere): read through free_index.
    do c = 1, size(f, 2)
      call jd_times(size(this%dyn_q), size(this%jd_de), size(this%de_val), size(b, 1), &
        size(a, 1), this%jd_first, this%jd_last_free, this%dyn_q, this%jd_de, this%jd_free, &
        this%de_val, b(:, c), a(:, c))
      do iq = model%n_rh + 1, model%n_q
        if (model%q_coord(iq) > 0) then
          i = this%free_index(model%q_coord(iq))
          a(iq - model%n_rh, c) = 0.0_wp
          if (i > 0) a(iq - model%n_rh, c) = b(i, c)
        end if
      end do
    end do
  end procedure aug_accelerations

  ! The products with J_d on explicit-shape arrays: the compiler keeps the bases in registers
  ! where it reloaded each component's descriptor per entry.

  !> f = J_d^T g over the dynamic modes (zero on the other coordinates), mode by mode: its
  !> generalised force is read once for its entries.
  pure subroutine jd_transpose_times(n_dyn, n_jd, n_de, n_x, n_g, first, dyn_q, jd_de, &
      jd_coord, de, g, f)
    integer, intent(in) :: n_dyn, n_jd, n_de, n_x, n_g
    integer, intent(in) :: first(n_dyn + 1), dyn_q(n_dyn), jd_de(n_jd), jd_coord(n_jd)
    real(wp), intent(in) :: de(n_de), g(n_g)
    real(wp), intent(out) :: f(n_x)
    real(wp) :: gi
    integer :: i, p
    f = 0.0_wp
    do i = 1, n_dyn
      gi = g(dyn_q(i))
      do p = first(i), first(i + 1) - 1
        f(jd_coord(p)) = f(jd_coord(p)) + de(jd_de(p)) * gi
      end do
    end do
  end subroutine jd_transpose_times

  !> a = J_d y for y = b on the free coordinates (zero elsewhere), mode by mode (its entries
  !> of free coordinates are consecutive): its acceleration summed in a scalar.
  pure subroutine jd_times(n_dyn, n_jd, n_de, n_b, n_a, first, last_free, dyn_q, jd_de, &
      jd_free, de, b, a)
    integer, intent(in) :: n_dyn, n_jd, n_de, n_b, n_a
    integer, intent(in) :: first(n_dyn + 1), last_free(n_dyn), dyn_q(n_dyn), jd_de(n_jd), &
      jd_free(n_jd)
    real(wp), intent(in) :: de(n_de), b(n_b)
    real(wp), intent(out) :: a(n_a)
    real(wp) :: s
    integer :: j, p
    a = 0.0_wp
    do j = 1, n_dyn
      s = 0.0_wp
      do p = first(j), last_free(j)
        s = s + de(jd_de(p)) * b(jd_free(p))
      end do
      a(dyn_q(j)) = s
    end do
  end subroutine jd_times
end submodule dynamics_augmented_products
