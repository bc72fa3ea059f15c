!> The sparse path (KLU on the kinematic Jacobian and on the system in nodal accelerations and
!> multipliers; reduced models through W = DF_dy V) against the dense one (LAPACK, eq. (1) with
!> Mbar), on the example scenes, which hold every coordinate class: rigid, prescribed, dynamic
!> and elastic modes, released hinges, nodal coordinates that are degrees of freedom or
!> prescribed. Both solve the same equations, so they agree to round-off: the bounds are
!> 1e-7 relative, where cond(Mbar) (about 1e6 on the beams) times the machine epsilon is 1e-10.
!> Also the sparse LU object itself: repeated entries, transposed solves, copies, singularity.
program test_sparse
  use core_kinds, only: wp
  use core_error, only: error_t
  use core_sparse, only: sparse_lu_t
  use model_scene, only: scene_t
  use dynamics_system, only: dynamics_t
  use reduction_system, only: reduced_t
  use testing, only: suite_t
  use test_scenes, only: source_dir, make_dynamics
  implicit none

  type(suite_t) :: suite
  character(len=*), parameter :: scenes(6) = [character(len=24) :: 'two_link', &
    'leaf_spring_guide', 'cross_spring_pivot', 'slider_crank', 'spin_up', 'four_bar']
  integer :: i

  call suite%init('sparse path against dense path')
  call sparse_lu_checks()
  do i = 1, size(scenes)
    call compare_scene(trim(scenes(i)))
  end do
  call suite%finish()

