!> Reads &motion groups: the law, its parameters and, for tables, the values inline or from a
!> CSV file (docs/input.md, &motion).
module io_scene_motion
  use core_error, only: error_t, ERR_INPUT
  use io_namelist, only: nml_group_t, string_t
  use io_fields, only: rd_real, rd_string, rd_choice, rd_label, only_with, rd_reals, &
    check_entries, check_unique
  use model_scene, only: motion_rec_t
  use motion_law, only: table_problem
  use io_table, only: read_table_csv, relative_to
  implicit none
  private
  public :: read_motion

contains

  subroutine read_motion(g, r, err)
    type(nml_group_t), intent(inout) :: g
    type(motion_rec_t), intent(out) :: r
    type(error_t), intent(inout) :: err
    character(len=*), parameter :: REST = 'with law = ''constant'', ''cubic'', ''quintic'' or ' &
      // '''cycloidal'''
    type(string_t), allocatable :: terms(:)
    type(error_t) :: e
    logical :: rest_to_rest
    integer :: i
    call rd_label(g, r%label, err)
    call rd_choice(g, 'law', r%law, err)
    if (.not. err%ok()) return
    ! Each law reads only its own variables: another law's would be ignored without a word.
    rest_to_rest = any(r%law == [character(len=9) :: 'constant', 'cubic', 'quintic', 'cycloidal'])
    call only_with(g, ['end'], rest_to_rest, REST, err)
    call only_with(g, ['duration'], rest_to_rest .or. r%law == 'spin_up', REST // &
      ' or ''spin_up''', err)
    call only_with(g, ['start', 't0   '], r%law /= 'sum' .and. r%law /= 'table', &
      'with laws other than ''sum'' and ''table''', err)
    call only_with(g, ['rate'], r%law == 'ramp' .or. r%law == 'spin_up', &
      'with law = ''ramp'' or ''spin_up''', err)
    call only_with(g, ['amplitude', 'frequency', 'phase    '], r%law == 'harmonic', &
      'with law = ''harmonic''', err)
    call only_with(g, ['terms'], r%law == 'sum', 'with law = ''sum''', err)
    call only_with(g, ['times ', 'values', 'file  '], r%law == 'table', 'with law = ''table''', err)
    call rd_real(g, 'start', r%start, err)
    call rd_real(g, 't0', r%t0, err)
    select case (r%law)
    case ('constant')
      call rd_real(g, 'end', r%end, err, default=r%start)
      ! A constant law ignores its duration; one given must still make sense.
      if (g%has('duration')) call rd_real(g, 'duration', r%duration, err)
    case ('ramp')
      call rd_real(g, 'rate', r%rate, err)
    case ('spin_up')
      call rd_real(g, 'rate', r%rate, err)
      call rd_real(g, 'duration', r%duration, err)
    case ('harmonic')
      call rd_real(g, 'amplitude', r%amplitude, err)
      call rd_real(g, 'frequency', r%frequency, err)
      call rd_real(g, 'phase', r%phase, err)
    case ('sum')
      if (.not. err%ok()) return
      call g%get_string_array('terms', terms, e)
      if (e%ok()) call check_unique(g, 'terms', terms, e)
      if (.not. e%ok()) then
        err = e
      else if (size(terms) == 0) then
        call err%set(ERR_INPUT, g%where() // ': variable ''terms'' needs at least one label')
      else
        allocate(r%terms(size(terms)))
        do i = 1, size(terms)
          r%terms(i)%s = terms(i)%s
        end do
      end if
    case ('table')
      call read_motion_table(g, r, err)
    case default
      call rd_real(g, 'end', r%end, err)
      call rd_real(g, 'duration', r%duration, err)
    end select
  end subroutine read_motion

  !> A table's points, inline (`times`, `values`) or from `file` (relative to the scene file).
  subroutine read_motion_table(g, r, err)
    type(nml_group_t), intent(inout) :: g
    type(motion_rec_t), intent(inout) :: r
    type(error_t), intent(inout) :: err
    character(len=:), allocatable :: path, var, msg
    type(error_t) :: e
    if (.not. err%ok()) return
    if (g%has('file')) then
      var = 'file'
      if (g%has('times') .or. g%has('values')) then
        call err%set(ERR_INPUT, g%where() // ': give either ''file'' or ''times'' and ' // &
          '''values'', not both')
        return
      end if
      call rd_string(g, 'file', path, err)
      if (.not. err%ok()) return
      call read_table_csv(relative_to(g%path, path), r%times, r%values, e)
      if (.not. e%ok()) e%message = g%where() // ': variable ''file'': ' // e%message
      if (e%ok()) then
        call check_entries(g, 'times', r%times, e, source='of file ''' // path // &
          ''' (column 1)')
        call check_entries(g, 'values', r%values, e, source='of file ''' // path // &
          ''' (column 2)')
      end if
    else
      var = 'times'', ''values'
      call rd_reals(g, 'times', r%times, e)
      call rd_reals(g, 'values', r%values, e)
    end if
    if (.not. e%ok()) then
      err = e
      return
    end if
    msg = table_problem(r%times, r%values)
    if (var /= 'file' .and. size(r%times) == size(r%values)) var = 'times'
    if (len(msg) > 0) call err%set(ERR_INPUT, g%where() // ': variable ''' // var // ''': ' // msg)
  end subroutine read_motion_table
end module io_scene_motion
