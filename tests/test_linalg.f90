!> The dense wrappers of core_linalg: the Cholesky factorisation and solve written out for
!> orders up to SMALL_DENSE against LAPACK's (above it) and against an LU solve.
program test_linalg
  use core_kinds, only: wp
  use core_linalg, only: chol_factor, chol_solve, solve_dense, SMALL_DENSE
  use testing, only: suite_t
  implicit none
  type(suite_t) :: t
  integer :: n
  call t%init('dense linear algebra')
  do n = 1, SMALL_DENSE + 3
    call check_order(n)
  end do
  call check_indefinite(3)
  call check_indefinite(SMALL_DENSE + 2)
  call t%finish()
contains

  !> A symmetric positive definite matrix of order n, its condition about 10 (B^T B + n I with B
  !> of entries in [-1, 1]), so that round-off leaves the solution 1e-14 relative; checked
  !> against LU at 1e-12.
  function spd(n) result(a)
    integer, intent(in) :: n
    real(wp) :: a(n, n), b(n, n)
    integer :: i, j
    do j = 1, n
      do i = 1, n
        b(i, j) = sin(1.7_wp * i + 0.9_wp * j * j)
      end do
    end do
    a = matmul(transpose(b), b)
    do i = 1, n
      a(i, i) = a(i, i) + n
    end do
  end function spd

  subroutine check_order(n)
    integer, intent(in) :: n
    real(wp) :: a(n, n), l(n, n), x(n), y(n)
    integer :: info, i
    character(len=40) :: what
    a = spd(n)
    l = a
    call chol_factor(l, info)
    x = [(cos(0.3_wp * i), i = 1, n)]
    y = x
    call chol_solve(l, x)
    call solve_dense(a, y, i)
    write(what, '(a, i0)') 'Cholesky solve against LU, order ', n
    call t%check(info == 0 .and. i == 0 .and. maxval(abs(x - y)) <= 1.0e-12_wp * &
      maxval(abs(y)), trim(what))
    ! The strict upper triangle is left as it was (LAPACK's 'L' convention).
    do i = 2, n
      if (any(l(1:i - 1, i) /= a(1:i - 1, i))) info = -1
    end do
    write(what, '(a, i0)') 'upper triangle untouched, order ', n
    call t%check(info == 0, trim(what))
  end subroutine check_order

  !> A matrix whose leading minor of order 2 is indefinite: info = 2 on either path.
  subroutine check_indefinite(n)
    integer, intent(in) :: n
    real(wp) :: a(n, n)
    integer :: info
    character(len=40) :: what
    a = spd(n)
    a(2, 2) = -a(2, 2)
    call chol_factor(a, info)
    write(what, '(a, i0)') 'indefinite minor 2 found, order ', n
    call t%check(info == 2, trim(what))
  end subroutine check_indefinite
end program test_linalg
