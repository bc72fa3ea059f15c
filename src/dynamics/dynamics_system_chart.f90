!> Moving charts: the modes of elements with a limited range (a free rotation's rotation
!> vector) are coordinates relative to a reference the element may move (element_t%recentre).
!> A full model's run moves it at output times, so that q stays inside the range however far
!> the body turns; the charts at each output are kept with the history, so that analyses of a
!> recorded state (&linear along the motion) read its q in the chart it was recorded in.
submodule (dynamics_system) dynamics_system_chart
  implicit none

contains

  !> At (t, q, v): every limited element whose modes are beyond its recentring threshold takes
  !> the current configuration as its reference; its dynamic modes get their values and rates
  !> there, e and D_x x_dot (x does not change, only what q means). After an output (the
  !> driver's call) the kinematics already belong to (t, q): no solve, and x_dot is one solve
  !> with their factors, only when a chart moves.
  module procedure dyn_rechart
    real(wp) :: e(this%model%max_modes), de(this%model%max_modes, this%model%max_dofs)
    real(wp) :: q_full(this%model%n_q), qd_full(this%model%n_q), xd(this%model%n_x)
    real(wp) :: pdd(this%model%n_rh)
    type(error_t) :: err
    logical :: moved
    integer :: k, iel, j, nm, nd, qi
    changed = .false.
    status = 0
    if (.not. allocated(this%model%limited)) return
    if (size(this%model%limited) == 0) return
    q_full = this%full_q(t, q)
    if (.not. (this%kin%has_factors .and. all(this%kin%q == q_full))) then
      call this%kin%solve(this%model, q_full, err)
      call this%report(err, status)
      if (status /= 0) return
    end if
    associate (m => this%model)
      do k = 1, size(m%limited)
        iel = m%limited(k)
        associate (el => m%elements(iel)%e)
          nm = el%n_modes()
          nd = size(el%dofs)
          call m%mode_values(iel, q_full, e(:nm))
          call el%recentre(this%kin%x(el%dofs), e(:nm), moved)
          if (.not. moved) cycle
          if (.not. changed) then
            ! x_dot = DF qd with the factors of the old charts (x_dot is the same in any).
            call this%prescribed(t, q_full(1:m%n_rh), qd_full(1:m%n_rh), pdd)
            qd_full(m%n_rh + 1:) = v
            call this%kin%apply_df(m, qd_full, xd)
          end if
          changed = .true.
          call el%evaluate(this%kin%x(el%dofs), e(:nm), de(:nm, :nd))
          do j = 1, nm
            qi = m%modes(m%mode_first(iel) + j - 1)%q - m%n_rh
            if (qi <= 0) cycle
            q(qi) = e(j)
            v(qi) = dot_product(de(j, :nd), xd(el%dofs))
          end do
        end associate
      end do
    end associate
    ! The saved factors, DF and the predictor's q belong to the old charts' modes.
    if (changed) then
      this%kin%has_factors = .false.
      this%kin%has_df = .false.
    end if
  end procedure dyn_rechart

  module procedure dyn_charts
    integer :: k
    allocate(c(0))
    if (.not. allocated(this%model%limited)) return
    do k = 1, size(this%model%limited)
      c = [c, this%model%elements(this%model%limited(k))%e%chart()]
    end do
  end procedure dyn_charts

  module procedure dyn_use_charts
    integer :: k, first, n
    if (.not. allocated(this%model%limited)) return
    first = 1
    do k = 1, size(this%model%limited)
      associate (el => this%model%elements(this%model%limited(k))%e)
        n = size(el%chart())
        call el%set_chart(c(first:first + n - 1))
        first = first + n
      end associate
    end do
    this%kin%has_factors = .false.
    this%kin%has_df = .false.
  end procedure dyn_use_charts
end submodule dynamics_system_chart
