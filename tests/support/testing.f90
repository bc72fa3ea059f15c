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
    procedure :: order => suite_order
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
    write(line, '(a,es16.8,a,es16.8,a,es9.2,a,es8.1,a)') ' got ', actual, ' want ', expected, &
      ' diff ', abs(actual - expected), ' (bound ', atol + rtol * abs(expected), ')'
    call this%check(good, what // trim(line))
  end subroutine suite_close

  subroutine suite_close_array(this, actual, expected, rtol, atol, what)
    class(suite_t), intent(inout) :: this
    real(wp), intent(in) :: actual(:), expected(:), rtol, atol
    character(len=*), intent(in) :: what
    character(len=120) :: line
    real(wp) :: worst, used
    integer :: i
    logical :: good
    if (size(actual) /= size(expected)) then
      call this%check(.false., what // ' (size mismatch)')
      return
    end if
    good = all(abs(actual - expected) <= atol + rtol * abs(expected))
    good = good .and. all(actual == actual)
    worst = 0
    used = 0   ! largest |diff| / bound: the margin is its inverse
    do i = 1, size(actual)
      worst = max(worst, abs(actual(i) - expected(i)))
      if (atol + rtol * abs(expected(i)) > 0) used = max(used, abs(actual(i) - expected(i)) / &
        (atol + rtol * abs(expected(i))))
    end do
    write(line, '(a,es9.2,a,es8.1,a)') ' max diff ', worst, ' (', used, ' of its bound)'
    call this%check(good, what // trim(line))
  end subroutine suite_close_array

  !> Observed convergence order log2(e(h) / e(h/2)) within 0.5 of `expected`: halfway to the
  !> neighbouring orders, so a method one order off fails whatever the higher-order terms.
  subroutine suite_order(this, e_coarse, e_fine, expected, what)
    class(suite_t), intent(inout) :: this
    real(wp), intent(in) :: e_coarse, e_fine   !< errors at step h and h / 2
    integer, intent(in) :: expected
    character(len=*), intent(in) :: what
    character(len=80) :: line
    real(wp) :: p
    p = -huge(1.0_wp)
    if (e_coarse > 0 .and. e_fine > 0) p = log(e_coarse / e_fine) / log(2.0_wp)
    write(line, '(a,f7.3,a,i0,a)') ' (observed order ', p, ', expected ', expected, ' +- 0.5)'
    call this%check(abs(p - expected) < 0.5_wp, what // trim(line))
  end subroutine suite_order

  subroutine suite_finish(this)
    class(suite_t), intent(inout) :: this
    write(*, '(a,i0,a,i0,a)') '== ' // this%name // ': ', this%n_pass, ' passed, ', &
      this%n_fail, ' failed'
    if (this%n_fail > 0) error stop 1
  end subroutine suite_finish
end module testing
