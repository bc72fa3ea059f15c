!> The predictor of a kinematic solve. From the last solution (x0, q0), x(q) = x0 + DF dq +
!> D2F(dq, dq)/2 + ...: the first-order predictor leaves the quadratic term, about
!> (h qd)^2 / 2 in a time step h, which takes a chord correction and a second element pass at
!> every step's first evaluation. When the caller noted the rates of the last solution at
!> time t0 (an integrator's evaluation: qd, qdd and x's own derivatives xd, xdd), the Taylor
!> series in time, x0 + s xd + s^2 xdd / 2 with s = t - t0, carries that term, and DF takes
!> the rest, dq - (s qd + s^2 qdd / 2): with dq = s qd + r, r = O(s^2), the error left is
!> D2F(s qd, r) + D2F(r, r) / 2 = O(s^3), whatever qdd was used (xdd holds the same qdd).
submodule (model_kinematics) model_kinematics_rates
  implicit none

contains

  module procedure kin_note_rates
    this%rates%t = t
    this%rates%qd = qd
    this%rates%qdd = qdd
    this%rates%xd = xd
    this%rates%xdd = xdd
    this%rates%valid = .true.
  end procedure kin_note_rates

  module procedure kin_predict
    real(wp) :: dq(model%n_q), dx(model%n_x), s
    dq = q - this%q
    if (present(t) .and. this%rates%valid) then
      s = t - this%rates%t
      dq = dq - s * (this%rates%qd + (0.5_wp * s) * this%rates%qdd)
      call this%apply_df(model, dq, dx)
      this%x = this%x + s * (this%rates%xd + (0.5_wp * s) * this%rates%xdd) + dx
      ! At the same time (an output of the state just evaluated, a Newton correction) the
      ! solution moves by a correction only, and the rates still serve the next step.
      this%rates%valid = s == 0
    else
      call this%apply_df(model, dq, dx)
      this%x = this%x + dx
      this%rates%valid = .false.
    end if
  end procedure kin_predict
end submodule model_kinematics_rates
