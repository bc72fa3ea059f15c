!> Small file-system operations Fortran lacks: rename, delete, fsync, probing an output path,
!> and the interrupt guard of a result file (POSIX, via src/io/io_fs.c).
!>
!> The guard: once `install_interrupt_guard` has run (the executables do it at start), SIGINT and
!> SIGTERM delete the result file being written (its temporary name, and the final one from the
!> moment the commit starts), print one line and exit with 130 or 143. Library callers that do
!> not install it keep the default signal behaviour; `guard_result_file` is then harmless.
!>
!> Paths are passed as given (not trimmed). Failures come back in `err` (ERR_IO) with the path(s)
!> and the system's reason, e.g. "cannot rename 'a.tmp' to 'a': No such file or directory".
module io_fs
  use, intrinsic :: iso_c_binding, only: c_char, c_int, c_size_t, c_null_char
  use core_error, only: error_t, ERR_IO
  implicit none
  private
  public :: rename_file, delete_file, sync_file, check_output_path, install_interrupt_guard, &
    guard_result_file, clear_result_guard, make_folder, same_file

  integer(c_int), parameter :: ENOENT = 2   !< errno "No such file or directory" (Linux)
  integer(c_int), parameter :: EISDIR = 21  !< errno "Is a directory" (Linux)

  interface
    integer(c_int) function c_rename(from, to) bind(C, name='flexmor_rename')
      import :: c_int, c_char
      character(kind=c_char), intent(in) :: from(*), to(*)
    end function c_rename

    integer(c_int) function c_mkdir(path) bind(C, name='flexmor_mkdir')
      import :: c_int, c_char
      character(kind=c_char), intent(in) :: path(*)
    end function c_mkdir
    integer(c_int) function c_unlink(path) bind(C, name='flexmor_unlink')
      import :: c_int, c_char
      character(kind=c_char), intent(in) :: path(*)
    end function c_unlink

    integer(c_int) function c_fsync_path(path) bind(C, name='flexmor_fsync_path')
      import :: c_int, c_char
      character(kind=c_char), intent(in) :: path(*)
    end function c_fsync_path

    integer(c_int) function c_same_file(a, b) bind(C, name='flexmor_same_file')
      import :: c_int, c_char
      character(kind=c_char), intent(in) :: a(*), b(*)
    end function c_same_file
    integer(c_int) function c_probe_output(path, tmp, folder_missing) &
        bind(C, name='flexmor_probe_output')
      import :: c_int, c_char
      character(kind=c_char), intent(in) :: path(*), tmp(*)
      integer(c_int), intent(out) :: folder_missing
    end function c_probe_output

    integer(c_int) function c_guard_install(msg_int, msg_term) &
        bind(C, name='flexmor_guard_install')
      import :: c_int, c_char
      character(kind=c_char), intent(in) :: msg_int(*), msg_term(*)
    end function c_guard_install

    subroutine c_guard_set(tmp, final, final_ours) bind(C, name='flexmor_guard_set')
      import :: c_int, c_char
      character(kind=c_char), intent(in) :: tmp(*), final(*)
      integer(c_int), value :: final_ours
    end subroutine c_guard_set

    subroutine c_guard_clear() bind(C, name='flexmor_guard_clear')
    end subroutine c_guard_clear

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

  !> Create the folder `path` (its parent must exist); one that exists already is fine.
  subroutine make_folder(path, err)
    character(len=*), intent(in) :: path
    type(error_t), intent(out) :: err
    integer(c_int) :: rc
    rc = c_mkdir(to_c(path))
    if (rc /= 0) call err%set(ERR_IO, "cannot create the folder '" // path // "': " // &
      errno_text(rc))
  end subroutine make_folder

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

  !> Whether both paths name one existing file (however spelled, through links too).
  logical function same_file(a, b)
    character(len=*), intent(in) :: a, b
    same_file = c_same_file(to_c(a), to_c(b)) /= 0
  end function same_file

  !> Fail early (ERR_IO) when `path` cannot become the result file: it is a folder, a device
  !> or another file that is not a regular one, the `input` file itself, its folder does not
  !> exist or is not writable. Run before the analyses, so a long run does not end in a write
  !> error (or replace the scene it read). Creates and removes `path // '.tmp'`, the name the
  !> writer uses.
  subroutine check_output_path(path, err, input)
    character(len=*), intent(in) :: path
    type(error_t), intent(out) :: err
    character(len=*), intent(in), optional :: input
    integer(c_int), parameter :: NOT_REGULAR = -1_c_int   ! FLEXMOR_NOT_REGULAR of io_fs.c
    integer(c_int) :: rc, folder_missing
    integer :: slash
    if (len_trim(path) == 0) then
      call err%set(ERR_IO, 'the result file name is empty')
      return
    end if
    if (present(input)) then
      if (same_file(path, input)) then
        call err%set(ERR_IO, "cannot write the result file '" // path // "': it is the " // &
          "input file '" // input // "' (give another name, e.g. -o result.h5)")
        return
      end if
    end if
    ! An interrupt during the probe must not leave the probe file behind either.
    call guard_result_file(path // '.tmp', path, final_ours=.false.)
    rc = c_probe_output(to_c(path), to_c(path // '.tmp'), folder_missing)
    call clear_result_guard()
    if (rc == 0) return
    slash = index(path, '/', back=.true.)
    if (rc == NOT_REGULAR) then
      call err%set(ERR_IO, "cannot write the result file '" // path // "': it is not a " // &
        "regular file (a device, pipe or socket), which the result would replace")
    else if (rc == EISDIR) then
      call err%set(ERR_IO, "cannot write the result file '" // path // "': it is a folder " // &
        "(give a file name, e.g. -o " // path // "/result.h5)")
    else if (folder_missing /= 0 .and. slash > 1) then
      call err%set(ERR_IO, "cannot write the result file '" // path // "': the folder '" // &
        path(1:slash - 1) // "' does not exist")
    else
      call err%set(ERR_IO, "cannot write the result file '" // path // "': " // errno_text(rc))
    end if
  end subroutine check_output_path

  !> Make SIGINT and SIGTERM remove the guarded result file, print `program: interrupted
  !> (SIGINT): outcome` (or terminated, SIGTERM) and exit 130/143; `outcome` says what is left.
  !> With `silent`, print nothing (the other ranks of an MPI job).
  subroutine install_interrupt_guard(program, outcome, err, silent)
    character(len=*), intent(in) :: program, outcome
    type(error_t), intent(out) :: err
    logical, intent(in), optional :: silent
    character(len=*), parameter :: NL = achar(10)
    integer(c_int) :: rc
    if (present(silent)) then
      if (silent) then
        rc = c_guard_install(to_c(''), to_c(''))
        if (rc /= 0) call err%set(ERR_IO, 'cannot install the SIGINT/SIGTERM handler: ' // &
          errno_text(rc))
        return
      end if
    end if
    rc = c_guard_install(to_c(program // ': interrupted (SIGINT): ' // outcome // NL), &
      to_c(program // ': terminated (SIGTERM): ' // outcome // NL))
    if (rc /= 0) call err%set(ERR_IO, 'cannot install the SIGINT/SIGTERM handler: ' // &
      errno_text(rc))
  end subroutine install_interrupt_guard

  !> From now on an interrupt deletes `tmp`, and `final` too when `final_ours`.
  subroutine guard_result_file(tmp, final, final_ours)
    character(len=*), intent(in) :: tmp, final
    logical, intent(in) :: final_ours
    call c_guard_set(to_c(tmp), to_c(final), merge(1_c_int, 0_c_int, final_ours))
  end subroutine guard_result_file

  !> An interrupt deletes nothing any more.
  subroutine clear_result_guard()
    call c_guard_clear()
  end subroutine clear_result_guard

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
