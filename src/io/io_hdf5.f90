!> Serial HDF5 result writer: one file per run, written under a temporary name and renamed into
!> place on `commit`, so a half-written file never carries the final name.
!>
!> Usage:
!>
!>     type(h5_writer_t) :: h5
!>     call h5%open('run.h5', err)                       ! writes run.h5.tmp
!>     if (err%ok()) call h5%write_real_1d('/time', t, err, units='s')
!>     if (err%ok()) call h5%write_real_2d('/nodes/tip/position', pos, err, units='m') ! pos(3,nt)
!>     if (err%ok()) call h5%write_string_attr('/', 'status', 'ok', err)
!>     if (err%ok()) call h5%commit(err)                 ! run.h5.tmp -> run.h5
!>     if (.not. err%ok()) call h5%abort()               ! no file is left behind
!>
!> Layout conventions:
!> - Dataset names are absolute paths ('/time', '/modal/frequency_hz'); a name without a leading
!>   '/' is taken from the root. Missing intermediate groups are created. Writing a dataset that
!>   exists already is an error.
!> - Reals are stored as IEEE 64-bit little-endian, default integers as 32-bit and integer(i8)
!>   as 64-bit little-endian integers, strings as variable-length UTF-8 (h5py reads them as
!>   `str`; any length, e.g. the whole input file, is fine).
!> - Rank 2: HDF5's Fortran API reverses dimensions, so Fortran `data(ncol, nrow)` reads in h5py,
!>   numpy and C as shape (nrow, ncol). Store time series with time last in Fortran, e.g.
!>   positions `pos(3, nt)`, which read as (nt, 3) with rows at successive times.
!> - Writing an attribute that exists already replaces it.
!>
!> The file is opened with the default (serial, POSIX) file access property list; no MPI is needed
!> and MPI_Init need not have been called. `open` initialises the HDF5 library if that is not done
!> yet and switches off HDF5's automatic error-stack printing (for the whole process): failures
!> come back in `err` (code ERR_IO) with a message naming the file and the dataset or attribute.
!> The HDF5 calls themselves (types, attributes, dataset creation) are io_h5base's, shared with
!> the sweep result file (io_sweep_file).
!> The writer holds all its state; the module has none. A writer is not thread-safe.
module io_hdf5
  use, intrinsic :: iso_c_binding, only: c_ptr, c_loc, c_null_ptr, c_char, c_null_char
  use hdf5, only: hid_t, hsize_t, h5fcreate_f, h5fflush_f, h5fclose_f, H5F_ACC_TRUNC_F, &
    H5F_SCOPE_GLOBAL_F, h5pcreate_f, h5pset_create_inter_group_f, H5P_LINK_CREATE_F, &
    h5lexists_f, h5oopen_f, h5oclose_f, h5kind_to_type, H5T_IEEE_F64LE, &
    H5_REAL_KIND, H5_INTEGER_KIND
  use core_kinds, only: wp, i8
  use core_error, only: error_t, ERR_IO
  use io_fs, only: rename_file, delete_file, sync_file, guard_result_file, clear_result_guard
  use io_h5base, only: h5_init, h5_close, h5_int_file_type, h5_string_type, h5_put_string_attr, &
    h5_put_real_attr, h5_put_int_attr, h5_create_dataset
  implicit none
  private
  public :: h5_writer_t

  !> Writer of one result file. Components are private; use the type-bound procedures.
  type :: h5_writer_t
    private
    integer(hid_t) :: file_id = -1
    logical :: opened = .false.           !< the temporary file is open
    logical :: tmp_left = .false.         !< a temporary file may exist on disk
    character(len=:), allocatable :: path !< final name
    character(len=:), allocatable :: tmp  !< temporary name (path // '.tmp')
  contains
    !> `open(path, err)`: create `path // '.tmp'` (truncating a leftover); `path` appears on commit.
    procedure :: open => h5w_open
    !> `write_real_1d(name, data(:), err [, units])`
    procedure :: write_real_1d => h5w_write_real_1d
    !> `write_real_2d(name, data(:,:), err [, units])`: Fortran (ncol, nrow) reads as (nrow, ncol).
    procedure :: write_real_2d => h5w_write_real_2d
    !> `write_real_3d(name, data(:,:,:), err [, units])`: Fortran (a, b, c) reads as (c, b, a).
    procedure :: write_real_3d => h5w_write_real_3d
    procedure, private :: h5w_write_int_1d, h5w_write_int_1d_i8
    !> `write_int_1d(name, data(:), err [, units])`, data default integer or integer(i8).
    generic :: write_int_1d => h5w_write_int_1d, h5w_write_int_1d_i8
    !> `write_int_2d(name, data(:,:), err)`: default integers, Fortran (ncol, nrow) as above.
    procedure :: write_int_2d => h5w_write_int_2d
    !> `write_string_1d(name, values(:), err)`: variable-length UTF-8 strings, trailing blanks
    !> of the Fortran strings removed (h5py reads a list of str).
    procedure :: write_string_1d => h5w_write_string_1d
    !> `write_string_attr(object, name, value, err)`; object '/' for the root, or a path.
    procedure :: write_string_attr => h5w_write_string_attr
    !> `write_real_attr(object, name, value, err)`, value real(wp).
    procedure :: write_real_attr => h5w_write_real_attr
    procedure, private :: h5w_write_int_attr, h5w_write_int_attr_i8
    !> `write_int_attr(object, name, value, err)`, value default integer or integer(i8).
    generic :: write_int_attr => h5w_write_int_attr, h5w_write_int_attr_i8
    !> `commit(err)`: flush, close, fsync, rename the temporary file to the final name.
    procedure :: commit => h5w_commit
    !> `abort()`: close if open and delete the temporary file; safe to call in any state.
    procedure :: abort => h5w_abort
    !> `is_open()`: true between a successful `open` and `commit`/`abort`.
    procedure :: is_open => h5w_is_open
  end type h5_writer_t

contains

  subroutine h5w_open(this, path, err)
    class(h5_writer_t), intent(inout) :: this
    character(len=*), intent(in) :: path
    type(error_t), intent(out) :: err
    integer :: hdferr

    if (this%opened) then
      call err%set(ERR_IO, path // ": cannot open: this writer still has '" // this%path // &
                   "' open (commit or abort it first)")
      return
    end if
    if (len_trim(path) == 0) then
      call err%set(ERR_IO, 'cannot open an HDF5 result file with an empty name')
      return
    end if
    this%path = path
    this%tmp = path // '.tmp'
    this%tmp_left = .false.
    this%file_id = -1

    call h5_init(path, err)
    if (.not. err%ok()) return
    call guard_result_file(this%tmp, this%path, final_ours=.false.)
    call h5fcreate_f(this%tmp, H5F_ACC_TRUNC_F, this%file_id, hdferr)
    if (hdferr < 0) then
      this%file_id = -1
      call err%set(ERR_IO, path // ": cannot create the temporary file '" // this%tmp // &
                   "' (does the folder exist and is it writable?)")
      return
    end if
    this%opened = .true.
    this%tmp_left = .true.
  end subroutine h5w_open

  logical function h5w_is_open(this)
    class(h5_writer_t), intent(in) :: this
    h5w_is_open = this%opened
  end function h5w_is_open

  !> Write a rank-1 real(wp) dataset. Optional `units` becomes the string attribute 'units'.
  subroutine h5w_write_real_1d(this, name, data, err, units)
    class(h5_writer_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    real(wp), intent(in) :: data(:)
    type(error_t), intent(out) :: err
    character(len=*), intent(in), optional :: units
    real(wp), allocatable, target :: buf(:)
    type(c_ptr) :: p
    allocate(buf, source=data)
    p = c_null_ptr
    if (size(buf) > 0) p = c_loc(buf)
    call write_dataset(this, name, shape(data, kind=hsize_t), &
                       h5kind_to_type(wp, H5_REAL_KIND), H5T_IEEE_F64LE, p, err, units)
  end subroutine h5w_write_real_1d

  !> Write a rank-2 real(wp) dataset. Fortran `data(ncol, nrow)` reads in h5py (C order) as shape
  !> (nrow, ncol): positions stored as pos(3, nt) read as (nt, 3). Optional `units` as above.
  subroutine h5w_write_real_2d(this, name, data, err, units)
    class(h5_writer_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    real(wp), intent(in) :: data(:, :)
    type(error_t), intent(out) :: err
    character(len=*), intent(in), optional :: units
    real(wp), allocatable, target :: buf(:, :)
    type(c_ptr) :: p
    allocate(buf, source=data)
    p = c_null_ptr
    if (size(buf) > 0) p = c_loc(buf)
    call write_dataset(this, name, shape(data, kind=hsize_t), &
                       h5kind_to_type(wp, H5_REAL_KIND), H5T_IEEE_F64LE, p, err, units)
  end subroutine h5w_write_real_2d

  subroutine h5w_write_real_3d(this, name, data, err, units)
    class(h5_writer_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    real(wp), intent(in) :: data(:, :, :)
    type(error_t), intent(out) :: err
    character(len=*), intent(in), optional :: units
    real(wp), allocatable, target :: buf(:, :, :)
    type(c_ptr) :: p
    allocate(buf, source=data)
    p = c_null_ptr
    if (size(buf) > 0) p = c_loc(buf)
    call write_dataset(this, name, shape(data, kind=hsize_t), &
                       h5kind_to_type(wp, H5_REAL_KIND), H5T_IEEE_F64LE, p, err, units)
  end subroutine h5w_write_real_3d

  !> Write a rank-1 default-integer dataset (stored as 32-bit integers).
  subroutine h5w_write_int_1d(this, name, data, err, units)
    class(h5_writer_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    integer, intent(in) :: data(:)
    type(error_t), intent(out) :: err
    character(len=*), intent(in), optional :: units
    integer, allocatable, target :: buf(:)
    type(c_ptr) :: p
    allocate(buf, source=data)
    p = c_null_ptr
    if (size(buf) > 0) p = c_loc(buf)
    call write_dataset(this, name, shape(data, kind=hsize_t), &
                       h5kind_to_type(kind(data), H5_INTEGER_KIND), &
                       h5_int_file_type(kind(data)), p, err, units)
  end subroutine h5w_write_int_1d

  !> Write a rank-1 integer(i8) dataset (stored as 64-bit integers).
  subroutine h5w_write_int_1d_i8(this, name, data, err, units)
    class(h5_writer_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    integer(i8), intent(in) :: data(:)
    type(error_t), intent(out) :: err
    character(len=*), intent(in), optional :: units
    integer(i8), allocatable, target :: buf(:)
    type(c_ptr) :: p
    allocate(buf, source=data)
    p = c_null_ptr
    if (size(buf) > 0) p = c_loc(buf)
    call write_dataset(this, name, shape(data, kind=hsize_t), &
                       h5kind_to_type(i8, H5_INTEGER_KIND), h5_int_file_type(i8), p, err, units)
  end subroutine h5w_write_int_1d_i8

  subroutine h5w_write_int_2d(this, name, data, err)
    class(h5_writer_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    integer, intent(in) :: data(:, :)
    type(error_t), intent(out) :: err
    integer, allocatable, target :: buf(:, :)
    type(c_ptr) :: p
    allocate(buf, source=data)
    p = c_null_ptr
    if (size(buf) > 0) p = c_loc(buf)
    call write_dataset(this, name, shape(data, kind=hsize_t), &
                       h5kind_to_type(kind(data), H5_INTEGER_KIND), &
                       h5_int_file_type(kind(data)), p, err)
  end subroutine h5w_write_int_2d

  subroutine h5w_write_string_1d(this, name, values, err)
    class(h5_writer_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    character(len=*), intent(in) :: values(:)
    type(error_t), intent(out) :: err
    ! All strings NUL-terminated in one buffer; the dataset's elements point into it.
    character(kind=c_char), allocatable, target :: chars(:)
    type(c_ptr), allocatable, target :: ptrs(:)
    integer(hid_t) :: type_id
    integer :: i, j, at, hdferr
    allocate(chars(sum(len_trim(values)) + size(values)), ptrs(size(values)))
    at = 1
    do i = 1, size(values)
      ptrs(i) = c_loc(chars(at))
      do j = 1, len_trim(values(i))
        chars(at) = values(i)(j:j)
        at = at + 1
      end do
      chars(at) = c_null_char
      at = at + 1
    end do
    call h5_string_type(type_id, hdferr)
    if (hdferr < 0) then
      call err%set(ERR_IO, this%path // ": cannot make the string type of dataset '" // &
                   abs_name(name) // "'")
    else if (size(values) == 0) then
      call write_dataset(this, name, [0_hsize_t], type_id, type_id, c_null_ptr, err)
    else
      call write_dataset(this, name, shape(values, kind=hsize_t), type_id, type_id, &
                         c_loc(ptrs), err)
    end if
    call h5_close(type_id)
  end subroutine h5w_write_string_1d

  !> Attach a string attribute (variable-length UTF-8, read by h5py as str) to `object`
  !> ('/' for the root, or the path of a group or dataset).
  subroutine h5w_write_string_attr(this, object, name, value, err)
    class(h5_writer_t), intent(inout) :: this
    character(len=*), intent(in) :: object, name, value
    type(error_t), intent(out) :: err
    integer(hid_t) :: obj_id
    call open_object(this, object, name, obj_id, err)
    call h5_put_string_attr(this%path, obj_id, abs_name(object), name, value, err)
    call close_object(obj_id)
  end subroutine h5w_write_string_attr

  !> Attach a real(wp) scalar attribute (IEEE 64-bit) to `object`.
  subroutine h5w_write_real_attr(this, object, name, value, err)
    class(h5_writer_t), intent(inout) :: this
    character(len=*), intent(in) :: object, name
    real(wp), intent(in) :: value
    type(error_t), intent(out) :: err
    integer(hid_t) :: obj_id
    call open_object(this, object, name, obj_id, err)
    call h5_put_real_attr(this%path, obj_id, abs_name(object), name, value, err)
    call close_object(obj_id)
  end subroutine h5w_write_real_attr

  !> Attach a default-integer scalar attribute (32-bit) to `object`.
  subroutine h5w_write_int_attr(this, object, name, value, err)
    class(h5_writer_t), intent(inout) :: this
    character(len=*), intent(in) :: object, name
    integer, intent(in) :: value
    type(error_t), intent(out) :: err
    integer(hid_t) :: obj_id
    call open_object(this, object, name, obj_id, err)
    call h5_put_int_attr(this%path, obj_id, abs_name(object), name, value, err)
    call close_object(obj_id)
  end subroutine h5w_write_int_attr

  !> Attach an integer(i8) scalar attribute (64-bit) to `object`.
  subroutine h5w_write_int_attr_i8(this, object, name, value, err)
    class(h5_writer_t), intent(inout) :: this
    character(len=*), intent(in) :: object, name
    integer(i8), intent(in) :: value
    type(error_t), intent(out) :: err
    integer(hid_t) :: obj_id
    call open_object(this, object, name, obj_id, err)
    call h5_put_int_attr(this%path, obj_id, abs_name(object), name, value, err)
    call close_object(obj_id)
  end subroutine h5w_write_int_attr_i8

  !> Flush and close the file, fsync it and rename it to the final name (atomic: readers see the
  !> old file or the complete new one). On success the writer is closed and may be opened again.
  !> If any step fails the temporary file is deleted and nothing is left.
  subroutine h5w_commit(this, err)
    class(h5_writer_t), intent(inout) :: this
    type(error_t), intent(out) :: err
    integer :: hdferr
    type(error_t) :: fs_err

    if (.not. this%opened) then
      if (allocated(this%path)) then
        call err%set(ERR_IO, this%path // ': cannot commit: the file is not open')
      else
        call err%set(ERR_IO, 'cannot commit an HDF5 writer that was never opened')
      end if
      return
    end if

    call h5fflush_f(this%file_id, H5F_SCOPE_GLOBAL_F, hdferr)
    if (hdferr < 0) then
      call this%abort()
      call err%set(ERR_IO, this%path // ': cannot flush the HDF5 file (nothing was written)')
      return
    end if
    call h5fclose_f(this%file_id, hdferr)
    this%file_id = -1
    this%opened = .false.
    if (hdferr < 0) then
      call this%abort()
      call err%set(ERR_IO, this%path // ': cannot close the HDF5 file (nothing was written)')
      return
    end if

    call sync_file(this%tmp, fs_err)
    if (.not. fs_err%ok()) then
      call this%abort()
      call err%set(ERR_IO, this%path // ': ' // fs_err%message // ' (nothing was written)')
      return
    end if
    ! From here an interrupt removes the final file too: a run stopped while committing leaves
    ! nothing, like one stopped earlier (the executables never clear this guard).
    call guard_result_file(this%tmp, this%path, final_ours=.true.)
    call rename_file(this%tmp, this%path, fs_err)
    if (.not. fs_err%ok()) then
      call this%abort()
      call err%set(ERR_IO, this%path // ': ' // fs_err%message // ' (nothing was written)')
      return
    end if
    this%tmp_left = .false.
  end subroutine h5w_commit

  !> Close the file if open (ignoring errors) and delete the temporary file. Never fails; safe to
  !> call in any state, also twice, or after a commit (the committed file is left alone).
  subroutine h5w_abort(this)
    class(h5_writer_t), intent(inout) :: this
    integer :: hdferr
    if (this%opened) then
      call h5fclose_f(this%file_id, hdferr)
      this%file_id = -1
      this%opened = .false.
    end if
    if (this%tmp_left) then
      call delete_file(this%tmp)
      this%tmp_left = .false.
      call clear_result_guard()
    end if
  end subroutine h5w_abort

  ! ---------------------------------------------------------------------------------------------
  ! Internals

  !> True if the file is open; otherwise sets `err` naming `what`.
  logical function check_open(this, what, err)
    class(h5_writer_t), intent(in) :: this
    character(len=*), intent(in) :: what
    type(error_t), intent(inout) :: err
    check_open = this%opened
    if (check_open) return
    if (allocated(this%path)) then
      call err%set(ERR_IO, this%path // ': cannot write ' // what // ': the file is not open')
    else
      call err%set(ERR_IO, 'cannot write ' // what // ': the HDF5 writer was never opened')
    end if
  end function check_open

  !> Open `object` to attach attribute `name` to it; obj_id = -1 and `err` set on failure.
  subroutine open_object(this, object, name, obj_id, err)
    class(h5_writer_t), intent(in) :: this
    character(len=*), intent(in) :: object, name
    integer(hid_t), intent(out) :: obj_id
    type(error_t), intent(inout) :: err
    integer :: hdferr
    obj_id = -1
    if (.not. check_open(this, "attribute '" // name // "' of '" // object // "'", err)) return
    call h5oopen_f(this%file_id, abs_name(object), obj_id, hdferr)
    if (hdferr < 0) then
      obj_id = -1
      call err%set(ERR_IO, this%path // ": cannot write attribute '" // name // "': no object '" &
                   // abs_name(object) // "' in the file")
    end if
  end subroutine open_object

  !> Close what open_object opened (a group or a dataset, so h5oclose).
  subroutine close_object(obj_id)
    integer(hid_t), intent(inout) :: obj_id
    integer :: hdferr
    if (obj_id >= 0) call h5oclose_f(obj_id, hdferr)
    obj_id = -1
  end subroutine close_object

  !> Name from the root: 'time' -> '/time'.
  pure function abs_name(name) result(full)
    character(len=*), intent(in) :: name
    character(len=:), allocatable :: full
    if (len(name) > 0) then
      if (name(1:1) == '/') then
        full = name
        return
      end if
    end if
    full = '/' // name
  end function abs_name

  !> Create dataset `name` (with missing parent groups) of shape `dims` (Fortran order) and write
  !> the contiguous buffer `buf` (c_null_ptr for an empty dataset).
  subroutine write_dataset(this, name, dims, mem_type, file_type, buf, err, units)
    class(h5_writer_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    integer(hsize_t), intent(in) :: dims(:)
    integer(hid_t), intent(in) :: mem_type, file_type
    type(c_ptr), intent(in) :: buf
    type(error_t), intent(inout) :: err
    character(len=*), intent(in), optional :: units
    character(len=:), allocatable :: full
    integer(hid_t) :: lcpl_id, dset_id
    integer :: hdferr
    logical :: exists

    full = abs_name(name)
    if (.not. check_open(this, "dataset '" // full // "'", err)) return
    if (len(full) < 2 .or. full(len(full):len(full)) == '/') then
      call err%set(ERR_IO, this%path // ": cannot write dataset '" // full // "': not a valid name")
      return
    end if
    ! h5lexists_f fails when a parent group is missing: that also means "does not exist".
    call h5lexists_f(this%file_id, full, exists, hdferr)
    if (hdferr == 0 .and. exists) then
      call err%set(ERR_IO, this%path // ": cannot write dataset '" // full // &
                   "': it exists already")
      return
    end if

    dset_id = -1
    ! Link creation that makes the missing parent groups.
    call h5pcreate_f(H5P_LINK_CREATE_F, lcpl_id, hdferr)
    if (hdferr < 0) lcpl_id = -1
    if (hdferr == 0) call h5pset_create_inter_group_f(lcpl_id, 1, hdferr)
    if (hdferr < 0) then
      call err%set(ERR_IO, this%path // ": cannot set up creating dataset '" // full // "'")
    else
      call h5_create_dataset(this%path, this%file_id, full, dims, file_type, dset_id, err, &
                             lcpl=lcpl_id, hint=' (is a parent a dataset rather than a group?)', &
                             mem_type=mem_type, data=buf)
    end if
    if (present(units)) call h5_put_string_attr(this%path, dset_id, full, 'units', units, err)
    call h5_close(dset_id)
    call h5_close(lcpl_id)
  end subroutine write_dataset
end module io_hdf5
