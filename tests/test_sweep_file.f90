!> Sweep result file (io_sweep_file): create, write cases, close, resume with open_existing,
!> the layout read back with the HDF5 API, errors, and crash safety (a child process writes
!> cases and kills itself with SIGKILL; the file must reopen with every finished case intact).
!> Files go to $TMPDIR (default /tmp) under a random name and are removed at the end.
!>
!> Child mode (used by the test itself, and by hand for kill -9 experiments):
!>     test_sweep_file --writer PATH N_CASES KILL_AFTER
!> creates PATH with N_CASES cases and writes them in order with values that depend on the case
!> only (see `expected_row`); after KILL_AFTER cases (if >= 0) it raises SIGKILL.
program test_sweep_file
  use, intrinsic :: iso_c_binding, only: c_ptr, c_loc, c_int, c_null_char
  use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan, ieee_is_nan
  use hdf5, only: hid_t, hsize_t, size_t, h5open_f, h5fopen_f, h5fclose_f, H5F_ACC_RDONLY_F, &
    h5dopen_f, h5dread_f, h5dclose_f, h5dget_type_f, h5dget_create_plist_f, h5pget_layout_f, &
    h5pclose_f, H5D_CONTIGUOUS_F, h5tget_size_f, h5tget_strpad_f, h5tclose_f, H5T_STR_NULLPAD_F, &
    h5gget_info_by_name_f, h5lget_name_by_idx_f, H5_INDEX_CRT_ORDER_F, H5_ITER_INC_F
  use core_kinds, only: wp, i8
  use core_error, only: error_t, ERR_INPUT, ERR_IO, ERR_INTERNAL
  use core_strings, only: int_str
  use io_fs, only: delete_file
  use io_hdf5, only: h5_writer_t
  use io_namelist, only: string_t
  use io_sweep_file, only: sweep_file_t, sweep_attrs_t, SWEEP_MESSAGE_LEN
  use testing, only: suite_t
  use h5_read, only: open_objects, dataset_dims, read_real, read_int, read_string_attr, &
    read_i8_attr, scratch_dir, random_tag, exists, msg
  implicit none

  interface
    integer(c_int) function c_raise(sig) bind(C, name='raise')
      import :: c_int
      integer(c_int), value :: sig
    end function c_raise
  end interface

  integer, parameter :: NC = 5, NP = 2, NM = 3
  character(len=*), parameter :: INPUT_TEXT = "&sweep base = 'arm.nml', mode = 'product' /" // &
    new_line('a') // "&parameter name = 'motion.phi1.end', values = 1, 2, 3, 4, 5 /" // &
    new_line('a')
  character(len=16), parameter :: PNAMES(NP) = [character(len=16) :: 'motion.phi1.end', &
                                                'dynamic.rtol']
  character(len=18), parameter :: MNAMES(NM) = [character(len=18) :: 'max_tip_deflection', &
                                                'n_steps', 'residual_vibration']
  character(len=1), parameter :: MUNITS(NM) = [character(len=1) :: 'm', '', 'm']

  type(suite_t) :: t
  character(len=:), allocatable :: dir, tag, path, long_msg, utf8_msg
  real(wp) :: pvals(NC, NP), nan
  integer :: hdferr, i
  integer(size_t) :: objects_at_start

  if (child_mode()) stop

  call t%init('sweep result file')
  dir = scratch_dir()
  tag = random_tag()
  path = dir // '/flexmor_test_sweep_file_' // tag // '.h5'
  call h5open_f(hdferr)
  objects_at_start = open_objects()
  nan = ieee_value(1.0_wp, ieee_quiet_nan)
  do i = 1, NC
    pvals(i, :) = [0.5_wp * i, 10.0_wp ** (-i)]
  end do
  ! Digits 0123456789... 31 bytes longer than a message may be.
  long_msg = ''
  do i = 0, SWEEP_MESSAGE_LEN + 30
    long_msg = long_msg // achar(iachar('0') + mod(i, 10))
  end do
  ! SWEEP_MESSAGE_LEN - 1 ASCII bytes, then 'é' (2 bytes in UTF-8: it would be split by a cut at
  ! SWEEP_MESSAGE_LEN), then more.
  utf8_msg = repeat('x', SWEEP_MESSAGE_LEN - 1) // char(195) // char(169) // 'tail'

  call test_create_and_write()
  call test_resume()
  call test_read_back()
  call test_open_errors()
  call test_create_errors()
  call test_write_errors()
  call test_string_names()
  call test_kill()
  call delete_file(path)
  call t%check(open_objects() == objects_at_start, 'no HDF5 file, group or dataset is left ' &
               // 'open at the end')
  call t%finish()

contains

  subroutine test_create_and_write()
    type(sweep_file_t) :: f
    type(error_t) :: err
    type(sweep_attrs_t) :: a
    a = attrs()
    call f%create(path, a, PNAMES, pvals, MNAMES, err, metric_units=MUNITS)
    call t%check(err%ok(), 'create with 5 cases, 2 parameters, 3 metrics: ' // msg(err))
    call t%check(f%is_open() .and. f%n_cases() == NC, 'the file is open with 5 cases')
    call t%check(all(f%status() == -1), 'every case starts as not run (-1)')
    call t%check(exists(path), 'the file exists under its final name while the sweep runs')
    call t%check(.not. exists(path // '.tmp'), 'no temporary file')
    call f%write_case(3, 0, '', 1.5_wp, 2, [0.25_wp, 120.0_wp, nan], err)
    call t%check(err%ok(), 'write case 3: ' // msg(err))
    call f%write_case(1, 2, long_msg, 0.75_wp, 1, [nan, nan, nan], err)
    call t%check(err%ok(), 'write case 1 with a 301-character message: ' // msg(err))
    call t%check(all(f%status() == [2, -1, 0, -1, -1]), 'status() follows write_case')
    call f%close(err)
    call t%check(err%ok() .and. .not. f%is_open(), 'close: ' // msg(err))
    call f%close(err)
    call t%check(err%ok(), 'close twice is harmless')
    call t%check(size(f%status()) == 0 .and. f%n_cases() == 0, 'a closed file has no status')
  end subroutine test_create_and_write

  subroutine test_resume()
    type(sweep_file_t) :: f
    type(error_t) :: err
    call f%open_existing(path, INPUT_TEXT, err)
    call t%check(err%ok(), 'open_existing with the same sweep input: ' // msg(err))
    call t%check(all(f%status() == [2, -1, 0, -1, -1]), &
                 'status after reopening: [2, -1, 0, -1, -1]')
    call check_names(f%metric_names(), MNAMES, 'the metrics on reopening')
    call f%close(err)

    call f%open_existing(path, INPUT_TEXT // 'x', err)
    call t%check(err%code == ERR_INPUT .and. index(msg(err), path) > 0 .and. &
                 index(msg(err), 'different sweep file') > 0, &
                 'a different sweep input is an input error naming the file: ' // msg(err))
    call t%check(.not. f%is_open(), '... and leaves the object closed')
    call f%open_existing(path, INPUT_TEXT // '  ', err)
    call t%check(err%code == ERR_INPUT, 'trailing blanks count as a difference')
    call f%open_existing(path, INPUT_TEXT, err, base_input_text='other base')
    call t%check(err%code == ERR_INPUT .and. index(msg(err), 'base scene') > 0, &
                 'a changed base scene text is an input error: ' // msg(err))

    call f%open_existing(path, INPUT_TEXT, err, base_input_text='&scene /')
    call t%check(err%ok(), 'open_existing with the same sweep and base input: ' // msg(err))
    call f%open_existing(path, INPUT_TEXT, err)
    call t%check(err%code == ERR_INTERNAL .and. f%is_open(), &
                 'opening an object that is open is an error and keeps it open: ' // msg(err))
    call f%write_case(2, 0, 'fine', 2.0_wp, 3, [1.0_wp, 2.0_wp, 3.0_wp], err)
    call f%write_case(4, 3, utf8_msg, 4.0_wp, 0, [4.0_wp, 5.0_wp, nan], err)
    call f%write_case(5, 1, "scene.nml: &dynamic: variable 'rtol' must be > 0", 5.0_wp, 1, &
                      [nan, 0.0_wp, -1.0_wp], err)
    call t%check(err%ok(), 'write the remaining cases 2, 4, 5: ' // msg(err))
    call t%check(all(f%status() == [2, 0, 0, 3, 1]), 'status after all cases')
    call f%close(err)
    call t%check(err%ok(), 'close after resuming: ' // msg(err))
  end subroutine test_resume

  !> Names (of a group's members, in creation order) against the expected ones. They come in
  !> as a dummy: a local deferred-length array makes gfortran 12 -O2 read its length
  !> uninitialized.
  subroutine check_names(names, expected, what)
    character(len=*), intent(in) :: names(:), expected(:), what
    call t%check(size(names) == size(expected), what // ': as many names as written')
    if (size(names) == size(expected)) call t%check(all(names == expected), what // &
      ': the names in creation order')
  end subroutine check_names

  !> Everything as written, read with the plain HDF5 API.
  subroutine test_read_back()
    integer(hid_t) :: fid
    real(wp), allocatable :: r(:)
    integer, allocatable :: iv(:)
    character(len=SWEEP_MESSAGE_LEN), allocatable :: m(:)
    integer :: j

    call h5fopen_f(path, H5F_ACC_RDONLY_F, fid, hdferr)
    call t%check(hdferr == 0, 'the finished file opens read-only')
    if (hdferr /= 0) return

    iv = read_int(fid, '/cases/status')
    call t%check(all(iv == [2, 0, 0, 3, 1]), '/cases/status reads back')
    iv = read_int(fid, '/cases/rank')
    call t%check(all(iv == [1, 3, 2, 0, 1]), '/cases/rank reads back')
    r = read_real(fid, '/cases/wall_time_s')
    call t%close_array(r, [0.75_wp, 2.0_wp, 1.5_wp, 4.0_wp, 5.0_wp], 0.0_wp, 0.0_wp, &
                       '/cases/wall_time_s reads back')
    r = read_real(fid, '/cases/metrics/max_tip_deflection')
    call t%check(ieee_is_nan(r(1)) .and. ieee_is_nan(r(5)), 'NaN metrics read back as NaN')
    call t%close_array(r(2:4), [1.0_wp, 0.25_wp, 4.0_wp], 0.0_wp, 0.0_wp, &
                       'metric max_tip_deflection reads back')
    r = read_real(fid, '/cases/metrics/n_steps')
    call t%check(ieee_is_nan(r(1)), 'n_steps of case 1 is NaN')
    call t%close_array(r(2:5), [2.0_wp, 120.0_wp, 5.0_wp, 0.0_wp], 0.0_wp, 0.0_wp, &
                       'metric n_steps reads back')
    r = read_real(fid, '/cases/metrics/residual_vibration')
    call t%check(ieee_is_nan(r(1)) .and. ieee_is_nan(r(3)) .and. ieee_is_nan(r(4)), &
                 'residual_vibration NaN where written so')
    call t%check(r(2) == 3.0_wp .and. r(5) == -1.0_wp, 'residual_vibration values')
    do j = 1, NP
      r = read_real(fid, '/cases/parameters/' // trim(PNAMES(j)))
      call t%close_array(r, pvals(:, j), 0.0_wp, 0.0_wp, '/cases/parameters/' // &
                         trim(PNAMES(j)) // ' (a name with dots) reads back')
    end do

    m = read_messages(fid)
    call t%check(m(1) == long_msg(1:SWEEP_MESSAGE_LEN), &
                 'a message longer than SWEEP_MESSAGE_LEN bytes is cut to that length')
    call t%check(m(2)(1:4) == 'fine' .and. all_nul(m(2)(5:)), &
                 "a short message is NUL padded ('fine' then NULs)")
    call t%check(all_nul(m(3)), 'an empty message is all NUL bytes')
    call t%check(m(4)(1:SWEEP_MESSAGE_LEN - 1) == repeat('x', SWEEP_MESSAGE_LEN - 1) .and. &
                 all_nul(m(4)(SWEEP_MESSAGE_LEN:)), &
                 'a cut never splits a UTF-8 character (SWEEP_MESSAGE_LEN - 1 bytes kept)')
    call t%check(m(5)(1:9) == 'scene.nml', 'message of case 5')
    call t%check(string_type_ok(fid), '/cases/message is a fixed-length NUL-padded string')

    ! Array constructors, not .and.: every impure function call is made.
    call t%check(all([layout_is_contiguous(fid, '/cases/status'), &
                      layout_is_contiguous(fid, '/cases/metrics/n_steps'), &
                      layout_is_contiguous(fid, '/cases/message')]), 'the datasets are contiguous')

    call t%check(read_string_attr(fid, '/', 'sweep_input') == INPUT_TEXT, 'attribute sweep_input')
    call t%check(read_string_attr(fid, '/', 'flexmor_version') == '0.1.0', &
                 'attribute flexmor_version')
    call t%check(read_string_attr(fid, '/', 'base_input') == '&scene /', 'attribute base_input')
    call t%check(read_string_attr(fid, '/', 'mode') == 'product', 'attribute mode')
    call t%check(read_string_attr(fid, '/', 'node') == 'tip', 'attribute node')
    call t%check(read_string_attr(fid, '/', 'title') == '', 'an unset string attribute is ""')
    call t%check(read_string_attr(fid, '/', 'sweep_file') == 'arm_sweep.nml', &
                 'attribute sweep_file')
    call t%check(read_string_attr(fid, '/', 'base_scene') == 'arm.nml', 'attribute base_scene')
    call t%check(all([read_i8_attr(fid, '/', 'n_cases'), read_i8_attr(fid, '/', 'n_parameters'), &
                      read_i8_attr(fid, '/', 'seed')] == [integer(i8) :: NC, NP, 42]), &
                 'integer attributes')
    call t%check(read_string_attr(fid, '/cases/wall_time_s', 'units') == 's', &
                 'units of wall_time_s')
    call t%check(read_string_attr(fid, '/cases/metrics/max_tip_deflection', 'units') == 'm', &
                 'units of a metric')
    call t%check(read_string_attr(fid, '/cases/metrics/n_steps', 'units') == '(unreadable)', &
                 "a metric with units '' has no units attribute")

    call check_names(crt_order_names(fid, '/cases/metrics'), MNAMES, '/cases/metrics')
    call check_names(crt_order_names(fid, '/cases/parameters'), PNAMES, '/cases/parameters')
    call h5fclose_f(fid, hdferr)
    call t%check(hdferr == 0, 'the read-back closes cleanly')
  end subroutine test_read_back

  subroutine test_open_errors()
    type(sweep_file_t) :: f
    type(error_t) :: err
    type(h5_writer_t) :: h5
    character(len=:), allocatable :: p
    integer :: n
    integer(size_t) :: n_before

    n_before = open_objects()
    p = dir // '/flexmor_test_sweep_file_' // tag // '_missing.h5'
    call f%open_existing(p, INPUT_TEXT, err)
    call t%check(err%code == ERR_IO .and. index(msg(err), p) > 0, &
                 'a missing file is a file-system error naming it: ' // msg(err))

    p = dir // '/flexmor_test_sweep_file_' // tag // '_text.h5'
    call write_bytes(p, 'this is not HDF5' // new_line('a'))
    call f%open_existing(p, INPUT_TEXT, err)
    call t%check(err%code == ERR_INPUT .and. index(msg(err), p) > 0 .and. &
                 index(msg(err), 'not an HDF5 file') > 0, &
                 'a text file is an input error naming it: ' // msg(err))
    call write_bytes(p, '')
    call f%open_existing(p, INPUT_TEXT, err)
    call t%check(err%code == ERR_INPUT .and. index(msg(err), p) > 0, &
                 'an empty file is an input error: ' // msg(err))

    ! The finished sweep file cut short, as after a crash of the file system or a bad copy.
    n = file_size(path)
    call copy_prefix(path, p, n / 2)
    call f%open_existing(p, INPUT_TEXT, err)
    call t%check(err%code == ERR_INPUT .and. index(msg(err), p) > 0, &
                 'a sweep file cut to half its size is an input error, no crash: ' // msg(err))
    call copy_prefix(path, p, 600)
    call f%open_existing(p, INPUT_TEXT, err)
    call t%check(err%code == ERR_INPUT .and. index(msg(err), p) > 0, &
                 'a sweep file cut to 600 bytes is an input error: ' // msg(err))
    call copy_prefix(path, p, 16)
    call f%open_existing(p, INPUT_TEXT, err)
    call t%check(err%code == ERR_INPUT, 'only the HDF5 signature: input error: ' // msg(err))
    call delete_file(p)

    ! A good HDF5 file that is not a sweep file.
    p = dir // '/flexmor_test_sweep_file_' // tag // '_run.h5'
    call h5%open(p, err)
    if (err%ok()) call h5%write_real_1d('/time', [0.0_wp, 1.0_wp], err)
    if (err%ok()) call h5%write_string_attr('/', 'sweep_input', INPUT_TEXT, err)
    if (err%ok()) call h5%commit(err)
    call f%open_existing(p, INPUT_TEXT, err)
    call t%check(err%code == ERR_INPUT .and. index(msg(err), p) > 0 .and. &
                 index(msg(err), 'not a sweep result file') > 0, 'an HDF5 file that is no ' // &
                 'sweep file is an input error: ' // msg(err))
    ! Root attributes but no /cases: as if the creation had been cut short.
    call h5%open(p, err)
    if (err%ok()) call h5%write_string_attr('/', 'sweep_input', INPUT_TEXT, err)
    if (err%ok()) call h5%write_int_attr('/', 'n_cases', NC, err)
    if (err%ok()) call h5%write_real_1d('/cases/wall_time_s', [1.0_wp], err)
    if (err%ok()) call h5%commit(err)
    call f%open_existing(p, INPUT_TEXT, err)
    call t%check(err%code == ERR_INPUT .and. index(msg(err), p) > 0 .and. &
                 index(msg(err), '/cases/status') > 0, 'a sweep file without /cases/status ' // &
                 'is an input error naming what is missing: ' // msg(err))
    call delete_file(p)
    call t%check(all([.not. f%is_open(), open_objects() == n_before]), &
                 'failed opens leave nothing open')
  end subroutine test_open_errors

  subroutine test_create_errors()
    type(sweep_file_t) :: f
    type(error_t) :: err
    character(len=:), allocatable :: p
    character(len=8) :: bad(NP)
    p = dir // '/flexmor_test_sweep_file_' // tag // '_c.h5'

    bad = [character(len=8) :: 'a/b', 'c']
    call f%create(p, attrs(), bad, pvals, MNAMES, err)
    call t%check(err%code == ERR_INPUT .and. index(msg(err), 'a/b') > 0 .and. &
                 index(msg(err), p) > 0, "a parameter name with '/' is an input error: " // &
                 msg(err))
    call t%check(.not. exists(p) .and. .not. f%is_open(), '... and creates nothing')
    bad = [character(len=8) :: 'x', ' x ']
    call f%create(p, attrs(), bad, pvals, MNAMES, err)
    call t%check(err%code == ERR_INPUT .and. index(msg(err), 'twice') > 0, &
                 'a repeated parameter name is an input error: ' // msg(err))
    bad = [character(len=8) :: 'x', '']
    call f%create(p, attrs(), bad, pvals, MNAMES, err)
    call t%check(err%code == ERR_INPUT, 'an empty name is an input error: ' // msg(err))
    call f%create(p, attrs(), PNAMES, pvals, [character(len=4) :: 'a', '..', 'b'], err)
    call t%check(err%code == ERR_INPUT, "a metric named '..' is an input error: " // msg(err))
    call f%create(p, attrs(), PNAMES(1:1), pvals, MNAMES, err)
    call t%check(err%code == ERR_INTERNAL, 'names and value columns must agree: ' // msg(err))
    call f%create(p, attrs(), PNAMES, pvals, MNAMES, err, metric_units=MUNITS(1:2))
    call t%check(err%code == ERR_INTERNAL, 'metric units must match the metrics: ' // msg(err))

    call f%create(path, attrs(), PNAMES, pvals, MNAMES, err)
    call t%check(err%code == ERR_IO .and. index(msg(err), path) > 0 .and. .not. f%is_open(), &
                 'create does not replace an existing file: ' // msg(err))
    call f%create(p, attrs(), PNAMES, pvals, MNAMES, err)
    call t%check(err%ok(), 'create again')
    call f%close()
    call f%create(p, attrs(), PNAMES, pvals(1:2, :), MNAMES, err, overwrite=.true.)
    call t%check(err%ok() .and. f%n_cases() == 2, 'overwrite=.true. replaces an existing file')
    call f%create(p, attrs(), PNAMES, pvals, MNAMES, err)
    call t%check(err%code == ERR_INTERNAL .and. f%n_cases() == 2, &
                 'create on an open object is an error and keeps it open: ' // msg(err))
    call f%close()
    call delete_file(p)

    call f%create(dir // '/no_such_dir_' // tag // '/out.h5', attrs(), PNAMES, pvals, MNAMES, err)
    call t%check(err%code == ERR_IO .and. index(msg(err), 'no_such_dir_' // tag) > 0, &
                 'create in a missing folder is a file-system error naming it: ' // msg(err))
  end subroutine test_create_errors

  subroutine test_write_errors()
    type(sweep_file_t) :: f
    type(error_t) :: err
    character(len=:), allocatable :: p
    p = dir // '/flexmor_test_sweep_file_' // tag // '_w.h5'
    call f%write_case(1, 0, '', 1.0_wp, 0, [1.0_wp, 2.0_wp, 3.0_wp], err)
    call t%check(err%code == ERR_INTERNAL, 'write_case before create is an error: ' // msg(err))
    call f%create(p, attrs(), PNAMES, pvals, MNAMES, err, sync=.true.)
    call t%check(err%ok(), 'create with sync=.true.: ' // msg(err))
    call f%write_case(6, 0, '', 1.0_wp, 0, [1.0_wp, 2.0_wp, 3.0_wp], err)
    call t%check(err%code == ERR_INTERNAL .and. index(msg(err), p) > 0, &
                 'case 6 of 5 is an error naming the file: ' // msg(err))
    call f%write_case(0, 0, '', 1.0_wp, 0, [1.0_wp, 2.0_wp, 3.0_wp], err)
    call t%check(err%code == ERR_INTERNAL, 'case 0 is an error')
    call f%write_case(1, 0, '', 1.0_wp, 0, [1.0_wp, 2.0_wp], err)
    call t%check(err%code == ERR_INTERNAL, 'two metrics for three is an error: ' // msg(err))
    call f%write_case(1, -1, '', 1.0_wp, 0, [1.0_wp, 2.0_wp, 3.0_wp], err)
    call t%check(err%code == ERR_INTERNAL, 'status -1 is not a result: ' // msg(err))
    call t%check(all(f%status() == -1), 'rejected writes change nothing')
    call f%write_case(5, 4, '', 1.0_wp, 0, [1.0_wp, 2.0_wp, 3.0_wp], err)
    call t%check(err%ok() .and. all(f%status() == [-1, -1, -1, -1, 4]), &
                 'a case written with sync=.true.: ' // msg(err))
    call f%close(err)
    call t%check(err%ok(), 'close with sync: ' // msg(err))
    call delete_file(p)
  end subroutine test_write_errors

  subroutine test_string_names()
    type(sweep_file_t) :: f
    type(error_t) :: err
    type(string_t) :: names(NP)
    character(len=:), allocatable :: p
    integer(hid_t) :: fid
    p = dir // '/flexmor_test_sweep_file_' // tag // '_s.h5'
    names(1)%s = 'hinge.joint1.stiffness'
    names(2)%s = 'link.link1.n_elements'
    call f%create(p, attrs(), names, pvals, MNAMES, err)
    call t%check(err%ok(), 'create with string_t parameter names: ' // msg(err))
    call f%close()
    call h5fopen_f(p, H5F_ACC_RDONLY_F, fid, hdferr)
    call t%check(hdferr == 0, 'the file with string_t names opens')
    ! (read_real gives an empty array, a size mismatch here, if the file did not open.)
    call t%close_array(read_real(fid, '/cases/parameters/link.link1.n_elements'), pvals(:, 2), &
                       0.0_wp, 0.0_wp, 'string_t names: values read back')
    if (hdferr == 0) call h5fclose_f(fid, hdferr)
    call delete_file(p)
  end subroutine test_string_names

  !> A child process writes cases 1..3 of 7 and is killed (SIGKILL, no cleanup, no close). The
  !> file must reopen with open_existing, show cases 1..3 complete and 4..7 not run, and take
  !> the rest.
  subroutine test_kill()
    type(sweep_file_t) :: f
    type(error_t) :: err
    character(len=:), allocatable :: p, exe
    character(len=4096) :: buf
    integer :: stat, cstat, k, n
    integer, allocatable :: st(:)
    logical, allocatable :: bad(:)
    real(wp) :: wall, metrics(NM)
    character(len=:), allocatable :: message
    logical :: opened

    p = dir // '/flexmor_test_sweep_file_' // tag // '_kill.h5'
    call get_command_argument(0, buf, n)
    exe = trim(buf)
    stat = 0
    cstat = 0
    ! (exec 2>/dev/null: the shell's own 'Killed' notice would only clutter the test output.)
    call execute_command_line("exec 2>/dev/null; '" // exe // "' --writer '" // p // "' 7 3", &
                              exitstat=stat, cmdstat=cstat)
    call t%check(cstat == 0 .and. stat /= 0, 'the child writer was killed (exit status ' // &
                 int_str(stat) // ')')
    call f%open_existing(p, 'writer', err)
    call t%check(err%ok(), 'a file whose writer was killed reopens: ' // msg(err))
    call t%check(all(f%status() == [1, 0, 1, -1, -1, -1, -1]), &
                 'cases written before the kill are there, the others not run')
    do k = 4, 7
      call expected_row(k, wall, metrics, message)
      call f%write_case(k, mod(k, 2), message, wall, k, metrics, err)
    end do
    call t%check(err%ok(), 'the killed sweep is finished after resuming: ' // msg(err))
    call f%close()

    call check_rows(p, st, bad, opened)
    call t%check(opened, 'the resumed file opens read-only')
    call t%check(size(st) == 7 .and. all(st /= -1) .and. .not. any(bad), &
                 'every row of the resumed file is complete and right')
    call delete_file(p)
  end subroutine test_kill

  ! --- child mode -----------------------------------------------------------------------------

  logical function child_mode()
    character(len=4096) :: a1, a2, a3, a4
    child_mode = .false.
    if (command_argument_count() == 2) then
      call get_command_argument(1, a1)
      call get_command_argument(2, a2)
      if (a1 /= '--check') error stop 'usage: test_sweep_file --check PATH'
      call check_child(trim(a2))
      child_mode = .true.
    else if (command_argument_count() == 4) then
      call get_command_argument(1, a1)
      call get_command_argument(2, a2)
      call get_command_argument(3, a3)
      call get_command_argument(4, a4)
      if (a1 /= '--writer') error stop 'usage: test_sweep_file --writer PATH N_CASES KILL_AFTER'
      call writer_child(trim(a2), a3, a4)
      child_mode = .true.
    end if
  end function child_mode

  !> Write N cases in order into a new file; raise SIGKILL after KILL_AFTER of them (if >= 0).
  subroutine writer_child(path_, a3, a4)
    character(len=*), intent(in) :: path_, a3, a4
    type(sweep_file_t) :: f
    type(error_t) :: err
    type(sweep_attrs_t) :: a
    real(wp), allocatable :: v(:, :)
    integer :: n, kill_after, k, st
    real(wp) :: wall, metrics(NM)
    character(len=:), allocatable :: message
    read(a3, *) n
    read(a4, *) kill_after
    a%sweep_input = 'writer'
    allocate(v(n, 1))
    v(:, 1) = [(real(k, wp), k = 1, n)]
    call f%create(path_, a, ['k'], v, MNAMES, err, overwrite=.true.)
    if (.not. err%ok()) error stop 'child: create failed'
    do k = 1, n
      if (k - 1 == kill_after) st = c_raise(9_c_int)
      call expected_row(k, wall, metrics, message)
      call f%write_case(k, mod(k, 2), message, wall, k, metrics, err)
      if (.not. err%ok()) error stop 'child: write_case failed'
    end do
    if (n == kill_after) st = c_raise(9_c_int)
    call f%close()
  end subroutine writer_child

  !> Reopen a file made by writer_child (after a kill -9), check every finished row, print
  !> 'done N of M', and finish the remaining cases. Exit status 1 on any problem.
  subroutine check_child(path_)
    character(len=*), intent(in) :: path_
    type(sweep_file_t) :: f
    type(error_t) :: err
    integer, allocatable :: st(:)
    logical, allocatable :: bad(:)
    real(wp) :: wall, metrics(NM)
    character(len=:), allocatable :: message
    integer :: k
    logical :: opened
    call h5open_f(hdferr)
    call check_rows(path_, st, bad, opened)
    if (.not. opened) then
      call f%open_existing(path_, 'writer', err)
      write(*, '(a)') 'check: unreadable; open_existing says: ' // msg(err)
      error stop 1
    end if
    do k = 1, size(st)
      if (bad(k)) write(*, '(a,i0,a)') 'check: case ', k, ' is incomplete or wrong'
    end do
    write(*, '(a,i0,a,i0,a,i0,a)') 'check: done ', count(st /= -1), ' of ', size(st), &
      ' (first not run: ', findloc(st, -1, dim=1), ')'
    call f%open_existing(path_, 'writer', err)
    if (.not. err%ok()) then
      write(*, '(a)') 'check: open_existing: ' // err%message
      error stop 1
    end if
    do k = 1, size(st)
      if (st(k) /= -1) cycle
      call expected_row(k, wall, metrics, message)
      call f%write_case(k, mod(k, 2), message, wall, k, metrics, err)
      if (.not. err%ok()) error stop 'check: write_case failed'
    end do
    call f%close(err)
    if (.not. err%ok() .or. any(bad)) error stop 1
    write(*, '(a)') 'check: resumed and finished'
  end subroutine check_child

  !> Read the file at `path_` (written by writer_child, perhaps killed, perhaps resumed) with the
  !> HDF5 API: /cases/status in `st`, and bad(k) where case k is marked done (status /= -1) but
  !> its row is not the one expected_row gives. `opened` is false if the file does not open.
  subroutine check_rows(path_, st, bad, opened)
    character(len=*), intent(in) :: path_
    integer, allocatable, intent(out) :: st(:)
    logical, allocatable, intent(out) :: bad(:)
    logical, intent(out) :: opened
    integer(hid_t) :: fid
    integer, allocatable :: rk(:)
    real(wp), allocatable :: r(:), w(:)
    character(len=SWEEP_MESSAGE_LEN), allocatable :: m(:)
    real(wp) :: wall, metrics(NM)
    character(len=:), allocatable :: message
    integer :: k
    call h5fopen_f(path_, H5F_ACC_RDONLY_F, fid, hdferr)
    opened = hdferr == 0
    if (.not. opened) then
      allocate(st(0), bad(0))
      return
    end if
    st = read_int(fid, '/cases/status')
    rk = read_int(fid, '/cases/rank')
    r = read_real(fid, '/cases/metrics/residual_vibration')
    w = read_real(fid, '/cases/wall_time_s')
    m = read_messages(fid)
    call h5fclose_f(fid, hdferr)
    allocate(bad(size(st)), source=.false.)
    do k = 1, size(st)
      if (st(k) == -1) cycle
      call expected_row(k, wall, metrics, message)
      bad(k) = st(k) /= mod(k, 2) .or. rk(k) /= k .or. r(k) /= metrics(3) .or. w(k) /= wall &
               .or. m(k)(1:len(message)) /= message .or. .not. all_nul(m(k)(len(message) + 1:))
    end do
  end subroutine check_rows

  !> The row the writer writes for case k (status mod(k, 2), rank k).
  subroutine expected_row(k, wall, metrics, message)
    integer, intent(in) :: k
    real(wp), intent(out) :: wall, metrics(NM)
    character(len=:), allocatable, intent(out) :: message
    wall = 0.5_wp * k
    metrics = [real(k, wp), 10.0_wp * k, 100.0_wp * k]
    message = 'case ' // int_str(k) // ' ' // repeat('m', mod(k * 37, 200))
  end subroutine expected_row

  ! --- helpers --------------------------------------------------------------------------------

  function attrs() result(a)
    type(sweep_attrs_t) :: a
    a%flexmor_version = '0.1.0'
    a%sweep_input = INPUT_TEXT
    a%sweep_file = 'arm_sweep.nml'
    a%base_input = '&scene /'
    a%base_scene = 'arm.nml'
    a%mode = 'product'
    a%seed = 42
    a%node = 'tip'
  end function attrs

  pure logical function all_nul(s)
    character(len=*), intent(in) :: s
    all_nul = verify(s, c_null_char) == 0
  end function all_nul

  integer function file_size(p)
    character(len=*), intent(in) :: p
    inquire(file=p, size=file_size)
  end function file_size

  subroutine write_bytes(p, text)
    character(len=*), intent(in) :: p, text
    integer :: u
    open(newunit=u, file=p, access='stream', form='unformatted', status='replace')
    write(u) text
    close(u)
  end subroutine write_bytes

  !> Copy the first n bytes of file `from` to `to`.
  subroutine copy_prefix(from, to, n)
    character(len=*), intent(in) :: from, to
    integer, intent(in) :: n
    character(len=:), allocatable :: bytes
    integer :: u
    allocate(character(len=n) :: bytes)
    open(newunit=u, file=from, access='stream', form='unformatted', status='old', action='read')
    read(u) bytes
    close(u)
    call write_bytes(to, bytes)
  end subroutine copy_prefix

  !> /cases/message with its own file type as the memory type (NUL-padded fields of
  !> SWEEP_MESSAGE_LEN bytes).
  function read_messages(fid) result(m)
    integer(hid_t), intent(in) :: fid
    character(len=SWEEP_MESSAGE_LEN), allocatable, target :: m(:)
    integer(hid_t) :: did, tid
    integer(hsize_t), allocatable :: dims(:)
    type(c_ptr) :: p
    allocate(dims, source=dataset_dims(fid, '/cases/message'))
    if (size(dims) /= 1) then
      allocate(m(0))
      return
    end if
    allocate(m(dims(1)))
    m = ''
    if (size(m) == 0) return
    call h5dopen_f(fid, '/cases/message', did, hdferr)
    call h5dget_type_f(did, tid, hdferr)
    p = c_loc(m)
    call h5dread_f(did, tid, p, hdferr)
    call t%check(hdferr == 0, 'h5dread /cases/message')
    call h5tclose_f(tid, hdferr)
    call h5dclose_f(did, hdferr)
  end function read_messages

  logical function string_type_ok(fid)
    integer(hid_t), intent(in) :: fid
    integer(hid_t) :: did, tid
    integer(size_t) :: sz
    integer :: pad
    call h5dopen_f(fid, '/cases/message', did, hdferr)
    call h5dget_type_f(did, tid, hdferr)
    call h5tget_size_f(tid, sz, hdferr)
    call h5tget_strpad_f(tid, pad, hdferr)
    string_type_ok = sz == int(SWEEP_MESSAGE_LEN, size_t) .and. pad == H5T_STR_NULLPAD_F
    call h5tclose_f(tid, hdferr)
    call h5dclose_f(did, hdferr)
  end function string_type_ok

  logical function layout_is_contiguous(fid, name)
    integer(hid_t), intent(in) :: fid
    character(len=*), intent(in) :: name
    integer(hid_t) :: did, pid
    integer :: layout
    layout = -1
    call h5dopen_f(fid, name, did, hdferr)
    call h5dget_create_plist_f(did, pid, hdferr)
    call h5pget_layout_f(pid, layout, hdferr)
    call h5pclose_f(pid, hdferr)
    call h5dclose_f(did, hdferr)
    layout_is_contiguous = layout == H5D_CONTIGUOUS_F
  end function layout_is_contiguous

  function crt_order_names(fid, group) result(names)
    integer(hid_t), intent(in) :: fid
    character(len=*), intent(in) :: group
    character(len=:), allocatable :: names(:)
    integer :: storage, nlinks, maxc, k
    integer(size_t) :: sz
    character(len=64) :: b
    call h5gget_info_by_name_f(fid, group, storage, nlinks, maxc, hdferr)
    if (hdferr /= 0) nlinks = 0
    allocate(character(len=18) :: names(nlinks))
    do k = 1, nlinks
      b = ''
      call h5lget_name_by_idx_f(fid, group, H5_INDEX_CRT_ORDER_F, H5_ITER_INC_F, &
                                int(k - 1, hsize_t), b, hdferr, sz)
      names(k) = b
    end do
  end function crt_order_names

end program test_sweep_file
