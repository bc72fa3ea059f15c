!> Minimal assertion module for flexmor's test programs (pFUnit is not available on Debian).
!> A test program creates a suite, makes checks and calls `finish`, which stops with a
!> non-zero code if any check failed; CTest reads that exit status.
module testing
  use core_kinds, only: wp
  implicit none
  private
  public :: suite_t

  type :: suite_t
    character(len=:), allocatable :: name
    integer :: n_pass = 0
    integer :: n_fail = 0
  contains
    procedure :: init => suite_init
    procedure :: check => suite_check
    procedure :: close => suite_close
    procedure :: close_array => suite_close_array
    procedure :: finish => suite_finish
  end type suite_t

contains

  subroutine suite_init(this, name)
    class(suite_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    this%name = name
    this%n_pass = 0
    this%n_fail = 0
    write(*, '(a)') '== ' // name
  end subroutine suite_init

  subroutine suite_check(this, condition, what)
    class(suite_t), intent(inout) :: this
    logical, intent(in) :: condition
    character(len=*), intent(in) :: what
    if (condition) then
      this%n_pass = this%n_pass + 1
      write(*, '(a)') '  ok    ' // what
    else
      this%n_fail = this%n_fail + 1
      write(*, '(a)') '  FAIL  ' // what
    end if
  end subroutine suite_check

  !> |actual - expected| <= atol + rtol |expected|
  subroutine suite_close(this, actual, expected, rtol, atol, what)
    class(suite_t), intent(inout) :: this
    real(wp), intent(in) :: actual, expected, rtol, atol
    character(len=*), intent(in) :: what
    character(len=160) :: line
    logical :: good
    good = abs(actual - expected) <= atol + rtol * abs(expected)
    good = good .and. actual == actual
    write(line, '(a,es16.8,a,es16.8,a,es9.2)') ' got ', actual, ' want ', expected, &
      ' diff ', abs(actual - expected)
    call this%check(good, what // trim(line))
  end subroutine suite_close

  subroutine suite_close_array(this, actual, expected, rtol, atol, what)
    class(suite_t), intent(inout) :: this
    real(wp), intent(in) :: actual(:), expected(:), rtol, atol
    character(len=*), intent(in) :: what
    character(len=120) :: line
    real(wp) :: worst
    integer :: i
    logical :: good
    if (size(actual) /= size(expected)) then
      call this%check(.false., what // ' (size mismatch)')
      return
    end if
    good = all(abs(actual - expected) <= atol + rtol * abs(expected))
    good = good .and. all(actual == actual)
    worst = 0
    do i = 1, size(actual)
      worst = max(worst, abs(actual(i) - expected(i)))
    end do
    write(line, '(a,es9.2)') ' max diff ', worst
    call this%check(good, what // trim(line))
  end subroutine suite_close_array

  subroutine suite_finish(this)
    class(suite_t), intent(inout) :: this
    write(*, '(a,i0,a,i0,a)') '== ' // this%name // ': ', this%n_pass, ' passed, ', &
      this%n_fail, ' failed'
    if (this%n_fail > 0) error stop 1
  end subroutine suite_finish
end module testing
