!> Reading HDF5 files back in the tests of the result writers (test_hdf5, test_sweep_file), with
!> the plain HDF5 API on purpose: the check does not go through the writers' own helpers
!> (io_h5base), so a mistake there cannot hide itself. Also what both test programs need besides:
!> the open-handle count that shows leaks, scratch file names, error text for check lines.
!>
!> Readers never fail loudly: a missing or unreadable object gives an empty array, an array
!> filled with -999 or '(unreadable)', which the test's comparison then reports. The HDF5
!> library must be initialised (h5open_f) before use. No module state.
module h5_read
  use, intrinsic :: iso_c_binding, only: c_ptr, c_loc, c_f_pointer, c_char, c_null_char, &
    c_null_ptr, c_associated
  use hdf5, only: hid_t, hsize_t, size_t, h5fget_obj_count_f, H5F_OBJ_ALL_F, H5F_OBJ_FILE_F, &
    H5F_OBJ_GROUP_F, H5F_OBJ_DATASET_F, h5dopen_f, h5dread_f, h5dclose_f, h5dget_space_f, &
    h5sget_simple_extent_ndims_f, h5sget_simple_extent_dims_f, h5sclose_f, h5aopen_by_name_f, &
    h5aread_f, h5aclose_f, h5aget_space_f, h5aget_type_f, h5tclose_f, h5dvlen_reclaim_f, &
    h5kind_to_type, H5_REAL_KIND, H5_INTEGER_KIND, H5P_DEFAULT_F
  use core_kinds, only: wp, i8
  use core_error, only: error_t
  use core_strings, only: int_str
  implicit none
  private
  public :: open_objects, dataset_dims, read_dataset, read_real, read_int, read_i8
  public :: read_string_attr, read_real_attr, read_i8_attr
  public :: scratch_dir, random_tag, exists, msg

