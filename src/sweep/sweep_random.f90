!> The sweeps' random numbers: splitmix64 streams, uniform samples and permutations that are
!> the same on every rank, compiler and machine (docs/sweep.md).
module sweep_random
  use core_kinds, only: wp, i8
  implicit none
  private
  public :: rng_t, rng_init, uniform, permutation


  ! splitmix64 (Steele, Lea and Flood 2014) constants, as the bit patterns of int64.
  integer(i8), parameter :: SM_GAMMA = int(z'9E3779B97F4A7C15', i8)
  integer(i8), parameter :: SM_MUL1 = int(z'BF58476D1CE4E5B9', i8)
  integer(i8), parameter :: SM_MUL2 = int(z'94D049BB133111EB', i8)
  integer(i8), parameter :: MASK16 = 65535_i8, MASK32 = 4294967295_i8

  type :: rng_t
    integer(i8) :: state = 0
  end type rng_t

contains

  ! ---------------------------------------------------------------- random numbers
  !
  ! splitmix64 written with bit operations and 16/32-bit limbs: Fortran integers are signed and
  ! their overflow is undefined, so the mod-2**64 sums and products are built from pieces that
  ! cannot overflow. The stream is then the same with every compiler and option.

  !> Stream `stream` of seed `seed`: the seed and stream number are hashed into the state.
  pure subroutine rng_init(rng, seed, stream)
    type(rng_t), intent(out) :: rng
    integer, intent(in) :: seed, stream
    rng%state = mix64(add64(mix64(int(seed, i8)), int(stream, i8)))
  end subroutine rng_init

  integer(i8) function next64(rng) result(z)
    type(rng_t), intent(inout) :: rng
    rng%state = add64(rng%state, SM_GAMMA)
    z = mix64(rng%state)
  end function next64

  !> Uniform in [0, 1): the top 53 bits, exactly representable.
  real(wp) function uniform(rng) result(u)
    type(rng_t), intent(inout) :: rng
    u = real(ishft(next64(rng), -11), wp) * 2.0_wp**(-53)
  end function uniform

  !> A uniformly random permutation of 1..n (Fisher-Yates).
  subroutine permutation(rng, perm)
    type(rng_t), intent(inout) :: rng
    integer, intent(out) :: perm(:)
    integer :: i, k, tmp
    perm = [(i, i = 1, size(perm))]
    do i = size(perm), 2, -1
      k = min(int(uniform(rng) * i) + 1, i)
      tmp = perm(i)
      perm(i) = perm(k)
      perm(k) = tmp
    end do
  end subroutine permutation

  pure integer(i8) function mix64(x) result(z)
    integer(i8), intent(in) :: x
    z = mul64(ieor(x, ishft(x, -30)), SM_MUL1)
    z = mul64(ieor(z, ishft(z, -27)), SM_MUL2)
    z = ieor(z, ishft(z, -31))
  end function mix64

  !> a + b mod 2**64 on the bit patterns.
  pure integer(i8) function add64(a, b) result(r)
    integer(i8), intent(in) :: a, b
    integer(i8) :: lo, hi
    lo = iand(a, MASK32) + iand(b, MASK32)
    hi = ishft(a, -32) + ishft(b, -32) + ishft(lo, -32)
    r = ior(iand(lo, MASK32), ishft(iand(hi, MASK32), 32))
  end function add64

  !> a * b mod 2**64 on the bit patterns, by 16-bit limbs (every partial product < 2**32).
  pure integer(i8) function mul64(a, b) result(r)
    integer(i8), intent(in) :: a, b
    integer(i8) :: al(0:3), bl(0:3), acc, carry
    integer :: i, k
    do i = 0, 3
      al(i) = iand(ishft(a, -16 * i), MASK16)
      bl(i) = iand(ishft(b, -16 * i), MASK16)
    end do
    r = 0
    carry = 0
    do k = 0, 3
      acc = carry
      do i = 0, k
        acc = acc + al(i) * bl(k - i)
      end do
      r = ior(r, ishft(iand(acc, MASK16), 16 * k))
      carry = ishft(acc, -16)
    end do
  end function mul64
end module sweep_random
