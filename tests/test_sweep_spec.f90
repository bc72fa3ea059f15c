!> Sweep files (sweep_spec, docs/sweep.md): case generation for every mode, the integer
!> variables, writing a case into a base scene, and the input errors.
program test_sweep_spec
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_INPUT
  use io_namelist, only: nml_file_t
  use io_scene, only: read_scene
  use model_scene, only: scene_t
  use sweep_spec, only: sweep_spec_t, apply_case
  use testing, only: suite_t
  implicit none
  character(len=*), parameter :: NL = new_line('a')
  character(len=*), parameter :: SWEEP = "&sweep base = 'base.nml' /" // NL

  !> A small scene the scene reader accepts (read_scene only: no model is built).
  character(len=*), parameter :: BASE_SCENE = &
    "&node label = 'a', x = 0, y = 0, fixed = .true. /" // NL // &
    "&node label = 'b', x = 1, y = 0 /" // NL // &
    "&node label = 'c', x = 2, y = 0 /" // NL // &
    "&link label = 'l1', from = 'a', to = 'b', n_elements = 2, E = 2e11, A = 1e-4, " // &
    "I = 1e-8, rho = 7800 /" // NL // &
    "&link label = 'l2', from = 'b', to = 'c', E = 2e11, A = 1e-4, I = 1e-8, rho = 7800 /" // NL &
    // "&hinge label = 'j1', node = 'a', link = 'l1', mode = 'prescribed', motion = 'm1' /" // NL &
    // "&motion label = 'm1', end = 1.0, duration = 0.5 /" // NL // &
    "&mass node = 'c', m = 2.0 /" // NL // &
    "&dynamic t_end = 1.0 /" // NL
  !> The same scene with lists: gravity, and a table motion.
  character(len=*), parameter :: LIST_SCENE = BASE_SCENE(:index(BASE_SCENE, '&motion') - 1) // &
    "&motion label = 'm1', law = 'table', times = 0, 0.5, 1, values = 0, 0.25, 1 /" // NL // &
    "&mass node = 'c', m = 2.0 /" // NL // &
    "&scene gravity = 0.5, -9.81 /" // NL // &
    "&dynamic t_end = 1.0 /" // NL
  type(suite_t) :: t

  call t%init('sweep specification')
  call test_product()
  call test_ranges()
  call test_zip()
  call test_random()
  call test_lhs()
  call test_integers()
  call test_paths()
  call test_apply_case()
  call test_errors()
  call test_base_errors()
  call test_list_entries()
  call test_list_entry_errors()
  call t%finish()