contains

  !> Files, groups and datasets open in the HDF5 library. (The 1.10 Fortran wrapper offsets counts
  !> over all files by the number of its predefined types, so compare differences only.)
  integer(size_t) function open_objects() result(n)
    integer(size_t) :: k
    integer :: kinds(3), j, hdferr
    kinds = [H5F_OBJ_FILE_F, H5F_OBJ_GROUP_F, H5F_OBJ_DATASET_F]
    n = 0
    do j = 1, size(kinds)
      call h5fget_obj_count_f(int(H5F_OBJ_ALL_F, hid_t), kinds(j), k, hdferr)
      n = n + k
    end do
  end function open_objects

  !> Dimensions of dataset `name` in Fortran order (reversed from h5py's); empty if it does not
  !> open.
  function dataset_dims(fid, name) result(dims)
    integer(hid_t), intent(in) :: fid
    character(len=*), intent(in) :: name
    integer(hsize_t), allocatable :: dims(:)
    integer(hsize_t) :: d(7), maxd(7)
    integer(hid_t) :: did, sid
    integer :: rank, hdferr
    allocate(dims(0))
    call h5dopen_f(fid, name, did, hdferr)
    if (hdferr /= 0) return
    call h5dget_space_f(did, sid, hdferr)
    call h5sget_simple_extent_ndims_f(sid, rank, hdferr)
    call h5sget_simple_extent_dims_f(sid, d(1:rank), maxd(1:rank), hdferr)
    dims = d(1:rank)
    call h5sclose_f(sid, hdferr)
    call h5dclose_f(did, hdferr)
  end function dataset_dims

  !> Read all of dataset `name` into `buf` (memory type `mem_type`); ok = it opened and read.
  subroutine read_dataset(fid, name, mem_type, buf, ok)
    integer(hid_t), intent(in) :: fid, mem_type
    character(len=*), intent(in) :: name
    type(c_ptr), intent(in) :: buf
    logical, intent(out) :: ok
    integer(hid_t) :: did
    type(c_ptr) :: p
    integer :: hdferr
    p = buf
    ok = .false.
    call h5dopen_f(fid, name, did, hdferr)
    if (hdferr /= 0) return
    call h5dread_f(did, mem_type, p, hdferr)
    ok = hdferr == 0
    call h5dclose_f(did, hdferr)
  end subroutine read_dataset

  !> Length of the rank-1 dataset `name`; -1 if it does not open or has another rank.
  integer(hsize_t) function length_1d(fid, name) result(n)
    integer(hid_t), intent(in) :: fid
    character(len=*), intent(in) :: name
    integer(hsize_t), allocatable :: dims(:)
    allocate(dims, source=dataset_dims(fid, name))
    n = -1
    if (size(dims) == 1) n = dims(1)
  end function length_1d

  !> The rank-1 dataset `name` as real(wp): empty if it is missing or not rank 1, -999 where it
  !> does not read.
  function read_real(fid, name) result(r)
    integer(hid_t), intent(in) :: fid
    character(len=*), intent(in) :: name
    real(wp), allocatable, target :: r(:)
    logical :: ok
    allocate(r(max(0_hsize_t, length_1d(fid, name))))
    r = -999.0_wp
    if (size(r) > 0) call read_dataset(fid, name, h5kind_to_type(wp, H5_REAL_KIND), c_loc(r), ok)
  end function read_real

  !> As read_real, for default integers.
  function read_int(fid, name) result(v)
    integer(hid_t), intent(in) :: fid
    character(len=*), intent(in) :: name
    integer, allocatable, target :: v(:)
    logical :: ok
    allocate(v(max(0_hsize_t, length_1d(fid, name))))
    v = -999
    if (size(v) > 0) call read_dataset(fid, name, h5kind_to_type(kind(v), H5_INTEGER_KIND), &
                                       c_loc(v), ok)
  end function read_int

  !> As read_real, for integer(i8).
  function read_i8(fid, name) result(v)
    integer(hid_t), intent(in) :: fid
    character(len=*), intent(in) :: name
    integer(i8), allocatable, target :: v(:)
    logical :: ok
    allocate(v(max(0_hsize_t, length_1d(fid, name))))
    v = -999
    if (size(v) > 0) call read_dataset(fid, name, h5kind_to_type(i8, H5_INTEGER_KIND), c_loc(v), &
                                       ok)
  end function read_i8

  !> A scalar variable-length string attribute of `object`; '(unreadable)' if there is none.
  function read_string_attr(fid, object, name) result(s)
    integer(hid_t), intent(in) :: fid
    character(len=*), intent(in) :: object, name
    character(len=:), allocatable :: s
    integer(hid_t) :: aid, sid, tid
    type(c_ptr), target :: ptr(1)
    type(c_ptr) :: p
    character(kind=c_char), pointer :: chars(:)
    integer :: n, hdferr
    s = '(unreadable)'
    ptr(1) = c_null_ptr
    p = c_loc(ptr)
    call h5aopen_by_name_f(fid, object, name, aid, hdferr)
    if (hdferr /= 0) return
    ! The attribute's own type (variable-length UTF-8 string) serves as the memory type.
    call h5aget_type_f(aid, tid, hdferr)
    call h5aread_f(aid, tid, p, hdferr)
    if (hdferr == 0 .and. c_associated(ptr(1))) then
      call c_f_pointer(ptr(1), chars, [huge(0)])
      n = 0
      do while (chars(n + 1) /= c_null_char)
        n = n + 1
      end do
      deallocate(s)
      allocate(character(len=n) :: s)
      s = transfer(chars(1:n), s)
      call h5aget_space_f(aid, sid, hdferr)
      call h5dvlen_reclaim_f(tid, sid, H5P_DEFAULT_F, p, hdferr)
      call h5sclose_f(sid, hdferr)
    end if
    call h5tclose_f(tid, hdferr)
    call h5aclose_f(aid, hdferr)
  end function read_string_attr

  !> Read scalar attribute `name` of `object` into `buf` (memory type `mem_type`) if it opens.
  subroutine read_scalar_attr(fid, object, name, mem_type, buf)
    integer(hid_t), intent(in) :: fid, mem_type
    character(len=*), intent(in) :: object, name
    type(c_ptr), intent(in) :: buf
    integer(hid_t) :: aid
    type(c_ptr) :: p
    integer :: hdferr
    p = buf
    call h5aopen_by_name_f(fid, object, name, aid, hdferr)
    if (hdferr /= 0) return
    call h5aread_f(aid, mem_type, p, hdferr)
    call h5aclose_f(aid, hdferr)
  end subroutine read_scalar_attr

  !> A scalar attribute as real(wp); -1 if it does not read.
  real(wp) function read_real_attr(fid, object, name) result(v)
    integer(hid_t), intent(in) :: fid
    character(len=*), intent(in) :: object, name
    real(wp), target :: buf
    buf = -1
    call read_scalar_attr(fid, object, name, h5kind_to_type(wp, H5_REAL_KIND), c_loc(buf))
    v = buf
  end function read_real_attr

  !> A scalar attribute as integer(i8); -1 if it does not read.
  integer(i8) function read_i8_attr(fid, object, name) result(v)
    integer(hid_t), intent(in) :: fid
    character(len=*), intent(in) :: object, name
    integer(i8), target :: buf
    buf = -1
    call read_scalar_attr(fid, object, name, h5kind_to_type(i8, H5_INTEGER_KIND), c_loc(buf))
    v = buf
  end function read_i8_attr

  !> $TMPDIR, or /tmp when it is not set: where the tests write their files.
  function scratch_dir() result(d)
    character(len=:), allocatable :: d
    character(len=4096) :: buf
    integer :: n, stat
    call get_environment_variable('TMPDIR', buf, n, stat)
    if (stat == 0 .and. n > 0) then
      d = trim(buf)
    else
      d = '/tmp'
    end if
  end function scratch_dir

  !> A random number as text, for file names that concurrent test runs do not share.
  function random_tag() result(tag)
    character(len=:), allocatable :: tag
    real :: x
    call random_init(.false., .true.)
    call random_number(x)
    tag = int_str(int(x * 999999999.0))
  end function random_tag

  logical function exists(p)
    character(len=*), intent(in) :: p
    inquire(file=p, exist=exists)
  end function exists

  !> The message of `err` for a check line, '(none)' if there is none.
  function msg(err) result(m)
    type(error_t), intent(in) :: err
    character(len=:), allocatable :: m
    m = '(none)'
    if (allocated(err%message)) m = err%message
  end function msg
end module h5_read
