!> HDF5 helpers shared by the result writers io_hdf5 (one file per run) and io_sweep_file (the
!> sweep result file), so that both set up the library, build string types, attach attributes
!> and create datasets the same way and report failures in the same words (the reading
!> helpers, for resuming a sweep, are in io_h5read).
!>
!> Writing helpers take the file's path (only for messages) and report failures in `err` (code
!> ERR_IO; ERR_INPUT for bad names) with a message naming the file and the object. They do
!> nothing when `err` already holds an error, so a sequence of calls stops at the first failure
!> and reports it. Reading helpers (used to resume a sweep) say *why* they failed in `why`
!> (H5_MISSING ...) instead: only the caller knows what the file was meant to be, and so how to
!> word the message. Handles are closed with `h5_close`. The module has no state.
module io_h5base
  use, intrinsic :: iso_c_binding, only: c_ptr, c_loc, c_null_ptr, c_char, c_null_char, &
    c_size_t, c_associated, c_f_pointer
  use hdf5, only: hid_t, hsize_t, size_t, h5open_f, h5iis_valid_f, h5iget_type_f, &
    h5eset_auto_f, H5T_NATIVE_DOUBLE, H5I_GROUP_F, H5I_DATATYPE_F, H5I_DATASPACE_F, &
    H5I_DATASET_F, H5I_ATTR_F, H5I_GENPROP_LST_F, h5screate_f, h5screate_simple_f, h5sclose_f, &
    h5sselect_hyperslab_f, H5S_SCALAR_F, H5S_SELECT_SET_F, h5pcreate_f, h5pclose_f, &
    H5P_GROUP_CREATE_F, h5pset_obj_track_times_f, h5pset_link_creation_order_f, &
    H5P_CRT_ORDER_TRACKED_F, H5P_CRT_ORDER_INDEXED_F, h5gcreate_f, h5gclose_f, h5dcreate_f, &
    h5dwrite_f, h5dclose_f, h5dget_space_f, h5dget_type_f, h5acreate_f, h5awrite_f, h5aclose_f, &
    h5aexists_f, h5adelete_f, h5tcopy_f, h5tset_cset_f, h5tset_strpad_f, h5tset_size_f, &
    h5tget_size_f, h5tclose_f, h5kind_to_type, H5T_STRING, H5T_C_S1, H5T_CSET_UTF8_F, &
    H5T_STR_NULLTERM_F, H5T_STR_NULLPAD_F, H5T_IEEE_F64LE, H5T_STD_I32LE, H5T_STD_I64LE, &
    H5_REAL_KIND, H5_INTEGER_KIND
  use core_kinds, only: wp, i8
  use core_error, only: error_t, ERR_INPUT, ERR_IO
  use core_strings, only: int_str
  implicit none
  private
  public :: h5_init, h5_close, h5_string_type, h5_int_file_type
  public :: h5_put_string_attr, h5_put_real_attr, h5_put_int_attr
  public :: h5_create_dataset, h5_create_group, h5_check_names, h5_write_element

  !> `h5_put_int_attr(path, obj_id, object, name, value, err)`: default integer as 32-bit,
  !> integer(i8) as 64-bit little-endian.
  interface h5_put_int_attr
    module procedure put_int_attr, put_int_attr_i8
  end interface h5_put_int_attr

  !> `h5_write_element(path, dset_id, name, i, value, err)`: element i (1-based) of the rank-1
  !> dataset `dset_id`, in place; value real(wp), default integer, or text for a dataset of
  !> fixed-length strings. `path` starts the message, `name` names the dataset in it.
  interface h5_write_element
    module procedure write_element_real, write_element_int, write_element_text
  end interface h5_write_element


