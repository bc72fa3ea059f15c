!> Small file-system operations Fortran lacks: rename, delete, fsync (POSIX, via src/io/io_fs.c).
!>
!> Paths are passed as given (not trimmed). Failures come back in `err` (ERR_IO) with the path(s)
!> and the system's reason, e.g. "cannot rename 'a.tmp' to 'a': No such file or directory".
module io_fs
  use, intrinsic :: iso_c_binding, only: c_char, c_int, c_size_t, c_null_char
  use core_error, only: error_t, ERR_IO
  implicit none
  private
  public :: rename_file, delete_file, sync_file

  integer(c_int), parameter :: ENOENT = 2  !< errno "No such file or directory" (Linux)

  interface
    integer(c_int) function c_rename(from, to) bind(C, name='flexmor_rename')
      import :: c_int, c_char
      character(kind=c_char), intent(in) :: from(*), to(*)
    end function c_rename

    integer(c_int) function c_unlink(path) bind(C, name='flexmor_unlink')
      import :: c_int, c_char
      character(kind=c_char), intent(in) :: path(*)
    end function c_unlink

    integer(c_int) function c_fsync_path(path) bind(C, name='flexmor_fsync_path')
      import :: c_int, c_char
      character(kind=c_char), intent(in) :: path(*)
    end function c_fsync_path

    subroutine c_strerror(code, buf, len) bind(C, name='flexmor_strerror')
      import :: c_int, c_char, c_size_t
      integer(c_int), value :: code
      character(kind=c_char), intent(out) :: buf(*)
      integer(c_size_t), value :: len
    end subroutine c_strerror
  end interface

contains

  !> Rename `from` to `to`, atomically replacing `to` if it exists (both on one file system).
  subroutine rename_file(from, to, err)
    character(len=*), intent(in) :: from, to
    type(error_t), intent(out) :: err
    integer(c_int) :: rc
    rc = c_rename(to_c(from), to_c(to))
    if (rc /= 0) call err%set(ERR_IO, "cannot rename '" // from // "' to '" // to // "': " &
                              // errno_text(rc))
  end subroutine rename_file

  !> Delete a file. A file that does not exist is not an error; other failures are reported in
  !> `err` when it is present and ignored otherwise (for removing leftovers on error paths).
  subroutine delete_file(path, err)
    character(len=*), intent(in) :: path
    type(error_t), intent(out), optional :: err
    integer(c_int) :: rc
    rc = c_unlink(to_c(path))
    if (rc /= 0 .and. rc /= ENOENT .and. present(err)) then
      call err%set(ERR_IO, "cannot delete '" // path // "': " // errno_text(rc))
    end if
  end subroutine delete_file

  !> Flush a closed file's contents to stable storage (fsync), e.g. before renaming it.
  subroutine sync_file(path, err)
    character(len=*), intent(in) :: path
    type(error_t), intent(out) :: err
    integer(c_int) :: rc
    rc = c_fsync_path(to_c(path))
    if (rc /= 0) call err%set(ERR_IO, "cannot sync '" // path // "' to disk: " // errno_text(rc))
  end subroutine sync_file

  !> NUL-terminated copy of a Fortran string.
  pure function to_c(s) result(c)
    character(len=*), intent(in) :: s
    character(kind=c_char, len=len(s) + 1) :: c
    c = s // c_null_char
  end function to_c

  function errno_text(code) result(text)
    integer(c_int), intent(in) :: code
    character(len=:), allocatable :: text
    character(kind=c_char) :: buf(200)
    integer :: i
    buf = c_null_char
    call c_strerror(code, buf, int(size(buf), c_size_t))
    text = ''
    do i = 1, size(buf)
      if (buf(i) == c_null_char) exit
      text = text // buf(i)
    end do
  end function errno_text
end module io_fs
