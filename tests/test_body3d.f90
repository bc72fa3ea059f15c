!> The spatial rigid body element (elements_body3d) against independent forms:
!>   - G(lambda) against the body angular velocity from differences of the rotation matrix,
!>     R^T dR/dt = [omega x], along a unit-norm path lambda(t);
!>   - kinetic energy 1/2 lambda'^T M lambda' = 1/2 omega^T J omega + 1/2 m |v|^2;
!>   - E(lambda) against the global angular velocity dR/dt R^T, and R = E G^T;
!>   - M symmetric, positive semi-definite in lambda with the null direction lambda itself;
!>   - the convective force h against Lagrange's form from central differences of M,
!>     h_i = sum_jk (dM_ij/dx_k - 1/2 dM_jk/dx_i) xd_j xd_k, on random states (also with
!>     |lambda| /= 1: the formula holds for any lambda).
program test_body3d
  use core_kinds, only: wp
  use testing, only: suite_t
  use fd_helpers, only: lcg_t, relerr, flat
  use elements_body3d, only: body3d_t
  use elements_rotation, only: euler_g, euler_e
  implicit none

  type(suite_t) :: suite
  type(lcg_t) :: rng
  type(body3d_t) :: body
  integer :: trial

  call suite%init('test_body3d')
  rng%seed = 20261125
  body%label = 'body'
  body%dofs = [1, 2, 3, 4, 5, 6, 7]
  allocate(body%mode_class(0))
  body%mass = 2.5_wp
  ! A full, non-diagonal inertia tensor (principal moments 0.3, 0.5, 0.9 in a tilted frame).
  body%inertia_tensor = reshape([0.62_wp, 0.11_wp, -0.07_wp, 0.11_wp, 0.48_wp, 0.09_wp, &
    -0.07_wp, 0.09_wp, 0.54_wp], [3, 3])
  do trial = 1, 6
    call check_state(trial)
  end do
  call suite%finish()

