!> The Newton iteration of a generalized-alpha step and its iteration matrix.
submodule (integrators_galpha) integrators_galpha_newton
  implicit none

contains

  !> Evaluate the Jacobian when asked to, and refactor when it or the step has changed.
  module procedure refresh_iteration_matrix
    real(wp) :: a(this%n), tolerance
    integer :: status

    if (this%refresh_jac .or. .not. this%have_jac) then
      if (this%system_solver) then
        ! The system factors at the state of its last evaluation: put it here.
        call sys%accel(this%clamped(this%t), this%q, this%v, a, status)
      else
        call sys%jacobian(this%clamped(this%t), this%q, this%v, this%dadq, this%dadv, status)
      end if
      this%stats%n_jac_evals = this%stats%n_jac_evals + 1
      if (status < 0 .or. (status > 0 .and. .not. this%have_jac)) then
        call err%set(ERR_NUMERIC, 'galpha: jacobian returned status ' // int_str(status) // &
          ' at t = ' // real_str(this%t))
        return
      end if
      ! After a recoverable failure the previous Jacobian is still a usable Newton matrix.
      if (status == 0) then
        this%have_jac = .true.
        this%lu_valid = .false.
      end if
      this%jac_is_current = .true.
      this%refresh_jac = .false.
    end if
    tolerance = 1.0e-6_wp
    if (this%adaptive) tolerance = refactor_ratio
    if (.not. this%lu_valid .or. abs(h - this%h_lu) > tolerance * h) then
      call factor_iteration_matrix(this, sys, h, .false.)
    else if (this%refactor_here) then
      call factor_iteration_matrix(this, sys, h, .true.)
    end if
    this%refactor_here = .false.
  end procedure refresh_iteration_matrix

  !> keep_rate: the same step and a state near the last matrix's, whose contraction rate then
  !> bounds the new one's.
  subroutine factor_iteration_matrix(this, sys, h, keep_rate)
    type(galpha_solver_t), intent(inout) :: this
    class(ode2_system_t), intent(inout) :: sys
    real(wp), intent(in) :: h
    logical, intent(in) :: keep_rate
    real(wp) :: c_q, c_v
    integer :: i, info
    call newton_coefficients(this, h, c_q, c_v)
    if (this%system_solver) then
      call sys%iteration_factor(c_q, c_v, info)
    else
      this%lu = -c_q * this%dadq - c_v * this%dadv
      do i = 1, this%n
        this%lu(i, i) = this%lu(i, i) + 1
      end do
      call lu_factor(this%lu, this%pivots, info)
    end if
    this%lu_valid = info == 0
    this%stats%n_factorisations = this%stats%n_factorisations + 1
    this%h_lu = h
    this%matrix_age = 0
    ! Otherwise a new matrix: no rate known for it yet.
    if (.not. keep_rate) this%newton_rate = 1
  end subroutine factor_iteration_matrix

  !> d(q+)/d(qdd+) and d(v+)/d(qdd+).
  pure subroutine newton_coefficients(this, h, c_q, c_v)
    type(galpha_solver_t), intent(in) :: this
    real(wp), intent(in) :: h
    real(wp), intent(out) :: c_q, c_v
    real(wp) :: ratio
    ratio = (1 - this%alpha_f) / (1 - this%alpha_m)
    c_q = h**2 * this%beta * ratio
    c_v = h * this%gamma * ratio
  end subroutine newton_coefficients

  !> One step from this%t to t_new = this%t + h; the state is updated only on success.
  module procedure take_step
    real(wp) :: c_q, c_v, dnorm, dnorm_old, rate, first_norm, first_rate
    integer :: iter, status

    associate (acc0 => this%work(:, 1), acc_known => this%work(:, 2), &
               q_known => this%work(:, 3), v_known => this%work(:, 4), x => this%work(:, 5), &
               q1 => this%work(:, 6), v1 => this%work(:, 7), f => this%work(:, 8), &
               dx => this%work(:, 9))
      outcome = STEP_NEWTON_FAILED
      if (.not. this%lu_valid) return
      ! acc lags qdd by (alpha_m - alpha_f) h_last; a new step size needs the lag for h.
      acc0 = this%qdd + (h / this%h_last) * (this%acc - this%qdd)
      acc_known = (this%alpha_f * this%qdd - this%alpha_m * acc0) / (1 - this%alpha_m)
      q_known = this%q + h * this%v + h**2 * ((0.5_wp - this%beta) * acc0 + this%beta * acc_known)
      v_known = this%v + h * ((1 - this%gamma) * acc0 + this%gamma * acc_known)
      call newton_coefficients(this, h, c_q, c_v)

      ! Smooth accelerations: the linear extrapolation leaves a first correction O(h^2) smaller
      ! than the constant one, so that more steps stop after one correction.
      x = this%qdd
      if (this%h_old > 0) x = x + (h / this%h_old) * (this%qdd - this%qdd_old)
      dnorm_old = huge(1.0_wp)
      do iter = 1, max_newton_iters
        q1 = q_known + c_q * x
        v1 = v_known + c_v * x
        if (this%system_solver) then
          call sys%newton_correction(this%clamped(t_new), q1, v1, x, dx, status)
        else
          call sys%accel(this%clamped(t_new), q1, v1, f, status)
          if (status == 0) then
            dx = f - x
            call lu_solve_vector(this%lu, this%pivots, dx)
          end if
        end if
        this%stats%n_rhs_evals = this%stats%n_rhs_evals + 1
        if (status /= 0) then
          this%bad_status = status
          outcome = merge(STEP_FATAL, STEP_RECOVERABLE, status < 0)
          return
        end if
        x = x + dx
        dnorm = max(weighted_norm(this, c_q, dx, q1), weighted_norm(this, c_v, dx, v1))
        if (iter == 1) first_norm = dnorm
        if (iter > 1) then
          rate = dnorm / dnorm_old
          if (iter == 2) first_rate = rate
          if (rate > max_newton_rate) return
          ! A rate of 1 stands for none known (a new matrix, or one unmeasured for long): the
          ! first measurement replaces it rather than decaying from it, which took about six
          ! steps of second corrections (two-link, 32 el/link: 1.28 -> 1.14 evaluations per
          ! step).
          if (this%newton_rate >= 1) then
            this%newton_rate = rate
          else
            this%newton_rate = max(rate_decay * this%newton_rate, rate)
          end if
          this%rate_age = 0
        end if
        ! The error left after this correction is about rate * dnorm (linear convergence of
        ! the chord iteration); the first correction uses the rate of earlier steps.
        if (dnorm * min(1.0_wp, this%newton_rate) <= newton_tol) exit
        dnorm_old = dnorm
      end do
      if (dnorm * min(1.0_wp, this%newton_rate) > newton_tol) return

      if (iter > slow_newton_iters) this%refresh_jac = .true.
      ! The iteration matrix goes stale along the motion, and its contraction rate with it (two-
      ! link, 32 el/link, dt 1e-4: about 2e-4 fresh, 8e-3 after the ~200 steps one served), and
      ! the first correction times the rate decides whether a step stops after one evaluation.
      ! A system solver refactors at the state of its last evaluation (no accel needed), for
      ! about half an evaluation's work: worth it once the matrix needs second corrections.
      this%matrix_age = this%matrix_age + 1
      ! Only where the measured rate itself would have kept the first correction from
      ! stopping: a step that verified a rate no longer known keeps its matrix (half the
      ! refactorisations at 32 and 64 el/link, the same evaluations).
      if (this%system_solver .and. iter > 1 .and. this%matrix_age >= refactor_age) then
        if (first_rate * first_norm > newton_tol) this%refactor_here = .true.
      end if
      this%rate_age = this%rate_age + 1
      if (this%rate_age >= rate_lifetime) this%newton_rate = 1
      this%q = q_known + c_q * x
      this%v = v_known + c_v * x
      this%acc = acc_known + (1 - this%alpha_f) / (1 - this%alpha_m) * x
      this%qdd = x
      this%t = t_new
      this%h_last = h
      outcome = STEP_OK
    end associate
  end procedure take_step

  !> max |c d_i| / (atol + rtol |x_i|) (c apart: c d as an argument would be a temporary)
  pure real(wp) function weighted_norm(this, c, d, x)
    type(galpha_solver_t), intent(in) :: this
    real(wp), intent(in) :: c, d(:), x(:)
    weighted_norm = abs(c) * maxval(abs(d) / (this%atol + this%rtol * abs(x)))
  end function weighted_norm

end submodule integrators_galpha_newton
