!> The stresses of the dynamic modes: their terms, the stress resultants and the constant
!> stiffness and damping they give.
submodule (dynamics_system) dynamics_system_stresses
  implicit none

contains

  !> The terms of sigma_dy = S (e + beta e_dot) over q (dyn_stresses), element by element
  !> in the order of S's rows and columns (elements with elastic modes excluded).
  module procedure stress_entries
    integer :: iel, i, j, nm, n, pass
    associate (m => this%model)
      if (allocated(this%st_first)) deallocate(this%st_first, this%st_row, this%st_col, &
        this%st_i, this%st_j)
      allocate(this%st_first(m%n_elements + 1))
      do pass = 1, 2
        n = 0
        do iel = 1, m%n_elements
          this%st_first(iel) = n + 1
          if (m%elastic_element(iel)) cycle
          nm = m%elements(iel)%e%n_modes()
          do i = 1, nm
            associate (row => m%modes(m%mode_first(iel) + i - 1))
              if (row%class /= MODE_DYNAMIC) cycle
              do j = 1, nm
                associate (col => m%modes(m%mode_first(iel) + j - 1))
                  if (col%q <= 0) cycle
                  n = n + 1
                  if (pass == 1) cycle
                  this%st_row(n) = row%q - m%n_rh
                  this%st_col(n) = col%q
                  this%st_i(n) = i
                  this%st_j(n) = j
                end associate
              end do
            end associate
          end do
        end do
        this%st_first(m%n_elements + 1) = n + 1
        if (pass == 1) allocate(this%st_row(n), this%st_col(n), this%st_i(n), this%st_j(n))
      end do
    end associate
  end procedure stress_entries

  !> Stress resultants of the dynamic modes, sigma_dy = S (e + beta e_dot), in q_dy order, for
  !> full q = (q_rh, q_dy), from the terms of stress_entries (elements with elastic modes
  !> excluded: their stresses act as nodal forces).
  module procedure dyn_stresses
    ! Every element's S and beta first, then the terms in one loop on explicit-shape arrays:
    ! the compiler keeps the bases in registers where it reloaded each component's
    ! descriptor per term.
    real(wp) :: s(this%model%max_modes, this%model%max_modes, this%model%n_elements)
    real(wp) :: beta(this%model%n_elements)
    integer :: iel, nm
    do iel = 1, this%model%n_elements
      beta(iel) = 0.0_wp
      if (this%st_first(iel + 1) == this%st_first(iel)) cycle
      associate (el => this%model%elements(iel)%e)
        nm = el%n_modes()
        call el%stiffness(s(1:nm, 1:nm, iel))
        beta(iel) = el%damping
      end associate
    end do
    call add_terms(this%model%n_elements, size(this%st_row), this%model%max_modes, size(q), &
      size(sigma), this%st_first, this%st_row, this%st_col, this%st_i, this%st_j, s, beta, q, qd, &
      sigma)
  end procedure dyn_stresses

  !> sigma = sum of the terms S_ij (q + beta qd) of dyn_stresses, element by element.
  pure subroutine add_terms(n_el, n, mm, n_q, n_dy, first, row, col, ti, tj, s, beta, q, qd, &
      sigma)
    integer, intent(in) :: n_el, n, mm, n_q, n_dy
    integer, intent(in) :: first(n_el + 1), row(n), col(n), ti(n), tj(n)
    real(wp), intent(in) :: s(mm, mm, n_el), beta(n_el), q(n_q), qd(n_q)
    real(wp), intent(out) :: sigma(n_dy)
    integer :: iel, k
    sigma = 0.0_wp
    do iel = 1, n_el
      do k = first(iel), first(iel + 1) - 1
        sigma(row(k)) = sigma(row(k)) + &
          s(ti(k), tj(k), iel) * (q(col(k)) + beta(iel) * qd(col(k)))
      end do
    end do
  end subroutine add_terms

  !> The constant part of K0 and D0: dsigma_dy/dq_dy and dsigma_dy/dv_dy of the dynamic
  !> modes (block diagonal by element).
  module procedure dyn_mode_stiffness
    real(wp) :: s(this%model%max_modes, this%model%max_modes)
    integer :: iel, k, nm, nr
    ! The dynamic-dynamic terms of stress_entries' list (a prescribed column has q <= n_rh).
    k0 = 0.0_wp
    d0 = 0.0_wp
    nr = this%model%n_rh
    do iel = 1, this%model%n_elements
      if (this%st_first(iel + 1) == this%st_first(iel)) cycle
      associate (el => this%model%elements(iel)%e)
        nm = el%n_modes()
        call el%stiffness(s(1:nm, 1:nm))
        do k = this%st_first(iel), this%st_first(iel + 1) - 1
          if (this%st_col(k) <= nr) cycle
          k0(this%st_row(k), this%st_col(k) - nr) = s(this%st_i(k), this%st_j(k))
          d0(this%st_row(k), this%st_col(k) - nr) = el%damping * s(this%st_i(k), this%st_j(k))
        end do
      end associate
    end do
  end procedure dyn_mode_stiffness

end submodule dynamics_system_stresses
