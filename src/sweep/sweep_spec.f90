!> A parameter sweep file (docs/sweep.md): the base scene, the swept parameters and every
!> case's values, and the scene text of one case.
!>
!> All cases are generated up front from the file alone, with a random generator of our own
!> (splitmix64 in integer bit operations), so every MPI rank and every machine that reads the
!> same file gets the same cases without any communication. A case is applied to the base
!> scene as text (`set_raw`), so the scene reader checks every case like a hand-written file.
module sweep_spec
  use core_kinds, only: wp, i8
  use core_error, only: error_t, ERR_INPUT, ERR_INTERNAL
  use core_strings, only: int_str, real_str, lower_case
  use io_namelist, only: nml_file_t, nml_group_t, string_t
  use io_schema, only: SCENE_GROUPS, SINGLE_GROUPS, SCHEMA, find_spec, kind_name, VK_REAL, &
    VK_INT
  implicit none
  private
  public :: sweep_spec_t, apply_case

  !> One &parameter: its target in the scene and where its values come from.
  type :: param_t
    character(len=:), allocatable :: name        ! as given
    character(len=:), allocatable :: origin      ! "sweep.nml:7: group &parameter #2 'name'"
    character(len=:), allocatable :: group, key, var   ! group and var lower case; key '' if none
    logical :: is_int = .false.
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

  ! splitmix64 (Steele, Lea and Flood 2014) constants, as the bit patterns of int64.
  integer(i8), parameter :: SM_GAMMA = int(z'9E3779B97F4A7C15', i8)
  integer(i8), parameter :: SM_MUL1 = int(z'BF58476D1CE4E5B9', i8)
  integer(i8), parameter :: SM_MUL2 = int(z'94D049BB133111EB', i8)
  integer(i8), parameter :: MASK16 = 65535_i8, MASK32 = 4294967295_i8

  type :: rng_t
    integer(i8) :: state = 0
  end type rng_t

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
    integer :: i, j, n_par

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
      ! The same variable twice would let the second silently overwrite the first.
      do i = 1, j - 1
        if (same_target(this%params(i), this%params(j))) then
          call err%set(ERR_INPUT, this%params(j)%origin // ': the same scene variable as ' // &
            '&parameter #' // int_str(i) // " '" // this%params(i)%name // "'")
          return
        end if
      end do
    end do

    select case (this%mode)
    case ('product')
      call gen_product(this, err)
    case ('zip')
      call gen_zip(this, err)
    case default
      call gen_sampled(this, err)
    end select
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

  !> 'group.variable' or 'group.key.variable' into its parts; a key may itself contain dots
  !> (everything between the first and the last dot).
  subroutine split_name(p, err)
    type(param_t), intent(inout) :: p
    type(error_t), intent(inout) :: err
    character(len=:), allocatable :: name
    integer :: d1, d2, k

    name = trim(adjustl(p%name))
    d1 = index(name, '.')
    d2 = index(name, '.', back=.true.)
    if (d1 == 0) then
      call err%set(ERR_INPUT, p%origin // ": a name has the form 'group.variable' or " // &
        "'group.key.variable' (e.g. 'dynamic.rtol', 'link.link1.E')")
      return
    end if
    p%group = lower_case(name(1:d1 - 1))
    p%var = lower_case(name(d2 + 1:))
    p%key = ''
    if (d2 > d1) p%key = name(d1 + 1:d2 - 1)

    if (all(SCENE_GROUPS /= p%group)) then
      call err%set(ERR_INPUT, p%origin // ": unknown group '" // p%group // "' (scene groups: " &
        // join(SCENE_GROUPS) // ')')
      return
    end if
    if (any(SINGLE_GROUPS == p%group)) then
      if (d2 > d1) then
        call err%set(ERR_INPUT, p%origin // ': group &' // p%group // ' appears at most ' // &
          "once and takes no key: write '" // name(1:d1 - 1) // '.' // name(d2 + 1:) // "'")
        return
      end if
    else if (d2 == d1) then
      call err%set(ERR_INPUT, p%origin // ': group &' // p%group // ' may repeat: name ' // &
        "one by its " // key_var(p%group) // ", '" // name(1:d1 - 1) // '.<' // &
        key_var(p%group) // '>.' // name(d2 + 1:) // "'")
      return
    else if (len(p%key) == 0) then
      call err%set(ERR_INPUT, p%origin // ': the key (the group''s ' // key_var(p%group) // &
        ') is empty')
      return
    end if
    if (.not. is_name(p%var)) then
      call err%set(ERR_INPUT, p%origin // ": '" // p%var // "' is not a variable name")
      return
    end if

    k = find_spec(p%group, p%var)
    if (k == 0) then
      call err%set(ERR_INPUT, p%origin // ": &" // p%group // " has no variable '" // p%var // &
        "' (docs/input.md lists them)")
      return
    end if
    if (SCHEMA(k)%kind /= VK_REAL .and. SCHEMA(k)%kind /= VK_INT) then
      call err%set(ERR_INPUT, p%origin // ": variable '" // p%var // "' of &" // p%group // &
        ' is a ' // kind_name(SCHEMA(k)%kind) // ', not one number: it cannot be swept')
      return
    end if
    p%is_int = SCHEMA(k)%kind == VK_INT
  end subroutine split_name

  !> The variable that names a group of a repeating kind.
  pure function key_var(group) result(v)
    character(len=*), intent(in) :: group
    character(len=:), allocatable :: v
    if (group == 'mass' .or. group == 'force') then
      v = 'node'
    else
      v = 'label'
    end if
  end function key_var

  pure logical function same_target(a, b)
    type(param_t), intent(in) :: a, b
    same_target = a%group == b%group .and. a%key == b%key .and. a%var == b%var
  end function same_target

  ! ---------------------------------------------------------------- generating the cases

  !> Cartesian product, the first parameter varying slowest.
  subroutine gen_product(this, err)
    type(sweep_spec_t), intent(inout) :: this
    type(error_t), intent(inout) :: err
    integer(i8) :: n
    integer :: i, j, r, k, m

    m = size(this%params)
    n = 1
    do j = 1, m
      n = n * size(this%params(j)%list, kind=i8)
      if (n > huge(0)) then
        call err%set(ERR_INPUT, this%path // ': the product of the value lists has more than ' &
          // int_str(huge(0)) // ' cases')
        return
      end if
    end do
    call alloc_values(this, int(n), err)
    if (.not. err%ok()) return
    do i = 1, int(n)
      r = i - 1
      do j = m, 1, -1
        associate (list => this%params(j)%list)
          k = mod(r, size(list))
          r = r / size(list)
          this%values(i, j) = list(k + 1)
        end associate
      end do
    end do
  end subroutine gen_product

  subroutine gen_zip(this, err)
    type(sweep_spec_t), intent(inout) :: this
    type(error_t), intent(inout) :: err
    character(len=:), allocatable :: lengths
    integer :: j, n

    n = size(this%params(1)%list)
    if (any([(size(this%params(j)%list), j = 1, size(this%params))] /= n)) then
      lengths = ''
      do j = 1, size(this%params)
        if (j > 1) lengths = lengths // ', '
        lengths = lengths // "'" // this%params(j)%name // "' " // &
          int_str(size(this%params(j)%list))
      end do
      call err%set(ERR_INPUT, this%path // ": mode 'zip' needs value lists of equal length, " &
        // 'got ' // lengths)
      return
    end if
    call alloc_values(this, n, err)
    if (.not. err%ok()) return
    do j = 1, size(this%params)
      this%values(:, j) = this%params(j)%list
    end do
  end subroutine gen_zip

  !> Mode 'random': independent uniform samples; mode 'lhs': in each parameter, one sample in
  !> each of the n_samples equal strata, the strata in a random order. Each parameter draws from
  !> a stream of its own, so adding a parameter leaves the earlier parameters' values unchanged.
  subroutine gen_sampled(this, err)
    type(sweep_spec_t), intent(inout) :: this
    type(error_t), intent(inout) :: err
    type(rng_t) :: rng
    integer, allocatable :: perm(:)
    integer :: i, j, n
    real(wp) :: u

    n = this%n_samples
    call alloc_values(this, n, err)
    if (.not. err%ok()) return
    if (this%mode == 'lhs') allocate(perm(n))
    do j = 1, size(this%params)
      call rng_init(rng, this%seed, j)
      if (this%mode == 'lhs') call permutation(rng, perm)
      do i = 1, n
        u = uniform(rng)
        if (this%mode == 'lhs') u = (real(perm(i) - 1, wp) + u) / n
        this%values(i, j) = sample_at(this%params(j), u)
      end do
    end do
  end subroutine gen_sampled

  !> The value at u in [0, 1) of the parameter's (log-)uniform distribution; integers rounded.
  pure function sample_at(p, u) result(x)
    type(param_t), intent(in) :: p
    real(wp), intent(in) :: u
    real(wp) :: x, a, b
    a = p%lo
    b = p%hi
    if (p%is_int) then
      a = a - 0.5_wp
      b = b + 0.5_wp
    end if
    if (p%log) then
      x = exp(log(a) + u * (log(b) - log(a)))
    else
      x = a + u * (b - a)
    end if
    x = min(max(x, a), b)   ! exp(log(b)) may round just beyond b
    if (p%is_int) x = min(max(real(floor(x + 0.5_wp), wp), p%lo), p%hi)
  end function sample_at

  subroutine alloc_values(this, n, err)
    type(sweep_spec_t), intent(inout) :: this
    integer, intent(in) :: n
    type(error_t), intent(inout) :: err
    integer :: stat
    allocate(this%values(n, size(this%params)), stat=stat)
    if (stat /= 0) call err%set(ERR_INPUT, this%path // ': no memory for ' // int_str(n) // &
      ' cases')
  end subroutine alloc_values

  ! ---------------------------------------------------------------- one case

  !> scene_file = base with case icase's values written into it. Errors name the sweep file,
  !> the &parameter and the base scene.
  subroutine apply_case(spec, base, icase, scene_file, err)
    type(sweep_spec_t), intent(in) :: spec
    type(nml_file_t), intent(in) :: base
    integer, intent(in) :: icase
    type(nml_file_t), intent(out) :: scene_file
    type(error_t), intent(out) :: err
    integer :: j, k

    if (.not. allocated(spec%values)) then
      call err%set(ERR_INTERNAL, 'apply_case: the sweep specification is not loaded')
      return
    else if (icase < 1 .or. icase > spec%n_cases()) then
      call err%set(ERR_INTERNAL, 'apply_case: case ' // int_str(icase) // ' is not in 1..' // &
        int_str(spec%n_cases()))
      return
    end if
    scene_file = base
    do j = 1, size(spec%params)
      call set_value(spec%params(j), spec%values(icase, j), scene_file, err)
      do k = 1, size(spec%params(j)%tied)
        if (err%ok()) call set_value(spec%params(j)%tied(k), spec%values(icase, j), &
          scene_file, err)
      end do
      if (.not. err%ok()) return
    end do
  end subroutine apply_case

  subroutine set_value(p, x, scene_file, err)
    type(param_t), intent(in) :: p
    real(wp), intent(in) :: x
    type(nml_file_t), intent(inout) :: scene_file
    type(error_t), intent(inout) :: err
    integer :: ig
    call find_group(p, scene_file, ig, err)
    if (.not. err%ok()) return
    call scene_file%groups(ig)%set_raw(p%var, value_text(x, p%is_int), err)
    if (.not. err%ok()) call err%prefix(p%origin // ': ')
  end subroutine set_value

  !> Index in `file%groups` of the group the parameter names.
  subroutine find_group(p, file, ig, err)
    type(param_t), intent(in) :: p
    type(nml_file_t), intent(in) :: file
    integer, intent(out) :: ig
    type(error_t), intent(inout) :: err
    type(nml_group_t) :: g
    type(error_t) :: e
    character(len=:), allocatable :: key, keys, kv
    integer :: k, idx, n_match

    ig = 0
    if (file%count(p%group) == 0) then
      call err%set(ERR_INPUT, p%origin // ": the base scene '" // file%path // "' has no &" // &
        p%group // ' group')
      return
    end if
    if (any(SINGLE_GROUPS == p%group)) then
      ig = file%group_index(p%group, 1)
      return
    end if
    kv = key_var(p%group)
    keys = ''
    n_match = 0
    do k = 1, file%count(p%group)
      idx = file%group_index(p%group, k)
      g = file%groups(idx)   ! a copy: reading the key must not mark it used in the scene
      call g%get_string(kv, key, e)
      if (.not. e%ok()) cycle   ! the scene reader reports it
      if (len(keys) > 0) keys = keys // ', '
      keys = keys // "'" // key // "'"
      if (key == p%key) then
        n_match = n_match + 1
        if (n_match == 1) ig = idx
      end if
    end do
    if (n_match == 0) then
      call err%set(ERR_INPUT, p%origin // ': no &' // p%group // " group of the base scene '" &
        // file%path // "' has " // kv // " '" // p%key // "' (" // kv // 's: ' // keys // ')')
      ig = 0
    else if (n_match > 1) then
      call err%set(ERR_INPUT, p%origin // ': ' // int_str(n_match) // ' &' // p%group // &
        " groups of the base scene '" // file%path // "' have " // kv // " '" // p%key // &
        "': the name must pick one")
      ig = 0
    end if
  end subroutine find_group

  !> A value as namelist text: integers as such, reals to full precision.
  function value_text(x, is_int) result(s)
    real(wp), intent(in) :: x
    logical, intent(in) :: is_int
    character(len=:), allocatable :: s
    character(len=32) :: buf
    if (is_int) then
      write(buf, '(i0)') nint(x)
    else
      write(buf, '(es24.16e3)') x
    end if
    s = trim(adjustl(buf))
  end function value_text

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

  ! ---------------------------------------------------------------- random numbers
  !
  ! splitmix64 written with bit operations and 16/32-bit limbs: Fortran integers are signed and
  ! their overflow is undefined, so the mod-2**64 sums and products are built from pieces that
  ! cannot overflow. The stream is then the same with every compiler and option.

  !> Stream `stream` of seed `seed`: the seed and stream number are hashed into the state.
  pure subroutine rng_init(rng, seed, stream)
    type(rng_t), intent(out) :: rng
    integer, intent(in) :: seed, stream
    rng%state = mix64(add64(mix64(int(seed, i8)), int(stream, i8)))
  end subroutine rng_init

  integer(i8) function next64(rng) result(z)
    type(rng_t), intent(inout) :: rng
    rng%state = add64(rng%state, SM_GAMMA)
    z = mix64(rng%state)
  end function next64

  !> Uniform in [0, 1): the top 53 bits, exactly representable.
  real(wp) function uniform(rng) result(u)
    type(rng_t), intent(inout) :: rng
    u = real(ishft(next64(rng), -11), wp) * 2.0_wp**(-53)
  end function uniform

  !> A uniformly random permutation of 1..n (Fisher-Yates).
  subroutine permutation(rng, perm)
    type(rng_t), intent(inout) :: rng
    integer, intent(out) :: perm(:)
    integer :: i, k, tmp
    perm = [(i, i = 1, size(perm))]
    do i = size(perm), 2, -1
      k = min(int(uniform(rng) * i) + 1, i)
      tmp = perm(i)
      perm(i) = perm(k)
      perm(k) = tmp
    end do
  end subroutine permutation

  pure integer(i8) function mix64(x) result(z)
    integer(i8), intent(in) :: x
    z = mul64(ieor(x, ishft(x, -30)), SM_MUL1)
    z = mul64(ieor(z, ishft(z, -27)), SM_MUL2)
    z = ieor(z, ishft(z, -31))
  end function mix64

  !> a + b mod 2**64 on the bit patterns.
  pure integer(i8) function add64(a, b) result(r)
    integer(i8), intent(in) :: a, b
    integer(i8) :: lo, hi
    lo = iand(a, MASK32) + iand(b, MASK32)
    hi = ishft(a, -32) + ishft(b, -32) + ishft(lo, -32)
    r = ior(iand(lo, MASK32), ishft(iand(hi, MASK32), 32))
  end function add64

  !> a * b mod 2**64 on the bit patterns, by 16-bit limbs (every partial product < 2**32).
  pure integer(i8) function mul64(a, b) result(r)
    integer(i8), intent(in) :: a, b
    integer(i8) :: al(0:3), bl(0:3), acc, carry
    integer :: i, k
    do i = 0, 3
      al(i) = iand(ishft(a, -16 * i), MASK16)
      bl(i) = iand(ishft(b, -16 * i), MASK16)
    end do
    r = 0
    carry = 0
    do k = 0, 3
      acc = carry
      do i = 0, k
        acc = acc + al(i) * bl(k - i)
      end do
      r = ior(r, ishft(iand(acc, MASK16), 16 * k))
      carry = ishft(acc, -16)
    end do
  end function mul64

  ! ---------------------------------------------------------------- text helpers

  function join(items) result(s)
    character(len=*), intent(in) :: items(:)
    character(len=:), allocatable :: s
    integer :: i
    s = ''
    do i = 1, size(items)
      if (i > 1) s = s // ', '
      s = s // trim(items(i))
    end do
  end function join

  pure logical function is_name(s)
    character(len=*), intent(in) :: s
    character(len=*), parameter :: LETTERS = 'abcdefghijklmnopqrstuvwxyz'
    is_name = .false.
    if (len(s) == 0) return
    is_name = index(LETTERS, s(1:1)) > 0 .and. verify(s, LETTERS // '0123456789_') == 0
  end function is_name

end module sweep_spec