contains

  ! ---------------------------------------------------------------------------------------------
  ! Library and handles

  !> Initialise the HDF5 library and its Fortran interface unless that is done already, and
  !> switch off HDF5's automatic error-stack printing (for the whole process): failures come back
  !> in `err` instead. h5open_f is idempotent for the C library, but HDF5 1.10's Fortran wrapper
  !> copies its ~55 predefined types again on every call (over 20000 calls: 600 MB and minutes),
  !> so look first whether a predefined type id is valid (it is 0, never valid, before the first
  !> h5open_f and invalid again after h5close_f). The library is never closed here.
  subroutine h5_init(path, err)
    character(len=*), intent(in) :: path
    type(error_t), intent(inout) :: err
    logical :: ready
    integer :: hdferr
    if (.not. err%ok()) return
    call h5iis_valid_f(H5T_NATIVE_DOUBLE, ready, hdferr)
    if (hdferr /= 0 .or. .not. ready) call h5open_f(hdferr)
    if (hdferr < 0) then
      call err%set(ERR_IO, path // ': cannot initialise the HDF5 library')
      return
    end if
    call h5eset_auto_f(0, hdferr)
  end subroutine h5_init

  !> Close a dataset, dataspace, datatype, attribute, property list or group (HDF5 says which it
  !> is), ignoring errors, and set `id` to -1; -1 (nothing open) is left alone. Files are not
  !> closed here: their owners need the status of the close.
  subroutine h5_close(id)
    integer(hid_t), intent(inout) :: id
    integer :: kind_, hdferr
    if (id < 0) return
    call h5iget_type_f(id, kind_, hdferr)
    if (hdferr == 0) then
      if (kind_ == H5I_DATASET_F) then
        call h5dclose_f(id, hdferr)
      else if (kind_ == H5I_DATASPACE_F) then
        call h5sclose_f(id, hdferr)
      else if (kind_ == H5I_DATATYPE_F) then
        call h5tclose_f(id, hdferr)
      else if (kind_ == H5I_ATTR_F) then
        call h5aclose_f(id, hdferr)
      else if (kind_ == H5I_GENPROP_LST_F) then
        call h5pclose_f(id, hdferr)
      else if (kind_ == H5I_GROUP_F) then
        call h5gclose_f(id, hdferr)
      end if
    end if
    id = -1
  end subroutine h5_close

  !> A UTF-8 string type: variable-length NUL-terminated (h5py reads `str`; any length, e.g. a
  !> whole input file) or, with `fixed_len`, fixed-length NUL-padded of that many bytes (h5py
  !> reads `bytes`; fixed length is what lets a dataset be overwritten in place). The caller
  !> closes type_id (h5_close), also when hdferr < 0 (it is -1 if the type was never made).
  subroutine h5_string_type(type_id, hdferr, fixed_len)
    integer(hid_t), intent(out) :: type_id
    integer, intent(out) :: hdferr
    integer, intent(in), optional :: fixed_len
    if (present(fixed_len)) then
      call h5tcopy_f(H5T_C_S1, type_id, hdferr)
    else
      call h5tcopy_f(H5T_STRING, type_id, hdferr)
    end if
    if (hdferr < 0) then
      type_id = -1
      return
    end if
    if (present(fixed_len)) then
      call h5tset_size_f(type_id, int(fixed_len, size_t), hdferr)
      if (hdferr == 0) call h5tset_strpad_f(type_id, H5T_STR_NULLPAD_F, hdferr)
    else
      call h5tset_strpad_f(type_id, H5T_STR_NULLTERM_F, hdferr)
    end if
    if (hdferr == 0) call h5tset_cset_f(type_id, H5T_CSET_UTF8_F, hdferr)
  end subroutine h5_string_type

  !> File type of an integer kind: little-endian 32 or 64 bit.
  function h5_int_file_type(kind_) result(type_id)
    integer, intent(in) :: kind_
    integer(hid_t) :: type_id
    if (kind_ == i8 .or. (kind_ == kind(0) .and. storage_size(0) > 32)) then
      type_id = H5T_STD_I64LE
    else
      type_id = H5T_STD_I32LE
    end if
  end function h5_int_file_type

  ! ---------------------------------------------------------------------------------------------
  ! Attributes: scalars of the open object `obj_id`; `object` names it in messages.

  !> Replace attribute `name` of the open object `obj_id` by a scalar of file type `file_type`
  !> and write `buf` (of memory type `mem_type`) into it.
  subroutine h5_put_attr(path, obj_id, object, name, mem_type, file_type, buf, err)
    character(len=*), intent(in) :: path, object, name
    integer(hid_t), intent(in) :: obj_id, mem_type, file_type
    type(c_ptr), intent(in) :: buf
    type(error_t), intent(inout) :: err
    character(len=:), allocatable :: what
    integer(hid_t) :: space_id, attr_id
    integer :: hdferr
    logical :: exists

    if (.not. err%ok()) return
    what = "attribute '" // name // "' of '" // object // "'"
    if (len(name) == 0) then
      call err%set(ERR_IO, path // ": cannot write an attribute with an empty name on '" // &
                   object // "'")
      return
    end if
    call h5aexists_f(obj_id, name, exists, hdferr)
    if (hdferr == 0 .and. exists) call h5adelete_f(obj_id, name, hdferr)
    if (hdferr < 0) then
      call err%set(ERR_IO, path // ': cannot replace ' // what)
      return
    end if

    space_id = -1
    attr_id = -1
    work: block
      call h5screate_f(H5S_SCALAR_F, space_id, hdferr)
      if (hdferr < 0) then
        space_id = -1
        call err%set(ERR_IO, path // ': cannot create the dataspace of ' // what)
        exit work
      end if
      call h5acreate_f(obj_id, name, file_type, space_id, attr_id, hdferr)
      if (hdferr < 0) then
        attr_id = -1
        call err%set(ERR_IO, path // ': cannot create ' // what)
        exit work
      end if
      call h5awrite_f(attr_id, mem_type, buf, hdferr)
      if (hdferr < 0) call err%set(ERR_IO, path // ': cannot write ' // what)
    end block work
    call h5_close(attr_id)
    call h5_close(space_id)
  end subroutine h5_put_attr

  !> Attribute `name` = `value` as a variable-length UTF-8 string (h5py reads it as str).
  subroutine h5_put_string_attr(path, obj_id, object, name, value, err)
    character(len=*), intent(in) :: path, object, name, value
    integer(hid_t), intent(in) :: obj_id
    type(error_t), intent(inout) :: err
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
    call h5_string_type(type_id, hdferr)
    if (hdferr < 0) then
      call err%set(ERR_IO, path // ": cannot make the string type of attribute '" // name // &
                   "' of '" // object // "'")
    else
      call h5_put_attr(path, obj_id, object, name, type_id, type_id, c_loc(ptr), err)
    end if
    call h5_close(type_id)
  end subroutine h5_put_string_attr

  !> Attribute `name` = `value`, real(wp) stored as IEEE 64-bit.
  subroutine h5_put_real_attr(path, obj_id, object, name, value, err)
    character(len=*), intent(in) :: path, object, name
    integer(hid_t), intent(in) :: obj_id
    real(wp), intent(in) :: value
    type(error_t), intent(inout) :: err
    real(wp), target :: buf
    buf = value
    call h5_put_attr(path, obj_id, object, name, h5kind_to_type(wp, H5_REAL_KIND), &
                     H5T_IEEE_F64LE, c_loc(buf), err)
  end subroutine h5_put_real_attr

  subroutine put_int_attr(path, obj_id, object, name, value, err)
    character(len=*), intent(in) :: path, object, name
    integer(hid_t), intent(in) :: obj_id
    integer, intent(in) :: value
    type(error_t), intent(inout) :: err
    integer, target :: buf
    buf = value
    call h5_put_attr(path, obj_id, object, name, h5kind_to_type(kind(buf), H5_INTEGER_KIND), &
                     h5_int_file_type(kind(buf)), c_loc(buf), err)
  end subroutine put_int_attr

  subroutine put_int_attr_i8(path, obj_id, object, name, value, err)
    character(len=*), intent(in) :: path, object, name
    integer(hid_t), intent(in) :: obj_id
    integer(i8), intent(in) :: value
    type(error_t), intent(inout) :: err
    integer(i8), target :: buf
    buf = value
    call h5_put_attr(path, obj_id, object, name, h5kind_to_type(i8, H5_INTEGER_KIND), &
                     h5_int_file_type(i8), c_loc(buf), err)
  end subroutine put_int_attr_i8

  ! ---------------------------------------------------------------------------------------------
  ! Datasets and groups

  !> Create dataset `name` under `loc_id` with shape `dims` (Fortran order) and file type
  !> `file_type`, with the optional creation (dcpl) and link creation (lcpl) property lists, and
  !> write `data` (contiguous, of memory type `mem_type`) into it if given and not empty; returns
  !> it open in `dset_id` (-1 if it was not made). `hint` ends the message if h5dcreate fails.
  subroutine h5_create_dataset(path, loc_id, name, dims, file_type, dset_id, err, dcpl, lcpl, &
                               hint, mem_type, data)
    character(len=*), intent(in) :: path, name
    integer(hid_t), intent(in) :: loc_id, file_type
    integer(hsize_t), intent(in) :: dims(:)
    integer(hid_t), intent(out) :: dset_id
    type(error_t), intent(inout) :: err
    integer(hid_t), intent(in), optional :: dcpl, lcpl, mem_type
    character(len=*), intent(in), optional :: hint
    type(c_ptr), intent(in), optional :: data
    integer(hid_t) :: space_id
    integer :: hdferr
    dset_id = -1
    if (.not. err%ok()) return
    call h5screate_simple_f(size(dims), dims, space_id, hdferr)
    if (hdferr < 0) then
      call err%set(ERR_IO, path // ": cannot create the dataspace of dataset '" // name // "'")
      return
    end if
    call h5dcreate_f(loc_id, name, file_type, space_id, dset_id, hdferr, dcpl_id=dcpl, &
                     lcpl_id=lcpl)
    call h5_close(space_id)
    if (hdferr < 0) then
      dset_id = -1
      if (present(hint)) then
        call err%set(ERR_IO, path // ": cannot create dataset '" // name // "'" // hint)
      else
        call err%set(ERR_IO, path // ": cannot create dataset '" // name // "'")
      end if
      return
    end if
    if (present(data) .and. present(mem_type) .and. product(dims) > 0) then
      call h5dwrite_f(dset_id, mem_type, data, hdferr)
      if (hdferr < 0) call err%set(ERR_IO, path // ": cannot write the data of dataset '" // &
                                   name // "'")
    end if
  end subroutine h5_create_dataset

  !> Names of the members of one group: trimmed, non-empty, without '/', not '.' or '..' (HDF5's
  !> rules for link names), no repeats. `what` says what they name in the message; ERR_INPUT.
  subroutine h5_check_names(path, what, names, err)
    character(len=*), intent(in) :: path, what, names(:)
    type(error_t), intent(inout) :: err
    character(len=:), allocatable :: a
    integer :: i, k
    do i = 1, size(names)
      if (.not. err%ok()) return
      a = trim(adjustl(names(i)))
      if (len(a) == 0) then
        call err%set(ERR_INPUT, path // ': ' // what // ' ' // int_str(i) // ' has an empty name')
      else if (index(a, '/') > 0) then
        call err%set(ERR_INPUT, path // ': ' // what // " name '" // a // "' contains '/'")
      else if (a == '.' .or. a == '..') then
        call err%set(ERR_INPUT, path // ': ' // what // " name '" // a // "' is not allowed")
      end if
      do k = 1, i - 1
        if (trim(adjustl(names(k))) == a) call err%set(ERR_INPUT, path // ': ' // what // &
                                                       " name '" // a // "' is given twice")
      end do
    end do
  end subroutine h5_check_names

  !> Group `name` without time stamps (so that nothing in its header changes later and files
  !> are reproducible), optionally keeping (and indexing) the creation order of its members.
  subroutine h5_create_group(path, loc_id, name, keep_order, err)
    character(len=*), intent(in) :: path, name
    integer(hid_t), intent(in) :: loc_id
    logical, intent(in) :: keep_order
    type(error_t), intent(inout) :: err
    integer(hid_t) :: gcpl, gid
    integer :: hdferr
    if (.not. err%ok()) return
    call h5pcreate_f(H5P_GROUP_CREATE_F, gcpl, hdferr)
    if (hdferr < 0) then
      call err%set(ERR_IO, path // ": cannot set up creating group '" // name // "'")
      return
    end if
    call h5pset_obj_track_times_f(gcpl, .false., hdferr)
    if (hdferr == 0 .and. keep_order) &
      call h5pset_link_creation_order_f(gcpl, ior(H5P_CRT_ORDER_TRACKED_F, &
                                                  H5P_CRT_ORDER_INDEXED_F), hdferr)
    if (hdferr == 0) call h5gcreate_f(loc_id, name, gid, hdferr, gcpl_id=gcpl)
    if (hdferr < 0) then
      call err%set(ERR_IO, path // ": cannot create group '" // name // "'")
    else
      call h5gclose_f(gid, hdferr)
    end if
    call h5pclose_f(gcpl, hdferr)
  end subroutine h5_create_group

  subroutine write_element_real(path, dset_id, name, i, value, err)
    character(len=*), intent(in) :: path, name
    integer(hid_t), intent(in) :: dset_id
    integer, intent(in) :: i
    real(wp), intent(in) :: value
    type(error_t), intent(inout) :: err
    real(wp), target :: buf
    buf = value
    call write_element_buf(path, dset_id, name, i, h5kind_to_type(wp, H5_REAL_KIND), c_loc(buf), &
                           err)
  end subroutine write_element_real

  subroutine write_element_int(path, dset_id, name, i, value, err)
    character(len=*), intent(in) :: path, name
    integer(hid_t), intent(in) :: dset_id
    integer, intent(in) :: i, value
    type(error_t), intent(inout) :: err
    integer, target :: buf
    buf = value
    call write_element_buf(path, dset_id, name, i, h5kind_to_type(kind(buf), H5_INTEGER_KIND), &
                           c_loc(buf), err)
  end subroutine write_element_int

  !> Text into a dataset of fixed-length strings (h5_string_type with fixed_len), NUL-padded;
  !> longer text is cut to the string length, moved back to the start of a UTF-8 character if
  !> the cut would split one.
  subroutine write_element_text(path, dset_id, name, i, value, err)
    character(len=*), intent(in) :: path, name, value
    integer(hid_t), intent(in) :: dset_id
    integer, intent(in) :: i
    type(error_t), intent(inout) :: err
    character(len=:), allocatable, target :: field
    integer(hid_t) :: type_id
    integer(size_t) :: width
    integer :: hdferr, n
    if (.not. err%ok()) return
    ! The dataset's own string type serves as the memory type too: no conversion.
    call h5dget_type_f(dset_id, type_id, hdferr)
    if (hdferr < 0) type_id = -1
    if (hdferr == 0) call h5tget_size_f(type_id, width, hdferr)
    if (hdferr < 0) then
      call err%set(ERR_IO, path // ': cannot make the string type of ' // name)
    else
      n = min(len(value), int(width))
      if (n < len(value)) then
        ! value(n+1:n+1) starts the part cut off; while it is a continuation byte (10xxxxxx),
        ! the character it belongs to began at or before n: drop that character too.
        do while (n > 0)
          if (iand(ichar(value(n + 1:n + 1)), 192) /= 128) exit
          n = n - 1
        end do
      end if
      field = value(1:n) // repeat(c_null_char, int(width) - n)
      call write_element_buf(path, dset_id, name, i, type_id, c_loc(field), err)
    end if
    call h5_close(type_id)
  end subroutine write_element_text

  !> Write one element (i, 1-based) of the open rank-1 dataset `dset_id` from `buf`.
  subroutine write_element_buf(path, dset_id, name, i, mem_type, buf, err)
    character(len=*), intent(in) :: path, name
    integer(hid_t), intent(in) :: dset_id, mem_type
    integer, intent(in) :: i
    type(c_ptr), intent(in) :: buf
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
      call h5sselect_hyperslab_f(fspace, H5S_SELECT_SET_F, [int(i - 1, hsize_t)], [1_hsize_t], &
                                 hdferr)
      if (hdferr < 0) exit work
      call h5screate_simple_f(1, [1_hsize_t], mspace, hdferr)
      if (hdferr < 0) then
        mspace = -1
        exit work
      end if
      call h5dwrite_f(dset_id, mem_type, buf, hdferr, mspace, fspace)
    end block work
    if (hdferr < 0) call err%set(ERR_IO, path // ": cannot write to dataset '" // name // "'")
    call h5_close(mspace)
    call h5_close(fspace)
  end subroutine write_element_buf

end module io_h5base
