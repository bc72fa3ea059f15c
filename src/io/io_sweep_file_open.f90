!> Reopening a sweep result file to resume it: every check that the file is this sweep's,
!> with a message naming what differs; and the release of the ids both paths hold.
submodule (io_sweep_file) io_sweep_file_open
  use hdf5, only: size_t, h5fopen_f, h5fclose_f, h5fis_hdf5_f, h5dread_f, H5F_ACC_RDWR_F, &
    H5T_FLOAT_F, H5T_INTEGER_F, H5T_STRING_F
  use io_fs, only: sync_file
  use io_h5read, only: h5_read_string_attr, h5_read_int_attr, h5_open_dataset, &
    h5_dataset_shape, h5_member_names, h5_probe_read_only, H5_OK, H5_MISSING, H5_UNOPENABLE, &
    H5_BAD_TYPE, H5_UNREADABLE
  implicit none

contains

  ! ---------------------------------------------------------------------------------------------
  ! open_existing

  module procedure sf_open_existing
    character(len=*), parameter :: not_sweep = ' (remove it or choose another -o)'
    character(len=:), allocatable :: text
    integer(hid_t) :: fid
    integer :: hdferr, n, j, why
    logical :: exists, is_h5
    integer, allocatable, target :: st(:)
    type(c_ptr) :: p

    if (this%opened) then
      call err%set(ERR_INTERNAL, path // ": cannot open the sweep file: this object still has '" &
                   // this%path // "' open")
      return
    end if
    inquire(file=path, exist=exists)
    if (.not. exists) then
      call err%set(ERR_IO, path // ': cannot resume the sweep: the result file does not exist')
      return
    end if
    call h5_init(path, err)
    if (.not. err%ok()) return

    call h5fis_hdf5_f(path, is_h5, hdferr)
    if (hdferr < 0) then
      ! Say why when the file system can tell (a folder, no permission).
      call check_output_path(path, err)
      if (err%ok()) call err%set(ERR_IO, path // ': cannot read the file (is it readable?)')
      return
    end if
    if (.not. is_h5) then
      call err%set(ERR_INPUT, path // ' is not an HDF5 file, so not a sweep result file' // &
                   not_sweep)
      return
    end if
    call h5fopen_f(path, H5F_ACC_RDWR_F, fid, hdferr)
    if (hdferr < 0) then
      call diagnose_open_failure(path, err)
      return
    end if
    this%file_id = fid
    this%path = path
    this%opened = .true.
    this%do_sync = .false.
    if (present(sync)) this%do_sync = sync

    work: block
      call h5_read_string_attr(fid, '/', 'sweep_input', text, why)
      call check_attr(this, 'sweep_input', why, 'a text', err)
      if (.not. err%ok()) exit work
      if (.not. same_text(text, sweep_input_text)) then
        call reject(path, ' was written by a different sweep file', err)
        exit work
      end if
      if (present(base_input_text)) then
        call h5_read_string_attr(fid, '/', 'base_input', text, why)
        call check_attr(this, 'base_input', why, 'a text', err)
        if (.not. err%ok()) exit work
        if (.not. same_text(text, base_input_text)) then
          call reject(path, ' was written with a different base scene (its text has changed ' &
                      // 'since)', err)
          exit work
        end if
      end if
      call h5_read_int_attr(fid, '/', 'n_cases', n, why)
      ! An integer that does not read is "not a readable integer" like one of another type.
      if (why == H5_UNREADABLE) why = H5_BAD_TYPE
      call check_attr(this, 'n_cases', why, 'a readable integer', err)
      if (.not. err%ok()) exit work
      if (n < 1) then
        call err%set(ERR_INPUT, path // ": is not a sweep result file (attribute 'n_cases' is " &
                     // int_str(n) // ')' // not_sweep)
        exit work
      end if
      this%ncases = n

      call open_dataset(this, '/cases/status', H5T_INTEGER_F, this%status_id, err)
      ! Of any fixed length: files of flexmor 0.6 have 256 bytes (write_case cuts to the
      ! dataset's own length).
      call open_dataset(this, '/cases/message', H5T_STRING_F, this%message_id, err, &
                        fixed_string=.true.)
      call open_dataset(this, '/cases/wall_time_s', H5T_FLOAT_F, this%wall_id, err)
      call open_dataset(this, '/cases/rank', H5T_INTEGER_F, this%rank_id, err)
      if (.not. err%ok()) exit work
      ! The names come from a function: a local deferred-length array passed to group_members
      ! makes gfortran 12 -O2 read its length uninitialized.
      call check_float_datasets(this, '/cases/parameters/', &
        group_member_names(this, '/cases/parameters', err), err)
      if (.not. err%ok()) exit work
      call group_members(this, '/cases/metrics', this%metric_list, err)
      if (.not. err%ok()) exit work
      allocate(this%metric_ids(size(this%metric_list)))
      this%metric_ids = -1
      do j = 1, size(this%metric_list)
        call open_dataset(this, '/cases/metrics/' // trim(this%metric_list(j)), H5T_FLOAT_F, &
                          this%metric_ids(j), err)
      end do
      if (.not. err%ok()) exit work

      allocate(st(n))
      p = c_loc(st)
      call h5dread_f(this%status_id, h5kind_to_type(kind(st), H5_INTEGER_KIND), p, hdferr)
      if (hdferr < 0) then
        call err%set(ERR_INPUT, path // ": cannot read dataset '/cases/status' (damaged file?)" &
                     // not_sweep)
        exit work
      end if
      if (any(st < -1)) then
        call err%set(ERR_INPUT, path // ": dataset '/cases/status' holds values below -1, so " // &
                     'this is not a sweep result file' // not_sweep)
        exit work
      end if
      call move_alloc(st, this%case_status)
    end block work
    if (.not. err%ok()) call release(this)
  end procedure sf_open_existing

  module procedure release
    integer :: hdferr, j
    if (present(hdferr_out)) hdferr_out = 0
    if (allocated(this%metric_ids)) then
      do j = 1, size(this%metric_ids)
        call h5_close(this%metric_ids(j))
      end do
      deallocate(this%metric_ids)
    end if
    call h5_close(this%status_id)
    call h5_close(this%message_id)
    call h5_close(this%wall_id)
    call h5_close(this%rank_id)
    if (this%opened) then
      call h5fclose_f(this%file_id, hdferr)
      if (present(hdferr_out)) hdferr_out = hdferr
    end if
    this%file_id = -1
    this%opened = .false.
    this%ncases = 0
    if (allocated(this%metric_list)) deallocate(this%metric_list)
    if (allocated(this%case_status)) deallocate(this%case_status)
  end procedure release

  module procedure sync_or_fail
    type(error_t) :: e
    call sync_file(this%path, e)
    if (.not. e%ok()) call err%set(e%code, this%path // ': ' // e%message)
  end procedure sync_or_fail

  !> A file to resume that is not (or no longer) a sweep file of this sweep: an input error that
  !> names the file and says what to do.
  subroutine reject(path, what, err)
    character(len=*), intent(in) :: path, what
    type(error_t), intent(inout) :: err
    call err%set(ERR_INPUT, path // what // ': remove it or choose another -o')
  end subroutine reject

  !> `path` is an HDF5 file that did not open read-write: tell a damaged file (ERR_INPUT) from
  !> one another process holds open (HDF5's file lock) or that may not be written (ERR_IO).
  subroutine diagnose_open_failure(path, err)
    character(len=*), intent(in) :: path
    type(error_t), intent(inout) :: err
    logical :: readable, lockable
    call h5_probe_read_only(path, readable, lockable)
    if (.not. readable) then
      call reject(path, ' is damaged: it cannot be opened as HDF5 (was its creation ' // &
                  'interrupted?)', err)
    else if (.not. lockable) then
      call err%set(ERR_IO, path // ' is in use: another process (a running sweep?) has it ' // &
                   'open for writing')
    else
      call err%set(ERR_IO, path // ': cannot open the sweep result file for writing (is it ' // &
                   'read-only?)')
    end if
  end subroutine diagnose_open_failure

  !> The error for root attribute `name` that did not read (`why` from io_h5base); `expected`
  !> says what it should be ('a text').
  subroutine check_attr(this, name, why, expected, err)
    class(sweep_file_t), intent(in) :: this
    character(len=*), intent(in) :: name, expected
    integer, intent(in) :: why
    type(error_t), intent(inout) :: err
    select case (why)
    case (H5_MISSING)
      call reject(this%path, " is not a sweep result file (no attribute '" // name // "')", err)
    case (H5_UNOPENABLE)
      call reject(this%path, ": cannot open attribute '" // name // "' (damaged file?)", err)
    case (H5_BAD_TYPE)
      call reject(this%path, ": attribute '" // name // "' is not " // expected // ', so ' // &
                  'this is not a sweep result file', err)
    case (H5_UNREADABLE)
      call reject(this%path, ": cannot read attribute '" // name // "' (damaged file?)", err)
    end select
  end subroutine check_attr

  !> Open dataset `name`, check it is rank 1 with n_cases elements of type class `cls`, and with
  !> `fixed_string`, that they are fixed-length strings.
  subroutine open_dataset(this, name, cls, dset_id, err, fixed_string)
    class(sweep_file_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    integer, intent(in) :: cls
    integer(hid_t), intent(out) :: dset_id
    type(error_t), intent(inout) :: err
    logical, intent(in), optional :: fixed_string
    integer(hsize_t) :: n
    integer(size_t) :: type_size
    integer :: why, rank, tclass
    logical :: vl
    dset_id = -1
    if (.not. err%ok()) return
    call h5_open_dataset(this%file_id, name, dset_id, why)
    if (why == H5_MISSING) then
      call reject(this%path, " is not a complete sweep result file (no dataset '" // name // &
                  "'; was its creation interrupted?)", err)
      return
    else if (why /= H5_OK) then
      call reject(this%path, ": cannot open dataset '" // name // "' (damaged file?)", err)
      return
    end if
    call h5_dataset_shape(dset_id, rank, n, tclass, type_size, vl)
    if (rank /= 1 .or. n /= int(this%ncases, hsize_t) .or. tclass /= cls) then
      call reject(this%path, ": dataset '" // name // "' does not have the shape or type " // &
                  'of a sweep result file with ' // int_str(this%ncases) // ' cases', err)
    else if (present(fixed_string)) then
      if (fixed_string .and. (vl .or. type_size < 1)) &
        call reject(this%path, ": dataset '" // name // "' is not made of fixed-length " // &
                    'strings, so this is not a sweep result file', err)
    end if
  end subroutine open_dataset

  !> Every dataset prefix // names(j) must be a float dataset of n_cases elements; nothing is
  !> checked if err is already set.
  subroutine check_float_datasets(this, prefix, names, err)
    class(sweep_file_t), intent(inout) :: this
    character(len=*), intent(in) :: prefix, names(:)
    type(error_t), intent(inout) :: err
    integer(hid_t) :: did
    integer :: j
    if (.not. err%ok()) return
    do j = 1, size(names)
      call open_dataset(this, prefix // trim(names(j)), H5T_FLOAT_F, did, err)
      call h5_close(did)
    end do
  end subroutine check_float_datasets

  !> The members of `group` in creation order (empty, and err set, if it cannot be listed).
  function group_member_names(this, group, err) result(names)
    class(sweep_file_t), intent(inout) :: this
    character(len=*), intent(in) :: group
    type(error_t), intent(inout) :: err
    character(len=:), allocatable :: names(:)
    call group_members(this, group, names, err)
  end function group_member_names

  !> Names of the members of group `group` in creation order.
  subroutine group_members(this, group, names, err)
    class(sweep_file_t), intent(inout) :: this
    character(len=*), intent(in) :: group
    character(len=:), allocatable, intent(out) :: names(:)
    type(error_t), intent(inout) :: err
    integer :: why
    call h5_member_names(this%file_id, group, names, why)
    if (why == H5_MISSING) then
      call reject(this%path, " is not a complete sweep result file (no group '" // group // &
                  "')", err)
    else if (why /= H5_OK) then
      call reject(this%path, ": cannot list group '" // group // "' in creation order, so " // &
                  'this is not a sweep result file', err)
    end if
  end subroutine group_members

  !> Exact comparison (Fortran's == ignores trailing blanks).
  pure logical function same_text(a, b)
    character(len=*), intent(in) :: a, b
    same_text = len(a) == len(b)
    if (same_text) same_text = a == b
  end function same_text
end submodule io_sweep_file_open
