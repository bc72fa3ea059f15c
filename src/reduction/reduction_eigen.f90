!> The lowest eigenpairs of the symmetric-definite problem K v = lambda M v (K symmetric, M
!> symmetric positive definite, both dense), by dense LAPACK (dsygvd) or by ARPACK (Lanczos in
!> shift-invert mode), with one output convention for both:
!>   - lambda ascending, v(:, i) M-normalised (V^T M V = I);
!>   - the component of largest magnitude of each vector positive (the first one if several
!>     tie), so that the two solvers give comparable vectors for simple eigenvalues;
!>   - only the lower triangles of K and M are read, as dsygvd does, so a slightly
!>     unsymmetric input gives the same answer from either solver.
!> dsygvd's vectors are polished by inverse iteration with the shift ARPACK uses
!> (polish_by_inverse_iteration), both solvers' eigenvalues are Rayleigh quotients
!> (rayleigh_polish): the two then agree to rounding even where M is ill-conditioned.
module reduction_eigen
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_INPUT, ERR_NUMERIC
  use core_linalg, only: sym_gen_eig, chol_factor
  use core_strings, only: int_str
  use core_sort, only: sort_by_value
  use reduction_lanczos, only: lanczos_t, LZ_OP, LZ_OP_BX, LZ_B
  implicit none
  private
  public :: lowest_modes, eigen_solver_choice, sort_modes
  public :: EIGEN_AUTO_DENSE_MAX_N, EIGEN_AUTO_NEV_DIVISOR

  !> solver = 'auto' takes LAPACK when n <= EIGEN_AUTO_DENSE_MAX_N or
  !> nev > n / EIGEN_AUTO_NEV_DIVISOR, and ARPACK otherwise. Below the size limit the dense
  !> solver costs 5 ms at most and needs no shift; above it ARPACK wins as long as the wanted
  !> modes are a small part of the spectrum (its cost grows with nev, the dense one is n^3
  !> whatever nev is). Measured (Release, OpenBLAS on one thread, the chains of
  !> tests/test_eigen.f90), dense / ARPACK: n = 200, nev = 6: 3.8 / 0.9 ms; n = 300, nev = 6:
  !> 12.7 / 2.7 ms, nev = 30: 11.8 / 6.3 ms, nev = 60: 12.5 / 13.7 ms; n = 1000, nev = 60:
  !> 246 / 179 ms.
  integer, parameter :: EIGEN_AUTO_DENSE_MAX_N = 200
  integer, parameter :: EIGEN_AUTO_NEV_DIVISOR = 10

  !> Shifts tried, as multiples of -||K||_1 / ||M||_1 (see shift_below_spectrum).
  real(wp), parameter :: SHIFT_FACTORS(7) = [1.0e-8_wp, 1.0e-6_wp, 1.0e-4_wp, 1.0e-2_wp, &
    1.0_wp, 1.0e2_wp, 1.0e4_wp]

  !> Inverse-iteration steps applied to dsygvd's vectors (see polish_by_inverse_iteration).
  !> Each divides the part of mode j in the vector of mode i < j by about lambda_j / lambda_i;
  !> what dsygvd leaves there is mostly the nearest modes (two-link, 1024 coordinates: mode 2
  !> at 2.5e-5 in mode 1, lambda_2 / lambda_1 = 58), so one step takes the lowest eigenvalue
  !> from 3.5e-8 to 1.0e-11 relative and a second one to rounding (1.3e-13, as ARPACK).
  integer, parameter :: POLISH_STEPS = 2

  interface
    subroutine dsymv(uplo, n, alpha, a, lda, x, incx, beta, y, incy)
      import :: wp
      character(len=1), intent(in) :: uplo
      integer, intent(in) :: n, lda, incx, incy
      real(wp), intent(in) :: alpha, beta, a(lda, *), x(*)
      real(wp), intent(inout) :: y(*)
    end subroutine dsymv
    subroutine dsymm(side, uplo, m, n, alpha, a, lda, b, ldb, beta, c, ldc)
      import :: wp
      character(len=1), intent(in) :: side, uplo
      integer, intent(in) :: m, n, lda, ldb, ldc
      real(wp), intent(in) :: alpha, beta, a(lda, *), b(ldb, *)
      real(wp), intent(inout) :: c(ldc, *)
    end subroutine dsymm
    subroutine dgemm(transa, transb, m, n, k, alpha, a, lda, b, ldb, beta, c, ldc)
      import :: wp
      character(len=1), intent(in) :: transa, transb
      integer, intent(in) :: m, n, k, lda, ldb, ldc
      real(wp), intent(in) :: alpha, beta, a(lda, *), b(ldb, *)
      real(wp), intent(inout) :: c(ldc, *)
    end subroutine dgemm
    subroutine dtrsm(side, uplo, transa, diag, m, n, alpha, a, lda, b, ldb)
      import :: wp
      character(len=1), intent(in) :: side, uplo, transa, diag
      integer, intent(in) :: m, n, lda, ldb
      real(wp), intent(in) :: alpha, a(lda, *)
      real(wp), intent(inout) :: b(ldb, *)
    end subroutine dtrsm
    subroutine dpotrf(uplo, n, a, lda, info)
      import :: wp
      character(len=1), intent(in) :: uplo
      integer, intent(in) :: n, lda
      real(wp), intent(inout) :: a(lda, *)
      integer, intent(out) :: info
    end subroutine dpotrf
    subroutine dpotrs(uplo, n, nrhs, a, lda, b, ldb, info)
      import :: wp
      character(len=1), intent(in) :: uplo
      integer, intent(in) :: n, nrhs, lda, ldb
      real(wp), intent(in) :: a(lda, *)
      real(wp), intent(inout) :: b(ldb, *)
      integer, intent(out) :: info
    end subroutine dpotrs
  end interface

