!> core_sparse's block solver (core_sparse_block: KLU's block triangular ordering, dense
!> diagonal blocks) against LAPACK's dense LU, on block upper triangular matrices with their
!> rows and columns scrambled: blocks of 1 to 5 unknowns (3 takes the unrolled kernels, the
!> others the generic ones), a block that needs row exchanges, rows of very different scales,
!> one and two right-hand sides, plain and transposed. Also: a pattern with a block above
!> MAX_BLOCK stays with KLU, a singular block is reported, a copy solves with its own factors.
!> The bound on the difference from the dense solution is 10 n cond(A) eps max|x|, with
!> Skeel's condition number cond(A) = || |A^-1| |A| ||_inf (|| |A^-T| |A^T| ||_inf for the
!> transposed systems): the forward error bound of LU with partial pivoting for both solvers,
!> independent of the row scales, with margin.
program test_sparse_block
  use core_kinds, only: wp
  use core_sparse, only: sparse_lu_t
  use testing, only: suite_t
  implicit none

  type(suite_t) :: suite
  integer, parameter :: SIZES_SMALL(9) = [3, 1, 3, 2, 4, 3, 5, 1, 3]
  integer, parameter :: SIZES_BIG(3) = [3, 12, 2]

  call suite%init('sparse block solver against dense LU')
  call compare('small blocks', SIZES_SMALL, .true.)
  call compare('a block above MAX_BLOCK', SIZES_BIG, .false.)
  call singular_block()
  call suite%finish()

