!> Sparse matrices with a fixed pattern and their LU factors (SuiteSparse KLU, through the C
!> handle of core_sparse_klu.c). The pattern is given once as a list of (row, column) entries,
!> repeats allowed: entry k then adds into value slot pos(k), so an assembly loop that visits
!> the entries in the same order only sums into `val`. The symbolic analysis is done once per
!> pattern; each `factor` refactors the current values (KLU keeps the pivot order while it stays
!> well conditioned).
!>
!> When KLU's block triangular ordering leaves no diagonal block larger than MAX_BLOCK (8)
!> (the kinematic Jacobian of an open chain), the factors and solves are core_sparse_block's
!> instead, in KLU's ordering with its row scaling and pivot rule: each block keeps its inverse
!> and its product with the entries above it, so that a solve is a gather and a few dot
!> products per block, where KLU's per-block overhead dominated (its solves were 28 % of a
!> step of the two-link benchmark at 64 elements per link). The choice is made per pattern at
!> the first factorisation. After a factorisation that reports a singular matrix, the block
!> solver's solves leave b unchanged.
!>
!> The C handle belongs to the object that made it, recognised by its address: an intrinsic copy
!> of a containing object (which Fortran cannot prevent) neither uses nor frees the original's
!> factors but analyses its own pattern on its first factorisation.
module core_sparse
  use, intrinsic :: iso_c_binding, only: c_ptr, c_null_ptr, c_int, c_double, c_associated, &
    c_loc, c_intptr_t
  use core_kinds, only: wp
  use core_sparse_block, only: block_lu_t, MAX_BLOCK
  use core_sort, only: sort_by_key
  implicit none
  private
  public :: sparse_lu_t, entries_t

  !> A growing list of (row, column) entries, for building patterns in one pass (capacity
  !> doubles, so n entries cost O(n)).
  type :: entries_t
    integer :: n = 0
    integer, allocatable :: rows(:), cols(:)
  contains
    procedure :: add => entries_add
  end type entries_t

  type :: sparse_lu_t
    integer :: n = 0
    integer :: n_entries = 0                  !< entries given to setup, repeats included
    integer, allocatable :: pos(:)            !< entry -> value slot
    real(wp), allocatable :: val(:)           !< values in compressed-column order
    integer(c_int), allocatable, private :: colptr(:), rowind(:)   ! 0-based for KLU
    type(c_ptr), private :: handle = c_null_ptr
    integer(c_intptr_t), private :: owner = 0
    !> Block solver in use (analysed: a copy keeps it, factors included, being plain data)
    logical, private :: blocked = .false.
    type(block_lu_t), private :: blocks
  contains
    procedure :: setup => sparse_setup
    procedure :: factor => sparse_factor
    procedure :: factor_pivoting => sparse_factor_pivoting
    procedure :: solve => sparse_solve
    procedure :: solve_many => sparse_solve_many
    procedure :: multiply => sparse_multiply
    procedure :: uses_blocks => sparse_uses_blocks
    final :: sparse_final
  end type sparse_lu_t

  interface
    function klu_new(n, ap, ai) result(h) bind(C, name='flexmor_klu_new')
      import :: c_ptr, c_int
      integer(c_int), value :: n
      integer(c_int), intent(in) :: ap(*), ai(*)
      type(c_ptr) :: h
    end function klu_new
    function klu_factor(h, ax, rcond) result(info) bind(C, name='flexmor_klu_factor')
      import :: c_ptr, c_int, c_double
      type(c_ptr), value :: h
      real(c_double), intent(in) :: ax(*)
      real(c_double), intent(out) :: rcond
      integer(c_int) :: info
    end function klu_factor
    function klu_factor_pivoting(h, ax, rcond) result(info) &
      bind(C, name='flexmor_klu_factor_pivoting')
      import :: c_ptr, c_int, c_double
      type(c_ptr), value :: h
      real(c_double), intent(in) :: ax(*)
      real(c_double), intent(out) :: rcond
      integer(c_int) :: info
    end function klu_factor_pivoting
    function klu_solve(h, nrhs, b, transposed) result(info) bind(C, name='flexmor_klu_solve')
      import :: c_ptr, c_int, c_double
      type(c_ptr), value :: h
      integer(c_int), value :: nrhs, transposed
      real(c_double), intent(inout) :: b(*)
      integer(c_int) :: info
    end function klu_solve
    function klu_ordering(h, p, q, r, maxblock) result(nblocks) &
        bind(C, name='flexmor_klu_ordering')
      import :: c_ptr, c_int
      type(c_ptr), value :: h
      integer(c_int), intent(out) :: p(*), q(*), r(*), maxblock
      integer(c_int) :: nblocks
    end function klu_ordering
    subroutine klu_free(h) bind(C, name='flexmor_klu_free')
      import :: c_ptr
      type(c_ptr), value :: h
    end subroutine klu_free
  end interface

