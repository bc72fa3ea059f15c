!> ARPACK's symmetric Lanczos driver (dsaupd/dseupd) in shift-invert mode 3 as a
!> reverse-communication object: OP = (K - sigma B)^-1 B, B-inner product, which = 'LM', so
!> that the nev eigenvalues nearest sigma come out. The caller applies OP and B in its own
!> form (dense Cholesky factors in reduction_eigen, sparse augmented factors in
!> reduction_krylov); the driver, its start vector and its error reports are shared.
!>
!>     call lz%start(n, nev, sigma, 'arpack')
!>     do
!>       call lz%next(request)
!>       select case (request)
!>       case (LZ_OP);     y = OP x           with x = lz%input()
!>       case (LZ_OP_BX);  y = (K - sigma B)^-1 b   with b = B x = lz%input()
!>       case (LZ_B);      y = B x            with x = lz%input()
!>       case default; exit
!>       end select
!>       call lz%output(y)
!>     end do
!>     call lz%finish(lambda, v, err)     ! ascending, B-normalised
module reduction_lanczos
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_NUMERIC
  use core_strings, only: int_str
  use core_arpack, only: dsaupd, dseupd
  use core_sort, only: sort_by_value
  implicit none
  private
  public :: lanczos_t, LZ_DONE, LZ_OP, LZ_OP_BX, LZ_B

  integer, parameter :: LZ_DONE = 0, LZ_OP = 1, LZ_OP_BX = 2, LZ_B = 3
  !> ARPACK restarts allowed (iparam(3)); shift-invert about a shift below the spectrum
  !> usually needs fewer than ten.
  integer, parameter :: MAX_RESTARTS = 1000

  type :: lanczos_t
    private
    integer :: n = 0, nev = 0, ncv = 0, lworkl = 0, ido = 0, info = 0, request = LZ_DONE
    integer :: iparam(11) = 0, ipntr(11) = 0
    real(wp) :: sigma = 0.0_wp
    real(wp) :: tol = 0.0_wp                     !< 0: machine precision (dsaupd sets it)
    real(wp), allocatable :: resid(:), basis(:, :), workd(:), workl(:)
    character(len=:), allocatable :: name        !< the solver's name in messages
  contains
    procedure :: start => lz_start
    procedure :: next => lz_next
    procedure :: input => lz_input
    procedure :: output => lz_output
    procedure :: finish => lz_finish
  end type lanczos_t

