!> A program outside flexmor that uses it only through `use flexmor` (tests/downstream): a
!> cantilever built from scene text, once under a tip load (static) and once free (modal),
!> checked against the closed forms. Exits non-zero on any failure. Argument: the path of a
!> result file to write (optional).
program downstream
  use flexmor, only: wp, run_t, results_t, error_t, flexmor_version
  implicit none

  character(len=*), parameter :: NL = new_line('a')
  real(wp), parameter :: PI = 3.14159265358979323846_wp
  ! Aluminium strip; L is not 1 so that a wrong power of L shows.
  real(wp), parameter :: L_BEAM = 1.5_wp, E_MOD = 7.0e10_wp, AREA = 1.0e-4_wp, INER = 1.0e-9_wp, &
    RHO = 2700.0_wp, EI = E_MOD * INER
  integer, parameter :: N_EL = 4
  ! First root of 1 + cos(b) cosh(b) = 0 (clamped-free beam).
  real(wp), parameter :: BETA1_L = 1.8751040687119611_wp
  integer :: failures = 0

  write(*, '(a)') 'flexmor ' // flexmor_version()
  call check(len(flexmor_version()) >= 5 .and. index(flexmor_version(), '.') > 0, &
    'flexmor_version() is "major.minor.patch"')
  call static_tip()
  call modal_first()
  if (failures > 0) then
    write(*, '(i0,a)') failures, ' check(s) failed'
    error stop 1
  end if
  write(*, '(a)') 'all checks passed'

