!> Motion bandwidth: the frequency below which a fraction of the acceleration energy lies.
!> Checks Parseval (the band energy tends to int a^2 dt; for the cubic law, whose
!> acceleration jumps, the missing tail against its asymptote 2 * 72 / (4 pi^2 nu)), the
!> band energy against the closed-form Fourier transform of the cubic law, the 1 / duration
!> scaling, the independence of t0 and the span, smooth laws against the cubic, and constants.
program test_motion_bandwidth
  use core_kinds, only: wp
  use motion_law, only: motion_t, LAW_CONSTANT, LAW_CUBIC, LAW_QUINTIC, LAW_CYCLOIDAL, &
    BANDWIDTH_MAX_CYCLES
  use testing, only: suite_t
  implicit none

  real(wp), parameter :: PI = 3.14159265358979323846_wp
  character(len=9), parameter :: NAMES(3) = ['cubic    ', 'quintic  ', 'cycloidal']
  integer, parameter :: LAWS(3) = [LAW_CUBIC, LAW_QUINTIC, LAW_CYCLOIDAL]
  !> int_0^1 (d^2 f / ds^2)^2 ds of the normalised laws f(s): int a^2 dt = C span^2 / T^3
  real(wp), parameter :: ENERGY_COEF(3) = [12.0_wp, 120.0_wp / 7, 2 * PI**2]
  real(wp), parameter :: SPAN = 1.5707963267948966_wp

  type(suite_t) :: suite
  type(motion_t) :: m, m2
  real(wp) :: f99(3), f_half, total, e, nu, tail, t0, dt, ref
  integer :: i, k

  call suite%init('motion bandwidth (acceleration energy spectrum)')

  do i = 1, 3
    m = motion_t(label='m', law=LAWS(i), start=0.0_wp, end=SPAN, t0=0.0_wp, duration=0.5_wp)
    total = ENERGY_COEF(i) * SPAN**2 / m%duration**3
    t0 = seconds()
    f99(i) = m%bandwidth_hz(0.99_wp)
    dt = seconds() - t0
    write(*, '(a,f10.4,a,f8.3,a)') '    ' // NAMES(i) // ' T = 0.5 s: F(0.99) = ', f99(i), &
      ' Hz (', 1.0e3_wp * dt, ' ms)'
    ! The time is printed, not checked: a wall-time bound fails on a slow or loaded machine.
    ! The definition itself: E(F) = 0.99 int a^2 dt.
    e = m%band_energy(f99(i))
    call suite%close(e / total, 0.99_wp, 1.0e-9_wp, 0.0_wp, trim(NAMES(i)) // &
      ': E(F(0.99)) = 0.99 int a^2 dt')

    ! Parseval: E(F) -> int a^2 dt. Smooth ends: the tail falls as nu^-3.
    nu = 200
    e = m%band_energy(nu / m%duration)
    if (LAWS(i) == LAW_CUBIC) then
      ! The jumps of +-6 span / T^2 at both ends give |G(nu)|^2 ~ 72 (1 + cos 2 pi nu) /
      ! (4 pi^2 nu^2) (span / T^2)^2, so the energy above nu is 2 * 72 / (4 pi^2 nu) span^2/T^3.
      tail = 2 * 72 / (4 * PI**2 * nu) * SPAN**2 / m%duration**3
      write(*, '(a,es12.4,a,es12.4)') '      int a^2 - E(200 / T) = ', total - e, &
        ', asymptotic tail ', tail
      call suite%close(total - e, tail, 1.0e-2_wp, 0.0_wp, &
        'cubic: int a^2 dt - E(200 / T) equals the 1/f tail of the jumps (1%)')
    else
      write(*, '(a,es10.2)') '      Parseval: E(200 / T) / int a^2 dt - 1 = ', e / total - 1
      call suite%close(e, total, 1.0e-6_wp, 0.0_wp, trim(NAMES(i)) // &
        ': Parseval, E(200 / T) = int a^2 dt')
    end if

    ! 1 / duration: halving the duration doubles F.
    m2 = m
    m2%duration = m%duration / 2
    f_half = m2%bandwidth_hz(0.99_wp)
    call suite%close(f_half / f99(i), 2.0_wp, 1.0e-3_wp, 0.0_wp, trim(NAMES(i)) // &
      ': halving the duration doubles F(0.99)')
    ! Neither the start time nor the span changes the spectrum's shape.
    m2 = motion_t(label='m', law=LAWS(i), start=2.0_wp, end=-0.3_wp, t0=1.7_wp, duration=0.5_wp)
    call suite%close(m2%bandwidth_hz(0.99_wp), f99(i), 1.0e-9_wp, 0.0_wp, trim(NAMES(i)) // &
      ': F independent of t0 and span')
    call suite%check(m%bandwidth_hz(0.9_wp) < f99(i) .and. f99(i) < m%bandwidth_hz(0.999_wp), &
      trim(NAMES(i)) // ': F grows with the fraction')
  end do

  ! The cubic law's transform in closed form: a = c (6 - 12 s) on s in [0, 1], c = span/T^2,
  ! A(f) = T c G(nu), G = 6 I0 - 12 (I0 - exp(-i w)) / (i w), I0 = (1 - exp(-i w)) / (i w),
  ! w = 2 pi nu; E(F) by the composite Simpson rule in nu.
  m = motion_t(label='m', law=LAW_CUBIC, start=0.0_wp, end=SPAN, t0=0.3_wp, duration=0.5_wp)
  ref = 0
  do k = 0, 20000
    nu = 10.0_wp * k / 20000
    ref = ref + merge(1, merge(4, 2, mod(k, 2) == 1), k == 0 .or. k == 20000) * cubic_g2(nu)
  end do
  ref = ref * (10.0_wp / 20000) / 3
  ref = 2 * m%duration * (SPAN / m%duration**2)**2 * ref
  e = m%band_energy(10 / m%duration)
  call suite%close(e, ref, 1.0e-8_wp, 0.0_wp, &
    'cubic: E(10 / T) equals the closed-form transform')

  ! Smooth ends (quintic, cycloidal) keep the spectrum much lower than the cubic's jumps.
  call suite%check(f99(2) < f99(1) / 3 .and. f99(3) < f99(1) / 3, &
    'quintic and cycloidal: F(0.99) below a third of the cubic one')
  write(*, '(a,3f10.4)') '    F(0.99) [Hz], T = 0.5 s, cubic / quintic / cycloidal:', f99

  ! No acceleration: no bandwidth. Fraction 1 (never reached) gives the search limit.
  m = motion_t(label='m', law=LAW_CONSTANT, start=0.4_wp)
  call suite%check(m%bandwidth_hz(0.99_wp) == 0, 'constant law: F = 0')
  m = motion_t(label='m', law=LAW_CUBIC, start=0.4_wp, end=0.4_wp, duration=0.5_wp)
  call suite%check(m%bandwidth_hz(0.99_wp) == 0, 'cubic law with end = start: F = 0')
  m = motion_t(label='m', law=LAW_QUINTIC, start=0.0_wp, end=1.0_wp, duration=0.5_wp)
  call suite%check(m%bandwidth_hz(1.0_wp) == BANDWIDTH_MAX_CYCLES / 0.5_wp, &
    'fraction 1: the search limit BANDWIDTH_MAX_CYCLES / duration')
  call suite%check(m%bandwidth_hz(0.0_wp) == 0, 'fraction 0: F = 0')

  call suite%finish()

contains

  real(wp) function cubic_g2(nu)
    real(wp), intent(in) :: nu
    complex(wp) :: iw, e, i0, g
    if (nu <= 0) then
      cubic_g2 = 0   ! G(0) = int a = 0 (rest to rest)
      return
    end if
    iw = cmplx(0.0_wp, 2 * PI * nu, wp)
    e = exp(-iw)
    i0 = (1 - e) / iw
    g = 6 * i0 - 12 * (i0 - e) / iw
    cubic_g2 = abs(g)**2
  end function cubic_g2

  real(wp) function seconds()
    integer(kind=8) :: c, rate
    call system_clock(c, rate)
    seconds = real(c, wp) / real(rate, wp)
  end function seconds
end program test_motion_bandwidth