contains

  !> Append entry (row, col); entries with a row or column 0 (not an unknown) are skipped.
  pure subroutine entries_add(this, row, col)
    class(entries_t), intent(inout) :: this
    integer, intent(in) :: row, col
    integer, allocatable :: grown(:)
    if (row < 1 .or. col < 1) return
    if (.not. allocated(this%rows)) allocate(this%rows(64), this%cols(64))
    if (this%n == size(this%rows)) then
      allocate(grown(2 * this%n))
      grown(1:this%n) = this%rows
      call move_alloc(grown, this%rows)
      allocate(grown(2 * this%n))
      grown(1:this%n) = this%cols
      call move_alloc(grown, this%cols)
    end if
    this%n = this%n + 1
    this%rows(this%n) = row
    this%cols(this%n) = col
  end subroutine entries_add

  !> The pattern of an n x n matrix from its entries (rows(k), cols(k)); repeats share a slot.
  !> Values are zero afterwards.
  subroutine sparse_setup(this, n, rows, cols)
    class(sparse_lu_t), intent(inout) :: this
    integer, intent(in) :: n, rows(:), cols(:)
    integer :: order(size(rows)), count_in_col(n), k, j, slot, prev_row, prev_col
    call release(this)
    this%n = n
    this%n_entries = size(rows)
    ! Counting sort by column, then insertion by row within each (short) column.
    count_in_col = 0
    do k = 1, size(rows)
      count_in_col(cols(k)) = count_in_col(cols(k)) + 1
    end do
    block
      integer :: start(n + 1), fill(n)
      start(1) = 1
      do j = 1, n
        start(j + 1) = start(j) + count_in_col(j)
      end do
      fill = start(1:n)
      do k = 1, size(rows)
        order(fill(cols(k))) = k
        fill(cols(k)) = fill(cols(k)) + 1
      end do
      do j = 1, n
        call sort_by_key(order(start(j):start(j + 1) - 1), rows)
      end do
    end block
    allocate(this%pos(size(rows)), this%colptr(n + 1), this%rowind(size(rows)))
    slot = 0
    prev_row = -1
    prev_col = -1
    this%colptr = 0
    do k = 1, size(rows)
      associate (e => order(k))
        if (rows(e) /= prev_row .or. cols(e) /= prev_col) then
          slot = slot + 1
          this%rowind(slot) = rows(e) - 1
          this%colptr(cols(e) + 1) = slot
          prev_row = rows(e)
          prev_col = cols(e)
        end if
        this%pos(e) = slot
      end associate
    end do
    ! colptr(j + 1) holds the last slot of column j (or 0 if empty): make it cumulative.
    do j = 2, n + 1
      this%colptr(j) = max(this%colptr(j), this%colptr(j - 1))
    end do
    this%rowind = this%rowind(1:slot)
    allocate(this%val(slot))
    this%val = 0.0_wp
  end subroutine sparse_setup

  !> LU factors of the current values. info = 0 on success, 1 if singular (or the pattern
  !> could not be analysed); rcond is min|u_ii| / max|u_ii|.
  subroutine sparse_factor(this, info, rcond)
    class(sparse_lu_t), intent(inout), target :: this
    integer, intent(out) :: info
    real(wp), intent(out) :: rcond
    rcond = 0.0_wp
    info = 1
    if (.not. this%blocked .and. .not. owns_handle(this)) then
      this%handle = klu_new(int(this%n, c_int), this%colptr, this%rowind)
      if (.not. c_associated(this%handle)) return
      this%owner = address_of(this)
      call choose_blocks(this)
    end if
    if (this%blocked) then
      call this%blocks%factor(this%val, info, rcond)
    else
      info = klu_factor(this%handle, this%val, rcond)
    end if
  end subroutine sparse_factor

  !> LU factors as sparse_factor, but afresh with full partial pivoting (KLU's own prefers the
  !> diagonal): for values whose factors came out unusable. The block solver's factors are
  !> redone as they are (it already picks the largest pivot in its blocks).
  subroutine sparse_factor_pivoting(this, info, rcond)
    class(sparse_lu_t), intent(inout), target :: this
    integer, intent(out) :: info
    real(wp), intent(out) :: rcond
    if (this%blocked .or. .not. owns_handle(this)) then
      call this%factor(info, rcond)
      return
    end if
    info = klu_factor_pivoting(this%handle, this%val, rcond)
  end subroutine sparse_factor_pivoting

  !> Take KLU's ordering for the block solver when its diagonal blocks are all small (KLU's
  !> handle is then freed: the block solver is plain data).
  subroutine choose_blocks(this)
    type(sparse_lu_t), intent(inout) :: this
    integer(c_int) :: p(this%n), q(this%n), r(this%n + 1), maxblock, nblocks
    logical :: ok
    nblocks = klu_ordering(this%handle, p, q, r, maxblock)
    if (maxblock > MAX_BLOCK) return
    call this%blocks%setup(this%n, this%colptr, this%rowind, p, q, r, nblocks, ok)
    if (.not. ok) then
      this%blocks = block_lu_t()
      return
    end if
    call klu_free(this%handle)
    this%handle = c_null_ptr
    this%owner = 0
    this%blocked = .true.
  end subroutine choose_blocks

  !> Whether the factors are the block solver's (known after the first factorisation).
  pure logical function sparse_uses_blocks(this)
    class(sparse_lu_t), intent(in) :: this
    sparse_uses_blocks = this%blocked
  end function sparse_uses_blocks

  !> b := A^-1 b (transposed: A^-T b) with the last factors.
  subroutine sparse_solve(this, b, transposed)
    class(sparse_lu_t), intent(inout), target :: this
    real(wp), intent(inout), contiguous :: b(:)
    logical, intent(in), optional :: transposed
    integer :: info
    if (this%n == 0) return
    if (this%blocked) then
      call this%blocks%solve(1, b, optional_true(transposed))
      return
    end if
    call ensure_own_factors(this)
    info = klu_solve(this%handle, 1_c_int, b, merge(1_c_int, 0_c_int, optional_true(transposed)))
  end subroutine sparse_solve

  subroutine sparse_solve_many(this, b, transposed)
    class(sparse_lu_t), intent(inout), target :: this
    real(wp), intent(inout), contiguous :: b(:, :)
    logical, intent(in), optional :: transposed
    integer :: info
    if (this%n == 0 .or. size(b, 2) == 0) return
    if (this%blocked) then
      call this%blocks%solve(size(b, 2), b, optional_true(transposed))
      return
    end if
    call ensure_own_factors(this)
    info = klu_solve(this%handle, int(size(b, 2), c_int), b, &
      merge(1_c_int, 0_c_int, optional_true(transposed)))
  end subroutine sparse_solve_many

  !> y = A x with the current values.
  pure function sparse_multiply(this, x) result(y)
    class(sparse_lu_t), intent(in) :: this
    real(wp), intent(in) :: x(:)
    real(wp) :: y(this%n)
    integer :: j, s
    y = 0.0_wp
    do j = 1, this%n
      do s = this%colptr(j) + 1, this%colptr(j + 1)
        y(this%rowind(s) + 1) = y(this%rowind(s) + 1) + this%val(s) * x(j)
      end do
    end do
  end function sparse_multiply

  !> A copy refactors its own values (those of the original's last factorisation) once.
  subroutine ensure_own_factors(this)
    class(sparse_lu_t), intent(inout), target :: this
    integer :: info
    real(wp) :: rcond
    if (.not. owns_handle(this)) call this%factor(info, rcond)
  end subroutine ensure_own_factors

  pure logical function optional_true(flag)
    logical, intent(in), optional :: flag
    optional_true = .false.
    if (present(flag)) optional_true = flag
  end function optional_true

  logical function owns_handle(this)
    class(sparse_lu_t), intent(in), target :: this
    owns_handle = c_associated(this%handle)
    if (owns_handle) owns_handle = this%owner == address_of(this)
  end function owns_handle

  integer(c_intptr_t) function address_of(this)
    class(sparse_lu_t), intent(in), target :: this
    select type (this)
    type is (sparse_lu_t)
      address_of = transfer(c_loc(this), 0_c_intptr_t)
    class default
      address_of = 0
    end select
  end function address_of

  subroutine release(this)
    class(sparse_lu_t), intent(inout), target :: this
    if (owns_handle(this)) call klu_free(this%handle)
    this%handle = c_null_ptr
    this%owner = 0
    this%blocked = .false.
    this%blocks = block_lu_t()
    if (allocated(this%pos)) deallocate(this%pos, this%val, this%colptr, this%rowind)
  end subroutine release

  subroutine sparse_final(this)
    type(sparse_lu_t), intent(inout) :: this
    call release(this)
  end subroutine sparse_final
end module core_sparse
