!> One entry point for all time integrators: checks the options, walks the output times and
!> breakpoints, restarts the method at each breakpoint and hands every output to the system.
module integrators_driver
  use core_kinds, only: wp, i8
  use core_strings, only: int_str, real_str, approx_str
  use core_error, only: error_t, ERR_INPUT, ERR_NUMERIC
  use integrators_system, only: ode2_system_t, integrator_options_t, integrator_stats_t, &
    MIN_RTOL, MIN_ATOL, &
    INTEGRATOR_NAMES, INTEGRATOR_BDF, INTEGRATOR_GALPHA, INTEGRATOR_GALPHA_ADAPTIVE, &
    INTEGRATOR_ERK, JACOBIAN_LINEARISED, JACOBIAN_FD, JACOBIAN_INTERNAL
  use integrators_base, only: integrator_t
  use integrators_cvode, only: cvode_solver_t
  use integrators_galpha, only: galpha_solver_t
  use integrators_arkode, only: erk_solver_t
  implicit none
  private
  public :: integrate, new_integrator

contains

  !> Integrate q'' = a(t, q, v) from (t_out(1), q0, v0) and call sys%record at every t_out(k),
  !> k = 1 included. `breakpoints` are times where a(t, ...) jumps: each one inside
  !> (t_out(1), t_out(end)) is landed on exactly and the method restarted there; a is never
  !> evaluated at a breakpoint itself but one rounding step to its left or right, so that
  !> both segments see their own side of the jump.
  subroutine integrate(sys, opts, t_out, q0, v0, breakpoints, stats, err)
    class(ode2_system_t), intent(inout), target :: sys
    type(integrator_options_t), intent(in) :: opts
    real(wp), intent(in) :: t_out(:)
    real(wp), intent(in) :: q0(:), v0(:)
    real(wp), intent(in) :: breakpoints(:)
    type(integrator_stats_t), intent(out) :: stats
    type(error_t), intent(out) :: err
    class(integrator_t), allocatable :: stepper
    real(wp) :: q(size(q0)), v(size(v0))

    call check_options(opts, t_out, q0, v0, err)
    if (.not. err%ok()) return
    q = q0
    v = v0
    call breakpoint_reached(sys, t_out(1), q, v, err)
    if (.not. err%ok()) return
    call record_output(sys, 1, t_out(1), q, v, err)
    if (.not. err%ok() .or. size(t_out) == 1) return

    call new_integrator(opts%method, stepper)
    call run_segments(stepper, sys, opts, t_out, &
      breakpoints_inside(breakpoints, t_out(1), t_out(size(t_out))), q, v, err)
    call stepper%get_stats(stats)
    call stepper%finish()
    ! The integrators say where they stopped; the run's user needs why (t_end = 1e30 ran
    ! 2 minutes into 'max_steps reached at t = 2377.9').
    if (.not. err%ok() .and. stats%n_steps >= opts%max_steps) err%message = err%message // &
      ': the ' // int_str(int(min(opts%max_steps, int(huge(1), i8)))) // ' steps a run may ' // &
      'take did not ' // &
      'reach t = ' // approx_str(t_out(size(t_out))) // ' (t_end far beyond the time ' // &
      'scale of the motions and vibrations: shorten it; or steps made tiny by a singular ' // &
      'configuration)'
    ! The next integration (a reduced run's next segment) counts on from here.
    if (associated(opts%progress)) opts%progress%steps_done = opts%progress%steps_done + &
      stats%n_steps
  end subroutine integrate

  !> The integrator of a method INTEGRATOR_* (checked by check_options): the one place that
  !> knows the methods.
  subroutine new_integrator(method, integrator)
    integer, intent(in) :: method
    class(integrator_t), allocatable, intent(out) :: integrator
    select case (method)
    case (INTEGRATOR_BDF)
      allocate(cvode_solver_t :: integrator)
    case (INTEGRATOR_ERK)
      allocate(erk_solver_t :: integrator)
    case default
      allocate(galpha_solver_t :: integrator)
    end select
  end subroutine new_integrator

  subroutine run_segments(stepper, sys, opts, t_out, bps, q, v, err)
    class(integrator_t), intent(inout) :: stepper
    class(ode2_system_t), intent(inout), target :: sys
    type(integrator_options_t), intent(in) :: opts
    real(wp), intent(in) :: t_out(:), bps(:)
    real(wp), intent(inout) :: q(:), v(:)
    type(error_t), intent(inout) :: err
    real(wp) :: t, t_end
    integer :: k, ib, status
    logical :: changed

    t = t_out(1)
    t_end = t_out(size(t_out))
    ib = 1
    call stepper%start(sys, opts, t, q, v, segment_end(bps, ib, t_end), &
      -huge(1.0_wp), eval_limit(bps, ib), err)
    if (.not. err%ok()) return
    do k = 2, size(t_out)
      do while (ib <= size(bps))
        if (bps(ib) > t_out(k)) exit
        if (.not. reached(t, bps(ib))) then
          call stepper%advance(sys, bps(ib), q, v, err)
          if (.not. err%ok()) return
        end if
        t = bps(ib)
        ib = ib + 1
        call breakpoint_reached(sys, t, q, v, err)
        if (.not. err%ok()) return
        call stepper%restart(sys, t, q, v, segment_end(bps, ib, t_end), &
          nearest(t, 1.0_wp), eval_limit(bps, ib), err)
        if (.not. err%ok()) return
      end do
      if (.not. reached(t, t_out(k))) then
        call stepper%advance(sys, t_out(k), q, v, err)
        if (.not. err%ok()) return
        t = t_out(k)
      end if
      call record_output(sys, k, t, q, v, err)
      if (.not. err%ok()) return
      if (k == size(t_out)) exit
      call sys%rechart(t, q, v, changed, status)
      if (status /= 0) then
        call err%set(ERR_NUMERIC, 'integrate: the system failed to move its coordinates ' // &
          'at t = ' // real_str(t) // ' (status ' // int_str(status) // ')')
        return
      end if
      ! Same state, other coordinates: the method's history (past steps, its acceleration
      ! variable) is in the old ones. The right-hand side is continuous here, so the restart
      ! evaluates just right of t as after a breakpoint.
      if (changed) call stepper%restart(sys, t, q, v, segment_end(bps, ib, t_end), &
        nearest(t, 1.0_wp), eval_limit(bps, ib), err)
      if (.not. err%ok()) return
    end do
  end subroutine run_segments

  !> Targets within a few roundoffs of t count as reached: CVODE refuses to step to them.
  pure logical function reached(t, target)
    real(wp), intent(in) :: t, target
    reached = target - t <= 4 * spacing(max(abs(t), abs(target)))
  end function reached

  !> Where the current segment ends: the next breakpoint or the last output time.
  pure real(wp) function segment_end(bps, ib, t_end)
    real(wp), intent(in) :: bps(:), t_end
    integer, intent(in) :: ib
    segment_end = t_end
    if (ib <= size(bps)) segment_end = bps(ib)
  end function segment_end

  !> Latest time at which a may be evaluated in the current segment.
  pure real(wp) function eval_limit(bps, ib)
    real(wp), intent(in) :: bps(:)
    integer, intent(in) :: ib
    eval_limit = huge(1.0_wp)
    if (ib <= size(bps)) eval_limit = nearest(bps(ib), -1.0_wp)
  end function eval_limit

  !> The breakpoints strictly inside (t_first, t_last), sorted, without repeats. A sampled
  !> controller brings one per sample: sorted by merging runs, O(n log n).
  pure function breakpoints_inside(breakpoints, t_first, t_last) result(bps)
    real(wp), intent(in) :: breakpoints(:), t_first, t_last
    real(wp), allocatable :: bps(:)
    real(wp), allocatable :: a(:), b(:)
    integer :: n, width, lo, mid, hi, i, j, k
    a = pack(breakpoints, breakpoints > t_first .and. breakpoints < t_last)
    n = size(a)
    allocate(b(n))
    width = 1
    do while (width < n)
      do lo = 1, n, 2 * width
        mid = min(lo + width, n + 1)
        hi = min(lo + 2 * width, n + 1)
        i = lo
        j = mid
        do k = lo, hi - 1
          if (j >= hi) then
            b(k) = a(i); i = i + 1
          else if (i < mid) then
            if (a(i) <= a(j)) then
              b(k) = a(i); i = i + 1
            else
              b(k) = a(j); j = j + 1
            end if
          else
            b(k) = a(j); j = j + 1
          end if
        end do
      end do
      a = b
      width = 2 * width
    end do
    allocate(bps(n))
    k = 0
    do i = 1, n
      if (k > 0) then
        if (a(i) == bps(k)) cycle
      end if
      k = k + 1
      bps(k) = a(i)
    end do
    bps = bps(1:k)
  end function breakpoints_inside

  subroutine breakpoint_reached(sys, t, q, v, err)
    class(ode2_system_t), intent(inout) :: sys
    real(wp), intent(in) :: t, q(:), v(:)
    type(error_t), intent(inout) :: err
    integer :: status
    call sys%at_breakpoint(t, q, v, status)
    if (status /= 0) call err%set(ERR_NUMERIC, 'integrate: the system failed at the ' // &
      'breakpoint t = ' // real_str(t) // ' (status ' // int_str(status) // ')')
  end subroutine breakpoint_reached

  subroutine record_output(sys, k, t, q, v, err)
    class(ode2_system_t), intent(inout) :: sys
    integer, intent(in) :: k
    real(wp), intent(in) :: t, q(:), v(:)
    type(error_t), intent(inout) :: err
    integer :: status
    call sys%record(k, t, q, v, status)
    if (status /= 0) call err%set(ERR_NUMERIC, 'integrate: record returned status ' // &
      int_str(status) // ' at output ' // int_str(k) // ' (t = ' // real_str(t) // ')')
  end subroutine record_output

  subroutine check_options(opts, t_out, q0, v0, err)
    type(integrator_options_t), intent(in) :: opts
    real(wp), intent(in) :: t_out(:), q0(:), v0(:)
    type(error_t), intent(inout) :: err
    character(len=*), parameter :: ctx = 'integrator options: '
    integer :: n

    n = size(t_out)
    if (n < 1) call err%set(ERR_INPUT, ctx // 'no output times')
    if (n > 1) then
      if (.not. all(t_out(2:) > t_out(:n - 1))) call err%set(ERR_INPUT, &
        ctx // 'output times must be strictly increasing')
    end if
    if (size(q0) /= size(v0) .or. size(q0) < 1) call err%set(ERR_INPUT, ctx // &
      'q0 and v0 must have the same, non-zero size')
    if (.not. opts%rtol >= MIN_RTOL) call err%set(ERR_INPUT, ctx // 'rtol must be >= ' // &
      approx_str(MIN_RTOL) // ' (double precision cannot meet a smaller one), got ' // &
      real_str(opts%rtol))
    if (.not. opts%atol >= MIN_ATOL) call err%set(ERR_INPUT, ctx // 'atol must be >= ' // &
      approx_str(MIN_ATOL) // ', got ' // real_str(opts%atol))
    if (opts%max_steps < 1) call err%set(ERR_INPUT, ctx // 'max_steps must be >= 1')
    select case (opts%method)
    case (INTEGRATOR_BDF)
      if (opts%max_order < 0 .or. opts%max_order > 5) call err%set(ERR_INPUT, ctx // &
        'max_order must be in 0..5 (0: by rtol), got ' // int_str(opts%max_order))
      call check_max_step(opts, err)
      if (all(opts%jacobian /= [JACOBIAN_LINEARISED, JACOBIAN_FD, JACOBIAN_INTERNAL])) &
        call err%set(ERR_INPUT, ctx // 'jacobian must be JACOBIAN_LINEARISED, JACOBIAN_FD ' // &
        'or JACOBIAN_INTERNAL, got ' // int_str(opts%jacobian))
    case (INTEGRATOR_ERK)
      ! The orders for which ARKODE has a default embedded table.
      if (all(opts%erk_order /= [2, 3, 4, 5, 6, 8])) call err%set(ERR_INPUT, ctx // &
        'erk_order must be 2, 3, 4, 5, 6 or 8, got ' // int_str(opts%erk_order))
      call check_max_step(opts, err)
    case (INTEGRATOR_GALPHA, INTEGRATOR_GALPHA_ADAPTIVE)
      if (.not. opts%dt > 0) call err%set(ERR_INPUT, ctx // 'dt must be > 0, got ' // &
        real_str(opts%dt))
      if (opts%method == INTEGRATOR_GALPHA_ADAPTIVE) call check_max_step(opts, err)
      if (.not. (opts%rho_inf >= 0 .and. opts%rho_inf <= 1)) call err%set(ERR_INPUT, ctx // &
        'rho_inf must be in [0, 1], got ' // real_str(opts%rho_inf))
    case default
      ! INTEGRATOR_AUTO included: its choice is the caller's.
      call err%set(ERR_INPUT, ctx // 'method ' // method_word(opts%method) // &
        " is not an integrator (expected 'bdf', 'galpha', 'galpha_adaptive' or 'erk')")
    end select
  end subroutine check_options

  !> A method's name in messages, its number if it has none.
  pure function method_word(method) result(word)
    integer, intent(in) :: method
    character(len=:), allocatable :: word
    if (method >= 1 .and. method <= size(INTEGRATOR_NAMES)) then
      word = "'" // trim(INTEGRATOR_NAMES(method)) // "'"
    else
      word = int_str(method)
    end if
  end function method_word

  subroutine check_max_step(opts, err)
    type(integrator_options_t), intent(in) :: opts
    type(error_t), intent(inout) :: err
    if (.not. opts%max_step >= 0) call err%set(ERR_INPUT, 'integrator options: ' // &
      'max_step must be >= 0 (0: no limit), got ' // real_str(opts%max_step))
  end subroutine check_max_step

end module integrators_driver
