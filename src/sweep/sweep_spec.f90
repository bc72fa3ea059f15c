!> A parameter sweep file (docs/sweep.md): the base scene, the swept parameters and every
!> case's values, and the scene text of one case.
!>
!> All cases are generated up front from the file alone, with a random generator of our own
!> (splitmix64 in integer bit operations), so every MPI rank and every machine that reads the
!> same file gets the same cases without any communication. A case is applied to the base
!> scene as text (`set_raw`), so the scene reader checks every case like a hand-written file.
module sweep_spec
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_INPUT
  use core_strings, only: int_str, real_str, lower_case
  use io_namelist, only: nml_file_t, nml_group_t, string_t
  implicit none
  private
  public :: sweep_spec_t, apply_case

  !> One &parameter: its target in the scene and where its values come from.
  type :: param_t
    character(len=:), allocatable :: name        ! as given
    character(len=:), allocatable :: origin      ! "sweep.nml:7: group &parameter #2 'name'"
    character(len=:), allocatable :: group, key, var   ! group and var lower case; key '' if none
    !> The entry of a list variable, 'scene.gravity(2)'; 0 for a variable that is one number.
    integer :: entry = 0
    logical :: is_int = .false.
    integer :: spec = 0                          ! the variable's entry in the scene schema
    real(wp), allocatable :: list(:)             ! product/zip
    real(wp) :: lo = 0, hi = 0                   ! random/lhs (integer variables: integral)
    logical :: log = .false.
    !> Further scene variables that take the same values (`name` given as a list), e.g. the
    !> motion times of two joints that move together.
    type(param_t), allocatable :: tied(:)
  end type param_t

  type :: sweep_spec_t
    character(len=:), allocatable :: path          ! sweep file path as given
    character(len=:), allocatable :: text          ! its text
    character(len=:), allocatable :: base_path     ! base scene, relative to the sweep file's folder
    character(len=:), allocatable :: mode          ! product|zip|random|lhs
    character(len=:), allocatable :: node, title
    integer :: n_samples = 0, seed = 1
    !> Each case's own result file too, in the folder <result file without extension>_cases
    logical :: case_files = .false.
    type(string_t), allocatable :: names(:)        ! parameter names as given
    real(wp), allocatable :: values(:, :)          ! (n_cases, n_parameters)
    type(param_t), allocatable, private :: params(:)
  contains
    procedure :: load => spec_load
    procedure :: parse => spec_parse
    procedure :: n_cases => spec_n_cases
    procedure :: n_parameters => spec_n_parameters
  end type sweep_spec_t

  !> A value within this relative distance of an integer counts as that integer: start/stop/n
  !> spacing of integers carries round-off.
  real(wp), parameter :: INT_TOL = 1.0e-9_wp
  !> Cases of one sweep: every case gets rows in the result file (a message of hundreds of
  !> bytes, its metrics) and in memory, created at full size before the first case runs
  !> (docs/sweep.md).
  integer, parameter, public :: MAX_CASES = 10000000

  interface
    !> The variable that names a group of a repeating kind (in sweep_spec_names; declared here
    !> because sweep_spec_cases uses it too, and a submodule sees no other submodule's own).
    pure module function key_var(group) result(v)
      character(len=*), intent(in) :: group
      character(len=:), allocatable :: v
    end function key_var
    !> p%name ('group.variable', 'group.key.variable', either with '(k)' for one entry of a
    !> list) into p's group, key, var and entry, checked against the scene schema.
    module subroutine split_name(p, err)
      type(param_t), intent(inout) :: p
      type(error_t), intent(inout) :: err
    end subroutine split_name
    !> The variables the last of `params` sets (its name and tied names) differ from each
    !> other and from those the earlier ones set.
    module subroutine check_targets(params, err)
      type(param_t), intent(in) :: params(:)
      type(error_t), intent(inout) :: err
    end subroutine check_targets
    !> Every case's values within the schema's ranges of the variables they set.
    module subroutine check_ranges(this, err)
      type(sweep_spec_t), intent(in) :: this
      type(error_t), intent(inout) :: err
    end subroutine check_ranges
    pure module logical function same_target(a, b)
      type(param_t), intent(in) :: a, b
    end function same_target
    module subroutine gen_product(this, err)
      type(sweep_spec_t), intent(inout) :: this
      type(error_t), intent(inout) :: err
    end subroutine gen_product
    module subroutine gen_zip(this, err)
      type(sweep_spec_t), intent(inout) :: this
      type(error_t), intent(inout) :: err
    end subroutine gen_zip
    !> Mode 'random' or 'lhs' (docs/sweep.md).
    module subroutine gen_sampled(this, err)
      type(sweep_spec_t), intent(inout) :: this
      type(error_t), intent(inout) :: err
    end subroutine gen_sampled
    !> scene_file = base with case icase's values written into it. Errors name the sweep
    !> file, the &parameter and the base scene.
    module subroutine apply_case(spec, base, icase, scene_file, err)
      type(sweep_spec_t), intent(in) :: spec
      type(nml_file_t), intent(in) :: base
      integer, intent(in) :: icase
      type(nml_file_t), intent(out) :: scene_file
      type(error_t), intent(out) :: err
    end subroutine apply_case
  end interface


contains

  ! ---------------------------------------------------------------- reading

  subroutine spec_load(this, path, err)
    class(sweep_spec_t), intent(inout) :: this
    character(len=*), intent(in) :: path
    type(error_t), intent(out) :: err
    type(nml_file_t) :: f
    call f%load(path, err)   ! only for its error messages about the file itself
    if (err%ok()) call this%parse(f%text, path, err)
  end subroutine spec_load

  subroutine spec_parse(this, text, path, err)
    class(sweep_spec_t), intent(inout) :: this
    character(len=*), intent(in) :: text, path
    type(error_t), intent(out) :: err
    type(nml_file_t) :: f
    integer :: j, n_par

    call reset(this)
    this%path = path
    this%text = text
    call f%parse(text, path, err)
    if (.not. err%ok()) return
    call f%check_known_groups([character(len=9) :: 'sweep', 'parameter'], err)
    if (.not. err%ok()) return

    if (f%count('sweep') == 0) then
      call err%set(ERR_INPUT, path // ': no &sweep group (it names the base scene)')
      return
    else if (f%count('sweep') > 1) then
      call err%set(ERR_INPUT, path // ': group &sweep may appear only once')
      return
    end if
    call read_sweep_group(this, f%groups(f%group_index('sweep', 1)), err)
    if (.not. err%ok()) return

    n_par = f%count('parameter')
    if (n_par == 0) then
      call err%set(ERR_INPUT, path // ': no &parameter group (one per swept variable)')
      return
    end if
    allocate(this%params(n_par), this%names(n_par))
    do j = 1, n_par
      call read_parameter(f%groups(f%group_index('parameter', j)), this%mode, this%params(j), err)
      if (.not. err%ok()) return
      this%names(j)%s = this%params(j)%name
      call check_targets(this%params(1:j), err)
      if (.not. err%ok()) return
    end do

    select case (this%mode)
    case ('product')
      call gen_product(this, err)
    case ('zip')
      call gen_zip(this, err)
    case default
      call gen_sampled(this, err)
    end select
    ! Here rather than when a case runs: a value the scene reader refuses would only fail its
    ! cases one by one, after the others had run for hours.
    if (err%ok()) call check_ranges(this, err)
  end subroutine spec_parse

  subroutine reset(this)
    type(sweep_spec_t), intent(inout) :: this
    if (allocated(this%base_path)) deallocate(this%base_path)
    if (allocated(this%names)) deallocate(this%names)
    if (allocated(this%values)) deallocate(this%values)
    if (allocated(this%params)) deallocate(this%params)
    this%mode = 'product'
    this%node = 'tip'
    this%title = ''
    this%n_samples = 0
    this%seed = 1
    this%case_files = .false.
  end subroutine reset

  subroutine read_sweep_group(this, g, err)
    type(sweep_spec_t), intent(inout) :: this
    type(nml_group_t), intent(inout) :: g
    type(error_t), intent(inout) :: err
    character(len=:), allocatable :: base
    type(error_t) :: e
    integer :: k

    call g%get_string('base', base, e)
    if (e%ok()) call g%get_string('mode', this%mode, e, default='product')
    if (e%ok()) call g%get_int('seed', this%seed, e, default=1)
    if (e%ok()) call g%get_string('node', this%node, e, default='tip')
    if (e%ok()) call g%get_string('title', this%title, e, default='')
    if (e%ok()) call g%get_logical('case_files', this%case_files, e, default=.false.)
    if (.not. e%ok()) then
      err = e
      return
    end if
    this%mode = lower_case(this%mode)

    if (len_trim(base) == 0) then
      call err%set(ERR_INPUT, g%where() // ": variable 'base' is empty (the base scene file)")
      return
    end if
    k = index(this%path, '/', back=.true.)
    if (base(1:1) == '/' .or. k == 0) then
      this%base_path = base
    else
      this%base_path = this%path(1:k) // base
    end if

    select case (this%mode)
    case ('product', 'zip')
      ! The case count follows from the lists; a count given anyway would be ignored.
      if (g%has('n_samples') .or. g%has('seed')) then
        call err%set(ERR_INPUT, g%where() // ": variable '" // trim(merge('n_samples', &
          'seed     ', g%has('n_samples'))) // "' is for mode 'random' or 'lhs'; mode '" // &
          this%mode // "' takes its cases from the value lists")
        return
      end if
    case ('random', 'lhs')
      if (.not. g%has('n_samples')) then
        call err%set(ERR_INPUT, g%where() // ": mode '" // this%mode // &
          "' needs 'n_samples' (the number of cases)")
        return
      end if
      call g%get_int('n_samples', this%n_samples, e)
      if (.not. e%ok()) then
        err = e
        return
      end if
      if (this%n_samples == 0) then
        call err%set(ERR_INPUT, g%where() // ": variable 'n_samples': zero samples " // &
          '(at least 1 is needed)')
        return
      else if (this%n_samples < 0) then
        call err%set(ERR_INPUT, g%where() // ": variable 'n_samples' must be at least 1, got " &
          // int_str(this%n_samples))
        return
      else if (this%n_samples > MAX_CASES) then
        call err%set(ERR_INPUT, g%where() // ": variable 'n_samples' must be at most " // &
          int_str(MAX_CASES) // ', got ' // int_str(this%n_samples))
        return
      end if
    case default
      call err%set(ERR_INPUT, g%where() // ": variable 'mode': unknown mode '" // this%mode // &
        "' (use product, zip, random or lhs)")
      return
    end select
    call g%check_all_used(err)
  end subroutine read_sweep_group

  subroutine read_parameter(g, mode, p, err)
    type(nml_group_t), intent(inout) :: g
    character(len=*), intent(in) :: mode
    type(param_t), intent(out) :: p
    type(error_t), intent(inout) :: err
    character(len=:), allocatable :: tag
    integer :: k
    call read_parameter_body(g, mode, p, err)
    if (err%ok() .or. .not. allocated(p%origin)) return
    ! The namelist getters name the group, not the parameter: add its name there.
    tag = 'group &' // g%name // ' #' // int_str(g%occurrence)
    if (index(err%message, tag // " '" // p%name // "'") > 0) return
    k = index(err%message, tag)
    if (k > 0) err%message = err%message(:k + len(tag) - 1) // " '" // p%name // "'" // &
      err%message(k + len(tag):)
  end subroutine read_parameter

  subroutine read_parameter_body(g, mode, p, err)
    type(nml_group_t), intent(inout) :: g
    character(len=*), intent(in) :: mode
    type(param_t), intent(inout) :: p
    type(error_t), intent(inout) :: err
    type(error_t) :: e
    logical :: has_values, has_range, has_bounds

    type(string_t), allocatable :: names(:)
    integer :: k

    call g%get_string_array('name', names, e)
    if (.not. e%ok()) then
      err = e
      return
    end if
    p%name = names(1)%s
    p%origin = g%where() // " '" // p%name // "'"
    call split_name(p, err)
    if (.not. err%ok()) return
    allocate(p%tied(size(names) - 1))
    do k = 2, size(names)
      p%tied(k - 1)%name = names(k)%s
      p%tied(k - 1)%origin = g%where() // " '" // names(k)%s // "'"
      call split_name(p%tied(k - 1), err)
      if (.not. err%ok()) return
      if (p%tied(k - 1)%is_int .neqv. p%is_int) then
        call err%set(ERR_INPUT, p%tied(k - 1)%origin // ': the names of one &parameter ' // &
          'take the same values, so they must all be integer or all real variables')
        return
      end if
    end do
    call g%get_logical('log', p%log, e, default=.false.)
    if (.not. e%ok()) then
      err = e
      return
    end if

    has_values = g%has('values')
    has_range = g%has('start') .or. g%has('stop') .or. g%has('n')
    has_bounds = g%has('min') .or. g%has('max')
    if (mode == 'product' .or. mode == 'zip') then
      if (has_bounds) then
        call err%set(ERR_INPUT, p%origin // ": 'min' and 'max' are for mode 'random' or " // &
          "'lhs'; mode '" // mode // "' takes 'values' or 'start', 'stop', 'n'")
      else if (has_values .and. has_range) then
        call err%set(ERR_INPUT, p%origin // ": give either 'values' or 'start', 'stop', 'n', " &
          // 'not both')
      else if (has_values) then
        if (p%log) then
          call err%set(ERR_INPUT, p%origin // ": 'log' spaces 'start', 'stop', 'n'; it does " &
            // "not apply to 'values'")
        else
          call g%get_real_array('values', p%list, e)
          if (.not. e%ok()) err = e
        end if
      else if (has_range) then
        call read_range(g, p, err)
      else
        call err%set(ERR_INPUT, p%origin // ": no values: give 'values' or 'start', 'stop', 'n'")
      end if
      if (err%ok() .and. p%is_int) call check_integral(p, err)
    else
      if (has_values .or. has_range) then
        call err%set(ERR_INPUT, p%origin // ": 'values' and 'start', 'stop', 'n' are for " // &
          "mode 'product' or 'zip'; mode '" // mode // "' samples between 'min' and 'max'")
      else
        call read_bounds(g, p, err)
      end if
    end if
    if (err%ok()) call g%check_all_used(err)
  end subroutine read_parameter_body

  !> n values from start to stop, equally or geometrically spaced; the ends exactly as given.
  subroutine read_range(g, p, err)
    type(nml_group_t), intent(inout) :: g
    type(param_t), intent(inout) :: p
    type(error_t), intent(inout) :: err
    type(error_t) :: e
    character(len=:), allocatable :: missing
    real(wp) :: start, stop
    integer :: n, i

    missing = ''
    if (.not. g%has('start')) missing = missing // " 'start'"
    if (.not. g%has('stop')) missing = missing // " 'stop'"
    if (.not. g%has('n')) missing = missing // " 'n'"
    if (len(missing) > 0) then
      call err%set(ERR_INPUT, p%origin // ": 'start', 'stop' and 'n' go together; missing" // &
        missing)
      return
    end if
    call g%get_real('start', start, e)
    if (e%ok()) call g%get_real('stop', stop, e)
    if (e%ok()) call g%get_int('n', n, e)
    if (.not. e%ok()) then
      err = e
      return
    end if
    if (n < 1) then
      call err%set(ERR_INPUT, p%origin // ': empty range: n = ' // int_str(n) // &
        ' (n must be at least 1)')
      return
    end if
    if (n > MAX_CASES) then
      call err%set(ERR_INPUT, p%origin // ": variable 'n': " // int_str(n) // &
        ' values, more than a sweep can have cases (' // int_str(MAX_CASES) // ')')
      return
    end if
    if (p%log .and. (start <= 0 .or. stop <= 0)) then
      call err%set(ERR_INPUT, p%origin // ": 'log' needs start > 0 and stop > 0, got " // &
        real_str(start) // ' and ' // real_str(stop))
      return
    end if
    allocate(p%list(n))
    p%list(1) = start
    do i = 2, n - 1
      if (p%log) then
        p%list(i) = exp(log(start) + (log(stop) - log(start)) * real(i - 1, wp) / (n - 1))
      else
        p%list(i) = start + (stop - start) * real(i - 1, wp) / (n - 1)
      end if
    end do
    if (n > 1) p%list(n) = stop
  end subroutine read_range

  subroutine read_bounds(g, p, err)
    type(nml_group_t), intent(inout) :: g
    type(param_t), intent(inout) :: p
    type(error_t), intent(inout) :: err
    type(error_t) :: e
    real(wp) :: lo, hi

    if (.not. (g%has('min') .and. g%has('max'))) then
      call err%set(ERR_INPUT, p%origin // ": random and lhs sampling need 'min' and 'max'")
      return
    end if
    call g%get_real('min', lo, e)
    if (e%ok()) call g%get_real('max', hi, e)
    if (.not. e%ok()) then
      err = e
      return
    end if
    if (.not. lo < hi) then
      call err%set(ERR_INPUT, p%origin // ': min < max is needed, got min = ' // real_str(lo) &
        // ', max = ' // real_str(hi))
    else if (p%log .and. lo <= 0) then
      call err%set(ERR_INPUT, p%origin // ": 'log' needs min > 0, got " // real_str(lo))
    else if (p%is_int) then
      if (lo < -real(huge(0), wp) .or. hi > real(huge(0), wp)) then
        call err%set(ERR_INPUT, p%origin // ': min and max are beyond the integer range ' // &
          '(the variable is an integer)')
        return
      end if
      ! Sampling covers [lo - 1/2, hi + 1/2] of the whole numbers inside, so that rounding
      ! gives every one of them the same chance.
      p%lo = real(ceiling(lo), wp)
      p%hi = real(floor(hi), wp)
      if (p%lo > p%hi) call err%set(ERR_INPUT, p%origin // ': no integer between min = ' // &
        real_str(lo) // ' and max = ' // real_str(hi) // ' (the variable is an integer)')
    else
      p%lo = lo
      p%hi = hi
    end if
  end subroutine read_bounds

  !> Values of an integer variable must be whole numbers; snap away spacing round-off.
  subroutine check_integral(p, err)
    type(param_t), intent(inout) :: p
    type(error_t), intent(inout) :: err
    integer :: i
    do i = 1, size(p%list)
      if (abs(p%list(i)) > real(huge(0), wp)) then
        call err%set(ERR_INPUT, p%origin // ': value ' // int_str(i) // ' (' // &
          real_str(p%list(i)) // ') is beyond the integer range (the variable is an integer)')
        return
      end if
      if (abs(p%list(i) - anint(p%list(i))) > INT_TOL * max(1.0_wp, abs(p%list(i)))) then
        call err%set(ERR_INPUT, p%origin // ': value ' // int_str(i) // ' (' // &
          real_str(p%list(i)) // ") is not a whole number, and '" // p%var // "' of &" // &
          p%group // ' is an integer')
        return
      end if
      p%list(i) = anint(p%list(i))
    end do
  end subroutine check_integral

  ! ---------------------------------------------------------------- sizes

  pure integer function spec_n_cases(this) result(n)
    class(sweep_spec_t), intent(in) :: this
    n = 0
    if (allocated(this%values)) n = size(this%values, 1)
  end function spec_n_cases

  pure integer function spec_n_parameters(this) result(n)
    class(sweep_spec_t), intent(in) :: this
    n = 0
    if (allocated(this%names)) n = size(this%names)
  end function spec_n_parameters

end module sweep_spec
