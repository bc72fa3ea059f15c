!> Transfer functions of the kinematics: DF and DF^T applied through solves with the factors of
!> J_c, the dense DF for small models, and the second-order terms D2F qd qd.
submodule (model_kinematics) model_kinematics_transfer
  implicit none

contains

  !> Right-hand sides of J_c DF_c = (selection of q) - J_in for the nc columns dq (n_q, nc).
  !> Explicit shapes: a vector is passed as one column without a reshaped copy.
  subroutine transfer_rhs(this, model, nc, dq, b)
    type(kinematics_t), intent(in) :: this
    type(model_t), intent(in) :: model
    integer, intent(in) :: nc
    real(wp), intent(in) :: dq(model%n_q, nc)
    real(wp), intent(out) :: b(model%n_c, nc)
    integer :: c
    do c = 1, nc
      call rhs_column(model%n_c, model%n_q, size(this%in_row), model%row_q, this%in_row, &
        this%in_q, this%in_val, dq(:, c), b(:, c))
    end do
  end subroutine transfer_rhs

  ! The loops of the transfer functions on explicit-shape arrays: the compiler keeps the bases
  ! in registers where it reloaded each component's descriptor per entry, and assigns each
  ! entry once where whole-array zeroing went first.

  !> One column of transfer_rhs.
  pure subroutine rhs_column(n_c, n_q, n_in, row_q, in_row, in_q, in_val, dq, b)
    integer, intent(in) :: n_c, n_q, n_in, row_q(n_c), in_row(n_in), in_q(n_in)
    real(wp), intent(in) :: in_val(n_in), dq(n_q)
    real(wp), intent(out) :: b(n_c)
    integer :: row, k
    do row = 1, n_c
      if (row_q(row) > 0) then
        b(row) = dq(row_q(row))
      else
        b(row) = 0.0_wp
      end if
    end do
    do k = 1, n_in
      b(in_row(k)) = b(in_row(k)) - in_val(k) * dq(in_q(k))
    end do
  end subroutine rhs_column

  !> Nodal vector dx (n_x) from its calculable part b (n_c) and its inputs dq (n_dq = n_q, or
  !> 0 for zero inputs): the other coordinates are zero. One pass over the coordinates, read
  !> through calc_index and input_q (a calculable coordinate is never an input).
  pure subroutine nodal_from(n_x, n_c, n_dq, calc_index, input_q, b, dq, dx)
    integer, intent(in) :: n_x, n_c, n_dq, calc_index(n_x), input_q(n_x)
    real(wp), intent(in) :: b(n_c), dq(n_dq)
    real(wp), intent(out) :: dx(n_x)
    integer :: i
    do i = 1, n_x
      if (calc_index(i) > 0) then
        dx(i) = b(calc_index(i))
      else if (input_q(i) > 0 .and. n_dq > 0) then
        dx(i) = dq(input_q(i))
      else
        dx(i) = 0.0_wp
      end if
    end do
  end subroutine nodal_from

  module procedure kin_apply_df
    call apply_df_columns(this, model, 1, dq, dx)
  end procedure kin_apply_df

  module procedure kin_apply_df_many
    call apply_df_columns(this, model, size(dq, 2), dq, dx)
  end procedure kin_apply_df_many

  subroutine apply_df_columns(this, model, nc, dq, dx)
    type(kinematics_t), intent(inout) :: this
    type(model_t), intent(in) :: model
    integer, intent(in) :: nc
    real(wp), intent(in) :: dq(model%n_q, nc)
    real(wp), intent(out) :: dx(model%n_x, nc)
    real(wp) :: b(model%n_c, nc)
    integer :: c
    call transfer_rhs(this, model, nc, dq, b)
    call this%jacobian_solve(b)
    do c = 1, nc
      call nodal_from(model%n_x, model%n_c, model%n_q, model%calc_index, model%input_q, b(:, c), &
        dq(:, c), dx(:, c))
    end do
  end subroutine apply_df_columns

  module procedure kin_apply_dft
    real(wp) :: z(model%n_c, 1)
    integer :: row, k, iq
    z(:, 1) = g(model%calc_coord)
    call this%jacobian_solve(z, transposed=.true.)
    g_q = 0.0_wp
    do row = 1, model%n_c
      if (model%row_q(row) > 0) g_q(model%row_q(row)) = z(row, 1)
    end do
    do k = 1, size(this%in_row)
      g_q(this%in_q(k)) = g_q(this%in_q(k)) - this%in_val(k) * z(this%in_row(k), 1)
    end do
    do iq = 1, model%n_q
      if (model%q_coord(iq) > 0) g_q(iq) = g_q(iq) + g(model%q_coord(iq))
    end do
  end procedure kin_apply_dft

  module procedure kin_transfer
    real(wp) :: b(model%n_c, model%n_q), unit(model%n_q, model%n_q)
    integer :: iq
    unit = 0.0_wp
    do iq = 1, model%n_q
      unit(iq, iq) = 1.0_wp
    end do
    call transfer_rhs(this, model, model%n_q, unit, b)
    call this%jacobian_solve(b)
    ! Allocated here, on first use: dense (n_x by n_q), it is what the sparse path avoids.
    if (.not. allocated(this%df)) allocate(this%df(model%n_x, model%n_q))
    this%df = 0.0_wp
    this%df(model%calc_coord, :) = b
    do iq = 1, model%n_q
      if (model%q_coord(iq) > 0) this%df(model%q_coord(iq), iq) = 1.0_wp
    end do
    this%has_df = .true.
  end procedure kin_transfer

  module procedure kin_second
    real(wp) :: xd(model%n_x), d2e(size(model%modes))
    real(wp) :: xe(model%max_dofs), xde(model%max_dofs)
    integer :: iel, k, nm, nd, first
    if (present(xd_known)) then
      xd = xd_known
    else
      call this%apply_df(model, qd, xd)
    end if
    do iel = 1, model%n_elements
      nm = this%el_nm(iel)
      nd = this%el_nd(iel)
      first = model%mode_first(iel)
      associate (el => model%elements(iel)%e)
        do k = 1, nd
          xe(k) = this%x(el%dofs(k))
          xde(k) = xd(el%dofs(k))
        end do
        call el%second(xe(1:nd), xde(1:nd), d2e(first:first + nm - 1))
      end associate
    end do
    call this%second_solve(model, d2e, d2x, qdd)
  end procedure kin_second

  module procedure kin_second_solve
    real(wp) :: rhs(model%n_c, 1)
    integer :: m, row
    if (present(qdd)) then
      call transfer_rhs(this, model, 1, qdd, rhs)
    else
      rhs = 0.0_wp
    end if
    do m = 1, size(d2e)
      row = this%mode_row(m)
      if (row > 0) rhs(row, 1) = rhs(row, 1) - d2e(m)
    end do
    call this%jacobian_solve(rhs)
    if (present(qdd)) then
      call nodal_from(model%n_x, model%n_c, model%n_q, model%calc_index, model%input_q, &
        rhs(:, 1), qdd, d2x)
    else
      call nodal_from(model%n_x, model%n_c, 0, model%calc_index, model%input_q, rhs(:, 1), &
        d2e(1:0), d2x)
    end if
  end procedure kin_second_solve
end submodule model_kinematics_transfer
