!> The feedback controllers' part of an evaluation of the equations of motion.
submodule (dynamics_system) dynamics_system_control
  use model_control, only: ACT_MODE, MEAS_MODE
  implicit none

contains

  !> Each controller measures y (a joint's q, or a nodal coordinate's displacement x - x0)
  !> and its rate, and compares them with its reference r(t), r'(t) (zero without one). Its
  !> output works on the actuator's coordinate: an actuator on a dynamic mode like a stress of
  !> the opposite sign (as &hinge torque does), one on a nodal coordinate as a nodal force.
  module procedure dyn_apply_controllers
    real(wp) :: y, y_dot, r, r_dot, r_ddot, u
    integer :: k, j
    associate (m => this%model)
      do k = 1, size(m%controllers)
        associate (c => m%controllers(k))
          if (c%meas_kind == MEAS_MODE) then
            j = m%modes(c%meas_index)%q
            y = this%q_now(j)
            y_dot = this%qd_now(j)
          else
            j = c%meas_index
            y = this%kin%x(j) - m%x0(j)
            y_dot = this%xd_now(j)
          end if
          r = 0.0_wp
          r_dot = 0.0_wp
          if (c%reference > 0) call m%motions(c%reference)%eval(t, r, r_dot, r_ddot)
          this%ctrl_error(k) = r - y
          this%ctrl_error_rate(k) = r_dot - y_dot
          this%ctrl_law(k) = c%law(this%ctrl_error(k), this%ctrl_error_rate(k), &
            this%ctrl_integral(k)) + this%ctrl_ff(k)
          if (c%sampled()) then
            u = this%ctrl_held(k)
          else
            u = c%limited(this%ctrl_law(k))
          end if
          this%ctrl_u(k) = u
          u = u + this%ctrl_probe(k)
          if (c%act_kind == ACT_MODE) then
            j = m%modes(c%act_index)%q - m%n_rh
            this%sigma_now(j) = this%sigma_now(j) - u
          else
            this%nodal_force(c%act_index) = this%nodal_force(c%act_index) + u
          end if
        end associate
      end do
    end associate
  end procedure dyn_apply_controllers
end submodule dynamics_system_control
