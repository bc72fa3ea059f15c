!> The run's history (q, v, x and the charts at the output times) and the energy at a state.
submodule (dynamics_system) dynamics_system_history
  implicit none

contains

  module procedure dyn_allocate_history
    if (allocated(this%x_hist)) deallocate(this%x_hist, this%q_hist, this%v_hist, &
      this%energy_hist, this%chart_hist)
    allocate(this%x_hist(this%model%n_x, nt), this%q_hist(this%model%n_dy, nt))
    allocate(this%v_hist(this%model%n_dy, nt), this%energy_hist(2, nt))
    allocate(this%chart_hist(size(this%charts()), nt))
  end procedure dyn_allocate_history

  module procedure dyn_record
    type(error_t) :: err
    ! An output needs the configuration only (the energy takes the velocities through DF):
    ! a kinematic solution, not a whole evaluation of the equations of motion.
    call this%kin%solve(this%model, this%full_q(t, q), err, t)
    call this%report(err, status)
    if (status == 0) call this%store(k, t, q, v)
  end procedure dyn_record

  module procedure dyn_store
    if (present(x)) then
      this%x_hist(:, k) = x
    else
      this%x_hist(:, k) = this%kin%x
    end if
    this%q_hist(:, k) = q
    this%v_hist(:, k) = v
    if (present(energy)) then
      this%energy_hist(:, k) = energy
    else
      this%energy_hist(:, k) = this%energy(t, q, v)
    end if
    this%chart_hist(:, k) = this%charts()
  end procedure dyn_store

  module procedure dyn_energy
    real(wp) :: qd(this%model%n_q), pdd(this%model%n_rh), xd(this%model%n_x)
    real(wp) :: q_rh(this%model%n_rh)
    associate (m => this%model)
      call this%prescribed(t, q_rh, qd(1:m%n_rh), pdd)
      qd(m%n_rh + 1:) = v_dy
      call this%kin%apply_df(m, qd, xd)
      en = this%energy_at(t, q_dy, this%kin%x, xd)
    end associate
  end procedure dyn_energy

  module procedure dyn_energy_at
    real(wp) :: q(this%model%n_q), qd_rh(this%model%n_rh), pdd(this%model%n_rh), pot
    real(wp) :: me(this%model%max_dofs, this%model%max_dofs), he(this%model%max_dofs)
    real(wp) :: fe(this%model%max_dofs), g(3)
    real(wp) :: e(this%model%max_modes), s(this%model%max_modes, this%model%max_modes)
    real(wp) :: de(this%model%max_modes, this%model%max_dofs)
    real(wp) :: xe(this%model%max_dofs), xde(this%model%max_dofs)
    integer :: iel, nm, nd, k
    associate (m => this%model)
      call this%prescribed(t, q(1:m%n_rh), qd_rh, pdd)
      q(m%n_rh + 1:) = q_dy
      en(1) = 0.5_wp * sum(m%lumped * xd**2)
      en(2) = -this%load_factor * dot_product(this%loads_at(t), x)
      g = this%load_factor * m%gravity
      do iel = 1, m%n_elements
        associate (el => m%elements(iel)%e)
          nm = el%n_modes()
          nd = size(el%dofs)
          ! Gathered: vector-subscripted arguments are a heap temporary each, per element
          ! and output.
          do k = 1, nd
            xe(k) = x(el%dofs(k))
            xde(k) = xd(el%dofs(k))
          end do
          if (m%elastic_element(iel)) then
            call el%evaluate(xe(:nd), e(:nm), de(:nm, :nd))
            where (.not. mode_has_stress(m%modes(m%mode_first(iel):m%mode_first(iel) + nm - 1) &
                   %class)) e(:nm) = 0.0_wp
          else
            call m%mode_values(iel, q, e(:nm))
          end if
          call el%stiffness(s(:nm, :nm))
          en(2) = en(2) + 0.5_wp * dot_product(e(:nm), matmul(s(:nm, :nm), e(:nm)))
          if (.not. el%has_inertia()) cycle
          call el%inertia(xe(:nd), xde(:nd), me(:nd, :nd), he(:nd))
          call el%weight(xe(:nd), g(1:m%dim), fe(:nd), pot)
          en(1) = en(1) + 0.5_wp * dot_product(xde(:nd), matmul(me(:nd, :nd), xde(:nd)))
          en(2) = en(2) + pot
        end associate
      end do
    end associate
  end procedure dyn_energy_at
end submodule dynamics_system_history
