!> Finding, placing and leaving the kept expansions of a run (reduction_expansion).
submodule (reduction_expansion) reduction_expansion_set
  implicit none

contains

  !> Make an expansion that serves (p, eta) current, if one is kept; false if none is.
  module procedure set_find
    real(wp) :: d(2)
    integer :: i
    this%p_last = p
    i = serving(this, p, eta, d)
    found = i > 0
    if (.not. found .or. i == this%current) return
    this%current = i
    this%clock = this%clock + 1
    this%last_use(i) = this%clock
  end procedure set_find

  !> Keep the accepted state (t, p, eta, eta_dot) if it is the farthest the expansion serving
  !> it has served: set_unchecked compares the expansion with the exact model there. Only
  !> accepted states: a rejected trial step may swing far beyond anything the run used
  !> (input/four_bar.nml, 4 modes: a trial state 0.09 m from the exact coordinates, outputs
  !> 4e-6 m from the full evaluation).
  module procedure set_note_served
    real(wp) :: d(2)
    integer :: i
    i = serving(this, p, eta, d)
    if (i == 0) return
    associate (ex => this%item(i))
      if (d(2) > ex%far_d2) then
        ex%far_d2 = d(2)
        ex%far_t = t
        ex%far_z = [p, eta]
        ex%far_rate = eta_dot
      end if
    end associate
  end procedure set_note_served

  !> The kept expansion that serves the state (p, eta), the current one first (0: none), and
  !> its spreads d there.
  integer function serving(set, p, eta, d) result(i)
    type(expansion_set_t), intent(in) :: set
    real(wp), intent(in) :: p(:), eta(:)
    real(wp), intent(out) :: d(2)
    integer :: j
    d = 0.0_wp
    i = 0
    if (.not. allocated(set%item)) return
    if (set%current > 0) then
      if (serves(set%current)) then
        i = set%current
        return
      end if
    end if
    do j = 1, size(set%item)
      if (j == set%current) cycle
      if (.not. serves(j)) cycle
      i = j
      return
    end do
  contains
    logical function serves(k)
      integer, intent(in) :: k
      serves = .false.
      if (.not. set%item(k)%valid) return
      d = set%item(k)%spread_at(p, eta)
      serves = .not. set%item(k)%beyond(d, set%tol)
    end function serves
  end function serving

  !> Where to centre a new expansion for the state (t, p): the latest time ahead at which the
  !> prescribed coordinates alone use AHEAD_FRACTION of the tolerance, measured with the
  !> current expansion's spreads (those of its neighbour differ little); t itself when there is
  !> no current expansion or the prescribed coordinates stay put. Doubling then bisection keeps
  !> the criterion met at the time returned, whatever the motion laws do in between.
  module procedure set_centre_time
    real(wp) :: lo, hi, tau
    integer :: i
    tc = t
    if (this%current == 0 .or. size(p) == 0) return
    ! With exact turns the joints' travel costs no range.
    if (this%item(this%current)%frames%on) return
    lo = 0.0_wp
    tau = 1.0e-9_wp * max(1.0_wp, abs(t))
    do i = 1, 80
      if (beyond(tau)) exit
      lo = tau
      tau = 2 * tau
    end do
    if (i > 80) return
    hi = tau
    do i = 1, 50
      tau = 0.5_wp * (lo + hi)
      if (beyond(tau)) then
        hi = tau
      else
        lo = tau
      end if
    end do
    tc = t + lo
  contains
    logical function beyond(dt)
      real(wp), intent(in) :: dt
      real(wp) :: pa(size(p)), pd(size(p)), pdd(size(p)), d(2)
      real(wp) :: dz(this%item(this%current)%m)
      call dyn%prescribed(t + dt, pa, pd, pdd)
      dz = 0.0_wp
      dz(1:size(p)) = pa - p
      d = this%item(this%current)%spread(dz)
      beyond = d(2)**2 > AHEAD_FRACTION * this%tol * d(1)**2
    end function beyond
  end procedure set_centre_time

  !> Where to centre a new expansion with the turns exact for the state (eta, eta_dot): ahead
  !> along eta_dot, where the step back to eta uses AHEAD_FRACTION of the tolerance, measured
  !> with the current expansion's spreads (d1 grows as the step, d2 as its square), but no
  !> more than tau_max [s] ahead (where nearly linear kinematics would put it out of reach);
  !> eta itself without a current expansion with exact turns or without modal motion.
  module procedure set_centre_modal
    real(wp) :: d(2), tau
    eta_c = eta
    if (this%current == 0) return
    if (.not. this%item(this%current)%frames%on) return
    associate (ex => this%item(this%current))
      d = ex%spread([spread(0.0_wp, 1, ex%nr), eta_dot])
    end associate
    if (d(2) <= 0 .or. d(1) <= 0) return
    tau = min(tau_max, sqrt(AHEAD_FRACTION * this%tol) * d(1) / d(2))
    eta_c = eta + tau * eta_dot
  end procedure set_centre_modal

  module procedure set_unchecked
    t = 0.0_wp
    do i = 1, size(this%last_use)
      if (.not. allocated(this%item)) exit
      if (i > size(this%item)) exit
      if (i == skip .or. .not. this%item(i)%valid) cycle
      if (this%item(i)%far_d2 <= this%item(i)%checked_d2) cycle
      t = this%item(i)%far_t
      z = this%item(i)%far_z
      z_rate = this%item(i)%far_rate
      return
    end do
    i = 0
  end procedure set_unchecked

  module procedure set_note_checked
    associate (ex => this%item(i))
      this%manifold_error = max(this%manifold_error, model%largest_translation(x - x_series))
      ex%checked_d2 = ex%far_d2
    end associate
  end procedure set_note_checked
  !> A new expansion about (t, eta), in an empty slot or the one used longest ago.
  module procedure set_expand
    integer :: slot
    if (.not. allocated(this%item)) allocate(this%item(kept_slots(dyn%model%n_x, &
      dyn%model%n_rh + size(eta))))
    slot = minloc(merge(this%last_use(1:size(this%item)), -1, this%item%valid), 1)
    this%item(slot)%use_frames = this%use_frames
    call this%item(slot)%build(dyn, basis, t, eta, err)
    if (.not. err%ok()) return
    this%current = slot
    this%clock = this%clock + 1
    this%last_use(slot) = this%clock
    this%n_expansions = this%n_expansions + 1
    if (this%item(slot)%frames%on) this%n_exact_turns = this%n_exact_turns + 1
  end procedure set_expand

  !> Drop every expansion (a new basis).
  module procedure set_forget
    if (allocated(this%item)) this%item%valid = .false.
    this%current = 0
    this%last_use = 0
  end procedure set_forget

end submodule reduction_expansion_set
