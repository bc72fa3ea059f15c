!> Accelerations of the dynamic coordinates from the sparse system in nodal accelerations and
!> constraint multipliers (docs/theory.md section 5.4):
!>     [ M    J_k^T ] [ y      ]   [ f - J_d^T sigma_dy ]
!>     [ J_k  0     ] [ lambda ] = [ 0                  ]
!> over the free nodal coordinates (calculable ones and those that are degrees of freedom).
!> J_k are the rows of the rigid and prescribed modes, J_d those of the dynamic modes, f the
!> nodal forces of eq. (1) (loads, weight, -M (D2F qd qd + DF_rh qdd_rh), -h, elastic stresses)
!> and y = DF_dy qdd_dy the part of the nodal accelerations due to the dynamic coordinates. Its
!> solution is that of Mbar qdd_dy = DF_dy^T f - sigma_dy: y spans the null space of J_k, which
!> is the range of DF_dy, and DF_dy^T J_d^T sigma_dy = sigma_dy. Then qdd of a dynamic mode is
!> J_d y on its row and that of a dynamic coordinate its entry of y. The matrix has a few
!> entries per element, so KLU factors it in O(n) where forming Mbar costs O(n^3).
module dynamics_augmented
  use core_kinds, only: wp
  use core_sparse, only: sparse_lu_t, entries_t
  use elements_base, only: MODE_DYNAMIC, MODE_RIGID, MODE_PRESCRIBED, mode_has_stress
  use model_system, only: model_t
  implicit none
  private
  public :: augmented_t, element_mass_t

  !> Element mass matrices of the last evaluation, one flat array (offset per element).
  type :: element_mass_t
    integer, allocatable :: offset(:)         !< start of element i's block, 0 if no inertia
    real(wp), allocatable :: val(:)
    !> Every element's coordinates, flat: element i's from dof_first(i) to dof_first(i + 1) - 1
    !> (the products loop over them without reaching into the polymorphic elements).
    integer, allocatable :: dof_first(:), dofs(:)
  contains
    procedure :: init => mass_init
    procedure :: times => mass_times
    procedure :: difference_times => mass_difference_times
  end type element_mass_t

  type :: augmented_t
    integer :: n_free = 0, n_con = 0
    !> Counts the factorisations of `newton`, so that a caller can tell whether the factors
    !> it left there are still the ones it made.
    integer :: newton_serial = 0
    integer, allocatable :: free_index(:)     !< coordinate -> unknown (0 if not free)
    integer, allocatable :: con_index(:)      !< kinematic row -> multiplier unknown (0: none)
    !> Element Jacobians dD/dx of the last factorisation, flat (offset per element)
    integer, allocatable :: de_offset(:)
    real(wp), allocatable :: de_val(:)
    !> The dynamic modes' q_dy indices, and J_d entry by entry (dynamic mode, coordinate k of
    !> its element, in that order) for the products with it without class tests or element
    !> lookups: position in de_val, coordinate and its unknown (0: none).
    !> Dynamic mode i's entries run from jd_first(i) to jd_first(i + 1) - 1, those of free
    !> coordinates first (to jd_last_free(i), in element order, as are the others): the
    !> products with J_d over the unknowns stop there.
    integer, allocatable :: dyn_q(:), jd_first(:), jd_last_free(:)
    integer, allocatable :: jd_de(:), jd_coord(:), jd_free(:)
    !> Element coordinates, flat as in element_mass_t.
    integer, allocatable :: dof_first(:), dofs(:)
    !> free_index of the flat element coordinates, and per mode whether its row enters the
    !> iteration matrix's stiffness (dynamic modes; stressed modes of elastic elements).
    integer, allocatable :: free_of(:), el_nm(:)     !< el_nm: modes per element
    logical, allocatable :: stressed(:)
    type(sparse_lu_t) :: lu
    !> The iteration matrix of implicit integrators in the same form, M replaced by
    !> M + D_x^T (c_q S + c_v S_d) D_x over the stressed modes (see aug_factor_newton).
    type(sparse_lu_t) :: newton
  contains
    procedure :: init => aug_init
    procedure :: factor => aug_factor
    procedure :: factor_newton => aug_factor_newton
    procedure :: accelerations => aug_accelerations
    procedure :: nodal_equivalent => aug_nodal_equivalent
  end type augmented_t

  interface
    !> M w for nodal vectors w (n_x, k): the lumped masses and the element blocks
    !> (dynamics_augmented_mass).
    module function mass_times(this, model, w) result(mw)
      class(element_mass_t), intent(in) :: this
      type(model_t), intent(in) :: model
      real(wp), intent(in) :: w(:, :)
      real(wp) :: mw(size(w, 1), size(w, 2))
    end function mass_times
    !> (M - M_base) w over the element blocks of two sets of element masses of one model.
    module function mass_difference_times(this, base, model, w) result(dw)
      class(element_mass_t), intent(in) :: this
      type(element_mass_t), intent(in) :: base
      type(model_t), intent(in) :: model
      real(wp), intent(in) :: w(:, :)
      real(wp) :: dw(size(w, 1), size(w, 2))
    end function mass_difference_times
    !> Nodal forces whose projection DF_dy^T is the generalised force g (n_dy, k columns):
    !> J_d^T g on the modes, g itself on the dynamic coordinates (dynamics_augmented_products).
    module function aug_nodal_equivalent(this, model, g) result(f)
      class(augmented_t), intent(in) :: this
      type(model_t), intent(in) :: model
      real(wp), intent(in) :: g(:, :)
      real(wp) :: f(model%n_x, size(g, 2))
    end function aug_nodal_equivalent
    !> Accelerations a (n_dy, k) for nodal forces f (n_x, k) with the last factors (those of
    !> the iteration matrix with `newton`): the solution of Mbar a = DF_dy^T f.
    module subroutine aug_accelerations(this, model, f, a, newton)
      class(augmented_t), intent(inout) :: this
      type(model_t), intent(in) :: model
      real(wp), intent(in) :: f(:, :)
      real(wp), intent(out) :: a(:, :)
      logical, intent(in), optional :: newton
    end subroutine aug_accelerations
  end interface

