!> Prescribed time laws: rest-to-rest end values, rates and accelerations against central
!> differences, and the breakpoints the integrators restart at.
program test_motion
  use core_kinds, only: wp
  use motion_law, only: motion_t, LAW_CONSTANT, LAW_CUBIC, LAW_QUINTIC, LAW_CYCLOIDAL
  use testing, only: suite_t
  implicit none
  type(suite_t) :: suite
  character(len=9), parameter :: NAMES(3) = ['cubic    ', 'quintic  ', 'cycloidal']
  integer, parameter :: LAWS(3) = [LAW_CUBIC, LAW_QUINTIC, LAW_CYCLOIDAL]
  type(motion_t) :: m
  real(wp) :: p, pd, pdd, pp, pm, dum, pdp, pdm, t, h
  real(wp), allocatable :: tb(:)
  integer :: i, k

  call suite%init('motion laws')
  do i = 1, size(LAWS)
    m = motion_t(label='m', law=LAWS(i), start=0.3_wp, end=-1.2_wp, t0=0.1_wp, duration=0.4_wp)
    call m%eval(0.0_wp, p, pd, pdd)
    call suite%check(p == 0.3_wp .and. pd == 0 .and. pdd == 0, trim(NAMES(i)) // ': held before t0')
    call m%eval(0.9_wp, p, pd, pdd)
    call suite%check(p == -1.2_wp .and. pd == 0 .and. pdd == 0, trim(NAMES(i)) // ': held after')
    call m%eval(0.3_wp, p, pd, pdd)
    call suite%close(p, -0.45_wp, 1.0e-12_wp, 1.0e-12_wp, trim(NAMES(i)) // ': half way')
    h = 1.0e-6_wp
    do k = 1, 7
      t = 0.1_wp + 0.4_wp * k / 8.0_wp + 0.013_wp
      call m%eval(t, p, pd, pdd)
      call m%eval(t + h, pp, pdp, dum)
      call m%eval(t - h, pm, pdm, dum)
      call suite%close(pd, (pp - pm) / (2 * h), 1.0e-7_wp, 1.0e-9_wp, trim(NAMES(i)) // ': rate')
      call suite%close(pdd, (pdp - pdm) / (2 * h), 1.0e-6_wp, 1.0e-7_wp, &
        trim(NAMES(i)) // ': acceleration')
    end do
    tb = m%breakpoints()
    call suite%close_array(tb, [0.1_wp, 0.5_wp], 0.0_wp, 1.0e-15_wp, trim(NAMES(i)) // ': breakpoints')
  end do
  ! The cubic law starts with its own acceleration (right-continuous at t0), 6 span / T^2.
  m = motion_t(label='m', law=LAW_CUBIC, start=0.0_wp, end=1.0_wp, t0=0.0_wp, duration=0.5_wp)
  call m%eval(0.0_wp, p, pd, pdd)
  call suite%close(pdd, 24.0_wp, 1.0e-14_wp, 0.0_wp, 'cubic: acceleration at t0 is the motion''s')
  m = motion_t(label='c', law=LAW_CONSTANT, start=0.7_wp)
  call m%eval(3.0_wp, p, pd, pdd)
  call suite%check(p == 0.7_wp .and. pd == 0 .and. pdd == 0, 'constant law')
  call suite%check(size(m%breakpoints()) == 0, 'constant law: no breakpoints')
  call suite%finish()
end program test_motion
