!> Euler parameters (unit quaternions) lambda = (l0, l1, l2, l3), scalar first, for the
!> spatial elements (docs/theory.md section 2.6).
!>
!> The rotation matrix is used in its homogeneous quadratic form
!>   R(lambda) = (l0^2 - lv.lv) I + 2 lv lv^T + 2 l0 [lv x],
!> which is the rotation for |lambda| = 1 and |lambda|^2 times it otherwise. Elements use this
!> form so that R a is a quadratic polynomial in lambda: its Jacobian is linear in lambda and
!> its second derivative constant, and the unit length is left to a separate normalisation
!> element (elements_euler) instead of being built into every formula.
module elements_rotation
  use core_kinds, only: wp
  implicit none
  private
  public :: rot_matrix, rot_apply, rot_apply_jac, rot_apply_second
  public :: rotvec_to_euler, euler_to_matrix, matrix_to_euler, euler_product, skew
  public :: euler_g, euler_e, cross, unit_normal, orthonormal_frame

  !> Below this angle sin(theta/2)/theta is summed as its series: the closed form loses
  !> accuracy as theta^2 / theta^2 and is 0/0 at theta = 0.
  real(wp), parameter :: SMALL_ANGLE = 1.0e-3_wp

contains

  !> G(lambda) (3 x 4): omega_body = 2 G(lambda) lambda'. Linear in lambda; G(a) a = 0.
  pure function euler_g(l) result(g)
    real(wp), intent(in) :: l(4)
    real(wp) :: g(3, 4)
    g(1, :) = [-l(2), l(1), l(4), -l(3)]
    g(2, :) = [-l(3), -l(4), l(1), l(2)]
    g(3, :) = [-l(4), l(3), -l(2), l(1)]
  end function euler_g

  !> E(lambda) (3 x 4): omega_global = 2 E(lambda) lambda' (R = E G^T). Linear in lambda.
  pure function euler_e(l) result(e)
    real(wp), intent(in) :: l(4)
    real(wp) :: e(3, 4)
    e(1, :) = [-l(2), l(1), -l(4), l(3)]
    e(2, :) = [-l(3), l(4), l(1), -l(2)]
    e(3, :) = [-l(4), -l(3), l(2), l(1)]
  end function euler_e

  !> [a x], the cross-product matrix: skew(a) b = a x b.
  pure function skew(a) result(s)
    real(wp), intent(in) :: a(3)
    real(wp) :: s(3, 3)
    s = reshape([0.0_wp, a(3), -a(2), -a(3), 0.0_wp, a(1), a(2), -a(1), 0.0_wp], [3, 3])
  end function skew

  pure function cross(a, b) result(c)
    real(wp), intent(in) :: a(3), b(3)
    real(wp) :: c(3)
    c = [a(2) * b(3) - a(3) * b(2), a(3) * b(1) - a(1) * b(3), a(1) * b(2) - a(2) * b(1)]
  end function cross

  !> The right-handed orthonormal frame (columns e1, e2, e3) with e1 along the unit vector e1
  !> and b in the e1-e2 plane (b orthogonalised against e1). ok is .false. when b is zero or
  !> within a sine of 1e-6 of e1: e2 would then carry a relative rounding error of eps / 1e-6
  !> and follow noise rather than the user (a beam's orientation vector, a hinge's
  !> perpendicular, a body's axes).
  pure subroutine orthonormal_frame(e1, b, frame, ok)
    real(wp), intent(in) :: e1(3), b(3)
    real(wp), intent(out) :: frame(3, 3)
    logical, intent(out) :: ok
    real(wp), parameter :: PARALLEL_TOL = 1.0e-6_wp
    real(wp) :: y(3)
    y = b - dot_product(b, e1) * e1
    ok = norm2(y) > PARALLEL_TOL * norm2(b)
    frame = 0.0_wp
    if (.not. ok) return
    frame(:, 1) = e1
    frame(:, 2) = y / norm2(y)
    frame(:, 3) = cross(e1, frame(:, 2))
  end subroutine orthonormal_frame

  !> A unit vector normal to the unit vector n, orthogonalised from the coordinate axis least
  !> aligned with n (the first of equals): a deterministic frame for a hinge axis or a guide.
  pure function unit_normal(n) result(t)
    real(wp), intent(in) :: n(3)
    real(wp) :: t(3)
    integer :: i
    i = minloc(abs(n), 1)
    t = -n(i) * n
    t(i) = t(i) + 1
    t = t / norm2(t)
  end function unit_normal

  !> Homogeneous quadratic R(lambda): the rotation times |lambda|^2.
  pure function rot_matrix(lam) result(r)
    real(wp), intent(in) :: lam(4)
    real(wp) :: r(3, 3)
    integer :: i
    r = 2 * spread(lam(2:4), 2, 3) * spread(lam(2:4), 1, 3) + 2 * lam(1) * skew(lam(2:4))
    do i = 1, 3
      r(i, i) = r(i, i) + lam(1)**2 - dot_product(lam(2:4), lam(2:4))
    end do
  end function rot_matrix

  !> R(lambda) a without forming R.
  pure function rot_apply(lam, a) result(ra)
    real(wp), intent(in) :: lam(4), a(3)
    real(wp) :: ra(3)
    ra = (lam(1)**2 - dot_product(lam(2:4), lam(2:4))) * a &
      + 2 * dot_product(lam(2:4), a) * lam(2:4) + 2 * lam(1) * cross(lam(2:4), a)
  end function rot_apply

  !> d(R(lambda) a)/dlambda (3 x 4), linear in lambda; rot_apply_jac(lam, a) lam = 2 R a
  !> (Euler's theorem for a homogeneous quadratic).
  pure function rot_apply_jac(lam, a) result(j)
    real(wp), intent(in) :: lam(4), a(3)
    real(wp) :: j(3, 4)
    integer :: i
    j(:, 1) = 2 * lam(1) * a + 2 * cross(lam(2:4), a)
    ! d/dlv of -(lv.lv) a + 2 (lv.a) lv + 2 l0 lv x a
    j(:, 2:4) = -2 * spread(a, 2, 3) * spread(lam(2:4), 1, 3) &
      + 2 * spread(lam(2:4), 2, 3) * spread(a, 1, 3) - 2 * lam(1) * skew(a)
    do i = 1, 3
      j(i, i + 1) = j(i, i + 1) + 2 * dot_product(lam(2:4), a)
    end do
  end function rot_apply_jac

  !> d2/ds2 R(lambda + s mu) a: constant (R a is quadratic), equal to 2 R(mu) a.
  pure function rot_apply_second(mu, a) result(d2)
    real(wp), intent(in) :: mu(4), a(3)
    real(wp) :: d2(3)
    d2 = 2 * rot_apply(mu, a)
  end function rot_apply_second

  !> Unit Euler parameters of the rotation by |phi| about phi / |phi|.
  pure function rotvec_to_euler(phi) result(lam)
    real(wp), intent(in) :: phi(3)
    real(wp) :: lam(4)
    real(wp) :: t, t2, sinc_half
    t2 = dot_product(phi, phi)
    t = sqrt(t2)
    if (t < SMALL_ANGLE) then
      ! sin(t/2)/t = 1/2 - t^2/48 + t^4/3840 - ...; the next term (t^6/645120) is below eps.
      sinc_half = 0.5_wp - t2 / 48 + t2**2 / 3840
    else
      sinc_half = sin(t / 2) / t
    end if
    lam(1) = cos(t / 2)
    lam(2:4) = sinc_half * phi
  end function rotvec_to_euler

  !> The proper rotation matrix of (not necessarily unit) lambda /= 0: R(lambda) / |lambda|^2.
  pure function euler_to_matrix(lam) result(r)
    real(wp), intent(in) :: lam(4)
    real(wp) :: r(3, 3)
    r = rot_matrix(lam) / dot_product(lam, lam)
  end function euler_to_matrix

  !> Unit Euler parameters (l0 >= 0) of a rotation matrix, by the largest of the four
  !> squared components (Shepperd): no division by a small number.
  pure function matrix_to_euler(r) result(lam)
    real(wp), intent(in) :: r(3, 3)
    real(wp) :: lam(4)
    real(wp) :: d(4), f
    integer :: k
    d(1) = 1 + r(1, 1) + r(2, 2) + r(3, 3)
    d(2) = 1 + r(1, 1) - r(2, 2) - r(3, 3)
    d(3) = 1 - r(1, 1) + r(2, 2) - r(3, 3)
    d(4) = 1 - r(1, 1) - r(2, 2) + r(3, 3)
    k = maxloc(d, 1)
    f = sqrt(d(k)) / 2   ! the k-th component; d(k) >= 1 for a rotation
    select case (k)
    case (1)
      lam = [f, (r(3, 2) - r(2, 3)) / (4 * f), (r(1, 3) - r(3, 1)) / (4 * f), &
             (r(2, 1) - r(1, 2)) / (4 * f)]
    case (2)
      lam = [(r(3, 2) - r(2, 3)) / (4 * f), f, (r(1, 2) + r(2, 1)) / (4 * f), &
             (r(1, 3) + r(3, 1)) / (4 * f)]
    case (3)
      lam = [(r(1, 3) - r(3, 1)) / (4 * f), (r(1, 2) + r(2, 1)) / (4 * f), f, &
             (r(2, 3) + r(3, 2)) / (4 * f)]
    case default
      lam = [(r(2, 1) - r(1, 2)) / (4 * f), (r(1, 3) + r(3, 1)) / (4 * f), &
             (r(2, 3) + r(3, 2)) / (4 * f), f]
    end select
    if (lam(1) < 0) lam = -lam
  end function matrix_to_euler

  !> Quaternion product p q, so that R(p q) = R(p) R(q): q applied first, then p.
  pure function euler_product(p, q) result(pq)
    real(wp), intent(in) :: p(4), q(4)
    real(wp) :: pq(4)
    pq(1) = p(1) * q(1) - dot_product(p(2:4), q(2:4))
    pq(2:4) = p(1) * q(2:4) + q(1) * p(2:4) + cross(p(2:4), q(2:4))
  end function euler_product
end module elements_rotation
