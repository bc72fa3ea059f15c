!> What a static analysis reports at each converged step beside the configuration: reactions,
!> compliances and the lowest natural frequencies (dynamics_response). On the Newton-Krylov path
!> of large models the frequencies of a stable step come from the sparse shift-invert Lanczos
!> of reduction_krylov instead of the dense tangent: stable, the tangent has no negative
!> eigenvalue, so the ones nearest the shift (about 0) are the lowest. An unstable step keeps
!> the dense tangent, whose eigenvalues are ordered from the most negative.
submodule (analysis_run) analysis_run_static
  use dynamics_static, only: static_uses_krylov
  use reduction_krylov, only: krylov_modes, krylov_modes_applies
  implicit none

contains

  !> The prescribed coordinates stepped with the load when `ramped`, as static_solve has them;
  !> held at their full values as arc_length_solve has them.
  module procedure static_responses
    integer, allocatable :: out_coords(:, :), comp_coords(:, :)
    real(wp), allocatable :: omega2(:), shapes(:, :), node_shapes(:, :)
    integer :: i, k, nf
    logical :: krylov, krylov_frequencies, lanczos
    associate (m => this%dyn%model, sc => this%scene)
      allocate(out_coords(NODE_SLOTS, size(sc%output_nodes)), &
        comp_coords(NODE_SLOTS, size(sc%compliance_nodes)))
      do i = 1, size(sc%output_nodes)
        out_coords(:, i) = m%node_coord(:, m%find_node(sc%output_nodes(i)%s))
      end do
      do i = 1, size(sc%compliance_nodes)
        comp_coords(:, i) = m%node_coord(:, m%find_node(sc%compliance_nodes(i)%s))
      end do
      nf = sc%static%n_frequencies
      if (nf > m%n_dy) then
        call err%set(ERR_INPUT, 'group &static: variable ''n_frequencies'' = ' // &
          int_str(nf) // ' exceeds the ' // int_str(m%n_dy) // ' dynamic coordinates')
        return
      end if
      call this%static_response%init(out_coords, comp_coords, nf, size(q_steps, 2), m%dim)
      call static_uses_krylov(this%dyn, m%n_dy, sc%static%solver, krylov, err)
      if (.not. err%ok()) return
      ! Lanczos needs n - 2 coordinates beyond the modes it is asked for.
      krylov_frequencies = krylov .and. nf > 0 .and. nf <= m%n_dy - 2
      if (krylov_frequencies) krylov_frequencies = krylov_modes_applies(this%dyn, .false.) == ''
      this%dyn%ramp_prescribed = ramped
      do k = 1, size(q_steps, 2)
        this%dyn%load_factor = this%static_load_factor(k)
        call this%dyn%kin%restart_from(this%x_static(:, k))
        lanczos = krylov_frequencies .and. this%static_stable(k)
        call this%static_response%record(this%dyn, 0.0_wp, q_steps(:, k), k, err, krylov, &
          frequencies=.not. lanczos)
        if (err%ok() .and. lanczos) then
          call krylov_modes(this%dyn, 0.0_wp, q_steps(:, k), nf, omega2, shapes, node_shapes, &
            err)
          if (err%ok()) this%static_response%frequency_hz(:, k) = &
            sign(sqrt(abs(omega2)), omega2) / TWO_PI
        end if
        if (.not. err%ok()) exit
      end do
      this%dyn%ramp_prescribed = .false.
      this%dyn%load_factor = 1.0_wp
    end associate
    if (.not. err%ok()) call err%prefix('static, load step ' // int_str(k) // ': ')
  end procedure static_responses
end submodule analysis_run_static
