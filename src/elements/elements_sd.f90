!> Scalar functions of the spatial beam's 14 coordinates carried with their gradient and
!> their first and second derivatives along one direction v: the modes of elements_beam3d and
!> the centroid field of its mass are built from products and sums of these, so that e, de
!> and the second directional derivative come out of one evaluation.
module elements_sd
  use core_kinds, only: wp
  implicit none
  private
  public :: sd_t, sd_lin, sd_scale, sd_mul, sd_atan2, sd_sqrt, N_X

  integer, parameter :: N_X = 14     !< coordinates of the spatial beam

  !> A scalar function of x with its gradient and its first and second derivatives along v.
  type :: sd_t
    real(wp) :: f = 0.0_wp, g(N_X) = 0.0_wp, d1 = 0.0_wp, d2 = 0.0_wp
  end type sd_t

contains

  !> sa a + sb b.
  pure function sd_lin(a, sa, b, sb) result(s)
    type(sd_t), intent(in) :: a, b
    real(wp), intent(in) :: sa, sb
    type(sd_t) :: s
    s%f = sa * a%f + sb * b%f
    s%g = sa * a%g + sb * b%g
    s%d1 = sa * a%d1 + sb * b%d1
    s%d2 = sa * a%d2 + sb * b%d2
  end function sd_lin

  pure function sd_scale(a, sa) result(s)
    type(sd_t), intent(in) :: a
    real(wp), intent(in) :: sa
    type(sd_t) :: s
    s%f = sa * a%f
    s%g = sa * a%g
    s%d1 = sa * a%d1
    s%d2 = sa * a%d2
  end function sd_scale

  pure function sd_mul(a, b) result(s)
    type(sd_t), intent(in) :: a, b
    type(sd_t) :: s
    s%f = a%f * b%f
    s%g = a%f * b%g + b%f * a%g
    s%d1 = a%f * b%d1 + b%f * a%d1
    s%d2 = a%d2 * b%f + 2 * a%d1 * b%d1 + a%f * b%d2
  end function sd_mul

  !> atan2(a, b): d(atan2) = (b da - a db) / r^2 with r^2 = a^2 + b^2, and along v the
  !> derivative of that quotient for the second.
  pure function sd_atan2(a, b) result(s)
    type(sd_t), intent(in) :: a, b
    type(sd_t) :: s
    real(wp) :: r2, num1
    ! Both zero only at a degenerate state (lambda = 0, a section axis along the other's
    ! normal); the floor keeps the result finite there.
    r2 = max(a%f**2 + b%f**2, 1.0e-30_wp)
    s%f = atan2(a%f, b%f)
    s%g = (b%f * a%g - a%f * b%g) / r2
    num1 = b%f * a%d1 - a%f * b%d1
    s%d1 = num1 / r2
    ! Divided by r2 twice rather than by r2**2: a runaway iterate (a 1e30 load on a spatial
    ! beam, its Euler parameters at 1e25) gave r2 of 1e200 and r2**2 overflowed, a
    ! floating-point trap before Newton could see that it diverged.
    s%d2 = (b%f * a%d2 - a%f * b%d2) / r2 - num1 / r2 * 2 * (a%f * a%d1 + b%f * b%d1) / r2
  end function sd_atan2

  !> sqrt(a), a > 0 (floored like sd_atan2's radius).
  pure function sd_sqrt(a) result(s)
    type(sd_t), intent(in) :: a
    type(sd_t) :: s
    s%f = sqrt(max(a%f, 1.0e-30_wp))
    s%g = a%g / (2 * s%f)
    s%d1 = a%d1 / (2 * s%f)
    s%d2 = a%d2 / (2 * s%f) - a%d1**2 / (4 * s%f**3)
  end function sd_sqrt
end module elements_sd