contains

  subroutine check(ok, what)
    logical, intent(in) :: ok
    character(len=*), intent(in) :: what
    write(*, '(a)') merge('  ok    ', '  FAIL  ', ok) // what
    if (.not. ok) failures = failures + 1
  end subroutine check

  !> Stop the program on an error from flexmor (its message names file, group and variable).
  subroutine require(err, what)
    type(error_t), intent(in) :: err
    character(len=*), intent(in) :: what
    if (err%ok()) return
    write(*, '(a,i0,a)') '  FAIL  ' // what // ': error ', err%code, ': ' // err%message
    error stop 2
  end subroutine require

  !> The cantilever along x, clamped at 'root', N_EL beam elements, plus `extra` groups.
  function cantilever(extra) result(t)
    character(len=*), intent(in) :: extra
    character(len=:), allocatable :: t
    character(len=200) :: props, tip
    write(props, '(a,i0,4(a,es23.16))') 'n_elements = ', N_EL, ', E = ', E_MOD, ', A = ', AREA, &
      ', I = ', INER, ', rho = ', RHO
    write(tip, '(a,es23.16,a)') "&node label = 'tip', x = ", L_BEAM, ', y = 0.0 /'
    t = "&scene title = 'downstream cantilever' /" // NL // &
      "&node label = 'root', x = 0.0, y = 0.0, fixed = .true. /" // NL // &
      trim(tip) // NL // &
      "&link label = 'beam', from = 'root', to = 'tip', " // trim(props) // " /" // NL // extra
  end function cantilever

  !> Tip load P: w = P L^3 / (3 EI), phi = P L^2 / (2 EI). Cubic beam elements reproduce the
  !> linear solution exactly; what remains is the geometric non-linearity, relative
  !> O((P L^2 / EI)^2) = 1e-7 at P L^2 / EI = 3e-4 (observed: 1e-8), and the Newton tolerance
  !> (1e-12 of L, 1e-8 of w): 1e-6 is a bound with a margin of 10 over the estimate.
  subroutine static_tip()
    real(wp), parameter :: K = 3.0e-4_wp, P = K * EI / L_BEAM**2, REL = 1.0e-6_wp
    type(run_t) :: run
    type(results_t) :: res
    type(error_t) :: err
    real(wp), allocatable :: pos(:, :), rot(:)
    real(wp) :: w_ref, phi_ref
    character(len=1024) :: out_path
    character(len=60) :: force
    logical :: written
    integer :: n
    write(force, '(a,es23.16,a)') "&force node = 'tip', fy = ", P, ' /'
    run%verbose = .false.
    call run%load_text(cantilever(trim(force) // NL // &
      '&static n_steps = 2, tol = 1.0e-12 /' // NL), 'static-cantilever', err)
    call require(err, 'load_text (static)')
    call run%execute(err)
    call require(err, 'execute (static)')
    call get_command_argument(1, out_path)
    if (len_trim(out_path) > 0) then
      call run%write(trim(out_path), err)
      call require(err, 'write ' // trim(out_path))
      inquire(file=trim(out_path), exist=written)
      call check(written, 'result file written: ' // trim(out_path))
    end if
    call res%from_run(run)
    call check(size(res%load_factor) == 2, 'two load steps')
    if (size(res%load_factor) /= 2) return
    call check(abs(res%load_factor(2) - 1.0_wp) < 1.0e-15_wp, 'last load factor 1')
    call check(size(res%time) == 0 .and. size(res%frequency_hz) == 0, &
      'no dynamic or modal results asked for, none given')
    call check(res%wall_time_s >= 0.0_wp, 'wall time measured')
    call res%node_position('tip', 'static', pos, err)
    call require(err, 'tip position')
    call res%node_rotation('tip', 'static', rot, err)
    call require(err, 'tip rotation')
    n = size(pos, 2)
    w_ref = P * L_BEAM**3 / (3 * EI)
    phi_ref = P * L_BEAM**2 / (2 * EI)
    write(*, '(a,es23.16,a,es10.2)') '  static: tip w   = ', pos(2, n), ' m,   relative error ', &
      pos(2, n) / w_ref - 1
    write(*, '(a,es23.16,a,es10.2)') '  static: tip phi = ', rot(n), ' rad, relative error ', &
      rot(n) / phi_ref - 1
    call check(abs(pos(2, n) / w_ref - 1) < REL, 'tip deflection = P L^3 / (3 EI)')
    call check(abs(rot(n) / phi_ref - 1) < REL, 'tip rotation = P L^2 / (2 EI)')
    ! Half the load at the first step: linear, so half the deflection.
    call check(abs(pos(2, 1) / (0.5_wp * w_ref) - 1) < REL, 'half load, half deflection')
    call res%node_position('nowhere', 'static', pos, err)
    call check(.not. err%ok(), 'an unknown node label is an error')
    call res%node_position('tip', 'dynamic', pos, err)
    call check(.not. err%ok(), 'positions of an analysis that did not run are an error')
  end subroutine static_tip

  !> f1 = (beta1 L)^2 / (2 pi L^2) sqrt(EI / (rho A)). Cubic elements with consistent mass
  !> give an upper bound converging as h^4: f_h / f - 1 = c (beta1 h)^4, c = 3.9e-4 for one
  !> element (closed form omega^2 = 12.48 EI / (m L^4) against 12.36), c = 6.8e-4 observed at
  !> h = L / 4 (3.3e-5). The bound (beta1 h)^4 / 100 = 4.8e-4 keeps a margin of 15.
  subroutine modal_first()
    type(run_t) :: run
    type(results_t) :: res
    type(error_t) :: err
    real(wp) :: f_ref, rel, bound
    run%verbose = .false.
    call run%load_text(cantilever('&modal n_modes = 3 /' // NL), 'modal-cantilever', err)
    call require(err, 'load_text (modal)')
    call run%execute(err)
    call require(err, 'execute (modal)')
    call res%from_run(run)
    call check(size(res%frequency_hz) == 3, 'three modes, as asked')
    if (size(res%frequency_hz) < 1) return
    f_ref = BETA1_L**2 / (2 * PI * L_BEAM**2) * sqrt(EI / (RHO * AREA))
    rel = res%frequency_hz(1) / f_ref - 1
    bound = (BETA1_L / N_EL)**4 / 100
    write(*, '(a,es23.16,a,es10.2,a,es9.2,a)') '  modal: f1 = ', res%frequency_hz(1), &
      ' Hz, relative error ', rel, ' (bound ', bound, ')'
    call check(rel > -1.0e-12_wp .and. rel < bound, 'f1 of the clamped-free beam: upper ' // &
      'bound within (beta1 h)^4 / 100')
  end subroutine modal_first
end program downstream
