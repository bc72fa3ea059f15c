!> The laws of running machines (ramp, harmonic, spin_up, table, sum): values, rates and
!> accelerations against closed forms and central differences, continuity at breakpoints,
!> the not-a-knot spline (cubics reproduced, C2), sums, and bandwidths.
!>
!> Central differences with step h: |(f(t+h) - f(t-h)) / (2h) - f'(t)| <= h^2/6 max|f'''| +
!> 2 u max|f| / h + eps |t| |f'| / (2h) (u: the relative rounding of one evaluation, a few
!> eps; the last term: t + h and t - h are rounded to the spacing of t, so the step actually
!> taken differs from 2h by up to eps |t|); each check allows 10 times that bound, u = 4 eps.
program test_motion_laws
  use core_kinds, only: wp
  use motion_law, only: motion_t, motion_sum, motion_table, table_problem, LAW_RAMP, &
    LAW_HARMONIC, LAW_SPIN_UP, LAW_CYCLOIDAL, BANDWIDTH_UNBOUNDED
  use testing, only: suite_t
  implicit none

  real(wp), parameter :: PI = 3.14159265358979323846_wp
  real(wp), parameter :: U = 4 * epsilon(1.0_wp)
  type(suite_t) :: suite
  type(motion_t) :: ramp, harm, spin, tab, cyc, s1, s2, s3
  real(wp) :: p, pd, pdd, q(3), qd(3), qdd(3), t, w, om, m3, err_p, err_d, err_a
  real(wp), allocatable :: tb(:), x(:), y(:)
  integer :: k

  call suite%init('motion laws of running machines')

  ! ramp: held before t0, then start + rate (t - t0); the rate steps at t0.
  ramp = motion_t(law=LAW_RAMP, start=0.2_wp, rate=3.0_wp, t0=0.5_wp)
  ramp%label = 'ramp'
  call ramp%eval(0.4_wp, p, pd, pdd)
  call suite%check(p == 0.2_wp .and. pd == 0 .and. pdd == 0, 'ramp: held before t0')
  call ramp%eval(0.5_wp, p, pd, pdd)
  call suite%check(p == 0.2_wp .and. pd == 3 .and. pdd == 0, 'ramp: started at t0 (right-continuous)')
  call ramp%eval(2.5_wp, p, pd, pdd)
  call suite%close(p, 6.2_wp, 4 * U, 0.0_wp, 'ramp: p = start + rate (t - t0)')
  call fd_check(ramp, [0.7_wp, 1.3_wp, 9.0_wp], 1.0e-4_wp, 0.0_wp, 0.0_wp, 'ramp')
  call suite%check(same(ramp%breakpoints(), [0.5_wp]), 'ramp: breakpoint t0')
  call suite%check(ramp%bandwidth_hz(0.99_wp) == BANDWIDTH_UNBOUNDED, &
    'ramp: no finite bandwidth (velocity step)')

  ! harmonic: start + A (sin(om (t - t0) + phase) - sin(phase)), continuous at t0.
  harm = motion_t(law=LAW_HARMONIC, start=-0.1_wp, amplitude=0.2_wp, frequency=3.0_wp, &
    phase=0.4_wp, t0=0.25_wp)
  harm%label = 'harm'
  om = 2 * PI * 3
  call harm%eval(0.25_wp, p, pd, pdd)
  call suite%close(p, -0.1_wp, 0.0_wp, 4 * U * 0.2_wp, 'harmonic: p(t0) = start')
  call suite%close(pd, 0.2_wp * om * cos(0.4_wp), 4 * U, 0.0_wp, 'harmonic: rate at t0')
  call harm%eval(0.2_wp, p, pd, pdd)
  call suite%check(p == -0.1_wp .and. pd == 0 .and. pdd == 0, 'harmonic: held before t0')
  t = 1.37_wp
  call harm%eval(t, p, pd, pdd)
  w = om * (t - 0.25_wp) + 0.4_wp
  call suite%close(p, -0.1_wp + 0.2_wp * (sin(w) - sin(0.4_wp)), 0.0_wp, 1.0e-14_wp, &
    'harmonic: closed form p')
  call suite%close(pdd, -0.2_wp * om**2 * sin(w), 1.0e-13_wp, 0.0_wp, 'harmonic: closed form pdd')
  call fd_check(harm, [0.31_wp, 0.77_wp, 1.9_wp], 1.0e-5_wp, 0.2_wp * om**3, 0.2_wp * om**4, &
    'harmonic')
  call suite%check(same(harm%breakpoints(), [0.25_wp]), 'harmonic: breakpoint t0')
  call suite%check(harm%bandwidth_hz(0.99_wp) == 3.0_wp, 'harmonic: bandwidth = frequency')

  ! spin_up (Kane et al.), w = 4 rad/s, T = 15 s, from t0 = 1: rate w and acceleration 0 at
  ! t0 + T, and theta = w (t - t0 - T/2) after.
  spin = motion_t(law=LAW_SPIN_UP, start=0.5_wp, rate=4.0_wp, duration=15.0_wp, t0=1.0_wp)
  spin%label = 'spin'
  call spin%eval(1.0_wp, p, pd, pdd)
  call suite%check(p == 0.5_wp .and. pd == 0 .and. pdd == 0, 'spin_up: at rest at t0')
  call spin%eval(8.5_wp, p, pd, pdd)
  ! tau = T/2: theta = (w/T)(T^2/8 - 2 (T/(2 pi))^2), rate (w/T) T/2, acceleration 2 w/T.
  call suite%close(p, 0.5_wp + 4.0_wp / 15 * (15.0_wp**2 / 8 - 2 * (15 / (2 * PI))**2), &
    1.0e-14_wp, 0.0_wp, 'spin_up: closed form p at T/2')
  call suite%close(pd, 2.0_wp, 1.0e-14_wp, 0.0_wp, 'spin_up: rate w/2 at T/2')
  call suite%close(pdd, 8.0_wp / 15, 1.0e-14_wp, 0.0_wp, 'spin_up: acceleration 2 w/T at T/2')
  call spin%eval(21.0_wp, p, pd, pdd)
  call suite%close(p, 0.5_wp + 4 * (20 - 7.5_wp), 1.0e-15_wp, 0.0_wp, &
    'spin_up: w (t - t0 - T/2) after T')
  call suite%check(pd == 4 .and. pdd == 0, 'spin_up: rate w, no acceleration after T')
  m3 = 4.0_wp / 15 * (2 * PI / 15)
  call fd_check(spin, [1.3_wp, 6.1_wp, 12.7_wp, 15.9_wp, 18.0_wp], 1.0e-4_wp, m3, &
    m3 * 2 * PI / 15, 'spin_up')
  tb = spin%breakpoints()
  call suite%check(same(tb, [1.0_wp, 16.0_wp]), 'spin_up: breakpoints t0 and t0 + T')
  ! The acceleration (and its derivative) is continuous at both: no restart is needed there.
  do k = 1, size(tb)
    call continuity(spin, tb(k), 1.0e-6_wp, 4.0_wp, 8.0_wp / 15, m3, 50.0_wp, .true., 'spin_up')
  end do
  ! Its acceleration (w/T)(1 - cos 2 pi s) on [t0, t0 + T] has |G(nu)|^2 = (w/T)^2 sin^2(pi nu)
  ! / (pi^2 nu^2 (1 - nu^2)^2) per unit of nu = f T and int_0^1 a^2 ds = 1.5 (w/T)^2.
  call suite%close(spin_fraction(spin%bandwidth_hz(0.99_wp) * 15), 0.99_wp, 0.0_wp, 1.0e-8_wp, &
    'spin_up: bandwidth holds 99 % of the closed-form acceleration energy')

  ! Table: the not-a-knot spline reproduces a cubic exactly (to rounding) on uneven knots.
  x = [0.0_wp, 0.3_wp, 0.45_wp, 1.0_wp, 1.2_wp, 1.9_wp, 2.0_wp]
  y = cubic(x)
  call suite%check(table_problem(x, y) == '', 'table: good points accepted')
  tab = motion_table('tab', x, y)
  err_p = 0; err_d = 0; err_a = 0
  do k = 0, 400
    t = 2.0_wp * k / 400
    if (k == 400) t = nearest(2.0_wp, -1.0_wp)
    call tab%eval(t, p, pd, pdd)
    err_p = max(err_p, abs(p - cubic1(t)))
    err_d = max(err_d, abs(pd - (-2 + t + 2.1_wp * t**2)))
    err_a = max(err_a, abs(pdd - (1 + 4.2_wp * t)))
  end do
  write(*, '(a,3es10.2)') '    spline vs cubic, max errors p, pd, pdd:', err_p, err_d, err_a
  ! Scale of p, pd, pdd: about 5, 10, 10; the knot solve and evaluation lose a few tens of eps
  ! (observed 2e-15, 5e-15, 2e-14).
  call suite%check(err_p < 2.0e-13_wp .and. err_d < 2.0e-13_wp .and. err_a < 2.0e-13_wp, &
    'table: cubic reproduced to rounding (2e-13)')
  call tab%eval(-1.0_wp, p, pd, pdd)
  call suite%check(p == y(1) .and. pd == 0 .and. pdd == 0, 'table: held before the first time')
  call tab%eval(2.0_wp, p, pd, pdd)
  call suite%check(p == y(7) .and. pd == 0 .and. pdd == 0, 'table: held from the last time')
  call suite%check(same(tab%breakpoints(), [0.0_wp, 2.0_wp]), 'table: breakpoints at its ends')
  ! Three points: the parabola through them; two: the line.
  tab = motion_table('t3', [0.0_wp, 1.0_wp, 3.0_wp], [1.0_wp, 0.0_wp, 4.0_wp])
  call tab%eval(2.0_wp, p, pd, pdd)
  ! Through (0,1), (1,0), (3,4): (t - 1)^2.
  call suite%close(p, 1.0_wp, 0.0_wp, 1.0e-14_wp, 'table: 3 points, parabola')
  call suite%close(pd, 2.0_wp, 0.0_wp, 1.0e-14_wp, 'table: 3 points, parabola''s rate')
  call suite%close(pdd, 2.0_wp, 1.0e-14_wp, 0.0_wp, 'table: 3 points, curvature')
  tab = motion_table('t2', [1.0_wp, 3.0_wp], [1.0_wp, 0.0_wp])
  call tab%eval(2.5_wp, p, pd, pdd)
  call suite%check(abs(p - 0.25_wp) < 1.0e-15_wp .and. pd == -0.5_wp .and. pdd == 0, &
    'table: 2 points, line')
  ! C2 on data that is no polynomial: continuity of p, pd, pdd at the interior knots, and
  ! central differences inside the pieces (the spline's fourth derivative is 0 there).
  x = [(0.1_wp * k + 0.02_wp * sin(real(k, wp)), k = 0, 20)]
  y = sin(3 * x) + 0.3_wp * x
  tab = motion_table('tab', x, y)
  m3 = maxval(abs(tab%curvature(2:) - tab%curvature(:size(x) - 1)) / (x(2:) - x(:size(x) - 1)))
  do k = 2, size(x) - 1
    call continuity(tab, x(k), 1.0e-7_wp, 5.0_wp, maxval(abs(tab%curvature)), m3, 2.0_wp, &
      .true., 'table')
  end do
  call fd_check(tab, [(0.5_wp * (x(k) + x(k + 1)), k = 1, size(x) - 1)], 1.0e-5_wp, m3, &
    0.0_wp, 'table')
  ! A table of a cycloidal law (101 points) has nearly its bandwidth: the spline's
  ! acceleration differs by O(h^2) = 1e-4 relative.
  cyc = motion_t(law=LAW_CYCLOIDAL, start=0.0_wp, end=1.0_wp, t0=0.0_wp, duration=1.0_wp)
  x = [(0.01_wp * k, k = 0, 100)]
  y = [real(wp) ::]
  do k = 1, size(x)
    call cyc%eval(x(k), p, pd, pdd)
    y = [y, p]
  end do
  tab = motion_table('cyc', x, y)
  call suite%close(tab%bandwidth_hz(0.99_wp), cyc%bandwidth_hz(0.99_wp), 1.0e-3_wp, 0.0_wp, &
    'table of a cycloidal law: its bandwidth (0.1 %; observed 2e-5)')

  ! Sums: term by term, nested sums flattened, breakpoints the union, bandwidth the largest.
  x = [0.0_wp, 0.3_wp, 0.45_wp, 1.0_wp, 1.2_wp, 1.9_wp, 2.0_wp]
  tab = motion_table('tab', x, cubic(x))
  s1 = motion_sum('s1', [harm, spin])
  s2 = motion_sum('s2', [s1, tab])
  call suite%check(size(s2%terms) == 3, 'sum: nested sums flattened')
  do k = 0, 30
    t = -0.5_wp + 0.7_wp * k
    call harm%eval(t, q(1), qd(1), qdd(1))
    call spin%eval(t, q(2), qd(2), qdd(2))
    call tab%eval(t, q(3), qd(3), qdd(3))
    call s2%eval(t, p, pd, pdd)
    if (p /= q(1) + q(2) + q(3) .or. pd /= qd(1) + qd(2) + qd(3) .or. &
        pdd /= qdd(1) + qdd(2) + qdd(3)) exit
  end do
  call suite%check(k == 31, 'sum: p, pd, pdd are the sums of the terms''')
  call suite%check(same(s2%breakpoints(), [0.0_wp, 0.25_wp, 1.0_wp, 2.0_wp, 16.0_wp]), &
    'sum: breakpoints are the union')
  call suite%close(s2%bandwidth_hz(0.99_wp), max(harm%bandwidth_hz(0.99_wp), &
    spin%bandwidth_hz(0.99_wp), tab%bandwidth_hz(0.99_wp)), 0.0_wp, 0.0_wp, &
    'sum: bandwidth the largest of the terms''')
  s3 = motion_sum('s3', [s2, ramp])
  call suite%check(s3%bandwidth_hz(0.99_wp) == BANDWIDTH_UNBOUNDED, &
    'sum with a ramp: no finite bandwidth')

  ! Bad tables.
  call suite%check(index(table_problem([0.0_wp, 1.0_wp, 1.0_wp], [1.0_wp, 2.0_wp, 3.0_wp]), &
    'strictly increasing') > 0, 'table: repeated time refused')
  call suite%check(index(table_problem([0.0_wp, 1.0_wp], [1.0_wp]), '2 times but 1 values') > 0, &
    'table: unequal lengths refused')
  call suite%check(index(table_problem([0.0_wp], [1.0_wp]), 'at least 2') > 0, &
    'table: one point refused')
  call suite%finish()

contains

  elemental real(wp) function cubic1(t)
    real(wp), intent(in) :: t
    cubic1 = 1 - 2 * t + 0.5_wp * t**2 + 0.7_wp * t**3
  end function cubic1

  pure function cubic(t) result(c)
    real(wp), intent(in) :: t(:)
    real(wp) :: c(size(t))
    c = cubic1(t)
  end function cubic

  !> Same times, in any order and with repeats.
  logical function same(a, b)
    real(wp), intent(in) :: a(:), b(:)
    integer :: i
    same = .true.
    do i = 1, size(a)
      same = same .and. any(a(i) == b)
    end do
    do i = 1, size(b)
      same = same .and. any(b(i) == a)
    end do
  end function same

  !> pd and pdd against central differences of p and pd at times ts (m3, m4: bounds of the
  !> third and fourth derivatives there).
  subroutine fd_check(m, ts, h, m3, m4, name)
    type(motion_t), intent(in) :: m
    real(wp), intent(in) :: ts(:), h, m3, m4
    character(len=*), intent(in) :: name
    real(wp) :: p, pd, pdd, pp, pdp, pm, pdm, dum, bound
    integer :: k
    do k = 1, size(ts)
      call m%eval(ts(k), p, pd, pdd)
      call m%eval(ts(k) + h, pp, pdp, dum)
      call m%eval(ts(k) - h, pm, pdm, dum)
      ! Without the step's rounding (eps |t| |f'| / 2h) the table's accelerations at t ~ 2
      ! came within 4.3x of the bound (6.0e-11 of 2.6e-10, both builds): that term is 1.9e-10.
      bound = 10 * (h**2 / 6 * m3 + 2 * U * max(abs(pp), abs(pm)) / h + &
        epsilon(1.0_wp) * abs(ts(k)) * abs(pd) / (2 * h))
      call suite%close(pd, (pp - pm) / (2 * h), 0.0_wp, bound, name // ': rate vs differences')
      bound = 10 * (h**2 / 6 * m4 + 2 * U * max(abs(pdp), abs(pdm)) / h + &
        epsilon(1.0_wp) * abs(ts(k)) * abs(pdd) / (2 * h))
      call suite%close(pdd, (pdp - pdm) / (2 * h), 0.0_wp, bound, &
        name // ': acceleration vs differences')
    end do
  end subroutine fd_check

  !> p, pd (and pdd when c2) just before tb against the values at tb: the changes over delta
  !> are at most pd_max delta, pdd_max delta and m3 delta (m3: max |p'''|), plus rounding of
  !> values ~ pmax. (The rate's change used pd_max where the mean value theorem needs
  !> pdd_max: on the table, |pdd| reaches 9 > pd_max = 5, and the observed change came
  !> within 5.5x of the bound, 9.0e-7 of 5e-6; with pdd_max it is at most 1/10 of it.)
  subroutine continuity(m, tb, delta, pd_max, pdd_max, m3, pmax, c2, name)
    type(motion_t), intent(in) :: m
    real(wp), intent(in) :: tb, delta, pd_max, pdd_max, m3, pmax
    logical, intent(in) :: c2
    character(len=*), intent(in) :: name
    real(wp) :: p0, pd0, pdd0, p1, pd1, pdd1
    call m%eval(tb - delta, p0, pd0, pdd0)
    call m%eval(tb, p1, pd1, pdd1)
    call suite%close(p0, p1, 0.0_wp, 10 * (pd_max * delta + U * pmax), name // ': p continuous')
    call suite%close(pd0, pd1, 0.0_wp, 10 * (pdd_max * delta + U * pd_max), &
      name // ': rate continuous')
    if (c2) call suite%close(pdd0, pdd1, 0.0_wp, 10 * (m3 * delta + U * pd_max), &
      name // ': acceleration continuous')
  end subroutine continuity

  !> Fraction of the spin-up's acceleration energy below nu = f T, from the closed-form
  !> transform, by 4-point Gauss-Legendre on 4000 panels per unit of nu (the nodes never
  !> meet the removable singularities at nu = 0 and 1).
  real(wp) function spin_fraction(nu) result(frac)
    real(wp), intent(in) :: nu
    real(wp), parameter :: XG(4) = [-0.8611363115940526_wp, -0.3399810435848563_wp, &
      0.3399810435848563_wp, 0.8611363115940526_wp]
    real(wp), parameter :: WG(4) = [0.3478548451374538_wp, 0.6521451548625461_wp, &
      0.6521451548625461_wp, 0.3478548451374538_wp]
    real(wp) :: h, a, v
    integer :: k, j, n
    n = ceiling(4000 * nu)
    h = nu / n
    frac = 0
    do k = 0, n - 1
      a = (k + 0.5_wp) * h
      do j = 1, 4
        v = a + 0.5_wp * h * XG(j)
        frac = frac + 0.5_wp * h * WG(j) * sin(PI * v)**2 / (PI**2 * v**2 * (1 - v**2)**2)
      end do
    end do
    frac = 2 * frac / 1.5_wp
  end function spin_fraction
end program test_motion_laws
