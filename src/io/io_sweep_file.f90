!> The result file of a parameter sweep (docs/sweep.md, "Result file"): one HDF5 file written by
!> one process (rank 0 of flexmor-sweep) with the serial (sec2) driver, one row per case.
!>
!> Usage:
!>
!>     type(sweep_file_t) :: f
!>     type(sweep_attrs_t) :: a
!>     a%sweep_input = text; a%mode = 'product'; ...               ! the root attributes
!>     call f%create('out.h5', a, ['dynamic.rtol'], values, ['max_tip_deflection'], err, &
!>                   metric_units=['m'])                            ! values(n_cases, n_params)
!>     ! or, to resume:  call f%open_existing('out.h5', text, err);  todo = f%status() == -1
!>     call f%write_case(icase, 0, '', wall_s, rank, metrics, err) ! durable on return
!>     call f%close(err)
!>
!> Crash safety (the point of this module). Everything that ever is in the file is created in
!> `create`, at its final size, before the first case: the root attributes, the groups and every
!> /cases dataset with n_cases elements, pre-filled with "not run" (status and rank -1, wall time
!> and metrics NaN, message empty). The datasets are contiguous with early allocation, so their
!> place in the file is fixed at creation; `create` ends with H5Fflush. From then on `write_case`
!> only overwrites bytes of existing datasets in place: no object header, group, heap, B-tree or
!> superblock changes, no file growth. The file uses the default (earliest) format, superblock
!> version 0, which has no "file is open for writing" flag, so a writer killed at any moment
!> (kill -9, the out-of-memory killer, a crash, mpirun tearing the job down) leaves a file that
!> HDF5 and h5py open normally with every case that `write_case` had returned from. Within a
!> case, the row's metrics, wall time, rank and message are written and flushed first and its
!> status last (and flushed again): a status other than -1 therefore means the whole row is on
!> disk, and a case cut in the middle still reads as not run (-1) and is run again on resume.
!> H5Fflush hands the data to the operating system, which survives the death of the process;
!> to survive a power loss or kernel crash too, pass `sync=.true.` to `create`/`open_existing`
!> (an fsync after every case: milliseconds on local disks, possibly much more on network file
!> systems).
!>
!> While the writer has the file open, HDF5 (1.10+) holds a lock on it: a second sweep on the
!> same file gets an "in use" error, and h5py opens it only with
!> `h5py.File(path, 'r', locking=False)` (or HDF5_USE_FILE_LOCKING=FALSE), which is safe here to
!> watch progress because no metadata changes after creation.
!>
!> The file is created under its final name (exclusively: an existing file is an error unless
!> `overwrite=.true.`), because it must exist while the sweep runs to be resumable. If `create`
!> fails, the half-made file is deleted. A file whose creation was interrupted is reported by
!> `open_existing` as damaged or not a sweep file (ERR_INPUT); it held no case yet.
!>
!> Strings: root attributes are scalar variable-length UTF-8 strings (h5py reads `str`),
!> /cases/message holds fixed-length NUL-padded strings of SWEEP_MESSAGE_LEN bytes (h5py reads
!> `bytes`; files of flexmor 0.6 have 256, and resume with them); longer messages are cut to
!> the dataset's length (at a UTF-8 character boundary). /cases/parameters and
!> /cases/metrics keep their datasets in creation order (h5py lists them in that order), which
!> is how `open_existing` recovers the order of the metrics for `write_case`.
!>
!> Errors come back in `err` with the path in the message: ERR_INPUT for bad names (empty,
!> containing '/', '.' or '..', repeated) and for a file that is not a sweep file of this sweep
!> (not HDF5, damaged, incomplete, other sweep input); ERR_IO for file system and HDF5 failures
!> (missing file, no permission, in use, write failures); ERR_INTERNAL for calls that break the
!> API contract (wrong sizes, case out of range, not open). Like io_hdf5, the HDF5 library is
!> initialised once if needed (never closed) and its automatic error printing is switched off;
!> the HDF5 calls both share (attributes, string types, dataset creation, reading) are in
!> io_h5base. All state is in the object; the module has none. Not thread-safe.
module io_sweep_file
  use, intrinsic :: iso_c_binding, only: c_ptr, c_loc, c_null_ptr, c_associated
  use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
  use hdf5, only: hid_t, hsize_t, h5fcreate_f, h5fflush_f, H5F_ACC_TRUNC_F, H5F_ACC_EXCL_F, &
    H5F_SCOPE_GLOBAL_F, h5pcreate_f, H5P_DATASET_CREATE_F, h5pset_layout_f, H5D_CONTIGUOUS_F, &
    h5pset_alloc_time_f, H5D_ALLOC_TIME_EARLY_F, h5pset_fill_time_f, H5D_FILL_TIME_ALLOC_F, &
    h5pset_fill_value_f, h5pset_obj_track_times_f, h5kind_to_type, H5T_IEEE_F64LE, &
    H5T_STD_I32LE, H5_REAL_KIND, H5_INTEGER_KIND
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_INPUT, ERR_IO, ERR_INTERNAL
  use core_strings, only: int_str
  use io_namelist, only: string_t
  use io_fs, only: delete_file, check_output_path
  use io_h5base, only: h5_init, h5_close, h5_string_type, h5_put_string_attr, h5_put_int_attr, &
    h5_create_dataset, h5_create_group, h5_check_names, h5_write_element
  implicit none
  private
  public :: sweep_file_t, sweep_attrs_t, SWEEP_MESSAGE_LEN

  !> Bytes of one /cases/message entry: room for a failure's whole message with its cause
  !> (a kinematic failure at a singular configuration takes about 400).
  integer, parameter :: SWEEP_MESSAGE_LEN = 1024

  !> The root attributes of a sweep file. Strings left unallocated are written as ''.
  !> n_cases and n_parameters are taken from the shape of the parameter values given to
  !> `create`; left at -1 they need not be set, otherwise they must agree.
  type :: sweep_attrs_t
    character(len=:), allocatable :: flexmor_version
    character(len=:), allocatable :: sweep_input   !< text of the sweep file (checked on resume)
    character(len=:), allocatable :: sweep_file    !< its path
    character(len=:), allocatable :: base_input    !< text of the base scene
    character(len=:), allocatable :: base_scene    !< its path
    character(len=:), allocatable :: mode          !< product, zip, random, lhs
    integer :: n_cases = -1
    integer :: n_parameters = -1
    integer :: seed = 1
    character(len=:), allocatable :: node
    character(len=:), allocatable :: title
    !> The folder of the cases' own result files ('' when they are not written).
    character(len=:), allocatable :: case_files
  end type sweep_attrs_t

  !> One open sweep result file. Components are private; use the type-bound procedures.
  type :: sweep_file_t
    private
    integer(hid_t) :: file_id = -1
    logical :: opened = .false.
    logical :: do_sync = .false.               !< fsync after every case
    character(len=:), allocatable :: path
    integer :: ncases = 0
    integer(hid_t) :: status_id = -1, message_id = -1, wall_id = -1, rank_id = -1
    integer(hid_t), allocatable :: metric_ids(:)
    character(len=:), allocatable :: metric_list(:)
    integer, allocatable :: case_status(:)     !< copy of /cases/status
  contains
    procedure, private :: sf_create, sf_create_strings
    !> `create(path, attrs, param_names(:), param_values(n_cases, n_params), metric_names(:),
    !> err [, metric_units(:)] [, overwrite] [, sync])`: make the complete file, flushed.
    !> param_names: character array or type(string_t) array (io_namelist).
    generic :: create => sf_create, sf_create_strings
    !> `open_existing(path, sweep_input_text, err [, base_input_text] [, sync])`: reopen a sweep
    !> file read-write to resume it; ERR_INPUT unless it is an intact sweep file whose
    !> 'sweep_input' (and 'base_input', if given) attribute equals the text.
    procedure :: open_existing => sf_open_existing
    !> `status()`: /cases/status (n_cases): -1 not run yet, 0 ok, else the exit code of the
    !> failure. Read from the file on open, kept current by write_case; empty when not open.
    procedure :: status => sf_status
    !> `write_case(icase, status, message, wall_time_s, rank, metrics(:), err)`: write row
    !> icase (1-based) of every /cases dataset, status last; flushed when it returns.
    procedure :: write_case => sf_write_case
    !> `close([err])`: flush and close; safe in any state.
    procedure :: close => sf_close
    !> `is_open()`
    procedure :: is_open => sf_is_open
    !> `n_cases()`: number of cases (0 when not open).
    procedure :: n_cases => sf_n_cases
    !> `metric_names()`: the metrics in the order write_case takes them (blank-padded).
    procedure :: metric_names => sf_metric_names
  end type sweep_file_t

  interface
    module subroutine sf_open_existing(this, path, sweep_input_text, err, base_input_text, sync)
      class(sweep_file_t), intent(inout) :: this
      character(len=*), intent(in) :: path
      character(len=*), intent(in) :: sweep_input_text
      type(error_t), intent(out) :: err
      character(len=*), intent(in), optional :: base_input_text
      logical, intent(in), optional :: sync
    end subroutine sf_open_existing
    !> Close every id held and forget the file (its path stays for messages); reports the
    !> file close status in `hdferr_out`.
    module subroutine release(this, hdferr_out)
      class(sweep_file_t), intent(inout) :: this
      integer, intent(out), optional :: hdferr_out
    end subroutine release
    module subroutine sync_or_fail(this, err)
      class(sweep_file_t), intent(inout) :: this
      type(error_t), intent(inout) :: err
    end subroutine sync_or_fail
  end interface

