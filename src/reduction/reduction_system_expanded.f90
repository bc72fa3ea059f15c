!> The expanded evaluation of a reduced model (reduction_system, `evaluation = 'expanded'`):
!> accelerations from the kept expansions, new ones where the state leaves them, and the exact
!> measurements of the error indicators along the run (where the first expansion is made, at
!> the farthest accepted state each served, at estimate_samples outputs), logged in `measured`.
submodule (reduction_system) reduction_system_expanded
  implicit none

contains

  module procedure expanded_accel
    real(wp) :: p(this%dyn%model%n_rh), pd(this%dyn%model%n_rh), pdd(this%dyn%model%n_rh)
    call this%dyn%prescribed(t, p, pd, pdd)
    if (.not. this%expansions%find(p, eta)) then
      call new_expansion(this, t, p, eta, eta_dot, err)
      if (.not. err%ok()) return
    end if
    call this%expansions%item(this%expansions%current)%accel(this%dyn, t, p, pd, pdd, eta, &
      eta_dot, a, err)
    if (err%ok()) call check_finite(a, t, err)
  end procedure expanded_accel

  !> A new expansion for the state (t, p, eta, eta_dot), which has left the kept ones. The
  !> first of a run (or of a basis) is made at the state the run starts from, where the error
  !> indicators are measured exactly; later ones at an integrator's trial state, which a
  !> rejected step may have swung far beyond anything the run uses: not measured there (the
  !> expansion left is compared at the farthest accepted state it served, check_expansions).
  !> Apart from expanded_accel the full model's arrays are made only here.
  subroutine new_expansion(this, t, p, eta, eta_dot, err)
    type(reduced_t), intent(inout) :: this
    real(wp), intent(in) :: t, p(:), eta(:), eta_dot(:)
    type(error_t), intent(out) :: err
    real(wp) :: t_centre, eta_c(size(eta)), tau_max, residual, estimate
    real(wp) :: q_dy(this%dyn%model%n_dy), v_dy(this%dyn%model%n_dy)
    type(kin_state_t) :: before
    ! Kept ones taken again since they were left (before a slot is reused).
    call this%check_expansions(skip=this%expansions%current)
    call this%dyn%kin%save_state(before)
    if (this%expansions%current > 0) then
      ! The new expansion's kinematics start from the exact solution here, found from the
      ! series' coordinates: after a stretch on the expansions the last exact solution may lie
      ! turns back.
      call this%dyn%kin%restart_from(this%expansions%item(this%expansions%current)% &
        coordinates([p, eta]))
      call this%full_state(eta, eta_dot, q_dy, v_dy)
      call this%dyn%kin%solve(this%dyn%model, [p, q_dy], err, t)
    else
      call measure(this, t, eta, eta_dot, residual, estimate, err)
      if (err%ok()) call this%measured%add(t, residual, estimate, MEASURED_EXPANSION)
      ! Not measurable here: counted as not compared, as at the samples.
      if (.not. err%ok()) this%expansions%n_unchecked = this%expansions%n_unchecked + 1
    end if
    if (.not. err%ok()) then
      ! The expansion is made as usual, from the kinematics as they were.
      call this%dyn%kin%restore_state(before)
      call err%clear()
    end if
    t_centre = this%expansions%centre_time(this%dyn, t, p)
    ! Along the modal rates no further than a quarter period of the lowest mode, where the
    ! motion may turn back.
    tau_max = 0.0_wp
    if (allocated(this%basis%frequency_hz)) then
      if (size(this%basis%frequency_hz) > 0) then
        if (this%basis%frequency_hz(1) > 0) tau_max = 0.25_wp / this%basis%frequency_hz(1)
      end if
    end if
    eta_c = this%expansions%centre_modal(eta, eta_dot, tau_max)
    call this%expansions%expand(this%dyn, this%basis, t_centre, eta_c, err)
    ! Centred ahead, it may fail there (the kinematics) or still miss this state: then centre
    ! it here.
    if (err%ok()) then
      if (.not. this%expansions%item(this%expansions%current)%needs_update(p, eta, &
        this%expansions%tol)) return
    end if
    if (err%ok() .or. t_centre /= t .or. any(eta_c /= eta)) &
      call this%expansions%expand(this%dyn, this%basis, t, eta, err)
    ! The state is the integrator's trial: where the kinematics fail there (singular on
    ! input/four_bar.nml with 4 modes, whose first trial step swung the 3 kHz mode far out),
    ! a shorter step may stay clear of it.
    if (err%code == ERR_MODEL) then
      err%code = ERR_NUMERIC
      call err%prefix('at a trial state of the integrator: ')
    end if
  end subroutine new_expansion

  !> The distance from the exact coordinates and the error indicators at each farthest state
  !> (one evaluation each). Else the expansion a run or a basis ends in, or one never
  !> replaced, would be measured only where it was made (spin_up's one expansion: at rest).
  !> Where the model cannot be evaluated there the expansion counts as not compared
  !> (n_unchecked).
  !> An accepted step of the integrator: the farthest state of the expansion serving it.
  module procedure red_step_accepted
    real(wp) :: p(this%dyn%model%n_rh), pd(this%dyn%model%n_rh), pdd(this%dyn%model%n_rh)
    if (.not. this%expanded) return
    call this%dyn%prescribed(t, p, pd, pdd)
    call this%expansions%note_served(t, p, q, v)
  end procedure red_step_accepted

  module procedure red_check_expansions
    real(wp), allocatable :: z(:), z_rate(:), x_series(:)
    real(wp) :: t, residual, estimate
    type(error_t) :: err
    type(kin_state_t) :: before
    integer :: i, nr, not_this
    logical :: moved
    nr = this%dyn%model%n_rh
    not_this = 0
    if (present(skip)) not_this = skip
    moved = .false.
    do
      i = this%expansions%unchecked(not_this, t, z, z_rate)
      if (i == 0) exit
      ! The run's kinematics goes on from where it was, as if nothing had been checked.
      if (.not. moved) call this%dyn%kin%save_state(before)
      moved = .true.
      x_series = this%expansions%item(i)%coordinates(z)
      call measure(this, t, z(nr + 1:), z_rate, residual, estimate, err, x_series)
      if (err%ok()) then
        call this%expansions%note_checked(i, this%dyn%model, this%dyn%kin%x, x_series)
        call this%measured%add(t, residual, estimate, MEASURED_FARTHEST)
      else
        this%expansions%n_unchecked = this%expansions%n_unchecked + 1
        this%expansions%item(i)%checked_d2 = this%expansions%item(i)%far_d2
      end if
    end do
    if (moved) call this%dyn%kin%restore_state(before)
  end procedure red_check_expansions

  !> The nodal coordinates (O(n m^3), no solve) and the energies from the expansion, the
  !> indicators' latest measurement (here, at a sample).
  module procedure expanded_store
    real(wp) :: p(this%dyn%model%n_rh), pd(this%dyn%model%n_rh), pdd(this%dyn%model%n_rh)
    real(wp) :: a(size(eta)), x(this%dyn%model%n_x)
    call this%dyn%prescribed(t, p, pd, pdd)
    if (.not. this%expansions%find(p, eta)) then
      call expanded_accel(this, t, eta, eta_dot, a, err)
      if (.not. err%ok()) return
    end if
    associate (ex => this%expansions%item(this%expansions%current))
      x = ex%coordinates([p, eta])
      call this%dyn%store(kg, t, q_dy, v_dy, x, ex%energy([p, eta], [pd, eta_dot], &
        this%dyn%load_factor * this%dyn%loads_at(t), x))
    end associate
    if (this%sample_every > 0 .and. kg > 1) then
      if (mod(kg - 1, this%sample_every) == 0 .or. kg == size(this%estimate)) &
        call sample(this, t, eta, eta_dot, x)
    end if
    if (this%measured%n > 0) then
      this%residual(kg) = this%measured%residual(this%measured%n)
      this%estimate(kg) = this%measured%estimate(this%measured%n)
    else
      this%residual(kg) = 0.0_wp
      this%estimate(kg) = 0.0_wp
    end if
  end procedure expanded_store

  !> The error indicators and the expansion's distance from the exact coordinates (x: its
  !> own) at an output, by one exact evaluation. The error depends on the rates and loads as
  !> well as on where the expansions were made: spin_up's, measured at its one expansion and
  !> the farthest modal state, 6.0e-5 m, reaches 2.3e-4 m at full speed.
  subroutine sample(this, t, eta, eta_dot, x)
    type(reduced_t), intent(inout) :: this
    real(wp), intent(in) :: t, eta(:), eta_dot(:), x(:)
    real(wp) :: residual, estimate
    type(kin_state_t) :: before
    type(error_t) :: err
    call this%dyn%kin%save_state(before)
    call measure(this, t, eta, eta_dot, residual, estimate, err, x)
    if (err%ok()) then
      call this%measured%add(t, residual, estimate, MEASURED_SAMPLE)
      this%expansions%manifold_error = max(this%expansions%manifold_error, &
        this%dyn%model%largest_translation(this%dyn%kin%x - x))
    else
      this%expansions%n_unchecked = this%expansions%n_unchecked + 1
    end if
    call this%dyn%kin%restore_state(before)
  end subroutine sample

  !> The error indicators at the reduced state (t, eta, eta_dot) by one exact evaluation, its
  !> kinematics started from x_series, an expansion's coordinates there: after a stretch on
  !> the expansions the last exact solution may lie turns back (spin_up's hub turns 8 rad
  !> between samples, too far for Newton). Leaves the model evaluated at the state.
  subroutine measure(this, t, eta, eta_dot, residual, estimate, err, x_series)
    type(reduced_t), intent(inout) :: this
    real(wp), intent(in) :: t, eta(:), eta_dot(:)
    real(wp), intent(out) :: residual, estimate
    type(error_t), intent(out) :: err
    real(wp), intent(in), optional :: x_series(:)
    real(wp) :: q_dy(this%dyn%model%n_dy), v_dy(this%dyn%model%n_dy), dq(this%dyn%model%n_dy)
    if (present(x_series)) call this%dyn%kin%restart_from(x_series)
    call this%full_state(eta, eta_dot, q_dy, v_dy)
    call this%indicators(t, eta, eta_dot, q_dy, v_dy, residual, estimate, dq, err)
  end subroutine measure
end submodule reduction_system_expanded
