program test_error
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_INPUT
  use core_strings, only: printable, approx_str
  use testing, only: suite_t
  implicit none
  type(suite_t) :: t
  type(error_t) :: err, raw
  call t%init('error object')
  call t%check(err%ok(), 'a fresh error is ok')
  call err%set(ERR_INPUT, 'first')
  call err%set(ERR_INPUT, 'second')
  call t%check(.not. err%ok() .and. err%message == 'first', 'the first error is kept')
  call err%prefix('f.nml: ')
  call t%check(err%message == 'f.nml: first', 'context goes in front')
  ! Control characters of the input (a form feed in a value) were echoed raw.
  call raw%set(ERR_INPUT, 'got ''a' // achar(12) // 'b' // achar(27) // achar(9) // '''')
  call t%check(raw%message == 'got ''a\fb<0x1B>\t''', 'control characters are escaped')
  call raw%prefix('x' // achar(13) // ': ')
  call t%check(raw%message(1:5) == 'x\r: ', 'also in the context')
  call t%check(printable('plain \ text') == 'plain \ text', 'plain text is unchanged')
  call t%check(printable(achar(0) // achar(127)) == '<0x00><0x7F>', 'NUL and DEL as bytes')
  ! Three exponent digits keep their 'E' (es10.2 gave '3.00+298').
  call t%check(approx_str(3.0e298_wp) == '3.00E+298', 'approx_str of 3e298')
  call t%finish()
end program test_error
