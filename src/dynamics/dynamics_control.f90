!> A plant (the full or a reduced model) with its feedback controllers, as one second-order
!> system for the integrators: the controllers' states are integrated with the model, so
!> implicit integrators see them (docs/theory.md, closed-loop simulation).
!>
!> A continuous controller's integral I of its error e = r - y is carried as the velocity of
!> an extra coordinate s with s'' = e, so the state stays (q, q'): q = (q_plant, s),
!> q' = (q_plant', I). s itself (the double integral) is never used. Its error is not
!> controlled by the integrators' error norm (the plant's), as I enters the equations only
!> through ki I, whose error follows that of y.
!> A sampled controller (period T > 0) holds its output between samples (zero-order hold):
!> at each sample time, a breakpoint of the run where the integrator restarts, it measures,
!> computes u = kp e + ki I + kd e' and adds T e to its discrete integral I.
!> Either kind stops integrating while its actuator is at a limit and e pushes further into it
!> (model_control's winds_up).
!> A user law (law = 'user') has n_states states x of its own, carried like the PID's I: the
!> velocities of extra coordinates whose accelerations are the law's dx/dt (continuous), or
!> replaced by the law's next x at each sample (sampled, where u is held as above).
module dynamics_control
  use core_kinds, only: wp
  use core_error, only: error_t
  use core_strings, only: real_str
  use model_system, only: model_t
  use integrators_system, only: ode2_system_t
  use dynamics_system, only: dynamics_t
  use model_control, only: LAW_USER, controller_sizes
  implicit none
  private
  public :: controlled_t

  type, extends(ode2_system_t) :: controlled_t
    private
    class(ode2_system_t), pointer :: plant => null()
    !> The full model the plant evaluates (the plant itself, or the reduced model's): it
    !> holds the controllers and their last errors and outputs.
    type(dynamics_t), pointer :: dyn => null()
    !> Plant coordinates, controllers, and the controllers' actuators, outputs and states.
    integer :: n = 0, nc = 0, nu = 0, ny = 0, nx = 0
    real(wp) :: t0 = 0.0_wp
    !> Sampled controllers: their states (a PID's discrete integral, a user law's x; the
    !> continuous ones' entries are unused) and the number of samples taken.
    real(wp), allocatable :: x_sampled(:)
    integer, allocatable :: n_samples(:)
    !> Feedforward: the rigid-body model, whose dynamic coordinate ff_q(k) is the joint that
    !> controller k drives (0: no feedforward).
    type(dynamics_t), allocatable :: rigid
    integer, allocatable :: ff_q(:)
    !> The time dyn%ctrl_ff was computed for: the feedforward depends on t alone, and a
    !> Jacobian evaluates the loop many times at one t.
    real(wp) :: ff_time = -huge(1.0_wp)
    !> Last state recorded, for a run that continues in segments (reduced with updates).
    real(wp), allocatable :: last_s(:), last_i(:)
    !> At the output times: per controller a PID's error e = r - y, per actuator the applied
    !> output u, per measured output y (model_control's offsets).
    real(wp), allocatable, public :: error_hist(:, :), u_hist(:, :), y_hist(:, :)
    !> A run in segments (reduced with basis updates) maps the output index k of a record to
    !> the run's (0: not an output); not allocated: the same.
    integer, allocatable, public :: out_index(:)
    !> Why a sampled controller may be unstable ('' if no reason is seen): check_sampling.
    character(len=:), allocatable, public :: hint
  contains
    procedure :: init => control_init
    procedure :: set_feedforward => control_set_feedforward
    procedure :: accel => control_accel
    procedure :: record => control_record
    procedure :: error_norm => control_error_norm
    procedure :: jacobian => control_jacobian
    procedure :: at_breakpoint => control_at_breakpoint
    procedure :: rechart => control_rechart
    procedure :: state => control_state
    procedure :: check_sampling => control_check_sampling
    procedure :: allocate_history => control_allocate_history
  end type controlled_t

contains

  !> Wrap `plant` (n coordinates), whose evaluations go through `dyn`, from time t0. The
  !> controllers start with zero states.
  subroutine control_init(this, plant, dyn, n, t0)
    class(controlled_t), intent(inout) :: this
    class(ode2_system_t), intent(in), target :: plant
    type(dynamics_t), intent(in), target :: dyn
    integer, intent(in) :: n
    real(wp), intent(in) :: t0
    this%plant => plant
    this%dyn => dyn
    this%n = n
    this%nc = size(dyn%model%controllers)
    call controller_sizes(dyn%model%controllers, this%nu, this%ny, this%nx)
    this%t0 = t0
    allocate(this%x_sampled(this%nx), this%n_samples(this%nc))
    this%x_sampled = 0.0_wp
    this%n_samples = 0
    this%last_s = this%x_sampled
    this%last_i = this%x_sampled
  end subroutine control_init

  !> Feedforward from the rigid-body model `rigid` (model_build's build_rigid_model), whose
  !> dynamic coordinate ff_q(k) controller k drives: at every evaluation its inverse dynamics at
  !> the references r, r', r'' gives the torques tau = Mbar r'' - g(t, r, r') the joints need.
  subroutine control_set_feedforward(this, rigid, ff_q, err)
    class(controlled_t), intent(inout) :: this
    type(model_t), intent(in) :: rigid
    integer, intent(in) :: ff_q(:)
    type(error_t), intent(out) :: err
    real(wp) :: q(rigid%n_dy), v(rigid%n_dy), a(rigid%n_dy)
    allocate(this%rigid)
    this%ff_q = ff_q
    call references(this, this%t0, q, v, a)
    call this%rigid%init(rigid, this%t0, q, err, linear_solver='dense')
    if (.not. err%ok()) call err%prefix('feedforward (rigid-body inverse dynamics): ')
  end subroutine control_set_feedforward

  !> The rigid model's state on the references at t: positions, rates and accelerations.
  subroutine references(this, t, q, v, a)
    type(controlled_t), intent(in) :: this
    real(wp), intent(in) :: t
    real(wp), intent(out) :: q(:), v(:), a(:)
    integer :: k
    q = 0.0_wp
    v = 0.0_wp
    a = 0.0_wp
    do k = 1, size(this%ff_q)
      if (this%ff_q(k) == 0) cycle
      associate (m => this%dyn%model)
        call m%motions(m%controllers(k)%reference)%eval(t, q(this%ff_q(k)), &
          v(this%ff_q(k)), a(this%ff_q(k)))
      end associate
    end do
  end subroutine references

  !> The feedforward torques at t into dyn%ctrl_ff.
  subroutine feedforward(this, t, status)
    type(controlled_t), intent(inout) :: this
    real(wp), intent(in) :: t
    integer, intent(out) :: status
    real(wp) :: q(this%rigid%model%n_dy), v(size(q)), a(size(q)), tau(size(q))
    type(error_t) :: err
    integer :: k
    status = 0
    if (t == this%ff_time) return
    call references(this, t, q, v, a)
    call this%rigid%assemble(t, q, v, err)
    call this%rigid%report(err, status)
    if (status /= 0) return
    this%ff_time = t
    tau = matmul(this%rigid%mbar, a) - this%rigid%gen_force
    do k = 1, size(this%ff_q)
      if (this%ff_q(k) > 0) &
        this%dyn%ctrl_ff(this%dyn%model%controllers(k)%u_offset + 1) = tau(this%ff_q(k))
    end do
  end subroutine feedforward

  !> Why a sampled PID may be unstable, from the state (t, q, v) at the start: its output
  !> reaches the measured rate at once through G = (de/dq) (da/du) (the inverse of the
  !> inertia the actuator sees at the instant, for a joint its own), and a rate gain held over
  !> a period T acts like explicit Euler on the fast pole -kd G of the continuous loop, which
  !> grows unless kd G T < 2. A joint driving a flexible link sees little inertia (the link's
  !> end turns against its bending), so that pole can be fast. '' when every such product is
  !> below 2; otherwise a hint (this%hint, entries after '; ') for the error of a failed run.
  subroutine control_check_sampling(this, t, q, v)
    class(controlled_t), intent(inout) :: this
    real(wp), intent(in) :: t, q(:), v(:)
    real(wp) :: a0(size(q)), e0(this%nc), g(this%n, this%nc), dedq(this%nc, this%n), gain
    logical :: want(this%nc)
    integer :: k, status
    this%hint = ''
    associate (c => this%dyn%model%controllers)
      want = [(c(k)%sampled() .and. c(k)%law_kind /= LAW_USER .and. c(k)%kd > 0, &
               k = 1, this%nc)]
    end associate
    if (.not. any(want)) return
    call this%accel(t, q, v, a0, status)
    if (status /= 0) return
    e0 = this%dyn%ctrl_error
    call couplings(this, t, q, v, a0, e0, want, g, dedq, status)
    if (status /= 0) return
    do k = 1, this%nc
      associate (c => this%dyn%model%controllers(k))
        if (.not. want(k)) cycle
        gain = -dot_product(dedq(k, :), g(:, k))
        if (c%kd * gain * c%period > 2) this%hint = this%hint // '; controller ''' // &
          c%label // ''': kd G T = ' // real_str(c%kd * gain * c%period) // ' > 2 with ' // &
          'G = ' // real_str(gain) // ' (the inverse of the inertia its actuator sees at ' // &
          'the instant): sample faster than 2/(kd G) = ' // real_str(2 / (c%kd * gain)) // &
          ' s or lower kd'
      end associate
    end do
    call this%accel(t, q, v, a0, status)
  end subroutine control_check_sampling

  !> The augmented initial state: the plant's (q, v), then s and the controllers' states
  !> recorded last (zero at the start).
  subroutine control_state(this, q_plant, v_plant, q, v)
    class(controlled_t), intent(in) :: this
    real(wp), intent(in) :: q_plant(:), v_plant(:)
    real(wp), allocatable, intent(out) :: q(:), v(:)
    q = [q_plant, this%last_s]
    v = [v_plant, this%last_i]
  end subroutine control_state

  subroutine control_allocate_history(this, nt)
    class(controlled_t), intent(inout) :: this
    integer, intent(in) :: nt
    if (allocated(this%error_hist)) deallocate(this%error_hist, this%u_hist, this%y_hist)
    allocate(this%error_hist(this%nc, nt), this%u_hist(this%nu, nt), this%y_hist(this%ny, nt))
    this%error_hist = 0.0_wp
    this%u_hist = 0.0_wp
    this%y_hist = 0.0_wp
  end subroutine control_allocate_history

  !> Continuous controllers take their states from the integrated state, sampled ones their
  !> own.
  subroutine set_states(this, v)
    type(controlled_t), intent(inout) :: this
    real(wp), intent(in) :: v(:)
    integer :: k
    do k = 1, this%nc
      associate (c => this%dyn%model%controllers(k))
        associate (i => c%x_offset + 1, j => c%x_offset + c%n_x())
          if (c%sampled()) then
            this%dyn%ctrl_x(i:j) = this%x_sampled(i:j)
          else
            this%dyn%ctrl_x(i:j) = v(this%n + i:this%n + j)
          end if
        end associate
      end associate
    end do
  end subroutine set_states

  subroutine control_accel(this, t, q, v, a, status)
    class(controlled_t), intent(inout) :: this
    real(wp), intent(in) :: t, q(:), v(:)
    real(wp), intent(out) :: a(:)
    integer, intent(out) :: status
    integer :: k, n
    n = this%n
    a = 0.0_wp
    call set_states(this, v)
    if (allocated(this%rigid)) then
      call feedforward(this, t, status)
      if (status /= 0) then
        call this%dyn%last_error%clear()
        call this%dyn%last_error%set(this%rigid%last_error%code, &
          'feedforward: ' // this%rigid%last_error%message)
        return
      end if
    end if
    call this%plant%accel(t, q(1:n), v(1:n), a(1:n), status)
    if (status /= 0) return
    do k = 1, this%nc
      associate (c => this%dyn%model%controllers(k), e => this%dyn%ctrl_error(k))
        if (c%sampled()) cycle
        associate (i => n + c%x_offset + 1, j => n + c%x_offset + c%n_x())
          if (c%law_kind == LAW_USER) then
            a(i:j) = this%dyn%ctrl_x_rate(i - n:j - n)
          else if (.not. c%winds_up(this%dyn%ctrl_law(k), e)) then
            a(i) = e
          end if
        end associate
      end associate
    end do
  end subroutine control_accel

  !> The plant records its output; the controllers' errors and outputs at (t, q, v) come from
  !> one evaluation (a record solves only the kinematics).
  subroutine control_record(this, k, t, q, v, status)
    class(controlled_t), intent(inout) :: this
    integer, intent(in) :: k
    real(wp), intent(in) :: t, q(:), v(:)
    integer, intent(out) :: status
    real(wp) :: a(size(q))
    integer :: kg
    call this%accel(t, q, v, a, status)
    if (status /= 0) return
    kg = k
    if (allocated(this%out_index)) kg = this%out_index(k)
    if (kg > 0) then
      this%error_hist(:, kg) = this%dyn%ctrl_error
      this%u_hist(:, kg) = this%dyn%ctrl_u
      this%y_hist(:, kg) = this%dyn%ctrl_y
    end if
    this%last_s = q(this%n + 1:)
    this%last_i = v(this%n + 1:)
    call this%plant%record(k, t, q(1:this%n), v(1:this%n), status)
  end subroutine control_record

  !> The plant moves its charts; the controllers' states are not coordinates of a chart.
  subroutine control_rechart(this, t, q, v, changed, status)
    class(controlled_t), intent(inout) :: this
    real(wp), intent(in) :: t
    real(wp), intent(inout) :: q(:), v(:)
    logical, intent(out) :: changed
    integer, intent(out) :: status
    call this%plant%rechart(t, q(1:this%n), v(1:this%n), changed, status)
  end subroutine control_rechart

  !> da/dq and da/dv of the closed loop: the plant's own Jacobian (its linearised structural
  !> part, as without controllers) plus what the PID controllers add through their outputs,
  !>   du_k = kp de_k + kd de_k' + ki dI_k,   de_k = (de_k/dq) dq,   de_k' = (de_k/dq) dv,
  !> with the actuator's column da/du_k from one evaluation with u_k raised by 1 (exact: u
  !> enters linearly) and the measurement's gradient de_k/dq by differences of the kinematics
  !> with steps far above its tolerance. (Differences of the whole system with the usual
  !> sqrt(eps) steps drown in the kinematic solver's 1e-11 tolerance.) A saturated or sampled
  !> output does not depend on the state. A continuous user law, whose structure is unknown,
  !> makes the whole Jacobian come from differences with those larger steps.
  subroutine control_jacobian(this, t, q, v, dadq, dadv, status)
    class(controlled_t), intent(inout) :: this
    real(wp), intent(in) :: t, q(:), v(:)
    real(wp), intent(out) :: dadq(:, :), dadv(:, :)
    integer, intent(out) :: status
    real(wp) :: a0(size(q)), e0(this%nc), dedq(this%nc, this%n), g(this%n, this%nc)
    logical :: live(this%nc), integrating(this%nc)
    integer :: n, j, k
    n = this%n
    if (any([(this%dyn%model%controllers(k)%law_kind == LAW_USER .and. &
              .not. this%dyn%model%controllers(k)%sampled(), k = 1, this%nc)])) then
      call difference_jacobian(this, t, q, v, dadq, dadv, status)
      return
    end if
    dadq = 0.0_wp
    dadv = 0.0_wp
    call set_states(this, v)
    call this%plant%jacobian(t, q(1:n), v(1:n), dadq(1:n, 1:n), dadv(1:n, 1:n), status)
    if (status /= 0) return
    call this%accel(t, q, v, a0, status)
    if (status /= 0) return
    e0 = this%dyn%ctrl_error
    do k = 1, this%nc
      associate (c => this%dyn%model%controllers(k), law => this%dyn%ctrl_law(k))
        live(k) = .not. c%sampled() .and. law >= c%u_min .and. law <= c%u_max
        integrating(k) = .not. c%sampled() .and. .not. c%winds_up(law, e0(k))
      end associate
    end do
    call couplings(this, t, q, v, a0, e0, live, g, dedq, status)
    if (status /= 0) return
    do k = 1, this%nc
      associate (c => this%dyn%model%controllers(k))
        associate (ix => n + c%x_offset + 1)
          if (live(k)) then
            do j = 1, n
              dadq(1:n, j) = dadq(1:n, j) + c%kp * dedq(k, j) * g(:, k)
              dadv(1:n, j) = dadv(1:n, j) + c%kd * dedq(k, j) * g(:, k)
            end do
            dadv(1:n, ix) = c%ki * g(:, k)
          end if
          if (integrating(k)) dadq(ix, 1:n) = dedq(k, :)
        end associate
      end associate
    end do
    ! Leave the model at the state asked for (the integrators use the last evaluation).
    call this%accel(t, q, v, a0, status)
  end subroutine control_jacobian

  !> Difference step for coordinate (or rate) x: far above the kinematic solver's 1e-11
  !> tolerance, which differences with sqrt(eps) steps drown in.
  pure real(wp) function fd_step(x)
    real(wp), intent(in) :: x
    fd_step = 1.0e-6_wp * max(abs(x), 1.0e-2_wp)
  end function fd_step

  !> How the PID controllers couple to the plant at (t, q, v), where the accelerations are a0
  !> and the errors e0: g(:, k), the plant's accelerations per unit of controller k's output
  !> (one evaluation with it raised by 1, exact as u enters linearly), for the controllers in
  !> `want`, and dedq(k, :), the gradients of all errors by differences (n evaluations).
  subroutine couplings(this, t, q, v, a0, e0, want, g, dedq, status)
    type(controlled_t), intent(inout) :: this
    real(wp), intent(in) :: t, q(:), v(:), a0(:), e0(:)
    logical, intent(in) :: want(:)
    real(wp), intent(out) :: g(:, :), dedq(:, :)
    integer, intent(out) :: status
    real(wp) :: a1(size(q)), qp(size(q)), h
    integer :: j, k
    g = 0.0_wp
    status = 0
    do k = 1, this%nc
      if (.not. want(k)) cycle
      associate (iu => this%dyn%model%controllers(k)%u_offset + 1)
        this%dyn%ctrl_probe(iu) = 1.0_wp
        call this%accel(t, q, v, a1, status)
        this%dyn%ctrl_probe(iu) = 0.0_wp
      end associate
      if (status /= 0) return
      g(:, k) = a1(1:this%n) - a0(1:this%n)
    end do
    do j = 1, this%n
      qp = q
      h = fd_step(q(j))
      qp(j) = q(j) + h
      call this%accel(t, qp, v, a1, status)
      if (status /= 0) return
      dedq(:, j) = (this%dyn%ctrl_error - e0) / h
    end do
  end subroutine couplings

  !> The closed loop's Jacobian by forward differences with steps fd_step.
  subroutine difference_jacobian(this, t, q, v, dadq, dadv, status)
    type(controlled_t), intent(inout) :: this
    real(wp), intent(in) :: t, q(:), v(:)
    real(wp), intent(out) :: dadq(:, :), dadv(:, :)
    integer, intent(out) :: status
    real(wp) :: a0(size(q)), a1(size(q)), qp(size(q)), h
    integer :: j
    call this%accel(t, q, v, a0, status)
    if (status /= 0) return
    do j = 1, size(q)
      qp = q
      h = fd_step(q(j))
      qp(j) = q(j) + h
      call this%accel(t, qp, v, a1, status)
      if (status /= 0) return
      dadq(:, j) = (a1 - a0) / h
      qp = v
      h = fd_step(v(j))
      qp(j) = v(j) + h
      call this%accel(t, q, qp, a1, status)
      if (status /= 0) return
      dadv(:, j) = (a1 - a0) / h
    end do
    call this%accel(t, q, v, a0, status)
  end subroutine difference_jacobian

  subroutine control_error_norm(this, dq, q_old, q_new, rtol, atol, norm)
    class(controlled_t), intent(inout) :: this
    real(wp), intent(in) :: dq(:), q_old(:), q_new(:), rtol, atol
    real(wp), intent(out) :: norm
    associate (n => this%n)
      call this%plant%error_norm(dq(1:n), q_old(1:n), q_new(1:n), rtol, atol, norm)
    end associate
  end subroutine control_error_norm

  !> Samples due at t (t0 + i T, the times the run made breakpoints of): measure, hold the
  !> limited output, and integrate the error over the coming period (a PID) or take the
  !> law's next states (a user law).
  subroutine control_at_breakpoint(this, t, q, v, status)
    class(controlled_t), intent(inout) :: this
    real(wp), intent(in) :: t, q(:), v(:)
    integer, intent(out) :: status
    real(wp) :: a(size(q))
    real(wp), allocatable :: x_next(:), u(:)
    type(error_t) :: err
    logical :: measured
    integer :: k
    status = 0
    measured = .false.
    do k = 1, this%nc
      associate (c => this%dyn%model%controllers(k))
        if (.not. c%sampled()) cycle
        ! Compared as the run computes its breakpoints, t0 + i T, with a margin for round-off.
        if (t < this%t0 + this%n_samples(k) * c%period - 1.0e-6_wp * c%period) cycle
        if (.not. measured) then
          call this%accel(t, q, v, a, status)
          if (status /= 0) return
          measured = .true.
        end if
        associate (i => c%x_offset + 1, j => c%x_offset + c%n_x(), &
                   iu => c%u_offset + 1, ju => c%u_offset + size(c%act_index))
          if (c%law_kind == LAW_USER) then
            allocate(x_next(j - i + 1), u(ju - iu + 1))
            call this%dyn%user_law(k, t, x_next, u, err)
            call this%dyn%report(err, status)
            if (status /= 0) return
            this%dyn%ctrl_held(iu:ju) = c%limited(u)
            this%x_sampled(i:j) = x_next
            deallocate(x_next, u)
          else
            this%dyn%ctrl_held(iu) = c%limited(this%dyn%ctrl_law(k))
            if (.not. c%winds_up(this%dyn%ctrl_law(k), this%dyn%ctrl_error(k))) &
              this%x_sampled(i) = this%x_sampled(i) + c%period * this%dyn%ctrl_error(k)
          end if
        end associate
        this%n_samples(k) = this%n_samples(k) + 1
      end associate
    end do
  end subroutine control_at_breakpoint
end module dynamics_control
