!> Generating a sweep's cases (product, zip, random, Latin hypercube) and writing one case
!> into the base scene.
submodule (sweep_spec) sweep_spec_cases
  use core_kinds, only: i8
  use core_error, only: ERR_INTERNAL
  use sweep_random, only: rng_t, rng_init, uniform, permutation
  use io_schema, only: SINGLE_GROUPS
  implicit none

contains

  ! ---------------------------------------------------------------- generating the cases

  !> Cartesian product, the first parameter varying slowest.
  module procedure gen_product
    integer(i8) :: n
    integer :: i, j, r, k, m

    m = size(this%params)
    n = 1
    do j = 1, m
      n = n * size(this%params(j)%list, kind=i8)
      if (n > MAX_CASES) then
        call err%set(ERR_INPUT, this%path // ': the product of the value lists has more than ' &
          // int_str(MAX_CASES) // ' cases')
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
  end procedure gen_product

  module procedure gen_zip
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
  end procedure gen_zip

  !> Mode 'random': independent uniform samples; mode 'lhs': in each parameter, one sample in
  !> each of the n_samples equal strata, the strata in a random order. Each parameter draws from
  !> a stream of its own, so adding a parameter leaves the earlier parameters' values unchanged.
  module procedure gen_sampled
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
  end procedure gen_sampled

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
  module procedure apply_case
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
  end procedure apply_case

  subroutine set_value(p, x, scene_file, err)
    type(param_t), intent(in) :: p
    real(wp), intent(in) :: x
    type(nml_file_t), intent(inout) :: scene_file
    type(error_t), intent(inout) :: err
    character(len=:), allocatable :: text
    integer :: ig
    call find_group(p, scene_file, ig, err)
    if (.not. err%ok()) return
    if (p%entry > 0) then
      call entry_text(p, x, scene_file%groups(ig), scene_file%path, text, err)
      if (.not. err%ok()) return
    else
      text = value_text(x, p%is_int)
    end if
    call scene_file%groups(ig)%set_raw(p%var, text, err)
    if (.not. err%ok()) call err%prefix(p%origin // ': ')
  end subroutine set_value

  !> The group's list p%var with entry p%entry replaced by x, as namelist text: a namelist sets
  !> a list whole, so the other entries are written back as the scene (or an earlier
  !> parameter on another entry) has them.
  subroutine entry_text(p, x, group, path, text, err)
    type(param_t), intent(in) :: p
    real(wp), intent(in) :: x
    type(nml_group_t), intent(in) :: group
    character(len=*), intent(in) :: path
    character(len=:), allocatable, intent(out) :: text
    type(error_t), intent(inout) :: err
    type(nml_group_t) :: g
    real(wp), allocatable :: list(:)
    integer :: i

    g = group   ! a copy: reading the list must not mark it used in the scene
    if (.not. g%has(p%var)) then
      call err%set(ERR_INPUT, p%origin // ': &' // p%group // " of the base scene '" // path // &
        "' does not set '" // p%var // "': a sweep changes one entry of a list the base " // &
        'scene gives (write the whole list there)')
      return
    end if
    call g%get_real_array(p%var, list, err)
    if (.not. err%ok()) then
      call err%prefix(p%origin // ': ')
      return
    end if
    if (p%entry > size(list)) then
      call err%set(ERR_INPUT, p%origin // ': entry ' // int_str(p%entry) // " of '" // p%var // &
        "' is beyond the list of &" // p%group // " in the base scene '" // path // "', " // &
        'which has ' // int_str(size(list)) // ' entries')
      return
    end if
    list(p%entry) = x
    text = ''
    do i = 1, size(list)
      if (i > 1) text = text // ', '
      text = text // value_text(list(i), .false.)
    end do
  end subroutine entry_text

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

end submodule sweep_spec_cases
