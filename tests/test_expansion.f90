!> The expanded evaluation of a reduced model (reduction_expansion) against the exact one on a
!> small two-link arm under gravity and a time-varying tip force (2 beams per link, k = 3):
!> at the expansion point the accelerations agree to round-off; away from it the nodal
!> coordinates converge at order 4 (a third-order series) and the accelerations and kinetic
!> energy at order 2 (coefficients to first order), for steps that mix the prescribed and modal
!> coordinates. With the joints' turns kept exact (reduction_frames) the expansion agrees with
!> the exact model to round-off however far the joints turn, on the two-link with consistent
!> and lumped masses and on a tree of three turns (two siblings inside a parent).
program test_expansion
  use core_kinds, only: wp
  use core_error, only: error_t
  use analysis_run, only: run_t
  use reduction_expansion, only: expansion_t, expansion_set_t, AHEAD_FRACTION, kept_slots
  use testing, only: suite_t
  use reduction_turns, only: turn_t
  implicit none
  type(suite_t) :: suite
  type(run_t) :: run
  type(expansion_t) :: ex
  type(error_t) :: err
  real(wp), parameter :: T0 = 0.2_wp, TAU = 0.01_wp
  real(wp) :: eta0(3), eta_dot(3), d_eta(3), d_p(2)
  !> Whether the expansions keep the turns' angles exact (reduction_frames): the series in the
  !> joint angles are checked without.
  logical :: frames = .false.
  !> The analyses of every scene here: a short reduced run (its basis and model are used).
  character(len=*), parameter :: ANALYSES = "&output nodes = 'tip' /" // new_line('a') // &
    "&dynamic t_end = 0.01, output_dt = 5e-3, integrator = 'bdf' /" // new_line('a') // &
    "&reduction n_modes = 3 /" // new_line('a')

  call suite%init('expansion: expanded reduced model against the exact one')
  eta0 = [0.02_wp, -0.01_wp, 0.004_wp]
  eta_dot = [0.3_wp, -0.2_wp, 0.05_wp]
  d_eta = [0.02_wp, 0.01_wp, 0.001_wp]
  d_p = [0.04_wp, -0.03_wp]
  call setup('consistent', run)
  call check_at_point()
  call check_coordinates()
  call check_accelerations()
  call check_energies(2, 3)
  call check_centre_time()
  call check_second_many()
  call check_turns()
  call check_frames()
  call setup('consistent', run, whole=tree_scene())
  call suite%check(ex%frames%on, 'a tree of three turns kept exact')
  call check_far_joints('a tree of three turns')
  call check_turn_by_parts('a tree of three turns')
  ! 1 GiB of series: all 64 at 389 coordinates (305 kB each), 13 at 10^5 (78 MB), 4 at least.
  call suite%check(kept_slots(389, 6) == 64 .and. kept_slots(10**5, 6) == 13 .and. &
    kept_slots(10**8, 6) == 4, 'kept expansions within the memory budget')
  ! With lumped masses the mass matrix is constant: its second-order terms are all there, and
  ! the kinetic energy converges at order 3; the weights are nodal loads, whose work follows
  ! the coordinates' series (order 4).
  call setup('lumped', run)
  call check_energies(3, 4)
  frames = .true.
  call setup('lumped', run)
  call check_far_joints('lumped masses')
  ! A base shaken along x: a prescribed translation is no turn, and the joints' turns are
  ! not used unless every prescribed coordinate is one.
  call setup('consistent', run, "&node label = 'base', x = 0, y = 0, fixed = .true., " // &
    "fix_x = .false., motion_x = 'shake' /" // new_line('a') // &
    "&motion label = 'shake', law = 'harmonic', frequency = 5, amplitude = 0.01 /")
  call suite%check(.not. ex%turned .and. .not. ex%frames%on, 'a shaken base: no turns')
  ! A released truss from the tip to the ground ties the arm to it: no joint turns a part
  ! rigidly (the series by element passes, still at its order).
  call setup('consistent', run, "&node label = 'base', x = 0, y = 0, fixed = .true. /" // &
    new_line('a') // "&node label = 'anchor', x = 1.22, y = -0.5, fixed = .true. /" // &
    new_line('a') // "&truss label = 's', from = 'tip', to = 'anchor', E = 2e9, A = 1e-6, " // &
    "mode = 'released' /")
  call suite%check(.not. ex%turned .and. .not. ex%frames%on, &
    'an arm tied to the ground: no turns')
  call check_coordinates()
  call suite%finish()

