!> The rotation-vector element of a free node rotation (elements_rotvec) at element level:
!>   - closed forms: a turn by a about a unit axis n gives psi = a n, for a = 0 (exactly), tiny,
!>     small, on both sides of the series switch, 170 and 300 degrees and up to 1.9 pi, for
!>     unit and scaled Euler parameters; at the reference psi = 0 and de = [0 2I] exactly;
!>   - invariance: the rotation of psi is that of lambda (random lambda, l0 of both signs);
!>     lambda -> -lambda gives the same rotation with |psi| -> 2 pi - |psi|; degree 0 in
!>     lambda (Euler's theorem: de lambda = 0);
!>   - the series and the closed form agree across the switch (u = s2 / l0^2 = 0.1);
!>   - de against central FD, second against a 5-point FD, the Hessian by polarisation of
!>     second against FD of de, at rotations of 0, 1e-8, 1e-3, 0.6 and 0.63 rad (either side
!>     of the series switch), 1 rad, 170 and 300 degrees and random ones, unit and non-unit
!>     lambda;
!>   - finite at the singular full turn, and the limit check (none below 1.9 pi, a message
!>     naming the element above).
!> Achieved errors are printed with every check and the worst per category at the end.
program test_rotvec
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use core_kinds, only: wp
  use core_strings, only: real_str
  use testing, only: suite_t
  use fd_helpers, only: lcg_t, relerr, flat, random_rotvec
  use element_fd, only: modes, jacobian, second, expect_derivatives
  use elements_base, only: MODE_DYNAMIC
  use elements_rotation, only: rotvec_to_euler, euler_to_matrix, euler_product
  use elements_rotvec, only: rotvec_t, ROTVEC_LIMIT, RECENTRE_ABOVE
  implicit none

  real(wp), parameter :: PI = 3.14159265358979323846_wp, EPS = epsilon(1.0_wp)
  real(wp), parameter :: DEG = PI / 180
  integer, parameter :: C_E = 1, C_INV = 2, C_SW = 3, C_DE = 4, C_D2 = 5, C_POL = 6, &
    C_CH = 7, N_CAT = 7
  character(len=44), parameter :: CAT_NAME(N_CAT) = [character(len=44) :: &
    'psi vs closed forms', 'invariance of psi', 'series vs closed form at the switch', &
    'de vs central FD of psi', 'second vs 5-point FD d2/ds2 psi(x+sv)', &
    'Hessian by polarisation vs FD Hessian', 'moved chart vs relative rotation']
  type(lcg_t) :: rng = lcg_t(seed=20261126)
  type(suite_t) :: ts
  type(rotvec_t) :: rv

  call ts%init('rotvec')
  rv%label = 'node ''n'' rotation'
  rv%dofs = [1, 2, 3, 4]
  rv%mode_class = [MODE_DYNAMIC, MODE_DYNAMIC, MODE_DYNAMIC]
  call basics()
  call closed_forms()
  call invariance()
  call series_switch()
  call derivative_tests()
  call full_turn()
  call moving_chart()
  call ts%print_worst(CAT_NAME)
  call ts%finish()

contains

  subroutine basics()
    real(wp) :: s(3, 3), de(3, 4), want(3, 4)
    integer :: i
    call rv%stiffness(s)
    call ts%check(rv%n_modes() == 3 .and. rv%type_name() == 'rotvec' .and. &
      .not. rv%has_inertia() .and. rv%has_limit() .and. all(s == 0), &
      'rotvec: 3 modes, type name, no inertia, a limit, no stiffness')
    call ts%check(all(modes(rv, [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp]) == 0), &
      'psi = 0 exactly at the reference')
    ! At the reference f = 2 (the series' first term) and f_0 lv = 0: de = [0 2I] exactly.
    de = jacobian(rv, [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp])
    want = 0.0_wp
    do i = 1, 3
      want(i, i + 1) = 2.0_wp
    end do
    call ts%check(all(de == want), 'de = [0 2I] exactly at the reference')
  end subroutine basics

  !> psi of a turn by a about n, for unit and scaled lambda. atan2, sqrt and products of O(1)
  !> numbers: a few eps relative to |psi| <= 6; bound 1e-14 + 20 eps |a|.
  subroutine closed_forms()
    real(wp), parameter :: angles(14) = [0.0_wp, 1.0e-12_wp, 1.0e-8_wp, 1.0e-3_wp, 0.3_wp, &
      0.6_wp, 0.63_wp, 1.0_wp, 2.0_wp, 170 * DEG, 180 * DEG, 250 * DEG, 300 * DEG, 1.89_wp * PI]
    real(wp) :: n(3), lam(4), sc, err
    integer :: k, j
    do k = 1, size(angles)
      err = 0.0_wp
      do j = 1, 4
        n = random_rotvec(rng, 1.0_wp)
        n = n / norm2(n)
        sc = 1.0_wp
        if (j > 2) sc = rng%uniform(0.5_wp, 2.0_wp)
        lam = sc * rotvec_to_euler(angles(k) * n)
        err = max(err, maxval(abs(modes(rv, lam) - angles(k) * n)) / &
          (1.0e-14_wp + 20 * EPS * angles(k)))
        lam = sc * rotvec_to_euler(-angles(k) * n)
        err = max(err, maxval(abs(modes(rv, lam) + angles(k) * n)) / &
          (1.0e-14_wp + 20 * EPS * angles(k)))
      end do
      call ts%expect('turn by ' // real_str(angles(k)) // ' rad about n: psi = a n', err, &
        1.0_wp, C_E)
    end do
  end subroutine closed_forms

  subroutine invariance()
    real(wp) :: lam(4), psi(3), psi2(3), err(3), a
    integer :: k
    err = 0.0_wp
    do k = 1, 40
      ! Random Euler parameters on the whole sphere (l0 of both signs), scaled.
      lam = rng%uniform_vec(4, -1.0_wp, 1.0_wp)
      if (norm2(lam(2:4)) < 0.2_wp) lam(2) = 0.5_wp
      lam = lam / norm2(lam) * rng%uniform(0.5_wp, 2.0_wp)
      psi = modes(rv, lam)
      a = norm2(psi)
      ! The rotation matrix of psi is lambda's: rounding of O(1) products, bound 1e-13.
      err(1) = max(err(1), maxval(abs(euler_to_matrix(rotvec_to_euler(psi)) - &
        euler_to_matrix(lam))))
      ! -lambda: the same rotation the other way round the axis, |psi| -> 2 pi - |psi|.
      psi2 = modes(rv, -lam)
      err(2) = max(err(2), maxval(abs(psi2 - (a - 2 * PI) * psi / a)))
      err(3) = max(err(3), maxval(abs(matmul(jacobian(rv, lam), lam))) * norm2(lam))
    end do
    call ts%expect('R(exp(psi(lambda))) = R(lambda), random lambda', err(1), 1.0e-13_wp, C_INV)
    call ts%expect('psi(-lambda) = (|psi| - 2 pi) psi / |psi|', err(2), 1.0e-12_wp, C_INV)
    call ts%expect('de lambda = 0 (degree 0 in lambda)', err(3), 1.0e-12_wp, C_INV)
  end subroutine invariance

  !> At u = 0.1 (1 -+ 1e-12) the two forms are evaluated 2e-13 apart in u: e, de and second
  !> change by ~1e-12 relative there, the closed form's round-off is ~2e-14 (eps / u^2 for
  !> second); a wrong series term would be ~1e-3 off. Bound 1e-10.
  subroutine series_switch()
    real(wp) :: lo(4), hi(4), n(3), v(4), a, err
    integer :: k
    err = 0.0_wp
    do k = 1, 6
      n = random_rotvec(rng, 1.0_wp)
      n = n / norm2(n)
      v = rng%uniform_vec(4, -1.0_wp, 1.0_wp)
      a = 2 * atan(sqrt(0.1_wp * (1 - 1.0e-12_wp)))
      lo = rotvec_to_euler(a * n)
      a = 2 * atan(sqrt(0.1_wp * (1 + 1.0e-12_wp)))
      hi = rotvec_to_euler(a * n)
      err = max(err, relerr(modes(rv, lo), modes(rv, hi), 1.0_wp), &
        relerr(flat(jacobian(rv, lo)), flat(jacobian(rv, hi)), 1.0_wp), &
        relerr(second(rv, lo, v), second(rv, hi, v), 1.0_wp))
    end do
    call ts%expect('series and closed form agree across u = 0.1', err, 1.0e-10_wp, C_SW)
  end subroutine series_switch


  !> The modes are smooth on the scale zs = min(1, |lambda| sin(|psi|/2)) beyond half a turn
  !> (the distance to the full-turn singularity, lv = 0 with l0 < 0), 1 before, so the steps
  !> of expect_derivatives are multiples of zs; there |psi| <= 2 pi bounds the round-off.
  subroutine derivative_tests()
    real(wp), parameter :: angles(10) = [0.0_wp, 1.0e-8_wp, 1.0e-3_wp, 0.6_wp, 0.63_wp, &
      1.0_wp, 170 * DEG, 300 * DEG, -300 * DEG, 1.85_wp * PI]
    real(wp) :: x(4), v(4), n(3), a, zs
    character(len=48) :: what
    integer :: k
    real(wp) :: all_angles(size(angles) + 8)
    all_angles(1:size(angles)) = angles
    do k = size(angles) + 1, size(all_angles)
      all_angles(k) = rng%uniform(0.0_wp, ROTVEC_LIMIT)
    end do
    do k = 1, size(all_angles)
      n = random_rotvec(rng, 1.0_wp)
      a = all_angles(k)
      write(what, '(a,es10.3,a)') 'turn ', a, ' rad'
      n = n / norm2(n)
      x = rotvec_to_euler(a * n)
      ! Every other state off the unit sphere: the forms hold for any lambda /= 0.
      if (mod(k, 2) == 0) x = rng%uniform(0.6_wp, 1.4_wp) * x
      zs = 1.0_wp
      if (abs(a) > PI) zs = norm2(x) * abs(sin(a / 2))
      v = 0.3_wp * zs * rng%uniform_vec(4, -1.0_wp, 1.0_wp)
      call expect_derivatives(ts, rv, x, v, zs, trim(what), &
        C_DE, C_D2, C_POL)
    end do
  end subroutine derivative_tests

  subroutine full_turn()
    real(wp) :: x(4), v(4), psi(3), values(2, 3, 6)
    character(len=:), allocatable :: msg
    integer :: k
    ! Exactly a full turn, and lambda = 0: the floors keep everything finite.
    v = [0.3_wp, -0.2_wp, 0.5_wp, 0.1_wp]
    do k = 1, 2
      x = [-1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp] * (2 - k)
      values(k, :, 1) = modes(rv, x)
      values(k, :, 2:5) = jacobian(rv, x)
      values(k, :, 6) = second(rv, x, v)
    end do
    call ts%check(all(ieee_is_finite(values)), &
      'a full turn and lambda = 0: psi, de, second finite')
    psi = [0.6_wp, 0.0_wp, 0.8_wp] * (ROTVEC_LIMIT * (1 - 1.0e-9_wp))
    msg = rv%limit_problem(psi)
    call ts%check(len(msg) == 0, 'limit: no problem just below 1.9 pi')
    psi = [0.6_wp, 0.0_wp, 0.8_wp] * (ROTVEC_LIMIT * (1 + 1.0e-9_wp))
    msg = rv%limit_problem(psi)
    call ts%check(index(msg, 'node ''n'' rotation') == 1 .and. index(msg, 'full turn') > 0, &
      'limit: just above 1.9 pi, a message naming the element and the full turn')
  end subroutine full_turn
  !> A chart moved to a reference r: psi is the rotation vector of conj(r) lambda (the same
  !> closed forms' round-off, bound 1e-14 + 20 eps |a| as there), its derivatives pass the
  !> same difference checks, recentre moves only beyond RECENTRE_ABOVE and then gives psi = 0
  !> at x, and chart/set_chart restore a chart exactly.
  subroutine moving_chart()
    type(rotvec_t) :: moved
    real(wp) :: r(4), n(3), x(4), v(4), a, err, psi(3)
    real(wp), allocatable :: saved(:)
    logical :: did
    integer :: k
    moved = rv
    err = 0.0_wp
    do k = 1, 12
      r = rotvec_to_euler(random_rotvec(rng, 3.0_wp))
      call moved%set_chart(r)
      n = random_rotvec(rng, 1.0_wp)
      n = n / norm2(n)
      a = rng%uniform(0.0_wp, ROTVEC_LIMIT)
      x = rng%uniform(0.6_wp, 1.4_wp) * euler_product(r, rotvec_to_euler(a * n))
      err = max(err, maxval(abs(modes(moved, x) - a * n)) / (1.0e-14_wp + 20 * EPS * a))
      if (k <= 4) then
        v = 0.3_wp * rng%uniform_vec(4, -1.0_wp, 1.0_wp)
        ! The same scale as derivative_tests: the distance to the full-turn singularity.
        if (a > PI) v = v * norm2(x) * abs(sin(a / 2))
        call expect_derivatives(ts, moved, x, v, merge(norm2(x) * abs(sin(a / 2)), 1.0_wp, &
          a > PI), 'moved chart', C_DE, C_D2, C_POL)
      end if
    end do
    call ts%expect('psi in a moved chart = rotation vector of conj(r) lambda', err, 1.0_wp, &
      C_CH)
    x = 1.3_wp * rotvec_to_euler([0.0_wp, 0.9_wp * RECENTRE_ABOVE, 0.0_wp])
    call moved%set_chart([1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp])
    call moved%recentre(x, modes(moved, x), did)
    call ts%check(.not. did .and. all(moved%chart() == [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp]), &
      'recentre: below the threshold the chart stays')
    x = 1.3_wp * rotvec_to_euler([0.0_wp, 1.1_wp * RECENTRE_ABOVE, 0.0_wp])
    call moved%recentre(x, modes(moved, x), did)
    ! conj(x / |x|) x = (|x|, 0): psi is exactly zero up to the rounding of the product.
    call ts%expect('recentre beyond the threshold: psi = 0 at x', &
      maxval(abs(modes(moved, x))), 1.0e-15_wp, C_CH)
    call ts%check(did, 'recentre: beyond the threshold the chart moves')
    saved = moved%chart()
    x = rotvec_to_euler([0.4_wp, -0.5_wp, 0.6_wp])
    psi = modes(moved, x)
    call moved%set_chart(rotvec_to_euler([0.1_wp, 0.2_wp, 0.3_wp]))
    call ts%check(any(modes(moved, x) /= psi), 'another chart, other psi')
    call moved%set_chart(saved)
    call ts%check(all(moved%chart() == saved), 'chart / set_chart restore the chart')
    call ts%check(all(modes(moved, x) == psi), 'the restored chart gives the same psi')
    call ts%check(size(rv%chart()) == 4, 'the chart of a free rotation: 4 numbers')
  end subroutine moving_chart
end program test_rotvec
