!> HDF5 result writer (io_hdf5) and file helpers (io_fs): datasets, attributes, the Fortran
!> (ncol, nrow) -> C (nrow, ncol) convention, commit/abort through a temporary file, errors.
!> Files go to $TMPDIR (default /tmp) under a random name and are removed at the end.
program test_hdf5
  use, intrinsic :: iso_c_binding, only: c_loc
  use hdf5, only: hid_t, hsize_t, size_t, h5open_f, h5fopen_f, h5fclose_f, H5F_ACC_RDONLY_F, &
    h5kind_to_type, H5_REAL_KIND, h5lexists_f
  use core_kinds, only: wp, i8
  use core_error, only: error_t, ERR_IO
  use io_hdf5, only: h5_writer_t
  use io_fs, only: delete_file, rename_file
  use testing, only: suite_t
  use h5_read, only: open_objects, dataset_dims, read_dataset, read_real, read_int, read_i8, &
    read_string_attr, read_real_attr, read_i8_attr, scratch_dir, random_tag, exists, msg
  implicit none

  type(suite_t) :: t
  character(len=:), allocatable :: dir, path, long_text
  integer, parameter :: nt = 7
  real(wp) :: time(nt), pos(3, nt)
  integer :: i, hdferr

  call t%init('HDF5 result writer')
  dir = scratch_dir()
  path = dir // '/flexmor_test_hdf5_' // random_tag() // '.h5'
  call h5open_f(hdferr)

  do i = 1, nt
    time(i) = 0.1_wp * (i - 1)
    pos(:, i) = [real(i, wp), 10.0_wp * i, 0.0_wp]
  end do
  ! A long text with newlines, like a whole input file (well beyond the 64 kB header limit).
  long_text = repeat('&scene dt = 1.0e-3, name = "tip" /' // new_line('a'), 3000)

  call test_write_commit()
  call test_read_back()
  call test_replace_existing()
  call test_abort()
  call test_errors()
  call test_commit_rename_fails()
  call delete_file(path)

  call t%finish()

contains

  subroutine test_write_commit()
    type(h5_writer_t) :: h5
    type(error_t) :: err
    real(wp) :: empty(0)
    logical :: all_ok
    integer(size_t) :: n_before

    all_ok = .true.
    n_before = open_objects()
    call h5%open(path, err)
    call t%check(err%ok() .and. h5%is_open(), 'open creates the temporary file')
    call t%check(open_objects() == n_before + 1, 'the open writer holds one file and nothing else')
    call t%check(exists(path // '.tmp'), 'while writing the temporary file exists')
    call t%check(.not. exists(path), 'while writing the final name does not exist')
    call h5%write_real_1d('/time', time, err, units='s');                     call note(err, all_ok)
    call h5%write_real_2d('/nodes/tip/position', pos, err, units='m');        call note(err, all_ok)
    call h5%write_real_1d('modal/frequency_hz', [1.5_wp, 7.25_wp], err);      call note(err, all_ok)
    call h5%write_int_1d('/counts', [3, -1, 4], err);                         call note(err, all_ok)
    call h5%write_int_1d('/big', [2_i8**40, -5_i8], err);                     call note(err, all_ok)
    call h5%write_real_1d('/empty', empty, err);                              call note(err, all_ok)
    call h5%write_string_attr('/', 'flexmor_version', '0.1.0', err);          call note(err, all_ok)
    call h5%write_string_attr('/', 'status', 'running', err);                 call note(err, all_ok)
    call h5%write_string_attr('/', 'status', 'ok', err);                      call note(err, all_ok)
    call h5%write_string_attr('/', 'input', long_text, err);                  call note(err, all_ok)
    call h5%write_real_attr('/', 'wall_time_s', 12.5_wp, err);                call note(err, all_ok)
    call h5%write_int_attr('/', 'n_steps', 123456789012_i8, err);             call note(err, all_ok)
    call h5%write_int_attr('/', 'n_rhs_evals', 42, err);                      call note(err, all_ok)
    call h5%write_string_attr('/nodes/tip', 'description', 'end effector', err)
    call note(err, all_ok)
    call h5%write_real_attr('/time', 'scale', 1.0_wp, err);                   call note(err, all_ok)
    call t%check(all_ok, 'datasets and attributes are written without error')

    call h5%commit(err)
    call t%check(err%ok() .and. .not. h5%is_open(), 'commit succeeds and closes the writer')
    call t%check(exists(path), 'the final file exists after commit')
    call t%check(.not. exists(path // '.tmp'), 'the temporary file is gone after commit')
    call t%check(open_objects() == n_before, 'no HDF5 file, group or dataset is left open')
    call h5%abort()
    call t%check(exists(path), 'abort after commit leaves the committed file alone')
  end subroutine test_write_commit

  subroutine test_read_back()
    integer(hid_t) :: fid
    integer(hsize_t), allocatable :: dims(:)
    real(wp), allocatable, target :: r2(:, :)
    logical :: found, ok

    call h5fopen_f(path, H5F_ACC_RDONLY_F, fid, hdferr)
    call t%check(hdferr == 0, 'the committed file opens with HDF5')
    if (hdferr /= 0) return

    dims = dataset_dims(fid, '/nodes/tip/position')
    call t%check(size(dims) == 2, 'position has rank 2')
    if (size(dims) == 2) then
      ! The Fortran API reports dims in Fortran order, reversed from C/h5py: (3, nt) here is
      ! (nt, 3) in h5py.
      call t%check(all(dims == [3_hsize_t, int(nt, hsize_t)]), &
                   'pos(3, nt) is stored as Fortran (3, nt), i.e. (nt, 3) in C order')
      allocate(r2(dims(1), dims(2)))
      call read_dataset(fid, '/nodes/tip/position', h5kind_to_type(wp, H5_REAL_KIND), c_loc(r2), &
                        ok)
      call t%check(ok, 'h5dread /nodes/tip/position')
      call t%close_array(reshape(r2, [size(r2)]), reshape(pos, [size(pos)]), 0.0_wp, 0.0_wp, &
                         'position reads back exactly')
      ! Row k of the C view (time k) is pos(:, k): flat C index (k-1)*3 + j.
      call t%close(r2(2, 5), 50.0_wp, 0.0_wp, 0.0_wp, 'C row 5, column 2 is y at the 5th time')
    end if

    ! (read_real and read_int give an empty array for a missing dataset or one of another rank.)
    call t%close_array(read_real(fid, '/time'), time, 0.0_wp, 0.0_wp, 'time reads back exactly')
    call t%close_array(read_real(fid, '/modal/frequency_hz'), [1.5_wp, 7.25_wp], 0.0_wp, 0.0_wp, &
                       'frequencies read back (an intermediate group is created for /modal)')
    call t%check(same_ints(int(read_int(fid, '/counts'), i8), [3_i8, -1_i8, 4_i8]), &
                 'default integers read back')
    call t%check(same_ints(read_i8(fid, '/big'), [2_i8**40, -5_i8]), &
                 'integer(i8) values read back')
    dims = dataset_dims(fid, '/empty')
    call t%check(size(dims) == 1, 'an empty dataset is written')
    if (size(dims) == 1) call t%check(dims(1) == 0, 'the empty dataset has size 0')

    call t%check(read_string_attr(fid, '/', 'status') == 'ok', &
                 'writing an attribute again replaces it')
    call t%check(read_string_attr(fid, '/', 'flexmor_version') == '0.1.0', 'string attribute')
    call t%check(read_string_attr(fid, '/', 'input') == long_text, &
                 'a long multi-line string attribute reads back whole')
    call t%check(read_string_attr(fid, '/time', 'units') == 's', 'units attribute of /time')
    call t%check(read_string_attr(fid, '/nodes/tip/position', 'units') == 'm', &
                 'units attribute of the position')
    call t%check(read_string_attr(fid, '/nodes/tip', 'description') == 'end effector', &
                 'attribute on a group')
    call t%close(read_real_attr(fid, '/', 'wall_time_s'), 12.5_wp, 0.0_wp, 0.0_wp, &
                 'real attribute')
    call t%check(read_i8_attr(fid, '/', 'n_steps') == 123456789012_i8, 'integer(i8) attribute')
    call t%check(read_i8_attr(fid, '/', 'n_rhs_evals') == 42_i8, 'default integer attribute')
    call h5lexists_f(fid, '/modal', found, hdferr)
    call t%check(hdferr == 0 .and. found, 'group /modal exists')
    call h5fclose_f(fid, hdferr)
    call t%check(hdferr == 0, 'the file closes cleanly (no handles left open)')
  end subroutine test_read_back

  subroutine test_replace_existing()
    type(h5_writer_t) :: h5
    type(error_t) :: err
    integer(hid_t) :: fid
    call h5%open(path, err)
    if (err%ok()) call h5%write_real_1d('/time', [5.0_wp, 6.0_wp], err)
    call t%check(exists(path), 'the previous result stays in place while the new one is written')
    if (err%ok()) call h5%commit(err)
    call t%check(err%ok(), 'a second commit to the same name succeeds')
    call h5fopen_f(path, H5F_ACC_RDONLY_F, fid, hdferr)
    if (hdferr == 0) then
      call t%close_array(read_real(fid, '/time'), [5.0_wp, 6.0_wp], 0.0_wp, 0.0_wp, &
                         'commit replaces the existing file')
      call h5fclose_f(fid, hdferr)
    else
      call t%check(.false., 'the replaced file opens')
    end if
  end subroutine test_replace_existing

  subroutine test_abort()
    type(h5_writer_t) :: h5, never
    type(error_t) :: err
    character(len=:), allocatable :: p2
    integer(size_t) :: n_before
    integer :: k
    p2 = dir // '/flexmor_test_hdf5_' // random_tag() // '_abort.h5'
    call h5%open(p2, err)
    call t%check(err%ok(), 'open for abort')
    call h5%write_real_1d('/time', time, err)
    call h5%abort()
    call t%check(.not. exists(p2), 'abort leaves no final file')
    call t%check(.not. exists(p2 // '.tmp'), 'abort leaves no temporary file')
    call t%check(.not. h5%is_open(), 'abort closes the writer')
    call h5%abort()
    call never%abort()
    call t%check(.true., 'abort is safe twice and on a writer never opened')

    ! Many runs in one process (a sweep): the library is initialised once, nothing accumulates.
    ! (Re-running h5open_f would re-create HDF5's Fortran types and shift these counts.)
    n_before = open_objects()
    do k = 1, 50
      call h5%open(p2, err)
      if (err%ok()) call h5%write_real_1d('/time', time, err)
      call h5%abort()
    end do
    call t%check(all([err%ok(), open_objects() == n_before]), &
                 '50 open/write/abort cycles leave nothing open')
    call h5%write_real_1d('/time', time, err)
    call t%check(err%code == ERR_IO, 'writing after abort is an error: ' // msg(err))
    call h5%commit(err)
    call t%check(err%code == ERR_IO, 'commit after abort is an error: ' // msg(err))
    call never%commit(err)
    call t%check(err%code == ERR_IO, 'commit of a writer never opened is an error: ' // msg(err))
  end subroutine test_abort

  subroutine test_errors()
    type(h5_writer_t) :: h5
    type(error_t) :: err
    character(len=:), allocatable :: bad, p3
    integer(size_t) :: n_before

    n_before = open_objects()
    bad = dir // '/flexmor_no_such_dir_' // random_tag() // '/out.h5'
    call h5%open(bad, err)
    call t%check(err%code == ERR_IO .and. .not. h5%is_open(), &
                 'opening in a missing folder reports an error: ' // msg(err))
    call t%check(index(msg(err), bad) > 0, 'the message names the file')
    call h5%abort()

    p3 = dir // '/flexmor_test_hdf5_' // random_tag() // '_err.h5'
    call h5%open(p3, err)
    call t%check(err%ok(), 'open for the error tests')
    call h5%open(p3, err)
    call t%check(err%code == ERR_IO .and. h5%is_open(), &
                 'opening an open writer again is an error and keeps it open: ' // msg(err))
    call h5%write_real_1d('/a/x', time, err)
    call h5%write_real_1d('/a/x', time, err)
    call t%check(err%code == ERR_IO .and. index(msg(err), '/a/x') > 0, &
                 'a dataset written twice is an error naming it: ' // msg(err))
    call h5%write_real_1d('/a/x/y', time, err)
    call t%check(err%code == ERR_IO .and. index(msg(err), '/a/x/y') > 0, &
                 'a dataset under a dataset is an error: ' // msg(err))
    call h5%write_string_attr('/nope', 'units', 'm', err)
    call t%check(err%code == ERR_IO .and. index(msg(err), '/nope') > 0 .and. &
                 index(msg(err), p3) > 0, 'an attribute of a missing object is an error naming &
                 &file and object: ' // msg(err))
    call h5%write_real_attr('/missing/group', 'x', 1.0_wp, err)
    call t%check(err%code == ERR_IO, 'a real attribute of a missing object is an error')
    call h5%write_real_1d('/', time, err)
    call t%check(err%code == ERR_IO, 'a dataset named "/" is an error: ' // msg(err))
    call h5%write_real_1d('/ok', time, err)
    call t%check(err%ok(), 'the writer still works after errors')
    call h5%commit(err)
    call t%check(err%ok(), 'commit after recovered errors')
    call t%check(exists(p3), 'the file is there after recovered errors')
    call t%check(open_objects() == n_before, 'failed writes leave no HDF5 handle open')
    call delete_file(p3, err)
    call t%check(err%ok(), 'delete_file succeeds')
    call t%check(.not. exists(p3), 'delete_file removes the file')
    call delete_file(p3, err)
    call t%check(err%ok(), 'delete_file of a missing file is not an error')
    call rename_file(p3, p3 // '.x', err)
    call t%check(err%code == ERR_IO .and. index(msg(err), p3) > 0, &
                 'rename_file of a missing file is an error: ' // msg(err))
  end subroutine test_errors

  !> The final name is taken by a folder: rename fails, and the message says that nothing was
  !> written, which is true: the temporary file is gone too (a message must never point to a
  !> file that is not there).
  subroutine test_commit_rename_fails()
    type(h5_writer_t) :: h5
    type(error_t) :: err
    character(len=:), allocatable :: p4
    integer :: stat, cstat
    stat = 0
    cstat = 0
    p4 = dir // '/flexmor_test_hdf5_' // random_tag() // '_isdir.h5'
    call execute_command_line("mkdir '" // p4 // "'", exitstat=stat, cmdstat=cstat)
    if (stat /= 0 .or. cstat /= 0) then
      call t%check(.false., 'mkdir for the rename failure test')
      return
    end if
    call h5%open(p4, err)
    if (err%ok()) call h5%write_real_1d('/time', time, err)
    if (err%ok()) call h5%commit(err)
    call t%check(err%code == ERR_IO .and. index(msg(err), 'nothing was written') > 0, &
                 'a failed rename says nothing was written: ' // msg(err))
    call t%check(.not. exists(p4 // '.tmp'), 'no temporary file is left after a failed rename')
    call t%check(.not. h5%is_open(), 'the writer is closed after a failed commit')
    call h5%abort()
    call t%check(.not. exists(p4 // '.tmp'), 'abort after a failed commit is harmless')
    call execute_command_line("rmdir '" // p4 // "'", exitstat=stat, cmdstat=cstat)
  end subroutine test_commit_rename_fails

  ! --- helpers --------------------------------------------------------------------------------

  subroutine note(e, all_ok)
    type(error_t), intent(in) :: e
    logical, intent(inout) :: all_ok
    if (.not. e%ok()) then
      all_ok = .false.
      write(*, '(a)') '        error: ' // e%message
    end if
  end subroutine note

  !> a == b, also in size (a size mismatch is a failure, not an error).
  pure logical function same_ints(a, b)
    integer(i8), intent(in) :: a(:), b(:)
    same_ints = size(a) == size(b)
    if (same_ints) same_ints = all(a == b)
  end function same_ints
end program test_hdf5