contains

  subroutine mass_init(this, model)
    class(element_mass_t), intent(inout) :: this
    type(model_t), intent(in) :: model
    integer :: iel, n
    allocate(this%offset(model%n_elements))
    n = 0
    do iel = 1, model%n_elements
      this%offset(iel) = 0
      associate (el => model%elements(iel)%e)
        if (.not. el%has_inertia()) cycle
        this%offset(iel) = n + 1
        n = n + size(el%dofs)**2
      end associate
    end do
    allocate(this%val(n))
    this%val = 0.0_wp
    call flat_dofs(model, this%dof_first, this%dofs)
  end subroutine mass_init

  !> All elements' coordinates in one array, element iel's from first(iel) on.
  subroutine flat_dofs(model, first, dofs)
    type(model_t), intent(in) :: model
    integer, allocatable, intent(out) :: first(:), dofs(:)
    integer :: iel
    allocate(first(model%n_elements + 1))
    first(1) = 1
    do iel = 1, model%n_elements
      first(iel + 1) = first(iel) + size(model%elements(iel)%e%dofs)
    end do
    allocate(dofs(first(model%n_elements + 1) - 1))
    do iel = 1, model%n_elements
      dofs(first(iel):first(iel + 1) - 1) = model%elements(iel)%e%dofs
    end do
  end subroutine flat_dofs

  !> Number the unknowns and record the pattern, in the order aug_factor visits the entries.
  !> de_offset: the layout of the element Jacobians as the sparse kinematics keeps them.
  subroutine aug_init(this, model, de_offset, n_de)
    class(augmented_t), intent(inout) :: this
    type(model_t), intent(in) :: model
    integer, intent(in) :: de_offset(:), n_de
    type(entries_t) :: mass_pattern, newton_pattern
    integer :: i, iel, j, k, l, row, n
    allocate(this%free_index(model%n_x), this%con_index(model%n_c))
    this%de_offset = de_offset
    allocate(this%de_val(n_de))
    this%free_index = 0
    this%n_free = 0
    do i = 1, model%n_x
      if (model%calc_index(i) > 0 .or. model%coord_input(i) == MODE_DYNAMIC) then
        this%n_free = this%n_free + 1
        this%free_index(i) = this%n_free
      end if
    end do
    this%con_index = 0
    this%n_con = 0
    do i = 1, size(model%modes)
      if (model%modes(i)%row == 0) cycle
      if (model%modes(i)%class /= MODE_RIGID .and. model%modes(i)%class /= MODE_PRESCRIBED) cycle
      this%n_con = this%n_con + 1
      this%con_index(model%modes(i)%row) = this%n_free + this%n_con
    end do
    n = this%n_free + this%n_con
    ! Every diagonal entry is in the pattern (zeros for multipliers and massless coordinates)
    ! so that KLU may pivot on it when the values allow. The iteration matrix has every
    ! element's block (stiffness where there is no mass). Entries of fixed or prescribed
    ! coordinates (index 0) stay out.
    do i = 1, n
      call mass_pattern%add(i, i)
      call newton_pattern%add(i, i)
    end do
    do iel = 1, model%n_elements
      associate (el => model%elements(iel)%e)
        do l = 1, size(el%dofs)
          do k = 1, size(el%dofs)
            if (el%has_inertia()) call mass_pattern%add(this%free_index(el%dofs(k)), &
              this%free_index(el%dofs(l)))
            call newton_pattern%add(this%free_index(el%dofs(k)), this%free_index(el%dofs(l)))
          end do
        end do
        do j = 1, el%n_modes()
          row = model%modes(model%mode_first(iel) + j - 1)%row
          if (row == 0) cycle
          if (this%con_index(row) == 0) cycle
          do k = 1, size(el%dofs)
            if (this%free_index(el%dofs(k)) == 0) cycle
            call mass_pattern%add(this%con_index(row), this%free_index(el%dofs(k)))
            call mass_pattern%add(this%free_index(el%dofs(k)), this%con_index(row))
            call newton_pattern%add(this%con_index(row), this%free_index(el%dofs(k)))
            call newton_pattern%add(this%free_index(el%dofs(k)), this%con_index(row))
          end do
        end do
      end associate
    end do
    call flat_dofs(model, this%dof_first, this%dofs)
    this%free_of = this%free_index(this%dofs)
    allocate(this%stressed(size(model%modes)), this%el_nm(model%n_elements))
    do iel = 1, model%n_elements
      this%el_nm(iel) = model%elements(iel)%e%n_modes()
      do j = model%mode_first(iel), model%mode_first(iel) + this%el_nm(iel) - 1
        this%stressed(j) = model%modes(j)%class == MODE_DYNAMIC .or. &
          (model%elastic_element(iel) .and. mode_has_stress(model%modes(j)%class))
      end do
    end do
    call list_dynamic_modes(this, model)
    call this%lu%setup(n, mass_pattern%rows(1:mass_pattern%n), mass_pattern%cols(1:mass_pattern%n))
    call this%newton%setup(n, newton_pattern%rows(1:newton_pattern%n), &
      newton_pattern%cols(1:newton_pattern%n))
  end subroutine aug_init

  subroutine list_dynamic_modes(this, model)
    type(augmented_t), intent(inout) :: this
    type(model_t), intent(in) :: model
    integer :: iel, j, k, m, n, p, nm, nd, pass, coord
    n = count(model%modes%class == MODE_DYNAMIC)
    allocate(this%dyn_q(n), this%jd_first(n + 1), this%jd_last_free(n))
    p = 0
    do iel = 1, model%n_elements
      nm = model%elements(iel)%e%n_modes()
      p = p + (this%dof_first(iel + 1) - this%dof_first(iel)) * &
        count(model%modes(model%mode_first(iel):model%mode_first(iel) + nm - 1)%class &
        == MODE_DYNAMIC)
    end do
    allocate(this%jd_de(p), this%jd_coord(p), this%jd_free(p))
    n = 0
    p = 0
    do iel = 1, model%n_elements
      nm = model%elements(iel)%e%n_modes()
      nd = this%dof_first(iel + 1) - this%dof_first(iel)
      do j = 1, nm
        m = model%mode_first(iel) + j - 1
        if (model%modes(m)%class /= MODE_DYNAMIC) cycle
        n = n + 1
        this%dyn_q(n) = model%modes(m)%q - model%n_rh
        this%jd_first(n) = p + 1
        do pass = 1, 2
          do k = 1, nd
            coord = this%dofs(this%dof_first(iel) + k - 1)
            if ((this%free_index(coord) > 0) .neqv. (pass == 1)) cycle
            p = p + 1
            this%jd_de(p) = this%de_offset(iel) + j - 1 + (k - 1) * nm
            this%jd_coord(p) = coord
            this%jd_free(p) = this%free_index(coord)
          end do
          if (pass == 1) this%jd_last_free(n) = p
        end do
      end do
    end do
    this%jd_first(n + 1) = p + 1
  end subroutine list_dynamic_modes

  !> Assemble the matrix from the element Jacobians de_val (flat, as kept by the kinematics
  !> at its last factorisation: same layout as this%de_val) and mass blocks, and factor it.
  !> info /= 0 when it is singular: Mbar is then singular too.
  subroutine aug_factor(this, model, de_val, mass, info)
    class(augmented_t), intent(inout) :: this
    type(model_t), intent(in) :: model
    real(wp), intent(in) :: de_val(:)
    type(element_mass_t), intent(in) :: mass
    integer, intent(out) :: info
    real(wp) :: rcond
    integer :: iel, k, l, next, nd, d0, off
    this%de_val = de_val
    call start_assembly(this, model, this%lu, next, 1.0_wp)
    do iel = 1, model%n_elements
      d0 = this%dof_first(iel) - 1
      nd = this%dof_first(iel + 1) - 1 - d0
      off = mass%offset(iel)
      if (off > 0) then
        do l = 1, nd
          if (this%free_of(d0 + l) == 0) cycle
          do k = 1, nd
            if (this%free_of(d0 + k) == 0) cycle
            next = next + 1
            call add_entry(this%lu, next, mass%val(off + (l - 1) * nd + k - 1))
          end do
        end do
      end if
      call add_constraint_rows(this, model, iel, this%el_nm(iel), nd, &
        this%de_val(this%de_offset(iel):), this%lu, next)
    end do
    call this%lu%factor(info, rcond)
    call check_factors(this%lu, info, rcond)
  end subroutine aug_factor

  !> info = 1 where the factors of a regular-looking factorisation are unusable. A pivot
  !> ratio min|u_ii| / max|u_ii| below 1e-14 is no proof: in the augmented system stiffness,
  !> masses and the unit constraint rows differ by many orders, and KLU's pivoting, which
  !> prefers the diagonal, let it fall to 3.8e-15 on a regular matrix, whose solve then
  !> missed a known vector by up to 4e-3 (the two-link at 32 and 64 elements per link turned
  !> for 0.3 s and shifted for its modes; 1.4e-10 at rest). Such factors are redone with full
  !> pivoting and kept where a known vector comes back to 1e-6 (a singular matrix misses it
  !> by O(1)).
  subroutine check_factors(lu, info, rcond)
    type(sparse_lu_t), intent(inout) :: lu
    integer, intent(inout) :: info
    real(wp), intent(inout) :: rcond
    if (info /= 0 .or. rcond >= 1.0e-14_wp) return
    if (solves(lu)) return
    call lu%factor_pivoting(info, rcond)
    if (info == 0 .and. rcond < 1.0e-14_wp) then
      if (.not. solves(lu)) info = 1
    end if
  end subroutine check_factors

  !> Whether the factors return a known vector to 1e-6 of its size.
  logical function solves(lu)
    type(sparse_lu_t), intent(inout) :: lu
    real(wp) :: x0(lu%n), b(lu%n)
    integer :: i
    x0 = [(1.0_wp + 0.5_wp * sin(real(i, wp)), i = 1, lu%n)]
    b = lu%multiply(x0)
    call lu%solve(b)
    solves = maxval(abs(b - x0)) <= 1.0e-6_wp * maxval(abs(x0))
  end function solves

  !> The iteration matrix Mbar + c_q K0 + c_v D0 of an implicit step in augmented form (for
  !> I - c_q da/dq - c_v da/dv = Mbar^-1 (Mbar + c_q K0 + c_v D0) with the linearised Jacobian):
  !> K0 = DF_dy^T K_x DF_dy with the element stiffness K_x = D_x^T S D_x over the stressed modes
  !> (the dynamic ones; dynamic and elastic ones of elements with elastic modes), because
  !> D_x DF_dy is the unit row on a dynamic mode. The element Jacobians are those of the last
  !> aug_factor, or de_val (the kinematics' at the masses' state: the matrix then belongs to
  !> one state without an aug_factor there); the masses are those of `mass`. Statics'
  !> preconditioner (dynamics_static_krylov) asks for mass_scale M + c_q K0 instead, and for
  !> the traces of the two parts over the free coordinates (stiffness, mass) to choose
  !> mass_scale.
  subroutine aug_factor_newton(this, model, mass, c_q, c_v, info, mass_scale, traces, de_val)
    class(augmented_t), intent(inout) :: this
    type(model_t), intent(in) :: model
    type(element_mass_t), intent(in) :: mass
    real(wp), intent(in) :: c_q, c_v
    integer, intent(out) :: info
    real(wp), intent(in), optional :: mass_scale
    real(wp), intent(out), optional :: traces(2)
    real(wp), intent(in), optional :: de_val(:)
    ! Fixed-size element buffers: no allocation per element in a step's factorisation.
    real(wp) :: s(model%max_modes, model%max_modes), work(model%max_modes)
    real(wp) :: block(model%max_dofs, model%max_dofs)
    real(wp) :: rcond, scale, tr(2)
    integer :: iel, k, l, next, nd, nm, d0, off
    scale = 1.0_wp
    if (present(mass_scale)) scale = mass_scale
    if (present(de_val)) this%de_val = de_val
    call start_assembly(this, model, this%newton, next, scale)
    tr = [0.0_wp, sum(model%lumped, mask=this%free_index > 0)]
    do iel = 1, model%n_elements
      d0 = this%dof_first(iel) - 1
      nd = this%dof_first(iel + 1) - 1 - d0
      nm = this%el_nm(iel)
      call model%elements(iel)%e%stiffness(s(1:nm, 1:nm))
      call stiffness_block(nm, nd, this%de_val(this%de_offset(iel):), s, model%max_modes, &
        this%stressed(model%mode_first(iel):), c_q + c_v * model%elements(iel)%e%damping, &
        work, block, model%max_dofs)
      do k = 1, nd
        if (this%free_of(d0 + k) > 0) tr(1) = tr(1) + block(k, k)
      end do
      off = mass%offset(iel)
      if (off > 0) then
        do l = 1, nd
          do k = 1, nd
            block(k, l) = block(k, l) + scale * mass%val(off + (l - 1) * nd + k - 1)
          end do
        end do
        do k = 1, nd
          if (this%free_of(d0 + k) > 0) tr(2) = tr(2) + mass%val(off + (k - 1) * (nd + 1))
        end do
      end if
      do l = 1, nd
        if (this%free_of(d0 + l) == 0) cycle
        do k = 1, nd
          if (this%free_of(d0 + k) == 0) cycle
          next = next + 1
          call add_entry(this%newton, next, block(k, l))
        end do
      end do
      call add_constraint_rows(this, model, iel, nm, nd, this%de_val(this%de_offset(iel):), &
        this%newton, next)
    end do
    if (present(traces)) traces = tr
    call this%newton%factor(info, rcond)
    call check_factors(this%newton, info, rcond)
    this%newton_serial = this%newton_serial + 1
  end subroutine aug_factor_newton

  !> Zero the values, put the lumped masses (times mass_scale) on the diagonal (the first n
  !> entries of both patterns) and point next at the last diagonal entry.
  subroutine start_assembly(this, model, lu, next, mass_scale)
    type(augmented_t), intent(in) :: this
    type(model_t), intent(in) :: model
    type(sparse_lu_t), intent(inout) :: lu
    integer, intent(out) :: next
    real(wp), intent(in) :: mass_scale
    integer :: i
    lu%val = 0.0_wp
    do i = 1, model%n_x
      if (this%free_index(i) > 0) call add_entry(lu, this%free_index(i), &
        mass_scale * model%lumped(i))
    end do
    next = this%n_free + this%n_con
  end subroutine start_assembly

  !> The entries of element iel's rigid and prescribed rows, J_k and J_k^T, in pattern order
  !> from entry next + 1 on; next is left at the last one.
  subroutine add_constraint_rows(this, model, iel, nm, nd, de, lu, next)
    type(augmented_t), intent(in) :: this
    type(model_t), intent(in) :: model
    integer, intent(in) :: iel, nm, nd
    real(wp), intent(in) :: de(nm, nd)
    type(sparse_lu_t), intent(inout) :: lu
    integer, intent(inout) :: next
    integer :: j, k, row, d0
    d0 = this%dof_first(iel) - 1
    do j = 1, nm
      row = model%modes(model%mode_first(iel) + j - 1)%row
      if (row == 0) cycle
      if (this%con_index(row) == 0) cycle
      do k = 1, nd
        if (this%free_of(d0 + k) == 0) cycle
        call add_entry(lu, next + 1, de(j, k))
        call add_entry(lu, next + 2, de(j, k))
        next = next + 2
      end do
    end do
  end subroutine add_constraint_rows

  !> coef D^T S D over one element's stressed mode rows (nm x nd, D = de), into blk(1:nd,
  !> 1:nd): S D column by column in w, then the rows' products. Explicit shapes and the
  !> leading dimensions of the caller's fixed-size buffers: no temporaries per element.
  pure subroutine stiffness_block(nm, nd, de, s, lds, stressed, coef, w, blk, ldb)
    integer, intent(in) :: nm, nd, lds, ldb
    real(wp), intent(in) :: de(nm, nd), s(lds, nm), coef
    logical, intent(in) :: stressed(nm)
    real(wp), intent(inout) :: w(nm)
    real(wp), intent(out) :: blk(ldb, nd)
    real(wp) :: acc
    integer :: i, j, k, l
    do l = 1, nd
      do i = 1, nm
        acc = 0.0_wp
        do j = 1, nm
          if (stressed(j)) acc = acc + s(i, j) * de(j, l)
        end do
        w(i) = acc
      end do
      do k = 1, nd
        acc = 0.0_wp
        do i = 1, nm
          if (stressed(i)) acc = acc + de(i, k) * w(i)
        end do
        blk(k, l) = coef * acc
      end do
    end do
  end subroutine stiffness_block

  pure subroutine add_entry(lu, k, v)
    type(sparse_lu_t), intent(inout) :: lu
    integer, intent(in) :: k
    real(wp), intent(in) :: v
    lu%val(lu%pos(k)) = lu%val(lu%pos(k)) + v
  end subroutine add_entry
end module dynamics_augmented
