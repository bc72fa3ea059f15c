!> Thin wrappers over the LAPACK routines flexmor uses, with explicit interfaces.
module core_linalg
  use core_kinds, only: wp
  implicit none
  private
  public :: single_thread_blas, steady_heap, lu_factor, lu_solve, lu_solve_vector, chol_factor, chol_solve, sym_gen_eig, &
    gen_eig_values, solve_dense, gemv_add, SMALL_DENSE

  !> Up to this order the Cholesky factorisation and its solves run here, not in LAPACK, whose
  !> call overhead is most of their cost at these sizes (a reduced model's mass at every
  !> evaluation: k = 4, 2.3 k instructions per solve through dpotrs).
  integer, parameter :: SMALL_DENSE = 8

  interface
    subroutine dgetrf(m, n, a, lda, ipiv, info)
      import :: wp
      integer, intent(in) :: m, n, lda
      real(wp), intent(inout) :: a(lda, *)
      integer, intent(out) :: ipiv(*), info
    end subroutine dgetrf
    subroutine dgetrs(trans, n, nrhs, a, lda, ipiv, b, ldb, info)
      import :: wp
      character, intent(in) :: trans
      integer, intent(in) :: n, nrhs, lda, ldb, ipiv(*)
      real(wp), intent(in) :: a(lda, *)
      real(wp), intent(inout) :: b(ldb, *)
      integer, intent(out) :: info
    end subroutine dgetrs
    subroutine dpotrf(uplo, n, a, lda, info)
      import :: wp
      character, intent(in) :: uplo
      integer, intent(in) :: n, lda
      real(wp), intent(inout) :: a(lda, *)
      integer, intent(out) :: info
    end subroutine dpotrf
    subroutine dpotrs(uplo, n, nrhs, a, lda, b, ldb, info)
      import :: wp
      character, intent(in) :: uplo
      integer, intent(in) :: n, nrhs, lda, ldb
      real(wp), intent(in) :: a(lda, *)
      real(wp), intent(inout) :: b(ldb, *)
      integer, intent(out) :: info
    end subroutine dpotrs
    subroutine dsygvd(itype, jobz, uplo, n, a, lda, b, ldb, w, work, lwork, iwork, liwork, info)
      import :: wp
      integer, intent(in) :: itype, n, lda, ldb, lwork, liwork
      character, intent(in) :: jobz, uplo
      real(wp), intent(inout) :: a(lda, *), b(ldb, *)
      real(wp), intent(out) :: w(*), work(*)
      integer, intent(out) :: iwork(*), info
    end subroutine dsygvd
    subroutine dgemv(trans, m, n, alpha, a, lda, x, incx, beta, y, incy)
      import :: wp
      character, intent(in) :: trans
      integer, intent(in) :: m, n, lda, incx, incy
      real(wp), intent(in) :: alpha, beta, a(lda, *), x(*)
      real(wp), intent(inout) :: y(*)
    end subroutine dgemv
    subroutine dggev(jobvl, jobvr, n, a, lda, b, ldb, alphar, alphai, beta, vl, ldvl, vr, &
        ldvr, work, lwork, info)
      import :: wp
      character, intent(in) :: jobvl, jobvr
      integer, intent(in) :: n, lda, ldb, ldvl, ldvr, lwork
      real(wp), intent(inout) :: a(lda, *), b(ldb, *)
      real(wp), intent(out) :: alphar(*), alphai(*), beta(*), vl(ldvl, *), vr(ldvr, *), work(*)
      integer, intent(out) :: info
    end subroutine dggev
  end interface

  interface
    subroutine single_thread_blas() bind(C, name='flexmor_single_thread_blas')
    end subroutine single_thread_blas
    !> Process set-up of the executables: see core_heap.c.
    subroutine steady_heap() bind(C, name='flexmor_steady_heap')
    end subroutine steady_heap
  end interface

