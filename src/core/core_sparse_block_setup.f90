!> The structure of core_sparse_block's factors from KLU's ordering of a pattern.
submodule (core_sparse_block) core_sparse_block_setup
  use core_sort, only: sort_by_key
  implicit none

contains

  module procedure block_setup
    integer :: pinv(n), qinv(n), blk(n), row_count(n + 1), mark(n), colpos(n), order(n)
    integer, allocatable :: ent_col(:), list(:), row_ptr(:), row_mid(:), row_slot(:), row_dest(:)
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
    row_ptr = row_count
    allocate(row_slot(colptr(n + 1)), row_dest(colptr(n + 1)), ent_col(colptr(n + 1)))
    fill = row_count(1:n)
    do j = 1, n
      do s = colptr(j) + 1, colptr(j + 1)
        pi = pinv(rowind(s) + 1)
        row_slot(fill(pi)) = s
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
        do e = row_ptr(pi), row_ptr(pi + 1) - 1
          pj = ent_col(e)
          if (blk(pj) == k .or. mark(pj) == k) cycle
          mark(pj) = k
          n_cols = n_cols + 1
          list(n_cols) = pj
        end do
      end do
      order(1:n_cols) = [(i, i = 1, n_cols)]
      call sort_by_key(order(1:n_cols), list)
      list(1:n_cols) = list(order(1:n_cols))
      this%cols = [this%cols, [(i0 + i, i = 0, m - 1)], list(1:n_cols)]
      nc = m + n_cols
      this%col_ptr(k + 1) = this%col_ptr(k) + nc
      do i = 1, nc
        colpos(this%cols(this%col_ptr(k) + i - 1)) = i
      end do
      this%mt_offset(k) = n_mt
      do pi = i0, i0 + m - 1
        do e = row_ptr(pi), row_ptr(pi + 1) - 1
          pj = ent_col(e)
          if (blk(pj) == k) then
            row_dest(e) = this%dia_offset(k) + 1 + (pi - i0) + (pj - i0) * m
          else
            row_dest(e) = -(n_mt + colpos(pj) + (pi - i0) * nc)
          end if
        end do
      end do
      n_mt = n_mt + nc * m
    end do
    ! Each row's entries in D_k first (dest > 0), then the others (mt places, made positive).
    allocate(row_mid(n))
    do pi = 1, n
      associate (first => row_ptr(pi), last => row_ptr(pi + 1) - 1)
        s = count(row_dest(first:last) > 0)
        row_mid(pi) = first + s
        row_slot(first:last) = [pack(row_slot(first:last), &
          row_dest(first:last) > 0), pack(row_slot(first:last), &
          row_dest(first:last) < 0)]
        row_dest(first:last) = abs([pack(row_dest(first:last), &
          row_dest(first:last) > 0), pack(row_dest(first:last), &
          row_dest(first:last) < 0)])
      end associate
    end do
    ! One array for the factors: the diagonal blocks, then the [D_k^-1 R_k^-1, -G_k].
    this%mt_offset = this%mt_offset + n_dia
    allocate(this%fac(n_dia + n_mt), this%rs_perm(n), used(n_dia + n_mt))
    this%fac = 0.0_wp
    do pi = 1, n
      do e = row_ptr(pi), row_ptr(pi + 1) - 1
        row_dest(e) = row_dest(e) + merge(n_dia, 0, e >= row_mid(pi))
      end do
    end do
    ! row_slot holds 1-based value slots (colptr + 1 on): it indexes the values directly.
    this%row_ptr = row_ptr
    this%row_slot = row_slot
    this%row_dest = row_dest
    ! The places of -C_k no entry writes (the own columns are set in every factorisation).
    used = .false.
    used(1:n_dia) = .true.
    do k = 1, n_blocks
      m = this%block_start(k + 1) - this%block_start(k)
      nc = this%col_ptr(k + 1) - this%col_ptr(k)
      do i = 0, m - 1
        used(this%mt_offset(k) + i * nc + 1:this%mt_offset(k) + i * nc + m) = .true.
      end do
    end do
    used(this%row_dest) = .true.
    this%mt_zero = pack([(i, i = 1, n_dia + n_mt)], .not. used)
    ok = .true.
  end procedure block_setup
end submodule core_sparse_block_setup