contains

  !> The reduced run (full evaluation) of scene(mass) and the expansion at (T0, eta0).
  subroutine setup(mass, r, base, whole)
    character(len=*), intent(in) :: mass
    type(run_t), intent(out) :: r
    !> base: the base node's group instead of the fixed one; whole: the whole scene instead
    character(len=*), intent(in), optional :: base, whole
    character(len=*), parameter :: FIXED_BASE = &
      "&node label = 'base', x = 0, y = 0, fixed = .true. /"
    character(len=:), allocatable :: text
    integer :: u, at
    text = scene(mass)
    if (present(whole)) text = whole
    if (present(base)) then
      at = index(text, FIXED_BASE)
      text = text(1:at - 1) // base // text(at + len(FIXED_BASE):)
    end if
    open(newunit=u, file='test_expansion.nml', status='replace', action='write')
    write(u, '(a)') text
    close(u)
    r%verbose = .false.
    ex%use_frames = frames
    call r%load('test_expansion.nml', err)
    if (err%ok()) call r%execute(err)
    call suite%check(err%ok(), 'reduced run (full evaluation), ' // mass // ' masses')
    if (.not. err%ok()) then
      write(*, '(a)') '    ' // err%message
      call suite%finish()
    end if
    call ex%build(r%red%dyn, r%red%basis, T0, eta0, err)
    call suite%check(err%ok(), 'expansion builds')
    if (.not. err%ok()) call suite%finish()
  end subroutine setup

  !> The two-link arm under gravity, its joints turning a quarter turn in 0.4 s.
  function arm(mass) result(text)
    character(len=*), intent(in) :: mass
    character(len=:), allocatable :: text
    character(len=*), parameter :: nl = new_line('a')
    text = "&scene gravity = 0, -9.81 /" // nl // &
      "&node label = 'base', x = 0, y = 0, fixed = .true. /" // nl // &
      "&node label = 'elbow', x = 0.545, y = 0 /" // nl // &
      "&node label = 'tip', x = 1.22, y = 0 /" // nl // &
      "&link label = 'l1', from = 'base', to = 'elbow', n_elements = 2, E = 7.3e10, " // &
      "A = 9e-4, I = 1.69e-8, rho = 2700, mass = '" // mass // "' /" // nl // &
      "&link label = 'l2', from = 'elbow', to = 'tip', n_elements = 2, E = 7.3e10, " // &
      "A = 4e-4, I = 3.33e-9, rho = 2700, mass = '" // mass // "' /" // nl // &
      "&hinge label = 'j1', node = 'base', link = 'l1', mode = 'prescribed', motion = 'p1' /" &
      // nl // &
      "&hinge label = 'j2', node = 'elbow', link = 'l2', mode = 'prescribed', motion = 'p2' /" &
      // nl // &
      "&motion label = 'p1', law = 'cubic', end = 1.5707963, duration = 0.4 /" // nl // &
      "&motion label = 'p2', law = 'cubic', end = 1.5707963, duration = 0.4 /" // nl
  end function arm

  !> The arm under a time-varying tip force, with masses at the elbow and the tip.
  function scene(mass) result(text)
    character(len=*), intent(in) :: mass
    character(len=:), allocatable :: text
    character(len=*), parameter :: nl = new_line('a')
    text = arm(mass) // &
      "&motion label = 'f', law = 'harmonic', frequency = 3, amplitude = 1 /" // nl // &
      "&force node = 'tip', fx = 2, fy = -1, time_law = 'f' /" // nl // &
      "&mass node = 'elbow', m = 1 /" // nl // "&mass node = 'tip', m = 3 /" // nl // ANALYSES
  end function scene

  !> A tree of turns: link 1 turned about the base, links 2 and 3 about the elbow (siblings,
  !> each inside link 1's part), under gravity with a tip mass.
  function tree_scene() result(text)
    character(len=:), allocatable :: text
    character(len=*), parameter :: nl = new_line('a')
    text = arm('consistent') // &
      "&node label = 'tip2', x = 0.545, y = 0.4 /" // nl // &
      "&link label = 'l3', from = 'elbow', to = 'tip2', n_elements = 2, E = 7.3e10, " // &
      "A = 4e-4, I = 3.33e-9, rho = 2700 /" // nl // &
      "&hinge label = 'j3', node = 'elbow', link = 'l3', mode = 'prescribed', motion = 'p3' /" &
      // nl // &
      "&motion label = 'p3', law = 'cubic', end = -1.0, duration = 0.4 /" // nl // &
      "&mass node = 'tip', m = 3 /" // nl // ANALYSES
  end function tree_scene

  !> Exact reduced accelerations (the full model evaluated) at (t, eta, eta_dot).
  function exact_accel(t, eta) result(a)
    real(wp), intent(in) :: t, eta(:)
    real(wp) :: a(size(eta))
    integer :: status
    call run%red%accel(t, eta, eta_dot, a, status)
    call suite%check(status == 0, 'exact evaluation')
  end function exact_accel

  function expanded_accel(t, eta) result(a)
    real(wp), intent(in) :: t, eta(:)
    real(wp) :: a(size(eta))
    real(wp), dimension(run%red%dyn%model%n_rh) :: p, pd, pdd
    call run%red%dyn%prescribed(t, p, pd, pdd)
    call ex%accel(run%red%dyn, t, p, pd, pdd, eta, eta_dot, a, err)
    call suite%check(err%ok(), 'expanded evaluation')
  end function expanded_accel

  !> A new expansion is centred ahead on the joints' path, where they alone use AHEAD_FRACTION
  !> of the tolerance (bisection to round-off; 1 % allowed), and it still serves the state it
  !> was made for; at rest (after the motions' 0.4 s) it is centred at the state.
  subroutine check_centre_time()
    type(expansion_set_t) :: set
    real(wp) :: p(2), pd(2), pdd(2), pc(2), tc, d(2), use
    set%use_frames = .false.
    call set%expand(run%red%dyn, run%red%basis, T0, eta0, err)
    call suite%check(err%ok(), 'expansion set builds')
    call run%red%dyn%prescribed(T0, p, pd, pdd)
    tc = set%centre_time(run%red%dyn, T0, p)
    call run%red%dyn%prescribed(tc, pc, pd, pdd)
    d = set%item(set%current)%spread([pc - p, 0.0_wp, 0.0_wp, 0.0_wp])
    use = d(2)**2 / (set%tol * d(1)**2)
    call suite%check(tc > T0 .and. use <= AHEAD_FRACTION .and. use > 0.99_wp * &
      AHEAD_FRACTION, 'centre ahead where the joints use the set fraction of the tolerance')
    call set%expand(run%red%dyn, run%red%basis, tc, eta0, err)
    call suite%check(err%ok() .and. .not. set%item(set%current)%needs_update(p, eta0, set%tol), &
      'the expansion centred ahead serves the state')
    call run%red%dyn%prescribed(0.5_wp, p, pd, pdd)
    call suite%check(set%centre_time(run%red%dyn, 0.5_wp, p) == 0.5_wp, &
      'centred at the state where the joints rest')
  end subroutine check_centre_time

  !> Every element's second_many and convective_many (the beams' from one chord) equal second
  !> and inertia's h column by column, to round-off (the same arithmetic, perhaps contracted
  !> differently).
  subroutine check_second_many()
    real(wp) :: v(6, 3), d2e(3, 3), one(3), h(6, 3), h1(6), m(6, 6), worst(2), scale(2)
    integer :: iel, c, j, nd, nm
    worst = 0.0_wp
    scale = 0.0_wp
    do iel = 1, run%red%dyn%model%n_elements
      associate (el => run%red%dyn%model%elements(iel)%e, x => run%red%dyn%kin%x)
        nd = size(el%dofs)
        nm = el%n_modes()
        do c = 1, 3
          v(1:nd, c) = [(sin(1.3_wp * c + 0.7_wp * j), j = 1, nd)]
        end do
        call el%second_many(x(el%dofs), v(1:nd, :), d2e(1:nm, :))
        call el%convective_many(x(el%dofs), v(1:nd, :), h(1:nd, :))
        do c = 1, 3
          call el%second(x(el%dofs), v(1:nd, c), one(1:nm))
          worst(1) = max(worst(1), maxval(abs(one(1:nm) - d2e(1:nm, c))))
          scale(1) = max(scale(1), maxval(abs(one(1:nm))))
          call el%inertia(x(el%dofs), v(1:nd, c), m(1:nd, 1:nd), h1(1:nd))
          worst(2) = max(worst(2), maxval(abs(h1(1:nd) - h(1:nd, c))))
          scale(2) = max(scale(2), maxval(abs(h1(1:nd))))
        end do
      end associate
    end do
    call suite%check(all(scale > 0) .and. all(worst <= 1.0e-13_wp * scale), &
      'second_many and convective_many equal second and inertia per column (1e-13 relative)')
  end subroutine check_second_many

  !> At z0 the series is exact: only the projections' round-off differs.
  subroutine check_at_point()
    real(wp) :: a(3), b(3)
    a = exact_accel(T0, eta0)
    b = expanded_accel(T0, eta0)
    call suite%check(maxval(abs(a - b)) <= 1.0e-9_wp * maxval(abs(a)), &
      'accelerations at the expansion point (round-off: 1e-9 relative)')
  end subroutine check_at_point

  !> The joints turn the arm beyond them rigidly: the series' columns along them come from the
  !> turns' products. Against the element passes and solves: X2 to round-off; X3 to the
  !> truncation of the passes' one-sided differences (THIRD_STEP 1e-6 of the model's size:
  !> about 1e-6 relative); and so the accelerations off the expansion point.
  subroutine check_turns()
    type(expansion_t) :: passes
    real(wp) :: x2_scale, x3_scale, a(3), b(3), p(2), pd(2), pdd(2)
    call suite%check(ex%turned, 'both joints are turns')
    passes%use_turns = .false.
    call passes%build(run%red%dyn, run%red%basis, T0, eta0, err)
    call suite%check(err%ok() .and. .not. passes%turned, 'expansion by element passes')
    x2_scale = maxval(abs(passes%x2))
    x3_scale = maxval(abs(passes%x3))
    call suite%check(maxval(abs(ex%x2 - passes%x2)) <= 1.0e-10_wp * x2_scale, &
      'X2 along the turns: products against solves (1e-10 relative)')
    call suite%check(maxval(abs(ex%x3 - passes%x3)) <= 1.0e-4_wp * x3_scale, &
      'X3 along the turns: products against differences (1e-4 relative)')
    call run%red%dyn%prescribed(T0 + TAU, p, pd, pdd)
    call ex%accel(run%red%dyn, T0 + TAU, p, pd, pdd, eta0 + d_eta, eta_dot, a, err)
    call passes%accel(run%red%dyn, T0 + TAU, p, pd, pdd, eta0 + d_eta, eta_dot, b, err)
    call suite%check(maxval(abs(a - b)) <= 1.0e-5_wp * maxval(abs(b)), &
      'accelerations off the point: turns against passes (1e-5 relative)')
    write(*, '(a, 3es10.2)') '      X2, X3, accelerations (relative): ', &
      maxval(abs(ex%x2 - passes%x2)) / x2_scale, maxval(abs(ex%x3 - passes%x3)) / x3_scale, &
      maxval(abs(a - b)) / maxval(abs(b))
  end subroutine check_turns

  !> Largest nodal distance between the series and the exact kinematics at z0 + s (d_p, d_eta).
  real(wp) function coordinate_error(s) result(e)
    real(wp), intent(in) :: s
    e = coordinate_error_z(ex%z0 + s * [d_p, d_eta])
  end function coordinate_error

  !> The same at the joints' angles at time t and eta.
  real(wp) function coordinate_error_at(t, eta) result(e)
    real(wp), intent(in) :: t, eta(:)
    real(wp), dimension(run%red%dyn%model%n_rh) :: p, pd, pdd
    call run%red%dyn%prescribed(t, p, pd, pdd)
    e = coordinate_error_z([p, eta])
  end function coordinate_error_at

  real(wp) function coordinate_error_z(z) result(e)
    real(wp), intent(in) :: z(:)
    real(wp) :: q(run%red%dyn%model%n_q), x(run%red%dyn%model%n_x)
    integer :: i, nr
    nr = run%red%dyn%model%n_rh
    q(1:nr) = z(1:nr)
    q(nr + 1:) = run%red%basis%q_ref + matmul(run%red%basis%v, z(nr + 1:))
    x = ex%coordinates(z)
    call run%red%dyn%kin%solve(run%red%dyn%model, q, err)
    call suite%check(err%ok(), 'exact kinematics')
    e = 0.0_wp
    do i = 1, size(run%red%dyn%model%node_coord, 2)
      e = max(e, run%red%dyn%model%translation(i, x - run%red%dyn%kin%x))
    end do
  end function coordinate_error_z

  subroutine check_coordinates()
    ! At s = 1 the step turns the joints by 0.04 rad: the fourth-order term, about
    ! 1.2 m * 0.04^4 / 24 = 1e-7 m, is far above X3's difference error (1e-6 * 0.04^3 m).
    call suite%order(coordinate_error(1.0_wp), coordinate_error(0.5_wp), 4, &
      'nodal coordinates of the series')
  end subroutine check_coordinates

  !> Relative error of the expanded accelerations at time T0 + s TAU, eta0 + s d_eta: the
  !> joints move by about 0.06 s rad (their rate at T0 is near 5.9 rad/s). d_eta is small
  !> against eta0, so that the stiffness forces, large and exact in both, stay near their
  !> value and the error (of the mass and inertia coefficients) shows its order.
  real(wp) function accel_error(s) result(e)
    real(wp), intent(in) :: s
    real(wp) :: a(3)
    a = exact_accel(T0 + s * TAU, eta0 + s * d_eta)
    e = maxval(abs(expanded_accel(T0 + s * TAU, eta0 + s * d_eta) - a)) / maxval(abs(a))
  end function accel_error

  subroutine check_accelerations()
    call suite%order(accel_error(0.5_wp), accel_error(0.25_wp), 2, &
      'accelerations (mass, inertia, weight and load terms to first order)')
  end subroutine check_accelerations

  !> Errors of the expanded kinetic and potential energy at the state of accel_error.
  function energy_error(s) result(e)
    real(wp), intent(in) :: s
    real(wp) :: e(2)
    e = energy_error_at(T0 + s * TAU, eta0 + s * d_eta)
  end function energy_error

  function energy_error_at(t, eta) result(e)
    real(wp), intent(in) :: t, eta(:)
    real(wp) :: e(2)
    real(wp), dimension(run%red%dyn%model%n_rh) :: p, pd, pdd
    real(wp) :: q(run%red%dyn%model%n_q), exact(2), z(run%red%dyn%model%n_rh + size(eta))
    integer :: nr
    nr = run%red%dyn%model%n_rh
    call run%red%dyn%prescribed(t, p, pd, pdd)
    q(1:nr) = p
    q(nr + 1:) = run%red%basis%q_ref + matmul(run%red%basis%v, eta)
    call run%red%dyn%kin%solve(run%red%dyn%model, q, err)
    call suite%check(err%ok(), 'exact kinematics')
    exact = run%red%dyn%energy(t, q(nr + 1:), matmul(run%red%basis%v, eta_dot))
    z = [p, eta]
    e = abs(ex%energy(z, [pd, eta_dot], run%red%dyn%load_factor * &
      run%red%dyn%loads_at(t), ex%coordinates(z)) - exact)
  end function energy_error_at

  !> The kinetic energy from the mass to second order (to first in the element masses'
  !> change: order 2 with consistent beam masses); the potential exact in the strain, to
  !> fourth order in the loads' work and to third in the elements' weights.
  subroutine check_energies(kinetic_order, potential_order)
    integer, intent(in) :: kinetic_order, potential_order
    real(wp) :: coarse(2), fine(2)
    coarse = energy_error(0.5_wp)
    fine = energy_error(0.25_wp)
    call suite%order(coarse(1), fine(1), kinetic_order, 'kinetic energy')
    call suite%order(coarse(2), fine(2), potential_order, 'potential energy')
  end subroutine check_energies

  !> The parts' turn (frames%turn: one rotation per node) equals the turns' composition
  !> (apply_turns) on the series' columns and on positions, to round-off (1e-13 relative).
  subroutine check_turn_by_parts(what)
    character(len=*), intent(in) :: what
    real(wp), allocatable :: a(:, :), b(:, :)
    real(wp) :: delta(size(ex%turns))
    integer :: i
    delta = [(0.3_wp * i - 0.7_wp, i = 1, size(delta))]
    a = ex%x1
    b = a
    call ex%frames%turn(delta, a, .false.)
    call apply_turns(ex%turns, ex%turn_order, delta, b, .false.)
    call suite%check(maxval(abs(a - b)) <= 1.0e-13_wp * maxval(abs(b)), &
      'fields turned by parts as by the turns: ' // what)
    a = reshape(ex%x0, [size(ex%x0), 1])
    b = a
    call ex%frames%turn(delta, a, .true.)
    call apply_turns(ex%turns, ex%turn_order, delta, b, .true.)
    call suite%check(maxval(abs(a - b)) <= 1.0e-13_wp * maxval(abs(b)), &
      'positions turned by parts as by the turns: ' // what)
    call check_norm_by_parts(delta, what)
  end subroutine check_turn_by_parts

  !> The error norm's one pass over the turned fields (frames_norm_terms) against the norm of
  !> the fields turned by the turns one by one; round-off apart they are the same maxima. A
  !> maximum sees one node: a step along each mode, and far turns, put it on several.
  subroutine check_norm_by_parts(delta, what)
    real(wp), intent(in) :: delta(:)
    character(len=*), intent(in) :: what
    real(wp), parameter :: RTOL = 1.0e-6_wp, ATOL = 1.0e-8_wp
    real(wp) :: dq(ex%k), eta_old(ex%k), eta_new(ex%k), norm, ref, worst
    real(wp), allocatable :: f(:, :)
    integer :: i, l, c
    allocate(f(size(ex%x0), 3))
    worst = 0.0_wp
    do c = 1, 2
      do l = 1, ex%k
        dq = 0.0_wp
        dq(l) = 1.0e-5_wp
        eta_old = [(0.01_wp * (2 - i), i = 1, ex%k)]
        eta_new = eta_old + dq
        f(:, 1) = matmul(ex%x1(:, ex%nr + 1:), dq)
        f(:, 2) = ex%xr + matmul(ex%x1(:, ex%nr + 1:), eta_old)
        f(:, 3) = ex%xr + matmul(ex%x1(:, ex%nr + 1:), eta_new)
        call apply_turns(ex%turns, ex%turn_order, c * delta, f, .false.)
        ref = run%red%dyn%model%error_norm(f(:, 1), max(abs(f(:, 2)), abs(f(:, 3))), RTOL, &
          ATOL)
        call ex%error_norm(run%red%dyn%model, dq, eta_old, eta_new, RTOL, ATOL, &
          ex%z0(1:ex%nr) + c * delta, norm)
        worst = max(worst, abs(norm - ref) / ref)
      end do
    end do
    call suite%check(worst <= 1.0e-12_wp, &
      'error norm in one pass as of the fields turned by the turns: ' // what)
  end subroutine check_norm_by_parts

  !> With the turns exact (reduction_frames) the expansion serves any joint angles: at the
  !> expansion's modal coordinates the accelerations, energies and coordinates agree with the
  !> exact ones to round-off however far the joints have turned, the modal step keeps its
  !> order, and a new expansion is centred ahead along the modal rates.
  subroutine check_frames()
    type(expansion_set_t) :: set
    real(wp) :: p(2), pd(2), pdd(2), tc
    frames = .true.
    call setup('consistent', run)
    call suite%check(ex%frames%on, 'the turns kept exact (consistent masses)')
    call check_at_point()
    call check_far_joints('consistent masses')
    call check_turn_by_parts('two-link')
    call suite%order(far_accel_error(0.5_wp), far_accel_error(0.25_wp), 2, &
      'accelerations 0.35 rad of the joints away, modal step (coefficients to first order)')
    call set%expand(run%red%dyn, run%red%basis, T0, eta0, err)
    call run%red%dyn%prescribed(T0, p, pd, pdd)
    tc = set%centre_time(run%red%dyn, T0, p)
    call suite%check(err%ok() .and. tc == T0, &
      'with the turns exact the joints do not move the centre')
    call check_centre_modal(set)
  end subroutine check_frames

  !> With the turns exact a new expansion is centred ahead along the modal rates, where the
  !> step back to the state uses AHEAD_FRACTION of the tolerance (by the current expansion's
  !> spreads: d1 grows as the step, d2 as its square, so this holds to round-off), but no
  !> further than tau_max ahead.
  subroutine check_centre_modal(set)
    type(expansion_set_t), intent(in) :: set
    real(wp) :: eta_c(3), dz(5), d(2)
    eta_c = set%centre_modal(eta0, eta_dot, huge(1.0_wp))
    dz(1:2) = 0.0_wp
    dz(3:) = eta0 - eta_c
    d = set%item(set%current)%spread(dz)
    call suite%check(all(eta_c /= eta0) .and. abs(d(2)**2 / (d(1)**2 * AHEAD_FRACTION * &
      set%tol) - 1) < 1.0e-10_wp, 'a new expansion is centred ahead along the modal rates')
    eta_c = set%centre_modal(eta0, eta_dot, 1.0e-4_wp)
    call suite%check(all(abs(eta_c - (eta0 + 1.0e-4_wp * eta_dot)) <= 1.0e-15_wp), &
      'no further ahead than tau_max')
    eta_c = set%centre_modal(eta0, 0 * eta_dot, huge(1.0_wp))
    call suite%check(all(eta_c == eta0), 'without modal rates it is centred at the state')
  end subroutine check_centre_modal

  !> At eta0 and joint angles up to 0.5 rad from the expansion's (T0 + 0.08 s: the joints turn
  !> at up to 5.9 rad/s), only round-off and the elements' mass check (1e-10) separate the
  !> expansion from the exact model (observed: 3e-11 relative in the accelerations).
  subroutine check_far_joints(what)
    character(len=*), intent(in) :: what
    real(wp) :: worst(3), a(3), b(3), t, e(2), x_err
    integer :: i
    worst = 0.0_wp
    do i = 1, 4
      t = T0 + 0.02_wp * i
      a = exact_accel(t, eta0)
      b = expanded_accel(t, eta0)
      worst(1) = max(worst(1), maxval(abs(a - b)) / maxval(abs(a)))
      e = energy_error_at(t, eta0)
      worst(2) = max(worst(2), maxval(e))
      x_err = coordinate_error_at(t, eta0)
      worst(3) = max(worst(3), x_err)
    end do
    call suite%check(worst(1) <= 1.0e-9_wp, 'accelerations with the joints turned away, ' // &
      what // ' (1e-9 relative)')
    call suite%check(worst(2) <= 1.0e-8_wp, 'energies with the joints turned away, ' // &
      what // ' (1e-8 J)')
    call suite%check(worst(3) <= 1.0e-11_wp, 'nodal coordinates with the joints turned ' // &
      'away, ' // what // ' (1e-11 m)')
    write(*, '(a, 3es10.2)') '      accelerations, energies [J], coordinates [m]: ', worst
  end subroutine check_far_joints

  !> The accelerations' error at T0 + 0.06 s (the joints 0.35 rad away) and the modal step
  !> s d_eta.
  real(wp) function far_accel_error(s) result(e)
    real(wp), intent(in) :: s
    real(wp) :: a(3)
    a = exact_accel(T0 + 0.06_wp, eta0 + s * d_eta)
    e = maxval(abs(expanded_accel(T0 + 0.06_wp, eta0 + s * d_eta) - a)) / maxval(abs(a))
  end function far_accel_error

  !> The reference for frames%turn: the turns applied one after the other (children first, in
  !> turn_order's order) to v(:, c), configurations at joint angles p0 turned to p0 + delta
  !> (positions) or fields of one (.not. positions: the angles keep their values), in place.
  pure subroutine apply_turns(turns, order, delta, v, positions)
    type(turn_t), intent(in) :: turns(:)
    integer, intent(in) :: order(:)
    real(wp), intent(in) :: delta(:)
    real(wp), intent(inout) :: v(:, :)
    logical, intent(in) :: positions
    real(wp) :: cx, cy, co, si, rx, ry
    integer :: o, j, i, ix, iy, c
    do o = 1, size(order)
      j = order(o)
      if (delta(j) == 0) cycle
      co = cos(delta(j))
      si = sin(delta(j))
      do c = 1, size(v, 2)
        cx = v(turns(j)%centre(1), c)
        cy = v(turns(j)%centre(2), c)
        do i = 1, size(turns(j)%moving, 2)
          ix = turns(j)%moving(1, i)
          iy = turns(j)%moving(2, i)
          rx = v(ix, c) - cx
          ry = v(iy, c) - cy
          v(ix, c) = cx + co * rx - si * ry
          v(iy, c) = cy + si * rx + co * ry
        end do
        if (positions) then
          do i = 1, size(turns(j)%angles)
            v(turns(j)%angles(i), c) = v(turns(j)%angles(i), c) + delta(j)
          end do
        end if
      end do
    end do
  end subroutine apply_turns
end program test_expansion