contains

  !> The solver 'auto' resolves to for an n x n problem and nev modes ('lapack' or 'arpack');
  !> other names come back as given (trimmed).
  pure function eigen_solver_choice(solver, n, nev) result(name)
    character(len=*), intent(in) :: solver
    integer, intent(in) :: n, nev
    character(len=:), allocatable :: name
    name = trim(adjustl(solver))
    if (name /= 'auto') return
    if (n <= EIGEN_AUTO_DENSE_MAX_N .or. nev > n / EIGEN_AUTO_NEV_DIVISOR .or. &
      nev > n - 2) then
      name = 'lapack'
    else
      name = 'arpack'
    end if
  end function eigen_solver_choice

  !> The nev lowest eigenpairs of k v = lambda m v with solver 'lapack', 'arpack' or 'auto'
  !> (see EIGEN_AUTO_DENSE_MAX_N). `used` returns the solver that ran.
  subroutine lowest_modes(k, m, nev, solver, lambda, v, err, used)
    real(wp), intent(in) :: k(:, :), m(:, :)
    integer, intent(in) :: nev
    character(len=*), intent(in) :: solver
    real(wp), allocatable, intent(out) :: lambda(:), v(:, :)
    type(error_t), intent(out) :: err
    character(len=*), intent(out), optional :: used
    character(len=:), allocatable :: name
    integer :: n, j
    n = size(k, 1)
    if (present(used)) used = ''
    if (size(k, 2) /= n .or. size(m, 1) /= n .or. size(m, 2) /= n) then
      call err%set(ERR_INPUT, 'eigensolver: K and M must be square and of the same size')
      return
    end if
    if (nev < 0 .or. nev > n) then
      call err%set(ERR_INPUT, 'eigensolver: the number of modes ' // int_str(nev) // &
        ' is outside 0..' // int_str(n) // ' (the problem size)')
      return
    end if
    name = eigen_solver_choice(solver, n, nev)
    if (nev == 0 .and. any(name == [character(len=6) :: 'lapack', 'arpack'])) then
      allocate(lambda(0), v(n, 0))
      if (present(used)) used = name
      return
    end if
    select case (name)
    case ('lapack')
      call lapack_modes(k, m, nev, lambda, v, err)
    case ('arpack')
      if (nev > n - 2) then
        ! ARPACK needs nev < ncv <= n and a Lanczos basis larger than the wanted space.
        call err%set(ERR_INPUT, "eigensolver 'arpack': needs at most n - 2 modes (n = " // &
          int_str(n) // ', asked ' // int_str(nev) // "); use 'lapack' or 'auto'")
        return
      end if
      call arpack_modes(k, m, nev, lambda, v, err)
    case default
      call err%set(ERR_INPUT, "eigensolver: unknown solver '" // name // &
        "' (valid: 'auto', 'lapack', 'arpack')")
      return
    end select
    if (.not. err%ok()) return
    if (present(used)) used = name
    call rayleigh_polish(k, m, lambda, v)
    do j = 1, nev
      if (v(maxloc(abs(v(:, j)), 1), j) < 0) v(:, j) = -v(:, j)
    end do
    call sort_modes(lambda, v)
  end subroutine lowest_modes

  !> Eigenvalues ascending, the vectors' columns with them. The Rayleigh quotients replace the
  !> solvers' ascending eigenvalues, and where several are equal in exact arithmetic (the
  !> zero eigenvalues of rigid-body modes: 1e-40 and -1e-43 in rad^2/s^2) they come out in
  !> the order of their rounding, not ascending.
  subroutine sort_modes(lambda, v)
    real(wp), intent(inout) :: lambda(:), v(:, :)
    integer :: order(size(lambda)), j
    order = [(j, j = 1, size(lambda))]
    call sort_by_value(order, lambda)
    lambda = lambda(order)
    v = v(:, order)
  end subroutine sort_modes

  !> Eigenvalues as Rayleigh quotients v^T K v of the M-normalised vectors. Their error is
  !> of second order in the vector error, while dsygvd's eigenvalues carry the rounding of
  !> its reduction L^-1 K L^-T, which grows with the condition of M (the rotary inertia of
  !> short beam elements is tiny: on the two-link with 40 elements per link, dsygvd's lowest
  !> eigenvalue is off by 1e-6 relative, the quotient of its own vector by 1e-12), and
  !> ARPACK's carry the cancellation in sigma + 1 / nu. The quotient is only as good as the
  !> vector, though: on finer meshes dsygvd's vector of mode 1 holds enough of mode 2
  !> (2.5e-5 at 256 elements per link) for the quotient to be off by 3.5e-8, hence the
  !> inverse iteration before it (polish_by_inverse_iteration). Both solvers then agree to
  !> rounding.
  subroutine rayleigh_polish(k, m, lambda, v)
    real(wp), intent(in) :: k(:, :), m(:, :)
    real(wp), intent(inout) :: lambda(:), v(:, :)
    real(wp) :: y(size(v, 1), size(v, 2)), vmv
    integer :: j, n, nev
    n = size(k, 1)
    nev = size(lambda)
    if (n == 0 .or. nev == 0) return
    ! dsymm: a matrix product, so that all n modes cost little next to dsygvd itself
    call dsymm('L', 'L', n, nev, 1.0_wp, m, n, v, n, 0.0_wp, y, n)
    do j = 1, nev
      vmv = dot_product(v(:, j), y(:, j))
      if (vmv > 0) v(:, j) = v(:, j) / sqrt(vmv)
    end do
    call dsymm('L', 'L', n, nev, 1.0_wp, k, n, v, n, 0.0_wp, y, n)
    do j = 1, nev
      lambda(j) = dot_product(v(:, j), y(:, j))
    end do
  end subroutine rayleigh_polish

  !> All eigenpairs by dsygvd, then the first nev, polished by inverse iteration.
  subroutine lapack_modes(k, m, nev, lambda, v, err)
    real(wp), intent(in) :: k(:, :), m(:, :)
    integer, intent(in) :: nev
    real(wp), allocatable, intent(out) :: lambda(:), v(:, :)
    type(error_t), intent(inout) :: err
    real(wp), allocatable :: lam(:), vv(:, :)
    integer :: n, info
    n = size(k, 1)
    allocate(lam(n), vv(n, n))
    call sym_gen_eig(k, m, lam, vv, info)
    if (info > n) then
      call err%set(ERR_NUMERIC, "eigensolver 'lapack': the mass matrix is not positive " // &
        'definite (leading minor of order ' // int_str(info - n) // ')')
      return
    else if (info /= 0) then
      call err%set(ERR_NUMERIC, "eigensolver 'lapack': dsygvd did not converge (info = " // &
        int_str(info) // ')')
      return
    end if
    lambda = lam(1:nev)
    v = vv(:, 1:nev)
    deallocate(vv)
    call polish_by_inverse_iteration(k, m, v)
  end subroutine lapack_modes

  !> POLISH_STEPS steps of block inverse iteration on dsygvd's M-orthonormal vectors v:
  !> Y = (K - sigma M)^-1 M V with sigma below the spectrum, then Y made M-orthonormal from
  !> the lowest mode up. dsygvd's vectors are exact for a perturbation of L^-1 K L^-T of the
  !> size of its rounding, eps ||L^-1 K L^-T|| ~ eps lambda_max, which mixes into mode i
  !> the modes j nearby in proportion to eps lambda_max / (lambda_j - lambda_i): with the
  !> tiny rotary inertia of short beams lambda_max / lambda_1 reaches 1e14. The solve with
  !> K - sigma M does not form L^-1: its rounding stays at the size of K's, and the step
  !> scales the part of mode j in y_i by (lambda_i - sigma) / (lambda_j - sigma).
  !> The orthonormalisation is Gram-Schmidt in the M inner product done as a Cholesky QR
  !> (G = Y^T M Y = R^T R, Y <- Y R^-1): the same triangular factor, so the same order
  !> (y_i loses its parts along y_1 .. y_(i-1), whose errors are smaller), but in BLAS-3,
  !> which for nev = n keeps the cost at the order of dsygvd's. Its loss of orthogonality,
  !> eps cond(Y)^2, stays small because the columns of Y are close to M-orthogonal already;
  !> the second step's factorisation acts as the reorthogonalisation of the first's
  !> (CholeskyQR2). The vectors stay as dsygvd gave them where no shift proves
  !> K - sigma M positive definite (K indefinite by more than 1e4 ||K|| / ||M||) or G is
  !> numerically not positive definite (columns dependent): dsygvd's result is still a
  !> valid one, only less accurate in the lowest modes, and the polish is no reason to fail.
  subroutine polish_by_inverse_iteration(k, m, v)
    real(wp), intent(in) :: k(:, :), m(:, :)
    real(wp), intent(inout) :: v(:, :)
    real(wp), allocatable :: c(:, :), y(:, :), my(:, :), g(:, :)
    real(wp) :: sigma, big
    integer :: n, nev, info, step, j
    n = size(k, 1)
    nev = size(v, 2)
    if (n == 0 .or. nev == 0) return
    call shift_below_spectrum(k, m, c, sigma, info)
    if (info /= 0) return
    allocate(y(n, nev), my(n, nev), g(nev, nev))
    call dsymm('L', 'L', n, nev, 1.0_wp, m, n, v, n, 0.0_wp, my, n)
    do step = 1, POLISH_STEPS
      y = my
      call dpotrs('L', n, nev, c, n, y, n, info)
      ! The columns grow as 1 / (lambda_i - sigma), over many decades: equilibrate first.
      do j = 1, nev
        big = maxval(abs(y(:, j)))
        if (big > 0) y(:, j) = y(:, j) / big
      end do
      call dsymm('L', 'L', n, nev, 1.0_wp, m, n, y, n, 0.0_wp, my, n)
      call dgemm('T', 'N', nev, nev, n, 1.0_wp, y, n, my, n, 0.0_wp, g, nev)
      call dpotrf('U', nev, g, nev, info)
      if (info /= 0) return
      call dtrsm('R', 'U', 'N', 'N', n, nev, 1.0_wp, g, nev, y, n)
      ! M Y R^-1 for the next step's right-hand side, without another product with M.
      call dtrsm('R', 'U', 'N', 'N', n, nev, 1.0_wp, g, nev, my, n)
      v = y
    end do
  end subroutine polish_by_inverse_iteration

  !> The Cholesky factor c (lower) of K - sigma M for the first sigma = -f ||K||_1 / ||M||_1,
  !> f in SHIFT_FACTORS, where it exists, which proves sigma below the whole spectrum.
  !> Zero-frequency (rigid) modes make K singular, so sigma = 0 cannot work: the first f is
  !> far below the elastic eigenvalues of interest (which keeps them well separated in
  !> 1 / (lambda - sigma)) yet large enough against the rounding in K (about n eps ||K||) to
  !> keep the factorisation regular; an indefinite K (unstable configuration) moves sigma
  !> further down. info /= 0: no such shift (c then holds the last failed attempt).
  subroutine shift_below_spectrum(k, m, c, sigma, info)
    real(wp), intent(in) :: k(:, :), m(:, :)
    real(wp), allocatable, intent(out) :: c(:, :)
    real(wp), intent(out) :: sigma
    integer, intent(out) :: info
    real(wp) :: scale
    integer :: n, j, is
    n = size(k, 1)
    allocate(c(n, n))
    scale = sym_norm1(k) / sym_norm1(m)
    if (scale == 0) scale = 1.0_wp
    info = 1
    sigma = 0.0_wp
    do is = 1, size(SHIFT_FACTORS)
      sigma = -SHIFT_FACTORS(is) * scale
      do j = 1, n
        c(j:n, j) = k(j:n, j) - sigma * m(j:n, j)
      end do
      call chol_factor(c, info)
      if (info == 0) exit
    end do
  end subroutine shift_below_spectrum

  !> Lanczos (dsaupd/dseupd) in shift-invert mode 3: OP = (K - sigma M)^-1 M, B = M,
  !> which = 'LM'. The eigenvalues nu = 1 / (lambda - sigma) of OP of largest magnitude
  !> belong to the lambda nearest sigma; with sigma below the whole spectrum these are the
  !> nev lowest. The shift is therefore chosen so that K - sigma M is positive definite,
  !> which its Cholesky factorisation proves (shift_below_spectrum); that factor then
  !> applies OP.
  subroutine arpack_modes(k, m, nev, lambda, v, err)
    real(wp), intent(in) :: k(:, :), m(:, :)
    integer, intent(in) :: nev
    real(wp), allocatable, intent(out) :: lambda(:), v(:, :)
    type(error_t), intent(inout) :: err
    real(wp), allocatable :: c(:, :)
    type(lanczos_t) :: lz
    integer :: n, info, request
    real(wp) :: sigma, mv(size(k, 1)), x(size(k, 1))
    n = size(k, 1)

    ! A mass matrix that is not positive definite would make ARPACK take the square root of
    ! a negative M-norm; dsygvd reports it, so check it the same way here.
    allocate(c(n, n))
    c = m
    call chol_factor(c, info)
    if (info /= 0) then
      call err%set(ERR_NUMERIC, "eigensolver 'arpack': the mass matrix is not positive " // &
        'definite (leading minor of order ' // int_str(info) // ')')
      return
    end if

    call shift_below_spectrum(k, m, c, sigma, info)
    if (info /= 0) then
      call err%set(ERR_NUMERIC, "eigensolver 'arpack': found no shift below the spectrum " // &
        '(K - sigma M indefinite down to sigma = -1e4 ||K|| / ||M||)')
      return
    end if

    call lz%start(n, nev, sigma, 'arpack')
    do
      call lz%next(request)
      select case (request)
      case (LZ_OP)
        ! y = (K - sigma M)^-1 M x
        x = lz%input()
        call dsymv('L', n, 1.0_wp, m, n, x, 1, 0.0_wp, mv, 1)
        call chol_apply(c, mv)
      case (LZ_OP_BX)
        mv = lz%input()
        call chol_apply(c, mv)
      case (LZ_B)
        x = lz%input()
        call dsymv('L', n, 1.0_wp, m, n, x, 1, 0.0_wp, mv, 1)
      case default
        exit
      end select
      call lz%output(mv)
    end do
    call lz%finish(lambda, v, err)
  end subroutine arpack_modes

  !> Solve (L L^T) x = b in place with the Cholesky factor from chol_factor.
  subroutine chol_apply(c, b)
    real(wp), intent(in) :: c(:, :)
    real(wp), intent(inout) :: b(:)
    integer :: info
    call dpotrs('L', size(c, 1), 1, c, size(c, 1), b, size(b), info)
  end subroutine chol_apply

  !> 1-norm of the symmetric matrix held in the lower triangle of a.
  pure real(wp) function sym_norm1(a) result(s)
    real(wp), intent(in) :: a(:, :)
    real(wp) :: col(size(a, 1))
    integer :: j, n
    n = size(a, 1)
    col = 0.0_wp
    do j = 1, n
      col(j) = col(j) + sum(abs(a(j:n, j)))
      col(j + 1:n) = col(j + 1:n) + abs(a(j + 1:n, j))
    end do
    s = 0.0_wp
    if (n > 0) s = maxval(col)
  end function sym_norm1
end module reduction_eigen
