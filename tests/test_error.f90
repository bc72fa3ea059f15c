program test_error
  use core_error, only: error_t, ERR_INPUT
  use testing, only: suite_t
  implicit none
  type(suite_t) :: t
  type(error_t) :: err
  call t%init('error object')
  call t%check(err%ok(), 'a fresh error is ok')
  call err%set(ERR_INPUT, 'first')
  call err%set(ERR_INPUT, 'second')
  call t%check(.not. err%ok() .and. err%message == 'first', 'the first error is kept')
  call err%prefix('f.nml: ')
  call t%check(err%message == 'f.nml: first', 'context goes in front')
  call t%finish()
end program test_error
