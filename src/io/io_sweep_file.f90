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
!> /cases/message holds fixed-length 256-byte NUL-padded strings (h5py reads `bytes`); longer
!> messages are cut to 256 bytes (at a UTF-8 character boundary). /cases/parameters and
!> /cases/metrics keep their datasets in creation order (h5py lists them in that order), which
!> is how `open_existing` recovers the order of the metrics for `write_case`.
!>
!> Errors come back in `err` with the path in the message: ERR_INPUT for bad names (empty,
!> containing '/', '.' or '..', repeated) and for a file that is not a sweep file of this sweep
!> (not HDF5, damaged, incomplete, other sweep input); ERR_IO for file system and HDF5 failures
!> (missing file, no permission, in use, write failures); ERR_INTERNAL for calls that break the
!> API contract (wrong sizes, case out of range, not open). Like io_hdf5, the HDF5 library is
!> initialised once if needed (never closed) and its automatic error printing is switched off.
!> All state is in the object; the module has none. Not thread-safe.
module io_sweep_file
  use, intrinsic :: iso_c_binding, only: c_ptr, c_loc, c_null_ptr, c_char, c_null_char, &
    c_size_t, c_associated, c_f_pointer
  use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
  use hdf5, only: hid_t, hsize_t, size_t, h5open_f, h5iis_valid_f, h5eset_auto_f, &
    H5T_NATIVE_DOUBLE, h5fcreate_f, h5fopen_f, h5fflush_f, h5fclose_f, h5fis_hdf5_f, &
    H5F_ACC_TRUNC_F, H5F_ACC_EXCL_F, H5F_ACC_RDWR_F, H5F_ACC_RDONLY_F, H5F_SCOPE_GLOBAL_F, &
    h5screate_f, h5screate_simple_f, h5sclose_f, h5sselect_hyperslab_f, H5S_SCALAR_F, &
    H5S_SELECT_SET_F, h5dget_space_f, h5sget_simple_extent_ndims_f, &
    h5sget_simple_extent_dims_f, h5sget_simple_extent_type_f, &
    h5pcreate_f, h5pclose_f, H5P_DATASET_CREATE_F, H5P_GROUP_CREATE_F, h5pset_layout_f, &
    H5P_FILE_ACCESS_F, h5pset_file_locking_f, &
    H5D_CONTIGUOUS_F, h5pset_alloc_time_f, H5D_ALLOC_TIME_EARLY_F, h5pset_fill_time_f, &
    H5D_FILL_TIME_ALLOC_F, h5pset_fill_value_f, h5pset_obj_track_times_f, &
    h5pset_link_creation_order_f, H5P_CRT_ORDER_TRACKED_F, H5P_CRT_ORDER_INDEXED_F, &
    h5gcreate_f, h5gclose_f, h5gget_info_by_name_f, h5lget_name_by_idx_f, h5lexists_f, &
    H5_INDEX_CRT_ORDER_F, H5_ITER_INC_F, &
    h5dcreate_f, h5dopen_f, h5dwrite_f, h5dread_f, h5dclose_f, h5dget_type_f, &
    h5acreate_f, h5awrite_f, h5aread_f, h5aclose_f, h5aexists_by_name_f, h5aopen_by_name_f, &
    h5aget_type_f, h5aget_space_f, h5dvlen_reclaim_f, H5P_DEFAULT_F, &
    h5tcopy_f, h5tset_cset_f, h5tset_strpad_f, h5tset_size_f, h5tget_size_f, h5tclose_f, &
    h5tget_class_f, h5tis_variable_str_f, h5kind_to_type, &
    H5T_STRING, H5T_C_S1, H5T_CSET_UTF8_F, H5T_STR_NULLTERM_F, H5T_STR_NULLPAD_F, &
    H5T_IEEE_F64LE, H5T_STD_I32LE, H5T_INTEGER_F, H5T_FLOAT_F, H5T_STRING_F, &
    H5_REAL_KIND, H5_INTEGER_KIND
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_INPUT, ERR_IO, ERR_INTERNAL
  use io_namelist, only: string_t
  use io_fs, only: delete_file, sync_file
  implicit none
  private
  public :: sweep_file_t, sweep_attrs_t, SWEEP_MESSAGE_LEN

  !> Bytes of one /cases/message entry.
  integer, parameter :: SWEEP_MESSAGE_LEN = 256

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
    pure integer(c_size_t) function c_strlen(s) bind(C, name='strlen')
      import :: c_ptr, c_size_t
      type(c_ptr), value, intent(in) :: s
    end function c_strlen
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
    integer :: n, np, nm, j, hdferr, close_err
    logical :: exists, replace
    integer(hid_t) :: pid
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
      call err%set(ERR_INTERNAL, path // ': cannot create the sweep file: ' // int_text(np) // &
                   ' parameter columns but ' // int_text(size(param_names)) // ' names')
      return
    end if
    if (n < 1) then
      call err%set(ERR_INPUT, path // ': cannot create the sweep file: the sweep has no case')
      return
    end if
    if ((attrs%n_cases /= -1 .and. attrs%n_cases /= n) .or. &
        (attrs%n_parameters /= -1 .and. attrs%n_parameters /= np)) then
      call err%set(ERR_INTERNAL, path // ': cannot create the sweep file: attributes n_cases/' // &
                   'n_parameters disagree with the parameter values (' // int_text(n) // ' x ' // &
                   int_text(np) // ')')
      return
    end if
    if (present(metric_units)) then
      if (size(metric_units) /= nm) then
        call err%set(ERR_INTERNAL, path // ': cannot create the sweep file: ' // int_text(nm) // &
                     ' metrics but ' // int_text(size(metric_units)) // ' units')
        return
      end if
    end if
    call check_names(path, 'parameter', param_names, err)
    if (.not. err%ok()) return
    call check_names(path, 'metric', metric_names, err)
    if (.not. err%ok()) return

    replace = .false.
    if (present(overwrite)) replace = overwrite
    inquire(file=path, exist=exists)
    if (exists .and. .not. replace) then
      call err%set(ERR_IO, path // ': cannot create the sweep result file: it exists already ' // &
                   '(resume it with the same sweep file, or remove it)')
      return
    end if

    call ensure_hdf5(hdferr)
    if (hdferr < 0) then
      call err%set(ERR_IO, path // ': cannot initialise the HDF5 library')
      return
    end if
    call h5eset_auto_f(0, hdferr)

    if (replace) then
      call h5fcreate_f(path, H5F_ACC_TRUNC_F, this%file_id, hdferr)
    else
      call h5fcreate_f(path, H5F_ACC_EXCL_F, this%file_id, hdferr)
    end if
    if (hdferr < 0) then
      this%file_id = -1
      call err%set(ERR_IO, path // ': cannot create the sweep result file (does the folder ' // &
                   'exist and is it writable?)')
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
    work: block
      ! Root attributes.
      call put_string_attr(this, this%file_id, 'flexmor_version', opt_text(attrs%flexmor_version), &
                           err)
      call put_string_attr(this, this%file_id, 'sweep_input', opt_text(attrs%sweep_input), err)
      call put_string_attr(this, this%file_id, 'sweep_file', opt_text(attrs%sweep_file), err)
      call put_string_attr(this, this%file_id, 'base_input', opt_text(attrs%base_input), err)
      call put_string_attr(this, this%file_id, 'base_scene', opt_text(attrs%base_scene), err)
      call put_string_attr(this, this%file_id, 'mode', opt_text(attrs%mode), err)
      call put_int_attr(this, this%file_id, 'n_cases', n, err)
      call put_int_attr(this, this%file_id, 'n_parameters', np, err)
      call put_int_attr(this, this%file_id, 'seed', attrs%seed, err)
      call put_string_attr(this, this%file_id, 'node', opt_text(attrs%node), err)
      call put_string_attr(this, this%file_id, 'title', opt_text(attrs%title), err)
      if (.not. err%ok()) exit work

      ! Groups: the named datasets keep their creation order.
      call make_group(this, '/cases', .false., err)
      call make_group(this, '/cases/parameters', .true., err)
      call make_group(this, '/cases/metrics', .true., err)
      if (.not. err%ok()) exit work

      allocate(column(n))
      do j = 1, np
        column = param_values(:, j)
        call make_dataset(this, '/cases/parameters/' // trim(adjustl(param_names(j))), &
                          H5T_IEEE_F64LE, h5kind_to_type(wp, H5_REAL_KIND), c_null_ptr, pid, err)
        if (.not. err%ok()) exit work
        call h5dwrite_f(pid, h5kind_to_type(wp, H5_REAL_KIND), c_loc(column), hdferr)
        call h5dclose_f(pid, close_err)
        if (hdferr < 0 .or. close_err < 0) then
          call err%set(ERR_IO, path // ": cannot write dataset '/cases/parameters/" // &
                       trim(adjustl(param_names(j))) // "'")
          exit work
        end if
      end do

      call make_dataset(this, '/cases/status', H5T_STD_I32LE, &
                        h5kind_to_type(kind(minus_one), H5_INTEGER_KIND), c_loc(minus_one), &
                        this%status_id, err)
      if (.not. err%ok()) exit work
      call make_message_dataset(this, err)
      if (.not. err%ok()) exit work
      call make_dataset(this, '/cases/wall_time_s', H5T_IEEE_F64LE, &
                        h5kind_to_type(wp, H5_REAL_KIND), c_loc(nan), this%wall_id, err)
      if (.not. err%ok()) exit work
      call put_string_attr(this, this%wall_id, 'units', 's', err, '/cases/wall_time_s')
      call make_dataset(this, '/cases/rank', H5T_STD_I32LE, &
                        h5kind_to_type(kind(minus_one), H5_INTEGER_KIND), c_loc(minus_one), &
                        this%rank_id, err)
      if (.not. err%ok()) exit work
      do j = 1, nm
        call make_dataset(this, '/cases/metrics/' // trim(this%metric_list(j)), H5T_IEEE_F64LE, &
                          h5kind_to_type(wp, H5_REAL_KIND), c_loc(nan), this%metric_ids(j), err)
        if (.not. err%ok()) exit work
        if (present(metric_units)) then
          if (len_trim(metric_units(j)) > 0) &
            call put_string_attr(this, this%metric_ids(j), 'units', trim(metric_units(j)), err, &
                                 '/cases/metrics/' // trim(this%metric_list(j)))
        end if
        if (.not. err%ok()) exit work
      end do

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
    character(len=:), allocatable :: names(:)
    integer :: j, longest
    longest = 1
    do j = 1, size(param_names)
      if (allocated(param_names(j)%s)) longest = max(longest, len(param_names(j)%s))
    end do
    allocate(character(len=longest) :: names(size(param_names)))
    do j = 1, size(param_names)
      names(j) = ''
      if (allocated(param_names(j)%s)) names(j) = param_names(j)%s
    end do
    call sf_create(this, path, attrs, names, param_values, metric_names, err, metric_units, &
                   overwrite, sync)
  end subroutine sf_create_strings

  ! ---------------------------------------------------------------------------------------------
  ! open_existing

  subroutine sf_open_existing(this, path, sweep_input_text, err, base_input_text, sync)
    class(sweep_file_t), intent(inout) :: this
    character(len=*), intent(in) :: path
    character(len=*), intent(in) :: sweep_input_text
    type(error_t), intent(out) :: err
    character(len=*), intent(in), optional :: base_input_text
    logical, intent(in), optional :: sync
    character(len=*), parameter :: not_sweep = ' (remove it or choose another -o)'
    character(len=:), allocatable :: text, names(:)
    integer(hid_t) :: fid
    integer :: hdferr, n, j
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
    call ensure_hdf5(hdferr)
    if (hdferr < 0) then
      call err%set(ERR_IO, path // ': cannot initialise the HDF5 library')
      return
    end if
    call h5eset_auto_f(0, hdferr)

    call h5fis_hdf5_f(path, is_h5, hdferr)
    if (hdferr < 0) then
      call err%set(ERR_IO, path // ': cannot read the file (is it readable?)')
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
      call get_string_attr(this, 'sweep_input', text, err)
      if (.not. err%ok()) exit work
      if (.not. same_text(text, sweep_input_text)) then
        call err%set(ERR_INPUT, path // ' was written by a different sweep file: remove it or ' // &
                     'choose another -o')
        exit work
      end if
      if (present(base_input_text)) then
        call get_string_attr(this, 'base_input', text, err)
        if (.not. err%ok()) exit work
        if (.not. same_text(text, base_input_text)) then
          call err%set(ERR_INPUT, path // ' was written with a different base scene (its text ' &
                       // 'has changed since): remove it or choose another -o')
          exit work
        end if
      end if
      call get_int_attr(this, 'n_cases', n, err)
      if (.not. err%ok()) exit work
      if (n < 1) then
        call err%set(ERR_INPUT, path // ": is not a sweep result file (attribute 'n_cases' is " &
                     // int_text(n) // ')' // not_sweep)
        exit work
      end if
      this%ncases = n

      call open_dataset(this, '/cases/status', H5T_INTEGER_F, this%status_id, err)
      call open_dataset(this, '/cases/message', H5T_STRING_F, this%message_id, err)
      call open_dataset(this, '/cases/wall_time_s', H5T_FLOAT_F, this%wall_id, err)
      call open_dataset(this, '/cases/rank', H5T_INTEGER_F, this%rank_id, err)
      if (.not. err%ok()) exit work
      call check_message_type(this, err)
      if (.not. err%ok()) exit work

      call group_members(this, '/cases/parameters', names, err)
      if (.not. err%ok()) exit work
      do j = 1, size(names)
        call check_dataset(this, '/cases/parameters/' // trim(names(j)), H5T_FLOAT_F, err)
      end do
      call group_members(this, '/cases/metrics', names, err)
      if (.not. err%ok()) exit work
      this%metric_list = names
      allocate(this%metric_ids(size(names)))
      this%metric_ids = -1
      do j = 1, size(names)
        call open_dataset(this, '/cases/metrics/' // trim(names(j)), H5T_FLOAT_F, &
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
  end subroutine sf_open_existing

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
    character(len=SWEEP_MESSAGE_LEN), target :: msg
    real(wp), target :: r
    integer, target :: i
    integer(hid_t) :: msg_type
    integer :: j, hdferr
    character(len=:), allocatable :: where

    if (.not. this%opened) then
      call err%set(ERR_INTERNAL, 'cannot write a sweep case: the sweep result file is not open')
      return
    end if
    where = this%path // ': case ' // int_text(icase)
    if (icase < 1 .or. icase > this%ncases) then
      call err%set(ERR_INTERNAL, where // ': no such case (the file has ' // &
                   int_text(this%ncases) // ')')
      return
    end if
    if (status < 0) then
      call err%set(ERR_INTERNAL, where // ': status ' // int_text(status) // ' is not a result')
      return
    end if
    if (size(metrics) /= size(this%metric_ids)) then
      call err%set(ERR_INTERNAL, where // ': ' // int_text(size(metrics)) // ' metrics given, ' &
                   // 'the file has ' // int_text(size(this%metric_ids)))
      return
    end if

    ! The row without its status, flushed; then the status, flushed: status /= -1 on disk means
    ! the row is complete (HDF5 keeps small writes to contiguous datasets in a sieve buffer until
    ! a flush, in no particular order).
    do j = 1, size(metrics)
      r = metrics(j)
      call write_element(this, this%metric_ids(j), icase, h5kind_to_type(wp, H5_REAL_KIND), &
                         c_loc(r), '/cases/metrics/' // trim(this%metric_list(j)), err)
    end do
    r = wall_time_s
    call write_element(this, this%wall_id, icase, h5kind_to_type(wp, H5_REAL_KIND), c_loc(r), &
                       '/cases/wall_time_s', err)
    i = rank
    call write_element(this, this%rank_id, icase, h5kind_to_type(kind(i), H5_INTEGER_KIND), &
                       c_loc(i), '/cases/rank', err)
    msg = fixed_message(message)
    call message_type(msg_type, hdferr)
    if (hdferr < 0) then
      call err%set(ERR_IO, where // ': cannot make the string type of /cases/message')
    else
      call write_element(this, this%message_id, icase, msg_type, c_loc(msg), '/cases/message', &
                         err)
    end if
    if (msg_type >= 0) call h5tclose_f(msg_type, hdferr)
    if (.not. err%ok()) return
    call flush_or_fail(this, err)
    if (.not. err%ok()) return

    i = status
    call write_element(this, this%status_id, icase, h5kind_to_type(kind(i), H5_INTEGER_KIND), &
                       c_loc(i), '/cases/status', err)
    if (.not. err%ok()) return
    call flush_or_fail(this, err)
    if (.not. err%ok()) return
    if (this%do_sync) call sync_or_fail(this, err)
    if (.not. err%ok()) return
    this%case_status(icase) = status
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
    character(len=:), allocatable :: p
    logical :: want_sync
    if (.not. this%opened) return
    p = this%path
    want_sync = this%do_sync
    call h5fflush_f(this%file_id, H5F_SCOPE_GLOBAL_F, hdferr)
    if (hdferr < 0) call e%set(ERR_IO, p // ': cannot flush the sweep result file')
    call release(this, hdferr)
    if (hdferr < 0) call e%set(ERR_IO, p // ': cannot close the sweep result file')
    if (want_sync .and. e%ok()) then
      call sync_file(p, e)
      if (.not. e%ok()) call e%prefix(p // ': ')
    end if
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
  ! Internals

  !> Initialise the HDF5 library unless that is done already (as io_hdf5: HDF5 1.10's h5open_f
  !> copies its predefined Fortran types on every call, so look first whether one is valid).
  subroutine ensure_hdf5(hdferr)
    integer, intent(out) :: hdferr
    logical :: ready
    call h5iis_valid_f(H5T_NATIVE_DOUBLE, ready, hdferr)
    if (hdferr == 0 .and. ready) return
    call h5open_f(hdferr)
  end subroutine ensure_hdf5

  !> `path` is an HDF5 file that did not open read-write: tell a damaged file (ERR_INPUT) from
  !> one another process holds open (HDF5's file lock) or that may not be written (ERR_IO).
  !> The probes open it read-only, once without taking the lock; nothing is written.
  subroutine diagnose_open_failure(path, err)
    character(len=*), intent(in) :: path
    type(error_t), intent(inout) :: err
    integer(hid_t) :: fapl, fid
    integer :: hdferr
    logical :: readable_unlocked, readable_locked
    readable_unlocked = .false.
    call h5pcreate_f(H5P_FILE_ACCESS_F, fapl, hdferr)
    if (hdferr == 0) then
      call h5pset_file_locking_f(fapl, .false., .true., hdferr)
      if (hdferr == 0) call h5fopen_f(path, H5F_ACC_RDONLY_F, fid, hdferr, access_prp=fapl)
      if (hdferr == 0) then
        readable_unlocked = .true.
        call h5fclose_f(fid, hdferr)
      end if
      call h5pclose_f(fapl, hdferr)
    end if
    if (.not. readable_unlocked) then
      call err%set(ERR_INPUT, path // ' is damaged: it cannot be opened as HDF5 (was its ' // &
                   'creation interrupted?): remove it or choose another -o')
      return
    end if
    call h5fopen_f(path, H5F_ACC_RDONLY_F, fid, hdferr)
    readable_locked = hdferr == 0
    if (readable_locked) call h5fclose_f(fid, hdferr)
    if (.not. readable_locked) then
      call err%set(ERR_IO, path // ' is in use: another process (a running sweep?) has it ' // &
                   'open for writing')
    else
      call err%set(ERR_IO, path // ': cannot open the sweep result file for writing (is it ' // &
                   'read-only?)')
    end if
  end subroutine diagnose_open_failure

  !> Close every id held and forget the file; reports the file close status in `hdferr_out`.
  subroutine release(this, hdferr_out)
    class(sweep_file_t), intent(inout) :: this
    integer, intent(out), optional :: hdferr_out
    integer :: hdferr, j
    if (present(hdferr_out)) hdferr_out = 0
    if (allocated(this%metric_ids)) then
      do j = 1, size(this%metric_ids)
        if (this%metric_ids(j) >= 0) call h5dclose_f(this%metric_ids(j), hdferr)
      end do
      deallocate(this%metric_ids)
    end if
    if (this%status_id >= 0) call h5dclose_f(this%status_id, hdferr)
    if (this%message_id >= 0) call h5dclose_f(this%message_id, hdferr)
    if (this%wall_id >= 0) call h5dclose_f(this%wall_id, hdferr)
    if (this%rank_id >= 0) call h5dclose_f(this%rank_id, hdferr)
    this%status_id = -1
    this%message_id = -1
    this%wall_id = -1
    this%rank_id = -1
    if (this%opened) then
      call h5fclose_f(this%file_id, hdferr)
      if (present(hdferr_out)) hdferr_out = hdferr
    end if
    this%file_id = -1
    this%opened = .false.
    this%ncases = 0
    if (allocated(this%metric_list)) deallocate(this%metric_list)
    if (allocated(this%case_status)) deallocate(this%case_status)
  end subroutine release

  subroutine flush_or_fail(this, err)
    class(sweep_file_t), intent(inout) :: this
    type(error_t), intent(inout) :: err
    integer :: hdferr
    call h5fflush_f(this%file_id, H5F_SCOPE_GLOBAL_F, hdferr)
    if (hdferr < 0) call err%set(ERR_IO, this%path // ': cannot flush the sweep result file')
  end subroutine flush_or_fail

  subroutine sync_or_fail(this, err)
    class(sweep_file_t), intent(inout) :: this
    type(error_t), intent(inout) :: err
    type(error_t) :: e
    call sync_file(this%path, e)
    if (.not. e%ok()) call err%set(e%code, this%path // ': ' // e%message)
  end subroutine sync_or_fail

  !> Names for datasets: trimmed, non-empty, without '/', not '.' or '..', no repeats.
  subroutine check_names(path, what, names, err)
    character(len=*), intent(in) :: path, what, names(:)
    type(error_t), intent(inout) :: err
    character(len=:), allocatable :: a
    integer :: i, k
    do i = 1, size(names)
      a = trim(adjustl(names(i)))
      if (len(a) == 0) then
        call err%set(ERR_INPUT, path // ': ' // what // ' ' // int_text(i) // ' has an empty name')
      else if (index(a, '/') > 0) then
        call err%set(ERR_INPUT, path // ': ' // what // " name '" // a // "' contains '/'")
      else if (a == '.' .or. a == '..') then
        call err%set(ERR_INPUT, path // ': ' // what // " name '" // a // "' is not allowed")
      end if
      do k = 1, i - 1
        if (trim(adjustl(names(k))) == a) call err%set(ERR_INPUT, path // ': ' // what // &
                                                       " name '" // a // "' is given twice")
      end do
      if (.not. err%ok()) return
    end do
  end subroutine check_names

  !> Group `name`, optionally keeping (and indexing) the creation order of its members.
  subroutine make_group(this, name, keep_order, err)
    class(sweep_file_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    logical, intent(in) :: keep_order
    type(error_t), intent(inout) :: err
    integer(hid_t) :: gcpl, gid
    integer :: hdferr
    if (.not. err%ok()) return
    call h5pcreate_f(H5P_GROUP_CREATE_F, gcpl, hdferr)
    if (hdferr < 0) then
      call err%set(ERR_IO, this%path // ": cannot set up creating group '" // name // "'")
      return
    end if
    call h5pset_obj_track_times_f(gcpl, .false., hdferr)
    if (hdferr == 0 .and. keep_order) &
      call h5pset_link_creation_order_f(gcpl, ior(H5P_CRT_ORDER_TRACKED_F, &
                                                  H5P_CRT_ORDER_INDEXED_F), hdferr)
    if (hdferr == 0) call h5gcreate_f(this%file_id, name, gid, hdferr, gcpl_id=gcpl)
    if (hdferr < 0) then
      call err%set(ERR_IO, this%path // ": cannot create group '" // name // "'")
    else
      call h5gclose_f(gid, hdferr)
    end if
    call h5pclose_f(gcpl, hdferr)
  end subroutine make_group

  !> Create a rank-1 contiguous dataset of n_cases elements, allocated now; filled with `*fill`
  !> (of memory type `mem_type`) at allocation unless `fill` is null. Returns it open.
  subroutine make_dataset(this, name, file_type, mem_type, fill, dset_id, err)
    class(sweep_file_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    integer(hid_t), intent(in) :: file_type, mem_type
    type(c_ptr), intent(in) :: fill
    integer(hid_t), intent(out) :: dset_id
    type(error_t), intent(inout) :: err
    integer(hid_t) :: dcpl, space_id
    integer :: hdferr
    dset_id = -1
    if (.not. err%ok()) return
    dcpl = -1
    space_id = -1
    work: block
      call h5screate_simple_f(1, [int(this%ncases, hsize_t)], space_id, hdferr)
      if (hdferr < 0) then
        space_id = -1
        exit work
      end if
      call dataset_plist(mem_type, fill, dcpl, hdferr)
      if (hdferr < 0) exit work
      call h5dcreate_f(this%file_id, name, file_type, space_id, dset_id, hdferr, dcpl_id=dcpl)
      if (hdferr < 0) dset_id = -1
    end block work
    if (dset_id < 0) call err%set(ERR_IO, this%path // ": cannot create dataset '" // name // "'")
    if (dcpl >= 0) call h5pclose_f(dcpl, hdferr)
    if (space_id >= 0) call h5sclose_f(space_id, hdferr)
  end subroutine make_dataset

  !> Dataset creation properties: contiguous, allocated at creation, fill value written then,
  !> no time stamps (nothing in the object header ever changes, and files are reproducible).
  subroutine dataset_plist(mem_type, fill, dcpl, hdferr)
    integer(hid_t), intent(in) :: mem_type
    type(c_ptr), intent(in) :: fill
    integer(hid_t), intent(out) :: dcpl
    integer, intent(out) :: hdferr
    call h5pcreate_f(H5P_DATASET_CREATE_F, dcpl, hdferr)
    if (hdferr < 0) then
      dcpl = -1
      return
    end if
    call h5pset_layout_f(dcpl, H5D_CONTIGUOUS_F, hdferr)
    if (hdferr == 0) call h5pset_alloc_time_f(dcpl, H5D_ALLOC_TIME_EARLY_F, hdferr)
    if (hdferr == 0) call h5pset_fill_time_f(dcpl, H5D_FILL_TIME_ALLOC_F, hdferr)
    if (hdferr == 0) call h5pset_obj_track_times_f(dcpl, .false., hdferr)
    if (hdferr == 0 .and. c_associated(fill)) call h5pset_fill_value_f(dcpl, mem_type, fill, &
                                                                        hdferr)
  end subroutine dataset_plist

  !> /cases/message: fixed-length 256-byte NUL-padded UTF-8 strings, empty (all NUL) at first.
  subroutine make_message_dataset(this, err)
    class(sweep_file_t), intent(inout) :: this
    type(error_t), intent(inout) :: err
    integer(hid_t) :: type_id
    integer :: hdferr
    if (.not. err%ok()) return
    call message_type(type_id, hdferr)
    if (hdferr < 0) then
      call err%set(ERR_IO, this%path // ": cannot make the string type of '/cases/message'")
    else
      ! The default fill value of a string type is all zero bytes: the empty string.
      call make_dataset(this, '/cases/message', type_id, type_id, c_null_ptr, this%message_id, err)
    end if
    if (type_id >= 0) call h5tclose_f(type_id, hdferr)
  end subroutine make_message_dataset

  !> The string type of /cases/message, used in the file and in memory alike (no conversion).
  subroutine message_type(type_id, hdferr)
    integer(hid_t), intent(out) :: type_id
    integer, intent(out) :: hdferr
    call h5tcopy_f(H5T_C_S1, type_id, hdferr)
    if (hdferr < 0) then
      type_id = -1
      return
    end if
    call h5tset_size_f(type_id, int(SWEEP_MESSAGE_LEN, size_t), hdferr)
    if (hdferr == 0) call h5tset_strpad_f(type_id, H5T_STR_NULLPAD_F, hdferr)
    if (hdferr == 0) call h5tset_cset_f(type_id, H5T_CSET_UTF8_F, hdferr)
  end subroutine message_type

  !> `message` as a 256-byte NUL-padded field; longer text is cut to 256 bytes, moved back to the
  !> start of a UTF-8 character if the cut would split one.
  pure function fixed_message(message) result(buf)
    character(len=*), intent(in) :: message
    character(len=SWEEP_MESSAGE_LEN) :: buf
    integer :: n
    n = len(message)
    if (n > SWEEP_MESSAGE_LEN) then
      n = SWEEP_MESSAGE_LEN
      ! message(n+1:n+1) starts the part cut off; while it is a continuation byte (10xxxxxx),
      ! the character it belongs to began at or before n: drop that character too.
      do while (n > 0)
        if (iand(ichar(message(n + 1:n + 1)), 192) /= 128) exit
        n = n - 1
      end do
    end if
    buf = repeat(c_null_char, SWEEP_MESSAGE_LEN)
    buf(1:n) = message(1:n)
  end function fixed_message

  !> Write one element (case icase) of the open rank-1 dataset `dset_id` from `buf`.
  subroutine write_element(this, dset_id, icase, mem_type, buf, name, err)
    class(sweep_file_t), intent(inout) :: this
    integer(hid_t), intent(in) :: dset_id, mem_type
    integer, intent(in) :: icase
    type(c_ptr), intent(in) :: buf
    character(len=*), intent(in) :: name
    type(error_t), intent(inout) :: err
    integer(hid_t) :: fspace, mspace
    integer :: hdferr
    if (.not. err%ok()) return
    fspace = -1
    mspace = -1
    work: block
      call h5dget_space_f(dset_id, fspace, hdferr)
      if (hdferr < 0) then
        fspace = -1
        exit work
      end if
      call h5sselect_hyperslab_f(fspace, H5S_SELECT_SET_F, [int(icase - 1, hsize_t)], &
                                 [1_hsize_t], hdferr)
      if (hdferr < 0) exit work
      call h5screate_simple_f(1, [1_hsize_t], mspace, hdferr)
      if (hdferr < 0) then
        mspace = -1
        exit work
      end if
      call h5dwrite_f(dset_id, mem_type, buf, hdferr, mspace, fspace)
    end block work
    if (hdferr < 0) call err%set(ERR_IO, this%path // ': case ' // int_text(icase) // &
                                 ": cannot write to dataset '" // name // "'")
    if (mspace >= 0) call h5sclose_f(mspace, hdferr)
    if (fspace >= 0) call h5sclose_f(fspace, hdferr)
  end subroutine write_element

  !> Open dataset `name`, check it is rank 1 with n_cases elements of type class `cls`.
  subroutine open_dataset(this, name, cls, dset_id, err)
    class(sweep_file_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    integer, intent(in) :: cls
    integer(hid_t), intent(inout) :: dset_id
    type(error_t), intent(inout) :: err
    integer(hid_t) :: space_id, type_id
    integer(hsize_t) :: dims(1), maxdims(1)
    integer :: hdferr, rank, tclass
    logical :: exists
    if (.not. err%ok()) return
    dset_id = -1
    call h5lexists_f(this%file_id, name, exists, hdferr)
    if (hdferr < 0 .or. .not. exists) then
      call err%set(ERR_INPUT, this%path // " is not a complete sweep result file (no dataset '" &
                   // name // "'; was its creation interrupted?): remove it or choose another -o")
      return
    end if
    call h5dopen_f(this%file_id, name, dset_id, hdferr)
    if (hdferr < 0) then
      dset_id = -1
      call err%set(ERR_INPUT, this%path // ": cannot open dataset '" // name // "' (damaged " // &
                   'file?): remove it or choose another -o')
      return
    end if
    rank = -1
    dims = 0
    tclass = -1
    call h5dget_space_f(dset_id, space_id, hdferr)
    if (hdferr == 0) then
      call h5sget_simple_extent_ndims_f(space_id, rank, hdferr)
      if (hdferr == 0 .and. rank == 1) &
        call h5sget_simple_extent_dims_f(space_id, dims, maxdims, hdferr)
      call h5sclose_f(space_id, hdferr)
    end if
    call h5dget_type_f(dset_id, type_id, hdferr)
    if (hdferr == 0) then
      call h5tget_class_f(type_id, tclass, hdferr)
      call h5tclose_f(type_id, hdferr)
    end if
    if (rank /= 1 .or. dims(1) /= int(this%ncases, hsize_t) .or. tclass /= cls) then
      call err%set(ERR_INPUT, this%path // ": dataset '" // name // "' does not have the " // &
                   'shape or type of a sweep result file with ' // int_text(this%ncases) // &
                   ' cases: remove it or choose another -o')
    end if
  end subroutine open_dataset

  subroutine check_dataset(this, name, cls, err)
    class(sweep_file_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    integer, intent(in) :: cls
    type(error_t), intent(inout) :: err
    integer(hid_t) :: dset_id
    integer :: hdferr
    call open_dataset(this, name, cls, dset_id, err)
    if (dset_id >= 0) call h5dclose_f(dset_id, hdferr)
  end subroutine check_dataset

  !> /cases/message must be a fixed-length string of SWEEP_MESSAGE_LEN bytes.
  subroutine check_message_type(this, err)
    class(sweep_file_t), intent(inout) :: this
    type(error_t), intent(inout) :: err
    integer(hid_t) :: type_id
    integer(size_t) :: sz
    logical :: vl
    integer :: hdferr
    sz = 0
    vl = .true.
    call h5dget_type_f(this%message_id, type_id, hdferr)
    if (hdferr == 0) then
      call h5tis_variable_str_f(type_id, vl, hdferr)
      call h5tget_size_f(type_id, sz, hdferr)
      call h5tclose_f(type_id, hdferr)
    end if
    if (vl .or. sz /= int(SWEEP_MESSAGE_LEN, size_t)) &
      call err%set(ERR_INPUT, this%path // ": dataset '/cases/message' is not made of " // &
                   int_text(SWEEP_MESSAGE_LEN) // '-byte strings, so this is not a sweep ' // &
                   'result file: remove it or choose another -o')
  end subroutine check_message_type

  !> Names of the members of group `group` in creation order.
  subroutine group_members(this, group, names, err)
    class(sweep_file_t), intent(inout) :: this
    character(len=*), intent(in) :: group
    character(len=:), allocatable, intent(out) :: names(:)
    type(error_t), intent(inout) :: err
    integer :: storage_type, nlinks, max_corder, hdferr, k, longest
    integer(size_t) :: nsize
    character(len=1024) :: buf
    character(len=1024), allocatable :: raw(:)
    logical :: exists
    allocate(character(len=1) :: names(0))
    if (.not. err%ok()) return
    call h5lexists_f(this%file_id, group, exists, hdferr)
    if (hdferr == 0 .and. exists) &
      call h5gget_info_by_name_f(this%file_id, group, storage_type, nlinks, max_corder, hdferr)
    if (hdferr < 0 .or. .not. exists) then
      call err%set(ERR_INPUT, this%path // " is not a complete sweep result file (no group '" // &
                   group // "'): remove it or choose another -o")
      return
    end if
    allocate(raw(nlinks))
    longest = 1
    do k = 1, nlinks
      buf = ''
      call h5lget_name_by_idx_f(this%file_id, group, H5_INDEX_CRT_ORDER_F, H5_ITER_INC_F, &
                                int(k - 1, hsize_t), buf, hdferr, nsize)
      if (hdferr < 0 .or. nsize > int(len(buf), size_t)) then
        call err%set(ERR_INPUT, this%path // ": cannot list group '" // group // "' in " // &
                     'creation order, so this is not a sweep result file: remove it or ' // &
                     'choose another -o')
        return
      end if
      raw(k) = buf(1:nsize)
      longest = max(longest, int(nsize))
    end do
    deallocate(names)
    allocate(character(len=longest) :: names(nlinks))
    do k = 1, nlinks
      names(k) = raw(k)(1:longest)
    end do
  end subroutine group_members

  !> Read the root attribute `name`, a scalar variable-length string.
  subroutine get_string_attr(this, name, value, err)
    class(sweep_file_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    character(len=:), allocatable, intent(out) :: value
    type(error_t), intent(inout) :: err
    integer(hid_t) :: aid, tid, sid
    type(c_ptr), target :: ptr(1)
    type(c_ptr) :: p
    character(kind=c_char), pointer :: chars(:)
    integer :: hdferr, tclass, n, i
    logical :: exists, vl
    value = ''
    if (.not. err%ok()) return
    call h5aexists_by_name_f(this%file_id, '/', name, exists, hdferr)
    if (hdferr < 0 .or. .not. exists) then
      call err%set(ERR_INPUT, this%path // " is not a sweep result file (no attribute '" // &
                   name // "'): remove it or choose another -o")
      return
    end if
    call h5aopen_by_name_f(this%file_id, '/', name, aid, hdferr)
    if (hdferr < 0) then
      call err%set(ERR_INPUT, this%path // ": cannot open attribute '" // name // &
                   "' (damaged file?): remove it or choose another -o")
      return
    end if
    tclass = -1
    vl = .false.
    call h5aget_type_f(aid, tid, hdferr)
    if (hdferr < 0) tid = -1
    if (hdferr == 0) call h5tget_class_f(tid, tclass, hdferr)
    if (hdferr == 0 .and. tclass == H5T_STRING_F) call h5tis_variable_str_f(tid, vl, hdferr)
    if (.not. vl) then
      call err%set(ERR_INPUT, this%path // ": attribute '" // name // "' is not a text, so " // &
                   'this is not a sweep result file: remove it or choose another -o')
    else
      ptr(1) = c_null_ptr
      p = c_loc(ptr)
      call h5aread_f(aid, tid, p, hdferr)
      if (hdferr < 0) then
        call err%set(ERR_INPUT, this%path // ": cannot read attribute '" // name // &
                     "' (damaged file?): remove it or choose another -o")
      else if (c_associated(ptr(1))) then
        n = int(c_strlen(ptr(1)))
        call c_f_pointer(ptr(1), chars, [n])
        deallocate(value)
        allocate(character(len=n) :: value)
        do i = 1, n
          value(i:i) = chars(i)
        end do
        call h5aget_space_f(aid, sid, hdferr)
        if (hdferr == 0) then
          call h5dvlen_reclaim_f(tid, sid, H5P_DEFAULT_F, p, hdferr)
          call h5sclose_f(sid, hdferr)
        end if
      end if
    end if
    if (tid >= 0) call h5tclose_f(tid, hdferr)
    call h5aclose_f(aid, hdferr)
  end subroutine get_string_attr

  !> Read the root attribute `name`, a scalar integer.
  subroutine get_int_attr(this, name, value, err)
    class(sweep_file_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    integer, intent(out) :: value
    type(error_t), intent(inout) :: err
    integer(hid_t) :: aid, tid, sid
    integer, target :: buf
    type(c_ptr) :: p
    integer :: hdferr, tclass, stype
    logical :: exists
    value = -1
    if (.not. err%ok()) return
    call h5aexists_by_name_f(this%file_id, '/', name, exists, hdferr)
    if (hdferr < 0 .or. .not. exists) then
      call err%set(ERR_INPUT, this%path // " is not a sweep result file (no attribute '" // &
                   name // "'): remove it or choose another -o")
      return
    end if
    call h5aopen_by_name_f(this%file_id, '/', name, aid, hdferr)
    if (hdferr < 0) then
      call err%set(ERR_INPUT, this%path // ": cannot open attribute '" // name // &
                   "' (damaged file?): remove it or choose another -o")
      return
    end if
    tclass = -1
    stype = -1
    call h5aget_type_f(aid, tid, hdferr)
    if (hdferr == 0) then
      call h5tget_class_f(tid, tclass, hdferr)
      call h5tclose_f(tid, hdferr)
    end if
    call h5aget_space_f(aid, sid, hdferr)
    if (hdferr == 0) then
      call h5sget_simple_extent_type_f(sid, stype, hdferr)
      call h5sclose_f(sid, hdferr)
    end if
    hdferr = -1
    p = c_loc(buf)
    if (tclass == H5T_INTEGER_F .and. stype == H5S_SCALAR_F) &
      call h5aread_f(aid, h5kind_to_type(kind(buf), H5_INTEGER_KIND), p, hdferr)
    if (hdferr < 0) then
      call err%set(ERR_INPUT, this%path // ": attribute '" // name // "' is not a readable " // &
                   'integer, so this is not a sweep result file: remove it or choose another -o')
    else
      value = buf
    end if
    call h5aclose_f(aid, hdferr)
  end subroutine get_int_attr

  !> Attach `value` as a scalar variable-length UTF-8 string attribute to the open object
  !> `obj_id` (`object` names it in messages; the root if absent). As io_hdf5: h5py reads str.
  subroutine put_string_attr(this, obj_id, name, value, err, object)
    class(sweep_file_t), intent(inout) :: this
    integer(hid_t), intent(in) :: obj_id
    character(len=*), intent(in) :: name, value
    type(error_t), intent(inout) :: err
    character(len=*), intent(in), optional :: object
    character(kind=c_char), allocatable, target :: chars(:)
    type(c_ptr), target :: ptr(1)
    integer(hid_t) :: type_id
    integer :: hdferr, i
    if (.not. err%ok()) return
    allocate(chars(len(value) + 1))
    do i = 1, len(value)
      chars(i) = value(i:i)
    end do
    chars(len(value) + 1) = c_null_char
    ptr(1) = c_loc(chars)
    call h5tcopy_f(H5T_STRING, type_id, hdferr)
    if (hdferr < 0) type_id = -1
    if (hdferr == 0) call h5tset_cset_f(type_id, H5T_CSET_UTF8_F, hdferr)
    if (hdferr == 0) call h5tset_strpad_f(type_id, H5T_STR_NULLTERM_F, hdferr)
    if (hdferr < 0) then
      call err%set(ERR_IO, this%path // ": cannot make the string type of attribute '" // name &
                   // "'")
    else
      call put_attr(this, obj_id, name, type_id, type_id, c_loc(ptr), err, object)
    end if
    if (type_id >= 0) call h5tclose_f(type_id, hdferr)
  end subroutine put_string_attr

  !> Attach a default-integer scalar attribute (32-bit little-endian) to the open object.
  subroutine put_int_attr(this, obj_id, name, value, err)
    class(sweep_file_t), intent(inout) :: this
    integer(hid_t), intent(in) :: obj_id
    character(len=*), intent(in) :: name
    integer, intent(in) :: value
    type(error_t), intent(inout) :: err
    integer, target :: buf
    if (.not. err%ok()) return
    buf = value
    call put_attr(this, obj_id, name, h5kind_to_type(kind(buf), H5_INTEGER_KIND), H5T_STD_I32LE, &
                  c_loc(buf), err)
  end subroutine put_int_attr

  !> Create scalar attribute `name` of the open object `obj_id` (it must not exist) and write it.
  subroutine put_attr(this, obj_id, name, mem_type, file_type, buf, err, object)
    class(sweep_file_t), intent(inout) :: this
    integer(hid_t), intent(in) :: obj_id
    character(len=*), intent(in) :: name
    integer(hid_t), intent(in) :: mem_type, file_type
    type(c_ptr), intent(in) :: buf
    type(error_t), intent(inout) :: err
    character(len=*), intent(in), optional :: object
    integer(hid_t) :: space_id, attr_id
    integer :: hdferr
    character(len=:), allocatable :: what
    what = "attribute '" // name // "' of '/'"
    if (present(object)) what = "attribute '" // name // "' of '" // object // "'"
    space_id = -1
    attr_id = -1
    work: block
      call h5screate_f(H5S_SCALAR_F, space_id, hdferr)
      if (hdferr < 0) then
        space_id = -1
        exit work
      end if
      call h5acreate_f(obj_id, name, file_type, space_id, attr_id, hdferr)
      if (hdferr < 0) then
        attr_id = -1
        exit work
      end if
      call h5awrite_f(attr_id, mem_type, buf, hdferr)
    end block work
    if (hdferr < 0) call err%set(ERR_IO, this%path // ': cannot write ' // what)
    if (attr_id >= 0) call h5aclose_f(attr_id, hdferr)
    if (space_id >= 0) call h5sclose_f(space_id, hdferr)
  end subroutine put_attr

  !> Exact comparison (Fortran's == ignores trailing blanks).
  pure logical function same_text(a, b)
    character(len=*), intent(in) :: a, b
    same_text = len(a) == len(b)
    if (same_text) same_text = a == b
  end function same_text

  pure function opt_text(s) result(t)
    character(len=:), allocatable, intent(in) :: s
    character(len=:), allocatable :: t
    if (allocated(s)) then
      t = s
    else
      t = ''
    end if
  end function opt_text

  pure function int_text(i) result(s)
    integer, intent(in) :: i
    character(len=:), allocatable :: s
    character(len=12) :: buf
    write(buf, '(i0)') i
    s = trim(buf)
  end function int_text
end module io_sweep_file
