!> Prescribed time laws for driven modes (joint angles): rest-to-rest cubic, quintic and
!> cycloidal laws from `start` to `end` over [t0, t0 + duration], held before and after, and
!> constants. The cubic law has acceleration jumps at both ends: `breakpoints` tells the
!> integrator where to restart. `bandwidth_hz` measures how far up in frequency a law excites
!> the structure (the energy spectrum of its acceleration), to choose the number of modes.
module motion_law
  use core_kinds, only: wp
  implicit none
  private
  public :: motion_t, LAW_CONSTANT, LAW_CUBIC, LAW_QUINTIC, LAW_CYCLOIDAL, law_from_name
  public :: BANDWIDTH_MAX_CYCLES

  integer, parameter :: LAW_CONSTANT = 0
  integer, parameter :: LAW_CUBIC = 1
  integer, parameter :: LAW_QUINTIC = 2
  integer, parameter :: LAW_CYCLOIDAL = 3

  real(wp), parameter :: PI = 3.14159265358979323846_wp

  !> bandwidth_hz searches up to BANDWIDTH_MAX_CYCLES / duration and returns that value when
  !> the fraction is not reached below it (or fraction >= 1). A law with acceleration jumps
  !> (cubic) leaves about 3.6 / (nu total) of its energy above nu cycles per duration, so
  !> the cap is reached for fractions above about 0.9997; smooth laws need far less.
  real(wp), parameter :: BANDWIDTH_MAX_CYCLES = 1000.0_wp
  !> Gauss-Legendre points per time panel; a panel spans at most two periods of the highest
  !> frequency in use, which these integrate to about 1e-10.
  integer, parameter :: GAUSS_TIME = 16
  !> Gauss-Legendre points per unit of nu = f duration: |A|^2 varies on that scale (the two
  !> ends of the motion interfere with period 1 in nu).
  integer, parameter :: GAUSS_FREQ = 12

  type :: motion_t
    character(len=:), allocatable :: label
    integer :: law = LAW_CONSTANT
    real(wp) :: start = 0.0_wp      !< value before t0 (rad or m)
    real(wp) :: end = 0.0_wp        !< value after t0 + duration
    real(wp) :: t0 = 0.0_wp         !< start time [s]
    real(wp) :: duration = 1.0_wp   !< motion time [s], > 0 unless constant
  contains
    procedure :: eval => motion_eval
    procedure :: breakpoints => motion_breakpoints
    procedure :: bandwidth_hz => motion_bandwidth_hz
    procedure :: band_energy => motion_band_energy
  end type motion_t

