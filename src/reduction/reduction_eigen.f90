!> The lowest eigenpairs of the symmetric-definite problem K v = lambda M v (K symmetric, M
!> symmetric positive definite, both dense), by dense LAPACK (dsygvd) or by ARPACK (Lanczos in
!> shift-invert mode), with one output convention for both:
!>   - lambda ascending, v(:, i) M-normalised (V^T M V = I);
!>   - the component of largest magnitude of each vector positive (the first one if several
!>     tie), so that the two solvers give comparable vectors for simple eigenvalues;
!>   - only the lower triangles of K and M are read, as dsygvd does, so a slightly
!>     unsymmetric input gives the same answer from either solver.
module reduction_eigen
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_INPUT, ERR_NUMERIC
  use core_linalg, only: sym_gen_eig, chol_factor
  use core_strings, only: int_str
  use reduction_lanczos, only: lanczos_t, LZ_OP, LZ_OP_BX, LZ_B
  implicit none
  private
  public :: lowest_modes, eigen_solver_choice
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

  !> Shifts tried, as multiples of -||K||_1 / ||M||_1 (see arpack_modes).
  real(wp), parameter :: SHIFT_FACTORS(7) = [1.0e-8_wp, 1.0e-6_wp, 1.0e-4_wp, 1.0e-2_wp, &
    1.0_wp, 1.0e2_wp, 1.0e4_wp]

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
  end subroutine lowest_modes

  !> Eigenvalues as Rayleigh quotients v^T K v of the M-normalised vectors. Their error is
  !> of second order in the vector error, while dsygvd's eigenvalues carry the rounding of
  !> its reduction L^-1 K L^-T, which grows with the condition of M (the rotary inertia of
  !> short beam elements is tiny: on the two-link with 40 elements per link, dsygvd's lowest
  !> eigenvalue is off by 1e-6 relative, the quotient of its own vector by 1e-12), and
  !> ARPACK's carry the cancellation in sigma + 1 / nu. Both solvers then agree to rounding.
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

  !> All eigenpairs by dsygvd, then the first nev.
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
  end subroutine lapack_modes

  !> Lanczos (dsaupd/dseupd) in shift-invert mode 3: OP = (K - sigma M)^-1 M, B = M,
  !> which = 'LM'. The eigenvalues nu = 1 / (lambda - sigma) of OP of largest magnitude
  !> belong to the lambda nearest sigma; with sigma below the whole spectrum these are the
  !> nev lowest. The shift is therefore chosen so that K - sigma M is positive definite,
  !> which its Cholesky factorisation proves; that factor then applies OP. Zero-frequency
  !> (rigid) modes make K singular, so sigma = 0 cannot work: sigma starts at
  !> -1e-8 ||K||_1 / ||M||_1, far below the elastic eigenvalues of interest (which keeps
  !> their nu well separated, so Lanczos converges fast) yet large enough against the
  !> rounding in K (about n eps ||K||) to keep the factorisation regular; an indefinite K
  !> (unstable configuration) moves it further down until the factorisation succeeds.
  subroutine arpack_modes(k, m, nev, lambda, v, err)
    real(wp), intent(in) :: k(:, :), m(:, :)
    integer, intent(in) :: nev
    real(wp), allocatable, intent(out) :: lambda(:), v(:, :)
    type(error_t), intent(inout) :: err
    real(wp), allocatable :: c(:, :)
    type(lanczos_t) :: lz
    integer :: n, info, j, is, request
    real(wp) :: scale, sigma, mv(size(k, 1)), x(size(k, 1))
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
