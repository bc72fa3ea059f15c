!> HDF5 reading helpers (to check and resume an existing sweep result file): each says *why*
!> it failed in `why` (H5_MISSING ...), as only the caller knows what the file was meant to be
!> and so how to word the message. The module has no state.
module io_h5read
  use, intrinsic :: iso_c_binding, only: c_ptr, c_loc, c_null_ptr, c_char, c_null_char, &
    c_size_t, c_associated, c_f_pointer
  use hdf5, only: hid_t, hsize_t, size_t, h5fopen_f, h5fclose_f, H5F_ACC_RDONLY_F, h5sclose_f, &
    H5S_SCALAR_F, h5sget_simple_extent_ndims_f, h5sget_simple_extent_dims_f, &
    h5sget_simple_extent_type_f, h5pcreate_f, h5pclose_f, H5P_FILE_ACCESS_F, H5P_DEFAULT_F, &
    h5pset_file_locking_f, h5gget_info_by_name_f, h5lget_name_by_idx_f, h5lexists_f, &
    H5_INDEX_CRT_ORDER_F, H5_ITER_INC_F, h5dopen_f, h5dget_space_f, h5dget_type_f, &
    h5dvlen_reclaim_f, h5aread_f, h5aexists_by_name_f, h5aopen_by_name_f, h5aget_type_f, &
    h5aget_space_f, h5tget_size_f, h5tclose_f, h5tget_class_f, h5tis_variable_str_f, &
    h5kind_to_type, H5T_INTEGER_F, H5T_STRING_F, H5_INTEGER_KIND
  use io_h5base, only: h5_close
  implicit none
  private
  public :: h5_read_string_attr, h5_read_int_attr, h5_open_dataset, h5_dataset_shape, &
            h5_member_names, h5_probe_read_only
  public :: H5_OK, H5_MISSING, H5_UNOPENABLE, H5_BAD_TYPE, H5_UNREADABLE

  !> `why` of the reading helpers.
  integer, parameter :: H5_OK = 0          !< read
  integer, parameter :: H5_MISSING = 1     !< no such object, attribute or group
  integer, parameter :: H5_UNOPENABLE = 2  !< it is there but does not open (damaged file?)
  integer, parameter :: H5_BAD_TYPE = 3    !< it has the wrong type or shape
  integer, parameter :: H5_UNREADABLE = 4  !< opened, but reading it failed (damaged file?)


  interface
    pure integer(c_size_t) function c_strlen(s) bind(C, name='strlen')
      import :: c_ptr, c_size_t
      type(c_ptr), value, intent(in) :: s
    end function c_strlen
  end interface

