!> &linear times along a reduced run with basis updates (docs/theory.md 8.2): the reduced
!> linearisation at a sample is the Galerkin projection V^T (full linearisation) V with the
!> basis that sample is relative to, and it is the derivative of the reduced equations
!> themselves (central differences of the reduced accelerations). The state's acceleration in
!> the linearisation is the reduced one, V eta'': with the full model's own at the same state
!> the projected stiffness here differs by 1% of its largest entry.
program test_linear_reduced
  use core_kinds, only: wp
  use core_error, only: error_t
  use analysis_run, only: run_t
  use dynamics_linear, only: linear_model_t, linearise
  use model_system, only: NODE_SLOTS
  use testing, only: suite_t
  implicit none
  type(suite_t) :: suite
  type(run_t) :: run
  type(error_t) :: err
  integer, parameter :: K = 3
  real(wp), parameter :: T_LIN = 0.25_wp
  character(len=*), parameter :: NL = new_line('a')

  call suite%init('linear: linearisation of a reduced run with basis updates')
  run%verbose = .false.
  call run%load_text(scene(), 'linear_reduced', err)
  if (err%ok()) call run%execute(err)
  call suite%check(err%ok(), 'reduced run with &linear times')
  if (.not. err%ok()) then
    write(*, '(a)') '    ' // err%message
    call suite%finish()
  end if
  call check_sample()
  call suite%finish()

