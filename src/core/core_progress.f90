!> Progress lines on stderr for long runs, e.g.
!>     flexmor: dynamic  t = 0.3120 of 0.7000 s (44.6 %), 12345 steps, 4.1 s elapsed, ETA 5.2 s
!>     flexmor: static   load step 7 of 20 (load factor 0.3500), 3.2 s elapsed, ETA 6.0 s
!> one line per report, the first after `interval` seconds of wall time (short runs stay silent)
!> and then one every `interval`. The run owns the object and hands it to the solvers (through
!> integrator_options_t%progress, or an argument of static_solve); they poll it where they take
!> steps or evaluate the right-hand side: `due` reads the clock only (some 20 ns), everything
!> else happens once per line.
module core_progress
  use, intrinsic :: iso_fortran_env, only: error_unit
  use core_kinds, only: wp, i8
  use core_strings, only: int_str
  implicit none
  private
  public :: progress_t, eta_text, crawl_text

  type :: progress_t
    !> Off (the default): `due` is always false and nothing is printed.
    logical :: enabled = .false.
    real(wp) :: interval = 2.0_wp        !< wall time [s] before the first line and between lines
    integer :: unit = error_unit
    !> Steps of the integrations already finished (the segments of a reduced run); the solvers
    !> add their own count of the current one.
    integer(i8) :: steps_done = 0
    !> Basis updates of an adaptive reduced run so far; < 0: not shown.
    integer :: n_updates = -1
    integer :: n_lines = 0               !< lines printed since `start`
    character(len=8), private :: kind = ''
    integer(i8), private :: rate = 1, c_start = 0, c_next = huge(1_i8)
    real(wp), private :: t_begin = 0, t_end = 0, t_shown = -huge(1.0_wp)
    !> Elapsed wall time and fraction done at the previous line (or the start): the ETA goes by
    !> the rate since then, as runs slow down or speed up (the adaptive steps follow the motion).
    real(wp), private :: elapsed_prev = 0, frac_prev = 0
    !> Steps at the previous line: their mean size since then shows a run that crawls.
    integer(i8), private :: steps_prev = 0
  contains
    procedure :: start => progress_start
    procedure :: due => progress_due
    procedure :: report_time => progress_report_time
    procedure :: report_load => progress_report_load
    procedure :: skip_pause => progress_skip_pause
  end type progress_t

