!> Explicit interfaces of the ARPACK routines flexmor calls (reverse communication): the
!> symmetric Lanczos pair for modes (reduction_eigen) and the non-symmetric Arnoldi pair for
!> the stability of Newton-Krylov statics (dynamics_static_krylov).
module core_arpack
  use core_kinds, only: wp
  implicit none
  private
  public :: dsaupd, dseupd, dnaupd, dneupd

  interface
    subroutine dsaupd(ido, bmat, n, which, nev, tol, resid, ncv, v, ldv, iparam, ipntr, &
      workd, workl, lworkl, info)
      import :: wp
      integer, intent(inout) :: ido
      character(len=1), intent(in) :: bmat
      integer, intent(in) :: n, nev, ncv, ldv, lworkl
      character(len=2), intent(in) :: which
      real(wp), intent(inout) :: tol
      real(wp), intent(inout) :: resid(*), v(ldv, *), workd(*), workl(*)
      integer, intent(inout) :: iparam(11), ipntr(11), info
    end subroutine dsaupd
    subroutine dseupd(rvec, howmny, sel, d, z, ldz, sigma, bmat, n, which, nev, tol, resid, &
      ncv, v, ldv, iparam, ipntr, workd, workl, lworkl, info)
      import :: wp
      logical, intent(in) :: rvec
      character(len=1), intent(in) :: howmny, bmat
      logical, intent(inout) :: sel(*)
      real(wp), intent(out) :: d(*)
      integer, intent(in) :: ldz, n, nev, ncv, ldv, lworkl
      real(wp), intent(out) :: z(ldz, *)
      real(wp), intent(in) :: sigma
      character(len=2), intent(in) :: which
      real(wp), intent(inout) :: tol
      real(wp), intent(inout) :: resid(*), v(ldv, *), workd(*), workl(*)
      integer, intent(inout) :: iparam(11), ipntr(11)
      integer, intent(inout) :: info
    end subroutine dseupd
    subroutine dnaupd(ido, bmat, n, which, nev, tol, resid, ncv, v, ldv, iparam, ipntr, &
      workd, workl, lworkl, info)
      import :: wp
      integer, intent(inout) :: ido
      character(len=1), intent(in) :: bmat
      integer, intent(in) :: n, nev, ncv, ldv, lworkl
      character(len=2), intent(in) :: which
      real(wp), intent(inout) :: tol
      real(wp), intent(inout) :: resid(*), v(ldv, *), workd(*), workl(*)
      integer, intent(inout) :: iparam(11), ipntr(14), info
    end subroutine dnaupd
    subroutine dneupd(rvec, howmny, sel, dr, di, z, ldz, sigmar, sigmai, workev, bmat, n, &
      which, nev, tol, resid, ncv, v, ldv, iparam, ipntr, workd, workl, lworkl, info)
      import :: wp
      integer, intent(in) :: ldz, n, nev, ncv, ldv, lworkl
      logical, intent(in) :: rvec
      character(len=1), intent(in) :: howmny, bmat
      logical, intent(inout) :: sel(*)
      real(wp), intent(out) :: dr(*), di(*), z(ldz, *), workev(*)
      real(wp), intent(in) :: sigmar, sigmai
      character(len=2), intent(in) :: which
      real(wp), intent(inout) :: tol
      real(wp), intent(inout) :: resid(*), v(ldv, *), workd(*), workl(*)
      integer, intent(inout) :: iparam(11), ipntr(14), info
    end subroutine dneupd
  end interface
end module core_arpack
