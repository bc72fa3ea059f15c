program test_namelist
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_INPUT, ERR_INTERNAL
  use io_namelist, only: nml_file_t, nml_group_t, string_t
  use io_fields, only: rd_enum
  use model_scene, only: UPDATE_NAMES, UPDATE_MAC, UPDATE_NONE, INTEGRATOR_NAMES, &
    INTEGRATOR_AUTO, INTEGRATOR_GALPHA_ADAPTIVE, JACOBIAN_NAMES, JACOBIAN_LINEARISED, &
    JACOBIAN_INTERNAL, STATIC_METHOD_NAMES, STATIC_LOAD, STATIC_ARC_LENGTH
  use testing, only: suite_t
  implicit none
  character(*), parameter :: NL = new_line('a')
  type(suite_t) :: t

  call t%init('namelist parser')
  call test_values()
  call test_arrays()
  call test_strings()
  call test_groups()
  call test_defaults_and_used()
  call test_set_raw()
  call test_getter_errors()
  call test_parse_errors()
  call test_load()
  call test_enum()
  call t%finish()

contains

  !> Parse text that must be valid.
  subroutine parse_ok(f, text)
    type(nml_file_t), intent(inout) :: f
    character(*), intent(in) :: text
    type(error_t) :: err
    integer :: eol
    eol = index(text // NL, NL) - 1
    call f%parse(text, 'scene.nml', err)
    call t%check(err%ok(), 'parses: ' // text(1:min(40, eol)))
    if (.not. err%ok()) write(*, '(a)') '        ' // err%message
  end subroutine parse_ok

  !> Parse text that must fail with a message containing each of `parts`.
  subroutine parse_fails(text, parts, what)
    character(*), intent(in) :: text, parts(:), what
    type(nml_file_t) :: f
    type(error_t) :: err
    call f%parse(text, 'scene.nml', err)
    call expect_error(err, parts, what)
  end subroutine parse_fails

  subroutine expect_error(err, parts, what)
    type(error_t), intent(in) :: err
    character(*), intent(in) :: parts(:), what
    logical :: good
    integer :: i
    good = .not. err%ok()
    if (good) good = err%code == ERR_INPUT .and. index(err%message, new_line('a')) == 0
    do i = 1, size(parts)
      if (good) good = index(err%message, trim(parts(i))) > 0
    end do
    call t%check(good, what)
    if (.not. err%ok()) then
      write(*, '(a)') '        -> ' // err%message
    end if
  end subroutine expect_error

  subroutine test_values()
    type(nml_file_t) :: f
    type(error_t) :: err
    real(wp) :: x
    integer :: n
    logical :: b
    integer :: k
    call parse_ok(f, '&Dyn' // NL // &
      '  a = 1, b = 1.5 c=-2e-3' // NL // &
      '  D = 7.3d10, e = .5  ! a comment' // NL // &
      '  n = -42 m = +7' // NL // &
      '  l1 = .true. l2 = .FALSE. l3 = T l4 = f l5 = .t. l6 = .F.' // NL // &
      '/')
    k = f%group_index('dyn', 1)
    call t%check(k == 1 .and. f%count('DYN') == 1, 'group name is case-insensitive')
    associate (g => f%groups(k))
      call t%check(g%name == 'dyn' .and. g%line == 1 .and. g%occurrence == 1, 'group metadata')
      call g%get_real('a', x, err)
      call t%close(x, 1.0_wp, 0.0_wp, 0.0_wp, 'integer text read as real')
      call g%get_real('B', x, err)
      call t%close(x, 1.5_wp, 0.0_wp, 0.0_wp, 'real, variable name case-insensitive')
      call g%get_real('c', x, err)
      call t%close(x, -2e-3_wp, 1e-15_wp, 0.0_wp, 'negative with exponent')
      call g%get_real('d', x, err)
      call t%close(x, 7.3e10_wp, 1e-15_wp, 0.0_wp, 'd exponent, upper-case name in file')
      call g%get_real('e', x, err)
      call t%close(x, 0.5_wp, 0.0_wp, 0.0_wp, 'leading dot')
      call g%get_int('n', n, err)
      call t%check(err%ok() .and. n == -42, 'negative integer')
      call g%get_int('m', n, err)
      call t%check(err%ok() .and. n == 7, 'integer with plus sign')
      call g%get_logical('l1', b, err)
      call t%check(err%ok() .and. b, '.true.')
      call g%get_logical('l2', b, err)
      call t%check(err%ok() .and. .not. b, '.FALSE.')
      call g%get_logical('l3', b, err)
      call t%check(err%ok() .and. b, 'T')
      call g%get_logical('l4', b, err)
      call t%check(err%ok() .and. .not. b, 'f')
      call g%get_logical('l5', b, err)
      call t%check(err%ok() .and. b, '.t.')
      call g%get_logical('l6', b, err)
      call t%check(err%ok() .and. .not. b, '.F.')
      call t%check(g%has('A') .and. .not. g%has('zz'), 'has')
      call t%check(g%where() == 'scene.nml:1: group &dyn #1', 'where: ' // g%where())
      call g%check_all_used(err)
      call t%check(err%ok(), 'every variable was read')
    end associate
  end subroutine test_values

  subroutine test_arrays()
    type(nml_file_t) :: f
    type(error_t) :: err
    real(wp), allocatable :: v(:)
    integer, allocatable :: iv(:)
    integer :: n
    call parse_ok(f, '&arr' // NL // &
      '  x = 1.0, 2.0,' // NL // &
      '      3.0   ! continued' // NL // &
      '      4' // NL // &
      '  z = 3*0.0, 2*1.5 7' // NL // &
      '  i = 1 2 2*3' // NL // &
      '  s = 1.0' // NL // &
      '  long = 1 2 3 4 5 6 7 8 9 10 11 /')
    associate (g => f%groups(1))
      call g%get_real_array('x', v, err)
      call t%check(err%ok(), 'multi-line array read')
      call t%close_array(v, [1.0_wp, 2.0_wp, 3.0_wp, 4.0_wp], 0.0_wp, 0.0_wp, 'multi-line array')
      call g%get_real_array('z', v, err)
      call t%close_array(v, [0.0_wp, 0.0_wp, 0.0_wp, 1.5_wp, 1.5_wp, 7.0_wp], 0.0_wp, 0.0_wp, &
        'repeat counts')
      call g%get_int_array('i', iv, err)
      call t%check(err%ok() .and. size(iv) == 4, 'integer array size')
      if (size(iv) == 4) call t%check(all(iv == [1, 2, 3, 3]), 'integer array with repeat')
      call g%get_real_array('s', v, err)
      call t%check(err%ok() .and. size(v) == 1, 'a scalar is an array of one')
      call g%get_int_array('long', iv, err)
      call t%check(err%ok() .and. size(iv) == 11, 'a longer list; / right after')
      if (size(iv) == 11) call t%check(all(iv == [(n, n = 1, 11)]), 'longer list values')
    end associate
  end subroutine test_arrays

  subroutine test_strings()
    type(nml_file_t) :: f
    type(error_t) :: err
    character(:), allocatable :: s
    type(string_t), allocatable :: l(:)
    call parse_ok(f, '&str' // NL // &
      '  a = ''hello! not a comment'' ! a real comment' // NL // &
      '  b = "it''s" c = ''it''''s'' d = "say ""hi"""' // NL // &
      '  e = ''a/b, c = &d''' // NL // &
      '  names = ''one'', "two"' // NL // &
      '          2*''x''' // NL // &
      '  empty = '''' /')
    associate (g => f%groups(1))
      call g%get_string('a', s, err)
      call t%check(err%ok() .and. s == 'hello! not a comment', '! inside a string: ' // s)
      call g%get_string('b', s, err)
      call t%check(s == "it's", 'other quote inside a string')
      call g%get_string('c', s, err)
      call t%check(s == "it's", 'doubled single quote: ' // s)
      call g%get_string('d', s, err)
      call t%check(s == 'say "hi"', 'doubled double quote: ' // s)
      call g%get_string('e', s, err)
      call t%check(s == 'a/b, c = &d', 'separators inside a string')
      call g%get_string('empty', s, err)
      call t%check(err%ok() .and. len(s) == 0, 'empty string')
      call g%get_string_array('names', l, err)
      call t%check(err%ok() .and. size(l) == 4, 'string array size with repeat')
      if (size(l) == 4) call t%check(l(1)%s == 'one' .and. l(2)%s == 'two' .and. &
        l(3)%s == 'x' .and. l(4)%s == 'x', 'string array values')
    end associate
  end subroutine test_strings

  subroutine test_groups()
    type(nml_file_t) :: f
    type(error_t) :: err
    real(wp) :: x
    integer :: k
    character(:), allocatable :: s
    character(*), parameter :: CRLF = achar(13) // achar(10)
    call parse_ok(f, '! notes before the groups: it''s fine ! & in a comment' // NL // &
      '&node x = 1 /' // NL // &
      '   ! between groups' // NL // &
      '&LINK e = 2 /' // NL // &
      '&Node x = 3,' // NL // &
      '/' // NL // &
      '&old x = 4 &end' // NL // &
      '! trailing comment')
    call t%check(size(f%groups) == 4, 'four groups')
    call t%check(f%count('node') == 2 .and. f%count('link') == 1 .and. f%count('foo') == 0, &
      'count')
    k = f%group_index('NODE', 2)
    call t%check(k == 3, 'group_index of the second &node')
    if (k == 3) then
      call f%groups(k)%get_real('x', x, err)
      call t%close(x, 3.0_wp, 0.0_wp, 0.0_wp, 'value from the second occurrence')
      call t%check(f%groups(k)%occurrence == 2 .and. f%groups(k)%line == 5, &
        'occurrence and line of the second &node')
      call t%check(f%groups(k)%where() == 'scene.nml:5: group &node #2', f%groups(k)%where())
    end if
    call t%check(f%group_index('node', 3) == 0 .and. f%group_index('foo', 1) == 0, &
      'group_index of a missing occurrence is 0')
    call f%check_known_groups([character(4) :: 'node', 'link', 'old'], err)
    call t%check(err%ok(), 'all groups known')
    call f%check_known_groups([character(4) :: 'node', 'old'], err)
    call expect_error(err, [character(40) :: 'scene.nml:4: unknown group &link'], &
      'unknown group')
    call parse_ok(f, '! only comments' // NL // '  ! and more')
    call t%check(size(f%groups) == 0 .and. f%count('node') == 0, 'no groups at all')
    call parse_ok(f, '&g' // CRLF // ' a = ''x''' // CRLF // ' b = 2' // CRLF // '/' // CRLF)
    call f%groups(1)%get_string('a', s, err)
    call t%check(err%ok() .and. s == 'x', 'CRLF line ends')
    call f%groups(1)%get_real('b', x, err)
    call t%check(err%ok() .and. index(f%groups(1)%where(), ':1:') > 0, 'CRLF line numbers')
  end subroutine test_groups

  subroutine test_defaults_and_used()
    type(nml_file_t) :: f
    type(error_t) :: err
    real(wp) :: x
    integer :: n
    logical :: b
    character(:), allocatable :: s
    real(wp), allocatable :: v(:)
    type(string_t), allocatable :: l(:)
    call parse_ok(f, NL // NL // '&dynamic' // NL // '  t_end = 2.0' // NL // '  dtt = 0.1 /')
    associate (g => f%groups(1))
      call g%get_real('dt', x, err, default=0.25_wp)
      call t%check(err%ok(), 'real default, no error')
      call t%close(x, 0.25_wp, 0.0_wp, 0.0_wp, 'real default')
      call g%get_int('steps', n, err, default=10)
      call t%check(err%ok() .and. n == 10, 'integer default')
      call g%get_logical('verbose', b, err, default=.true.)
      call t%check(err%ok() .and. b, 'logical default')
      call g%get_string('method', s, err, default='rk4')
      call t%check(err%ok() .and. s == 'rk4', 'string default')
      call g%get_real_array('v', v, err, default=[1.0_wp, 2.0_wp])
      call t%check(err%ok() .and. size(v) == 2, 'array default')
      call g%get_string_array('l', l, err, default=[string_t('a')])
      call t%check(err%ok() .and. size(l) == 1, 'string array default')
      call g%get_real('t_end', x, err, default=9.0_wp)
      call t%close(x, 2.0_wp, 0.0_wp, 0.0_wp, 'a given value beats the default')
      call g%get_real('tmax', x, err)
      call expect_error(err, [character(80) :: &
        "scene.nml:3: group &dynamic #1: missing required variable 'tmax'"], 'missing required')
      call g%check_all_used(err)
      call expect_error(err, [character(80) :: &
        "scene.nml:5: group &dynamic #1: unknown variable 'dtt'"], 'check_all_used')
    end associate
  end subroutine test_defaults_and_used

  subroutine test_set_raw()
    type(nml_file_t) :: f
    type(error_t) :: err
    real(wp) :: x
    real(wp), allocatable :: v(:)
    character(:), allocatable :: s
    call parse_ok(f, '&link e = 70 /')
    associate (g => f%groups(1))
      call g%set_raw('E', '2.5', err)
      call t%check(err%ok(), 'set_raw replaces')
      call g%get_real('e', x, err)
      call t%close(x, 2.5_wp, 0.0_wp, 0.0_wp, 'replaced value')
      call g%set_raw('rho', '1, 2*3.0', err)
      call g%get_real_array('rho', v, err)
      call t%close_array(v, [1.0_wp, 3.0_wp, 3.0_wp], 0.0_wp, 0.0_wp, 'set_raw adds a list')
      call g%set_raw('name', '''a b''', err)
      call g%get_string('name', s, err)
      call t%check(err%ok() .and. s == 'a b', 'set_raw string')
      call g%set_raw('nu', 'abc', err)
      call t%check(err%ok(), 'set_raw does not type-check')
      call g%get_real('nu', x, err)
      call expect_error(err, [character(60) :: "variable 'nu' (set by override)", &
        "expected a real number, got 'abc'"], 'override named in a getter error')
      call g%set_raw('nu', '1,,2', err)
      call expect_error(err, [character(40) :: "variable 'nu'", 'empty value'], 'set_raw ,,')
      call g%set_raw('nu', '', err)
      call expect_error(err, [character(40) :: 'empty value'], 'set_raw empty text')
      call g%set_raw('nu', '1 / 2', err)
      call expect_error(err, [character(40) :: "unexpected '/'"], 'set_raw with /')
      call g%set_raw('nu', '''abc', err)
      call expect_error(err, [character(40) :: 'unterminated string'], 'set_raw unterminated')
      call g%set_raw('nu(2)', '1', err)
      call expect_error(err, [character(40) :: 'indexed', 'not supported'], 'set_raw indexed')
      call g%set_raw('typo', '1', err)
      call g%check_all_used(err)
      call expect_error(err, [character(40) :: "unknown variable 'typo'"], &
        'an unused override is reported')
    end associate
  end subroutine test_set_raw

  subroutine test_getter_errors()
    type(nml_file_t) :: f
    type(error_t) :: err
    real(wp) :: x
    integer :: n
    logical :: b
    character(:), allocatable :: s
    real(wp), allocatable :: v(:)
    type(string_t), allocatable :: l(:)
    call parse_ok(f, '&link e = 1 /' // NL // '&link' // NL // NL // &
      '  e = abc' // NL // '  x = 1, 2, 3' // NL // '  r = 3*1.0' // NL // &
      '  i = 1.5 big = 99999999999 ok = 2' // NL // &
      '  nan = NaN inf = -Inf' // NL // '  huge = 1e400 tiny = 1e-400 bad = 1.5.3 ee = 1e' // NL // &
      '  lg = yes lq = ''T''' // NL // '  s = unquoted q = ''1.5''' // NL // &
      '  arr = 1, 2, x3 sarr = ''a'' b' // NL // '/')
    associate (g => f%groups(2))
      call g%get_real('e', x, err)
      call expect_error(err, [character(80) :: &
        "scene.nml:4: group &link #2: variable 'e': expected a real number, got 'abc'"], &
        'real type error names file, line, group, occurrence, variable')
      call g%get_real('x', x, err)
      call expect_error(err, [character(80) :: &
        "scene.nml:5: group &link #2: variable 'x': expected one value, got 3"], 'scalar from list')
      call g%get_real('r', x, err)
      call expect_error(err, [character(40) :: 'expected one value, got 3'], 'scalar from 3*')
      call g%get_int('i', n, err)
      call expect_error(err, [character(60) :: "variable 'i': expected an integer, got '1.5'"], &
        'integer getter rejects 1.5')
      call g%get_int('big', n, err)
      call expect_error(err, [character(40) :: 'integer out of range'], 'integer overflow')
      call g%get_int('ok', n, err)
      call t%check(err%ok() .and. n == 2, 'values after an error still read')
      call g%get_real('nan', x, err)
      call expect_error(err, [character(60) :: "expected a finite real number, got 'NaN'"], 'NaN')
      call g%get_real('inf', x, err)
      call expect_error(err, [character(60) :: "expected a finite real number, got '-Inf'"], 'Inf')
      call g%get_real('huge', x, err)
      call expect_error(err, [character(40) :: 'out of range'], '1e400 (no FP trap)')
      call g%get_real('tiny', x, err)
      call t%check(err%ok(), '1e-400 is accepted')
      call t%close(x, 0.0_wp, 0.0_wp, 1e-300_wp, '1e-400 underflows to zero')
      call g%get_real('bad', x, err)
      call expect_error(err, [character(40) :: 'expected a real number'], '1.5.3')
      call g%get_real('ee', x, err)
      call expect_error(err, [character(40) :: 'expected a real number'], '1e')
      call g%get_logical('lg', b, err)
      call expect_error(err, [character(60) :: "variable 'lg': expected a logical", "'yes'"], &
        'bad logical')
      call g%get_logical('lq', b, err)
      call expect_error(err, [character(60) :: "expected a logical", "string 'T'"], &
        'quoted logical')
      call g%get_string('s', s, err)
      call expect_error(err, [character(60) :: "expected a quoted string, got 'unquoted'"], &
        'unquoted string')
      call g%get_real('q', x, err)
      call expect_error(err, [character(60) :: "expected a real number, got string '1.5'"], &
        'quoted number')
      call g%get_real_array('arr', v, err)
      call expect_error(err, [character(60) :: "variable 'arr': value 3: expected a real number"], &
        'bad array element')
      call g%get_string_array('sarr', l, err)
      call expect_error(err, [character(60) :: "value 2: expected a quoted string"], &
        'bad string array element')
    end associate
  end subroutine test_getter_errors

  subroutine test_parse_errors()
    call parse_fails('&g' // NL // ' s = ''abc' // NL // ' t = 1 /', &
      [character(40) :: 'scene.nml:2: group &g #1', 'unterminated string'], 'unterminated string')
    call parse_fails('&g a = 1 /' // NL // 'x = 1' // NL // '&h b = 2 /', &
      [character(40) :: 'scene.nml:2:', 'text outside a group', '''x = 1'''], 'loose text')
    call parse_fails('&g a = 1 / b = 2', [character(40) :: 'scene.nml:1:', '''b = 2'''], &
      'a value after the closing slash')
    call parse_fails('g a = 1 /', [character(40) :: 'scene.nml:1:', '''g a = 1 /'''], &
      'a group without its ampersand')
    call parse_fails(NL // '$g a = 1 $end', [character(40) :: 'scene.nml:2:', '''$'''], &
      'dollar groups')
    call parse_fails('&g a = 1' // NL // NL, &
      [character(60) :: "scene.nml:1: group &g #1: missing closing '/'"], 'no closing / at EOF')
    call parse_fails('&g a = 1' // NL // '&h b = 2 /', &
      [character(80) :: "scene.nml:1: group &g #1: missing closing '/' before &h on line 2"], &
      'no closing / before the next group')
    call parse_fails('&g' // NL // '  a 1 /', &
      [character(60) :: "scene.nml:2: group &g #1: '=' missing after 'a'"], '= missing')
    call parse_fails('&g a = 1 /' // NL // '&g' // NL // ' a = 1' // NL // ' A = 2 /', &
      [character(80) :: "scene.nml:4: group &g #2: variable 'a' assigned twice (first on line 3)"], &
      'assigned twice')
    call parse_fails('&g a = /', [character(60) :: "scene.nml:1: group &g #1: variable 'a'", &
      'empty value'], 'empty value before /')
    call parse_fails('&g a = , b = 1 /', [character(40) :: 'empty value'], 'empty value ,')
    call parse_fails('&g a = b = 1 /', [character(40) :: "variable 'a': empty value"], &
      'empty value before the next name')
    call parse_fails('&g a = 1,, 2 /', [character(40) :: 'empty value'], 'empty value in a list')
    call parse_fails('&g a = 3* /', [character(40) :: 'empty value'], 'repeat without value')
    call parse_fails('&g a = x*2 /', [character(40) :: 'bad repeat count'], 'bad repeat count')
    call parse_fails('&g a = 0*2 /', [character(40) :: 'bad repeat count'], 'zero repeat count')
    call parse_fails('&g a = 0*''s'' /', [character(40) :: 'bad repeat count'], &
      'zero repeat count on a string')
    call parse_fails('&g' // NL // ' x(2) = 1.0 /', [character(80) :: 'scene.nml:2: group &g #1', &
      "indexed assignment 'x(2)' is not supported"], 'indexed assignment')
    call parse_fails('&g 1x = 1 /', [character(60) :: "invalid variable name '1x'"], 'bad name')
    call parse_fails('&g = 1 /', [character(60) :: "expected a variable name, got '='"], &
      '= without a name')
    call parse_fails('& g a = 1 /', [character(60) :: "scene.nml:1: expected a group name"], &
      '& without a name')
  end subroutine test_parse_errors

  subroutine test_load()
    type(nml_file_t) :: f
    type(error_t) :: err
    character(*), parameter :: path = 'test_namelist_tmp.nml'
    character(*), parameter :: text = '! scene' // NL // '&node x = 1.5 /' // NL
    integer :: u
    real(wp) :: x
    call f%load('nope.nml', err)
    call expect_error(err, [character(60) :: "cannot open input file 'nope.nml': ", &
      'No such file'], 'missing file')
    open(newunit=u, file=path, status='replace', access='stream', form='unformatted')
    write(u) text
    close(u)
    call f%load(path, err)
    call t%check(err%ok(), 'load a file')
    call t%check(f%text == text .and. f%path == path, 'the text is kept as read')
    call t%check(f%count('node') == 1, 'loaded group')
    if (f%count('node') == 1) then
      call f%groups(1)%get_real('x', x, err)
      call t%close(x, 1.5_wp, 0.0_wp, 0.0_wp, 'loaded value')
      call t%check(f%groups(1)%where() == path // ':2: group &node #1', 'path in where()')
    end if
    open(newunit=u, file=path, status='old')
    close(u, status='delete')
  end subroutine test_load

  !> A keyword read as an enum (io_fields' rd_enum): its constant, the schema's default, a
  !> clear error for a bad keyword, and the program's names checked against the schema's.
  subroutine test_enum()
    type(nml_file_t) :: f
    type(error_t) :: err
    integer :: mode
    call parse_ok(f, '&reduction n_modes = 2, update = ''MAC'' /' // NL // &
      '&reduction n_modes = 2 /' // NL // '&reduction n_modes = 2, update = ''often'' /')
    mode = 0
    call rd_enum(f%groups(1), 'update', UPDATE_NAMES, mode, err)
    call t%check(err%ok() .and. mode == UPDATE_MAC, 'enum of a keyword (case folded)')
    call rd_enum(f%groups(2), 'update', UPDATE_NAMES, mode, err)
    call t%check(err%ok() .and. mode == UPDATE_NONE, 'enum of the schema''s default')
    call rd_enum(f%groups(3), 'update', UPDATE_NAMES, mode, err)
    call expect_error(err, [character(30) :: '''update''', 'often', 'interval'], &
      'bad keyword named with the choices')
    call err%clear()
    call rd_enum(f%groups(1), 'update', [character(8) :: 'none', 'interval'], mode, err)
    call t%check(err%code == ERR_INTERNAL .and. index(err%message, 'update') > 0, &
      'names that are not the schema''s choices: an internal error')
    if (.not. err%ok()) write(*, '(a)') '        -> ' // err%message
    call err%clear()

    ! &dynamic integrator and jacobian, &static method: given and by default.
    call parse_ok(f, '&dynamic t_end = 1, integrator = ''Galpha_Adaptive'', ' // &
      'jacobian = ''internal'' /' // NL // '&dynamic t_end = 1 /' // NL // &
      '&static method = ''arc_length'' /' // NL // '&static /')
    call expect_enum(f%groups(1), 'integrator', INTEGRATOR_NAMES, INTEGRATOR_GALPHA_ADAPTIVE)
    call expect_enum(f%groups(2), 'integrator', INTEGRATOR_NAMES, INTEGRATOR_AUTO)
    call expect_enum(f%groups(1), 'jacobian', JACOBIAN_NAMES, JACOBIAN_INTERNAL)
    call expect_enum(f%groups(2), 'jacobian', JACOBIAN_NAMES, JACOBIAN_LINEARISED)
    call expect_enum(f%groups(3), 'method', STATIC_METHOD_NAMES, STATIC_ARC_LENGTH)
    call expect_enum(f%groups(4), 'method', STATIC_METHOD_NAMES, STATIC_LOAD)
    ! A name missing or misspelt in the program's list: reported, whatever the input says.
    call expect_mismatch(f%groups(2), 'integrator', INTEGRATOR_NAMES(2:))
    call expect_mismatch(f%groups(2), 'jacobian', [character(10) :: 'linearised', 'fd', &
      'cvode'])
    call expect_mismatch(f%groups(4), 'method', [character(10) :: 'load', 'arc_length', &
      'riks'])
  end subroutine test_enum

  subroutine expect_enum(g, var, names, expected)
    type(nml_group_t), intent(inout) :: g
    character(*), intent(in) :: var, names(:)
    integer, intent(in) :: expected
    type(error_t) :: err
    integer :: value
    value = 0
    call rd_enum(g, var, names, value, err)
    call t%check(err%ok() .and. value == expected, 'enum of &' // g%name // ' ' // var // &
      ' = ''' // trim(names(max(expected, 1))) // '''')
    if (.not. err%ok()) write(*, '(a)') '        -> ' // err%message
  end subroutine expect_enum

  subroutine expect_mismatch(g, var, names)
    type(nml_group_t), intent(inout) :: g
    character(*), intent(in) :: var, names(:)
    type(error_t) :: err
    integer :: value
    value = 0
    call rd_enum(g, var, names, value, err)
    call t%check(err%code == ERR_INTERNAL .and. index(err%message, '''' // var // '''') > 0 &
      .and. value == 0, '&' // g%name // ' ' // var // ': names that are not the ' // &
      'schema''s choices: an internal error')
  end subroutine expect_mismatch
end program test_namelist
