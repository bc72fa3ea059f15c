!> Scalar functions of the spatial beam's 14 coordinates carried with their gradient and
!> their first and second derivatives along one direction v: the modes of elements_beam3d and
!> the centroid field of its mass are built from products and sums of these, so that e, de
!> and the second directional derivative come out of one evaluation.
module elements_sd
  use core_kinds, only: wp
  implicit none
  private
  public :: sd_t, sd_lin, sd_scale, sd_mul, N_X

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
end module elements_sd
