!> Stability of static equilibria (dynamics_static: stable_tangent, static_solve's `stable`):
!>  - stable_tangent on small matrices: positive definite, indefinite, a neutral direction
!>    (a dynamic coordinate without stiffness) and round-off around zero;
!>  - a cantilever compressed to 1.1 times its buckling load P_cr = pi^2 EI / (4 L^2) on the
!>    straight (trivial) branch in 20 and in 50 load steps: exactly the steps below the
!>    discretised model's P_cr are stable; 0.9 P_cr gives only stable steps;
!>  - /static/stable in the result file of a run, and the stable flags of a pinned strut.
program test_static_stability
  use hdf5, only: hid_t, h5open_f, h5fopen_f, h5fclose_f, H5F_ACC_RDONLY_F
  use core_kinds, only: wp
  use core_error, only: error_t
  use core_linalg, only: sym_gen_eig
  use model_scene, only: scene_t
  use dynamics_system, only: dynamics_t
  use dynamics_static, only: tangent_stiffness, static_solve, stable_tangent, STABILITY_MARGIN
  use analysis_run, only: run_t
  use testing, only: suite_t
  use test_scenes, only: rtxt, itxt, make => make_dynamics, run_to_file
  use h5_read, only: read_int, scratch_dir, random_tag, msg
  implicit none

  character(len=*), parameter :: NL = new_line('a')
  real(wp), parameter :: PI = 3.14159265358979323846_wp
  real(wp), parameter :: LEN = 1.5_wp, E_MOD = 7.0e10_wp, AREA = 1.0e-4_wp, INER = 1.0e-9_wp, &
    RHO = 2700.0_wp
  real(wp), parameter :: P_EXACT = PI**2 * E_MOD * INER / (4 * LEN**2)
  !> Elements: the discretised P_cr is then within 0.1 % of P_EXACT (checked below).
  integer, parameter :: N_EL = 4

  type(suite_t) :: suite
  real(wp) :: p_cr

  call suite%init('static stability (tangent stiffness positive definite)')
  call matrices()
  p_cr = discrete_critical_load()
  if (p_cr > 0) then
    call load_stepping(20, 1.1_wp, p_cr)
    call load_stepping(50, 1.1_wp, p_cr)
    call load_stepping(20, 0.9_wp, p_cr)
  end if
  call result_file()
  call pinned_strut()
  call suite%finish()

contains

  !> Cantilever along x, root fixed, inextensible (so the compressed straight state is the
  !> reference itself and K_T(P) = S - P G holds exactly), tip load fx; `extra` appended.
  function cantilever(n, fx, extra) result(t)
    integer, intent(in) :: n
    real(wp), intent(in) :: fx
    character(len=*), intent(in) :: extra
    character(len=:), allocatable :: t
    t = "&scene title = 'compressed cantilever' /" // NL // &
      "&node label = 'root', x = 0.0, y = 0.0, fixed = .true. /" // NL // &
      "&node label = 'tip', x = " // rtxt(LEN) // ", y = 0.0 /" // NL // &
      "&link label = 'beam', from = 'root', to = 'tip', n_elements = " // itxt(n) // "," // NL // &
      "      E = " // rtxt(E_MOD) // ", A = " // rtxt(AREA) // ", I = " // rtxt(INER) // &
      ", rho = " // rtxt(RHO) // ", elongation = 'rigid' /" // NL // &
      "&force node = 'tip', fx = " // rtxt(fx) // " /" // NL // extra
  end function cantilever

  subroutine matrices()
    real(wp), parameter :: MASS(3) = [2.0_wp, 1.0e-4_wp, 5.0_wp]
    real(wp) :: k(3, 3), m(3, 3), s
    integer :: i
    m = 0
    do i = 1, 3
      m(i, i) = MASS(i)
    end do
    m(1, 3) = 0.5_wp
    m(3, 1) = 0.5_wp
    k = 0
    k(1, 1) = 4.0e6_wp
    k(2, 2) = 3.0_wp
    k(3, 3) = 1.0e3_wp
    k(2, 3) = 1.0_wp
    k(3, 2) = 1.0_wp
    ! The largest K_ii / M_ii, the scale of omega^2 the round-off margin refers to.
    s = maxval([(k(i, i) / m(i, i), i = 1, 3)])
    call suite%check(stable_tangent(k, m), 'positive definite K: stable')
    k(2, 2) = -3.0_wp
    call suite%check(.not. stable_tangent(k, m), 'one negative direction: unstable')
    ! A coordinate without stiffness (released hinge, rigid-body mode): neutral, not unstable.
    k(2, :) = 0
    k(:, 2) = 0
    call suite%check(stable_tangent(k, m), 'a zero-stiffness coordinate: not unstable')
    ! Round-off of the difference tangent around zero (omega^2 = -1e-16 s) is neutral too; a
    ! real negative omega^2 of -1e-6 s is not.
    k(2, 2) = -1.0e-16_wp * s * m(2, 2)
    call suite%check(stable_tangent(k, m), 'round-off below zero: not unstable')
    k(2, 2) = -1.0e-6_wp * s * m(2, 2)
    call suite%check(.not. stable_tangent(k, m), 'omega^2 = -1e-6 of the largest: unstable')
    ! Unsymmetric tangents (moments fixed in space): eigenvalues of K v = omega^2 M v with
    ! M = I decide. [[2, 1], [-1, 2]] has 2 +- i (a complex pair: not counted, see
    ! stable_tangent), [[1, 3], [0.5, 1]] has 1 +- sqrt(1.5), one negative: divergence, though
    ! the symmetric part [[1, 1.75], [1.75, 1]] is as indefinite in both cases.
    call suite%check(stable_tangent(reshape([2.0_wp, -1.0_wp, 1.0_wp, 2.0_wp], [2, 2]), &
      identity2()), 'unsymmetric K, complex pair 2 +- i: not unstable')
    call suite%check(.not. stable_tangent(reshape([1.0_wp, 0.5_wp, 3.0_wp, 1.0_wp], [2, 2]), &
      identity2()), 'unsymmetric K with omega^2 = 1 - sqrt(1.5) < 0: unstable')
    call suite%check(stable_tangent(reshape([4.0_wp, 0.5_wp, 3.0_wp, 1.0_wp], [2, 2]), &
      identity2()), 'unsymmetric K with real positive omega^2 (2.5 +- sqrt(3.75)): stable')
  end subroutine matrices

  pure function identity2() result(a)
    real(wp) :: a(2, 2)
    a = reshape([1.0_wp, 0.0_wp, 0.0_wp, 1.0_wp], [2, 2])
  end function identity2

  !> P_cr of the N_EL-element model: 1 / largest mu of G v = mu S v, K_T(P) = S - P G.
  real(wp) function discrete_critical_load() result(p_cr)
    type(scene_t) :: scene
    type(dynamics_t) :: dyn
    type(error_t) :: err
    real(wp), allocatable :: q(:), s(:, :), kt(:, :), g(:, :), mu(:), v(:, :)
    integer :: nd, info
    p_cr = 0
    call make(cantilever(N_EL, -P_EXACT, ''), scene, dyn, err)
    call suite%check(err%ok(), 'cantilever builds: ' // msg(err))
    if (.not. err%ok()) return
    nd = dyn%model%n_dy
    allocate(q(nd), s(nd, nd), kt(nd, nd), g(nd, nd), mu(nd), v(nd, nd))
    q = 0.0_wp
    dyn%load_factor = 0.0_wp
    call tangent_stiffness(dyn, 0.0_wp, q, s, err)
    if (err%ok()) then
      dyn%load_factor = 1.0_wp
      call tangent_stiffness(dyn, 0.0_wp, q, kt, err)
    end if
    call suite%check(err%ok(), 'tangent stiffness: ' // msg(err))
    if (.not. err%ok()) return
    g = (s - kt) / P_EXACT
    call sym_gen_eig(g, s, mu, v, info)
    call suite%check(info == 0 .and. mu(nd) > 0, 'buckling eigenproblem solves')
    if (info /= 0 .or. mu(nd) <= 0) return
    p_cr = 1 / mu(nd)
    write(*, '(a,i0,a,es12.5,a,es10.2)') '  P_cr of ', N_EL, ' elements: ', p_cr, &
      ' N, relative to pi^2 EI/(4 L^2): ', p_cr / P_EXACT - 1
    call suite%check(abs(p_cr / P_EXACT - 1) < 1.0e-3_wp, 'discretised P_cr within 0.1 % ' // &
      'of pi^2 EI / (4 L^2)')
  end function discrete_critical_load

  !> n load steps up to `factor` P_EXACT: step k is stable exactly when its load is below p_cr.
  subroutine load_stepping(n, factor, p_cr)
    integer, intent(in) :: n
    real(wp), intent(in) :: factor, p_cr
    type(scene_t) :: scene
    type(dynamics_t) :: dyn
    type(error_t) :: err
    real(wp), allocatable :: q(:), xs(:, :)
    real(wp) :: load(n), gap
    logical :: stable(n), expected(n)
    integer :: k, iters
    character(len=:), allocatable :: tag
    character(len=40) :: buf
    write(buf, '(f4.2,a,i0,a)') factor, ' P_cr in ', n, ' steps:'
    tag = trim(buf) // ' '
    call make(cantilever(N_EL, -factor * P_EXACT, ''), scene, dyn, err)
    if (.not. err%ok()) then
      call suite%check(.false., tag // 'builds: ' // msg(err))
      return
    end if
    allocate(q(dyn%model%n_dy), xs(dyn%model%n_x, n))
    q = 0.0_wp
    call static_solve(dyn, 0.0_wp, n, 1.0e-10_wp, 30, q, xs, iters, err, stable)
    call suite%check(err%ok(), tag // 'converges on the straight branch: ' // msg(err))
    if (.not. err%ok()) return
    load = [(real(k, wp) / n * factor * P_EXACT, k = 1, n)]
    expected = load < p_cr
    ! The check needs a real margin: no step within 0.5 % of P_cr (the nearest is 1 % off).
    gap = minval(abs(load / p_cr - 1))
    write(*, '(a,i0,a,f7.4,a,i0)') '  ', n, ' steps: nearest load ', gap, &
      ' from P_cr; first unstable step ', findloc(stable, .false., dim=1)
    call suite%check(gap > 5.0e-3_wp, tag // 'no step within 0.5 % of P_cr')
    call suite%check(all(stable .eqv. expected), tag // &
      'stable exactly below the discretised P_cr')
    if (factor > 1) call suite%check(any(.not. stable) .and. any(stable), tag // &
      'both stable and unstable steps')
    call suite%check(maxval(abs(q)) < 1.0e-12_wp, tag // 'stays straight (q = 0)')
    ! The steps on either side of P_cr: the sign of the lowest omega^2 is far from the
    ! round-off margin of the check.
    do k = 1, n
      if (k < n) then
        if (expected(k) .eqv. expected(k + 1)) cycle
      end if
      call margin_at(dyn, real(k, wp) / n, tag // 'step ' // itxt(k))
      if (k < n) call margin_at(dyn, real(k + 1, wp) / n, tag // 'step ' // itxt(k + 1))
      exit
    end do
  end subroutine load_stepping

  !> |lowest omega^2| of K_T v = omega^2 Mbar v (q = 0, load factor lambda) over the scale s of
  !> stable_tangent: over 100 times STABILITY_MARGIN.
  subroutine margin_at(dyn, lambda, tag)
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: lambda
    character(len=*), intent(in) :: tag
    type(error_t) :: err
    real(wp), allocatable :: q(:), kt(:, :), w(:), v(:, :)
    real(wp) :: s, ratio
    integer :: nd, i, info
    nd = dyn%model%n_dy
    allocate(q(nd), kt(nd, nd), w(nd), v(nd, nd))
    q = 0.0_wp
    dyn%load_factor = lambda
    dyn%locked = .true.
    call tangent_stiffness(dyn, 0.0_wp, q, kt, err)
    dyn%locked = .false.
    if (.not. err%ok()) then
      call suite%check(.false., tag // ': tangent stiffness: ' // msg(err))
      return
    end if
    s = maxval([(abs(kt(i, i)) / dyn%mbar(i, i), i = 1, nd)])
    call sym_gen_eig(kt, dyn%mbar, w, v, info)
    ratio = abs(w(1)) / s
    write(*, '(a,es10.2,a,es10.2)') '  ' // tag // ': lowest omega^2 ', w(1), ', |.| / s ', ratio
    call suite%check(info == 0 .and. ratio > 100 * STABILITY_MARGIN, tag // &
      ': |lowest omega^2| over 100x the round-off margin')
  end subroutine margin_at

  !> A run with &static writes /static/stable (n_steps) as 1/0, the same as static_solve.
  subroutine result_file()
    type(run_t) :: run
    type(error_t) :: err
    integer(hid_t) :: fid
    integer :: hdferr, k
    integer, allocatable :: flags(:)
    character(len=:), allocatable :: path
    path = scratch_dir() // '/test_static_stability_' // random_tag() // '.h5'
    call run_to_file(cantilever(N_EL, -1.1_wp * P_EXACT, "&static n_steps = 20 /" // NL // &
      "&output nodes = 'tip' /" // NL), 'stability.nml', path, run, err)
    call suite%check(err%ok(), 'run with &static writes its file: ' // msg(err))
    if (.not. err%ok()) return
    call h5open_f(hdferr)
    call h5fopen_f(path, H5F_ACC_RDONLY_F, fid, hdferr)
    call suite%check(hdferr == 0, 'result file opens')
    if (hdferr /= 0) return
    flags = read_int(fid, '/static/stable')
    call h5fclose_f(fid, hdferr)
    call execute_command_line('rm -f ' // path)
    call suite%check(size(flags) == 20, '/static/stable has n_steps entries')
    if (size(flags) /= 20) return
    call suite%check(all(flags == merge(1, 0, run%static_stable)), &
      '/static/stable holds the stable flags as 1/0')
    ! 1.1 P_cr in 20 steps: loads 0.055 k P_cr, unstable from k = 19 (1.045 P_cr).
    call suite%check(all(flags(1:18) == 1) .and. all(flags(19:20) == 0), &
      '/static/stable: steps 1-18 stable, 19-20 unstable')
    write(*, '(a,20i2)') '  /static/stable:', (flags(k), k = 1, 20)
  end subroutine result_file

  !> A hinge without stiffness at the root (a rigid-body rotation as a dynamic coordinate):
  !> pulled at the tip it is a hanging pendulum, stable; pushed, an inverted one, unstable from
  !> the first step.
  subroutine pinned_strut()
    character(len=*), parameter :: what(2) = [character(len=6) :: 'pulled', 'pushed']
    type(scene_t) :: scene
    type(dynamics_t) :: dyn
    type(error_t) :: err
    real(wp), allocatable :: q(:), xs(:, :)
    logical :: stable(5)
    integer :: i, iters
    do i = 1, 2
      call make("&node label = 'root', x = 0.0, y = 0.0, fixed = .true. /" // NL // &
        "&node label = 'tip', x = " // rtxt(LEN) // ", y = 0.0 /" // NL // &
        "&link label = 'beam', from = 'root', to = 'tip', n_elements = 2," // NL // &
        "      E = " // rtxt(E_MOD) // ", A = " // rtxt(AREA) // ", I = " // rtxt(INER) // &
        ", rho = " // rtxt(RHO) // " /" // NL // &
        "&hinge label = 'pin', node = 'root', link = 'beam', mode = 'dynamic', " // &
        "stiffness = 0.0 /" // NL // "&force node = 'tip', fx = " // &
        rtxt(merge(1.0_wp, -1.0_wp, i == 1)) // " /" // NL, scene, dyn, err)
      if (err%ok()) then
        allocate(q(dyn%model%n_dy), xs(dyn%model%n_x, 5))
        q = 0.0_wp
        call static_solve(dyn, 0.0_wp, 5, 1.0e-10_wp, 30, q, xs, iters, err, stable)
        deallocate(q, xs)
      end if
      call suite%check(err%ok(), 'pinned strut ' // trim(what(i)) // ': solves: ' // msg(err))
      if (.not. err%ok()) cycle
      if (i == 1) call suite%check(all(stable), 'pinned strut pulled: stable (pendulum)')
      if (i == 2) call suite%check(.not. any(stable), &
        'pinned strut pushed: unstable from step 1 (inverted pendulum)')
    end do
  end subroutine pinned_strut
end program test_static_stability
