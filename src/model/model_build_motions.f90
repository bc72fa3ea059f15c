!> Motions of a scene: one motion_t per &motion, sums resolved (cycles refused), tables
!> checked, and laws without a finite bandwidth refused where &reduction auto_factor needs one.
submodule (model_build) model_build_motions
  use motion_law, only: motion_t, law_from_name, motion_sum, motion_table, table_problem, &
    LAW_CONSTANT, LAW_RAMP, LAW_HARMONIC, LAW_SUM, LAW_TABLE, BANDWIDTH_UNBOUNDED
  use model_scene, only: motion_rec_t
  implicit none

contains

  module procedure add_motions
    type(motion_t) :: mo
    integer :: i, idx
    do i = 1, size(scene%motions)
      if (motion_index(scene, scene%motions(i)%label) /= i) then
        call err%set(ERR_INPUT, 'group &motion: label ''' // scene%motions(i)%label // &
          ''' is defined twice')
        return
      end if
    end do
    do i = 1, size(scene%motions)
      call make_motion(scene, i, [integer ::], mo, err)
      if (.not. err%ok()) return
      ! The fraction does not matter here: a velocity step has no finite bandwidth at all.
      if (scene%reduction%active .and. scene%reduction%auto_factor > 0) then
        if (mo%bandwidth_hz(0.5_wp) == BANDWIDTH_UNBOUNDED) then
          call err%set(ERR_INPUT, 'group &motion ''' // mo%label // ''': its velocity steps ' &
            // '(law ''ramp''), which has no finite bandwidth: &reduction auto_factor cannot ' &
            // 'use it; give n_modes or cutoff_hz')
          return
        end if
      end if
      idx = model%add_motion(mo)
    end do
  end procedure add_motions

  !> The motion of scene%motions(i); `chain` holds the sums that lead to it, to refuse cycles.
  recursive subroutine make_motion(scene, i, chain, mo, err)
    type(scene_t), intent(in) :: scene
    integer, intent(in) :: i, chain(:)
    type(motion_t), intent(out) :: mo
    type(error_t), intent(inout) :: err
    type(motion_t), allocatable :: terms(:)
    character(len=:), allocatable :: msg
    integer :: k, j
    associate (r => scene%motions(i), where => 'group &motion ''' // scene%motions(i)%label // '''')
      ! Before the table's spline, which would overflow on such points.
      msg = size_problem(r)
      if (len(msg) > 0) then
        call err%set(ERR_INPUT, where // ': ' // msg)
        return
      end if
      select case (law_from_name(r%law))
      case (-1)
        call err%set(ERR_INPUT, where // ': variable ''law'': unknown law ''' // r%law // &
          ''' (use constant, cubic, quintic, cycloidal, ramp, harmonic, spin_up, sum or table)')
      case (LAW_SUM)
        if (.not. allocated(r%terms)) allocate(terms(0))
        if (allocated(r%terms)) allocate(terms(size(r%terms)))
        if (size(terms) == 0) call err%set(ERR_INPUT, where // ': variable ''terms'' is empty')
        do k = 1, size(terms)
          j = motion_index(scene, r%terms(k)%s)
          msg = where // ': variable ''terms'': motion ''' // r%terms(k)%s // ''''
          if (j == 0) then
            call err%set(ERR_INPUT, msg // ' is not defined (no &motion with that label)')
          else if (j == i .or. any(chain == j)) then
            call err%set(ERR_INPUT, msg // ' is this sum or contains it: a sum may not ' // &
              'contain itself (' // cycle_text(scene, [chain, i, j]) // ')')
          else
            call make_motion(scene, j, [chain, i], terms(k), err)
          end if
          if (.not. err%ok()) return
        end do
        if (err%ok()) mo = motion_sum(r%label, terms)
      case (LAW_TABLE)
        msg = 'a table needs times and values'
        if (allocated(r%times) .and. allocated(r%values)) msg = table_problem(r%times, r%values)
        if (len(msg) > 0) then
          call err%set(ERR_INPUT, where // ': variable ''times'': ' // msg)
        else
          mo = motion_table(r%label, r%times, r%values)
        end if
      case default
        mo = motion_t(law=law_from_name(r%law), start=r%start, end=r%end, &
          t0=r%t0, duration=r%duration, rate=r%rate, amplitude=r%amplitude, &
          frequency=r%frequency, phase=r%phase)
        if (all(mo%law /= [LAW_CONSTANT, LAW_RAMP, LAW_HARMONIC])) &
          call require_positive(r%duration, where, 'duration', err)
        if (mo%law == LAW_HARMONIC) call require_positive(r%frequency, where, 'frequency', err)
      end select
    end associate
    ! Outside the associate: gfortran 12 loses a deferred-length component given there.
    mo%label = scene%motions(i)%label
  end subroutine make_motion

  !> Why the values, times, rates or accelerations of a law go beyond 1e100 in magnitude (''
  !> if they do not). The kinematics and the integrators multiply them (squares of rates, a time step
  !> times an acceleration): far beyond any machine's motion, they overflow, so that a
  !> `duration = 1e-300` or `end = 1e300` ended in a floating-point trap instead of a message.
  !> Judged in decimal logarithms, which cannot overflow themselves.
  function size_problem(r) result(msg)
    type(motion_rec_t), intent(in) :: r
    character(len=:), allocatable :: msg
    real(wp), parameter :: LG_LIMIT = 100.0_wp, MIN_DURATION = 1.0e-100_wp
    real(wp) :: lg_span, lg_dt
    integer :: k
    msg = ''
    select case (law_from_name(r%law))
    case (LAW_SUM)
      return                                   ! its terms are checked as motions
    case (LAW_TABLE)
      if (.not. (allocated(r%times) .and. allocated(r%values))) return
      if (size(r%times) /= size(r%values)) return    ! table_problem says so
      ! One at a time: too_big sets msg, and an .or. need not evaluate both.
      if (too_big(r%times, 'times')) return
      if (too_big(r%values, 'values')) return
      do k = 2, size(r%times)
        lg_span = lg(r%values(k) - r%values(k - 1))
        lg_dt = lg(r%times(k) - r%times(k - 1))
        if (lg_span - 2 * lg_dt > LG_LIMIT) then
          msg = 'variable ''times'': points ' // int_str(k - 1) // ' and ' // int_str(k) // &
            ' ask for accelerations of about ' // approx_str(10.0_wp**(min(lg_span - 2 * lg_dt, &
            300.0_wp))) // ' per s^2 (the limit is 1e100): spread the times or smooth the values'
          return
        end if
      end do
    case (LAW_HARMONIC)
      if (too_big([r%start, r%t0, r%amplitude, r%frequency, r%phase], 'start', 't0', &
        'amplitude', 'frequency', 'phase')) return
      if (lg(r%amplitude) + 2 * lg(2 * acos(-1.0_wp) * r%frequency) > LG_LIMIT) msg = &
        'variable ''frequency'': amplitude (2 pi frequency)^2 is beyond 1e100 per s^2'
    case (LAW_RAMP)
      if (too_big([r%start, r%t0, r%rate], 'start', 't0', 'rate')) return
    case (LAW_CONSTANT)
      if (too_big([r%start, r%t0, r%end], 'start', 't0', 'end')) return
    case default                               ! rest-to-rest and spin_up: a duration
      if (too_big([r%start, r%t0, r%end, r%duration, r%rate], 'start', 't0', 'end', &
        'duration', 'rate')) return
      if (.not. r%duration > 0) return               ! require_positive says so
      if (r%duration < MIN_DURATION) then
        msg = 'variable ''duration'': ' // approx_str(r%duration) // ' s is too short ' // &
          '(at least 1e-100 s)'
        return
      end if
      lg_span = max(lg(r%end - r%start), lg(r%rate * r%duration))
      if (lg_span - 2 * lg(r%duration) > LG_LIMIT) msg = 'variable ''duration'': the ' // &
        'motion needs accelerations of about ' // approx_str(10.0_wp**min(lg_span - 2 * &
        lg(r%duration), 300.0_wp)) // ' per s^2 (the limit is 1e100): give a longer duration'
    end select
  contains
    !> log10 |x|, and a very small number for zero.
    pure real(wp) function lg(x)
      real(wp), intent(in) :: x
      lg = log10(max(abs(x), tiny(1.0_wp)))
    end function lg

    !> Sets msg when a value is beyond 1e100; n1 .. n5 name the values in order (n1 alone: a
    !> whole list).
    logical function too_big(x, n1, n2, n3, n4, n5)
      real(wp), intent(in) :: x(:)
      character(len=*), intent(in) :: n1
      character(len=*), intent(in), optional :: n2, n3, n4, n5
      integer :: i
      character(len=:), allocatable :: name
      too_big = .false.
      do i = 1, size(x)
        if (lg(x(i)) <= LG_LIMIT) cycle
        name = n1
        if (i == 2 .and. present(n2)) name = n2
        if (i == 3 .and. present(n3)) name = n3
        if (i == 4 .and. present(n4)) name = n4
        if (i == 5 .and. present(n5)) name = n5
        msg = 'variable ''' // name // ''': ' // approx_str(x(i)) // ' is beyond 1e100 in ' // &
          'magnitude (a motion''s numbers, rates and accelerations must stay within it)'
        too_big = .true.
        return
      end do
    end function too_big
  end function size_problem

  !> 'a' -> 'b' -> 'a': the labels of the motions `chain` from where its cycle starts.
  function cycle_text(scene, chain) result(s)
    type(scene_t), intent(in) :: scene
    integer, intent(in) :: chain(:)
    character(len=:), allocatable :: s
    integer :: k
    s = ''
    do k = findloc(chain, chain(size(chain)), dim=1), size(chain)
      if (len(s) > 0) s = s // ' -> '
      s = s // '''' // scene%motions(chain(k))%label // ''''
    end do
  end function cycle_text

end submodule model_build_motions