contains

  !> LU factorisation in place. info > 0: the k-th pivot is exactly zero. `rcond_pivot`
  !> returns the smallest |pivot| relative to the largest, a cheap singularity indicator,
  !> and `worst` the column where it occurs.
  subroutine lu_factor(a, ipiv, info, rcond_pivot, worst)
    real(wp), intent(inout) :: a(:, :)
    integer, intent(out) :: ipiv(:), info
    real(wp), intent(out), optional :: rcond_pivot
    integer, intent(out), optional :: worst
    integer :: n, k, kmin
    real(wp) :: dmax
    n = size(a, 1)
    call dgetrf(n, n, a, max(n, 1), ipiv, info)
    if (present(rcond_pivot)) then
      dmax = 0.0_wp
      kmin = 1
      do k = 1, n
        dmax = max(dmax, abs(a(k, k)))
        if (abs(a(k, k)) < abs(a(kmin, kmin))) kmin = k
      end do
      rcond_pivot = 0.0_wp
      if (n == 0) rcond_pivot = 1.0_wp
      if (dmax > 0 .and. n > 0) rcond_pivot = abs(a(kmin, kmin)) / dmax
      if (present(worst)) worst = kmin
    end if
  end subroutine lu_factor

  !> Solve A X = B (or A^T X = B when `transposed`) with the factors of lu_factor.
  subroutine lu_solve(a, ipiv, b, transposed)
    real(wp), intent(in) :: a(:, :)
    integer, intent(in) :: ipiv(:)
    real(wp), intent(inout) :: b(:, :)
    logical, intent(in), optional :: transposed
    integer :: n, info
    character :: trans
    n = size(a, 1)
    if (n == 0 .or. size(b, 2) == 0) return
    trans = 'N'
    if (present(transposed)) then
      if (transposed) trans = 'T'
    end if
    call dgetrs(trans, n, size(b, 2), a, n, ipiv, b, n, info)
  end subroutine lu_solve

  subroutine lu_solve_vector(a, ipiv, b)
    real(wp), intent(in) :: a(:, :)
    integer, intent(in) :: ipiv(:)
    real(wp), intent(inout) :: b(:)
    integer :: info
    if (size(b) == 0) return
    call dgetrs('N', size(b), 1, a, size(b), ipiv, b, size(b), info)
  end subroutine lu_solve_vector

  !> Cholesky factorisation in place: a = L L^T, L in the lower triangle (the strict upper one untouched); info = j > 0 where
  !> the leading minor of order j is not positive definite (LAPACK's dpotrf convention).
  subroutine chol_factor(a, info)
    real(wp), intent(inout) :: a(:, :)
    integer, intent(out) :: info
    real(wp) :: d
    integer :: n, i, j
    n = size(a, 1)
    if (n > SMALL_DENSE) then
      call dpotrf('L', n, a, max(n, 1), info)
      return
    end if
    info = 0
    do j = 1, n
      d = a(j, j) - dot_product(a(j, 1:j - 1), a(j, 1:j - 1))
      ! Not positive, or NaN.
      if (.not. d > 0) then
        info = j
        return
      end if
      a(j, j) = sqrt(d)
      do i = j + 1, n
        a(i, j) = (a(i, j) - dot_product(a(i, 1:j - 1), a(j, 1:j - 1))) / a(j, j)
      end do
    end do
  end subroutine chol_factor

  !> b <- (L L^T)^-1 b with L from chol_factor.
  subroutine chol_solve(a, b)
    real(wp), intent(in) :: a(:, :)
    real(wp), intent(inout) :: b(:)
    integer :: n, info, i
    n = size(a, 1)
    if (n > SMALL_DENSE) then
      call dpotrs('L', n, 1, a, n, b, n, info)
      return
    end if
    do i = 1, n
      b(i) = (b(i) - dot_product(a(i, 1:i - 1), b(1:i - 1))) / a(i, i)
    end do
    do i = n, 1, -1
      b(i) = (b(i) - dot_product(a(i + 1:n, i), b(i + 1:n))) / a(i, i)
    end do
  end subroutine chol_solve

  !> Solve a general dense system a x = b (b overwritten by x); info /= 0 if singular.
  !> rcond_pivot: smallest over largest pivot, to catch near-singular systems.
  subroutine solve_dense(a, b, info, rcond_pivot)
    real(wp), intent(in) :: a(:, :)
    real(wp), intent(inout) :: b(:)
    integer, intent(out) :: info
    real(wp), intent(out), optional :: rcond_pivot
    real(wp) :: lu(size(a, 1), size(a, 2)), rhs(size(b), 1), rc
    integer :: ipiv(size(a, 1))
    lu = a
    call lu_factor(lu, ipiv, info, rc)
    if (present(rcond_pivot)) rcond_pivot = rc
    if (info /= 0) return
    rhs(:, 1) = b
    call dgetrs('N', size(a, 1), 1, lu, max(size(a, 1), 1), ipiv, rhs, max(size(a, 1), 1), info)
    b = rhs(:, 1)
  end subroutine solve_dense

  !> Generalised symmetric-definite eigenproblem k v = lambda m v (m positive definite).
  !> Eigenvalues ascending; vectors m-orthonormal in the columns of v.
  subroutine sym_gen_eig(k, m, lambda, v, info)
    real(wp), intent(in) :: k(:, :), m(:, :)
    real(wp), intent(out) :: lambda(:), v(:, :)
    integer, intent(out) :: info
    real(wp), allocatable :: b(:, :), work(:)
    integer, allocatable :: iwork(:)
    real(wp) :: wq(1)
    integer :: n, iwq(1)
    n = size(k, 1)
    v = k
    allocate(b, source=m)
    call dsygvd(1, 'V', 'L', n, v, n, b, n, lambda, wq, -1, iwq, -1, info)
    allocate(work(int(wq(1))), iwork(iwq(1)))
    call dsygvd(1, 'V', 'L', n, v, n, b, n, lambda, work, size(work), iwork, size(iwork), info)
  end subroutine sym_gen_eig

  !> Eigenvalues of the general (unsymmetric) problem k v = lambda m v: real parts wr,
  !> imaginary parts wi; an infinite eigenvalue (m singular in its direction) has
  !> wr = huge and wi = 0. With vr, the right eigenvectors as dggev stores them: a real
  !> eigenvalue's in its column, a complex pair's (wi(j) > 0, wi(j + 1) < 0) real part in
  !> column j and imaginary part in column j + 1.
  subroutine gen_eig_values(k, m, wr, wi, info, vr)
    real(wp), intent(in) :: k(:, :), m(:, :)
    real(wp), intent(out) :: wr(:), wi(:)
    integer, intent(out) :: info
    real(wp), intent(out), optional :: vr(:, :)
    real(wp), allocatable :: a(:, :), b(:, :), work(:), v(:, :)
    real(wp) :: beta(size(wr)), wq(1), vl(1, 1)
    integer :: n, i
    character :: jobvr
    n = size(k, 1)
    allocate(a, source=k)
    allocate(b, source=m)
    jobvr = 'N'
    if (present(vr)) jobvr = 'V'
    allocate(v(max(n, 1), merge(n, 1, present(vr))))
    call dggev('N', jobvr, n, a, n, b, n, wr, wi, beta, vl, 1, v, size(v, 1), wq, -1, info)
    allocate(work(int(wq(1))))
    call dggev('N', jobvr, n, a, n, b, n, wr, wi, beta, vl, 1, v, size(v, 1), work, &
      size(work), info)
    if (present(vr)) vr = v(1:n, 1:n)
    do i = 1, n
      if (abs(beta(i)) > tiny(1.0_wp) * max(abs(wr(i)), abs(wi(i)), 1.0_wp)) then
        wr(i) = wr(i) / beta(i)
        wi(i) = wi(i) / beta(i)
      else
        wr(i) = huge(1.0_wp)
        wi(i) = 0.0_wp
      end if
    end do
  end subroutine gen_eig_values

  !> y = y + a x with a taken as the contiguous rows x cols matrix it is (explicit shape: a
  !> tensor's storage passes as its matrix, an array element starts a block of columns). BLAS
  !> reads y once, where a loop of column updates reads and writes it once per column.
  subroutine gemv_add(rows, cols, a, x, y)
    integer, intent(in) :: rows, cols
    real(wp), intent(in) :: a(rows, cols), x(cols)
    real(wp), intent(inout) :: y(rows)
    integer :: j
    if (rows == 0 .or. cols == 0) return
    ! Products with a handful of rows (the expanded evaluation's, m <= 8) are mostly BLAS's
    ! call overhead: column by column here, y in registers (from m^2 = 36 rows BLAS is faster).
    if (rows <= SMALL_DENSE .and. cols <= SMALL_DENSE**2) then
      do j = 1, cols
        y = y + x(j) * a(:, j)
      end do
      return
    end if
    call dgemv('N', rows, cols, 1.0_wp, a, rows, x, 1, 1.0_wp, y, 1)
  end subroutine gemv_add
end module core_linalg