contains

  ! ---------------------------------------------------------------------------------------------
  ! create

  subroutine sf_create(this, path, attrs, param_names, param_values, metric_names, err, &
                       metric_units, overwrite, sync)
    class(sweep_file_t), intent(inout) :: this
    character(len=*), intent(in) :: path
    type(sweep_attrs_t), intent(in) :: attrs
    character(len=*), intent(in) :: param_names(:)
    real(wp), intent(in) :: param_values(:, :)
    character(len=*), intent(in) :: metric_names(:)
    type(error_t), intent(out) :: err
    character(len=*), intent(in), optional :: metric_units(:)
    logical, intent(in), optional :: overwrite
    logical, intent(in), optional :: sync
    character(len=*), parameter :: no_create = ': cannot create the sweep file: '
    character(len=:), allocatable :: name
    integer :: n, np, nm, j, hdferr, access
    logical :: exists, replace
    integer(hid_t) :: pid, real_type, int_type, msg_type
    integer, target :: minus_one
    real(wp), target :: nan
    real(wp), allocatable, target :: column(:)

    if (this%opened) then
      call err%set(ERR_INTERNAL, path // ": cannot create a sweep file: this object still has '" &
                   // this%path // "' open")
      return
    end if
    if (len_trim(path) == 0) then
      call err%set(ERR_IO, 'cannot create a sweep result file with an empty name')
      return
    end if
    n = size(param_values, 1)
    np = size(param_values, 2)
    nm = size(metric_names)
    if (size(param_names) /= np) then
      call err%set(ERR_INTERNAL, path // no_create // int_str(np) // ' parameter columns but ' &
                   // int_str(size(param_names)) // ' names')
      return
    end if
    if (n < 1) then
      call err%set(ERR_INPUT, path // no_create // 'the sweep has no case')
      return
    end if
    if ((attrs%n_cases /= -1 .and. attrs%n_cases /= n) .or. &
        (attrs%n_parameters /= -1 .and. attrs%n_parameters /= np)) then
      call err%set(ERR_INTERNAL, path // no_create // 'attributes n_cases/n_parameters ' // &
                   'disagree with the parameter values (' // int_str(n) // ' x ' // &
                   int_str(np) // ')')
      return
    end if
    if (present(metric_units)) then
      if (size(metric_units) /= nm) then
        call err%set(ERR_INTERNAL, path // no_create // int_str(nm) // ' metrics but ' // &
                     int_str(size(metric_units)) // ' units')
        return
      end if
    end if
    call h5_check_names(path, 'parameter', param_names, err)
    call h5_check_names(path, 'metric', metric_names, err)
    if (.not. err%ok()) return

    replace = .false.
    if (present(overwrite)) replace = overwrite
    inquire(file=path, exist=exists)
    if (exists .and. .not. replace) then
      call err%set(ERR_IO, path // ': cannot create the sweep result file: it exists already ' // &
                   '(resume it with the same sweep file, or remove it)')
      return
    end if

    call h5_init(path, err)
    if (.not. err%ok()) return
    access = H5F_ACC_EXCL_F
    if (replace) access = H5F_ACC_TRUNC_F
    call h5fcreate_f(path, access, this%file_id, hdferr)
    if (hdferr < 0) then
      this%file_id = -1
      call check_output_path(path, err)
      if (err%ok()) call err%set(ERR_IO, path // ': cannot create the sweep result file ' // &
                                 '(does the folder exist and is it writable?)')
      return
    end if
    this%path = path
    this%opened = .true.
    this%ncases = n
    this%do_sync = .false.
    if (present(sync)) this%do_sync = sync
    allocate(this%metric_ids(nm))
    this%metric_ids = -1
    allocate(character(len=max(1, maxval([0, (len_trim(adjustl(metric_names(j))), j = 1, nm)]))) &
             :: this%metric_list(nm))
    do j = 1, nm
      this%metric_list(j) = trim(adjustl(metric_names(j)))
    end do
    allocate(this%case_status(n), source=-1)

    minus_one = -1
    nan = ieee_value(1.0_wp, ieee_quiet_nan)
    real_type = h5kind_to_type(wp, H5_REAL_KIND)
    int_type = h5kind_to_type(kind(minus_one), H5_INTEGER_KIND)
    ! Every helper below does nothing once `err` holds an error, so checking now and then is
    ! enough: the first failure is the one reported.
    work: block
      ! Root attributes.
      call put_root_text(this, 'flexmor_version', attrs%flexmor_version, err)
      call put_root_text(this, 'sweep_input', attrs%sweep_input, err)
      call put_root_text(this, 'sweep_file', attrs%sweep_file, err)
      call put_root_text(this, 'base_input', attrs%base_input, err)
      call put_root_text(this, 'base_scene', attrs%base_scene, err)
      call put_root_text(this, 'mode', attrs%mode, err)
      call h5_put_int_attr(path, this%file_id, '/', 'n_cases', n, err)
      call h5_put_int_attr(path, this%file_id, '/', 'n_parameters', np, err)
      call h5_put_int_attr(path, this%file_id, '/', 'seed', attrs%seed, err)
      call put_root_text(this, 'node', attrs%node, err)
      call put_root_text(this, 'title', attrs%title, err)
      if (allocated(attrs%case_files)) call put_root_text(this, 'case_files', &
        attrs%case_files, err)

      ! Groups: the named datasets keep their creation order.
      call h5_create_group(path, this%file_id, '/cases', .false., err)
      call h5_create_group(path, this%file_id, '/cases/parameters', .true., err)
      call h5_create_group(path, this%file_id, '/cases/metrics', .true., err)
      if (.not. err%ok()) exit work

      allocate(column(n))
      do j = 1, np
        column = param_values(:, j)
        call make_dataset(this, '/cases/parameters/' // trim(adjustl(param_names(j))), &
                          H5T_IEEE_F64LE, real_type, c_null_ptr, pid, err, data=c_loc(column))
        call h5_close(pid)
      end do

      call make_dataset(this, '/cases/status', H5T_STD_I32LE, int_type, c_loc(minus_one), &
                        this%status_id, err)
      ! /cases/message: fixed-length UTF-8 strings, written in place by write_case. The default
      ! fill value of a string type is all zero bytes: every message starts empty.
      call h5_string_type(msg_type, hdferr, SWEEP_MESSAGE_LEN)
      if (hdferr < 0) call err%set(ERR_IO, path // ": cannot make the string type of " // &
                                   "'/cases/message'")
      call make_dataset(this, '/cases/message', msg_type, msg_type, c_null_ptr, this%message_id, &
                        err)
      call h5_close(msg_type)
      call make_dataset(this, '/cases/wall_time_s', H5T_IEEE_F64LE, real_type, c_loc(nan), &
                        this%wall_id, err)
      call h5_put_string_attr(path, this%wall_id, '/cases/wall_time_s', 'units', 's', err)
      call make_dataset(this, '/cases/rank', H5T_STD_I32LE, int_type, c_loc(minus_one), &
                        this%rank_id, err)
      do j = 1, nm
        name = '/cases/metrics/' // trim(this%metric_list(j))
        call make_dataset(this, name, H5T_IEEE_F64LE, real_type, c_loc(nan), this%metric_ids(j), &
                          err)
        if (present(metric_units)) then
          if (len_trim(metric_units(j)) > 0) &
            call h5_put_string_attr(path, this%metric_ids(j), name, 'units', &
                                    trim(metric_units(j)), err)
        end if
      end do
      if (.not. err%ok()) exit work

      call h5fflush_f(this%file_id, H5F_SCOPE_GLOBAL_F, hdferr)
      if (hdferr < 0) then
        call err%set(ERR_IO, path // ': cannot flush the new sweep result file')
        exit work
      end if
      if (this%do_sync) call sync_or_fail(this, err)
    end block work
    if (.not. err%ok()) then
      ! Nothing of value is in it yet: remove the half-made file.
      call release(this)
      call delete_file(path)
    end if
  end subroutine sf_create

  !> `create` with the parameter names as string_t (as the sweep reader keeps them).
  subroutine sf_create_strings(this, path, attrs, param_names, param_values, metric_names, err, &
                               metric_units, overwrite, sync)
    class(sweep_file_t), intent(inout) :: this
    character(len=*), intent(in) :: path
    type(sweep_attrs_t), intent(in) :: attrs
    type(string_t), intent(in) :: param_names(:)
    real(wp), intent(in) :: param_values(:, :)
    character(len=*), intent(in) :: metric_names(:)
    type(error_t), intent(out) :: err
    character(len=*), intent(in), optional :: metric_units(:)
    logical, intent(in), optional :: overwrite
    logical, intent(in), optional :: sync
    integer :: j, longest
    longest = 1
    do j = 1, size(param_names)
      if (allocated(param_names(j)%s)) longest = max(longest, len(param_names(j)%s))
    end do
    block
      character(len=longest) :: names(size(param_names))
      do j = 1, size(param_names)
        names(j) = ''
        if (allocated(param_names(j)%s)) names(j) = param_names(j)%s
      end do
      call sf_create(this, path, attrs, names, param_values, metric_names, err, metric_units, &
                     overwrite, sync)
    end block
  end subroutine sf_create_strings


  ! ---------------------------------------------------------------------------------------------
  ! write_case, status, close, getters

  subroutine sf_write_case(this, icase, status, message, wall_time_s, rank, metrics, err)
    class(sweep_file_t), intent(inout) :: this
    integer, intent(in) :: icase, status
    character(len=*), intent(in) :: message
    real(wp), intent(in) :: wall_time_s
    integer, intent(in) :: rank
    real(wp), intent(in) :: metrics(:)
    type(error_t), intent(out) :: err
    integer :: j
    character(len=:), allocatable :: where

    if (.not. this%opened) then
      call err%set(ERR_INTERNAL, 'cannot write a sweep case: the sweep result file is not open')
      return
    end if
    where = this%path // ': case ' // int_str(icase)
    if (icase < 1 .or. icase > this%ncases) then
      call err%set(ERR_INTERNAL, where // ': no such case (the file has ' // &
                   int_str(this%ncases) // ')')
      return
    end if
    if (status < 0) then
      call err%set(ERR_INTERNAL, where // ': status ' // int_str(status) // ' is not a result')
      return
    end if
    if (size(metrics) /= size(this%metric_ids)) then
      call err%set(ERR_INTERNAL, where // ': ' // int_str(size(metrics)) // ' metrics given, ' &
                   // 'the file has ' // int_str(size(this%metric_ids)))
      return
    end if

    ! The row without its status, flushed; then the status, flushed: status /= -1 on disk means
    ! the row is complete (HDF5 keeps small writes to contiguous datasets in a sieve buffer until
    ! a flush, in no particular order). Each call below does nothing once `err` is set, so the
    ! status is never written after a part of the row or its flush failed.
    do j = 1, size(metrics)
      call h5_write_element(where, this%metric_ids(j), '/cases/metrics/' // &
                            trim(this%metric_list(j)), icase, metrics(j), err)
    end do
    call h5_write_element(where, this%wall_id, '/cases/wall_time_s', icase, wall_time_s, err)
    call h5_write_element(where, this%rank_id, '/cases/rank', icase, rank, err)
    call h5_write_element(where, this%message_id, '/cases/message', icase, message, err)
    call flush_or_fail(this, err)

    call h5_write_element(where, this%status_id, '/cases/status', icase, status, err)
    call flush_or_fail(this, err)
    if (this%do_sync .and. err%ok()) call sync_or_fail(this, err)
    if (err%ok()) this%case_status(icase) = status
  end subroutine sf_write_case

  function sf_status(this) result(st)
    class(sweep_file_t), intent(in) :: this
    integer, allocatable :: st(:)
    if (this%opened .and. allocated(this%case_status)) then
      st = this%case_status
    else
      allocate(st(0))
    end if
  end function sf_status

  !> Close the datasets and the file (flushing it). Safe to call in any state and twice; a
  !> failure to flush or close is reported in `err` if present (the file is closed anyway).
  subroutine sf_close(this, err)
    class(sweep_file_t), intent(inout) :: this
    type(error_t), intent(out), optional :: err
    type(error_t) :: e
    integer :: hdferr
    logical :: want_sync
    if (.not. this%opened) return
    want_sync = this%do_sync
    call flush_or_fail(this, e)
    call release(this, hdferr)
    if (hdferr < 0) call e%set(ERR_IO, this%path // ': cannot close the sweep result file')
    if (want_sync .and. e%ok()) call sync_or_fail(this, e)
    if (present(err)) err = e
  end subroutine sf_close

  logical function sf_is_open(this)
    class(sweep_file_t), intent(in) :: this
    sf_is_open = this%opened
  end function sf_is_open

  integer function sf_n_cases(this)
    class(sweep_file_t), intent(in) :: this
    sf_n_cases = 0
    if (this%opened) sf_n_cases = this%ncases
  end function sf_n_cases

  function sf_metric_names(this) result(names)
    class(sweep_file_t), intent(in) :: this
    character(len=:), allocatable :: names(:)
    if (this%opened .and. allocated(this%metric_list)) then
      names = this%metric_list
    else
      allocate(character(len=1) :: names(0))
    end if
  end function sf_metric_names

  ! ---------------------------------------------------------------------------------------------
  ! Internals (the rest are in io_sweep_file_open)

  subroutine flush_or_fail(this, err)
    class(sweep_file_t), intent(inout) :: this
    type(error_t), intent(inout) :: err
    integer :: hdferr
    if (.not. err%ok()) return
    call h5fflush_f(this%file_id, H5F_SCOPE_GLOBAL_F, hdferr)
    if (hdferr < 0) call err%set(ERR_IO, this%path // ': cannot flush the sweep result file')
  end subroutine flush_or_fail


  !> Root attribute `name` = `text` ('' when unallocated), a variable-length string.
  subroutine put_root_text(this, name, text, err)
    class(sweep_file_t), intent(in) :: this
    character(len=*), intent(in) :: name
    character(len=:), allocatable, intent(in) :: text
    type(error_t), intent(inout) :: err
    if (allocated(text)) then
      call h5_put_string_attr(this%path, this%file_id, '/', name, text, err)
    else
      call h5_put_string_attr(this%path, this%file_id, '/', name, '', err)
    end if
  end subroutine put_root_text

  !> Create the rank-1 dataset `name` of n_cases elements to be overwritten in place (see "Crash
  !> safety" above) and return it open: contiguous, allocated at creation with `*fill` (of memory
  !> type `mem_type`; the type's default if null) written then, no time stamps (nothing in the
  !> object header ever changes, and files are reproducible); `data` (n_cases values of
  !> `mem_type`) is written into it if given.
  subroutine make_dataset(this, name, file_type, mem_type, fill, dset_id, err, data)
    class(sweep_file_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    integer(hid_t), intent(in) :: file_type, mem_type
    type(c_ptr), intent(in) :: fill
    integer(hid_t), intent(out) :: dset_id
    type(error_t), intent(inout) :: err
    type(c_ptr), intent(in), optional :: data
    integer(hid_t) :: dcpl
    integer :: hdferr
    dset_id = -1
    if (.not. err%ok()) return
    call h5pcreate_f(H5P_DATASET_CREATE_F, dcpl, hdferr)
    if (hdferr < 0) dcpl = -1
    if (hdferr == 0) call h5pset_layout_f(dcpl, H5D_CONTIGUOUS_F, hdferr)
    if (hdferr == 0) call h5pset_alloc_time_f(dcpl, H5D_ALLOC_TIME_EARLY_F, hdferr)
    if (hdferr == 0) call h5pset_fill_time_f(dcpl, H5D_FILL_TIME_ALLOC_F, hdferr)
    if (hdferr == 0) call h5pset_obj_track_times_f(dcpl, .false., hdferr)
    if (hdferr == 0 .and. c_associated(fill)) call h5pset_fill_value_f(dcpl, mem_type, fill, &
                                                                        hdferr)
    if (hdferr < 0) then
      call err%set(ERR_IO, this%path // ": cannot create dataset '" // name // "'")
    else
      call h5_create_dataset(this%path, this%file_id, name, [int(this%ncases, hsize_t)], &
                             file_type, dset_id, err, dcpl=dcpl, mem_type=mem_type, data=data)
    end if
    call h5_close(dcpl)
  end subroutine make_dataset

end module io_sweep_file
