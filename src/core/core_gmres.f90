!> The pieces of restarted GMRES that flexmor's matrix-free solvers share (Newton-Krylov
!> statics, the loaded Krylov modes): an Arnoldi step by modified Gram-Schmidt with Givens
!> rotations, and the cycle's correction. Each caller keeps its loop, its products and its
!> stopping rule (their products carry difference noise of different size).
module core_gmres
  use core_kinds, only: wp
  implicit none
  private
  public :: gmres_step, gmres_correct

contains

  !> Step j of a cycle: w = A v(:, j) is orthogonalised against v(:, 1:j) (twice: the products
  !> carry difference noise, and a basis that loses orthogonality stalls the residual
  !> estimate) into column j of the Hessenberg matrix hm and into v(:, j + 1); the previous
  !> rotations (cs, sn) and a new one bring hm to triangular form, and s(j + 1) is then the
  !> cycle's residual estimate (s(1) = the residual norm at the cycle's start).
  pure subroutine gmres_step(j, w, v, hm, cs, sn, s)
    integer, intent(in) :: j
    real(wp), intent(inout) :: w(:), v(:, :), hm(:, :), cs(:), sn(:), s(:)
    real(wp) :: tmp
    integer :: i, pass
    hm(:, j) = 0.0_wp
    do pass = 1, 2
      do i = 1, j
        tmp = dot_product(v(:, i), w)
        hm(i, j) = hm(i, j) + tmp
        w = w - tmp * v(:, i)
      end do
    end do
    hm(j + 1, j) = norm2(w)
    if (hm(j + 1, j) > 0) v(:, j + 1) = w / hm(j + 1, j)
    do i = 1, j - 1
      tmp = cs(i) * hm(i, j) + sn(i) * hm(i + 1, j)
      hm(i + 1, j) = -sn(i) * hm(i, j) + cs(i) * hm(i + 1, j)
      hm(i, j) = tmp
    end do
    tmp = hypot(hm(j, j), hm(j + 1, j))
    cs(j) = hm(j, j) / tmp
    sn(j) = hm(j + 1, j) / tmp
    hm(j, j) = tmp
    hm(j + 1, j) = 0.0_wp
    s(j + 1) = -sn(j) * s(j)
    s(j) = cs(j) * s(j)
  end subroutine gmres_step

  !> u := u + V(:, 1:j) c with the triangular system hm(1:j, 1:j) c = s(1:j) of j steps.
  pure subroutine gmres_correct(j, v, hm, s, u)
    integer, intent(in) :: j
    real(wp), intent(in) :: v(:, :), hm(:, :), s(:)
    real(wp), intent(inout) :: u(:)
    real(wp) :: c(j)
    integer :: i
    do i = j, 1, -1
      c(i) = (s(i) - dot_product(hm(i, i + 1:j), c(i + 1:j))) / hm(i, i)
    end do
    u = u + matmul(v(:, 1:j), c)
  end subroutine gmres_correct
end module core_gmres
