!> The feedback controllers' part of an evaluation of the equations of motion.
submodule (dynamics_system) dynamics_system_control
  use model_control, only: ACT_MODE, MEAS_MODE, LAW_USER
  use core_strings, only: int_str, real_str
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  implicit none

contains

  !> Each controller measures its outputs y (a joint's q, or a nodal coordinate's
  !> displacement x - x0) and their rates. A PID compares them with its reference r(t), r'(t)
  !> (zero without one); a continuous user law is evaluated here, a sampled one only at its
  !> samples (dynamics_control). The outputs work on the actuators' coordinates: an actuator
  !> on a dynamic mode like a stress of the opposite sign (as &hinge torque does), one on a
  !> nodal coordinate as a nodal force.
  module procedure dyn_apply_controllers
    real(wp) :: r, r_dot, r_ddot
    integer :: k, i, j
    associate (m => this%model)
      do k = 1, size(m%controllers)
        associate (c => m%controllers(k))
          do i = 1, size(c%meas_index)
            if (c%meas_kind(i) == MEAS_MODE) then
              j = m%modes(c%meas_index(i))%q
              this%ctrl_y(c%y_offset + i) = this%q_now(j)
              this%ctrl_y_dot(c%y_offset + i) = this%qd_now(j)
            else
              j = c%meas_index(i)
              this%ctrl_y(c%y_offset + i) = this%kin%x(j) - m%x0(j)
              this%ctrl_y_dot(c%y_offset + i) = this%xd_now(j)
            end if
          end do
          associate (u => this%ctrl_u(c%u_offset + 1:c%u_offset + size(c%act_index)), &
                     held => this%ctrl_held(c%u_offset + 1:c%u_offset + size(c%act_index)))
            if (c%law_kind == LAW_USER) then
              if (c%sampled()) then
                u = held
              else
                block
                  ! The law's results come back in copies: the law reads this, which they
                  ! are part of.
                  real(wp) :: u_law(size(c%act_index)), rate(c%n_states)
                  call this%user_law(k, t, rate, u_law, err)
                  if (.not. err%ok()) return
                  u = c%limited(u_law)
                  this%ctrl_x_rate(c%x_offset + 1:c%x_offset + c%n_states) = rate
                end block
              end if
            else
              r = 0.0_wp
              r_dot = 0.0_wp
              if (c%reference > 0) call m%motions(c%reference)%eval(t, r, r_dot, r_ddot)
              this%ctrl_error(k) = r - this%ctrl_y(c%y_offset + 1)
              this%ctrl_error_rate(k) = r_dot - this%ctrl_y_dot(c%y_offset + 1)
              this%ctrl_law(k) = c%law(this%ctrl_error(k), this%ctrl_error_rate(k), &
                this%ctrl_x(c%x_offset + 1)) + this%ctrl_ff(c%u_offset + 1)
              if (c%sampled()) then
                u = held
              else
                u = c%limited(this%ctrl_law(k))
              end if
            end if
            ! The probe (zero but in the closed loop's Jacobian) is not part of the output.
            do i = 1, size(c%act_index)
              if (c%act_kind(i) == ACT_MODE) then
                j = m%modes(c%act_index(i))%q - m%n_rh
                this%sigma_now(j) = this%sigma_now(j) - u(i) - this%ctrl_probe(c%u_offset + i)
              else
                j = c%act_index(i)
                this%nodal_force(j) = this%nodal_force(j) + u(i) + &
                  this%ctrl_probe(c%u_offset + i)
              end if
            end do
          end associate
        end associate
      end do
    end associate
  end procedure dyn_apply_controllers

  module procedure dyn_user_law
    integer :: status
    character(len=:), allocatable :: what
    associate (c => this%model%controllers(k))
      associate (y => this%ctrl_y(c%y_offset + 1:c%y_offset + size(c%meas_index)), &
                 y_dot => this%ctrl_y_dot(c%y_offset + 1:c%y_offset + size(c%meas_index)), &
                 x => this%ctrl_x(c%x_offset + 1:c%x_offset + c%n_states))
        call c%user_law%evaluate(t, y, y_dot, x, x_out, u, status)
      end associate
      what = 'group &controller ''' // c%label // ''': the user control law '
      if (status < 0) then
        call err%set(ERR_INPUT, what // 'failed (status ' // int_str(status) // ') at t = ' // &
          real_str(t))
      else if (status > 0) then
        call err%set(ERR_NUMERIC, what // 'asked for a shorter step (status ' // &
          int_str(status) // ') at t = ' // real_str(t))
      else if (.not. (all(ieee_is_finite(u)) .and. all(ieee_is_finite(x_out)))) then
        ! Neither a NaN nor an infinity may reach the integrator as a force or a state (tested
        ! without comparisons, which trap on a NaN in Debug).
        call err%set(ERR_NUMERIC, what // 'returned a value that is not finite at t = ' // &
          real_str(t))
      end if
    end associate
  end procedure dyn_user_law
end submodule dynamics_system_control
