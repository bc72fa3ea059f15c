!> reduction_eigen: the lowest eigenpairs of K v = lambda M v from ARPACK (shift-invert
!> Lanczos) against dense LAPACK (dsygvd):
!>  (a) a non-uniform fixed-free chain with consistent (non-diagonal) mass, n = 300;
!>  (b) the same chain free-free (singular K, one zero eigenvalue);
!>  (c) an indefinite K (two negative eigenvalues), which moves the shift down;
!>  (d) the two-link benchmark meshed with 40 elements per link through modal_analysis;
!>  (e) bad input and the 'auto' rule;
!>  (f) the two-link at 192 elements per link, where M is so ill-conditioned that dsygvd's
!>      lowest vector needs the inverse-iteration polish: LAPACK against ARPACK and Krylov;
!>  (g) all modes (nev = n) of a well-conditioned chain: the polish keeps dsygvd's
!>      eigenvalues and M-orthonormal vectors; K indefinite beyond every trial shift: no polish,
!>      no failure.
program test_eigen
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_INPUT
  use io_namelist, only: nml_file_t
  use model_scene, only: scene_t
  use dynamics_system, only: dynamics_t
  use core_linalg, only: sym_gen_eig
  use reduction_eigen, only: lowest_modes, eigen_solver_choice, EIGEN_AUTO_DENSE_MAX_N
  use reduction_modal, only: modal_result_t, modal_analysis
  use testing, only: suite_t
  use test_scenes, only: source_dir, itxt, make_from => make_dynamics_from
  implicit none

  integer, parameter :: NEV = 6
  type(suite_t) :: suite

  call suite%init('eigensolvers: ARPACK shift-invert against LAPACK dsygvd')
  call fixed_free_chain()
  call free_free_chain()
  call indefinite()
  call two_link_fine()
  call bad_input()
  call two_link_polish()
  call all_modes()
  call suite%finish()

