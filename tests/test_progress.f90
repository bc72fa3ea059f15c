!> The progress lines' ETA goes by the rate since the previous line (core_progress eta_text), and
!> a run whose steps have become too small to finish says so (crawl_text).
program test_progress
  use core_kinds, only: wp, i8
  use core_progress, only: progress_t, eta_text, crawl_text
  use testing, only: suite_t
  implicit none
  type(suite_t) :: t
  call t%init('progress ETA')
  call t%check(eta_text(4.0_wp, 0.5_wp, 2.0_wp, 0.25_wp) == ', ETA 4.0 s', &
    'a steady rate: the remaining half takes as long as the first ('// &
    eta_text(4.0_wp, 0.5_wp, 2.0_wp, 0.25_wp) // ')')
  ! The full two-link at 32 elements per link with 0.2 s turns: 88.5 % after 60 s, 88.9 % two
  ! seconds later (the average since the start promised 7.8 s; the run took 85 s).
  call t%check(eta_text(62.0_wp, 0.889_wp, 60.0_wp, 0.885_wp) == ', ETA 55.5 s', &
    'a run that has slowed down: the recent rate (' // &
    eta_text(62.0_wp, 0.889_wp, 60.0_wp, 0.885_wp) // ')')
  call t%check(eta_text(30.0_wp, 0.9_wp, 28.0_wp, 0.3_wp) == ', ETA 0.3 s', &
    'a run that has sped up: the recent rate (' // eta_text(30.0_wp, 0.9_wp, 28.0_wp, &
    0.3_wp) // ')')
  call t%check(eta_text(1.0e4_wp, 0.5_wp, 9.0e3_wp, 0.45_wp) == ', ETA 2.8 h', 'hours')
  call t%check(eta_text(6.0_wp, 0.4_wp, 4.0_wp, 0.4_wp) == &
    ', ETA unknown: no progress since the last line', 'no progress: said')
  call t%check(eta_text(2.0_wp, 0.0_wp, 0.0_wp, 0.0_wp) == '', 'nothing done: no ETA')
  ! 1e-9 of the run in 2 s: 2e9 s to go.
  call t%check(eta_text(4.0_wp, 0.5_wp + 1.0e-9_wp, 2.0_wp, 0.5_wp) == &
    ', ETA more than 10000 h', 'a crawl: no absurd number (' // eta_text(4.0_wp, &
    0.5_wp + 1.0e-9_wp, 2.0_wp, 0.5_wp) // ')')
  ! 1e-9 of a 0.1 s run in 1000 steps: 1e-13 s each, under 1e-7 of the run (1e-8 s).
  call t%check(index(crawl_text(1.0e-9_wp, 1000_i8, 0.1_wp), 'steps of about 1.00E-13 s') &
    > 0, 'tiny steps: said (' // crawl_text(1.0e-9_wp, 1000_i8, 0.1_wp) // ')')
  call t%check(crawl_text(1.0e-3_wp, 1000_i8, 0.1_wp) == '', 'steps of 1e-7 s: nothing')
  call t%check(crawl_text(0.0_wp, 1000_i8, 0.1_wp) == '', &
    'no progress at all: for the ETA to say')
  call t%check(crawl_text(1.0e-12_wp, 999_i8, 0.1_wp) == '', &
    'a few small steps (the first of a run): nothing')
  call test_skip_pause(t)
  call t%finish()

contains

  !> A line after a pause of 0.2 s (a basis update) that moved the run by 1e-9: without
  !> skip_pause its ETA extrapolates the pause (more than 10000 h), with it the rate starts
  !> after the pause (0.5e9 times the microseconds between the two calls: far below it).
  subroutine test_skip_pause(t)
    type(suite_t), intent(inout) :: t
    character(len=200) :: lines(2, 2)
    integer :: skip
    do skip = 1, 2
      block
        type(progress_t) :: p
        integer :: u
        open(newunit=u, status='scratch', action='readwrite')
        p%enabled = .true.
        p%interval = 0.0_wp
        p%unit = u
        call p%start('reduced', 0.0_wp, 1.0_wp)
        call p%report_time(0.5_wp, 100_i8)
        call pause(0.2_wp)
        p%steps_done = 100
        if (skip == 2) call p%skip_pause()
        call p%report_time(0.5_wp + 1.0e-9_wp, 1_i8)
        rewind(u)
        read(u, '(a)') lines(1, skip)
        read(u, '(a)') lines(2, skip)
        close(u)
      end block
    end do
    call t%check(index(lines(2, 1), 'more than 10000 h') > 0, 'without skip_pause: ' // &
      trim(lines(2, 1)))
    call t%check(index(lines(2, 2), 'more than 10000 h') == 0 .and. &
      index(lines(2, 2), 'ETA') > 0, 'with skip_pause: ' // trim(lines(2, 2)))
  end subroutine test_skip_pause

  !> Wait `sec` seconds of wall time.
  subroutine pause(sec)
    real(wp), intent(in) :: sec
    integer(i8) :: c0, c, rate
    call system_clock(c0, rate)
    do
      call system_clock(c)
      if (real(c - c0, wp) / rate >= sec) exit
    end do
  end subroutine pause
end program test_progress
