!> Making the parts of an expansion with exact turns (reduction_frames): which part each
!> coordinate and element with inertia belongs to, the checks that the parts' masses turn with
!> them, and the projections of the parts' momenta, weights and loads on the series.
submodule (reduction_frames) reduction_frames_setup
  use model_system, only: COORD_X, COORD_Y
  use core_sort, only: sort_by_key
  use reduction_turns, only: CHECK_ANGLE, position_pairs
  implicit none

  !> Relative tolerance of the checks that the elements' masses turn with their parts and
  !> that their weights are their masses times a uniform translation (round-off: 1e-15).
  real(wp), parameter :: CHECK_TOL = 1.0e-10_wp

contains

  module procedure frames_setup
    real(wp), allocatable :: rl(:, :), loads(:, :), rall(:, :), pr1(:, :), pr2(:, :)
    real(wp), allocatable :: pr3(:, :), pw1(:, :), pw2(:, :), pl1(:, :), pl2(:, :), x2f(:, :)
    integer :: j, a, l, r, i, nr, m, n
    logical :: ok
    nr = size(turns)
    m = size(x1, 2)
    n = size(x0)
    this%nr = nr
    this%m = m
    this%g = gravity
    call structure(this, model, mass, turns, ok)
    if (ok) ok = masses_turn(this, model, mass, x0)
    this%on = ok
    if (.not. ok) return
    if (allocated(this%r0)) deallocate(this%r0)
    allocate(this%r0(n, 2 * nr), rl(n, 2 * nr), loads(n, 2 * nr))
    call element_momenta(this, model, mass, this%r0)
    rl = 0.0_wp
    loads = 0.0_wp
    if (allocated(this%lsum)) deallocate(this%lsum, this%mass, this%mass_el)
    allocate(this%lsum(2, nr), this%mass(nr), this%mass_el(nr))
    this%mass_el = 0.0_wp
    this%mass = 0.0_wp
    this%lsum = 0.0_wp
    do i = 1, n
      j = this%coord_part(i)
      if (j == 0 .or. all(model%coord_kind(i) /= [COORD_X, COORD_Y])) cycle
      a = model%coord_kind(i)     ! COORD_X = 1 and COORD_Y = 2 number the axes
      rl(i, a + 2 * (j - 1)) = model%lumped(i)
      if (a == COORD_X) this%mass(j) = this%mass(j) + model%lumped(i)
      loads(i, 1 + 2 * (j - 1)) = load0(i)
      ! J f: (-f_y, f_x)
      loads(i, 2 + 2 * (j - 1)) = merge(-1.0_wp, 1.0_wp, a == COORD_X) * load0(this%pair_of(i))
      this%lsum(a, j) = this%lsum(a, j) + load0(i)
    end do
    do j = 1, nr
      do i = 1, n
        if (model%coord_kind(i) /= COORD_X) cycle
        if (this%coord_part(i) == j .or. i == this%centre(1, j)) this%mass_el(j) = &
          this%mass_el(j) + this%r0(i, 1 + 2 * (j - 1))
      end do
    end do
    this%mass = this%mass + this%mass_el
    rall = this%r0 + rl
    call allocate_series(this)
    ! Every covector against the series at once: (2 nr, m), (2 nr, m^2), (2 nr, distinct X3).
    pr1 = matmul(transpose(rall), x1)
    pw1 = matmul(transpose(this%r0), x1)
    pl1 = matmul(transpose(loads), x1)
    x2f = reshape(x2, [n, m * m])
    pr2 = matmul(transpose(rall), x2f)
    pw2 = matmul(transpose(this%r0), x2f)
    pl2 = matmul(transpose(loads), x2f)
    pr3 = matmul(transpose(rall), x3)
    do j = 1, nr
      associate (cj => this%centre(:, j), cols => [2 * j - 1, 2 * j])
        this%y0(:, j) = x0(cj)
        this%c1(:, :, j) = x1(cj, :)
        this%c2(:, :, :, j) = x2(cj, :, :)
        this%g0(:, :, j) = pr1(cols, :)
        this%w0(:, :, j) = pw1(cols, :)
        this%l0(:, :, j) = pl1(cols, :)
        this%g1(:, :, :, j) = reshape(pr2(cols, :), [2, m, m])
        this%w1(:, :, :, j) = reshape(pw2(cols, :), [2, m, m])
        this%l1(:, :, :, j) = reshape(pl2(cols, :), [2, m, m])
        do r = 1, m
          do l = 1, m
            do a = 1, m
              this%c3(:, a, l, r, j) = x3(cj, tri_of(a, l, r))
              this%g2(:, a, l, r, j) = pr3(cols, tri_of(a, l, r))
            end do
          end do
        end do
      end associate
    end do
  contains
    integer function tri_of(a, b, c)
      integer, intent(in) :: a, b, c
      integer :: s(3)
      s = [minval([a, b, c]), a + b + c - minval([a, b, c]) - maxval([a, b, c]), &
        maxval([a, b, c])]
      tri_of = tri(s(1), s(2), s(3))
    end function tri_of
  end procedure frames_setup

  !> The parts: each coordinate's deepest turn, the turns' parents and order, the part of
  !> each element with inertia; .false. where the turned sets do not nest or an element with
  !> inertia or a lumped mass would not turn with one part.
  subroutine structure(this, model, mass, turns, ok)
    type(frames_t), intent(inout) :: this
    type(model_t), intent(in) :: model
    type(element_mass_t), intent(in) :: mass
    type(turn_t), intent(in) :: turns(:)
    logical, intent(out) :: ok
    ! Of the model's size: allocated (this file's arrays are on the stack).
    logical, allocatable :: member(:, :)
    integer, allocatable :: pairs(:, :)
    integer :: sizes(size(turns)), depth(size(turns)), next(size(turns))
    integer :: nr, j, i, k, iel, d0, nd, part, np, first
    nr = size(turns)
    allocate(member(model%n_x, nr))
    ok = .false.
    member = .false.
    do j = 1, nr
      member(turns(j)%moving(1, :), j) = .true.
      member(turns(j)%moving(2, :), j) = .true.
      member(turns(j)%angles, j) = .true.
      sizes(j) = count(member(:, j))
    end do
    this%coord_part = [(0, i = 1, model%n_x)]
    do i = 1, model%n_x
      do j = 1, nr
        if (.not. member(i, j)) cycle
        if (this%coord_part(i) == 0) then
          this%coord_part(i) = j
        else if (sizes(j) < sizes(this%coord_part(i))) then
          this%coord_part(i) = j
        end if
      end do
    end do
    this%centre = reshape([(turns(j)%centre, j = 1, nr)], [2, nr])
    this%parent = [(this%coord_part(this%centre(1, j)), j = 1, nr)]
    if (allocated(this%inside)) deallocate(this%inside)
    allocate(this%inside(nr, nr))
    this%inside = .false.
    do j = 1, nr
      k = j
      do i = 1, nr
        if (k == 0) exit
        this%inside(k, j) = .true.
        k = this%parent(k)
      end do
      if (k /= 0) return
      depth(j) = count(this%inside(:, j))
    end do
    ! The sets nest: a coordinate is turned by its part's turn and that turn's parents only.
    do i = 1, model%n_x
      part = this%coord_part(i)
      if (part == 0) cycle
      if (any(member(i, :) .neqv. this%inside(:, part))) return
    end do
    this%order = [(i, i = 1, nr)]
    call sort_by_key(this%order, depth)
    ! x and y of every node, for J f and the lumped masses' check.
    pairs = position_pairs(model)
    np = size(pairs, 2)
    this%pair_of = [(0, i = 1, model%n_x)]
    this%pair_of(pairs(1, :)) = pairs(2, :)
    this%pair_of(pairs(2, :)) = pairs(1, :)
    do i = 1, np
      associate (ix => pairs(1, i), iy => pairs(2, i))
        if (this%coord_part(ix) /= this%coord_part(iy)) return
        if (this%coord_part(ix) > 0 .and. model%lumped(ix) /= model%lumped(iy)) return
      end associate
    end do
    do i = 1, model%n_x
      if (this%coord_part(i) > 0 .and. this%pair_of(i) == 0 .and. &
        any(model%coord_kind(i) == [COORD_X, COORD_Y])) return
    end do
    ! What frames_turn visits: the turned nodes' x and y, part by part (a counting sort: the
    ! nodes of part j are columns part_run(j) to part_run(j + 1) - 1), and the turned angles.
    if (allocated(this%part_run)) deallocate(this%part_run)
    if (allocated(this%turned_pairs)) deallocate(this%turned_pairs)
    allocate(this%part_run(nr + 1))
    this%part_run = 0
    do i = 1, np
      j = this%coord_part(pairs(1, i))
      if (j > 0) this%part_run(j + 1) = this%part_run(j + 1) + 1
    end do
    this%part_run(1) = 1
    do j = 1, nr
      this%part_run(j + 1) = this%part_run(j + 1) + this%part_run(j)
    end do
    allocate(this%turned_pairs(2, this%part_run(nr + 1) - 1))
    next = this%part_run(1:nr)
    do i = 1, np
      j = this%coord_part(pairs(1, i))
      if (j == 0) cycle
      this%turned_pairs(:, next(j)) = pairs(:, i)
      next(j) = next(j) + 1
    end do
    this%turned_angles = reshape([(i, this%coord_part(i), i = 1, model%n_x)], [2, model%n_x])
    this%turned_angles = this%turned_angles(:, pack([(i, i = 1, model%n_x)], &
      this%turned_angles(2, :) > 0 .and. this%pair_of(this%turned_angles(1, :)) == 0))
    this%still = pack([(i, i = 1, model%n_x)], this%coord_part == 0 .or. this%pair_of == 0)
    this%error_kind = [(model%error_kind(i), i = 1, model%n_x)]
    this%el_part = [(0, iel = 1, model%n_elements)]
    do iel = 1, model%n_elements
      call block_of(mass, iel, first, d0, nd)
      if (first == 0) cycle
      part = 0
      do k = 1, nd
        j = this%coord_part(mass%dofs(d0 + k))
        if (j == 0) cycle
        if (part == 0) then
          part = j
        else if (depth(j) > depth(part)) then
          part = j
        end if
      end do
      if (part == 0) cycle
      do k = 1, nd
        i = mass%dofs(d0 + k)
        if (this%coord_part(i) /= part .and. all(i /= this%centre(:, part))) return
      end do
      this%el_part(iel) = part
    end do
    ok = .true.
  end subroutine structure

  !> Whether every element with inertia in a part has weights that are its mass times a
  !> uniform translation and a mass that turns with it (M at the configuration turned by
  !> CHECK_ANGLE is A M A^T; checked on one element of each kind); the parts' first moments
  !> at x0 (moment0) on the way.
  logical function masses_turn(this, model, mass, x0) result(ok)
    type(frames_t), intent(inout) :: this
    type(model_t), intent(in) :: model
    type(element_mass_t), intent(in) :: mass
    real(wp), intent(in) :: x0(:)
    real(wp) :: me(model%max_dofs, model%max_dofs), mr(model%max_dofs, model%max_dofs)
    real(wp) :: a(model%max_dofs, model%max_dofs), xe(model%max_dofs), xr(model%max_dofs)
    real(wp) :: t(model%max_dofs), fe(model%max_dofs), he(model%max_dofs), pot, unit(2, 2)
    real(wp) :: rot(2, 2), worst(2), scale(2)
    integer :: iel, j, d0, nd, k, kk, first, c, n_checked, i
    integer :: kinds(2), checked(model%n_elements)
    kinds = [COORD_X, COORD_Y]
    n_checked = 0
    unit = EYE
    rot = rotation(CHECK_ANGLE)
    if (allocated(this%moment0)) deallocate(this%moment0)
    allocate(this%moment0(2, this%nr))
    this%moment0 = 0.0_wp
    worst = 0.0_wp
    scale = 0.0_wp
    do iel = 1, model%n_elements
      j = this%el_part(iel)
      if (j == 0) cycle
      call block_of(mass, iel, first, d0, nd)
      me(1:nd, 1:nd) = reshape(mass%val(first:first + nd * nd - 1), [nd, nd])
      xe(1:nd) = x0(mass%dofs(d0 + 1:d0 + nd))
      associate (el => model%elements(iel)%e, dofs => mass%dofs(d0 + 1:d0 + nd))
        do c = 1, 2
          t(1:nd) = merge(1.0_wp, 0.0_wp, model%coord_kind(dofs) == kinds(c))
          call el%weight(xe(1:nd), unit(:, c), fe(1:nd), pot)
          t(1:nd) = matmul(me(1:nd, 1:nd), t(1:nd))
          worst(1) = max(worst(1), maxval(abs(fe(1:nd) - t(1:nd))))
          scale(1) = max(scale(1), maxval(abs(t(1:nd))))
          this%moment0(c, j) = this%moment0(c, j) - pot
        end do
        ! The turn of the mass is a property of the element's kind: one of each is checked.
        if (any([(same_type_as(el, model%elements(checked(i))%e), i = 1, n_checked)])) cycle
        n_checked = n_checked + 1
        checked(n_checked) = iel
        ! The element turned about the origin: positions R x, angles + CHECK_ANGLE.
        a(1:nd, 1:nd) = 0.0_wp
        xr(1:nd) = xe(1:nd)
        do k = 1, nd
          a(k, k) = 1.0_wp
        end do
        do k = 1, nd
          if (model%coord_kind(dofs(k)) /= COORD_X) then
            if (model%coord_kind(dofs(k)) /= COORD_Y) xr(k) = xe(k) + CHECK_ANGLE
            cycle
          end if
          kk = findloc(dofs, this%pair_of(dofs(k)), 1)
          if (kk == 0) then
            ok = .false.
            return
          end if
          a([k, kk], [k, kk]) = rot
          xr([k, kk]) = matmul(rot, xe([k, kk]))
        end do
        t(1:nd) = 0.0_wp
        call el%inertia(xr(1:nd), t(1:nd), mr(1:nd, 1:nd), he(1:nd))
        mr(1:nd, 1:nd) = mr(1:nd, 1:nd) - matmul(matmul(a(1:nd, 1:nd), me(1:nd, 1:nd)), &
          transpose(a(1:nd, 1:nd)))
        worst(2) = max(worst(2), maxval(abs(mr(1:nd, 1:nd))))
        scale(2) = max(scale(2), maxval(abs(me(1:nd, 1:nd))))
      end associate
    end do
    ok = all(worst <= CHECK_TOL * scale)
  end function masses_turn

  !> The momenta of unit translations of each part's element masses, r(:, a + 2 (j - 1)) =
  !> sum over part j's elements of M_e t_a.
  subroutine element_momenta(this, model, mass, r)
    type(frames_t), intent(in) :: this
    type(model_t), intent(in) :: model
    type(element_mass_t), intent(in) :: mass
    real(wp), intent(out) :: r(:, :)
    integer :: iel, j, d0, nd, first, c, k, i
    r = 0.0_wp
    do iel = 1, model%n_elements
      j = this%el_part(iel)
      if (j == 0) cycle
      call block_of(mass, iel, first, d0, nd)
      ! Column k of the block times the unit translation along x or y.
      do k = 1, nd
        c = model%coord_kind(mass%dofs(d0 + k))
        if (c /= COORD_X .and. c /= COORD_Y) cycle
        do i = 1, nd
          r(mass%dofs(d0 + i), c + 2 * (j - 1)) = r(mass%dofs(d0 + i), c + 2 * (j - 1)) + &
            mass%val(first + (k - 1) * nd + i - 1)
        end do
      end do
    end do
  end subroutine element_momenta

  !> Element iel's mass block in mass: its first value, and its nd coordinates from
  !> mass%dofs(d0 + 1).
  pure subroutine block_of(mass, iel, first, d0, nd)
    type(element_mass_t), intent(in) :: mass
    integer, intent(in) :: iel
    integer, intent(out) :: first, d0, nd
    first = mass%offset(iel)
    d0 = mass%dof_first(iel) - 1
    nd = mass%dof_first(iel + 1) - 1 - d0
  end subroutine block_of

  subroutine allocate_series(this)
    type(frames_t), intent(inout) :: this
    integer :: m, nr
    m = this%m
    nr = this%nr
    if (allocated(this%y0)) deallocate(this%y0, this%c1, this%c2, this%c3, this%g0, this%g1, &
      this%g2, this%w0, this%w1, this%l0, this%l1)
    allocate(this%y0(2, nr), this%c1(2, m, nr), this%c2(2, m, m, nr), this%c3(2, m, m, m, nr))
    allocate(this%g0(2, m, nr), this%g1(2, m, m, nr), this%g2(2, m, m, m, nr))
    allocate(this%w0(2, m, nr), this%w1(2, m, m, nr), this%l0(2, m, nr), this%l1(2, m, m, nr))
  end subroutine allocate_series

  module procedure frames_mass_change
    real(wp), allocatable :: dr(:, :)
    real(wp) :: d1(2 * this%nr, this%m), d2(2 * this%nr, this%m, this%m)
    integer :: j, r
    if (.not. this%on) return
    allocate(dr(size(x1, 1), 2 * this%nr))
    call element_momenta(this, model, mass_l, dr)
    dr = (dr - this%r0) / h
    d1 = matmul(transpose(dr), x1)
    d2 = reshape(matmul(transpose(dr), x2), [2 * this%nr, this%m, this%m])
    do j = 1, this%nr
      associate (cols => [2 * j - 1, 2 * j])
        this%g1(:, :, l, j) = this%g1(:, :, l, j) + d1(cols, :)
        this%w1(:, :, l, j) = this%w1(:, :, l, j) + d1(cols, :)
        do r = 1, this%m
          this%g2(:, :, l, r, j) = this%g2(:, :, l, r, j) + d2(cols, :, r)
          this%g2(:, :, r, l, j) = this%g2(:, :, r, l, j) + d2(cols, :, r)
        end do
      end associate
    end do
  end procedure frames_mass_change
end submodule reduction_frames_setup
