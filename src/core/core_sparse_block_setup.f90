!> The structure of core_sparse_block's factors from KLU's ordering of a pattern.
submodule (core_sparse_block) core_sparse_block_setup
  implicit none

contains

  module procedure block_setup
    integer :: pinv(n), qinv(n), blk(n), row_count(n + 1), mark(n), colpos(n)
    integer, allocatable :: ent_col(:), list(:)
    integer :: k, j, s, pi, pj, m, i0, nc, e, i, n_cols, n_mt, n_dia, fill(n)
    logical, allocatable :: used(:)
    ok = .false.
    this%n = n
    this%n_blocks = n_blocks
    this%factored = .false.
    this%prow = p(1:n) + 1
    this%pcol = q(1:n) + 1
    this%block_start = r(1:n_blocks + 1) + 1
    allocate(this%dia_offset(n_blocks))
    n_dia = 0
    do k = 1, n_blocks
      m = this%block_start(k + 1) - this%block_start(k)
      if (m > MAX_BLOCK) return
      this%dia_offset(k) = n_dia
      n_dia = n_dia + m * m
      blk(this%block_start(k):this%block_start(k + 1) - 1) = k
    end do
    do k = 1, n
      pinv(this%prow(k)) = k
      qinv(this%pcol(k)) = k
    end do
    ! The slots by permuted row, with their permuted columns.
    row_count = 0
    do j = 1, n
      do s = colptr(j) + 1, colptr(j + 1)
        pi = pinv(rowind(s) + 1)
        if (blk(pi) > blk(qinv(j))) return
        row_count(pi + 1) = row_count(pi + 1) + 1
      end do
    end do
    row_count(1) = 1
    do k = 1, n
      row_count(k + 1) = row_count(k) + row_count(k + 1)
    end do
    this%row_ptr = row_count
    allocate(this%row_slot(colptr(n + 1)), this%row_dest(colptr(n + 1)), ent_col(colptr(n + 1)))
    fill = row_count(1:n)
    do j = 1, n
      do s = colptr(j) + 1, colptr(j + 1)
        pi = pinv(rowind(s) + 1)
        this%row_slot(fill(pi)) = s
        ent_col(fill(pi)) = qinv(j)
        fill(pi) = fill(pi) + 1
      end do
    end do
    ! Per block its columns: its own, then the others its rows touch in ascending order.
    allocate(this%col_ptr(n_blocks + 1), this%mt_offset(n_blocks), list(n))
    allocate(this%cols(0))
    mark = 0
    this%col_ptr(1) = 1
    n_mt = 0
    do k = 1, n_blocks
      i0 = this%block_start(k)
      m = this%block_start(k + 1) - i0
      n_cols = 0
      do pi = i0, i0 + m - 1
        do e = this%row_ptr(pi), this%row_ptr(pi + 1) - 1
          pj = ent_col(e)
          if (blk(pj) == k .or. mark(pj) == k) cycle
          mark(pj) = k
          n_cols = n_cols + 1
          list(n_cols) = pj
        end do
      end do
      call sort_ascending(list(1:n_cols))
      this%cols = [this%cols, [(i0 + i, i = 0, m - 1)], list(1:n_cols)]
      nc = m + n_cols
      this%col_ptr(k + 1) = this%col_ptr(k) + nc
      do i = 1, nc
        colpos(this%cols(this%col_ptr(k) + i - 1)) = i
      end do
      this%mt_offset(k) = n_mt
      do pi = i0, i0 + m - 1
        do e = this%row_ptr(pi), this%row_ptr(pi + 1) - 1
          pj = ent_col(e)
          if (blk(pj) == k) then
            this%row_dest(e) = this%dia_offset(k) + 1 + (pi - i0) + (pj - i0) * m
          else
            this%row_dest(e) = -(n_mt + colpos(pj) + (pi - i0) * nc)
          end if
        end do
      end do
      n_mt = n_mt + nc * m
    end do
    allocate(this%dia(n_dia), this%mt(n_mt), this%rs_perm(n), used(n_mt))
    this%dia = 0.0_wp
    this%mt = 0.0_wp
    ! The places of -C_k no entry writes (the own columns are set in every factorisation).
    used = .false.
    do k = 1, n_blocks
      m = this%block_start(k + 1) - this%block_start(k)
      nc = this%col_ptr(k + 1) - this%col_ptr(k)
      do i = 0, m - 1
        used(this%mt_offset(k) + i * nc + 1:this%mt_offset(k) + i * nc + m) = .true.
      end do
    end do
    do e = 1, size(this%row_dest)
      if (this%row_dest(e) < 0) used(-this%row_dest(e)) = .true.
    end do
    this%mt_zero = pack([(i, i = 1, n_mt)], .not. used)
    ok = .true.
  end procedure block_setup

  pure subroutine sort_ascending(a)
    integer, intent(inout) :: a(:)
    integer :: i, j, key
    do i = 2, size(a)
      key = a(i)
      j = i - 1
      do while (j >= 1)
        if (a(j) <= key) exit
        a(j + 1) = a(j)
        j = j - 1
      end do
      a(j + 1) = key
    end do
  end subroutine sort_ascending
end submodule core_sparse_block_setup
