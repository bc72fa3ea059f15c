!> The series' second and third terms X2 and X3 of an expansion (reduction_expansion), from the
!> kinematic factors at z0 only: element passes with every direction at once, then one solve
!> with every column.
!>
!> On the kinematic rows the constraints read D(x(z)) = linear in z, so that
!>     J X2_ab = R_ab := -D''[X1_a, X1_b]   and   J X3_lab = d R_ab / d z_l - J' X2_ab,
!> J = D' at x(z). The derivative along z_l is a one-sided difference of element quantities
!> only, (R_ab - J X2_ab)(x_h) / h with x_h = x0 + h X1_l + h^2 X2_ll / 2 and the directions
!> X1 + h X2_l (at x0 the bracket is X2's solve residual, round-off): one element pass per l
!> for both terms, and no kinematic solve at z0 + h e_l. Along a joint that turns part of the
!> model rigidly (the first `first - 1` directions, reduction_turns) neither is needed: its
!> columns are the turn's products of the columns one order lower.
submodule (reduction_expansion) reduction_expansion_series
  implicit none

  !> Nodal motion of X3's difference step, relative to the model's size: truncation about
  !> 1e-6 relative, round-off about 1e-10.
  real(wp), parameter :: THIRD_STEP = 1.0e-6_wp

contains

  !> x2(:, a, b) = D2F[T_a, T_b] (and its mirror) from the nodal shapes x1 = DF T at the
  !> kinematics' current solution: by polarised element terms and one solve for
  !> first <= a <= b, as turns' products for a < first.
  module procedure second_terms
    real(wp) :: rhs(dyn%model%n_c, n_pairs(size(x1, 2), first))
    integer :: a, b, m, k
    m = size(x1, 2)
    x2 = 0.0_wp
    if (first <= m) then
      call polarised_rhs(dyn, dyn%kin%x, x1, first, rhs)
      call dyn%kin%jacobian_solve(rhs)
      do a = first, m
        do b = a, m
          do k = 1, dyn%model%n_c
            x2(dyn%model%calc_coord(k), a, b) = rhs(k, pair_column(a, b, first, m))
          end do
        end do
      end do
    end if
    do a = 1, first - 1
      do b = a, m
        call turn_derivative(turns(a), x1(:, b), x2(:, a, b))
      end do
    end do
    do a = 1, m
      do b = a + 1, m
        x2(:, b, a) = x2(:, a, b)
      end do
    end do
  end procedure second_terms

  !> X3(:, l, a, b) for l <= a <= b, the distinct columns of the symmetric X3, in the order of
  !> tri(l, a, b); the kinematics stays at z0. Along a turn l (l < first) a column is the
  !> turn's product of X2(:, a, b); the others come from the element differences and one
  !> solve with all their columns.
  module procedure third_terms
    real(wp) :: x1h(size(this%x1, 1), this%m), xh(size(this%x0)), h
    real(wp), allocatable :: rhs(:, :), w(:, :), p(:, :), jw(:, :)
    integer :: l, a, b, c, k, np, m, n_turned
    m = this%m
    if (allocated(this%x3)) deallocate(this%x3, this%tri)
    allocate(this%x3(size(this%x0), m * (m + 1) * (m + 2) / 6), this%tri(m, m, m))
    this%tri = 0
    ! The turns' columns first, then those from differences (one solve for all of them).
    c = 0
    do l = 1, first - 1
      do a = l, m
        do b = a, m
          c = c + 1
          this%tri(l, a, b) = c
          call turn_derivative(turns(l), this%x2(:, a, b), this%x3(:, c))
        end do
      end do
    end do
    n_turned = c
    allocate(rhs(dyn%model%n_c, size(this%x3, 2) - n_turned))
    do l = first, m
      h = THIRD_STEP * size_x / max(tiny(1.0_wp), maxval(abs(this%x1(:, l))))
      xh = this%x0 + h * this%x1(:, l) + (0.5_wp * h**2) * this%x2(:, l, l)
      do a = l, m
        x1h(:, a) = this%x1(:, a) + h * this%x2(:, a, l)
      end do
      np = n_pairs(m, l)
      allocate(w(size(this%x0), np), p(dyn%model%n_c, np), jw(dyn%model%n_c, np))
      do a = l, m
        do b = a, m
          w(:, pair_column(a, b, l, m)) = this%x2(:, a, b)
          this%tri(l, a, b) = c + pair_column(a, b, l, m)
        end do
      end do
      call polarised_rhs(dyn, xh, x1h, l, p, w, jw)
      rhs(:, c - n_turned + 1:c - n_turned + np) = (p - jw) / h
      deallocate(w, p, jw)
      c = c + np
    end do
    if (size(rhs, 2) > 0) call dyn%kin%jacobian_solve(rhs)
    this%x3(:, n_turned + 1:) = 0.0_wp
    do k = 1, dyn%model%n_c
      this%x3(dyn%model%calc_coord(k), n_turned + 1:) = rhs(k, :)
    end do
  end procedure third_terms

  !> Number of pairs first <= a <= b <= m.
  pure integer function n_pairs(m, first) result(n)
    integer, intent(in) :: m, first
    n = (m - first + 1) * (m - first + 2) / 2
  end function n_pairs

  !> Column of the pair (a, b), first <= a <= b <= m, row by row of a.
  pure integer function pair_column(a, b, first, m) result(c)
    integer, intent(in) :: a, b, first, m
    ! Rows first .. a - 1 hold m - first + 1, m - first, ... pairs.
    c = (a - first) * (2 * (m - first + 1) - (a - first) + 1) / 2 + (b - a) + 1
  end function pair_column

  !> p(:, pair_column(a, b)) = -D''(x)[d_a, d_b] on the kinematic rows for first <= a <= b, by
  !> polarisation of the second-order terms along d_a and d_a + d_b; with w also jw = D'(x) w.
  !> One element pass.
  subroutine polarised_rhs(dyn, x, d, first, p, w, jw)
    type(dynamics_t), intent(in) :: dyn
    real(wp), intent(in) :: x(:), d(:, :)
    integer, intent(in) :: first
    real(wp), intent(out) :: p(:, :)
    real(wp), intent(in), optional :: w(:, :)
    real(wp), intent(out), optional :: jw(:, :)
    real(wp) :: xd(size(d, 1), size(p, 2)), raw(size(p, 1), size(p, 2))
    integer :: a, b, m
    m = size(d, 2)
    do a = first, m
      do b = a, m
        if (a == b) then
          xd(:, pair_column(a, b, first, m)) = d(:, a)
        else
          xd(:, pair_column(a, b, first, m)) = d(:, a) + d(:, b)
        end if
      end do
    end do
    call element_terms(dyn, x, xd, raw, w, jw)
    p = raw
    do a = first, m
      do b = a + 1, m
        p(:, pair_column(a, b, first, m)) = 0.5_wp * (raw(:, pair_column(a, b, first, m)) - &
          raw(:, pair_column(a, a, first, m)) - raw(:, pair_column(b, b, first, m)))
      end do
    end do
  end subroutine polarised_rhs

  !> rhs = -D''(x)[xd_c, xd_c] on the kinematic rows (kinematics_t%second's right-hand side with
  !> the velocities known) for every column, and with w also jw = D'(x) w: one element pass
  !> (el%second_many, el%evaluate). The columns are gathered and summed along the transposes,
  !> which keep each coordinate's and each row's values contiguous.
  subroutine element_terms(dyn, x, xd, rhs, w, jw)
    type(dynamics_t), intent(in) :: dyn
    real(wp), intent(in) :: x(:), xd(:, :)
    real(wp), intent(out) :: rhs(:, :)
    real(wp), intent(in), optional :: w(:, :)
    real(wp), intent(out), optional :: jw(:, :)
    real(wp) :: d2e(dyn%model%max_modes, size(xd, 2)), xe(dyn%model%max_dofs)
    real(wp) :: xde(dyn%model%max_dofs, size(xd, 2)), e(dyn%model%max_modes)
    real(wp) :: de(dyn%model%max_modes, dyn%model%max_dofs)
    real(wp) :: xd_t(size(xd, 2), size(xd, 1)), rhs_t(size(xd, 2), dyn%model%n_c)
    real(wp), allocatable :: w_t(:, :), jw_t(:, :)
    integer :: iel, j, k, nd, nm, row
    logical :: with_w
    with_w = present(w) .and. present(jw)
    xd_t = transpose(xd)
    rhs_t = 0.0_wp
    if (with_w) then
      w_t = transpose(w)
      allocate(jw_t(size(w, 2), dyn%model%n_c))
      jw_t = 0.0_wp
    end if
    do iel = 1, dyn%model%n_elements
      associate (el => dyn%model%elements(iel)%e)
        nd = size(el%dofs)
        nm = el%n_modes()
        do k = 1, nd
          xe(k) = x(el%dofs(k))
          xde(k, :) = xd_t(:, el%dofs(k))
        end do
        call el%second_many(xe(1:nd), xde(1:nd, :), d2e(1:nm, :))
        if (with_w) call el%evaluate(xe(1:nd), e(1:nm), de(1:nm, 1:nd))
        do j = 1, nm
          row = dyn%kin%mode_row(dyn%model%mode_first(iel) + j - 1)
          if (row == 0) cycle
          rhs_t(:, row) = rhs_t(:, row) - d2e(j, :)
          if (.not. with_w) cycle
          do k = 1, nd
            jw_t(:, row) = jw_t(:, row) + de(j, k) * w_t(:, el%dofs(k))
          end do
        end do
      end associate
    end do
    rhs = transpose(rhs_t)
    if (with_w) jw = transpose(jw_t)
  end subroutine element_terms
end submodule reduction_expansion_series
