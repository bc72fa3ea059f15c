!> User control laws through the library API (&controller law = 'user', control_law_t,
!> run%set_control_law): a PID written as a user law on a rigid two-link arm gives the same
!> motion as the built-in law = 'pid' (two SISO PIDs; one MIMO user law with two actuators,
!> two outputs and two states; a PID beside a user law), continuous and sampled; several runs
!> with their own laws in one process; the law of a shared library (&controller library) and
!> the program's law in its place; and every misuse gives a clear error.
module user_control_laws
  use flexmor, only: wp, control_law_t
  implicit none
  private
  public :: pid_law_t, failing_law_t

  !> Independent PIDs, channel i from measure i to actuator i, regulating to 0, with their
  !> integrals as the law's states: continuous (period = 0: dx/dt = e) or sampled as the
  !> built-in law (u from the integral before the sample, then x + T e).
  type, extends(control_law_t) :: pid_law_t
    real(wp), allocatable :: kp(:), ki(:), kd(:)
    real(wp) :: period = 0.0_wp
  contains
    procedure :: evaluate => pid_evaluate
  end type pid_law_t

  !> Returns `status` from t_fail on, and a NaN output when status is 0 there. (A recoverable
  !> status from a time on would make the integrator creep up to it in ever shorter steps.)
  type, extends(control_law_t) :: failing_law_t
    integer :: status = 0
    real(wp) :: t_fail = 0.0_wp
  contains
    procedure :: evaluate => failing_evaluate
  end type failing_law_t

contains

  subroutine pid_evaluate(this, t, y, y_dot, x, x_out, u, status)
    class(pid_law_t), intent(in) :: this
    real(wp), intent(in) :: t, y(:), y_dot(:), x(:)
    real(wp), intent(out) :: x_out(:), u(:)
    integer, intent(out) :: status
    u = this%kp * (-y) + this%ki * x + this%kd * (-y_dot)
    if (this%period > 0) then
      x_out = x + this%period * (-y)
    else
      x_out = -y
    end if
    status = 0
  end subroutine pid_evaluate

  subroutine failing_evaluate(this, t, y, y_dot, x, x_out, u, status)
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
    class(failing_law_t), intent(in) :: this
    real(wp), intent(in) :: t, y(:), y_dot(:), x(:)
    real(wp), intent(out) :: x_out(:), u(:)
    integer, intent(out) :: status
    x_out = 0.0_wp
    u = 0.0_wp
    status = 0
    if (t < this%t_fail) return
    status = this%status
    if (status == 0) u = ieee_value(1.0_wp, ieee_quiet_nan)
  end subroutine failing_evaluate
end module user_control_laws

program test_user_control
  use flexmor, only: wp, run_t, results_t, error_t, ERR_INPUT
  use user_control_laws, only: pid_law_t, failing_law_t
  use testing, only: suite_t
  use test_scenes, only: rtxt
  implicit none

  character(len=*), parameter :: NL = new_line('a')
  !> A rigid two-link arm (rigid links: the joint angles are the only coordinates) with
  !> constant disturbance torques on both joints, regulated to zero.
  character(len=*), parameter :: ARM = &
    "&node label = 'base', x = 0, y = 0, fixed = .true. /" // NL // &
    "&node label = 'elbow', x = 1, y = 0 /" // NL // &
    "&node label = 'tip', x = 1.6, y = 0 /" // NL // &
    "&link label = 'l1', from = 'base', to = 'elbow', n_elements = 1, E = 7e10, A = 1e-4, " // &
    "I = 1e-9, rho = 2700, elongation = 'rigid', bending = 'rigid' /" // NL // &
    "&link label = 'l2', from = 'elbow', to = 'tip', n_elements = 1, E = 7e10, A = 1e-4, " // &
    "I = 1e-9, rho = 2700, elongation = 'rigid', bending = 'rigid' /" // NL // &
    "&hinge label = 'j1', node = 'base', link = 'l1', mode = 'dynamic', torque = 0.05 /" // NL // &
    "&hinge label = 'j2', node = 'elbow', link = 'l2', mode = 'dynamic', torque = -0.02 /" // NL // &
    "&dynamic t_end = 3.0, output_dt = 0.05, integrator = 'bdf', rtol = 1e-9, atol = 1e-12 /" // NL
  real(wp), parameter :: KP(2) = [2.0_wp, 1.0_wp], KI(2) = [1.0_wp, 0.5_wp], &
    KD(2) = [0.5_wp, 0.3_wp]
  type(suite_t) :: t
  call t%init('user control laws (law = ''user'')')
  call same_as_pid(0.0_wp)
  call same_as_pid(0.01_wp)
  call misuse()
  call with_error_check()
  call library_laws()
  call t%finish()

