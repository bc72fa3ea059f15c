!> Prescribed time laws for driven modes (joint angles): rest-to-rest cubic, quintic and
!> cycloidal laws from `start` to `end` over [t0, t0 + duration], held before and after, and
!> constants. The cubic law has acceleration jumps at both ends: `breakpoints` tells the
!> integrator where to restart.
module motion_law
  use core_kinds, only: wp
  implicit none
  private
  public :: motion_t, LAW_CONSTANT, LAW_CUBIC, LAW_QUINTIC, LAW_CYCLOIDAL, law_from_name

  integer, parameter :: LAW_CONSTANT = 0
  integer, parameter :: LAW_CUBIC = 1
  integer, parameter :: LAW_QUINTIC = 2
  integer, parameter :: LAW_CYCLOIDAL = 3

  real(wp), parameter :: PI = 3.14159265358979323846_wp

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
end module motion_law