contains

  !> Begin a phase: kind 'dynamic' or 'reduced' integrates from t_begin to t_end, 'static'
  !> (t_begin, t_end unused) steps the load. Counters and the clock start again.
  subroutine progress_start(this, kind, t_begin, t_end)
    class(progress_t), intent(inout) :: this
    character(len=*), intent(in) :: kind
    real(wp), intent(in) :: t_begin, t_end
    this%kind = kind
    this%t_begin = t_begin
    this%t_end = t_end
    this%t_shown = -huge(1.0_wp)
    this%steps_done = 0
    this%n_updates = -1
    this%n_lines = 0
    this%elapsed_prev = 0
    this%frac_prev = 0
    this%steps_prev = 0
    call system_clock(this%c_start, this%rate)
    this%c_next = this%c_start + ticks(this)
  end subroutine progress_start

  !> Whether a line is due: cheap enough to call at every step or right-hand side evaluation.
  logical function progress_due(this) result(due)
    class(progress_t), intent(in) :: this
    integer(i8) :: c
    due = .false.
    if (.not. this%enabled) return
    call system_clock(c)
    due = c >= this%c_next
  end function progress_due

  !> The time since the previous line was one-time work (a reduced run's basis update: an
  !> eigensolution of the full model): the next line's rate starts here, at the time shown
  !> and the steps of the finished integrations, so that its ETA does not extrapolate the pause
  !> (a 0.35 s reduced run was promised more than 10,000 h after its first update).
  subroutine progress_skip_pause(this)
    class(progress_t), intent(inout) :: this
    integer(i8) :: c
    if (.not. this%enabled) return
    call system_clock(c)
    this%elapsed_prev = real(c - this%c_start, wp) / this%rate
    if (this%t_end > this%t_begin) this%frac_prev = max(this%frac_prev, &
      (max(this%t_shown, this%t_begin) - this%t_begin) / (this%t_end - this%t_begin))
    this%steps_prev = this%steps_done
  end subroutine progress_skip_pause

  !> The line of an integration at time t after n_steps steps of the current integration.
  subroutine progress_report_time(this, t, n_steps)
    class(progress_t), intent(inout) :: this
    real(wp), intent(in) :: t
    integer(i8), intent(in) :: n_steps
    character(len=:), allocatable :: line
    real(wp) :: elapsed, frac, span
    integer(i8) :: steps
    integer :: d
    ! An evaluation of a step that gets rejected may lie ahead of a later one: never go back.
    this%t_shown = min(max(this%t_shown, t, this%t_begin), this%t_end)
    elapsed = next_line(this)
    frac = 1
    if (this%t_end > this%t_begin) frac = (this%t_shown - this%t_begin) / (this%t_end - this%t_begin)
    ! Four significant digits of t_end.
    d = 4
    if (abs(this%t_end) > 0) d = min(12, max(1, 3 - floor(log10(abs(this%t_end)))))
    line = 'flexmor: ' // this%kind // ' t = ' // time_str(this%t_shown, d) // ' of ' // &
      time_str(this%t_end, d) // ' s (' // fixed(100 * frac, 1) // ' %), ' // &
      count_str(this%steps_done + n_steps) // ' steps, '
    if (this%n_updates >= 0) line = line // int_str(this%n_updates) // ' basis updates, '
    steps = this%steps_done + n_steps
    span = this%t_end - this%t_begin
    line = line // duration(elapsed) // ' elapsed' // crawl_text(frac - this%frac_prev, &
      steps - this%steps_prev, span) // next_eta(this, elapsed, frac)
    this%steps_prev = steps
    write(this%unit, '(a)') line
    flush(this%unit)
  end subroutine progress_report_time

  !> The line of load step k of n (load factor lambda) under way.
  subroutine progress_report_load(this, k, n, lambda)
    class(progress_t), intent(inout) :: this
    integer, intent(in) :: k, n
    real(wp), intent(in) :: lambda
    real(wp) :: elapsed
    elapsed = next_line(this)
    write(this%unit, '(a)') 'flexmor: ' // this%kind // ' load step ' // &
      int_str(k) // ' of ' // int_str(n) // ' (load factor ' // &
      fixed(lambda, 4) // '), ' // duration(elapsed) // ' elapsed' // &
      next_eta(this, elapsed, real(k - 1, wp) / n)
    flush(this%unit)
  end subroutine progress_report_load

  ! ---- helpers ------------------------------------------------------------------------------

  integer(i8) function ticks(this)
    type(progress_t), intent(in) :: this
    ticks = max(1_i8, nint(this%interval * this%rate, i8))
  end function ticks

  !> Elapsed wall time [s]; schedules the next line.
  real(wp) function next_line(this) result(elapsed)
    type(progress_t), intent(inout) :: this
    integer(i8) :: c
    call system_clock(c)
    elapsed = real(c - this%c_start, wp) / this%rate
    this%c_next = c + ticks(this)
    this%n_lines = this%n_lines + 1
  end function next_line

  !> The ETA text of a line at (elapsed, frac); the line becomes the previous one.
  function next_eta(this, elapsed, frac) result(s)
    type(progress_t), intent(inout) :: this
    real(wp), intent(in) :: elapsed, frac
    character(len=:), allocatable :: s
    s = eta_text(elapsed, frac, this%elapsed_prev, this%frac_prev)
    this%elapsed_prev = elapsed
    this%frac_prev = frac
  end function next_eta

  !> ', ETA ...' at the rate since the previous line (elapsed_prev, frac_prev), not the
  !> average since the start: an adaptive run whose steps shrink a hundredfold half-way (a
  !> whipping arm) would otherwise be promised seconds for minutes. ', ETA unknown: ...' when
  !> frac has not moved (a load step longer than a line's interval); nothing before anything
  !> is done.
  pure function eta_text(elapsed, frac, elapsed_prev, frac_prev) result(s)
    real(wp), intent(in) :: elapsed, frac, elapsed_prev, frac_prev
    character(len=:), allocatable :: s
    s = ''
    if (frac <= 1.0e-6_wp .or. frac > 1) return
    if (frac <= frac_prev) then
      s = ', ETA unknown: no progress since the last line'
    else
      s = ', ETA ' // duration(max(0.0_wp, elapsed - elapsed_prev) * (1 - frac) / &
        (frac - frac_prev))
    end if
  end function eta_text

  !> ', steps of about h s' where the mean step since the previous line (d_frac of the span in
  !> d_steps steps, at least 1000) is below CRAWL of the span: at that size the run needs more steps than
  !> the integrators allow (10 million), which a user should see long before they run out (a
  !> mechanism at a dead point: the four-bar of input/four_bar.nml with the rocker pin moved
  !> so that the crank cannot turn took steps of 1e-11 s).
  pure function crawl_text(d_frac, d_steps, span) result(s)
    real(wp), intent(in) :: d_frac, span
    integer(i8), intent(in) :: d_steps
    character(len=:), allocatable :: s
    real(wp), parameter :: CRAWL = 1.0e-7_wp
    real(wp) :: h
    character(len=16) :: buf
    s = ''
    ! No progress at all: the ETA says so. A few small steps are no crawl (a run's first step
    ! is small, and a line may follow it at once).
    if (d_steps < 1000 .or. .not. span > 0 .or. .not. d_frac > 0) return
    h = d_frac * span / real(d_steps, wp)
    if (h >= CRAWL * span) return
    write(buf, '(es9.2)') h
    s = ', steps of about ' // trim(adjustl(buf)) // ' s (under 1e-7 of the run: too small ' // &
      'to finish; a singular configuration, or t_end too long?)'
  end function crawl_text

  !> Seconds below two minutes, then minutes, then hours; beyond 10,000 h only that.
  pure function duration(sec) result(s)
    real(wp), intent(in) :: sec
    character(len=:), allocatable :: s
    if (sec >= 3.6e7_wp) then
      s = 'more than 10000 h'
    else if (sec < 120) then
      s = fixed(sec, 1) // ' s'
    else if (sec < 7200) then
      s = fixed(sec / 60, 1) // ' min'
    else
      s = fixed(sec / 3600, 1) // ' h'
    end if
  end function duration

  !> v with d decimals and a leading zero (F0.d leaves it out for |v| < 1 on some compilers).
  pure function fixed(v, d) result(s)
    real(wp), intent(in) :: v
    integer, intent(in) :: d
    character(len=:), allocatable :: s
    character(len=40) :: buf
    character(len=16) :: fmt
    write(fmt, '(a,i0,a)') '(f0.', d, ')'
    write(buf, fmt) v
    s = trim(adjustl(buf))
    if (s(1:1) == '.') s = '0' // s
    if (len(s) > 1) then
      if (s(1:2) == '-.') s = '-0' // s(2:)
    end if
  end function fixed

  !> A time of the line: fixed with d decimals, or with an exponent from 1e7 s on (t_end =
  !> 1e30 printed 31 digits).
  pure function time_str(v, d) result(s)
    real(wp), intent(in) :: v
    integer, intent(in) :: d
    character(len=:), allocatable :: s
    character(len=24) :: buf
    if (abs(v) < 1.0e7_wp) then
      s = fixed(v, d)
    else
      write(buf, '(es11.4e3)') v
      s = trim(adjustl(buf))
    end if
  end function time_str

  function count_str(i) result(s)
    integer(i8), intent(in) :: i
    character(len=:), allocatable :: s
    s = int_str(int(min(i, int(huge(1), i8))))
  end function count_str
end module core_progress