contains

  subroutine sparse_lu_checks()
    type(sparse_lu_t) :: a, b
    real(wp) :: x(3), y(3), rcond
    integer :: info
    ! [[4, 1, 0], [2, 5, 1], [0, 3, 6]] with entry (1, 1) given as 3 + 1.
    call a%setup(3, [1, 1, 2, 2, 2, 3, 3, 1], [1, 2, 1, 2, 3, 2, 3, 1])
    a%val(a%pos) = 0.0_wp
    a%val(a%pos(1)) = a%val(a%pos(1)) + 3.0_wp
    a%val(a%pos(8)) = a%val(a%pos(8)) + 1.0_wp
    a%val(a%pos(2)) = 1.0_wp
    a%val(a%pos(3)) = 2.0_wp
    a%val(a%pos(4)) = 5.0_wp
    a%val(a%pos(5)) = 1.0_wp
    a%val(a%pos(6)) = 3.0_wp
    a%val(a%pos(7)) = 6.0_wp
    call suite%check(size(a%val) == 7, 'repeated entries share a slot (7 of 8)')
    call a%factor(info, rcond)
    call suite%check(info == 0, 'factor a regular matrix')
    x = [1.0_wp, -2.0_wp, 3.0_wp]
    y = a%multiply(x)
    call a%solve(y)
    call suite%close_array(y, x, 0.0_wp, 1.0e-13_wp, 'solve A x = A x0')
    ! A^T x0 = [4 - 4, 1 - 10 + 9, -2 + 18] = [0, 0, 16]
    y = [0.0_wp, 0.0_wp, 16.0_wp]
    call a%solve(y, transposed=.true.)
    call suite%close_array(y, x, 0.0_wp, 1.0e-13_wp, 'transposed solve')
    b = a
    y = a%multiply(x)
    call b%solve(y)
    call suite%close_array(y, x, 0.0_wp, 1.0e-13_wp, 'a copy factors and solves on its own')
    a%val = 0.0_wp
    a%val(a%pos(1)) = 1.0_wp
    a%val(a%pos(4)) = 1.0_wp
    call a%factor(info, rcond)
    call suite%check(info /= 0, 'a singular matrix is reported')
    y = b%multiply(x)
    call b%solve(y)
    call suite%close_array(y, x, 0.0_wp, 1.0e-13_wp, 'the copy is untouched by the original')
  end subroutine sparse_lu_checks

  function scene_text(name, solver) result(text)
    character(len=*), intent(in) :: name, solver
    character(len=:), allocatable :: text
    character(len=4096) :: line
    integer :: unit, stat
    open(newunit=unit, file=source_dir() // '/input/' // name // '.nml', action='read', &
      iostat=stat)
    text = ''
    call suite%check(stat == 0, 'read input/' // name // '.nml (FLEXMOR_SOURCE_DIR)')
    if (stat /= 0) return
    do
      read(unit, '(a)', iostat=stat) line
      if (stat /= 0) exit
      if (index(line, '&scene ') == 1) line = '&scene linear_solver = ''' // solver // ''', ' &
        // line(8:)
      text = text // trim(line) // new_line('a')
    end do
    close(unit)
  end function scene_text

  subroutine compare_scene(name)
    character(len=*), intent(in) :: name
    type(dynamics_t) :: dense, sparse
    type(scene_t) :: scene
    type(error_t) :: err
    type(reduced_t) :: red_d, red_s
    real(wp), allocatable :: q(:), v(:), a_d(:), a_s(:), jq_d(:, :), jq_s(:, :), jv_d(:, :)
    real(wp), allocatable :: jv_s(:, :), eta(:), eta_d(:), ar_d(:), ar_s(:)
    real(wp), allocatable :: rq_d(:, :), rq_s(:, :), rv_d(:, :), rv_s(:, :)
    real(wp) :: t, scale
    integer :: n, i, k, status
    call make_dynamics(scene_text(name, 'dense'), scene, dense, err)
    call suite%check(err%ok(), name // ': dense model builds ' // err%message)
    if (.not. err%ok()) return
    call make_dynamics(scene_text(name, 'sparse'), scene, sparse, err)
    call suite%check(err%ok(), name // ': sparse model builds ' // err%message)
    if (.not. err%ok()) return
    call suite%check(sparse%sparse .and. .not. dense%sparse, name // ': paths as asked')
    n = dense%model%n_dy
    allocate(q(n), v(n), a_d(n), a_s(n), jq_d(n, n), jq_s(n, n), jv_d(n, n), jv_s(n, n))
    ! A state off the reference: small deformations and rates, early in the motions.
    do i = 1, n
      q(i) = 1.0e-4_wp * sin(1.0_wp * i)
      v(i) = 1.0e-2_wp * cos(1.3_wp * i)
    end do
    t = 0.02_wp
    call dense%accel(t, q, v, a_d, status)
    call suite%check(status == 0, name // ': dense accelerations ' // dense%last_error%message)
    if (status /= 0) return
    call sparse%accel(t, q, v, a_s, status)
    call suite%check(status == 0, name // ': sparse accelerations ' // sparse%last_error%message)
    if (status /= 0) return
    scale = maxval(abs(a_d))
    call suite%close_array(a_s, a_d, 0.0_wp, 1.0e-7_wp * scale, name // ': accelerations')
    call suite%close_array(sparse%kin%x, dense%kin%x, 0.0_wp, 1.0e-10_wp, &
      name // ': nodal coordinates')
    ! An open chain's kinematic Jacobian takes the block solver (core_sparse_block).
    if (name == 'two_link') call suite%check(sparse%kin%jac_sp%uses_blocks(), &
      name // ': kinematic Jacobian factorised by blocks')
    call dense%jacobian(t, q, v, jq_d, jv_d, status)
    call sparse%jacobian(t, q, v, jq_s, jv_s, status)
    call suite%close_array(reshape(jq_s, [n * n]), reshape(jq_d, [n * n]), 0.0_wp, &
      1.0e-7_wp * maxval(abs(jq_d)), name // ': linearised Jacobian da/dq')
    call suite%close_array(reshape(jv_s, [n * n]), reshape(jv_d, [n * n]), 0.0_wp, &
      1.0e-7_wp * max(maxval(abs(jv_d)), tiny(1.0_wp)), name // ': linearised Jacobian da/dv')

    call iteration_matrix(sparse, name, t, q, v, a_d, jq_s, jv_s)

    ! A reduced model on k = min(3, n) arbitrary directions, against V^T Mbar V and V^T
    ! gen_force of the dense assembly (the projection of eq. (1) itself).
    k = min(3, n)
    red_d%dyn = dense
    red_s%dyn = sparse
    allocate(red_d%basis%v(n, k))
    do i = 1, k
      red_d%basis%v(:, i) = [(cos(0.7_wp * i * real(n - i + 1, wp) + 0.3_wp * real(i * i, wp)), &
        i = 1, n)]
    end do
    do i = 1, k
      red_d%basis%v(:, i) = sin(real(i, wp) * [(real(i, wp) + 0.5_wp * real(k, wp), i = 1, n)])
    end do
    red_d%basis%q_ref = q
    red_s%basis = red_d%basis
    allocate(eta(k), eta_d(k), ar_d(k), ar_s(k), rq_d(k, k), rq_s(k, k), rv_d(k, k), rv_s(k, k))
    eta = 1.0e-4_wp * [(real(i, wp), i = 1, k)]
    eta_d = 1.0e-2_wp
    call red_d%accel(t, eta, eta_d, ar_d, status)
    call suite%check(status == 0, name // ': reduced accelerations (dense)')
    call red_s%accel(t, eta, eta_d, ar_s, status)
    call suite%check(status == 0, name // ': reduced accelerations (sparse)')
    call suite%close_array(ar_d, projected(red_d, t, eta, eta_d), 0.0_wp, &
      1.0e-7_wp * maxval(abs(ar_d)), name // ': reduced accelerations = (V^T Mbar V)^-1 V^T f')
    call suite%close_array(ar_s, ar_d, 0.0_wp, 1.0e-7_wp * maxval(abs(ar_d)), &
      name // ': reduced accelerations, sparse = dense')
    call red_d%jacobian(t, eta, eta_d, rq_d, rv_d, status)
    call red_s%jacobian(t, eta, eta_d, rq_s, rv_s, status)
    call suite%close_array(reshape(rq_s, [k * k]), reshape(rq_d, [k * k]), 0.0_wp, &
      1.0e-7_wp * maxval(abs(rq_d)), name // ': reduced Jacobian, sparse = dense')
    call suite%close_array(reshape(rq_d, [k * k]), reshape(reduced_k0(red_d, t, eta, eta_d), &
      [k * k]), 0.0_wp, 1.0e-7_wp * maxval(abs(rq_d)), &
      name // ': reduced Jacobian = -(V^T Mbar V)^-1 V^T K0 V')
  end subroutine compare_scene

  !> The sparse Newton correction (I - c_q da/dq - c_v da/dv)^-1 (a - x) at the Jacobian's
  !> state (t, q, v), formed from the residual of eq. (1), against the dense matrix made from
  !> the linearised Jacobian (jq, jv) and the accelerations a there, for a step of 1e-3 s.
  subroutine iteration_matrix(dyn, name, t, q, v, a, jq, jv)
    type(dynamics_t), intent(inout) :: dyn
    character(len=*), intent(in) :: name
    real(wp), intent(in) :: t, q(:), v(:), a(:), jq(:, :), jv(:, :)
    real(wp) :: x(size(jq, 1)), dx(size(jq, 1)), dx_d(size(jq, 1))
    real(wp) :: c_q, c_v
    integer :: status
    call suite%check(dyn%has_iteration_solver(), name // ': sparse model solves its Newton systems')
    c_q = 0.25e-6_wp
    c_v = 0.5e-3_wp
    call dense_correction(jq, jv, a, c_q, c_v, 2.1_wp, x, dx_d)
    call dyn%iteration_factor(c_q, c_v, status)
    call suite%check(status == 0, name // ': iteration matrix factorised')
    call dyn%newton_correction(t, q, v, x, dx, status)
    call suite%check(status == 0, name // ': Newton correction')
    call suite%close_array(dx, dx_d, 0.0_wp, 1.0e-7_wp * maxval(abs(dx_d)), &
      name // ': sparse Newton solve = dense (I - c_q A_q - c_v A_v)^-1 r')
    call refactor_where_left(dyn, name, t, q, v, c_q, c_v)
  end subroutine iteration_matrix

  !> A trial iterate x = a + max|a| cos(w i) and the dense correction dx = (I - c_q jq -
  !> c_v jv)^-1 (a - x).
  subroutine dense_correction(jq, jv, a, c_q, c_v, w, x, dx)
    real(wp), intent(in) :: jq(:, :), jv(:, :), a(:), c_q, c_v, w
    real(wp), intent(out) :: x(:), dx(:)
    real(wp) :: m(size(a), size(a))
    integer :: ipiv(size(a)), info, i
    m = -c_q * jq - c_v * jv
    do i = 1, size(a)
      m(i, i) = m(i, i) + 1.0_wp
      x(i) = a(i) + maxval(abs(a)) * cos(w * i)
    end do
    dx = a - x
    call dgesv(size(x), 1, m, size(x), ipiv, dx, size(x), info)
  end subroutine dense_correction

  !> iteration_factor takes the state of the last evaluation, here a newton_correction at t2
  !> (the two-link's joints turned by half their travel, the cranks by 0.6 rad), not that of
  !> the last accel at t: its correction then equals the one of the matrix made from the
  !> Jacobian at t2. The model is left at t for the checks that follow.
  subroutine refactor_where_left(dyn, name, t, q, v, c_q, c_v)
    type(dynamics_t), intent(inout) :: dyn
    character(len=*), intent(in) :: name
    real(wp), intent(in) :: t, q(:), v(:), c_q, c_v
    real(wp) :: jq(size(q), size(q)), jv(size(q), size(q))
    real(wp) :: a(size(q)), x(size(q)), dx(size(q)), dx_d(size(q)), t2
    integer :: status
    ! The crank mechanisms turn at 150 rad/s.
    t2 = t + merge(0.004_wp, 0.23_wp, name == 'slider_crank' .or. name == 'four_bar')
    call dyn%jacobian(t2, q, v, jq, jv, status)
    call dyn%accel(t2, q, v, a, status)
    call suite%check(status == 0, name // ': accelerations at t2')
    if (status /= 0) return
    call dense_correction(jq, jv, a, c_q, c_v, 1.7_wp, x, dx_d)
    call dyn%accel(t, q, v, a, status)
    call dyn%iteration_factor(c_q, c_v, status)
    call dyn%newton_correction(t2, q, v, x, dx, status)
    call dyn%iteration_factor(c_q, c_v, status)
    call suite%check(status == 0, name // ': iteration matrix refactorised at t2')
    call dyn%newton_correction(t2, q, v, x, dx, status)
    call suite%close_array(dx, dx_d, 0.0_wp, 1.0e-7_wp * maxval(abs(dx_d)), &
      name // ': refactorised where the last correction was evaluated')
    call dyn%accel(t, q, v, a, status)
  end subroutine refactor_where_left

  !> (V^T Mbar V)^-1 V^T gen_force from the dense assembly at q_ref + V eta.
  function projected(red, t, eta, eta_d) result(a)
    type(reduced_t), intent(inout) :: red
    real(wp), intent(in) :: t, eta(:), eta_d(:)
    real(wp) :: a(size(eta)), mr(size(eta), size(eta))
    real(wp) :: q(red%dyn%model%n_dy), v(red%dyn%model%n_dy)
    type(error_t) :: err
    integer :: ipiv(size(eta)), info
    call red%full_state(eta, eta_d, q, v)
    call red%dyn%assemble(t, q, v, err)
    mr = matmul(transpose(red%basis%v), matmul(red%dyn%mbar, red%basis%v))
    a = matmul(red%dyn%gen_force, red%basis%v)
    call dgesv(size(a), 1, mr, size(a), ipiv, a, size(a), info)
  end function projected

  !> -(V^T Mbar V)^-1 V^T K0 V with the dense K0 (structural_stiffness).
  function reduced_k0(red, t, eta, eta_d) result(j)
    type(reduced_t), intent(inout) :: red
    real(wp), intent(in) :: t, eta(:), eta_d(:)
    real(wp) :: j(size(eta), size(eta)), mr(size(eta), size(eta))
    real(wp) :: q(red%dyn%model%n_dy), v(red%dyn%model%n_dy)
    real(wp), allocatable :: k0(:, :), d0(:, :)
    type(error_t) :: err
    integer :: ipiv(size(eta)), info
    call red%full_state(eta, eta_d, q, v)
    call red%dyn%assemble(t, q, v, err)
    allocate(k0, d0, mold=red%dyn%mbar)
    call red%dyn%structural_stiffness(k0, d0)
    mr = matmul(transpose(red%basis%v), matmul(red%dyn%mbar, red%basis%v))
    j = -matmul(transpose(red%basis%v), matmul(k0, red%basis%v))
    call dgesv(size(eta), size(eta), mr, size(eta), ipiv, j, size(eta), info)
  end function reduced_k0
end program test_sparse