contains

  !> Law code for a name; -1 if unknown.
  pure integer function law_from_name(name)
    character(len=*), intent(in) :: name
    select case (name)
    case ('constant'); law_from_name = LAW_CONSTANT
    case ('cubic'); law_from_name = LAW_CUBIC
    case ('quintic'); law_from_name = LAW_QUINTIC
    case ('cycloidal'); law_from_name = LAW_CYCLOIDAL
    case default; law_from_name = -1
    end select
  end function law_from_name

  !> Value p, rate pd and acceleration pdd at time t.
  pure subroutine motion_eval(this, t, p, pd, pdd)
    class(motion_t), intent(in) :: this
    real(wp), intent(in) :: t
    real(wp), intent(out) :: p, pd, pdd
    real(wp) :: s, f, f1, f2, span
    if (this%law == LAW_CONSTANT) then
      p = this%start; pd = 0.0_wp; pdd = 0.0_wp
      return
    end if
    ! Right-continuous at both ends: at t0 the motion has started (its acceleration jumps
    ! there), at t0 + duration it is held. Integrators start segments at breakpoints.
    s = (t - this%t0) / this%duration
    if (s < 0.0_wp) then
      p = this%start; pd = 0.0_wp; pdd = 0.0_wp
      return
    else if (s >= 1.0_wp) then
      p = this%end; pd = 0.0_wp; pdd = 0.0_wp
      return
    end if
    select case (this%law)
    case (LAW_CUBIC)
      f = 3 * s**2 - 2 * s**3; f1 = 6 * s - 6 * s**2; f2 = 6 - 12 * s
    case (LAW_QUINTIC)
      f = 10 * s**3 - 15 * s**4 + 6 * s**5
      f1 = 30 * s**2 - 60 * s**3 + 30 * s**4
      f2 = 60 * s - 180 * s**2 + 120 * s**3
    case default
      f = s - sin(2 * PI * s) / (2 * PI); f1 = 1 - cos(2 * PI * s); f2 = 2 * PI * sin(2 * PI * s)
    end select
    span = this%end - this%start
    p = this%start + span * f
    pd = span * f1 / this%duration
    pdd = span * f2 / this%duration**2
  end subroutine motion_eval

  !> Times where the acceleration may jump (start and end of the motion).
  pure function motion_breakpoints(this) result(tb)
    class(motion_t), intent(in) :: this
    real(wp), allocatable :: tb(:)
    if (this%law == LAW_CONSTANT) then
      allocate(tb(0))
    else
      tb = [this%t0, this%t0 + this%duration]
    end if
  end function motion_breakpoints

  !> Frequency F [Hz] below which `fraction` (e.g. 0.99) of the energy of the acceleration
  !> signal lies:
  !>   E(F) = 2 int_0^F |A(f)|^2 df >= fraction int a(t)^2 dt,
  !>   A(f) = int a(t) exp(-2 pi i f t) dt over [t0, t0 + duration] (the law is at rest
  !> outside). 0 for a law without acceleration (constant, or end = start); at most
  !> BANDWIDTH_MAX_CYCLES / duration. F scales as 1 / duration and does not depend on t0 or
  !> the span. The cost grows as F^2: about a millisecond for 0.99 and a cubic law.
  pure real(wp) function motion_bandwidth_hz(this, fraction) result(f_hz)
    class(motion_t), intent(in) :: this
    real(wp), intent(in) :: fraction
    real(wp) :: xf(GAUSS_FREQ), wf(GAUSS_FREQ), total, target, e, piece, lo, hi, x, xn, h, dh
    real(wp), allocatable :: s(:), w(:), a(:)
    integer :: k, it
    f_hz = 0.0_wp
    if (this%law == LAW_CONSTANT .or. this%end == this%start .or. &
      .not. this%duration > 0 .or. .not. fraction > 0) return
    f_hz = BANDWIDTH_MAX_CYCLES / this%duration
    if (fraction >= 1) return
    ! Work in nu = f duration and s = (t - t0) / duration: A(f) = duration G(nu) with
    ! G(nu) = int_0^1 a exp(-2 pi i nu s) ds, and the condition reads
    ! 2 int_0^nu |G|^2 >= fraction int_0^1 a^2 ds.
    call gauss_legendre(GAUSS_FREQ, xf, wf)
    call time_nodes(this, 1.0_wp, s, w, a)
    total = sum(w * a**2)
    target = fraction * total
    e = 0.0_wp
    do k = 0, nint(BANDWIDTH_MAX_CYCLES) - 1
      call time_nodes(this, real(k + 1, wp), s, w, a)
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
        f_hz = x / this%duration
        return
      end if
      e = e + piece
    end do
  end function motion_bandwidth_hz

  !> E(F) = 2 int_0^F |A(f)|^2 df [units^2 / s^3], the acceleration energy below F [Hz]; tends
  !> to int a(t)^2 dt (Parseval) as F grows.
  pure real(wp) function motion_band_energy(this, f_hz) result(e)
    class(motion_t), intent(in) :: this
    real(wp), intent(in) :: f_hz
    real(wp) :: xf(GAUSS_FREQ), wf(GAUSS_FREQ), nu, lo
    real(wp), allocatable :: s(:), w(:), a(:)
    integer :: k
    e = 0.0_wp
    if (this%law == LAW_CONSTANT .or. .not. this%duration > 0 .or. .not. f_hz > 0) return
    call gauss_legendre(GAUSS_FREQ, xf, wf)
    nu = f_hz * this%duration
    do k = 0, ceiling(nu) - 1
      lo = k
      call time_nodes(this, min(lo + 1, nu), s, w, a)
      e = e + band_integral(s, w, a, lo, min(lo + 1, nu), xf, wf)
    end do
    ! E(F) = 2 int_0^F duration^2 |G(f duration)|^2 df = duration 2 int_0^nu |G|^2 dnu
    e = e * this%duration
  end function motion_band_energy

  !> Gauss-Legendre nodes s and weights w on [0, 1] fine enough for exp(-2 pi i nu s) up to
  !> nu_max, and the acceleration a at the nodes.
  pure subroutine time_nodes(this, nu_max, s, w, a)
    class(motion_t), intent(in) :: this
    real(wp), intent(in) :: nu_max
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
        call this%eval(this%t0 + s(n) * this%duration, p, pd, a(n))
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
    real(wp) :: z, z1, p0, p1, p2, dp
    integer :: i, j, it
    do i = 1, (n + 1) / 2
      z = cos(PI * (i - 0.25_wp) / (n + 0.5_wp))
      do it = 1, 100
        p0 = 1.0_wp
        p1 = 0.0_wp
        do j = 1, n
          p2 = p1
          p1 = p0
          p0 = ((2 * j - 1) * z * p1 - (j - 1) * p2) / j
        end do
        dp = n * (z * p0 - p1) / (z**2 - 1)
        z1 = z
        z = z1 - p0 / dp
        if (abs(z - z1) <= 1.0e-15_wp) exit
      end do
      ! Recompute the derivative at the converged root for the weight.
      p0 = 1.0_wp
      p1 = 0.0_wp
      do j = 1, n
        p2 = p1
        p1 = p0
        p0 = ((2 * j - 1) * z * p1 - (j - 1) * p2) / j
      end do
      dp = n * (z * p0 - p1) / (z**2 - 1)
      x(i) = 0.5_wp * (1 - z)
      x(n + 1 - i) = 0.5_wp * (1 + z)
      w(i) = 1 / ((1 - z**2) * dp**2)
      w(n + 1 - i) = w(i)
    end do
  end subroutine gauss_legendre
end module motion_law
