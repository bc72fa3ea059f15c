!> Prescribed time laws for driven modes (joint angles): rest-to-rest cubic, quintic and
!> cycloidal laws from `start` to `end` over [t0, t0 + duration], held before and after,
!> constants, and the laws of running machines: a constant-velocity `ramp`, a `harmonic`
!> oscillation, the smooth `spin_up` of Kane et al., a `table` (not-a-knot cubic spline) and
!> the `sum` of other laws. Laws whose acceleration may jump list the times in `breakpoints`,
!> where the integrator restarts. `bandwidth_hz` (submodule motion_law_bandwidth) measures how
!> far up in frequency a law excites the structure, to choose the number of modes.
module motion_law
  use core_kinds, only: wp
  use core_strings, only: int_str, real_str
  implicit none
  private
  public :: law_t, motion_t, law_from_name, motion_sum, motion_table, table_problem
  public :: LAW_CONSTANT, LAW_CUBIC, LAW_QUINTIC, LAW_CYCLOIDAL, LAW_RAMP, LAW_HARMONIC, &
    LAW_SPIN_UP, LAW_SUM, LAW_TABLE
  public :: BANDWIDTH_MAX_CYCLES, BANDWIDTH_UNBOUNDED

  integer, parameter :: LAW_CONSTANT = 0
  integer, parameter :: LAW_CUBIC = 1
  integer, parameter :: LAW_QUINTIC = 2
  integer, parameter :: LAW_CYCLOIDAL = 3
  integer, parameter :: LAW_RAMP = 4
  integer, parameter :: LAW_HARMONIC = 5
  integer, parameter :: LAW_SPIN_UP = 6
  integer, parameter :: LAW_SUM = 7
  integer, parameter :: LAW_TABLE = 8

  real(wp), parameter :: PI = 3.14159265358979323846_wp

  !> bandwidth_hz searches up to BANDWIDTH_MAX_CYCLES / duration and returns that value when
  !> the fraction is not reached below it (or fraction >= 1). A law with acceleration jumps
  !> (cubic) leaves about 3.6 / (nu total) of its energy above nu cycles per duration, so
  !> the cap is reached for fractions above about 0.9997; smooth laws need far less.
  real(wp), parameter :: BANDWIDTH_MAX_CYCLES = 1000.0_wp
  !> bandwidth_hz of a law whose acceleration has no finite bandwidth (the impulse of a
  !> `ramp`'s velocity step): callers that need a bandwidth must refuse such a motion.
  real(wp), parameter :: BANDWIDTH_UNBOUNDED = -1.0_wp

  !> One elementary law (any but `sum`); the variables a law does not use are ignored.
  type :: law_t
    integer :: law = LAW_CONSTANT
    real(wp) :: start = 0.0_wp      !< value before t0 (rad or m)
    real(wp) :: end = 0.0_wp        !< value after t0 + duration (rest-to-rest laws)
    real(wp) :: t0 = 0.0_wp         !< start time [s]
    real(wp) :: duration = 1.0_wp   !< motion time [s] (rest-to-rest, spin_up), > 0
    real(wp) :: rate = 0.0_wp       !< final rate (ramp, spin_up) [rad/s or m/s]
    real(wp) :: amplitude = 0.0_wp  !< harmonic
    real(wp) :: frequency = 1.0_wp  !< harmonic [Hz], > 0
    real(wp) :: phase = 0.0_wp      !< harmonic [rad]
    !> table: knots (strictly increasing), values and the spline's second derivatives there
    real(wp), allocatable :: knots(:), values(:), curvature(:)
  contains
    procedure :: eval => law_eval
    procedure :: breakpoints => law_breakpoints
    procedure :: bandwidth_hz => law_bandwidth_hz
    procedure :: band_energy => law_band_energy
  end type law_t

  !> A named motion: one law, or with law = LAW_SUM the sum of `terms` (flattened: a term is
  !> never a sum, see motion_sum).
  type, extends(law_t) :: motion_t
    character(len=:), allocatable :: label
    type(law_t), allocatable :: terms(:)
  contains
    procedure :: eval => motion_eval
    procedure :: breakpoints => motion_breakpoints
    procedure :: bandwidth_hz => motion_bandwidth_hz
  end type motion_t

  interface
    !> Frequency F [Hz] below which `fraction` (e.g. 0.99) of the energy of the acceleration
    !> lies. Laws with a finite span (rest-to-rest, spin_up over [t0, t0 + T], table over its
    !> times) integrate the acceleration spectrum over that span; a harmonic gives its
    !> frequency; a ramp gives BANDWIDTH_UNBOUNDED. 0 for a law without acceleration.
    pure module real(wp) function law_bandwidth_hz(this, fraction) result(f_hz)
      class(law_t), intent(in) :: this
      real(wp), intent(in) :: fraction
    end function law_bandwidth_hz
    !> E(F) = 2 int_0^F |A(f)|^2 df [units^2 / s^3], the acceleration energy below F [Hz] of
    !> a law with a finite span (0 for the others); tends to int a(t)^2 dt as F grows.
    pure module real(wp) function law_band_energy(this, f_hz) result(e)
      class(law_t), intent(in) :: this
      real(wp), intent(in) :: f_hz
    end function law_band_energy
  end interface

contains

  !> Law code for a name; -1 if unknown.
  pure integer function law_from_name(name)
    character(len=*), intent(in) :: name
    select case (name)
    case ('constant'); law_from_name = LAW_CONSTANT
    case ('cubic'); law_from_name = LAW_CUBIC
    case ('quintic'); law_from_name = LAW_QUINTIC
    case ('cycloidal'); law_from_name = LAW_CYCLOIDAL
    case ('ramp'); law_from_name = LAW_RAMP
    case ('harmonic'); law_from_name = LAW_HARMONIC
    case ('spin_up'); law_from_name = LAW_SPIN_UP
    case ('sum'); law_from_name = LAW_SUM
    case ('table'); law_from_name = LAW_TABLE
    case default; law_from_name = -1
    end select
  end function law_from_name

  !> The sum of `terms` (sums among them are expanded into their own terms).
  pure function motion_sum(label, terms) result(m)
    character(len=*), intent(in) :: label
    type(motion_t), intent(in) :: terms(:)
    type(motion_t) :: m
    integer :: i
    m%label = label
    m%law = LAW_SUM
    allocate(m%terms(0))
    do i = 1, size(terms)
      if (terms(i)%law == LAW_SUM) then
        m%terms = [m%terms, terms(i)%terms]
      else
        m%terms = [m%terms, terms(i)%law_t]
      end if
    end do
  end function motion_sum

  !> Why `times`, `values` cannot make a table ('' if they can): at least 2 points, as many
  !> values as times, times strictly increasing.
  pure function table_problem(times, values) result(msg)
    real(wp), intent(in) :: times(:), values(:)
    character(len=:), allocatable :: msg
    integer :: k
    msg = ''
    if (size(times) /= size(values)) then
      msg = int_str(size(times)) // ' times but ' // int_str(size(values)) // &
        ' values (give one value per time)'
    else if (size(times) < 2) then
      msg = 'a table needs at least 2 points'
    else
      do k = 2, size(times)
        if (.not. times(k) > times(k - 1)) then
          msg = 'times must be strictly increasing: time ' // int_str(k) // ' (' // &
            real_str(times(k)) // ') is not after the one before'
          return
        end if
      end do
    end if
  end function table_problem

  !> The not-a-knot cubic spline through (times, values), held outside [times(1), times(n)].
  !> Not-a-knot (third derivative continuous at the second and last-but-one knots) keeps the
  !> spline C2 and reproduces cubic polynomials exactly; 3 points give the parabola through
  !> them, 2 the line. Needs table_problem(times, values) == ''.
  pure function motion_table(label, times, values) result(m)
    character(len=*), intent(in) :: label
    real(wp), intent(in) :: times(:), values(:)
    type(motion_t) :: m
    m%label = label
    m%law = LAW_TABLE
    ! allocate(source=): gfortran's -Wuninitialized misreads realloc on a function result.
    allocate(m%knots, source=times)
    allocate(m%values, source=values)
    allocate(m%curvature, source=spline_curvature(times, values))
  end function motion_table

  !> Second derivatives at the knots of the not-a-knot spline. With M1 and Mn eliminated by
  !> the not-a-knot rows, the system in M2 .. M(n-1) is tridiagonal and strictly diagonally
  !> dominant, so elimination without pivoting is stable.
  pure function spline_curvature(x, y) result(mm)
    real(wp), intent(in) :: x(:), y(:)
    real(wp) :: mm(size(x))
    real(wp), allocatable :: h(:), d(:), lo(:), di(:), up(:), r(:)
    integer :: n, i, k
    n = size(x)
    mm = 0.0_wp
    if (n < 3) return
    h = x(2:n) - x(1:n - 1)
    d = (y(2:n) - y(1:n - 1)) / h
    if (n == 3) then
      mm = 2 * (d(2) - d(1)) / (h(1) + h(2))
      return
    end if
    k = n - 2
    allocate(lo(k), di(k), up(k), r(k))
    do i = 1, k
      lo(i) = h(i)
      di(i) = 2 * (h(i) + h(i + 1))
      up(i) = h(i + 1)
      r(i) = 6 * (d(i + 1) - d(i))
    end do
    ! M1 = ((h1 + h2) M2 - h1 M3) / h2 into row 1; Mn likewise into row k.
    di(1) = (h(1) + h(2)) * (h(1) + 2 * h(2)) / h(2)
    up(1) = (h(2)**2 - h(1)**2) / h(2)
    di(k) = (h(n - 1) + h(n - 2)) * (h(n - 1) + 2 * h(n - 2)) / h(n - 2)
    lo(k) = (h(n - 2)**2 - h(n - 1)**2) / h(n - 2)
    do i = 2, k
      di(i) = di(i) - lo(i) / di(i - 1) * up(i - 1)
      r(i) = r(i) - lo(i) / di(i - 1) * r(i - 1)
    end do
    mm(k + 1) = r(k) / di(k)
    do i = k - 1, 1, -1
      mm(i + 1) = (r(i) - up(i) * mm(i + 2)) / di(i)
    end do
    mm(1) = ((h(1) + h(2)) * mm(2) - h(1) * mm(3)) / h(2)
    mm(n) = ((h(n - 1) + h(n - 2)) * mm(n - 1) - h(n - 1) * mm(n - 2)) / h(n - 2)
  end function spline_curvature

  !> Value p, rate pd and acceleration pdd at time t.
  pure subroutine motion_eval(this, t, p, pd, pdd)
    class(motion_t), intent(in) :: this
    real(wp), intent(in) :: t
    real(wp), intent(out) :: p, pd, pdd
    real(wp) :: q, qd, qdd
    integer :: i
    if (this%law /= LAW_SUM) then
      call this%law_t%eval(t, p, pd, pdd)
      return
    end if
    p = 0.0_wp; pd = 0.0_wp; pdd = 0.0_wp
    do i = 1, size(this%terms)
      call this%terms(i)%eval(t, q, qd, qdd)
      p = p + q; pd = pd + qd; pdd = pdd + qdd
    end do
  end subroutine motion_eval

  !> Value p, rate pd and acceleration pdd of one law at time t. Right-continuous at every
  !> breakpoint: at t0 the motion has started, at its end it is held.
  pure subroutine law_eval(this, t, p, pd, pdd)
    class(law_t), intent(in) :: this
    real(wp), intent(in) :: t
    real(wp), intent(out) :: p, pd, pdd
    real(wp) :: s, f, f1, f2, span, tau, w, om
    p = this%start; pd = 0.0_wp; pdd = 0.0_wp
    select case (this%law)
    case (LAW_CONSTANT, LAW_SUM)
      return
    case (LAW_TABLE)
      call table_eval(this, t, p, pd, pdd)
      return
    end select
    tau = t - this%t0
    if (tau < 0) return
    select case (this%law)
    case (LAW_RAMP)
      p = this%start + this%rate * tau
      pd = this%rate
      return
    case (LAW_HARMONIC)
      om = 2 * PI * this%frequency
      w = om * tau + this%phase
      p = this%start + this%amplitude * (sin(w) - sin(this%phase))
      pd = this%amplitude * om * cos(w)
      pdd = -this%amplitude * om**2 * sin(w)
      return
    case (LAW_SPIN_UP)
      ! theta = (w/T) (tau^2/2 + (T/(2 pi))^2 (cos(2 pi tau/T) - 1)), then w (tau - T/2):
      ! rate and acceleration reach w and 0 at tau = T, so both are continuous there.
      if (tau >= this%duration) then
        p = this%start + this%rate * (tau - this%duration / 2)
        pd = this%rate
        return
      end if
      s = 2 * PI * tau / this%duration
      w = this%rate / this%duration
      p = this%start + w * (tau**2 / 2 + (this%duration / (2 * PI))**2 * (cos(s) - 1))
      pd = w * (tau - this%duration / (2 * PI) * sin(s))
      pdd = w * (1 - cos(s))
      return
    end select
    ! Rest-to-rest laws: the cubic one's acceleration jumps at both ends.
    s = tau / this%duration
    if (s >= 1.0_wp) then
      p = this%end
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
  end subroutine law_eval

  !> The spline of a table, held at its end values outside [knots(1), knots(n)).
  pure subroutine table_eval(this, t, p, pd, pdd)
    class(law_t), intent(in) :: this
    real(wp), intent(in) :: t
    real(wp), intent(out) :: p, pd, pdd
    real(wp) :: h, a, b
    integer :: n, lo, hi, mid
    n = size(this%knots)
    pd = 0.0_wp; pdd = 0.0_wp
    if (t < this%knots(1)) then
      p = this%values(1)
      return
    else if (t >= this%knots(n)) then
      p = this%values(n)
      return
    end if
    lo = 1
    hi = n
    do while (hi - lo > 1)
      mid = (lo + hi) / 2
      if (t >= this%knots(mid)) then
        lo = mid
      else
        hi = mid
      end if
    end do
    associate (y => this%values, mm => this%curvature)
      h = this%knots(hi) - this%knots(lo)
      a = (this%knots(hi) - t) / h
      b = 1 - a
      p = a * y(lo) + b * y(hi) + ((a**3 - a) * mm(lo) + (b**3 - b) * mm(hi)) * h**2 / 6
      pd = (y(hi) - y(lo)) / h + ((1 - 3 * a**2) * mm(lo) + (3 * b**2 - 1) * mm(hi)) * h / 6
      pdd = a * mm(lo) + b * mm(hi)
    end associate
  end subroutine table_eval

  !> Times where the acceleration may jump: the start and end of rest-to-rest laws, of the
  !> spin-up (its acceleration is continuous there; the restarts only help high orders) and
  !> of a table, the start of a ramp or harmonic.
  pure function law_breakpoints(this) result(tb)
    class(law_t), intent(in) :: this
    real(wp), allocatable :: tb(:)
    select case (this%law)
    case (LAW_CUBIC, LAW_QUINTIC, LAW_CYCLOIDAL, LAW_SPIN_UP)
      tb = [this%t0, this%t0 + this%duration]
    case (LAW_RAMP, LAW_HARMONIC)
      tb = [this%t0]
    case (LAW_TABLE)
      tb = [this%knots(1), this%knots(size(this%knots))]
    case default
      allocate(tb(0))
    end select
  end function law_breakpoints

  !> A sum's breakpoints are those of its terms (possibly repeated).
  pure function motion_breakpoints(this) result(tb)
    class(motion_t), intent(in) :: this
    real(wp), allocatable :: tb(:)
    integer :: i
    if (this%law /= LAW_SUM) then
      tb = this%law_t%breakpoints()
      return
    end if
    allocate(tb(0))
    do i = 1, size(this%terms)
      tb = [tb, this%terms(i)%breakpoints()]
    end do
  end function motion_breakpoints

  !> A sum's bandwidth is the largest of its terms' (BANDWIDTH_UNBOUNDED if one is): the
  !> spectrum of a sum lies within the union of its terms' spectra.
  pure real(wp) function motion_bandwidth_hz(this, fraction) result(f_hz)
    class(motion_t), intent(in) :: this
    real(wp), intent(in) :: fraction
    real(wp) :: f
    integer :: i
    if (this%law /= LAW_SUM) then
      f_hz = this%law_t%bandwidth_hz(fraction)
      return
    end if
    f_hz = 0.0_wp
    do i = 1, size(this%terms)
      f = this%terms(i)%bandwidth_hz(fraction)
      if (f == BANDWIDTH_UNBOUNDED) then
        f_hz = BANDWIDTH_UNBOUNDED
        return
      end if
      f_hz = max(f_hz, f)
    end do
  end function motion_bandwidth_hz
end module motion_law
