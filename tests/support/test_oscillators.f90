!> The undamped linear oscillator q'' = -omega^2 q shared by the integrator tests, with its
!> exact solution from q(0) = 1, v(0) = 0.
module test_oscillators
  use core_kinds, only: wp
  use integrators_system, only: ode2_system_t
  implicit none
  private
  public :: oscillator_t, oscillator_error

  real(wp), parameter :: pi = acos(-1.0_wp)

  !> q'' = -omega^2 q; record compares with the exact solution from q(0) = 1, v(0) = 0.
  type, extends(ode2_system_t) :: oscillator_t
    real(wp) :: omega = 2 * pi
    real(wp) :: max_error = 0       !< largest |q - q_exact| + |v - v_exact| / omega at outputs
    integer :: n_records = 0
    logical :: times_exact = .true.
    real(wp), allocatable :: t_expected(:)
  contains
    procedure :: accel => oscillator_accel
    procedure :: record => oscillator_record
    procedure :: jacobian => oscillator_jacobian
  end type oscillator_t

contains

  !> |q - cos(omega t)| + |v + omega sin(omega t)| / omega: the error against the exact
  !> solution from q(0) = 1, v(0) = 0.
  pure real(wp) function oscillator_error(omega, t, q, v)
    real(wp), intent(in) :: omega, t, q, v
    oscillator_error = abs(q - cos(omega * t)) + abs(v + omega * sin(omega * t)) / omega
  end function oscillator_error

  subroutine oscillator_accel(this, t, q, v, a, status)
    class(oscillator_t), intent(inout) :: this
    real(wp), intent(in) :: t, q(:), v(:)
    real(wp), intent(out) :: a(:)
    integer, intent(out) :: status
    a = -this%omega**2 * q
    status = 0
  end subroutine oscillator_accel

  subroutine oscillator_jacobian(this, t, q, v, dadq, dadv, status)
    class(oscillator_t), intent(inout) :: this
    real(wp), intent(in) :: t, q(:), v(:)
    real(wp), intent(out) :: dadq(:, :), dadv(:, :)
    integer, intent(out) :: status
    dadq = -this%omega**2
    dadv = 0
    status = 0
  end subroutine oscillator_jacobian

  subroutine oscillator_record(this, k, t, q, v, status)
    class(oscillator_t), intent(inout) :: this
    integer, intent(in) :: k
    real(wp), intent(in) :: t, q(:), v(:)
    integer, intent(out) :: status
    this%max_error = max(this%max_error, oscillator_error(this%omega, t, q(1), v(1)))
    this%n_records = this%n_records + 1
    if (allocated(this%t_expected)) then
      this%times_exact = this%times_exact .and. .not. abs(t - this%t_expected(k)) > 0
    end if
    status = 0
  end subroutine oscillator_record
end module test_oscillators
