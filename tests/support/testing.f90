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
    !> Worst achieved relative error per category of `expect`, for the summary.
    real(wp), allocatable :: worst(:)
  contains
    procedure :: init => suite_init
    procedure :: check => suite_check
    procedure :: close => suite_close
    procedure :: close_array => suite_close_array
    procedure :: order => suite_order
    procedure :: expect => suite_expect
    procedure :: print_worst => suite_print_worst
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

  !> A check on an achieved relative error err <= tol; records the worst per category cat.
  subroutine suite_expect(this, what, err, tol, cat)
    class(suite_t), intent(inout) :: this
    character(len=*), intent(in) :: what
    real(wp), intent(in) :: err, tol
    integer, intent(in) :: cat
    character(len=60) :: buf
    real(wp), allocatable :: grown(:)
    write(buf, '(a,es9.2,a,es8.1,a)') ': rel err ', err, ' (tol ', tol, ')'
    call this%check(err <= tol .and. err == err, what // trim(buf))
    if (.not. allocated(this%worst)) allocate(this%worst(0))
    if (size(this%worst) < cat) then
      allocate(grown(cat))
      grown = 0.0_wp
      grown(1:size(this%worst)) = this%worst
      call move_alloc(grown, this%worst)
    end if
    if (err == err) this%worst(cat) = max(this%worst(cat), err)
  end subroutine suite_expect

  !> The worst achieved relative error of every category, named.
  subroutine suite_print_worst(this, names)
    class(suite_t), intent(in) :: this
    character(len=*), intent(in) :: names(:)
    integer :: i
    write(*, '(a)') '-- worst achieved relative errors:'
    do i = 1, size(names)
      if (allocated(this%worst)) then
        if (i <= size(this%worst)) then
          write(*, '(4x,a,es10.2)') names(i), this%worst(i)
          cycle
        end if
      end if
      write(*, '(4x,a,a)') names(i), '  (no check)'
    end do
  end subroutine suite_print_worst

  subroutine suite_finish(this)
    class(suite_t), intent(inout) :: this
    write(*, '(a,i0,a,i0,a)') '== ' // this%name // ': ', this%n_pass, ' passed, ', &
      this%n_fail, ' failed'
    if (this%n_fail > 0) error stop 1
  end subroutine suite_finish
end module testing
