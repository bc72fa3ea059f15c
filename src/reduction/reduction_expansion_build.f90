!> Making an expansion (reduction_expansion): the exact kinematics at z0, the series terms X1,
!> X2, X3 and the projected coefficients. O(n m^3) work and about m^3 / 6 + m^2 solves with the
!> kinematic factors, so an expansion costs tens of full evaluations.
submodule (reduction_expansion) reduction_expansion_build
  use dynamics_augmented, only: element_mass_t
  use reduction_turns, only: turn_order
  implicit none

  !> Nodal motion of the masses' difference step, relative to the model's size (truncation
  !> 1e-7 relative, round-off 1e-9).
  real(wp), parameter :: MASS_STEP = 1.0e-7_wp

contains

  module procedure exp_build
    real(wp), allocatable :: tz(:, :), mx1(:, :), mx2(:, :), mx3(:, :), dmx(:, :), gh(:, :)
    real(wp), allocatable :: xl(:), fw0(:), fwl(:), x12(:, :), conv_l(:, :), zero(:)
    real(wp), allocatable :: x2mx2(:, :), x1mx2(:, :)
    real(wp) :: p(dyn%model%n_rh), pd(dyn%model%n_rh), pdd(dyn%model%n_rh), hl, size_x, vg
    type(element_mass_t) :: mass_l
    integer :: n, nr, k, m, l, i, first
    ! Not usable until complete (a failed build may be retried elsewhere in this slot).
    this%valid = .false.
    this%far_d2 = 0.0_wp
    this%checked_d2 = 0.0_wp
    nr = dyn%model%n_rh
    k = size(eta)
    m = nr + k
    n = dyn%model%n_x
    call dyn%prescribed(t, p, pd, pdd)
    allocate(zero(dyn%model%n_dy))
    zero = 0.0_wp
    call dyn%prepare(t, basis%q_ref + matmul(basis%v, eta), zero, err)
    if (.not. err%ok()) return
    this%nr = nr
    this%k = k
    this%m = m
    this%z0 = [p, eta]
    this%x0 = dyn%kin%x
    size_x = max(1.0e-3_wp, maxval(abs(this%x0)))
    allocate(tz(dyn%model%n_q, m))
    tz = 0.0_wp
    do i = 1, nr
      tz(i, i) = 1.0_wp
    end do
    tz(nr + 1:, nr + 1:) = basis%v
    if (allocated(this%x1)) deallocate(this%x1, this%x2, this%xr)
    allocate(this%x1(n, m), this%x2(n, m, m), this%xr(n))
    call dyn%kin%apply_df_many(dyn%model, tz, this%x1)
    this%turned = .false.
    this%frames%on = .false.
    if (allocated(this%turns)) deallocate(this%turns)
    if (this%use_turns) call find_turns(dyn%model, this%x0, this%x1, this%turns, this%turned)
    first = 1
    if (this%turned) first = nr + 1
    if (.not. allocated(this%turns)) allocate(this%turns(0))
    ! Only turns found have their nodes (find_turns stops at the first coordinate that is not).
    this%turn_order = [integer ::]
    if (this%turned) this%turn_order = turn_order(this%turns)
    call second_terms(dyn, this%x1, this%x2, this%turns, first)
    block
      real(wp) :: qr(dyn%model%n_q)
      qr(1:nr) = 0.0_wp
      qr(nr + 1:) = basis%q_ref
      call dyn%kin%apply_df(dyn%model, qr, this%xr)
    end block
    call third_terms(this, dyn, size_x, this%turns, first)
    ! Mass products at z0 and the quadratic velocity forces of the elements there.
    mx1 = dyn%mass%times(dyn%model, this%x1)
    mx2 = dyn%mass%times(dyn%model, reshape(this%x2, [n, m * m]))
    ! X1^T M X3 = (M X1)^T X3: M is symmetric.
    mx3 = third_projection(this, mx1)
    ! X2_il^T M X2_ab, row i + (l - 1) m, column a + (b - 1) m
    x2mx2 = matmul(transpose(reshape(this%x2, [n, m * m])), mx2)
    call second_order_mass(this, x2mx2, mx3)
    allocate(gh(n, m * m))
    call velocity_forces(dyn, this%x0, this%x1, gh)
    ! Loads: the constant part (with the lumped masses' weights) and the element weights.
    this%loads_vary = size(dyn%model%load_motion) > 0
    ! dyn%load is what loads_at(t) holds without the loads' motion laws.
    this%load0 = dyn%load_factor * dyn%load
    fw0 = element_weights(dyn, this%x0, this%vg0)
    if (this%turned .and. this%use_frames) call this%frames%setup(dyn%model, dyn%mass, &
      this%x0, this%x1, this%x2, this%x3, this%tri, this%turns, this%load0, &
      dyn%load_factor * dyn%model%gravity(1:2))
    this%a = matmul(transpose(this%x1), mx1)
    this%f1 = matmul(this%load0 + fw0, this%x1)
    this%gw1 = matmul(fw0, this%x1)
    ! X1^T M X2 serves g0 here and b below.
    x1mx2 = matmul(transpose(this%x1), mx2)
    this%g0 = reshape(x1mx2 + matmul(transpose(this%x1), gh), [m, m, m])
    if (allocated(this%b)) deallocate(this%b, this%g1, this%f2, this%gw2)
    allocate(this%b(m, m, m), this%g1(m, m, m, m), this%f2(m, m), this%gw2(m, m))
    ! First-order changes along each column of X1: of W (X2), of the element masses and
    ! weights (differences), of the convective term (X3).
    mass_l = dyn%mass
    x12 = reshape([this%x1, this%x2], [n, m + m * m])
    allocate(xl(n))
    do l = 1, m
      if (this%frames%on .and. l <= nr) then
        ! The turns exact: the series are used at the joints' angles z0 (dz_l = 0).
        this%b(:, :, l) = 0.0_wp
        this%g1(:, l, :, :) = 0.0_wp
        this%gw2(:, l) = 0.0_wp
        this%f2(:, l) = 0.0_wp
        cycle
      end if
      hl = MASS_STEP * size_x / max(tiny(1.0_wp), maxval(abs(this%x1(:, l))))
      xl = this%x0 + hl * this%x1(:, l)
      call element_masses(dyn, xl, mass_l)
      call this%frames%mass_change(dyn%model, mass_l, l, hl, this%x1, x12(:, m + 1:))
      ! X1^T dM [X1, X2] along X1_l = (dM X1)^T [X1, X2]: dM is symmetric
      dmx = matmul(transpose(mass_l%difference_times(dyn%mass, dyn%model, this%x1)), x12) / hl
      fwl = (element_weights(dyn, xl, vg) - fw0) / hl
      this%b(:, :, l) = x1mx2(:, (l - 1) * m + 1:l * m)
      this%b(:, :, l) = this%b(:, :, l) + transpose(this%b(:, :, l)) + dmx(:, 1:m)
      conv_l = dmx(:, m + 1:) + mx3(:, (l - 1) * m * m + 1:l * m * m)
      do i = 1, m
        this%g1(i, l, :, :) = reshape(x2mx2(i + (l - 1) * m, :) + conv_l(i, :), [m, m])
        this%gw2(i, l) = dot_product(this%x2(:, i, l), fw0) + dot_product(this%x1(:, i), fwl)
        this%f2(i, l) = dot_product(this%x2(:, i, l), this%load0) + this%gw2(i, l)
      end do
    end do
    call stress_terms(this, dyn, basis, tz)
    call strain_terms(this, dyn, tz, dyn%kin%q)
    if (allocated(this%s1)) deallocate(this%s1, this%s2)
    allocate(this%s1(m), this%s2(m, m))
    do l = 1, m
      this%s1(l) = dyn%model%largest_translation(this%x1(:, l))
      do i = 1, m
        this%s2(i, l) = dyn%model%largest_translation(this%x2(:, i, l))
      end do
    end do
    this%valid = .true.
  end procedure exp_build

  !> The mass's second-order terms with the element masses held: c(i, j, l, r) = X2_il^T M
  !> X2_jr + (X1_i^T M X3_jlr + X1_j^T M X3_ilr) / 2, from x2mx2 = X2^T M X2 and mx3.
  subroutine second_order_mass(this, x2mx2, mx3)
    type(expansion_t), intent(inout) :: this
    real(wp), intent(in) :: x2mx2(:, :), mx3(:, :)
    integer :: i, j, l, r, m
    m = this%m
    if (allocated(this%c)) deallocate(this%c)
    allocate(this%c(m, m, m, m))
    do r = 1, m
      do l = 1, m
        do j = 1, m
          do i = 1, m
            this%c(i, j, l, r) = x2mx2(i + (l - 1) * m, j + (r - 1) * m) + &
              0.5_wp * (mx3(i, (r - 1) * m * m + (l - 1) * m + j) + &
              mx3(j, (r - 1) * m * m + (l - 1) * m + i))
          end do
        end do
      end do
    end do
  end subroutine second_order_mass

  !> (M X1)^T X3 as (m, m^2 m), column (b - 1) m + a of block l holding X1_i^T M X3(:, a, b, l):
  !> M is symmetric, and X3's columns are looked up with their indices sorted.
  function third_projection(this, mx1) result(p)
    type(expansion_t), intent(in) :: this
    real(wp), intent(in) :: mx1(:, :)
    real(wp) :: p(this%m, this%m**3)
    real(wp) :: distinct(this%m, size(this%x3, 2))
    integer :: a, b, l, s(3)
    distinct = matmul(transpose(mx1), this%x3)
    do l = 1, this%m
      do b = 1, this%m
        do a = 1, this%m
          s = sorted([l, a, b])
          p(:, (l - 1) * this%m**2 + (b - 1) * this%m + a) = distinct(:, this%tri(s(1), s(2), &
            s(3)))
        end do
      end do
    end do
  end function third_projection

  pure function sorted(i) result(s)
    integer, intent(in) :: i(3)
    integer :: s(3)
    s(1) = minval(i)
    s(3) = maxval(i)
    s(2) = sum(i) - s(1) - s(3)
  end function sorted

  !> The elements' quadratic velocity forces h(x0, .) as a bilinear form on the columns of
  !> X1: gh(:, (b - 1) m + a) = h[X1_a, X1_b], by polarisation of h along X1_a and X1_a + X1_b,
  !> every direction in one element pass (el%convective_many).
  subroutine velocity_forces(dyn, x0, x1, gh)
    type(dynamics_t), intent(in) :: dyn
    real(wp), intent(in) :: x0(:), x1(:, :)
    real(wp), intent(out) :: gh(:, :)
    real(wp) :: xd(size(x1, 1), size(x1, 2) * (size(x1, 2) + 1) / 2)
    real(wp) :: h(size(x1, 1), size(xd, 2))
    integer :: a, b, m, c
    m = size(x1, 2)
    xd(:, 1:m) = x1
    c = m
    do a = 1, m
      do b = a + 1, m
        c = c + 1
        xd(:, c) = x1(:, a) + x1(:, b)
      end do
    end do
    h = nodal_h(dyn, x0, xd)
    c = m
    do a = 1, m
      gh(:, (a - 1) * m + a) = h(:, a)
      do b = a + 1, m
        c = c + 1
        gh(:, (b - 1) * m + a) = 0.5_wp * (h(:, c) - h(:, a) - h(:, b))
        gh(:, (a - 1) * m + b) = gh(:, (b - 1) * m + a)
      end do
    end do
  end subroutine velocity_forces

  !> Assembled quadratic velocity forces h(x, xd(:, c)) of the elements with inertia, for every
  !> column (gathered and summed along the transposes, as the series' element passes).
  function nodal_h(dyn, x, xd) result(h)
    type(dynamics_t), intent(in) :: dyn
    real(wp), intent(in) :: x(:), xd(:, :)
    real(wp) :: h(size(x), size(xd, 2))
    real(wp) :: xd_t(size(xd, 2), size(x)), h_t(size(xd, 2), size(x))
    real(wp) :: xe(dyn%model%max_dofs), xde(dyn%model%max_dofs, size(xd, 2))
    real(wp) :: he(dyn%model%max_dofs, size(xd, 2))
    integer :: iel, nd, k
    xd_t = transpose(xd)
    h_t = 0.0_wp
    do iel = 1, dyn%model%n_elements
      if (dyn%mass%offset(iel) == 0) cycle
      associate (el => dyn%model%elements(iel)%e)
        nd = size(el%dofs)
        do k = 1, nd
          xe(k) = x(el%dofs(k))
          xde(k, :) = xd_t(:, el%dofs(k))
        end do
        call el%convective_many(xe(1:nd), xde(1:nd, :), he(1:nd, :))
        do k = 1, nd
          h_t(:, el%dofs(k)) = h_t(:, el%dofs(k)) + he(k, :)
        end do
      end associate
    end do
    h = transpose(h_t)
  end function nodal_h

  !> The element mass blocks at x, in dyn%mass's layout.
  subroutine element_masses(dyn, x, mass)
    type(dynamics_t), intent(in) :: dyn
    real(wp), intent(in) :: x(:)
    type(element_mass_t), intent(inout) :: mass
    real(wp) :: me(dyn%model%max_dofs, dyn%model%max_dofs), he(dyn%model%max_dofs)
    real(wp) :: zero(dyn%model%max_dofs)
    integer :: iel, nd, first
    zero = 0.0_wp
    do iel = 1, dyn%model%n_elements
      first = mass%offset(iel)
      if (first == 0) cycle
      associate (el => dyn%model%elements(iel)%e)
        nd = size(el%dofs)
        call el%inertia(x(el%dofs), zero(1:nd), me(1:nd, 1:nd), he(1:nd))
        mass%val(first:first + nd * nd - 1) = reshape(me(1:nd, 1:nd), [nd * nd])
      end associate
    end do
  end subroutine element_masses

  !> Assembled element weights at x and their potential (lumped masses' weights are loads).
  function element_weights(dyn, x, potential) result(f)
    type(dynamics_t), intent(in) :: dyn
    real(wp), intent(in) :: x(:)
    real(wp), intent(out) :: potential
    real(wp) :: f(size(x))
    real(wp) :: fe(dyn%model%max_dofs), g(3), pot
    integer :: iel, nd
    f = 0.0_wp
    potential = 0.0_wp
    if (all(dyn%model%gravity == 0)) return
    g = dyn%load_factor * dyn%model%gravity
    do iel = 1, dyn%model%n_elements
      associate (el => dyn%model%elements(iel)%e)
        nd = size(el%dofs)
        call el%weight(x(el%dofs), g(1:dyn%model%dim), fe(1:nd), pot)
        f(el%dofs) = f(el%dofs) + fe(1:nd)
        potential = potential + pot
      end associate
    end do
  end function element_weights

  !> V^T sigma at z0 and its (exact, linear) dependence on dz and zd.
  subroutine stress_terms(this, dyn, basis, tz)
    type(expansion_t), intent(inout) :: this
    type(dynamics_t), intent(in) :: dyn
    type(basis_t), intent(in) :: basis
    real(wp), intent(in) :: tz(:, :)
    real(wp) :: zero(dyn%model%n_q), sigma(dyn%model%n_dy)
    integer :: l
    zero = 0.0_wp
    ! sigma is linear and homogeneous in (q, q_dot): its columns along T are exact.
    sigma = dyn%stresses(dyn%kin%q, zero)
    this%s0 = matmul(sigma, basis%v)
    if (allocated(this%kz)) deallocate(this%kz, this%dz)
    allocate(this%kz(this%k, this%m), this%dz(this%k, this%m))
    do l = 1, this%m
      sigma = dyn%stresses(tz(:, l), zero)
      this%kz(:, l) = matmul(sigma, basis%v)
      sigma = dyn%stresses(zero, tz(:, l))
      this%dz(:, l) = matmul(sigma, basis%v)
    end do
  end subroutine stress_terms

  !> The modes' strain energy E(q0 + T dz) = es0 + es1 dz + dz es2 dz / 2 in one element pass:
  !> the mode values are coordinates or zero, so e(q0 + T dz) = e0 + E dz with E the mode values
  !> of T's columns, and E(q) = sum e^T S e / 2 over the elements (no elastic elements here).
  subroutine strain_terms(this, dyn, tz, q0)
    type(expansion_t), intent(inout) :: this
    type(dynamics_t), intent(in) :: dyn
    real(wp), intent(in) :: tz(:, :), q0(:)
    real(wp) :: e0(dyn%model%max_modes), et(dyn%model%max_modes, this%m)
    real(wp) :: s(dyn%model%max_modes, dyn%model%max_modes)
    real(wp) :: se0(dyn%model%max_modes), set(dyn%model%max_modes, this%m)
    integer :: iel, nm, a
    if (allocated(this%es1)) deallocate(this%es1, this%es2)
    allocate(this%es1(this%m), this%es2(this%m, this%m))
    this%es0 = 0.0_wp
    this%es1 = 0.0_wp
    this%es2 = 0.0_wp
    do iel = 1, dyn%model%n_elements
      associate (el => dyn%model%elements(iel)%e)
        nm = el%n_modes()
        call dyn%model%mode_values(iel, q0, e0(:nm))
        do a = 1, this%m
          call dyn%model%mode_values(iel, tz(:, a), et(:nm, a))
        end do
        if (all(et(:nm, :) == 0) .and. all(e0(:nm) == 0)) cycle
        call el%stiffness(s(:nm, :nm))
        se0(:nm) = matmul(s(:nm, :nm), e0(:nm))
        set(:nm, :) = matmul(s(:nm, :nm), et(:nm, :))
        this%es0 = this%es0 + 0.5_wp * dot_product(e0(:nm), se0(:nm))
        this%es1 = this%es1 + matmul(se0(:nm), et(:nm, :))
        this%es2 = this%es2 + matmul(transpose(et(:nm, :)), set(:nm, :))
      end associate
    end do
  end subroutine strain_terms
end submodule reduction_expansion_build
