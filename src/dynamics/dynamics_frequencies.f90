!> Natural frequencies where the tangent stiffness is not symmetric: moments fixed in space,
!> whose load stiffness is not conservative under 3D rotations (docs/theory.md 7, 'Moments
!> fixed in space'). Stability is decided on the full problem K v = omega^2 M v (a real
!> omega^2 < 0: divergence, dynamics_static's stable_tangent), so the frequencies come from
!> that problem too (LAPACK dggev): the symmetric part, which the modal analysis used to take,
!> gave -39 Hz on input/roll_up.nml at load steps the test called stable, and disagreed with
!> the eigenvalues of &linear's A, which holds the full tangent.
!>
!> An eigenvalue mu = a + ib is a linearised motion exp(s t) with s^2 = -mu:
!>   - real (|b| within the stability test's margin): omega^2 = a, as in the symmetric case;
!>     a < 0 is the divergence the stability test counts;
!>   - a complex pair: s = +-i sqrt(mu), an oscillation at Re sqrt(mu) that grows or decays at
!>     |Im sqrt(mu)| (flutter in the linearised sense, which the stability test does not take
!>     as unstable). Both members are reported with omega^2 = (Re sqrt(mu))^2 > 0, and their
!>     shapes are the real and the imaginary part of the complex vector (as dggev stores them).
module dynamics_frequencies
  use core_kinds, only: wp
  use core_linalg, only: gen_eig_values
  use core_sort, only: sort_by_value
  implicit none
  private
  public :: general_modes, is_symmetric, stability_scale

contains

  !> Whether k is symmetric to the rounding of the difference tangent (a symmetrised tangent
  !> is exactly symmetric; only moments fixed in space leave it unsymmetric).
  logical function is_symmetric(k)
    real(wp), intent(in) :: k(:, :)
    is_symmetric = maxval(abs(k - transpose(k))) <= 1.0e-12_wp * maxval(abs(k))
  end function is_symmetric

  !> s = max_i |K_ii| / M_ii, at most the largest |omega^2|: the scale of the stability test's
  !> round-off margin (dynamics_static).
  pure real(wp) function stability_scale(k, m) result(s)
    real(wp), intent(in) :: k(:, :), m(:, :)
    integer :: i
    s = 0
    do i = 1, size(k, 1)
      if (m(i, i) > 0) s = max(s, abs(k(i, i)) / m(i, i))
    end do
  end function stability_scale

  !> The nev lowest modes of the full problem k v = omega^2 m v, k unsymmetric: omega2
  !> ascending as in the module comment (real eigenvalues, complex pairs by (Re sqrt(mu))^2),
  !> vectors (n, nev) m-normalised (v^T m v = 1) with their largest component positive. They
  !> are right eigenvectors (a pair's: the real and imaginary part), not m-orthogonal.
  !> margin: an |Im mu| up to it counts as real (the stability test's margin). info: dggev's.
  subroutine general_modes(k, m, nev, margin, omega2, v, info)
    real(wp), intent(in) :: k(:, :), m(:, :), margin
    integer, intent(in) :: nev
    real(wp), allocatable, intent(out) :: omega2(:), v(:, :)
    integer, intent(out) :: info
    real(wp), allocatable :: wr(:), wi(:), vr(:, :), w2(:)
    integer, allocatable :: order(:)
    real(wp) :: vmv
    integer :: n, j
    n = size(k, 1)
    allocate(wr(n), wi(n), vr(n, n), w2(n))
    allocate(omega2(0), v(n, 0))
    call gen_eig_values(k, m, wr, wi, info, vr)
    if (info /= 0) return
    do j = 1, n
      if (abs(wi(j)) <= margin .or. wr(j) >= huge(1.0_wp)) then
        w2(j) = wr(j)
      else
        w2(j) = real(sqrt(cmplx(wr(j), wi(j), wp)))**2
      end if
    end do
    order = [(j, j = 1, n)]
    ! Stable: a pair's two members (equal keys) keep dggev's order, real part first.
    call sort_by_value(order, w2)
    order = order(1:min(nev, n))
    omega2 = w2(order)
    v = vr(:, order)
    do j = 1, size(order)
      vmv = dot_product(v(:, j), matmul(m, v(:, j)))
      if (vmv > 0) v(:, j) = v(:, j) / sqrt(vmv)
      if (v(maxloc(abs(v(:, j)), 1), j) < 0) v(:, j) = -v(:, j)
    end do
  end subroutine general_modes
end module dynamics_frequencies