contains

  !> A deterministic pseudo-random number in [-1, 1] from an integer.
  pure real(wp) function noise(i)
    integer, intent(in) :: i
    noise = sin(12.9898_wp * i + 78.233_wp * sin(0.37_wp * i))
  end function noise

  !> Block upper triangular matrix with the given block sizes, dense diagonal blocks (the
  !> first diagonal entry of each block of 2 or more is zero: their LU must exchange rows),
  !> about a third of the entries above the blocks set, rows scaled by 10^(-3..3), then rows
  !> and columns permuted.
  subroutine make_matrix(sizes, a)
    integer, intent(in) :: sizes(:)
    real(wp), intent(out) :: a(:, :)
    real(wp) :: b(size(a, 1), size(a, 1))
    integer :: n, k, i, j, i0, start(size(sizes) + 1), prow(size(a, 1)), pcol(size(a, 1))
    n = size(a, 1)
    start(1) = 1
    do k = 1, size(sizes)
      start(k + 1) = start(k) + sizes(k)
    end do
    b = 0.0_wp
    do k = 1, size(sizes)
      i0 = start(k)
      do j = i0, start(k + 1) - 1
        do i = i0, start(k + 1) - 1
          b(i, j) = noise(1000 * i + j)
        end do
        b(j, j) = b(j, j) + 2.0_wp * sign(1.0_wp, noise(7 * j))
        do i = i0, start(k + 1) - 1
          if (sizes(k) > 1 .and. i == i0 .and. j == i0) b(i, j) = 0.0_wp
        end do
        do i = 1, i0 - 1
          if (noise(31 * i + 17 * j) > 0.3_wp) b(i, j) = noise(i + 977 * j)
        end do
      end do
    end do
    do i = 1, n
      b(i, :) = b(i, :) * 10.0_wp**nint(3.0_wp * noise(5 * i + 3))
    end do
    ! Scramble: row i goes to prow(i), column j to pcol(j) (7 and 11 are prime to n).
    prow = [(mod(7 * i, n) + 1, i = 0, n - 1)]
    pcol = [(mod(11 * i + 2, n) + 1, i = 0, n - 1)]
    do j = 1, n
      do i = 1, n
        a(prow(i), pcol(j)) = b(i, j)
      end do
    end do
  end subroutine make_matrix

  !> The sparse pattern and values of the nonzeros of a.
  subroutine make_sparse(a, s)
    real(wp), intent(in) :: a(:, :)
    type(sparse_lu_t), intent(out) :: s
    integer :: rows(count(a /= 0.0_wp)), cols(count(a /= 0.0_wp)), i, j, k
    k = 0
    do j = 1, size(a, 2)
      do i = 1, size(a, 1)
        if (a(i, j) == 0.0_wp) cycle
        k = k + 1
        rows(k) = i
        cols(k) = j
      end do
    end do
    call s%setup(size(a, 1), rows, cols)
    do k = 1, size(rows)
      s%val(s%pos(k)) = a(rows(k), cols(k))
    end do
  end subroutine make_sparse

  subroutine compare(what, sizes, blocked)
    character(len=*), intent(in) :: what
    integer, intent(in) :: sizes(:)
    logical, intent(in) :: blocked
    integer, parameter :: NRHS = 2
    real(wp) :: a(sum(sizes), sum(sizes)), lu(sum(sizes), sum(sizes))
    real(wp) :: inv(sum(sizes), sum(sizes)), b(sum(sizes), NRHS), x(sum(sizes), NRHS)
    real(wp) :: xt(sum(sizes), NRHS), y(sum(sizes), NRHS), rcond, skeel, skeel_t, tol, tol_t
    type(sparse_lu_t) :: s, copy
    integer :: n, i, info, ipiv(sum(sizes))
    n = sum(sizes)
    call make_matrix(sizes, a)
    call make_sparse(a, s)
    ! Dense reference: inverse (for the condition numbers), solutions of A x = b, A^T x = b.
    lu = a
    call dgetrf(n, n, lu, n, ipiv, info)
    call suite%check(info == 0, what // ': dense LU of the test matrix')
    inv = 0.0_wp
    do i = 1, n
      inv(i, i) = 1.0_wp
    end do
    call dgetrs('N', n, n, lu, n, ipiv, inv, n, info)
    skeel = maxval(sum(matmul(abs(inv), abs(a)), dim=2))
    skeel_t = maxval(sum(matmul(abs(a), abs(inv)), dim=1))
    do i = 1, n
      b(i, 1) = noise(3 * i)
      b(i, 2) = noise(11 * i + 1) * 1.0e3_wp
    end do
    x = b
    call dgetrs('N', n, NRHS, lu, n, ipiv, x, n, info)
    xt = b
    call dgetrs('T', n, NRHS, lu, n, ipiv, xt, n, info)
    call s%factor(info, rcond)
    call suite%check(info == 0 .and. rcond > 0.0_wp, what // ': factorised')
    call suite%check(s%uses_blocks() .eqv. blocked, what // ': block solver used as expected')
    tol = 10.0_wp * n * skeel * epsilon(1.0_wp)
    tol_t = 10.0_wp * n * skeel_t * epsilon(1.0_wp)
    y = b
    call s%solve_many(y)
    do i = 1, NRHS
      call suite%close_array(y(:, i), x(:, i), 0.0_wp, tol * maxval(abs(x(:, i))), &
        what // ': A x = b')
    end do
    y = b
    call s%solve_many(y, transposed=.true.)
    do i = 1, NRHS
      call suite%close_array(y(:, i), xt(:, i), 0.0_wp, tol_t * maxval(abs(xt(:, i))), &
        what // ': A^T x = b')
    end do
    y(:, 1) = b(:, 1)
    call s%solve(y(:, 1), transposed=.true.)
    call suite%close_array(y(:, 1), xt(:, 1), 0.0_wp, tol_t * maxval(abs(xt(:, 1))), &
      what // ': one transposed right-hand side')
    copy = s
    s%val = 2.0_wp * s%val
    call s%factor(info, rcond)
    y(:, 1) = b(:, 1)
    call copy%solve(y(:, 1))
    call suite%close_array(y(:, 1), x(:, 1), 0.0_wp, tol * maxval(abs(x(:, 1))), &
      what // ': a copy keeps its factors')
    y(:, 1) = b(:, 1)
    call s%solve(y(:, 1))
    call suite%close_array(2.0_wp * y(:, 1), x(:, 1), 0.0_wp, tol * maxval(abs(x(:, 1))), &
      what // ': the refactorised original (2 A)')
  end subroutine compare

  subroutine singular_block()
    real(wp) :: a(sum(SIZES_SMALL), sum(SIZES_SMALL)), rcond
    type(sparse_lu_t) :: s
    integer :: info
    call make_matrix(SIZES_SMALL, a)
    call make_sparse(a, s)
    call s%factor(info, rcond)
    call suite%check(info == 0 .and. s%uses_blocks(), 'regular before')
    ! Zero the values of one column: one diagonal block loses a column.
    where (abs(a(:, 5)) > 0.0_wp) a(:, 5) = 0.0_wp
    call set_values(s, a)
    call s%factor(info, rcond)
    call suite%check(info /= 0, 'a block with a zero column is reported singular')
  end subroutine singular_block

  !> The values of a on the pattern made from it (entries now zero are set to zero).
  subroutine set_values(s, a)
    type(sparse_lu_t), intent(inout) :: s
    real(wp), intent(in) :: a(:, :)
    real(wp) :: b(size(a, 1), size(a, 2))
    integer :: i, j, k
    k = 0
    call make_matrix(SIZES_SMALL, b)
    do j = 1, size(b, 2)
      do i = 1, size(b, 1)
        if (b(i, j) == 0.0_wp) cycle
        k = k + 1
        s%val(s%pos(k)) = a(i, j)
      end do
    end do
  end subroutine set_values
end program test_sparse_block
