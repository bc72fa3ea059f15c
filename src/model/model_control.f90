!> Feedback controllers of a model (docs/input.md, &controller): a PID law on one measured
!> output, tracking a reference motion, acting through one actuator, continuous or sampled with
!> a zero-order hold, within the actuator's limits. This module knows where a controller
!> measures and acts and evaluates its law; the states of a run (the integral of the error, the
!> held output) belong to the run (dynamics_control), so one model serves many runs.
module model_control
  use core_kinds, only: wp
  implicit none
  private
  public :: controller_t, ACT_MODE, ACT_COORD, MEAS_MODE, MEAS_COORD

  !> Where a controller acts: the generalised force on a dynamic mode (a joint's torque or a
  !> slider's force), or a nodal force on a coordinate (a force or, planar, a moment).
  integer, parameter :: ACT_MODE = 1, ACT_COORD = 2
  !> What it measures: a mode with a q coordinate (a joint's angle, a slider's position), or a
  !> nodal coordinate's displacement from the reference configuration.
  integer, parameter :: MEAS_MODE = 1, MEAS_COORD = 2

  type :: controller_t
    character(len=:), allocatable :: label
    integer :: act_kind = 0, act_index = 0    !< ACT_*; index into model%modes or x
    integer :: meas_kind = 0, meas_index = 0  !< MEAS_*; index into model%modes or x
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
  end type controller_t

contains

  !> The unlimited PID output kp e + ki integral + kd e_dot.
  pure real(wp) function controller_law(this, e, e_dot, integral) result(u)
    class(controller_t), intent(in) :: this
    real(wp), intent(in) :: e, e_dot, integral
    u = this%kp * e + this%ki * integral + this%kd * e_dot
  end function controller_law

  !> The output within the actuator's limits.
  pure real(wp) function controller_limited(this, u) result(u_lim)
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
