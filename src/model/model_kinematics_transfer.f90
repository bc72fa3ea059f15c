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
    integer :: row, k, c
    do c = 1, nc
      do row = 1, model%n_c
        b(row, c) = 0.0_wp
        if (model%row_q(row) > 0) b(row, c) = dq(model%row_q(row), c)
      end do
      do k = 1, size(this%in_row)
        b(this%in_row(k), c) = b(this%in_row(k), c) - this%in_val(k) * dq(this%in_q(k), c)
      end do
    end do
  end subroutine transfer_rhs

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
    integer :: iq, i, c
    call transfer_rhs(this, model, nc, dq, b)
    call this%jacobian_solve(b)
    do c = 1, nc
      dx(:, c) = 0.0_wp
      do i = 1, model%n_c
        dx(model%calc_coord(i), c) = b(i, c)
      end do
      do iq = 1, model%n_q
        if (model%q_coord(iq) > 0) dx(model%q_coord(iq), c) = dq(iq, c)
      end do
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
    integer :: m, row, i, iq
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
    d2x = 0.0_wp
    do i = 1, model%n_c
      d2x(model%calc_coord(i)) = rhs(i, 1)
    end do
    if (.not. present(qdd)) return
    do iq = 1, model%n_q
      if (model%q_coord(iq) > 0) d2x(model%q_coord(iq)) = qdd(iq)
    end do
  end procedure kin_second_solve
end submodule model_kinematics_transfer
