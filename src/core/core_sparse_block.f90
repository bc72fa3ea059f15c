!> LU factors of a sparse matrix in block upper triangular form whose diagonal blocks are all
!> small, for core_sparse: a kinematic Jacobian of an open chain falls apart into blocks of one
!> to three unknowns (an element's modes fix its far node), and KLU's per-block work (calls,
!> gathers, its general sparse kernels) costs several times the arithmetic there.
!>
!> With B = A(P, Q) (rows scaled) = D (I + G), D the diagonal blocks and G = D^-1 C for the
!> entries C above them, each block k keeps the dense m x nc matrix [D_k^-1, -G_k] over its
!> own m columns and the nc - m other columns its rows touch (D_k^-1 with the row scaling of
!> b folded in): a solve is then, block by block from the last, one gather and m dot
!> products, x_k = D_k^-1 b_k - G_k x (the transposed solve runs forward with the transposed
!> products). [D_k^-1, -G_k] comes from D_k's LU factors (partial pivoting) applied to
!> [R_k^-1, -C_k] at each factorisation.
!>
!> The ordering (rows P, columns Q, block starts R) is KLU's (core_sparse takes it from its
!> symbolic analysis), and so is the rest of the numerics: rows scaled by their largest
!> magnitude (KLU's default rule, the same divisions), partial pivoting within a block that
!> keeps the diagonal while it is at least 1e-3 of the column's largest entry (KLU's
!> tolerance), rcond = min |u_ii| / max |u_ii|. Results agree with KLU's to round-off: the
!> products with D_k^-1 and G_k differ from KLU's triangular solves by cond(D_k) eps, and the
!> blocks of a chain (an element's modes against its far node, rows scaled) are well
!> conditioned wherever the whole Jacobian is.
module core_sparse_block
  use core_kinds, only: wp
  implicit none
  private
  public :: block_lu_t

  !> KLU's pivot tolerance: a diagonal entry this fraction of the column's largest is kept.
  real(wp), parameter :: PIVOT_TOL = 1.0e-3_wp
  !> The largest diagonal block taken (core_sparse keeps KLU for patterns with larger ones).
  integer, parameter, public :: MAX_BLOCK = 8

  type :: block_lu_t
    integer :: n = 0, n_blocks = 0
    integer, allocatable :: block_start(:)   !< block k: permuted indices start(k):start(k+1)-1
    integer, allocatable :: prow(:), pcol(:) !< permuted index -> row, column of the matrix
    !> The factors in one array fac: block k's diagonal block D_k (scaled, column-major) from
    !> fac(dia_offset(k) + 1), negated as it is assembled; its columns (permuted indices: its
    !> own m, then the others its rows touch) from cols(col_ptr(k)) to cols(col_ptr(k + 1) - 1)
    !> and [D_k^-1 R_k^-1, -G_k] transposed (nc x m, column-major) from fac(mt_offset(k) + 1).
    integer, allocatable :: dia_offset(:), col_ptr(:), cols(:), mt_offset(:)
    real(wp), allocatable :: fac(:)
    !> The places in fac of -C_k that the pattern leaves zero, zeroed before each assembly.
    integer, allocatable :: mt_zero(:)
    !> The value slots by permuted row (row pi's from row_ptr(pi) to row_ptr(pi + 1) - 1) and
    !> each one's place in fac: the assembly is one pass over the rows, a row's largest
    !> magnitude found in registers and its values stored as -(a_ij / r_i) right after.
    integer, allocatable :: row_ptr(:), row_slot(:), row_dest(:)
    !> Reciprocal row scales by permuted row; a solve needs none of them: D_k^-1 is kept with
    !> the scaling of b_k folded in, as D_k^-1 R_k^-1 (and G_k = D_k^-1 C_k is free of it).
    real(wp), allocatable :: rs_perm(:)
    logical :: factored = .false.
  contains
    procedure :: setup => block_setup
    procedure :: factor => block_factor
    procedure :: solve => block_solve
  end type block_lu_t

  interface
    !> The structure of the n x n matrix with compressed columns (colptr, rowind, 0-based)
    !> under the block triangular ordering (p, q, r: 0-based, KLU's) with blocks of at most
    !> MAX_BLOCK unknowns. ok = .false. if an entry lies below the diagonal blocks (not KLU's
    !> form) or a block is larger: the caller then keeps KLU.
    module subroutine block_setup(this, n, colptr, rowind, p, q, r, n_blocks, ok)
      class(block_lu_t), intent(inout) :: this
      integer, intent(in) :: n, colptr(:), rowind(:), p(:), q(:), r(:), n_blocks
      logical, intent(out) :: ok
    end subroutine block_setup
  end interface

contains

  !> Factorise the values val (in the pattern's slot order). info = 0 on success, 1 when a
  !> block is singular (the factors are then unusable); rcond as KLU's.
  subroutine block_factor(this, val, info, rcond)
    class(block_lu_t), intent(inout) :: this
    real(wp), intent(in) :: val(:)
    integer, intent(out) :: info
    real(wp), intent(out) :: rcond
    real(wp) :: umin, umax, r
    integer :: i, p, k, m, nc
    this%factored = .false.
    info = 1
    rcond = 0.0_wp
    do p = 1, size(this%mt_zero)
      this%fac(this%mt_zero(p)) = 0.0_wp
    end do
    ! KLU's rule: each row divided by its largest magnitude (1 for a zero row); kept as the
    ! reciprocal, one division per row instead of one per entry.
    do i = 1, this%n
      r = 0.0_wp
      do p = this%row_ptr(i), this%row_ptr(i + 1) - 1
        r = max(r, abs(val(this%row_slot(p))))
      end do
      if (r == 0.0_wp) r = 1.0_wp
      r = 1.0_wp / r
      this%rs_perm(i) = r
      do p = this%row_ptr(i), this%row_ptr(i + 1) - 1
        this%fac(this%row_dest(p)) = -(val(this%row_slot(p)) * r)
      end do
    end do
    umin = huge(1.0_wp)
    umax = 0.0_wp
    do k = 1, this%n_blocks
      m = this%block_start(k + 1) - this%block_start(k)
      nc = this%col_ptr(k + 1) - this%col_ptr(k)
      associate (d => this%fac(this%dia_offset(k) + 1:), x => this%fac(this%mt_offset(k) + 1:))
        select case (m)
        case (3)
          call solution_3(nc, d, this%rs_perm(this%block_start(k):), x, umin, umax, info)
        case default
          call solution_m(m, nc, d, this%rs_perm(this%block_start(k):), x, umin, umax, info)
        end select
      end associate
      if (info /= 0) return
    end do
    info = 1
    if (this%n > 0 .and. .not. umin > 0.0_wp) return
    info = 0
    rcond = 1.0_wp
    if (this%n > 0) rcond = umin / umax
    this%factored = .true.
  end subroutine block_factor

  !> b := A^-1 b (transposed: A^-T b) for nc columns, with the last factors (b unchanged when
  !> the last factorisation failed: the caller has its info). Explicit shape: a vector is one
  !> column.
  subroutine block_solve(this, nc, b, transposed)
    class(block_lu_t), intent(in) :: this
    integer, intent(in) :: nc
    real(wp), intent(inout) :: b(this%n, nc)
    logical, intent(in) :: transposed
    real(wp) :: y(this%n)
    integer :: c, i
    if (.not. this%factored) return
    do c = 1, nc
      if (transposed) then
        do i = 1, this%n
          y(i) = b(this%pcol(i), c)
        end do
        call forward_transposed(this, y)
        do i = 1, this%n
          b(this%prow(i), c) = y(i)
        end do
      else
        do i = 1, this%n
          y(i) = b(this%prow(i), c)
        end do
        call backward(this, y)
        do i = 1, this%n
          b(this%pcol(i), c) = y(i)
        end do
      end if
    end do
  end subroutine block_solve

  !> y := A(P, Q)^-1 y (y in permuted order, unscaled), the last block first: x_k =
  !> [D_k^-1 R_k^-1, -G_k] applied to (b_k, x of the later columns).
  pure subroutine backward(this, y)
    type(block_lu_t), intent(in) :: this
    real(wp), intent(inout) :: y(:)
    integer :: k, i0, m, nc, c0
    do k = this%n_blocks, 1, -1
      i0 = this%block_start(k)
      m = this%block_start(k + 1) - i0
      c0 = this%col_ptr(k)
      nc = this%col_ptr(k + 1) - c0
      associate (mt => this%fac(this%mt_offset(k) + 1:), cols => this%cols(c0:))
        select case (m)
        case (3)
          call apply_3(nc, mt, cols, i0, y)
        case default
          call apply_m(m, nc, mt, cols, i0, y)
        end select
      end associate
    end do
  end subroutine backward

  !> y := A(P, Q)^-T y, the first block first: u = [D_k^-1 R_k^-1, -G_k]^T z_k for the
  !> block's part z_k (complete once the blocks before it are done), x_k = u's first m entries
  !> and the rest added to the later columns.
  pure subroutine forward_transposed(this, y)
    type(block_lu_t), intent(in) :: this
    real(wp), intent(inout) :: y(:)
    integer :: k, i0, m, nc, c0
    do k = 1, this%n_blocks
      i0 = this%block_start(k)
      m = this%block_start(k + 1) - i0
      c0 = this%col_ptr(k)
      nc = this%col_ptr(k + 1) - c0
      associate (mt => this%fac(this%mt_offset(k) + 1:), cols => this%cols(c0:))
        select case (m)
        case (3)
          call apply_t_3(nc, mt, cols, i0, y)
        case default
          call apply_t_m(m, nc, mt, cols, i0, y)
        end select
      end associate
    end do
  end subroutine forward_transposed

  ! The block kernels, one text (core_sparse_block_*.inc) for every block size m: a literal m
  ! (3: a planar node) lets the compiler unroll the loops over m, which for a generic m cost
  ! more than their arithmetic (the solve and factorisation of the two-link benchmark at 64
  ! elements per link took 2.2 times the instructions).

  pure subroutine solution_3(nc, d, rs, x, umin, umax, info)
    integer, parameter :: m = 3
    include 'core_sparse_block_solution.inc'
  end subroutine solution_3

  pure subroutine solution_m(m, nc, d, rs, x, umin, umax, info)
    integer, intent(in) :: m
    include 'core_sparse_block_solution.inc'
  end subroutine solution_m

  pure subroutine apply_3(nc, mt, cols, i0, y)
    integer, parameter :: m = 3
    include 'core_sparse_block_apply.inc'
  end subroutine apply_3

  pure subroutine apply_m(m, nc, mt, cols, i0, y)
    integer, intent(in) :: m
    include 'core_sparse_block_apply.inc'
  end subroutine apply_m

  pure subroutine apply_t_3(nc, mt, cols, i0, y)
    integer, parameter :: m = 3
    include 'core_sparse_block_apply_t.inc'
  end subroutine apply_t_3

  pure subroutine apply_t_m(m, nc, mt, cols, i0, y)
    integer, intent(in) :: m
    include 'core_sparse_block_apply_t.inc'
  end subroutine apply_t_m
end module core_sparse_block
