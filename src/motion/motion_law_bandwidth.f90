!> The bandwidth of a motion law: the energy spectrum of its acceleration (motion_law).
submodule (motion_law) motion_law_bandwidth
  implicit none

  !> Gauss-Legendre points per time panel; a panel spans at most two periods of the highest
  !> frequency in use, which these integrate to about 1e-10.
  integer, parameter :: GAUSS_TIME = 16
  !> Gauss-Legendre points per unit of nu = f duration: |A|^2 varies on that scale (the two
  !> ends of the motion interfere with period 1 in nu).
  integer, parameter :: GAUSS_FREQ = 12

contains

  !> Laws with a finite span work in nu = f duration and s = (t - ta) / duration over their
  !> span [ta, ta + duration] (the law is at rest, or moves without acceleration, outside):
  !>   E(F) = 2 int_0^F |A(f)|^2 df >= fraction int a(t)^2 dt,
  !>   A(f) = int a(t) exp(-2 pi i f t) dt over the span.
  !> At most BANDWIDTH_MAX_CYCLES / duration; F scales as 1 / duration and does not depend on
  !> the start time or the size of the motion. The cost grows as F^2: about a millisecond for
  !> 0.99 and a cubic law. A harmonic's acceleration is one sinusoid (its onset at t0 is not
  !> counted); a ramp's is an impulse at t0, with a flat spectrum.
  pure module real(wp) function law_bandwidth_hz(this, fraction) result(f_hz)
    class(law_t), intent(in) :: this
    real(wp), intent(in) :: fraction
    real(wp) :: xf(GAUSS_FREQ), wf(GAUSS_FREQ), total, target, e, piece, lo, hi, x, xn, h, dh
    real(wp), allocatable :: s(:), w(:), a(:)
    integer :: k, it
    real(wp) :: ta, duration
    f_hz = 0.0_wp
    select case (this%law)
    case (LAW_RAMP)
      if (this%rate /= 0) f_hz = BANDWIDTH_UNBOUNDED
      return
    case (LAW_HARMONIC)
      if (this%amplitude /= 0) f_hz = this%frequency
      return
    end select
    call finite_span(this, ta, duration)
    if (.not. duration > 0 .or. .not. fraction > 0) return
    f_hz = BANDWIDTH_MAX_CYCLES / duration
    if (fraction >= 1) return
    ! Work in nu = f duration and s = (t - t0) / duration: A(f) = duration G(nu) with
    ! G(nu) = int_0^1 a exp(-2 pi i nu s) ds, and the condition reads
    ! 2 int_0^nu |G|^2 >= fraction int_0^1 a^2 ds.
    call gauss_legendre(GAUSS_FREQ, xf, wf)
    call time_nodes(this, ta, duration, 1.0_wp, s, w, a)
    total = sum(w * a**2)
    if (.not. total > 0) then
      f_hz = 0.0_wp
      return
    end if
    target = fraction * total
    e = 0.0_wp
    do k = 0, nint(BANDWIDTH_MAX_CYCLES) - 1
      call time_nodes(this, ta, duration, real(k + 1, wp), s, w, a)
      piece = band_integral(s, w, a, real(k, wp), real(k + 1, wp), xf, wf)
      if (e + piece >= target) then
        ! E is increasing with derivative 2 |G|^2: Newton, kept inside the bracket by
        ! bisection where |G| nearly vanishes.
        lo = k
        hi = k + 1
        x = k + max(0.0_wp, min(1.0_wp, (target - e) / piece))
        do it = 1, 100
          h = e + band_integral(s, w, a, real(k, wp), x, xf, wf) - target
          if (h > 0) then
            hi = x
          else
            lo = x
          end if
          dh = 2 * spectrum2(s, w, a, x)
          xn = 0.5_wp * (lo + hi)
          if (dh > 0) then
            if (x - h / dh > lo .and. x - h / dh < hi) xn = x - h / dh
          end if
          if (abs(xn - x) <= 1.0e-11_wp * (1 + x) .or. hi - lo <= 1.0e-11_wp * (1 + x)) then
            x = xn
            exit
          end if
          x = xn
        end do
        f_hz = x / duration
        return
      end if
      e = e + piece
    end do
  end function law_bandwidth_hz

  pure module real(wp) function law_band_energy(this, f_hz) result(e)
    class(law_t), intent(in) :: this
    real(wp), intent(in) :: f_hz
    real(wp) :: xf(GAUSS_FREQ), wf(GAUSS_FREQ), nu, lo, ta, duration
    real(wp), allocatable :: s(:), w(:), a(:)
    integer :: k
    e = 0.0_wp
    call finite_span(this, ta, duration)
    if (.not. duration > 0 .or. .not. f_hz > 0) return
    call gauss_legendre(GAUSS_FREQ, xf, wf)
    nu = f_hz * duration
    do k = 0, ceiling(nu) - 1
      lo = k
      call time_nodes(this, ta, duration, min(lo + 1, nu), s, w, a)
      e = e + band_integral(s, w, a, lo, min(lo + 1, nu), xf, wf)
    end do
    ! E(F) = 2 int_0^F duration^2 |G(f duration)|^2 df = duration 2 int_0^nu |G|^2 dnu
    e = e * duration
  end function law_band_energy

  !> The span [ta, ta + duration] outside which a law does not accelerate; duration = 0 for
  !> laws that do not accelerate or never stop (constant, ramp, harmonic, sum).
  pure subroutine finite_span(this, ta, duration)
    class(law_t), intent(in) :: this
    real(wp), intent(out) :: ta, duration
    ta = this%t0
    duration = 0.0_wp
    select case (this%law)
    case (LAW_CUBIC, LAW_QUINTIC, LAW_CYCLOIDAL)
      if (this%end /= this%start) duration = this%duration
    case (LAW_SPIN_UP)
      if (this%rate /= 0) duration = this%duration
    case (LAW_TABLE)
      ta = this%knots(1)
      duration = this%knots(size(this%knots)) - ta
    end select
  end subroutine finite_span

  !> Gauss-Legendre nodes s and weights w on [0, 1] fine enough for exp(-2 pi i nu s) up to
  !> nu_max, and the acceleration a at the nodes (times ta + s duration). A table's
  !> acceleration has kinks at its knots, inside panels: its spectrum is less accurate.
  pure subroutine time_nodes(this, ta, duration, nu_max, s, w, a)
    class(law_t), intent(in) :: this
    real(wp), intent(in) :: ta, duration, nu_max
    real(wp), allocatable, intent(out) :: s(:), w(:), a(:)
    real(wp) :: x(GAUSS_TIME), wx(GAUSS_TIME), p, pd
    integer :: np, i, j, n
    np = max(2, ceiling(nu_max / 2))
    call gauss_legendre(GAUSS_TIME, x, wx)
    allocate(s(np * GAUSS_TIME), w(np * GAUSS_TIME), a(np * GAUSS_TIME))
    n = 0
    do i = 1, np
      do j = 1, GAUSS_TIME
        n = n + 1
        s(n) = (i - 1 + x(j)) / np
        w(n) = wx(j) / np
        ! Interior nodes only: the acceleration may jump at s = 0 and s = 1.
        call this%eval(ta + s(n) * duration, p, pd, a(n))
      end do
    end do
  end subroutine time_nodes

  !> |G(nu)|^2, G(nu) = sum w a exp(-2 pi i nu s).
  pure real(wp) function spectrum2(s, w, a, nu)
    real(wp), intent(in) :: s(:), w(:), a(:), nu
    real(wp) :: re, im, ph
    integer :: i
    re = 0.0_wp
    im = 0.0_wp
    do i = 1, size(s)
      ph = 2 * PI * nu * s(i)
      re = re + w(i) * a(i) * cos(ph)
      im = im - w(i) * a(i) * sin(ph)
    end do
    spectrum2 = re**2 + im**2
  end function spectrum2

  !> 2 int_lo^hi |G(nu)|^2 dnu by Gauss-Legendre (xf, wf on [0, 1]); hi - lo <= 1.
  pure real(wp) function band_integral(s, w, a, lo, hi, xf, wf) result(r)
    real(wp), intent(in) :: s(:), w(:), a(:), lo, hi, xf(:), wf(:)
    integer :: i
    r = 0.0_wp
    do i = 1, size(xf)
      r = r + wf(i) * spectrum2(s, w, a, lo + (hi - lo) * xf(i))
    end do
    r = 2 * (hi - lo) * r
  end function band_integral

  !> n-point Gauss-Legendre nodes x (ascending) and weights w on [0, 1] (Newton on the
  !> Legendre polynomial from the usual cosine guesses).
  pure subroutine gauss_legendre(n, x, w)
    integer, intent(in) :: n
    real(wp), intent(out) :: x(n), w(n)
    real(wp) :: z, z1, p0, dp
    integer :: i, it
    do i = 1, (n + 1) / 2
      z = cos(PI * (i - 0.25_wp) / (n + 0.5_wp))
      do it = 1, 100
        call legendre(n, z, p0, dp)
        z1 = z
        z = z1 - p0 / dp
        if (abs(z - z1) <= 1.0e-15_wp) exit
      end do
      ! The derivative at the converged root, for the weight.
      call legendre(n, z, p0, dp)
      x(i) = 0.5_wp * (1 - z)
      x(n + 1 - i) = 0.5_wp * (1 + z)
      w(i) = 1 / ((1 - z**2) * dp**2)
      w(n + 1 - i) = w(i)
    end do
  end subroutine gauss_legendre

  !> The Legendre polynomial P_n and its derivative at z, by the three-term recurrence.
  pure subroutine legendre(n, z, p, dp)
    integer, intent(in) :: n
    real(wp), intent(in) :: z
    real(wp), intent(out) :: p, dp
    real(wp) :: p1, p2
    integer :: j
    p = 1.0_wp
    p1 = 0.0_wp
    do j = 1, n
      p2 = p1
      p1 = p
      p = ((2 * j - 1) * z * p1 - (j - 1) * p2) / j
    end do
    dp = n * (z * p - p1) / (z**2 - 1)
  end subroutine legendre
end submodule motion_law_bandwidth