contains

  !> Rotation matrix of a unit lambda.
  pure function rot(l) result(r)
    real(wp), intent(in) :: l(4)
    real(wp) :: r(3, 3)
    r(1, :) = [l(1)**2 + l(2)**2 - l(3)**2 - l(4)**2, 2 * (l(2) * l(3) - l(1) * l(4)), &
      2 * (l(2) * l(4) + l(1) * l(3))]
    r(2, :) = [2 * (l(2) * l(3) + l(1) * l(4)), l(1)**2 - l(2)**2 + l(3)**2 - l(4)**2, &
      2 * (l(3) * l(4) - l(1) * l(2))]
    r(3, :) = [2 * (l(2) * l(4) - l(1) * l(3)), 2 * (l(3) * l(4) + l(1) * l(2)), &
      l(1)**2 - l(2)**2 - l(3)**2 + l(4)**2]
  end function rot

  subroutine check_state(trial)
    integer, intent(in) :: trial
    real(wp) :: x(7), xd(7), l(4), ld(4), omega(3), w(3, 3), r_p(3, 3), r_m(3, 3), s
    real(wp) :: m(7, 7), h(7), hfd(7), dm(7, 7, 7), kin, kin_ref, hs, g(3, 4), r0(3, 3)
    real(wp) :: e(3, 4)
    real(wp), parameter :: dt = 1.0e-6_wp, dx = 1.0e-5_wp
    character(len=12) :: tag
    integer :: i, j, k
    write(tag, '(a,i0,a)') ' (state ', trial, ')'
    l = rng%uniform_vec(4, -1.0_wp, 1.0_wp)
    l = l / norm2(l)
    omega = rng%uniform_vec(3, -3.0_wp, 3.0_wp)
    ! lambda' = G^T omega / 2 keeps |lambda| = 1 (G lambda = 0) and turns at omega (G G^T = I).
    g = euler_g(l)
    ld = 0.5_wp * matmul(transpose(g), omega)
    ! Body angular velocity from the rotation matrix along the normalised path.
    r_p = rot((l + dt * ld) / norm2(l + dt * ld))
    r_m = rot((l - dt * ld) / norm2(l - dt * ld))
    r0 = rot(l)
    w = matmul(transpose(r0), (r_p - r_m) / (2 * dt))
    ! Central differences at 1e-6 of an O(1) matrix: error about 1e-10; bound 1e-8.
    call suite%close(relerr([w(3, 2), w(1, 3), w(2, 1)], omega, 1.0_wp), 0.0_wp, 0.0_wp, &
      1.0e-8_wp, 'G: omega = 2 G lambdadot equals R^T dR/dt, rel. error' // tag)
    call suite%close(relerr(flat(w), -flat(transpose(w)), 1.0_wp), 0.0_wp, 0.0_wp, 1.0e-8_wp, &
      'R^T dR/dt is skew, rel. error' // tag)
    ! Global angular velocity: dR/dt R^T = [omega_g x] with omega_g = 2 E lambdadot = R omega,
    ! and R = E G^T.
    w = matmul((r_p - r_m) / (2 * dt), transpose(r0))
    e = euler_e(l)
    call suite%close(relerr([w(3, 2), w(1, 3), w(2, 1)], 2 * matmul(e, ld), 1.0_wp), 0.0_wp, &
      0.0_wp, 1.0e-8_wp, 'E: omega_global = 2 E lambdadot equals dR/dt R^T, rel. error' // tag)
    call suite%close(relerr(flat(matmul(e, transpose(g))), flat(r0), 1.0_wp), 0.0_wp, 0.0_wp, &
      1.0e-14_wp, 'R = E G^T, rel. error' // tag)

    x(1:3) = rng%uniform_vec(3, -2.0_wp, 2.0_wp)
    x(4:7) = l
    xd(1:3) = rng%uniform_vec(3, -1.0_wp, 1.0_wp)
    xd(4:7) = ld
    call body%inertia(x, xd, m, h)
    kin = 0.5_wp * dot_product(xd, matmul(m, xd))
    kin_ref = 0.5_wp * body%mass * dot_product(xd(1:3), xd(1:3)) + &
      0.5_wp * dot_product(omega, matmul(body%inertia_tensor, omega))
    call suite%close(kin, kin_ref, 1.0e-13_wp, 0.0_wp, 'kinetic energy' // tag)
    ! M(4:7, 4:7) = 4 G^T (J G): entries (i, j) and (j, i) are sums of 3 products of 3-term
    ! sums taken in different orders, each rounded by up to ~3 eps (4 |G|^T |J| |G|), so
    ! they differ by up to ~6-12 eps = 1.3e-15 to 2.7e-15 of the entries' scale, which is
    ! that of max|M| here: bound 1e-14 (45 eps).
    ! Observed up to 1.3e-16 in both builds (the old 1e-15, 4.5 eps, was below the rounding
    ! estimate and within 7.5x of it). An asymmetric M (a transposed G) gives O(1).
    call suite%close(relerr(flat(m), flat(transpose(m)), 1.0_wp), 0.0_wp, 0.0_wp, 1.0e-14_wp, &
      'M symmetric, rel. error' // tag)
    call suite%close(maxval(abs(matmul(m(4:7, 4:7), l))) / maxval(abs(m)), 0.0_wp, 0.0_wp, &
      1.0e-14_wp, 'M lambda = 0 (a change of |lambda| carries no energy), rel.' // tag)

    ! Lagrange form with an arbitrary lambda' (not tangent) and |lambda| /= 1.
    s = rng%uniform(0.7_wp, 1.4_wp)
    x(4:7) = s * l
    xd = rng%uniform_vec(7, -1.5_wp, 1.5_wp)
    call body%inertia(x, xd, m, h)
    do k = 1, 7
      dm(:, :, k) = mass_derivative(x, k, dx)
    end do
    hfd = 0.0_wp
    do i = 1, 7
      do j = 1, 7
        do k = 1, 7
          hfd(i) = hfd(i) + (dm(i, j, k) - 0.5_wp * dm(j, k, i)) * xd(j) * xd(k)
        end do
      end do
    end do
    hs = maxval(abs(m)) * dot_product(xd, xd)
    ! M is quadratic in lambda, so central differences are exact up to round-off (~1e-11
    ! relative at dx = 1e-5); bound 1e-8.
    call suite%close(relerr(h, hfd, 1.0e-3_wp * hs), 0.0_wp, 0.0_wp, 1.0e-8_wp, &
      'h vs Lagrange form from differences of M, rel. error' // tag)
  end subroutine check_state

  function mass_derivative(x, k, dx) result(d)
    real(wp), intent(in) :: x(7), dx
    integer, intent(in) :: k
    real(wp) :: d(7, 7), mp(7, 7), mm(7, 7), h(7), xp(7)
    xp = x
    xp(k) = x(k) + dx
    call body%inertia(xp, 0 * x, mp, h)
    xp(k) = x(k) - dx
    call body%inertia(xp, 0 * x, mm, h)
    d = (mp - mm) / (2 * dx)
  end function mass_derivative
end program test_body3d