contains

  function pid_groups(period) result(text)
    real(wp), intent(in) :: period
    character(len=:), allocatable :: text
    character(len=300) :: line
    integer :: i
    text = ''
    do i = 1, 2
      write(line, '(a,i0,a,i0,a,i0,3(a,es23.16),a,es23.16,a)') "&controller label = 'c", i, &
        "', actuator = 'j", i, ".torque', measure = 'j", i, ".angle', kp = ", KP(i), &
        ', ki = ', KI(i), ', kd = ', KD(i), ', period = ', period, ' /'
      text = text // trim(line) // NL
    end do
  end function pid_groups

  function user_group(label, joints, period) result(text)
    character(len=*), intent(in) :: label
    integer, intent(in) :: joints(:)
    real(wp), intent(in) :: period
    character(len=:), allocatable :: text
    character(len=40) :: p
    integer :: i
    write(p, '(es23.16)') period
    text = "&controller label = '" // label // "', law = 'user', actuator = "
    do i = 1, size(joints)
      text = text // merge("'j1.torque', ", "'j2.torque', ", joints(i) == 1)
    end do
    text = text // "measure = "
    do i = 1, size(joints)
      text = text // merge("'j1.angle', ", "'j2.angle', ", joints(i) == 1)
    end do
    text = text // "n_states = " // achar(iachar('0') + size(joints)) // ", period = " // &
      trim(p) // " /" // NL
  end function user_group

  !> Run `scene`, giving each label in `labels` the PID law on channels `channels`.
  subroutine run_scene(scene, name, labels, channels, period, run, err)
    character(len=*), intent(in) :: scene, name, labels(:)
    integer, intent(in) :: channels(:, :)  ! (2, size(labels)): first and last joint
    real(wp), intent(in) :: period
    type(run_t), intent(inout) :: run
    type(error_t), intent(out) :: err
    type(pid_law_t) :: law
    integer :: i
    run%verbose = .false.
    call run%load_text(scene, name, err)
    do i = 1, size(labels)
      if (.not. err%ok()) return
      law = pid_law_t(KP(channels(1, i):channels(2, i)), KI(channels(1, i):channels(2, i)), &
        KD(channels(1, i):channels(2, i)), period)
      call run%set_control_law(trim(labels(i)), law, err)
    end do
    if (err%ok()) call run%execute(err)
  end subroutine run_scene

  !> The tip's path under the built-in PIDs and under user laws doing the same. Both solve
  !> the same ODE with BDF at rtol 1e-9, atol 1e-12, but not bit for bit (continuous: the two
  !> paths reach the integrator by different code, so Newton iterates and step decisions
  !> may differ from one build or machine to the next), so the bound is the integrator's
  !> global error, not round-off: each path is within 1.1e-8 m (continuous) and 3e-10 m
  !> (sampled) of an rtol 1e-11 run, so two paths differ by at most ~2.2e-8 m; bound 10x that,
  !> 2e-7 m. Observed 8.9e-14 m (Release) and 2.9e-13 m (Debug) continuous, 0 sampled (the
  !> old 1e-12 m bound was within 3.4x of Debug). A wrong law (gain, sign, channel, a state
  !> not integrated) moves the tip by the disturbance response, > 1e-3 m (checked below).
  subroutine same_as_pid(period)
    real(wp), intent(in) :: period
    real(wp), parameter :: PATH_BOUND = 2.0e-7_wp   ! 10 x twice the global error [m]
    type(run_t) :: r_pid, r_mimo, r_mixed
    type(error_t) :: err
    real(wp), allocatable :: p_pid(:, :), p_mimo(:, :), p_mixed(:, :)
    character(len=:), allocatable :: what, pids
    logical :: ran
    what = merge('sampled   ', 'continuous', period > 0)
    pids = pid_groups(period)
    call run_scene(ARM // pid_groups(period), 'pid.nml', [character(len=3) ::], &
      reshape([integer ::], [2, 0]), period, r_pid, err)
    ran = err%ok()
    call t%check(err%ok(), trim(what) // ': two built-in PIDs run ' // msg(err))
    ! Both runs live in this process at once, each with its own law.
    call run_scene(ARM // user_group('ext', [1, 2], period), 'mimo.nml', ['ext'], &
      reshape([1, 2], [2, 1]), period, r_mimo, err)
    ran = ran .and. err%ok()
    call t%check(err%ok(), trim(what) // ': one 2x2 user law runs ' // msg(err))
    call run_scene(ARM // pids(1:index(pids, NL)) // &
      user_group('u2', [2], period), 'mixed.nml', ['u2'], reshape([2, 2], [2, 1]), period, &
      r_mixed, err)
    ran = ran .and. err%ok()
    call t%check(err%ok(), trim(what) // ': a PID beside a user law runs ' // msg(err))
    if (.not. ran) return
    p_pid = tip_path(r_pid)
    p_mimo = tip_path(r_mimo)
    p_mixed = tip_path(r_mixed)
    ! The disturbances move the tip before the integrals bring it back: a real comparison.
    call t%check(maxval(abs(p_pid(2, :))) > 1.0e-3_wp, trim(what) // ': the tip moves')
    call t%close_array(reshape(p_mimo, [size(p_mimo)]), reshape(p_pid, [size(p_pid)]), &
      0.0_wp, PATH_BOUND, trim(what) // ': MIMO user law = two PIDs')
    call t%close_array(reshape(p_mixed, [size(p_mixed)]), reshape(p_pid, [size(p_pid)]), &
      0.0_wp, PATH_BOUND, trim(what) // ': PID + user law = two PIDs')
  end subroutine same_as_pid

  !> The tip's positions at the output times of a run's dynamic analysis.
  function tip_path(run) result(p)
    type(run_t), intent(in) :: run
    real(wp), allocatable :: p(:, :)
    type(results_t) :: res
    type(error_t) :: err
    call res%from_run(run)
    call res%node_position('tip', 'dynamic', p, err)
    call t%check(err%ok(), 'the tip''s path ' // msg(err))
  end function tip_path

  !> &dynamic error_check: the second run calls the same user law (a copy). The PID law as a
  !> user law against itself at rtol 1e-10: the runs differ by the integrator's global error,
  !> ~1e-9 m at rtol 1e-9 (see same_as_pid); bound 1e-6 m, and above 0 (it was measured).
  !> Without the law the second run would stop with 'needs a control law'.
  subroutine with_error_check()
    type(run_t) :: run
    type(error_t) :: err
    character(len=:), allocatable :: scene
    integer :: at
    scene = ARM // user_group('ext', [1, 2], 0.0_wp)
    at = index(scene, 'atol = 1e-12 /')
    scene = scene(:at + 12) // ", error_check = 'tolerance' /" // scene(at + 14:)
    call run_scene(scene, 'check.nml', ['ext'], reshape([1, 2], [2, 1]), 0.0_wp, run, err)
    call t%check(err%ok(), 'error_check with a user law runs ' // msg(err))
    if (.not. err%ok()) return
    call t%check(allocated(run%check_distance), 'the check ran')
    if (.not. allocated(run%check_distance)) return
    call t%check(maxval(run%check_distance) > 0.0_wp .and. maxval(run%check_distance) < &
      1.0e-6_wp, 'the second run follows the same law (distance ' // &
      rtxt(maxval(run%check_distance)) // ' m)')
  end subroutine with_error_check

  !> &controller library (examples/c/pid_law.c, built by CTest: FLEXMOR_PID_LAW, else
  !> pid_law.so in the current folder): as two SISO laws with the PIDs' gains (params = kp,
  !> ki, kd, r = 0; the integral their state) it gives the built-in PIDs' motion, to the same
  !> bound as same_as_pid (the Jacobians of the two differ in the same way); and a law set by
  !> the program replaces a library's: with wrong gains in the scene (kp three times) the
  !> library laws alone move the tip elsewhere, the program's PID laws bring it back.
  subroutine library_laws()
    real(wp), parameter :: PATH_BOUND = 2.0e-7_wp   ! as in same_as_pid [m]
    type(run_t) :: r_pid, r_lib, r_wrong, r_set
    type(error_t) :: err
    real(wp), allocatable :: p_pid(:, :), p_lib(:, :), p_wrong(:, :), p_set(:, :)
    character(len=2), parameter :: LABELS(2) = ['c1', 'c2']
    logical :: ran
    call run_scene(ARM // pid_groups(0.0_wp), 'pid.nml', [character(len=3) ::], &
      reshape([integer ::], [2, 0]), 0.0_wp, r_pid, err)
    ran = err%ok()
    call run_scene(ARM // library_groups(1.0_wp), 'lib.nml', [character(len=3) ::], &
      reshape([integer ::], [2, 0]), 0.0_wp, r_lib, err)
    ran = ran .and. err%ok()
    call t%check(err%ok(), 'library laws run ' // msg(err))
    call run_scene(ARM // library_groups(3.0_wp), 'wrong.nml', [character(len=3) ::], &
      reshape([integer ::], [2, 0]), 0.0_wp, r_wrong, err)
    ran = ran .and. err%ok()
    call run_scene(ARM // library_groups(3.0_wp), 'set.nml', LABELS, &
      reshape([1, 1, 2, 2], [2, 2]), 0.0_wp, r_set, err)
    ran = ran .and. err%ok()
    call t%check(err%ok(), 'program laws over library laws run ' // msg(err))
    if (.not. ran) return
    p_pid = tip_path(r_pid)
    p_lib = tip_path(r_lib)
    p_wrong = tip_path(r_wrong)
    p_set = tip_path(r_set)
    call t%close_array(reshape(p_lib, [size(p_lib)]), reshape(p_pid, [size(p_pid)]), &
      0.0_wp, PATH_BOUND, 'library laws = two PIDs')
    call t%check(maxval(abs(p_wrong - p_pid)) > 1.0e-4_wp, 'kp x 3 in the library laws ' // &
      'moves the tip elsewhere (' // rtxt(maxval(abs(p_wrong - p_pid))) // ' m)')
    call t%close_array(reshape(p_set, [size(p_set)]), reshape(p_pid, [size(p_pid)]), &
      0.0_wp, PATH_BOUND, 'the program''s laws replace the library''s')
  end subroutine library_laws

  !> Two &controller groups, c1 and c2, on the joints with the law of the library pid_law.so
  !> and params = the PIDs' gains, kp times kp_factor.
  function library_groups(kp_factor) result(text)
    real(wp), intent(in) :: kp_factor
    character(len=:), allocatable :: text
    character(len=1024) :: path
    character(len=400) :: line
    integer :: i, n, stat
    call get_environment_variable('FLEXMOR_PID_LAW', path, n, stat)
    if (stat /= 0 .or. n == 0) path = 'pid_law.so'
    text = ''
    do i = 1, 2
      write(line, '(a,i0,a,i0,a,i0,a,3(es23.16,a))') "&controller label = 'c", i, &
        "', law = 'user', actuator = 'j", i, ".torque', measure = 'j", i, &
        ".angle', n_states = 1, symbol = 'pid_law', params = ", kp_factor * KP(i), ', ', &
        KI(i), ', ', KD(i), ', 0'
      text = text // trim(line) // ", library = '" // trim(path) // "' /" // NL
    end do
  end function library_groups

  subroutine misuse()
    type(run_t) :: run, run_pid
    type(error_t) :: err
    type(pid_law_t) :: law
    type(failing_law_t) :: bad
    character(len=:), allocatable :: scene
    scene = ARM // user_group('ext', [1, 2], 0.0_wp)
    law = pid_law_t(KP, KI, KD, 0.0_wp)
    run%verbose = .false.
    call run%load_text(scene, 'user.nml', err)
    call t%check(err%ok(), 'a user-law scene loads ' // msg(err))
    call run%execute(err)
    call t%check(err%code == ERR_INPUT .and. has(err, 'user.nml') .and. &
      has(err, '&controller ''ext''') .and. has(err, 'set_control_law'), &
      'no law set: ' // msg(err))
    call run%set_control_law('nope', law, err)
    call t%check(err%code == ERR_INPUT .and. has(err, '''nope''') .and. &
      has(err, '''ext'''), 'unknown label: ' // msg(err))
    call run_pid%load_text(ARM // pid_groups(0.0_wp), 'pid.nml', err)
    call run_pid%set_control_law('c1', law, err)
    call t%check(err%code == ERR_INPUT .and. has(err, '''c1''') .and. has(err, 'not ''user'''), &
      'a law on a PID: ' // msg(err))
    bad = failing_law_t(-2, 0.5_wp)
    call run_failing(scene, bad, 'failed (status -2)', 'fatal status')
    bad = failing_law_t(3, 0.0_wp)
    call run_failing(scene, bad, 'shorter step (status 3)', 'recoverable status for good')
    bad = failing_law_t(0, 0.0_wp)
    call run_failing(scene, bad, 'not finite', 'NaN output')
    call run_failing(ARM // user_group('ext', [1, 2], 0.01_wp), bad, 'not finite', &
      'NaN output, sampled')
  end subroutine misuse

  subroutine run_failing(scene, law, fragment, what)
    character(len=*), intent(in) :: scene, fragment, what
    type(failing_law_t), intent(in) :: law
    type(run_t) :: run
    type(error_t) :: err
    run%verbose = .false.
    call run%load_text(scene, 'fail.nml', err)
    if (err%ok()) call run%set_control_law('ext', law, err)
    if (err%ok()) call run%execute(err)
    call t%check(.not. err%ok() .and. has(err, '&controller ''ext''') .and. &
      has(err, fragment), what // ': ' // msg(err))
  end subroutine run_failing

  logical function has(err, fragment)
    type(error_t), intent(in) :: err
    character(len=*), intent(in) :: fragment
    has = .false.
    if (allocated(err%message)) has = index(err%message, fragment) > 0
  end function has

  function msg(err) result(text)
    type(error_t), intent(in) :: err
    character(len=:), allocatable :: text
    text = ''
    if (allocated(err%message)) text = '(' // err%message // ')'
  end function msg
end program test_user_control