contains

  !> The two-link arm of test_reduction (both joints turned a quarter turn in 0.4 s), three
  !> modes, a new basis every 0.1 s: the sample at 0.25 s is relative to the third basis.
  function scene() result(text)
    character(len=:), allocatable :: text
    text = "&node label = 'base', x = 0, y = 0, fixed = .true. /" // NL // &
      "&node label = 'elbow', x = 0.545, y = 0 /" // NL // &
      "&node label = 'tip', x = 1.22, y = 0 /" // NL // &
      "&link label = 'l1', from = 'base', to = 'elbow', n_elements = 2, E = 7.3e10, " // &
      "A = 9e-4, I = 1.69e-8, rho = 2700 /" // NL // &
      "&link label = 'l2', from = 'elbow', to = 'tip', n_elements = 2, E = 7.3e10, " // &
      "A = 4e-4, I = 3.33e-9, rho = 2700 /" // NL // &
      "&hinge label = 'j1', node = 'base', link = 'l1', mode = 'prescribed', motion = 'p1' /" &
      // NL // &
      "&hinge label = 'j2', node = 'elbow', link = 'l2', mode = 'prescribed', motion = 'p2' /" &
      // NL // &
      "&motion label = 'p1', law = 'cubic', end = 1.5707963, duration = 0.4 /" // NL // &
      "&motion label = 'p2', law = 'cubic', end = 1.5707963, duration = 0.4 /" // NL // &
      "&mass node = 'elbow', m = 1 /" // NL // "&mass node = 'tip', m = 3 /" // NL // &
      "&dynamic t_end = 0.3, output_dt = 0.01, integrator = 'bdf', rtol = 1e-8, " // &
      "atol = 1e-10 /" // NL // &
      "&reduction n_modes = 3, update = 'interval', update_interval = 0.1 /" // NL // &
      "&linear inputs = 'tip.fy', 'tip.fx', outputs = 'tip.y', 'elbow.phi', times = 0.25 /"
  end function scene

  subroutine check_sample()
    type(linear_model_t) :: full
    real(wp), allocatable :: v(:, :), q(:), qd(:), eta(:), eta_dot(:), eta_dd(:), m(:, :)
    real(wp), allocatable :: mr(:, :), expect(:, :), fd(:, :), got(:, :)
    integer, allocatable :: inputs(:, :), outputs(:, :)
    integer :: ks, ib, status, n
    character(len=80) :: line
    ks = minloc(abs(run%time - T_LIN), 1)
    ib = run%red%basis_of(ks)
    write(line, '(a,i0,a,i0,a)') 'sample relative to basis ', ib, ' of ', size(run%red%bases), &
      ' (two updates before it)'
    call suite%check(ib == 3 .and. size(run%red%bases) == 3, trim(line))
    call suite%check(size(run%linear(1)%a, 1) == 2 * K .and. run%linear(1)%k_reduced == K &
      .and. abs(run%linear(1)%time - run%time(ks)) == 0, 'reduced model: n_z = 2 k')
    associate (b => run%red%bases(ib), lin => run%linear(1))
      v = b%v
      eta = run%red%eta_hist(:, ks)
      eta_dot = run%red%eta_dot_hist(:, ks)
      q = b%q_ref + matmul(v, eta)
      qd = matmul(v, eta_dot)
      ! The reduced model's own acceleration at the sample (its basis put back in place).
      run%red%basis%v = v
      run%red%basis%q_ref = b%q_ref
      allocate(eta_dd(K))
      call run%red%accel(run%time(ks), eta, eta_dot, eta_dd, status)
      call suite%check(status == 0, 'reduced accelerations at the sample')
      inputs = io_columns([2, 1], 'tip')
      outputs = reshape([io_columns([2], 'tip'), io_columns([3], 'elbow')], &
        [NODE_SLOTS + 1, 2])
      ! The full linearisation at the reconstructed state, accelerating as the reduced one.
      call linearise(run%dyn, run%time(ks), q, inputs, outputs, .true., full, err, qd, &
        accel=matmul(v, eta_dd))
      call suite%check(err%ok(), 'full linearisation at the reconstructed state')
      n = run%dyn%model%n_dy
      m = run%dyn%mbar
      mr = matmul(transpose(v), matmul(m, v))
      ! Mr [A21 A22 B2]_reduced = V^T M [A21 A22 B2]_full [V, V, I]: both are -V^T K V,
      ! -V^T Cd V, V^T W_u^T. Equal to the differencing noise of the linearisation: observed
      ! 2.3e-10 of the largest entry, where linearising the same state twice differs by
      ! 7e-11 (the kinematic solver starts each difference from the last); bound 3e-9.
      expect = matmul(transpose(v), matmul(m, reshape([matmul(full%a(n + 1:, 1:n), v), &
        matmul(full%a(n + 1:, n + 1:), v), full%b(n + 1:, :)], [n, 2 * K + 2])))
      got = matmul(mr, reshape([lin%a(K + 1:, :), lin%b(K + 1:, :)], [K, 2 * K + 2]))
      call suite%close_array(pack(got, .true.), pack(expect, .true.), 0.0_wp, &
        3.0e-9_wp * maxval(abs(expect)), 'M_r [A21, A22, B2] = V^T M [A21 V, A22 V, B2]')
      ! Observed 3e-15 of the largest entry; bound 1e-12.
      call suite%close_array(pack(lin%c(:, 1:K), .true.), pack(matmul(full%c(:, 1:n), v), &
        .true.), 0.0_wp, 1.0e-12_wp * maxval(abs(full%c)), 'C_r = W_y V')
      ! The reduced equations differenced directly: d eta''/d(eta, eta') at the sample.
      ! Observed 7.6e-10 of the largest entry (differences on both sides); bound 1e-8.
      fd = reduced_derivative(run%time(ks), eta, eta_dot)
      call suite%close_array(pack(fd, .true.), pack(lin%a(K + 1:, :), .true.), 0.0_wp, &
        1.0e-8_wp * maxval(abs(fd)), 'reduced A = derivative of the reduced equations')
    end associate
  end subroutine check_sample

  !> Columns for linearise: node `label`'s coordinates and each component in `comps`.
  function io_columns(comps, label) result(which)
    integer, intent(in) :: comps(:)
    character(len=*), intent(in) :: label
    integer :: which(NODE_SLOTS + 1, size(comps)), i
    do i = 1, size(comps)
      which(1:NODE_SLOTS, i) = run%dyn%model%node_coord(:, run%dyn%model%find_node(label))
      which(NODE_SLOTS + 1, i) = comps(i)
    end do
  end function io_columns

  !> [d eta''/d eta, d eta''/d eta'] of the reduced model by Richardson-extrapolated central
  !> differences.
  function reduced_derivative(t, eta, eta_dot) result(d)
    real(wp), intent(in) :: t, eta(:), eta_dot(:)
    real(wp) :: d(size(eta), 2 * size(eta)), h
    integer :: j
    h = 1.0e-4_wp * max(1.0e-3_wp, maxval(abs(eta)))
    do j = 1, 2 * size(eta)
      d(:, j) = (4 * difference(t, [eta, eta_dot], j, h) - &
        difference(t, [eta, eta_dot], j, 2 * h)) / 3
    end do
  end function reduced_derivative

  !> Central difference of the reduced accelerations in component j of the state x.
  function difference(t, x0, j, hs) result(dd)
    real(wp), intent(in) :: t, x0(:), hs
    integer, intent(in) :: j
    real(wp) :: dd(K), ap(K), am(K), x(2 * K)
    integer :: status
    x = x0
    x(j) = x0(j) + hs
    call run%red%accel(t, x(1:K), x(K + 1:), ap, status)
    x(j) = x0(j) - hs
    call run%red%accel(t, x(1:K), x(K + 1:), am, status)
    dd = (ap - am) / (2 * hs)
  end function difference
end program test_linear_reduced
