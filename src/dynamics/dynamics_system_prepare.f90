!> One evaluation of the model at a state: the kinematics, velocities and second-order terms,
!> the element inertia, loads and stresses as nodal forces (prepare), and what statics and the
!> dense path take from it.
submodule (dynamics_system) dynamics_system_prepare
  use elements_base, only: element_t
  implicit none

contains

  module procedure dyn_prepare
    real(wp) :: q(this%model%n_q), qd(this%model%n_q), pdd(this%model%n_rh)
    real(wp) :: conv(this%model%n_x), rhs(this%model%n_x), xd(this%model%n_x)
    real(wp) :: dq(this%model%n_q), pot
    real(wp) :: fe_work(this%model%max_dofs)
    real(wp) :: xe(this%model%max_dofs), xde(this%model%max_dofs), ce(this%model%max_dofs)
    real(wp) :: d2e(size(this%model%modes)), h_all(size(this%mass%dofs))
    integer :: iel, nr, nd, k, mf, d0
    logical :: weighted
    real(wp) :: g(3)
    this%n_evals = this%n_evals + 1
    associate (m => this%model)
      nr = m%n_rh
      call this%prescribed(t, q(1:nr), qd(1:nr), pdd)
      q(nr + 1:) = q_dy
      qd(nr + 1:) = v_dy
      call this%kin%solve(m, q, err, t)
      if (.not. err%ok()) return
      call this%kin%apply_df(m, qd, xd)
      dq(1:nr) = pdd
      dq(nr + 1:) = 0.0_wp
      if (present(qdd_dy)) dq(nr + 1:) = qdd_dy
      ! One pass over the elements at (x, x_dot): the second-order terms of the kinematics
      ! and the element masses and convective forces (one chord per beam); then the solve
      ! for conv, and the inertia forces from the kept blocks.
      ! The element coordinates from the flat list mass%dofs: indexing through the polymorphic
      ! elements reloads their descriptors for every coordinate.
      do iel = 1, m%n_elements
        d0 = this%mass%dof_first(iel) - 1
        nd = this%mass%dof_first(iel + 1) - 1 - d0
        mf = m%mode_first(iel)
        associate (el => m%elements(iel)%e, first => this%mass%offset(iel), &
                   d2 => d2e(mf:mf + this%kin%el_nm(iel) - 1), dofs => this%mass%dofs)
          ! Gathered: vector-subscripted actual arguments would be temporaries per element.
          do k = 1, nd
            xe(k) = this%kin%x(dofs(d0 + k))
            xde(k) = xd(dofs(d0 + k))
          end do
          if (first == 0) then
            call el%second(xe(1:nd), xde(1:nd), d2)
            cycle
          end if
          if (this%kin%modes_at_x) then
            call second_inertia_into(el, xe(1:nd), xde(1:nd), d2, nd, &
              this%mass%val(first:first + nd * nd - 1), h_all(d0 + 1:d0 + nd), &
              this%kin%e_val(mf:mf + this%kin%el_nm(iel) - 1))
          else
            call second_inertia_into(el, xe(1:nd), xde(1:nd), d2, nd, &
              this%mass%val(first:first + nd * nd - 1), h_all(d0 + 1:d0 + nd))
          end if
        end associate
      end do
      call this%kin%second_solve(m, d2e, conv, dq)
      call this%kin%note_rates(t, qd, dq, xd, conv)
      rhs = this%load_factor * this%loads_at(t) - m%lumped * conv
      weighted = any(m%gravity /= 0)
      g = this%load_factor * m%gravity
      do iel = 1, m%n_elements
        if (this%mass%offset(iel) == 0) cycle
        d0 = this%mass%dof_first(iel) - 1
        nd = this%mass%dof_first(iel + 1) - 1 - d0
        associate (el => m%elements(iel)%e, he => h_all(d0 + 1:d0 + nd), &
                   fe => fe_work(1:nd), first => this%mass%offset(iel), dofs => this%mass%dofs)
          do k = 1, nd
            ce(k) = conv(dofs(d0 + k))
          end do
          if (weighted) then
            do k = 1, nd
              xe(k) = this%kin%x(dofs(d0 + k))
            end do
            call el%weight(xe(1:nd), g(1:m%dim), fe, pot)
            fe = fe - he
          else
            fe = -he
          end if
          call subtract_product(nd, this%mass%val(first:first + nd * nd - 1), ce, fe)
          do k = 1, nd
            rhs(dofs(d0 + k)) = rhs(dofs(d0 + k)) + fe(k)
          end do
        end associate
      end do
      this%xd_now = xd
      if (size(m%moment_lambda) > 0) call add_moments(m, t, this%kin%x, this%load_factor, rhs)
      if (m%n_elastic > 0) call this%elastic_forces(xd, rhs)
      this%nodal_force = rhs
      this%q_now = q
      this%qd_now = qd
      this%sigma_now = this%stresses(q, qd)
      ! An actuator's torque works on its mode like a stress of the opposite sign.
      if (size(m%actuator_element) > 0) this%sigma_now = this%sigma_now - &
        this%load_factor * m%actuator_forces(t)
      if (this%controls_on) call this%apply_controllers(t, err)
    end associate
  end procedure dyn_prepare

  !> el%second_inertia with the mass matrix written straight into its flat block m (nd x nd,
  !> contiguous in element_mass_t%val): no copy per element. e: the kinematics' mode values
  !> at x, when they are current.
  subroutine second_inertia_into(el, x, xd, d2e, nd, m, h, e)
    class(element_t), intent(in) :: el
    real(wp), intent(in) :: x(:), xd(:)
    real(wp), intent(out) :: d2e(:)
    integer, intent(in) :: nd
    real(wp), intent(out) :: m(nd, nd), h(:)
    real(wp), intent(in), optional :: e(:)
    call el%second_inertia(x, xd, d2e, m, h, e)
  end subroutine second_inertia_into

  !> f := f - m c for one element block, by hand (explicit shapes: constant strides; matmul
  !> on such small blocks costs more than the product). The planar beam's 6 x 6 blocks, most
  !> of a planar model's, go through a copy of the loop with constant trip counts, which the
  !> compiler unrolls into whole-vector operations.
  pure subroutine subtract_product(nd, m, c, f)
    integer, intent(in) :: nd
    real(wp), intent(in) :: m(nd, nd), c(nd)
    real(wp), intent(inout) :: f(nd)
    integer :: k, l
    if (nd == 6) then
      call subtract_product_6(m, c, f)
      return
    end if
    do l = 1, nd
      do k = 1, nd
        f(k) = f(k) - m(k, l) * c(l)
      end do
    end do
  end subroutine subtract_product

  pure subroutine subtract_product_6(m, c, f)
    real(wp), intent(in) :: m(6, 6), c(6)
    real(wp), intent(inout) :: f(6)
    integer :: l
    do l = 1, 6
      f = f - m(:, l) * c(l)
    end do
  end subroutine subtract_product_6

  !> Nodal forces of the moments on spatial nodes: M . omega_global = M . 2 E(lambda) lambda'
  !> gives 2 E^T M on the Euler parameters, E = [-lv, l0 I + [lv x]]. A moment fixed in space
  !> is not conservative under large 3D rotations: it has no potential in the energy output.
  pure subroutine add_moments(model, t, x, factor, f)
    type(model_t), intent(in) :: model
    real(wp), intent(in) :: t, x(:), factor
    real(wp), intent(inout) :: f(:)
    real(wp) :: e(3, 4)
    integer :: k, i
    do k = 1, size(model%moment_lambda)
      i = model%moment_lambda(k)
      e = euler_e(x(i:i + 3))
      f(i:i + 3) = f(i:i + 3) + 2 * factor * matmul(transpose(e), model%moment_at(k, t))
    end do
  end subroutine add_moments

  module procedure dyn_generalised_force
    real(wp) :: g_q(this%model%n_q)
    call this%prepare(t, q_dy, v_dy, err)
    if (.not. err%ok()) return
    call this%kin%apply_dft(this%model, this%nodal_force, g_q)
    g = g_q(this%model%n_rh + 1:) - this%sigma_now
    this%gen_force = g
  end procedure dyn_generalised_force

  module procedure dyn_assemble
    integer :: nr
    call this%prepare(t, q_dy, v_dy, err)
    if (.not. err%ok()) return
    call this%kin%transfer(this%model)
    nr = this%model%n_rh
    associate (dfd => this%kin%df(:, nr + 1:))
      this%mbar = matmul(transpose(dfd), this%mass%times(this%model, dfd))
      this%gen_force = matmul(this%nodal_force, dfd) - this%sigma_now
    end associate
  end procedure dyn_assemble
end submodule dynamics_system_prepare
