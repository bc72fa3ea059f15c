!> The kinematic residual and Jacobian (the element pass of every Newton iteration), and
!> kin_init with the flat entry lists it makes for it.
submodule (model_kinematics) model_kinematics_residual
  use elements_base, only: element_t
  implicit none

contains

  module procedure kin_init
    type(entries_t) :: jac, inputs
    ! Per entry (element, mode with a row, coordinate): column of J_c (0: not calculable),
    ! sparse value slot and input entry (0: none).
    integer, allocatable :: ent_col(:), ent_slot(:), ent_in(:)
    integer :: iel, j, k, row, m, n_ent
    this%sparse = .false.
    if (present(sparse)) this%sparse = sparse
    if (allocated(this%q)) deallocate(this%q)
    if (allocated(this%df)) deallocate(this%df)
    if (allocated(this%lu)) deallocate(this%lu, this%ipiv)
    this%x = model%x0
    allocate(this%q(model%n_q))
    if (.not. this%sparse) allocate(this%lu(model%n_c, model%n_c), this%ipiv(model%n_c))
    this%q = 0.0_wp
    this%has_df = .false.
    this%has_factors = .false.
    this%el_nm = [(model%elements(iel)%e%n_modes(), iel = 1, model%n_elements)]
    this%el_nd = [(size(model%elements(iel)%e%dofs), iel = 1, model%n_elements)]
    this%mode_row = model%modes%row
    this%mode_q = [(0, m = 1, size(model%modes))]
    this%mode_period = model%modes%period
    n_ent = 0
    do m = 1, size(model%modes)
      row = this%mode_row(m)
      if (row == 0) cycle
      this%mode_q(m) = model%row_q(row)
      n_ent = n_ent + this%el_nd(model%modes(m)%element)
    end do
    allocate(ent_col(n_ent), ent_slot(n_ent), ent_in(n_ent))
    n_ent = 0
    do iel = 1, model%n_elements
      associate (el => model%elements(iel)%e)
        do j = 1, this%el_nm(iel)
          row = this%mode_row(model%mode_first(iel) + j - 1)
          if (row == 0) cycle
          do k = 1, size(el%dofs)
            n_ent = n_ent + 1
            ent_col(n_ent) = model%calc_index(el%dofs(k))
            call jac%add(row, model%calc_index(el%dofs(k)))
            ent_slot(n_ent) = 0
            ent_in(n_ent) = 0
            if (model%calc_index(el%dofs(k)) > 0) ent_slot(n_ent) = jac%n
            call inputs%add(row, model%input_q(el%dofs(k)))
            if (model%input_q(el%dofs(k)) > 0) ent_in(n_ent) = inputs%n
          end do
        end do
      end associate
    end do
    this%in_row = inputs%rows(1:inputs%n)
    this%in_q = inputs%cols(1:inputs%n)
    allocate(this%in_val(inputs%n))
    this%in_val = 0.0_wp
    if (allocated(this%de_offset)) deallocate(this%de_offset, this%de_val)
    allocate(this%de_offset(model%n_elements))
    k = 0
    do iel = 1, model%n_elements
      this%de_offset(iel) = k + 1
      k = k + this%el_nm(iel) * this%el_nd(iel)
    end do
    allocate(this%de_val(k))
    if (this%sparse) then
      call this%jac_sp%setup(model%n_c, jac%rows(1:jac%n), jac%cols(1:jac%n))
      ! Entry number -> value slot, now that the pattern is known.
      do k = 1, n_ent
        if (ent_slot(k) > 0) ent_slot(k) = this%jac_sp%pos(ent_slot(k))
      end do
    end if
    call flat_entries(this, model, ent_col, ent_slot, ent_in)
    if (this%sparse) call gather_lists(this)
  end procedure kin_init

  module subroutine flat_entries(this, model, ent_col, ent_slot, ent_in)
    type(kinematics_t), intent(inout) :: this
    type(model_t), intent(in) :: model
    integer, intent(in) :: ent_col(:), ent_slot(:), ent_in(:)
    integer :: iel, j, k, p, n_jac, n_in, row, m
    if (allocated(this%e_val)) deallocate(this%e_val, this%row_mode, this%q_rows)
    allocate(this%e_val(0:size(model%modes)), this%row_mode(model%n_c))
    this%e_val = 0.0_wp
    this%row_mode = 0
    do m = 1, size(model%modes)
      if (this%mode_row(m) > 0) this%row_mode(this%mode_row(m)) = m
    end do
    this%q_rows = pack(this%mode_row, this%mode_row > 0 .and. this%mode_q > 0)
    n_jac = count(ent_col > 0)
    if (allocated(this%jac_src)) deallocate(this%jac_src, this%jac_row, this%jac_col, &
      this%jac_slot, this%in_src)
    allocate(this%jac_src(n_jac), this%jac_row(n_jac), this%jac_col(n_jac), &
      this%jac_slot(n_jac), this%in_src(count(ent_in > 0)))
    p = 0
    n_jac = 0
    n_in = 0
    do iel = 1, model%n_elements
      do j = 1, this%el_nm(iel)
        row = this%mode_row(model%mode_first(iel) + j - 1)
        if (row == 0) cycle
        do k = 1, this%el_nd(iel)
          p = p + 1
          if (ent_col(p) > 0) then
            n_jac = n_jac + 1
            this%jac_src(n_jac) = this%de_offset(iel) + (k - 1) * this%el_nm(iel) + j - 1
            this%jac_row(n_jac) = row
            this%jac_col(n_jac) = ent_col(p)
            this%jac_slot(n_jac) = ent_slot(p)
          end if
          if (ent_in(p) > 0) then
            n_in = n_in + 1
            this%in_src(n_in) = this%de_offset(iel) + (k - 1) * this%el_nm(iel) + j - 1
          end if
        end do
      end do
    end do
  end subroutine flat_entries


  module subroutine gather_lists(this)
    type(kinematics_t), intent(inout) :: this
    logical :: seen(size(this%jac_sp%val))
    logical :: first(size(this%jac_slot))
    integer :: k
    seen = .false.
    do k = 1, size(this%jac_slot)
      first(k) = .not. seen(this%jac_slot(k))
      seen(this%jac_slot(k)) = .true.
    end do
    this%jac_set_src = pack(this%jac_src, first)
    this%jac_set_slot = pack(this%jac_slot, first)
    this%jac_add_src = pack(this%jac_src, .not. first)
    this%jac_add_slot = pack(this%jac_slot, .not. first)
  end subroutine gather_lists


  !> el%evaluate with the Jacobian written straight into its flat storage de (nm x nd,
  !> contiguous in de_val): no copy per element and coordinate. Explicit shapes throughout:
  !> the caller passes addresses, only the element call needs descriptors.
  subroutine evaluate_into(el, nm, nd, x, e, de)
    class(element_t), intent(in) :: el
    integer, intent(in) :: nm, nd
    real(wp), intent(in) :: x(nd)
    real(wp), intent(out) :: e(nm), de(nm, nd)
    call el%evaluate(x, e, de)
  end subroutine evaluate_into


  module subroutine kin_residual(this, model, q, r, jacobian)
    class(kinematics_t), intent(inout) :: this
    type(model_t), intent(in) :: model
    real(wp), intent(in) :: q(:)
    real(wp), intent(out) :: r(:)
    logical, intent(in), optional :: jacobian
    real(wp) :: de(model%max_modes, model%max_dofs), xe(model%max_dofs)
    integer :: iel, k, nm, nd, first, mf
    logical :: with_jac
    with_jac = .false.
    if (present(jacobian)) with_jac = jacobian
    do iel = 1, model%n_elements
      nm = this%el_nm(iel)
      nd = this%el_nd(iel)
      mf = model%mode_first(iel)
      associate (el => model%elements(iel)%e, e => this%e_val(mf:mf + nm - 1))
        ! Gathered into a contiguous buffer: a vector subscript as the actual argument makes
        ! the compiler allocate a temporary per element.
        xe(1:nd) = this%x(el%dofs)
        if (with_jac) then
          first = this%de_offset(iel)
          call evaluate_into(el, nm, nd, xe(1:nd), e, this%de_val(first:first + nm * nd - 1))
        else
          call el%evaluate(xe(1:nd), e, de(1:nm, 1:nd))
        end if
      end associate
    end do
    call residual_rows(size(r), size(this%q_rows), size(this%e_val), size(q), this%row_mode, &
      this%q_rows, this%mode_q, this%mode_period, this%e_val, q, r)
    if (.not. with_jac) return
    ! The entries in the element order of kin_init: the sums into repeated slots are the same.
    if (this%sparse) then
      call assemble_sparse(size(this%jac_set_src), size(this%jac_add_src), size(this%de_val), &
        size(this%jac_sp%val), this%jac_set_src, this%jac_set_slot, this%jac_add_src, &
        this%jac_add_slot, this%de_val, this%jac_sp%val)
    else
      this%lu = 0.0_wp
      do k = 1, size(this%jac_src)
        this%lu(this%jac_row(k), this%jac_col(k)) = this%lu(this%jac_row(k), this%jac_col(k)) &
          + this%de_val(this%jac_src(k))
      end do
    end if
    call gather(size(this%in_src), size(this%de_val), this%in_src, this%de_val, this%in_val)
  end subroutine kin_residual

  ! The flat loops of kin_residual on explicit-shape arrays: the compiler keeps the bases in
  ! registers where it reloaded each component's descriptor per entry.

  !> Row i of the residual is the value of its mode (e_val(0) = 0 for a row without one),
  !> less q on the rows q_rows, wrapped into (-period/2, period/2] where the mode has a period.
  pure subroutine residual_rows(n_c, n_qr, n_e, n_q, row_mode, q_rows, mode_q, period, e_val, &
      q, r)
    integer, intent(in) :: n_c, n_qr, n_e, n_q
    integer, intent(in) :: row_mode(n_c), q_rows(n_qr), mode_q(n_e - 1)
    real(wp), intent(in) :: period(n_e - 1), e_val(0:n_e - 1), q(n_q)
    real(wp), intent(out) :: r(n_c)
    integer :: k, m, row
    do k = 1, n_c
      r(k) = e_val(row_mode(k))
    end do
    do k = 1, n_qr
      row = q_rows(k)
      m = row_mode(row)
      r(row) = e_val(m) - q(mode_q(m))
      if (period(m) > 0) r(row) = modulo(r(row) + period(m) / 2, period(m)) - period(m) / 2
    end do
  end subroutine residual_rows

  !> The sparse values from the element Jacobians: each slot's first entry assigned (0 + d as
  !> the former zeroing and sum gave: -0.0 becomes +0.0, the same bits), the others added.
  pure subroutine assemble_sparse(n_set, n_add, n_de, n_val, set_src, set_slot, add_src, &
      add_slot, de, val)
    integer, intent(in) :: n_set, n_add, n_de, n_val
    integer, intent(in) :: set_src(n_set), set_slot(n_set), add_src(n_add), add_slot(n_add)
    real(wp), intent(in) :: de(n_de)
    real(wp), intent(inout) :: val(n_val)
    integer :: k
    ! Every entry of J_c at every Newton iteration: unrolled, the loop control is a quarter of
    ! what it was per entry (other compilers read the directive as a comment).
    !GCC$ unroll 4
    do k = 1, n_set
      val(set_slot(k)) = 0.0_wp + de(set_src(k))
    end do
    do k = 1, n_add
      val(add_slot(k)) = val(add_slot(k)) + de(add_src(k))
    end do
  end subroutine assemble_sparse

  !> to(k) = from(src(k)).
  pure subroutine gather(n, n_src, src, from, to)
    integer, intent(in) :: n, n_src, src(n)
    real(wp), intent(in) :: from(n_src)
    real(wp), intent(out) :: to(n)
    integer :: k
    do k = 1, n
      to(k) = from(src(k))
    end do
  end subroutine gather
end submodule model_kinematics_residual