contains

  subroutine parse_ok(spec, text, what)
    type(sweep_spec_t), intent(inout) :: spec
    character(len=*), intent(in) :: text, what
    type(error_t) :: err
    call spec%parse(text, 'sweep.nml', err)
    call t%check(err%ok(), what // ' parses')
    if (.not. err%ok()) write(*, '(a)') '        ' // err%message
  end subroutine parse_ok

  !> The error must be an input error, one line, containing every one of `parts`.
  subroutine expect_error(err, parts, what)
    type(error_t), intent(in) :: err
    character(len=*), intent(in) :: parts(:), what
    logical :: good
    integer :: i
    good = .not. err%ok()
    if (good) good = err%code == ERR_INPUT .and. index(err%message, NL) == 0
    do i = 1, size(parts)
      if (good) good = index(err%message, trim(parts(i))) > 0
    end do
    call t%check(good, what)
    if (.not. err%ok()) write(*, '(a)') '        -> ' // err%message
  end subroutine expect_error

  subroutine parse_fails(text, parts, what)
    character(len=*), intent(in) :: text, parts(:), what
    type(sweep_spec_t) :: spec
    type(error_t) :: err
    call spec%parse(text, 'sweep.nml', err)
    call expect_error(err, parts, what)
  end subroutine parse_fails

  subroutine test_product()
    type(sweep_spec_t) :: s
    call parse_ok(s, SWEEP // &
      "&parameter name = 'link.l1.E', values = 1, 2, 3 /" // NL // &
      "&parameter name = 'dynamic.rtol', values = 10, 20 /", 'product 3x2')
    call t%check(s%n_cases() == 6 .and. s%n_parameters() == 2, 'product: 6 cases, 2 parameters')
    call t%check(s%mode == 'product' .and. s%seed == 1 .and. s%node == 'tip' .and. &
      s%title == '', 'sweep defaults')
    call t%check(s%names(1)%s == 'link.l1.E' .and. s%names(2)%s == 'dynamic.rtol', &
      'names as given')
    call t%close_array(s%values(:, 1), [1, 1, 2, 2, 3, 3] * 1.0_wp, 0.0_wp, 0.0_wp, &
      'first parameter varies slowest')
    call t%close_array(s%values(:, 2), [10, 20, 10, 20, 10, 20] * 1.0_wp, 0.0_wp, 0.0_wp, &
      'last parameter varies fastest')
  end subroutine test_product

  subroutine test_ranges()
    type(sweep_spec_t) :: s
    call parse_ok(s, SWEEP // &
      "&parameter name = 'motion.m1.end', start = 0, stop = 1, n = 5 /" // NL // &
      "&parameter name = 'dynamic.rtol', start = 1e-8, stop = 1e-4, n = 3, log = .true. /" // NL &
      // "&parameter name = 'mass.c.m', start = 7, stop = 9, n = 1 /", 'start/stop/n')
    call t%check(s%n_cases() == 15, 'range: 5 x 3 x 1 cases')
    call t%close_array(s%values(1:15:3, 1), [0.0_wp, 0.25_wp, 0.5_wp, 0.75_wp, 1.0_wp], &
      1.0e-15_wp, 0.0_wp, 'linear spacing')
    call t%close_array(s%values(1:3, 2), [1.0e-8_wp, 1.0e-6_wp, 1.0e-4_wp], 1.0e-13_wp, &
      0.0_wp, 'geometric spacing')
    call t%check(s%values(1, 2) == 1.0e-8_wp .and. s%values(3, 2) == 1.0e-4_wp, &
      'range ends exactly as given')
    call t%check(all(s%values(:, 3) == 7.0_wp), 'n = 1 gives start')
  end subroutine test_ranges

  subroutine test_zip()
    type(sweep_spec_t) :: s
    call parse_ok(s, "&sweep base = 'base.nml', mode = 'zip', title = 'z' /" // NL // &
      "&parameter name = 'link.l1.E', values = 1, 2, 3 /" // NL // &
      "&parameter name = 'motion.m1.end', start = 10, stop = 30, n = 3 /", 'zip')
    call t%check(s%n_cases() == 3 .and. s%mode == 'zip' .and. s%title == 'z', 'zip: 3 cases')
    call t%close_array(s%values(:, 1), [1.0_wp, 2.0_wp, 3.0_wp], 0.0_wp, 0.0_wp, 'zip column 1')
    call t%close_array(s%values(:, 2), [10.0_wp, 20.0_wp, 30.0_wp], 0.0_wp, 0.0_wp, &
      'zip column 2')
  end subroutine test_zip

  function random_text(mode, seed, n) result(text)
    character(len=*), intent(in) :: mode, seed, n
    character(len=:), allocatable :: text
    text = "&sweep base = 'base.nml', mode = '" // mode // "', seed = " // seed // &
      ', n_samples = ' // n // ' /' // NL // &
      "&parameter name = 'link.l1.E', min = 2, max = 5 /" // NL // &
      "&parameter name = 'dynamic.rtol', min = 1e-3, max = 1e-1, log = .true. /"
  end function random_text

  subroutine test_random()
    type(sweep_spec_t) :: a, b, c, d
    call parse_ok(a, random_text('random', '42', '200'), 'random')
    call parse_ok(b, random_text('random', '42', '200'), 'random again')
    call parse_ok(c, random_text('random', '43', '200'), 'random, other seed')
    call t%check(a%n_cases() == 200 .and. a%seed == 42 .and. a%n_samples == 200, &
      'random: n_samples cases')
    call t%check(all(a%values == b%values), 'same seed, same cases')
    call t%check(all(a%values /= c%values), 'another seed, other cases')
    call t%check(all(a%values(:, 1) >= 2 .and. a%values(:, 1) <= 5), 'uniform within bounds')
    call t%check(all(a%values(:, 2) >= 1.0e-3_wp .and. a%values(:, 2) <= 1.0e-1_wp), &
      'log-uniform within bounds')
    ! About half the log-uniform samples lie below the geometric mean 1e-2.
    call t%check(abs(count(a%values(:, 2) < 1.0e-2_wp) - 100) < 30, &
      'log-uniform: half below the geometric mean')
    call t%check(abs(count(a%values(:, 1) < 3.5_wp) - 100) < 30, &
      'uniform: half below the midpoint')
    ! Values of an independent splitmix64 implementation (Python): the stream must not depend
    ! on the compiler.
    call t%close_array(a%values(1:3, 1), [2.2980044938109425_wp, 4.926883800266796_wp, &
      2.3642949919210956_wp], 1.0e-15_wp, 0.0_wp, 'random values as the reference generator')
    call t%close_array(a%values(1:3, 2), [0.08135064385686329_wp, 0.047503625576025804_wp, &
      0.026553869383315103_wp], 1.0e-13_wp, 0.0_wp, 'log-uniform values as the reference')
    ! A parameter's stream is its own: dropping the second parameter keeps the first.
    call parse_ok(d, "&sweep base = 'base.nml', mode = 'random', seed = 42, n_samples = 200 /" &
      // NL // "&parameter name = 'link.l1.E', min = 2, max = 5 /", 'random, one parameter')
    call t%check(all(d%values(:, 1) == a%values(:, 1)), 'streams per parameter')
    call parse_ok(d, "&sweep base = 'base.nml', mode = 'random', seed = -5, n_samples = 1 /" &
      // NL // "&parameter name = 'link.l1.E', min = 0, max = 1 /", 'random, negative seed')
    call t%close(d%values(1, 1), 0.49599381399902864_wp, 1.0e-15_wp, 0.0_wp, &
      'negative seed as the reference')
  end subroutine test_random

  subroutine test_lhs()
    type(sweep_spec_t) :: s, s2
    integer, parameter :: N = 37
    integer :: hits(N), j, i, k
    logical :: one_each
    call parse_ok(s, random_text('lhs', '7', '37'), 'lhs')
    call parse_ok(s2, random_text('lhs', '7', '37'), 'lhs again')
    call t%check(s%n_cases() == N, 'lhs: n_samples cases')
    call t%check(all(s%values == s2%values), 'lhs reproducible')
    one_each = .true.
    do j = 1, 2
      hits = 0
      do i = 1, N
        if (j == 1) then
          k = floor((s%values(i, 1) - 2.0_wp) / 3.0_wp * N) + 1
        else   ! log: strata equal in log space
          k = floor(log(s%values(i, 2) / 1.0e-3_wp) / log(100.0_wp) * N) + 1
        end if
        k = min(max(k, 1), N)
        hits(k) = hits(k) + 1
      end do
      one_each = one_each .and. all(hits == 1)
    end do
    call t%check(one_each, 'lhs: exactly one sample per stratum per parameter (linear and log)')
    ! Not simply stratum i in case i: the strata are permuted.
    k = count([(floor((s%values(i, 1) - 2.0_wp) / 3.0_wp * N) + 1 == i, i = 1, N)])
    call t%check(2 * k < N, 'lhs: strata in random order')
  end subroutine test_lhs

  subroutine test_integers()
    type(sweep_spec_t) :: s
    integer :: v
    logical :: each
    call parse_ok(s, "&sweep base = 'base.nml', mode = 'random', n_samples = 400 /" // NL // &
      "&parameter name = 'link.l1.n_elements', min = 1, max = 4 /" // NL // &
      "&parameter name = 'link.l2.E', min = 1, max = 4 /", 'integer random')
    call t%check(all(s%values(:, 1) == anint(s%values(:, 1))), 'integer samples rounded')
    call t%check(any(s%values(:, 2) /= anint(s%values(:, 2))), 'real samples not rounded')
    each = .true.
    do v = 1, 4
      ! equal shares (100 each): the ends are not halved by the rounding
      each = each .and. abs(count(s%values(:, 1) == v) - 100) < 35
    end do
    call t%check(each .and. all(s%values(:, 1) >= 1 .and. s%values(:, 1) <= 4), &
      'integers 1..4 equally likely')
    call parse_ok(s, "&sweep base = 'base.nml', mode = 'lhs', n_samples = 50 /" // NL // &
      "&parameter name = 'Link.l1.N_Elements', min = 1.5, max = 8.2, log = .true. /", &
      'integer lhs, log, non-integral bounds')
    call t%check(all(s%values(:, 1) == anint(s%values(:, 1)) .and. s%values(:, 1) >= 2 .and. &
      s%values(:, 1) <= 8), 'integer lhs within the whole numbers of [min, max]')
    call parse_ok(s, SWEEP // "&parameter name = 'static.n_steps', start = 2, stop = 11, " // &
      "n = 4 /", 'integer range')
    call t%close_array(s%values(:, 1), [2.0_wp, 5.0_wp, 8.0_wp, 11.0_wp], 0.0_wp, 0.0_wp, &
      'integral range values')
  end subroutine test_integers

  subroutine test_paths()
    type(sweep_spec_t) :: s
    type(error_t) :: err
    integer :: u
    call s%parse(SWEEP // "&parameter name = 'dynamic.rtol', values = 1 /", &
      'runs/a/sweep.nml', err)
    call t%check(err%ok() .and. s%base_path == 'runs/a/base.nml', &
      'base relative to the sweep file: ' // s%base_path)
    call s%parse("&sweep base = '/abs/base.nml' /" // NL // &
      "&parameter name = 'dynamic.rtol', values = 1 /", 'runs/a/sweep.nml', err)
    call t%check(err%ok() .and. s%base_path == '/abs/base.nml', 'absolute base kept')
    call s%parse(SWEEP // "&parameter name = 'dynamic.rtol', values = 1 /", 'sweep.nml', err)
    call t%check(err%ok() .and. s%base_path == 'base.nml', 'sweep file in the current folder')

    open(newunit=u, file='test_sweep_spec.nml', status='replace', action='write')
    write(u, '(a)') "! a sweep" // NL // "&sweep base = 'b.nml', node = 'c' /" // NL // &
      "&parameter name = 'mass.c.m', values = 1, 2 /"
    close(u)
    call s%load('test_sweep_spec.nml', err)
    call t%check(err%ok() .and. s%n_cases() == 2 .and. s%node == 'c' .and. &
      s%path == 'test_sweep_spec.nml' .and. index(s%text, '! a sweep') == 1, 'load a file')
    open(newunit=u, file='test_sweep_spec.nml', status='old')
    close(u, status='delete')
    call s%load('no_such_sweep.nml', err)
    call expect_error(err, [character(30) :: 'no_such_sweep.nml'], 'missing sweep file')
  end subroutine test_paths

  subroutine test_apply_case()
    type(sweep_spec_t) :: s
    type(nml_file_t) :: base, case_file
    type(scene_t) :: scene
    type(error_t) :: err
    call base%parse(BASE_SCENE, 'base.nml', err)
    call t%check(err%ok(), 'base scene parses')
    call read_scene(base, scene, err)
    call t%check(err%ok(), 'base scene reads')
    if (.not. err%ok()) write(*, '(a)') '        ' // err%message
    call base%parse(BASE_SCENE, 'base.nml', err)   ! fresh: read_scene marked variables used
    call parse_ok(s, SWEEP // &
      "&parameter name = 'link.l2.n_elements', values = 3, 5 /" // NL // &
      "&parameter name = 'link.l1.E', values = 7.123456789012345e10 /" // NL // &
      "&parameter name = 'mass.c.m', values = 0.1 /" // NL // &
      "&parameter name = 'dynamic.rtol', values = 1e-9 /" // NL // &
      "&parameter name = 'motion.m1.end', values = -2.5 /", 'apply sweep')
    call apply_case(s, base, 2, case_file, err)
    call t%check(err%ok(), 'apply_case')
    if (.not. err%ok()) write(*, '(a)') '        ' // err%message
    call read_scene(case_file, scene, err)
    call t%check(err%ok(), 'the case scene reads')
    if (.not. err%ok()) write(*, '(a)') '        ' // err%message
    if (.not. err%ok()) return
    call t%check(scene%links(2)%n_elements == 5 .and. scene%links(1)%n_elements == 2, &
      'integer value landed (link l2 n_elements = 5, l1 unchanged)')
    call t%check(scene%links(1)%e_modulus == 7.123456789012345e10_wp, &
      'real value landed to full precision')
    call t%check(scene%masses(1)%m == 0.1_wp .and. scene%dynamic%rtol == 1.0e-9_wp .and. &
      scene%motions(1)%end == -2.5_wp, 'keyed by node, single group, negative value')
    ! The base stays as it was.
    call read_scene(base, scene, err)
    call t%check(err%ok() .and. scene%links(2)%n_elements == 1 .and. &
      scene%links(1)%e_modulus == 2.0e11_wp, 'base unchanged')
    ! A value beyond the schema's range is refused with the sweep, naming the parameter and the
    ! first case that has it (before, each such case failed when it ran).
    call base%parse(BASE_SCENE, 'base.nml', err)
    call parse_fails(SWEEP // "&parameter name = 'link.l1.E', values = 1e9, -1 /", &
      [character(40) :: "'link.l1.E'", 'case 2:', "'E' of &link", &
      'must be positive, in [1e-30, 1e30]', 'got -1'], 'negative E')
    call parse_fails(SWEEP // "&parameter name = 'mass.c.m', 'link.l1.E', values = 0, 1 /", &
      [character(40) :: "'link.l1.E'", 'case 1:', 'got 0'], 'tied name out of range')
    call parse_fails("&sweep base = 'base.nml', mode = 'random', n_samples = 5 /" // NL // &
      "&parameter name = 'scene.gravity(2)', min = -1e35, max = -1e34 /", &
      [character(40) :: "'scene.gravity(2)'", 'case 1:', "'gravity' of &scene", &
      'magnitude in [1e-30, 1e30]'], 'sampled list entry out of range')
    call parse_ok(s, SWEEP // "&parameter name = 'link.l1.G', values = 0, 1e-30, 1e30 /", &
      'the ends of a range and 0')
    ! A variable set twice through tied names: the later value silently won.
    call parse_fails(SWEEP // "&parameter name = 'link.l1.E', 'link.l1.E', values = 1 /", &
      [character(40) :: "'link.l1.E'", 'named twice in this &parameter'], &
      'a tied name twice in one &parameter')
    call parse_fails(SWEEP // "&parameter name = 'link.l1.E', values = 1 /" // NL // &
      "&parameter name = 'link.l2.E', 'link.l1.E', values = 2 /", &
      [character(40) :: "#2 'link.l1.E'", "as &parameter #1 'link.l1.E'"], &
      'a tied name of another &parameter')
    call parse_fails(SWEEP // "&parameter name = 'link.l2.E', 'link.l1.E', values = 1 /" // NL &
      // "&parameter name = 'link.l1.E', values = 2 /", &
      [character(40) :: "#2 'link.l1.E'", "as &parameter #1 'link.l1.E'"], &
      'a name another &parameter ties')
    ! Unknown variables are refused up front, from the scene schema.
    call parse_fails(SWEEP // "&parameter name = 'dynamic.rtoll', values = 1e-6 /", &
      [character(40) :: "'dynamic.rtoll'", "no variable 'rtoll'"], 'typo')
    call apply_case(s, base, 4, case_file, err)
    call t%check(.not. err%ok(), 'case number out of range: ' // err%message)
    ! One &parameter, several variables: both take the case's value.
    call parse_ok(s, SWEEP // "&parameter name = 'link.l1.E', 'link.l2.E', values = 1e9, 2e9 /", &
      'tied names')
    call t%check(case_scene(s, BASE_SCENE, 2, scene, 'tied names') .and. s%n_cases() == 2 .and. &
      s%n_parameters() == 1 .and. &
      scene%links(1)%e_modulus == 2.0e9_wp .and. scene%links(2)%e_modulus == 2.0e9_wp, &
      'tied names: one column, every named variable set')
  end subroutine test_apply_case

  !> Errors of the sweep file alone.
  subroutine test_errors()
    call parse_fails(SWEEP // "&parameter name = 'rtol', values = 1 /", &
      [character(40) :: 'sweep.nml:2', '&parameter #1', "'rtol'", 'group.variable'], &
      'name without a group')
    call parse_fails(SWEEP // "&parameter name = 'solver.tol', values = 1 /", &
      [character(40) :: '&parameter #1', "'solver.tol'", "unknown group 'solver'", 'dynamic'], &
      'unknown group')
    call parse_fails(SWEEP // "&parameter name = 'link.E', values = 1 /", &
      [character(40) :: "'link.E'", 'may repeat', 'link.<label>.E'], 'repeated group without key')
    call parse_fails(SWEEP // "&parameter name = 'mass.m', values = 1 /", &
      [character(40) :: "'mass.m'", 'mass.<node>.m'], '&mass without key: keyed by node')
    call parse_fails(SWEEP // "&parameter name = 'dynamic.x.rtol', values = 1 /", &
      [character(40) :: "'dynamic.x.rtol'", 'takes no key', "'dynamic.rtol'"], &
      'key for a single group')
    call parse_fails(SWEEP // "&parameter name = 'link.l1.2x', values = 1 /", &
      [character(40) :: "'link.l1.2x'", 'not a variable name'], 'bad variable name')
    call parse_fails(SWEEP // "&parameter name = 'motion.m1.law', values = 1 /", &
      [character(40) :: "'motion.m1.law'", 'keyword', 'cannot be swept'], 'keyword variable')
    call parse_fails(SWEEP // "&parameter name = 'scene.gravity', values = 1 /", &
      [character(40) :: "'scene.gravity'", 'real list', "'scene.gravity(1)'"], &
      'list variable without an entry')
    call parse_fails(SWEEP // "&parameter name = 'link.l1.bending(1)', values = 1 /", &
      [character(40) :: "'link.l1.bending(1)'", 'keyword list', 'cannot be swept'], &
      'entry of a keyword list')
    call parse_fails(SWEEP // "&parameter name = 'link.l1.n_elements', values = 2, 2.5 /", &
      [character(40) :: "'link.l1.n_elements'", 'value 2 (2.5)', 'not a whole number'], &
      'non-integral value of an integer variable')
    call parse_fails(SWEEP // "&parameter name = 'modal.n_modes', start = 1, stop = 10, n = 3 /", &
      [character(40) :: "'modal.n_modes'", '(5.5)', 'not a whole number'], &
      'non-integral range of an integer variable')
    call parse_fails("&sweep base = 'b.nml', mode = 'random', n_samples = 4 /" // NL // &
      "&parameter name = 'link.l1.E', values = 1, 2 /", &
      [character(40) :: "'link.l1.E'", "'values'", "mode 'random'"], 'values with random')
    call parse_fails("&sweep base = 'b.nml', mode = 'lhs', n_samples = 4 /" // NL // &
      "&parameter name = 'link.l1.E', start = 1, stop = 2, n = 2 /", &
      [character(40) :: "'link.l1.E'", "'start'", "mode 'lhs'"], 'start/stop/n with lhs')
    call parse_fails(SWEEP // "&parameter name = 'link.l1.E', min = 1, max = 2 /", &
      [character(40) :: "'link.l1.E'", "'min'", "mode 'product'"], 'min/max with product')
    call parse_fails(SWEEP // "&parameter name = 'link.l1.E', values = 1, start = 1, " // &
      "stop = 2, n = 2 /", [character(40) :: "'link.l1.E'", 'not both'], 'values and a range')
    call parse_fails(SWEEP // "&parameter name = 'link.l1.E' /", &
      [character(40) :: "'link.l1.E'", 'no values'], 'no values')
    call parse_fails(SWEEP // "&parameter name = 'link.l1.E', start = 1, n = 2 /", &
      [character(40) :: "'link.l1.E'", "missing 'stop'"], 'range without stop')
    call parse_fails(SWEEP // "&parameter name = 'motion.m1.end', start = 0, stop = 1, n = 0 /", &
      [character(40) :: "'motion.m1.end'", 'empty range', 'n = 0'], 'empty range')
    ! Each of these allocated its 16 GB list or table and was killed by the system.
    call parse_fails(SWEEP // "&parameter name = 'motion.m1.end', start = 0, stop = 1, " // &
      'n = 2000000000 /', [character(40) :: "'motion.m1.end'", "variable 'n'", '10000000'], &
      'range beyond the case limit')
    call parse_fails(SWEEP // "&parameter name = 'motion.m1.end', start = 0, stop = 1, " // &
      "n = 4000 /" // NL // "&parameter name = 'link.l1.E', start = 1, stop = 2, n = 4000 /", &
      [character(40) :: 'product', 'more than 10000000 cases'], 'product beyond the case limit')
    call parse_fails("&sweep base = 'b.nml', mode = 'lhs', n_samples = 2000000000 /" // NL // &
      "&parameter name = 'link.l1.E', min = 1, max = 2 /", &
      [character(40) :: '&sweep', "'n_samples'", 'at most 10000000'], 'samples beyond the limit')
    call parse_fails(SWEEP // "&parameter name = 'link.l1.E', start = 0, stop = 1, n = 3, " // &
      'log = .true. /', [character(40) :: "'link.l1.E'", "'log'", 'start > 0'], &
      'log range through zero')
    call parse_fails(SWEEP // "&parameter name = 'link.l1.E', values = 1, 2, log = .true. /", &
      [character(40) :: "'link.l1.E'", "'log'", "'values'"], 'log with values')
    call parse_fails("&sweep base = 'b.nml', mode = 'random', n_samples = 4 /" // NL // &
      "&parameter name = 'link.l1.E', min = 2, max = 2 /", &
      [character(40) :: "'link.l1.E'", 'min < max'], 'min = max')
    call parse_fails("&sweep base = 'b.nml', mode = 'random', n_samples = 4 /" // NL // &
      "&parameter name = 'link.l1.E', min = 0, max = 2, log = .true. /", &
      [character(40) :: "'link.l1.E'", "'log' needs min > 0"], 'log with min = 0')
    call parse_fails("&sweep base = 'b.nml', mode = 'random', n_samples = 4 /" // NL // &
      "&parameter name = 'link.l1.E', max = 2 /", &
      [character(40) :: "'link.l1.E'", "'min' and 'max'"], 'random without min')
    call parse_fails("&sweep base = 'b.nml', mode = 'random', n_samples = 4 /" // NL // &
      "&parameter name = 'link.l1.n_elements', min = 1.2, max = 1.8 /", &
      [character(40) :: "'link.l1.n_elements'", 'no integer'], 'no integer in [min, max]')
    call parse_fails("&sweep base = 'b.nml', mode = 'random' /" // NL // &
      "&parameter name = 'link.l1.E', min = 1, max = 2 /", &
      [character(40) :: '&sweep', "'n_samples'", "mode 'random'"], 'random without n_samples')
    call parse_fails("&sweep base = 'b.nml', mode = 'lhs', n_samples = 0 /" // NL // &
      "&parameter name = 'link.l1.E', min = 1, max = 2 /", &
      [character(40) :: '&sweep', "'n_samples'", 'zero samples'], 'zero samples')
    call parse_fails("&sweep base = 'b.nml', mode = 'lhs', n_samples = -3 /" // NL // &
      "&parameter name = 'link.l1.E', min = 1, max = 2 /", &
      [character(40) :: '&sweep', "'n_samples'", '-3'], 'negative samples')
    call parse_fails("&sweep base = 'b.nml', n_samples = 3 /" // NL // &
      "&parameter name = 'link.l1.E', values = 1 /", &
      [character(40) :: '&sweep', "'n_samples'", "mode 'product'"], 'n_samples with product')
    call parse_fails("&sweep base = 'b.nml', mode = 'grid' /" // NL // &
      "&parameter name = 'link.l1.E', values = 1 /", &
      [character(40) :: '&sweep', "'grid'", 'lhs'], 'unknown mode')
    call parse_fails("&sweep base = 'b.nml', mode = 'zip' /" // NL // &
      "&parameter name = 'link.l1.E', values = 1, 2, 3 /" // NL // &
      "&parameter name = 'link.l2.E', values = 1, 2 /", &
      [character(40) :: "mode 'zip'", "'link.l1.E' 3", "'link.l2.E' 2"], 'zip of unequal lists')
    call parse_fails(SWEEP // "&parameter name = 'link.l1.E', values = 1 /" // NL // &
      "&parameter name = 'LINK.l1.e', values = 2 /", &
      [character(40) :: '&parameter #2', "'LINK.l1.e'", "#1 'link.l1.E'"], 'duplicate parameter')
    call parse_fails(SWEEP, [character(40) :: 'sweep.nml', 'no &parameter'], 'no &parameter')
    call parse_fails("&parameter name = 'link.l1.E', values = 1 /", &
      [character(40) :: 'sweep.nml', 'no &sweep'], 'no &sweep')
    call parse_fails(SWEEP // SWEEP // "&parameter name = 'link.l1.E', values = 1 /", &
      [character(40) :: '&sweep', 'only once'], 'two &sweep groups')
    call parse_fails(SWEEP // "&param name = 'link.l1.E', values = 1 /", &
      [character(40) :: 'sweep.nml:2', 'unknown group &param'], 'unknown group in the sweep file')
    call parse_fails(SWEEP // "&parameter name = 'link.l1.E', values = 1, step = 2 /", &
      [character(40) :: "&parameter #1 'link.l1.E'", "unknown variable 'step'"], &
      'unknown &parameter variable')
    call parse_fails("&sweep base = 'b.nml', nodes = 'x' /" // NL // &
      "&parameter name = 'link.l1.E', values = 1 /", &
      [character(40) :: '&sweep', "unknown variable 'nodes'"], 'unknown &sweep variable')
    call parse_fails("&sweep mode = 'zip' /" // NL // "&parameter name = 'link.l1.E', values = 1 /", &
      [character(40) :: '&sweep', "'base'"], 'no base')
    call parse_fails("&sweep base = '' /" // NL // "&parameter name = 'link.l1.E', values = 1 /", &
      [character(40) :: '&sweep', "'base' is empty"], 'empty base')
    call parse_fails(SWEEP // "&parameter name = 'link.l1.E', values = 1, x /", &
      [character(40) :: "&parameter #1 'link.l1.E'", "'values'", "'x'"], 'value not a number')
    call parse_fails(SWEEP // "&parameter name = 'link.l1.E', 'link.l1.n_elements', " // &
      "values = 1 /", [character(40) :: "'link.l1.n_elements'", 'integer or all real'] , &
      'tied names of different types')
  end subroutine test_errors

  !> Errors found against the base scene (apply_case).
  subroutine test_base_errors()
    call base_fails("&parameter name = 'link.l9.E', values = 1 /", &
      [character(40) :: 'sweep.nml:2', '&parameter #1', "'link.l9.E'", "label 'l9'", &
      "'l1', 'l2'", 'base.nml'], 'unknown label')
    call base_fails("&parameter name = 'mass.a.m', values = 1 /", &
      [character(40) :: "'mass.a.m'", "node 'a'", "nodes: 'c'"], 'unknown &mass node')
    call base_fails("&parameter name = 'truss.t1.E', values = 1 /", &
      [character(40) :: "'truss.t1.E'", 'no &truss', "truss.t1"], 'no &truss at all')
    call base_fails("&parameter name = 'reduction.n_modes', values = 2 /", &
      [character(40) :: "'reduction.n_modes'", "'base.nml' has no &reduction group"], &
      'single group absent from the base')
    call base_fails("&parameter name = 'dynamic.rtol', values = 1e-6 /" // NL // &
      "&parameter name = 'static.tol', values = 1e-6 /", &
      [character(40) :: '&parameter #2', "'static.tol'", 'no &static'], &
      'second parameter names an absent group')
    call base_fails("&parameter name = 'mass.c.m', values = 1 /", &
      [character(40) :: "'mass.c.m'", '2 &mass groups', "node 'c'"], 'ambiguous key', &
      BASE_SCENE // "&mass node = 'c', m = 1 /" // NL)
  end subroutine test_base_errors

  !> Parameters on one entry of a list: that entry takes the case's value, the others stay.
  subroutine test_list_entries()
    type(sweep_spec_t) :: s
    type(scene_t) :: scene
    call parse_ok(s, SWEEP // &
      "&parameter name = 'scene.gravity(2)', values = -1.5, -3.25 /" // NL // &
      "&parameter name = ' motion.m1.values( 2 ) ', values = 0.125 /" // NL // &
      "&parameter name = 'motion.m1.values(3)', values = 0.75 /" // NL // &
      "&parameter name = 'motion.m1.times(2)', values = 0.375 /", 'list entries')
    call t%check(s%names(1)%s == 'scene.gravity(2)' .and. s%n_cases() == 2, &
      'names with an entry kept as given')
    if (.not. case_scene(s, LIST_SCENE, 2, scene, 'a case with list entries')) return
    call t%check(scene%gravity(1) == 0.5_wp .and. scene%gravity(2) == -3.25_wp, &
      'gravity(2) set, gravity(1) as the base has it')
    call t%check(all(scene%motions(1)%values == [0.0_wp, 0.125_wp, 0.75_wp]), &
      'two entries of one list, both set')
    call t%check(all(scene%motions(1)%times == [0.0_wp, 0.375_wp, 1.0_wp]), &
      'a second list of the same group')
  end subroutine test_list_entries

  !> Case icase of s written into the scene base_text and read by the scene reader: true if
  !> both worked (checked as `what`).
  logical function case_scene(s, base_text, icase, scene, what) result(ok)
    type(sweep_spec_t), intent(in) :: s
    character(len=*), intent(in) :: base_text, what
    integer, intent(in) :: icase
    type(scene_t), intent(out) :: scene
    type(nml_file_t) :: base, case_file
    type(error_t) :: err
    call base%parse(base_text, 'base.nml', err)
    if (err%ok()) call apply_case(s, base, icase, case_file, err)
    if (err%ok()) call read_scene(case_file, scene, err)
    ok = err%ok()
    call t%check(ok, what // ' reads')
    if (.not. ok) write(*, '(a)') '        ' // err%message
  end function case_scene

  !> Errors of a name with an entry: in the sweep file alone, and against the base scene.
  subroutine test_list_entry_errors()
    call parse_fails(SWEEP // "&parameter name = 'dynamic.rtol(1)', values = 1 /", &
      [character(40) :: 'sweep.nml:2', '&parameter #1', "'dynamic.rtol(1)'", "'rtol'", &
      'not a list', "without '(1)'"], 'entry of a scalar variable')
    call parse_fails(SWEEP // "&parameter name = 'scene.gravity(1.5)', values = 1 /", &
      [character(40) :: '&parameter #1', "'scene.gravity(1.5)'", "'(1.5)'", 'whole number'], &
      'non-integer entry')
    call parse_fails(SWEEP // "&parameter name = 'scene.gravity(-1)', values = 1 /", &
      [character(40) :: "'scene.gravity(-1)'", "'(-1)'", 'at least 1'], 'negative entry')
    call parse_fails(SWEEP // "&parameter name = 'scene.gravity()', values = 1 /", &
      [character(40) :: "'scene.gravity()'", "'()'", 'whole number'], 'empty entry')
    call parse_fails(SWEEP // "&parameter name = 'scene.gravity(0)', values = 1 /", &
      [character(40) :: '&parameter #1', "'scene.gravity(0)'", 'entry 0', 'count from 1'], &
      'entry 0')
    call parse_fails(SWEEP // "&parameter name = 'scene.gravity2)', values = 1 /", &
      [character(40) :: "'scene.gravity2)'", "without '('"], "')' without '('")
    call parse_fails(SWEEP // "&parameter name = 'scene.gravity(2)', values = 1 /" // NL // &
      "&parameter name = 'scene.gravity(1)', values = 2 /" // NL // &
      "&parameter name = 'Scene.Gravity(2)', values = 3 /", &
      [character(40) :: '&parameter #3', "'Scene.Gravity(2)'", "#1 'scene.gravity(2)'"], &
      'the same entry twice')
    call base_fails("&parameter name = 'scene.gravity(3)', values = 1 /", &
      [character(40) :: 'sweep.nml:2', '&parameter #1', "'scene.gravity(3)'", 'entry 3', &
      "'gravity'", "'base.nml'", 'has 2 entries'], 'entry beyond the base list', LIST_SCENE)
    call base_fails("&parameter name = 'motion.m1.times(1)', values = 1 /", &
      [character(40) :: '&parameter #1', "'motion.m1.times(1)'", "does not set 'times'", &
      "'base.nml'"], 'a list the base scene does not set')
  end subroutine test_list_entry_errors

  !> apply_case on the base scene must fail with a message containing `parts`.
  subroutine base_fails(params, parts, what, base_text)
    character(len=*), intent(in) :: params, parts(:), what
    character(len=*), intent(in), optional :: base_text
    type(sweep_spec_t) :: s
    type(nml_file_t) :: base_file, case_file
    type(error_t) :: err
    if (present(base_text)) then
      call base_file%parse(base_text, 'base.nml', err)
    else
      call base_file%parse(BASE_SCENE, 'base.nml', err)
    end if
    call s%parse(SWEEP // params, 'sweep.nml', err)
    call t%check(err%ok(), what // ': the sweep file parses')
    if (.not. err%ok()) write(*, '(a)') '        ' // err%message
    call apply_case(s, base_file, 1, case_file, err)
    call expect_error(err, parts, what)
  end subroutine base_fails
end program test_sweep_spec