contains

  ! ---------------------------------------------------------------------------------------------
  ! Reading (to check and resume an existing file)

  !> Open attribute `name` of object `object` (a path from `loc_id`); aid = -1 unless why = H5_OK.
  subroutine open_attr(loc_id, object, name, aid, why)
    integer(hid_t), intent(in) :: loc_id
    character(len=*), intent(in) :: object, name
    integer(hid_t), intent(out) :: aid
    integer, intent(out) :: why
    integer :: hdferr
    logical :: exists
    aid = -1
    why = H5_MISSING
    call h5aexists_by_name_f(loc_id, object, name, exists, hdferr)
    if (hdferr < 0 .or. .not. exists) return
    why = H5_UNOPENABLE
    call h5aopen_by_name_f(loc_id, object, name, aid, hdferr)
    if (hdferr < 0) then
      aid = -1
      return
    end if
    why = H5_OK
  end subroutine open_attr

  !> Read attribute `name` of `object`, a scalar variable-length string ('' if it is a null
  !> string); H5_BAD_TYPE if it is not a variable-length string.
  subroutine h5_read_string_attr(loc_id, object, name, value, why)
    integer(hid_t), intent(in) :: loc_id
    character(len=*), intent(in) :: object, name
    character(len=:), allocatable, intent(out) :: value
    integer, intent(out) :: why
    integer(hid_t) :: aid, tid, sid
    type(c_ptr), target :: ptr(1)
    type(c_ptr) :: p
    character(kind=c_char), pointer :: chars(:)
    integer :: hdferr, tclass, n, i
    logical :: vl
    value = ''
    call open_attr(loc_id, object, name, aid, why)
    if (why /= H5_OK) return
    tclass = -1
    vl = .false.
    call h5aget_type_f(aid, tid, hdferr)
    if (hdferr < 0) tid = -1
    if (hdferr == 0) call h5tget_class_f(tid, tclass, hdferr)
    if (hdferr == 0 .and. tclass == H5T_STRING_F) call h5tis_variable_str_f(tid, vl, hdferr)
    if (.not. vl) then
      why = H5_BAD_TYPE
    else
      ptr(1) = c_null_ptr
      p = c_loc(ptr)
      call h5aread_f(aid, tid, p, hdferr)
      if (hdferr < 0) then
        why = H5_UNREADABLE
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
    call h5_close(tid)
    call h5_close(aid)
  end subroutine h5_read_string_attr

  !> Read attribute `name` of `object`, a scalar integer (-1 unless why = H5_OK); H5_BAD_TYPE if
  !> it is not a scalar integer.
  subroutine h5_read_int_attr(loc_id, object, name, value, why)
    integer(hid_t), intent(in) :: loc_id
    character(len=*), intent(in) :: object, name
    integer, intent(out) :: value
    integer, intent(out) :: why
    integer(hid_t) :: aid, tid, sid
    integer, target :: buf
    type(c_ptr) :: p
    integer :: hdferr, tclass, stype
    value = -1
    call open_attr(loc_id, object, name, aid, why)
    if (why /= H5_OK) return
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
    if (tclass /= H5T_INTEGER_F .or. stype /= H5S_SCALAR_F) then
      why = H5_BAD_TYPE
    else
      p = c_loc(buf)
      call h5aread_f(aid, h5kind_to_type(kind(buf), H5_INTEGER_KIND), p, hdferr)
      if (hdferr < 0) then
        why = H5_UNREADABLE
      else
        value = buf
      end if
    end if
    call h5_close(aid)
  end subroutine h5_read_int_attr

  !> Open dataset `name` (a path from `loc_id`); dset_id = -1 unless why = H5_OK.
  subroutine h5_open_dataset(loc_id, name, dset_id, why)
    integer(hid_t), intent(in) :: loc_id
    character(len=*), intent(in) :: name
    integer(hid_t), intent(out) :: dset_id
    integer, intent(out) :: why
    integer :: hdferr
    logical :: exists
    dset_id = -1
    why = H5_MISSING
    call h5lexists_f(loc_id, name, exists, hdferr)
    if (hdferr < 0 .or. .not. exists) return
    why = H5_UNOPENABLE
    call h5dopen_f(loc_id, name, dset_id, hdferr)
    if (hdferr < 0) then
      dset_id = -1
      return
    end if
    why = H5_OK
  end subroutine h5_open_dataset

  !> Rank, number of elements and type class (H5T_FLOAT_F ...) of the open dataset `dset_id`,
  !> optionally the size in bytes of its type and whether it is a variable-length string; -1
  !> (and .true.) for what cannot be read.
  subroutine h5_dataset_shape(dset_id, rank, n, tclass, type_size, variable_str)
    integer(hid_t), intent(in) :: dset_id
    integer, intent(out) :: rank, tclass
    integer(hsize_t), intent(out) :: n
    integer(size_t), intent(out), optional :: type_size
    logical, intent(out), optional :: variable_str
    integer(hid_t) :: space_id, type_id
    integer(hsize_t), allocatable :: dims(:), maxdims(:)
    integer :: hdferr
    rank = -1
    n = -1
    tclass = -1
    if (present(type_size)) type_size = -1
    if (present(variable_str)) variable_str = .true.
    call h5dget_space_f(dset_id, space_id, hdferr)
    if (hdferr == 0) then
      call h5sget_simple_extent_ndims_f(space_id, rank, hdferr)
      if (hdferr == 0 .and. rank >= 0) then
        allocate(dims(rank), maxdims(rank))
        call h5sget_simple_extent_dims_f(space_id, dims, maxdims, hdferr)
        if (hdferr >= 0) n = product(dims)
      end if
      call h5sclose_f(space_id, hdferr)
    end if
    call h5dget_type_f(dset_id, type_id, hdferr)
    if (hdferr == 0) then
      call h5tget_class_f(type_id, tclass, hdferr)
      if (present(type_size)) call h5tget_size_f(type_id, type_size, hdferr)
      if (present(variable_str)) call h5tis_variable_str_f(type_id, variable_str, hdferr)
      call h5tclose_f(type_id, hdferr)
    end if
  end subroutine h5_dataset_shape

  !> Names of the members of group `group` in creation order (the group must track it);
  !> H5_MISSING if there is no such group, H5_UNREADABLE if it cannot be listed that way.
  subroutine h5_member_names(loc_id, group, names, why)
    integer(hid_t), intent(in) :: loc_id
    character(len=*), intent(in) :: group
    character(len=:), allocatable, intent(out) :: names(:)
    integer, intent(out) :: why
    integer :: storage_type, nlinks, max_corder, hdferr, k, longest
    integer(size_t) :: nsize
    character(len=1024) :: buf
    character(len=1024), allocatable :: raw(:)
    logical :: exists
    allocate(character(len=1) :: names(0))
    why = H5_MISSING
    call h5lexists_f(loc_id, group, exists, hdferr)
    if (hdferr == 0 .and. exists) &
      call h5gget_info_by_name_f(loc_id, group, storage_type, nlinks, max_corder, hdferr)
    if (hdferr < 0 .or. .not. exists) return
    why = H5_UNREADABLE
    allocate(raw(nlinks))
    longest = 1
    do k = 1, nlinks
      buf = ''
      call h5lget_name_by_idx_f(loc_id, group, H5_INDEX_CRT_ORDER_F, H5_ITER_INC_F, &
                                int(k - 1, hsize_t), buf, hdferr, nsize)
      if (hdferr < 0 .or. nsize > int(len(buf), size_t)) return
      raw(k) = buf(1:nsize)
      longest = max(longest, int(nsize))
    end do
    deallocate(names)
    allocate(character(len=longest) :: names(nlinks))
    do k = 1, nlinks
      names(k) = raw(k)(1:longest)
    end do
    why = H5_OK
  end subroutine h5_member_names

  !> Whether the HDF5 file `path` opens read-only without taking HDF5's file lock (`readable`:
  !> false means it is damaged) and taking it (`lockable`: false means another process holds it
  !> open for writing). Nothing is written.
  subroutine h5_probe_read_only(path, readable, lockable)
    character(len=*), intent(in) :: path
    logical, intent(out) :: readable, lockable
    integer(hid_t) :: fapl, fid
    integer :: hdferr
    readable = .false.
    lockable = .false.
    call h5pcreate_f(H5P_FILE_ACCESS_F, fapl, hdferr)
    if (hdferr == 0) then
      call h5pset_file_locking_f(fapl, .false., .true., hdferr)
      if (hdferr == 0) call h5fopen_f(path, H5F_ACC_RDONLY_F, fid, hdferr, access_prp=fapl)
      if (hdferr == 0) then
        readable = .true.
        call h5fclose_f(fid, hdferr)
      end if
      call h5pclose_f(fapl, hdferr)
    end if
    if (.not. readable) return
    call h5fopen_f(path, H5F_ACC_RDONLY_F, fid, hdferr)
    lockable = hdferr == 0
    if (lockable) call h5fclose_f(fid, hdferr)
  end subroutine h5_probe_read_only
end module io_h5read
