!> Newton support for the implicit integrators: the Jacobian, the sparse iteration solver
!> and the error norm of the equations of motion (documented at their interfaces).
submodule (dynamics_system) dynamics_system_newton
  use integrators_system, only: JACOBIAN_FD
  implicit none

contains

  module procedure dyn_jacobian
    real(wp) :: a(size(q)), chol(size(q), size(q)), k0(size(q), size(q)), d0(size(q), size(q))
    integer :: j, info
    if (this%jacobian_kind == JACOBIAN_FD) then
      call system_fd_jacobian(this, t, q, v, dadq, dadv, status)
      return
    end if
    call this%accel(t, q, v, a, status)
    if (status /= 0) return
    call this%structural_stiffness(k0, d0)
    if (this%sparse) then
      call this%aug%accelerations(this%model, -this%aug%nodal_equivalent(this%model, k0), dadq)
      call this%aug%accelerations(this%model, -this%aug%nodal_equivalent(this%model, d0), dadv)
      return
    end if
    chol = this%mbar
    call chol_factor(chol, info)
    do j = 1, size(q)
      dadq(:, j) = -k0(:, j)
      dadv(:, j) = -d0(:, j)
      call chol_solve(chol, dadq(:, j))
      call chol_solve(chol, dadv(:, j))
    end do
  end procedure dyn_jacobian

  module procedure dyn_has_iteration_solver
    dyn_has_iteration_solver = this%sparse .and. this%jacobian_kind == JACOBIAN_LINEARISED
  end procedure dyn_has_iteration_solver

  module procedure dyn_iteration_factor
    integer :: info
    call this%aug%factor_newton(this%model, this%mass, c_q, c_v, info, &
      de_val=this%kin%de_val)
    status = 0
    if (info /= 0) status = 1
  end procedure dyn_iteration_factor

  module procedure dyn_newton_correction
    real(wp) :: r_q(this%model%n_q)
    real(wp) :: r(size(x), 1), a(size(x), 1)
    type(error_t) :: err
    dx = 0.0_wp
    ! nodal_force is then f - M DF_dy x - M conv - h, whose projection is the residual.
    call this%prepare(t, q, v, err, x)
    if (err%ok()) then
      call this%kin%apply_dft(this%model, this%nodal_force, r_q)
      r(:, 1) = r_q(this%model%n_rh + 1:) - this%sigma_now
      call this%aug%accelerations(this%model, this%aug%nodal_equivalent(this%model, r), a, &
        newton=.true.)
      dx = a(:, 1)
      call check_finite(dx, t, err)
    end if
    call this%report(err, status)
    if (status /= 0) dx = 0.0_wp
  end procedure dyn_newton_correction

  module procedure dyn_error_norm
    real(wp) :: dqf(this%model%n_q, 3), dx(this%model%n_x, 3), motion(this%model%n_x)
    integer :: nr
    nr = this%model%n_rh
    dqf(1:nr, :) = 0.0_wp
    dqf(nr + 1:, 1) = dq
    dqf(nr + 1:, 2) = q_old
    dqf(nr + 1:, 3) = q_new
    call this%kin%apply_df_many(this%model, dqf, dx)
    motion = max(abs(dx(:, 2)), abs(dx(:, 3)))
    norm = this%model%error_norm(dx(:, 1), motion, rtol, atol)
  end procedure dyn_error_norm
end submodule dynamics_system_newton
