!> Motions of a scene: one motion_t per &motion, sums resolved (cycles refused), tables
!> checked, and laws without a finite bandwidth refused where &reduction auto_factor needs one.
submodule (model_build) model_build_motions
  use motion_law, only: motion_t, law_from_name, motion_sum, motion_table, table_problem, &
    LAW_CONSTANT, LAW_RAMP, LAW_HARMONIC, LAW_SUM, LAW_TABLE, BANDWIDTH_UNBOUNDED
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