contains

  !> Start a run for the nev eigenvalues nearest sigma of an n x n problem (nev <= n - 2).
  subroutine lz_start(this, n, nev, sigma, name)
    class(lanczos_t), intent(inout) :: this
    integer, intent(in) :: n, nev
    real(wp), intent(in) :: sigma
    character(len=*), intent(in) :: name
    integer :: i
    this%n = n
    this%nev = nev
    this%sigma = sigma
    this%name = name
    this%ncv = min(n, max(2 * nev + 1, nev + 8))
    this%lworkl = this%ncv * (this%ncv + 8)
    if (allocated(this%resid)) deallocate(this%resid, this%basis, this%workd, this%workl)
    allocate(this%resid(n), this%basis(n, this%ncv), this%workd(3 * n), &
      this%workl(this%lworkl))
    ! A fixed, deterministic start vector (info = 1) instead of ARPACK's random one, whose
    ! seed lives in the library and changes from call to call. Its quasi-random entries
    ! have a component along every mode.
    do i = 1, n
      this%resid(i) = modulo(i * 0.6180339887498949_wp, 1.0_wp) - 0.5_wp
    end do
    this%iparam = 0
    this%iparam(1) = 1              ! exact shifts
    this%iparam(3) = MAX_RESTARTS
    this%iparam(7) = 3              ! shift-invert, B-inner product
    this%ipntr = 0
    this%ido = 0
    this%tol = 0.0_wp
    this%info = 1                   ! resid holds the start vector
  end subroutine lz_start

  !> The next product the driver asks for (LZ_DONE when it has finished or failed).
  subroutine lz_next(this, request)
    class(lanczos_t), intent(inout) :: this
    integer, intent(out) :: request
    call dsaupd(this%ido, 'G', this%n, 'LM', this%nev, this%tol, this%resid, this%ncv, this%basis, &
      this%n, this%iparam, this%ipntr, this%workd, this%workl, this%lworkl, this%info)
    select case (this%ido)
    case (-1)
      request = LZ_OP
    case (1)
      request = LZ_OP_BX
    case (2)
      request = LZ_B
    case default
      request = LZ_DONE
    end select
    this%request = request
  end subroutine lz_next

  !> The vector the current request acts on: x, or B x for LZ_OP_BX.
  function lz_input(this) result(x)
    class(lanczos_t), intent(in) :: this
    real(wp) :: x(this%n)
    integer :: i
    i = this%ipntr(1)
    if (this%request == LZ_OP_BX) i = this%ipntr(3)
    x = this%workd(i:i + this%n - 1)
  end function lz_input

  subroutine lz_output(this, y)
    class(lanczos_t), intent(inout) :: this
    real(wp), intent(in) :: y(:)
    this%workd(this%ipntr(2):this%ipntr(2) + this%n - 1) = y
  end subroutine lz_output

  !> The converged pairs, eigenvalues ascending, vectors B-normalised; an error naming the
  !> solver where ARPACK failed.
  subroutine lz_finish(this, lambda, v, err)
    class(lanczos_t), intent(inout) :: this
    real(wp), allocatable, intent(out) :: lambda(:), v(:, :)
    type(error_t), intent(inout) :: err
    real(wp), allocatable :: d(:), z(:, :)
    logical, allocatable :: sel(:)
    integer, allocatable :: order(:)
    integer :: i, j, nconv, info
    character(len=:), allocatable :: who
    who = "eigensolver '" // this%name // "': "
    nconv = this%iparam(5)
    select case (this%info)
    case (0)
    case (1)
      call err%set(ERR_NUMERIC, who // 'no convergence after ' // int_str(this%iparam(3)) // &
        ' restarts (' // int_str(nconv) // ' of ' // int_str(this%nev) // &
        " modes converged); try solver = 'lapack'")
    case (3)
      call err%set(ERR_NUMERIC, who // 'no shifts could be applied during a restart ' // &
        "(Lanczos basis too small); try solver = 'lapack'")
    case (-8)
      call err%set(ERR_NUMERIC, who // 'the tridiagonal eigenproblem (dsteqr) failed in dsaupd')
    case (-9999)
      call err%set(ERR_NUMERIC, who // 'could not build a Lanczos factorisation (size ' // &
        int_str(this%iparam(5)) // ' reached)')
    case default
      call err%set(ERR_NUMERIC, who // 'dsaupd rejected its arguments (info = ' // &
        int_str(this%info) // ')')
    end select
    if (.not. err%ok()) return
    if (nconv < this%nev) then
      call err%set(ERR_NUMERIC, who // 'only ' // int_str(nconv) // ' of ' // &
        int_str(this%nev) // ' modes converged')
      return
    end if
    ! d and z sized ncv: dseupd writes all converged pairs, which may be more than nev.
    allocate(sel(this%ncv), d(this%ncv), z(this%n, this%ncv))
    sel = .true.
    call dseupd(.true., 'A', sel, d, z, this%n, this%sigma, 'G', this%n, 'LM', this%nev, &
      this%tol, this%resid, this%ncv, this%basis, this%n, this%iparam, this%ipntr, this%workd, &
      this%workl, this%lworkl, info)
    select case (info)
    case (0)
    case (-8)
      call err%set(ERR_NUMERIC, who // 'the tridiagonal eigenproblem (dsteqr) failed in dseupd')
    case (-14)
      call err%set(ERR_NUMERIC, who // 'dsaupd found no eigenvalue to sufficient accuracy')
    case (-17)
      call err%set(ERR_NUMERIC, who // 'dseupd found a different number of converged Ritz ' // &
        'values than dsaupd')
    case default
      call err%set(ERR_NUMERIC, who // 'dseupd rejected its arguments (info = ' // &
        int_str(info) // ')')
    end select
    if (.not. err%ok()) return
    ! Ascending order (dseupd's order depends on which and the mode).
    order = [(i, i = 1, this%nev)]
    call sort_by_value(order, d(1:this%nev))
    allocate(lambda(this%nev), v(this%n, this%nev))
    do j = 1, this%nev
      v(:, j) = z(:, order(j))
      lambda(j) = d(order(j))
    end do
  end subroutine lz_finish
end module reduction_lanczos
