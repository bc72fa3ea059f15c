!> Feedback controllers of a model (docs/input.md, &controller): a PID law on one measured
!> output, tracking a reference motion, acting through one actuator, or a law supplied by the
!> program or a shared library (law = 'user', a control_law_t; model_control_c has the laws
!> written in C) on several measured outputs and actuators with states of its own; continuous
!> or sampled with a zero-order hold, within the actuators' limits. This module knows where a
!> controller measures and acts and evaluates the PID law; the states of a run (the PID's
!> integral, a user law's states, the held outputs) belong to the run (dynamics_control), so
!> one model serves many runs.
module model_control
  use core_kinds, only: wp
  implicit none
  private
  public :: controller_t, control_law_t, ACT_MODE, ACT_COORD, MEAS_MODE, MEAS_COORD, LAW_PID, &
    LAW_USER, controller_sizes

  !> Where a controller acts: the generalised force on a dynamic mode (a joint's torque or a
  !> slider's force), or a nodal force on a coordinate (a force or, planar, a moment).
  integer, parameter :: ACT_MODE = 1, ACT_COORD = 2
  !> What it measures: a mode with a q coordinate (a joint's angle, a slider's position), or a
  !> nodal coordinate's displacement from the reference configuration.
  integer, parameter :: MEAS_MODE = 1, MEAS_COORD = 2

  integer, parameter :: LAW_PID = 1, LAW_USER = 2

  !> A control law supplied by the program that uses flexmor (law = 'user'; docs/api.md):
  !> extend it and give it to run%set_control_law. The run keeps its own copy, and copies of
  !> a model copy it again (by assignment: a law must stay valid so). evaluate is called at
  !> trial states of the integrator (continuous) or once per sample (sampled), so a law keeps
  !> its memory in x, never in itself (hence intent(in)).
  type, abstract :: control_law_t
  contains
    procedure(law_evaluate), deferred :: evaluate
  end type control_law_t

  abstract interface
    !> At time t with the measured outputs y and rates y_dot (the &controller's `measure`
    !> list, in its order) and the law's states x (n_states): the actuator inputs u (`actuator`
    !> list; limited by the run to [u_min, u_max]) and x_out, the rates dx/dt (period = 0) or
    !> the states after the sample (period > 0). status: 0 ok, > 0 recoverable (the
    !> integrator retries a shorter step), < 0 fatal (the run stops with an error).
    subroutine law_evaluate(this, t, y, y_dot, x, x_out, u, status)
      import :: control_law_t, wp
      class(control_law_t), intent(in) :: this
      real(wp), intent(in) :: t, y(:), y_dot(:), x(:)
      real(wp), intent(out) :: x_out(:), u(:)
      integer, intent(out) :: status
    end subroutine law_evaluate
  end interface

  type :: controller_t
    character(len=:), allocatable :: label
    integer :: law_kind = LAW_PID              !< LAW_*
    !> Per actuator and measured output (one each for a PID): ACT_* or MEAS_*, and the index
    !> into model%modes or x.
    integer, allocatable :: act_kind(:), act_index(:), meas_kind(:), meas_index(:)
    integer :: n_states = 0                    !< states of a user law
    !> Where this controller's actuators, measured outputs and states start (0-based) in the
    !> run's arrays over all controllers (dynamics_t ctrl_u, ctrl_y, ctrl_x).
    integer :: u_offset = 0, y_offset = 0, x_offset = 0
    !> The law of law = 'user': from the scene's `library` (model_build), or set by the
    !> program before the run (which replaces a library's).
    class(control_law_t), allocatable :: user_law
    integer :: reference = 0                  !< motion index of the reference, 0: r = 0
    real(wp) :: kp = 0.0_wp, ki = 0.0_wp, kd = 0.0_wp
    !> Sampling period [s]; 0: continuous.
    real(wp) :: period = 0.0_wp
    real(wp) :: u_min = -huge(1.0_wp), u_max = huge(1.0_wp)
    !> Adds the torque (force) the rigid-body model needs to follow the reference (the run
    !> computes it: dynamics_control).
    logical :: feedforward = .false.
  contains
    procedure :: law => controller_law
    procedure :: limited => controller_limited
    procedure :: winds_up => controller_winds_up
    procedure :: sampled => controller_sampled
    procedure :: n_x => controller_n_x
  end type controller_t

contains

  !> States a run carries for the controller: a PID's integral, or a user law's own.
  pure integer function controller_n_x(this)
    class(controller_t), intent(in) :: this
    controller_n_x = merge(1, this%n_states, this%law_kind == LAW_PID)
  end function controller_n_x

  !> Total actuators, measured outputs and states of all controllers (the sizes of a run's
  !> arrays; every controller's offsets are below them).
  pure subroutine controller_sizes(controllers, n_u, n_y, n_x)
    type(controller_t), intent(in) :: controllers(:)
    integer, intent(out) :: n_u, n_y, n_x
    integer :: k
    n_u = 0
    n_y = 0
    n_x = 0
    do k = 1, size(controllers)
      n_u = n_u + size(controllers(k)%act_index)
      n_y = n_y + size(controllers(k)%meas_index)
      n_x = n_x + controllers(k)%n_x()
    end do
  end subroutine controller_sizes

  !> The unlimited PID output kp e + ki integral + kd e_dot.
  pure real(wp) function controller_law(this, e, e_dot, integral) result(u)
    class(controller_t), intent(in) :: this
    real(wp), intent(in) :: e, e_dot, integral
    u = this%kp * e + this%ki * integral + this%kd * e_dot
  end function controller_law

  !> The output within the actuator's limits.
  elemental real(wp) function controller_limited(this, u) result(u_lim)
    class(controller_t), intent(in) :: this
    real(wp), intent(in) :: u
    u_lim = min(max(u, this%u_min), this%u_max)
  end function controller_limited

  !> Anti-windup by conditional integration: while the actuator is at a limit the integral
  !> stops growing in the direction that pushes further into it (ki >= 0), so it does not
  !> have to unwind for seconds after the limit is left.
  pure logical function controller_winds_up(this, u, e) result(stop_integrating)
    class(controller_t), intent(in) :: this
    real(wp), intent(in) :: u, e
    stop_integrating = (u > this%u_max .and. e > 0) .or. (u < this%u_min .and. e < 0)
  end function controller_winds_up

  pure logical function controller_sampled(this)
    class(controller_t), intent(in) :: this
    controller_sampled = this%period > 0
  end function controller_sampled
end module model_control
