!> Helpers of the finite-difference tests: a deterministic random generator, relative errors
!> and flattening of matrices.
module fd_helpers
  use core_kinds, only: wp
  implicit none
  private
  public :: lcg_t, relerr, flat, random_rotvec

  !> Deterministic uniform numbers in [a, b) (a 64-bit-free LCG, same on every platform).
  type :: lcg_t
    integer :: seed = 1
  contains
    procedure :: uniform => lcg_uniform
    procedure :: uniform_vec => lcg_uniform_vec
  end type lcg_t

contains

  real(wp) function lcg_uniform(this, a, b)
    class(lcg_t), intent(inout) :: this
    real(wp), intent(in) :: a, b
    this%seed = modulo(this%seed * 16807, 2147483647)
    if (this%seed <= 0) this%seed = this%seed + 2147483646
    lcg_uniform = a + (b - a) * real(this%seed, wp) / 2147483647.0_wp
  end function lcg_uniform

  function lcg_uniform_vec(this, n, a, b) result(v)
    class(lcg_t), intent(inout) :: this
    integer, intent(in) :: n
    real(wp), intent(in) :: a, b
    real(wp) :: v(n)
    integer :: k
    do k = 1, n
      v(k) = this%uniform(a, b)
    end do
  end function lcg_uniform_vec

  !> max |a - b| / max(max |b|, floor)
  pure real(wp) function relerr(a, b, floor)
    real(wp), intent(in) :: a(:), b(:), floor
    relerr = maxval(abs(a - b)) / max(maxval(abs(b)), floor)
  end function relerr

  pure function flat(m) result(v)
    real(wp), intent(in) :: m(:, :)
    real(wp) :: v(size(m))
    v = reshape(m, [size(m)])
  end function flat

  !> A rotation vector of random direction and random angle in [0, amax).
  function random_rotvec(rng, amax) result(phi)
    type(lcg_t), intent(inout) :: rng
    real(wp), intent(in) :: amax
    real(wp) :: phi(3)
    phi = rng%uniform_vec(3, -1.0_wp, 1.0_wp)
    phi = phi / norm2(phi) * rng%uniform(0.0_wp, amax)
  end function random_rotvec
end module fd_helpers
