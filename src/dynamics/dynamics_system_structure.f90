!> The structural terms of the equations: elastic modes' stresses as nodal forces, the constant
!> stiffness and damping of the stressed modes, and their action on a basis.
submodule (dynamics_system) dynamics_system_structure
  implicit none

contains

  module procedure dyn_elastic_forces
    real(wp), allocatable :: e(:), de(:, :), s(:, :), sigma(:)
    integer :: iel, nm
    associate (m => this%model)
      do iel = 1, m%n_elements
        if (.not. m%elastic_element(iel)) cycle
        associate (el => m%elements(iel)%e)
          nm = el%n_modes()
          allocate(e(nm), de(nm, size(el%dofs)), s(nm, nm))
          call el%evaluate(this%kin%x(el%dofs), e, de)
          call el%stiffness(s)
          sigma = matmul(s, e + el%damping * matmul(de, xd(el%dofs)))
          where (.not. stressed_modes(m, iel)) sigma = 0.0_wp
          f(el%dofs) = f(el%dofs) - matmul(sigma, de)
          deallocate(e, de, s)
        end associate
      end do
    end associate
  end procedure dyn_elastic_forces

  !> Which modes of element iel carry a stress (dynamic and elastic ones).
  pure function stressed_modes(m, iel) result(stressed)
    type(model_t), intent(in) :: m
    integer, intent(in) :: iel
    logical :: stressed(m%elements(iel)%e%n_modes())
    stressed = mode_has_stress(m%modes(m%mode_first(iel):m%mode_first(iel) + &
      size(stressed) - 1)%class)
  end function stressed_modes

  module procedure dyn_structural_stiffness
    real(wp), allocatable :: e(:), de(:, :), s(:, :), dfe(:, :), sdfe(:, :)
    logical, allocatable :: stressed(:)
    integer :: iel, nm
    call this%mode_stiffness(k0, d0)
    if (this%model%n_elastic > 0 .and. .not. this%kin%has_df) call this%kin%transfer(this%model)
    associate (m => this%model)
      do iel = 1, m%n_elements
        if (.not. m%elastic_element(iel)) cycle
        associate (el => m%elements(iel)%e)
          nm = el%n_modes()
          allocate(e(nm), de(nm, size(el%dofs)), s(nm, nm))
          call el%evaluate(this%kin%x(el%dofs), e, de)
          call el%stiffness(s)
          stressed = stressed_modes(m, iel)
          dfe = matmul(de, this%kin%df(el%dofs, m%n_rh + 1:))
          where (spread(.not. stressed, 2, size(dfe, 2))) dfe = 0.0_wp
          sdfe = matmul(transpose(dfe), matmul(s, dfe))
          k0 = k0 + sdfe
          d0 = d0 + el%damping * sdfe
          deallocate(e, de, s)
        end associate
      end do
    end associate
  end procedure dyn_structural_stiffness

  module procedure dyn_structural_action
    real(wp), allocatable :: e(:), de(:, :), s(:, :), sdfe(:, :)
    real(wp) :: gk(this%model%n_x, size(v, 2)), gd(this%model%n_x, size(v, 2))
    real(wp) :: proj(this%model%n_q)
    integer :: iel, i, j, nm, qi, qj
    kv = 0.0_wp
    dv = 0.0_wp
    gk = 0.0_wp
    gd = 0.0_wp
    associate (m => this%model)
      do iel = 1, m%n_elements
        associate (el => m%elements(iel)%e)
          nm = el%n_modes()
          allocate(s(nm, nm))
          call el%stiffness(s)
          if (m%elastic_element(iel)) then
            allocate(e(nm), de(nm, size(el%dofs)))
            call el%evaluate(this%kin%x(el%dofs), e, de)
            where (.not. spread(stressed_modes(m, iel), 2, size(el%dofs))) de = 0.0_wp
            sdfe = matmul(transpose(de), matmul(s, matmul(de, w(el%dofs, :))))
            gk(el%dofs, :) = gk(el%dofs, :) + sdfe
            gd(el%dofs, :) = gd(el%dofs, :) + el%damping * sdfe
            deallocate(e, de)
          else
            do j = 1, nm
              if (m%modes(m%mode_first(iel) + j - 1)%class /= MODE_DYNAMIC) cycle
              qj = m%modes(m%mode_first(iel) + j - 1)%q - m%n_rh
              do i = 1, nm
                if (m%modes(m%mode_first(iel) + i - 1)%class /= MODE_DYNAMIC) cycle
                qi = m%modes(m%mode_first(iel) + i - 1)%q - m%n_rh
                kv(qi, :) = kv(qi, :) + s(i, j) * v(qj, :)
                dv(qi, :) = dv(qi, :) + el%damping * s(i, j) * v(qj, :)
              end do
            end do
          end if
          deallocate(s)
        end associate
      end do
      if (m%n_elastic == 0) return
      do j = 1, size(v, 2)
        call this%kin%apply_dft(m, gk(:, j), proj)
        kv(:, j) = kv(:, j) + proj(m%n_rh + 1:)
        call this%kin%apply_dft(m, gd(:, j), proj)
        dv(:, j) = dv(:, j) + proj(m%n_rh + 1:)
      end do
    end associate
  end procedure dyn_structural_action
end submodule dynamics_system_structure