contains

  !> A chain of n masses and springs with deterministic non-uniform properties; springs
  !> between neighbours plus weaker ones skipping a mass (pentadiagonal K), consistent bar
  !> masses (tridiagonal M). fixed: the first mass is tied to the ground.
  subroutine chain(n, fixed, k, m)
    integer, intent(in) :: n
    logical, intent(in) :: fixed
    real(wp), allocatable, intent(out) :: k(:, :), m(:, :)
    real(wp) :: ke, me
    integer :: i
    allocate(k(n, n), m(n, n))
    k = 0.0_wp
    m = 0.0_wp
    do i = 1, n - 1
      ke = 1.0e4_wp * (1.0_wp + 0.5_wp * sin(1.3_wp * i)**2)
      me = 0.1_wp * (1.0_wp + 0.3_wp * cos(0.7_wp * i))
      call add_pair(k, i, i + 1, ke, -ke)
      call add_pair(m, i, i + 1, me / 3, me / 6)
    end do
    do i = 1, n - 2
      ke = 2.0e3_wp * (1.0_wp + 0.4_wp * cos(2.1_wp * i)**2)
      call add_pair(k, i, i + 2, ke, -ke)
    end do
    if (fixed) then
      k(1, 1) = k(1, 1) + 1.0e4_wp
      m(1, 1) = m(1, 1) + 0.1_wp / 3
    end if
  end subroutine chain

  subroutine add_pair(a, i, j, diag, off)
    real(wp), intent(inout) :: a(:, :)
    integer, intent(in) :: i, j
    real(wp), intent(in) :: diag, off
    a(i, i) = a(i, i) + diag
    a(j, j) = a(j, j) + diag
    a(i, j) = a(i, j) + off
    a(j, i) = a(j, i) + off
  end subroutine add_pair

  real(wp) function seconds()
    integer(kind=8) :: c, rate
    call system_clock(c, rate)
    seconds = real(c, wp) / real(rate, wp)
  end function seconds

  !> Solve with both solvers and compare; first_vec: the first mode whose vector is compared
  !> (a rigid mode has equal components, so its sign convention is decided by rounding).
  subroutine compare(k, m, what, first_vec, lam_ref)
    real(wp), intent(in) :: k(:, :), m(:, :)
    character(len=*), intent(in) :: what
    integer, intent(in) :: first_vec
    real(wp), allocatable, intent(out), optional :: lam_ref(:)
    real(wp), allocatable :: lam_l(:), v_l(:, :), lam_a(:), v_a(:, :), g(:, :), r(:)
    type(error_t) :: err
    character(len=8) :: used
    real(wp) :: t0, t_lapack, t_arpack, rel_lam, vec_diff, ortho, resid, lam_scale
    integer :: i, n
    n = size(k, 1)
    t0 = seconds()
    call lowest_modes(k, m, NEV, 'lapack', lam_l, v_l, err, used)
    t_lapack = seconds() - t0
    call suite%check(err%ok() .and. used == 'lapack', what // ': LAPACK runs')
    if (.not. err%ok()) then
      write(*, '(a)') '    ' // err%message
      return
    end if
    t0 = seconds()
    call lowest_modes(k, m, NEV, 'arpack', lam_a, v_a, err, used)
    t_arpack = seconds() - t0
    call suite%check(err%ok() .and. used == 'arpack', what // ': ARPACK runs')
    if (.not. err%ok()) then
      write(*, '(a)') '    ' // err%message
      return
    end if
    if (present(lam_ref)) lam_ref = lam_l
    call suite%check(size(lam_a) == NEV .and. all(shape(v_a) == [n, NEV]), &
      what // ': nev pairs returned')
    call suite%check(all(lam_a(2:) >= lam_a(:NEV - 1)), what // ': ARPACK ascending')

    ! A zero eigenvalue has no relative error: its rounding is that of ||K|| / ||M||.
    lam_scale = maxval(sum(abs(k), 1)) / maxval(sum(abs(m), 1))
    rel_lam = 0
    do i = 1, NEV
      rel_lam = max(rel_lam, abs(lam_a(i) - lam_l(i)) / max(abs(lam_l(i)), 1.0e-6_wp * lam_scale))
    end do
    vec_diff = maxval(abs(v_a(:, first_vec:) - v_l(:, first_vec:)))
    g = matmul(transpose(v_a), matmul(m, v_a))
    do i = 1, NEV
      g(i, i) = g(i, i) - 1
    end do
    ortho = maxval(abs(g))
    resid = 0
    do i = 1, NEV
      r = matmul(k, v_a(:, i)) - lam_a(i) * matmul(m, v_a(:, i))
      resid = max(resid, maxval(abs(r)) / ((maxval(sum(abs(k), 1)) + &
        abs(lam_a(i)) * maxval(sum(abs(m), 1))) * maxval(abs(v_a(:, i)))))
    end do
    write(*, '(a,i0,a)') '    ' // what // ', n = ', n, ':'
    write(*, '(a,*(es12.4))') '      lambda (LAPACK)    ', lam_l
    write(*, '(a,es9.2,a,es9.2,a,es9.2,a,es9.2)') '      max rel. diff lambda ', rel_lam, &
      ', max |v_A - v_L| ', vec_diff, ', max |V^T M V - I| ', ortho, ', rel. residual ', resid
    write(*, '(a,f9.3,a,f9.3,a)') '      time LAPACK ', 1.0e3_wp * t_lapack, ' ms, ARPACK ', &
      1.0e3_wp * t_arpack, ' ms'
    call suite%check(rel_lam < 1.0e-8_wp, what // ': eigenvalues equal to 1e-8 relative')
    call suite%check(vec_diff < 1.0e-6_wp, what // ': eigenvectors equal to 1e-6 (max norm)')
    call suite%check(ortho < 1.0e-10_wp, what // ': ARPACK vectors M-orthonormal to 1e-10')
    call suite%check(resid < 1.0e-12_wp, what // ': ARPACK backward error of K v = lambda M v')
  end subroutine compare

  subroutine fixed_free_chain()
    real(wp), allocatable :: k(:, :), m(:, :)
    call chain(300, .true., k, m)
    call compare(k, m, '(a) fixed-free chain', 1)
  end subroutine fixed_free_chain

  subroutine free_free_chain()
    real(wp), allocatable :: k(:, :), m(:, :), lam(:)
    call chain(300, .false., k, m)
    call compare(k, m, '(b) free-free chain (singular K)', 2, lam)
    if (.not. allocated(lam)) return
    call suite%check(abs(lam(1)) < 1.0e-10_wp * lam(2) .and. lam(2) > 0, &
      '(b) one zero eigenvalue, the others positive')
  end subroutine free_free_chain

  !> K - s M with s between the second and third eigenvalue: two negative eigenvalues, so
  !> the first trial shifts leave K - sigma M indefinite.
  subroutine indefinite()
    real(wp), allocatable :: k(:, :), m(:, :), lam(:), v(:, :)
    type(error_t) :: err
    real(wp) :: s
    call chain(300, .true., k, m)
    call lowest_modes(k, m, 3, 'lapack', lam, v, err)
    if (.not. err%ok()) return
    s = 0.5_wp * (lam(2) + lam(3))
    k = k - s * m
    call compare(k, m, '(c) indefinite K', 1, lam)
    if (allocated(lam)) call suite%check(count(lam < 0) == 2, '(c) two negative eigenvalues')
  end subroutine indefinite

  !> The two-link benchmark of input/two_link.nml with 40 elements per link.
  subroutine two_link_fine()
    type(nml_file_t) :: f
    type(scene_t) :: scene
    type(dynamics_t) :: dyn
    type(error_t) :: err
    type(modal_result_t) :: res_l, res_a, res_auto
    real(wp), allocatable :: q(:), g(:, :), lam(:), v(:, :)
    real(wp) :: t0, t_lapack, t_arpack, rel, vec_diff
    integer :: i
    call f%load(source_dir() // '/input/two_link.nml', err)
    do i = 1, 2
      if (err%ok()) call f%groups(f%group_index('link', i))%set_raw('n_elements', '40', err)
    end do
    if (err%ok()) call make_from(f, scene, dyn, err)
    call suite%check(err%ok(), '(d) two-link, 40 elements per link: model builds')
    if (.not. err%ok()) then
      write(*, '(a)') '    ' // err%message
      return
    end if
    allocate(q(dyn%model%n_dy))
    q = 0.0_wp
    t0 = seconds()
    call modal_analysis(dyn, 0.0_wp, q, NEV, res_l, err, solver='lapack')
    t_lapack = seconds() - t0
    call suite%check(err%ok() .and. res_l%solver == 'lapack', '(d) two-link: modal, lapack')
    if (.not. err%ok()) return
    t0 = seconds()
    call modal_analysis(dyn, 0.0_wp, q, NEV, res_a, err, solver='arpack')
    t_arpack = seconds() - t0
    call suite%check(err%ok() .and. res_a%solver == 'arpack', '(d) two-link: modal, arpack')
    if (.not. err%ok()) then
      write(*, '(a)') '    ' // err%message
      return
    end if
    rel = maxval(abs(res_a%frequency_hz - res_l%frequency_hz) / abs(res_l%frequency_hz))
    vec_diff = maxval(abs(res_a%shapes - res_l%shapes))
    g = matmul(transpose(res_a%shapes), matmul(res_a%m0, res_a%shapes))
    do i = 1, NEV
      g(i, i) = g(i, i) - 1
    end do
    write(*, '(a,i0,a)') '    (d) two-link, n_dy = ', dyn%model%n_dy, ':'
    write(*, '(a,*(f11.4))') '      f [Hz] (LAPACK)  ', res_l%frequency_hz
    write(*, '(a,es9.2,a,es9.2,a,es9.2)') '      max rel. diff f ', rel, &
      ', max |v_A - v_L| ', vec_diff, ', max |V^T M0 V - I| ', maxval(abs(g))
    write(*, '(a,f9.3,a,f9.3,a)') '      modal_analysis time LAPACK ', 1.0e3_wp * t_lapack, &
      ' ms, ARPACK ', 1.0e3_wp * t_arpack, ' ms (both include the tangent stiffness)'
    ! The eigensolvers alone, on the matrices of the modal analysis (mean of 5 calls).
    t0 = seconds()
    do i = 1, 5
      call lowest_modes(res_l%k0, res_l%m0, NEV, 'lapack', lam, v, err)
    end do
    t_lapack = (seconds() - t0) / 5
    t0 = seconds()
    do i = 1, 5
      call lowest_modes(res_l%k0, res_l%m0, NEV, 'arpack', lam, v, err)
    end do
    t_arpack = (seconds() - t0) / 5
    write(*, '(a,f9.3,a,f9.3,a)') '      lowest_modes time LAPACK ', 1.0e3_wp * t_lapack, &
      ' ms, ARPACK ', 1.0e3_wp * t_arpack, ' ms'
    call suite%check(dyn%model%n_dy == 160, '(d) two-link: n_dy = 160')
    call suite%check(rel < 1.0e-8_wp, '(d) two-link: frequencies equal to 1e-8 relative')
    call suite%check(vec_diff < 1.0e-6_wp, '(d) two-link: mode shapes equal to 1e-6')
    call suite%check(maxval(abs(g)) < 1.0e-10_wp, '(d) two-link: ARPACK shapes M0-orthonormal')
    call suite%check(size(res_a%node_shapes, 2) == NEV, '(d) two-link: nodal shapes for nev modes')

    call modal_analysis(dyn, 0.0_wp, q, NEV, res_auto, err)
    ! 160 dynamic coordinates on the sparse path, no loads: 'auto' is the Krylov path there
    ! (reduction_modal), which the dense matrices' solvers are compared with in
    ! test_krylov_modes.
    call suite%check(err%ok() .and. res_auto%solver == 'krylov', &
      "(d) two-link: the default solver 'auto' takes the Krylov path, recorded (" // &
      trim(res_auto%solver) // ')')
    call modal_analysis(dyn, 0.0_wp, q, 0, res_auto, err, solver='arpack')
    call suite%check(err%ok() .and. res_auto%solver == 'lapack' .and. &
      size(res_auto%omega2) == dyn%model%n_dy, '(d) two-link: n_modes = 0 (all) uses LAPACK')
  end subroutine two_link_fine

  subroutine bad_input()
    real(wp), allocatable :: k(:, :), m(:, :), lam(:), v(:, :)
    type(error_t) :: err
    call chain(20, .true., k, m)
    call lowest_modes(k, m, 3, 'lanczos', lam, v, err)
    call suite%check(err%code == ERR_INPUT .and. index(err%message, "'arpack'") > 0 .and. &
      index(err%message, "'lapack'") > 0 .and. index(err%message, "'auto'") > 0, &
      '(e) unknown solver: ERR_INPUT listing the valid names')
    if (.not. err%ok()) write(*, '(a)') '    ' // err%message
    call lowest_modes(k, m, 21, 'lapack', lam, v, err)
    call suite%check(err%code == ERR_INPUT, '(e) nev > n: ERR_INPUT')
    if (.not. err%ok()) write(*, '(a)') '    ' // err%message
    call lowest_modes(k, m, -1, 'auto', lam, v, err)
    call suite%check(err%code == ERR_INPUT, '(e) nev < 0: ERR_INPUT')
    call lowest_modes(k, m, 19, 'arpack', lam, v, err)
    call suite%check(err%code == ERR_INPUT, '(e) arpack with nev = n - 1: ERR_INPUT')
    if (.not. err%ok()) write(*, '(a)') '    ' // err%message
    call lowest_modes(k, m, 18, 'arpack', lam, v, err)
    call suite%check(err%ok() .and. size(lam) == 18, '(e) arpack with nev = n - 2 runs')
    call lowest_modes(k, m, 0, 'arpack', lam, v, err)
    call suite%check(err%ok() .and. size(lam) == 0, '(e) nev = 0: empty result')
    call lowest_modes(k, m(1:19, 1:19), 3, 'lapack', lam, v, err)
    call suite%check(err%code == ERR_INPUT, '(e) K and M of different sizes: ERR_INPUT')
    m(5, 5) = -1.0_wp
    call lowest_modes(k, m, 3, 'arpack', lam, v, err)
    call suite%check(.not. err%ok(), '(e) arpack, M not positive definite: error')
    if (.not. err%ok()) write(*, '(a)') '    ' // err%message

    call suite%check(eigen_solver_choice('auto', EIGEN_AUTO_DENSE_MAX_N, 6) == 'lapack' .and. &
      eigen_solver_choice('auto', 1000, 6) == 'arpack' .and. &
      eigen_solver_choice('auto', 1000, 500) == 'lapack' .and. &
      eigen_solver_choice(' arpack', 10, 2) == 'arpack', "(e) the 'auto' rule")
  end subroutine bad_input

  !> input/two_link.nml with 192 elements per link (768 coordinates): lambda_max / lambda_1
  !> is about 1e14, and dsygvd's vector of mode 1 holds enough of mode 2 for its Rayleigh
  !> quotient to be off by 3.5e-8 relative (9e-9 at 160 elements, 6e-7 at 224). Polished,
  !> the lowest 4 eigenvalues agree with ARPACK's on the same matrices to 3.4e-14 and with
  !> the Krylov path's (its own rounding) to 2.8e-12 (observed): the bound is 35x the
  !> larger, and 350x below the unpolished error.
  subroutine two_link_polish()
    integer, parameter :: N_EL = 192, NCMP = 4
    real(wp), parameter :: BOUND = 1.0e-10_wp
    type(nml_file_t) :: f
    type(scene_t) :: scene
    type(dynamics_t) :: dyn
    type(error_t) :: err
    type(modal_result_t) :: res_l, res_k
    real(wp), allocatable :: q(:), lam_a(:), v_a(:, :), lam_raw(:), v_raw(:, :), old(:)
    real(wp) :: rel_a, rel_k, rel_old
    integer :: i, info
    call f%load(source_dir() // '/input/two_link.nml', err)
    do i = 1, 2
      if (err%ok()) call f%groups(f%group_index('link', i))%set_raw('n_elements', &
        itxt(N_EL), err)
    end do
    if (err%ok()) call make_from(f, scene, dyn, err)
    call suite%check(err%ok(), '(f) two-link, 192 elements per link: model builds')
    if (.not. err%ok()) return
    allocate(q(dyn%model%n_dy))
    q = 0.0_wp
    call modal_analysis(dyn, 0.0_wp, q, NCMP, res_l, err, solver='lapack')
    if (err%ok()) call lowest_modes(res_l%k0, res_l%m0, NCMP, 'arpack', lam_a, v_a, err)
    if (err%ok()) call modal_analysis(dyn, 0.0_wp, q, NCMP, res_k, err, solver='krylov')
    call suite%check(err%ok() .and. res_l%solver == 'lapack' .and. res_k%solver == 'krylov', &
      '(f) two-link: LAPACK, ARPACK and Krylov run')
    if (.not. err%ok()) then
      write(*, '(a)') '    ' // err%message
      return
    end if
    ! What LAPACK gave before the polish: dsygvd's vectors, their Rayleigh quotients.
    allocate(lam_raw(size(q)), v_raw(size(q), size(q)))
    call sym_gen_eig(res_l%k0, res_l%m0, lam_raw, v_raw, info)
    old = sum(v_raw(:, :NCMP) * matmul(res_l%k0, v_raw(:, :NCMP)), 1) / &
      sum(v_raw(:, :NCMP) * matmul(res_l%m0, v_raw(:, :NCMP)), 1)
    rel_a = maxval(abs(res_l%omega2 - lam_a) / abs(lam_a))
    rel_k = maxval(abs(res_l%omega2 - res_k%omega2) / abs(res_k%omega2))
    rel_old = maxval(abs(old - lam_a) / abs(lam_a))
    write(*, '(a,i0,a,es9.2,a,es9.2,a,es9.2)') '    (f) two-link, n_dy = ', size(q), &
      ': max rel. diff lambda LAPACK - ARPACK ', rel_a, ', LAPACK - Krylov ', rel_k, &
      '; unpolished dsygvd - ARPACK ', rel_old
    call suite%check(info == 0 .and. size(q) == 4 * N_EL, '(f) two-link: 768 coordinates')
    call suite%check(rel_a < BOUND, '(f) two-link: lowest eigenvalues LAPACK = ARPACK to 1e-10')
    call suite%check(rel_k < BOUND, '(f) two-link: lowest eigenvalues LAPACK = Krylov to 1e-10')
  end subroutine two_link_polish

  !> All modes of a 120-mass fixed-free chain (lambda_max / lambda_1 about 1e5, M well
  !> conditioned): dsygvd alone is accurate here, so the polish must leave its Rayleigh
  !> quotients within their rounding (observed 8e-15 to 1.5e-13 relative on the lowest,
  !> with the BLAS's kernel and threads: 6e-3 of the bound n eps (||K|| + |lambda| ||M||) /
  !> mu_min(M)) and return M-orthonormal vectors (observed 1e-15) with residuals at rounding
  !> (6e-16). Then K shifted below -1e4 ||K||_1 / ||M||_1, the last
  !> trial shift: no shift proves K - sigma M definite, so the polish is skipped and dsygvd's
  !> pairs come back unchanged.
  subroutine all_modes()
    integer, parameter :: N = 120
    real(wp), allocatable :: k(:, :), m(:, :), lam(:), v(:, :), lam_raw(:), v_raw(:, :), &
      old(:), g(:, :), r(:, :), eye(:, :), mu(:), v_m(:, :)
    type(error_t) :: err
    real(wp) :: rel, drift, ortho, resid, s
    integer :: i, info, info_m
    call chain(N, .true., k, m)
    allocate(lam_raw(N), v_raw(N, N))
    call sym_gen_eig(k, m, lam_raw, v_raw, info)
    ! M's smallest eigenvalue (M x = mu I x) for the rounding bound below.
    allocate(eye(N, N), mu(N), v_m(N, N))
    eye = 0.0_wp
    do i = 1, N
      eye(i, i) = 1.0_wp
    end do
    call sym_gen_eig(m, eye, mu, v_m, info_m)
    old = sum(v_raw * matmul(k, v_raw), 1) / sum(v_raw * matmul(m, v_raw), 1)
    call lowest_modes(k, m, N, 'lapack', lam, v, err)
    call suite%check(err%ok() .and. info == 0 .and. info_m == 0, '(g) all modes: LAPACK runs')
    if (.not. err%ok()) return
    rel = maxval(abs(lam - old) / abs(old))
    ! Rounding of a Rayleigh quotient of an M-normalised v: |v^T K v - fl(v^T K v)| <= n eps
    ! |v|^T |K| |v|, so its eigenvalue moves by up to about n eps (||K|| + |lambda| ||M||) /
    ! mu_min(M) (the 1-norms; M's eigenvalues mu lie within a few times of each other here).
    drift = maxval(abs(lam - old) / (N * epsilon(1.0_wp) * (maxval(sum(abs(k), 1)) + &
      abs(old) * maxval(sum(abs(m), 1))) / mu(1)))
    g = matmul(transpose(v), matmul(m, v))
    do i = 1, N
      g(i, i) = g(i, i) - 1
    end do
    ortho = maxval(abs(g))
    r = matmul(k, v) - matmul(m, v) * spread(lam, 1, N)
    resid = maxval(maxval(abs(r), 1) / ((maxval(sum(abs(k), 1)) + abs(lam) * &
      maxval(sum(abs(m), 1))) * maxval(abs(v), 1)))
    write(*, '(a,i0,a,es9.2,a,es9.2,a,es9.2,a,es9.2)') '    (g) all ', N, ' modes: max rel. ' // &
      'diff ' // &
      'lambda polished - unpolished ', rel, ' (', drift, ' of the rounding bound), max ' // &
      '|V^T M V - I| ', ortho, ', rel. residual ', resid
    call suite%check(drift < 0.1_wp, '(g) all modes: eigenvalues unchanged to a tenth of ' // &
      'their rounding')
    call suite%check(ortho < 1.0e-13_wp, '(g) all modes: polished vectors M-orthonormal')
    call suite%check(resid < 1.0e-13_wp, '(g) all modes: backward error of K v = lambda M v')

    s = 1.0e5_wp * maxval(sum(abs(k), 1)) / maxval(sum(abs(m), 1))
    k = k - s * m
    call sym_gen_eig(k, m, lam_raw, v_raw, info)
    old = sum(v_raw(:, :6) * matmul(k, v_raw(:, :6)), 1) / &
      sum(v_raw(:, :6) * matmul(m, v_raw(:, :6)), 1)
    call lowest_modes(k, m, 6, 'lapack', lam, v, err)
    call suite%check(err%ok(), '(g) K indefinite beyond every trial shift: LAPACK still runs')
    if (err%ok()) call suite%check(maxval(abs(lam - old) / abs(old)) < 1.0e-14_wp, &
      '(g) K indefinite beyond every trial shift: dsygvd''s eigenvalues, unpolished')
  end subroutine all_modes
end program test_eigen
