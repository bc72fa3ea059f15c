!> The expanded evaluation of a reduced model (docs/theory.md section 9, "Expanded
!> evaluation"): a cost per evaluation independent of the model's size.
!>
!> In z = (q_rh, eta), the prescribed coordinates and the modal ones, the nodal coordinates are
!> expanded to third order about a point z0,
!>     x(z) = x0 + X1 dz + X2[dz, dz] / 2 + X3[dz, dz, dz] / 6,   dz = z - z0,
!> X1 = DF T and X2 = D2F[T., T.] from solves with the kinematic factors at z0 (T: z -> q), X3
!> by differences of X2; along joints that turn part of a planar model rigidly, X2 and X3
!> from the turns' O(n) products instead (reduction_turns). With W = dx/dz, x_dot = W zd and x_ddot = W zdd + (X2 + X3[dz])[zd,
!> zd], so that the reduced mass W^T M W, the inertia forces W^T (M x_ddot + h), the loads
!> W^T f and the stresses V^T sigma are polynomials in dz and zd whose coefficients (up to m^4
!> numbers, m = n_rh + k) are projected once per expansion: an evaluation then costs O(m^4),
!> not O(n). They are kept to first order in dz, the mass to second (the element masses and
!> weights change by a difference along X1; the elements' quadratic velocity forces h are
!> taken at z0); the stresses of the dynamic modes are linear, exact.
!>
!> An expansion serves while the quadratic term is small: with d1 and d2 bounds of the nodal
!> translations of X1 dz and X2[dz, dz] / 2, while (d2 / d1)^2 <= tol, which for a rotation by
!> an angle a is a^2 / 4, the relative size of the first term the inertia forces drop. Up to
!> MAX_KEPT expansions are kept (fewer where their series would take more than KEPT_BYTES):
!> a state that leaves one is looked up among the others (a structure vibrating about a rest
!> position goes back and forth between two) before a new one is made in place of the one
!> used longest ago.
!>
!> Where the prescribed coordinates move, a new expansion is centred ahead of the state, on
!> their known path (set_centre_time): the state then crosses its whole range instead of
!> starting at its centre, and about half as many expansions serve a joint's travel. With the
!> joints' angles exact (reduction_frames) the joints cost no range, and the centre is put
!> ahead along the modal rates instead (set_centre_modal).
module reduction_expansion
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_MODEL
  use core_linalg, only: chol_factor, chol_solve, gemv_add
  use model_system, only: model_t, error_norm_of
  use dynamics_system, only: dynamics_t
  use reduction_basis, only: basis_t
  use reduction_turns, only: turn_t, find_turns, turn_derivative, apply_turns_transposed
  use reduction_frames, only: frames_t
  implicit none
  private
  public :: expansion_t, expansion_set_t, expansion_unsupported, AHEAD_FRACTION, kept_slots

  integer, parameter :: MAX_KEPT = 64, MIN_KEPT = 4
  !> Memory the kept expansions' series X1, X2, X3 may take together (n (m + m^2 + m (m + 1)
  !> (m + 2) / 6) numbers each): 64 at 128 elements per link and k = 4 take 39 MB; a model of
  !> 10^5 coordinates keeps 13.
  integer(kind=8), parameter :: KEPT_BYTES = 2_8**30
  !> A new expansion is centred where the prescribed coordinates alone would use this fraction
  !> of the tolerance at the current state: the rest is left to the modal coordinates, whose
  !> path is not known in advance (two-link, tol 1e-3: 0.25, 0.5 and 0.8 gave 53, 48 and 44
  !> expansions instead of 73, and a tip 1.0, 1.1 and 1.2 times as far from the full
  !> evaluation's).
  real(wp), parameter :: AHEAD_FRACTION = 0.5_wp

  !> One expansion and its projected coefficients (i: equation, l: the dz factor, a, b: the
  !> zd factors).
  type :: expansion_t
    logical :: valid = .false.
    !> Take the series' columns along prescribed coordinates that turn part of the model
    !> rigidly from the turns' products (reduction_turns); turned: this expansion did.
    logical :: use_turns = .true., turned = .false.
    !> Keep the turns' angles exact (reduction_frames) where they allow: the series are then
    !> in the modal coordinates only, the joints at their angles in z0.
    logical :: use_frames = .true.
    type(frames_t) :: frames
    type(turn_t), allocatable :: turns(:)
    integer, allocatable :: turn_order(:)
    integer :: nr = 0, k = 0, m = 0
    real(wp), allocatable :: z0(:), x0(:), xr(:)     !< xr = DF_dy q_ref (error norm)
    real(wp), allocatable :: x1(:, :), x2(:, :, :)   !< (n_x, m), (n_x, m, m)
    !> X3's distinct columns (n_x, m (m + 1) (m + 2) / 6): X3(:, l, a, b) for l <= a <= b is
    !> column tri(l, a, b) (X3 is symmetric in its three indices).
    real(wp), allocatable :: x3(:, :)
    integer, allocatable :: tri(:, :, :)
    real(wp), allocatable :: a(:, :), b(:, :, :)     !< mass: a + sum_l b(:, :, l) dz_l
    real(wp), allocatable :: c(:, :, :, :)           !< + sum_lr c(:, :, l, r) dz_l dz_r
    real(wp), allocatable :: g0(:, :, :), g1(:, :, :, :)  !< inertia forces (i, [l,] a, b)
    real(wp), allocatable :: f1(:), f2(:, :)         !< loads and weights: f1 + f2 dz
    real(wp), allocatable :: s0(:), kz(:, :), dz(:, :)    !< stresses: s0 + kz dz + dz zd
    real(wp), allocatable :: s1(:), s2(:, :)         !< largest nodal translation per column
    !> Potential energy: strain of the modes es0 + es1 dz + dz es2 dz / 2 and the elements'
    !> weights vg0 - gw1 dz - dz gw2 dz / 2 (loads at outputs: -f x).
    real(wp) :: es0 = 0.0_wp, vg0 = 0.0_wp
    real(wp), allocatable :: es1(:), es2(:, :), gw1(:), gw2(:, :)
    logical :: loads_vary = .false.                  !< loads with motion laws: projected per call
    real(wp), allocatable :: load0(:)                !< the constant loads in f1, f2
    !> The farthest state served (largest quadratic spread d2 [m]): time, z = (p, eta) and
    !> eta_dot; and the d2 up to which it has been compared with the exact model.
    real(wp) :: far_d2 = 0.0_wp, checked_d2 = 0.0_wp, far_t = 0.0_wp
    real(wp), allocatable :: far_z(:), far_rate(:)
  contains
    procedure :: build => exp_build
    procedure :: needs_update => exp_needs_update
    procedure :: spread => exp_spread
    procedure :: spread_at => exp_spread_at
    procedure, nopass :: beyond => exp_beyond
    procedure :: accel => exp_accel
    procedure :: coordinates => exp_coordinates
    procedure :: energy => exp_energy
    procedure :: error_norm => exp_error_norm
  end type expansion_t

  !> The expansions kept during a run, the one in use and the counts for the output.
  type :: expansion_set_t
    real(wp) :: tol = 1.0e-3_wp
    logical :: use_frames = .true.                   !< the expansions' use_frames
    type(expansion_t), allocatable :: item(:)        !< kept_slots(...) once one is made
    integer :: current = 0
    integer :: last_use(MAX_KEPT) = 0, clock = 0
    integer :: n_expansions = 0
    integer :: n_exact_turns = 0                     !< of them, with the turns exact
    !> The joint angles of the last state looked up (find): the error norm's configuration.
    real(wp), allocatable :: p_last(:)
    !> Largest nodal translation [m] between the exact kinematics and an expansion at the
    !> farthest accepted state it served (set_unchecked: when a new one is made, at the end of
    !> a run and before a new basis) and at the samples.
    real(wp) :: manifold_error = 0.0_wp
    integer :: n_unchecked = 0   !< of them, where the exact model failed (not compared)
  contains
    procedure :: find => set_find
    procedure :: note_served => set_note_served
    procedure :: centre_time => set_centre_time
    procedure :: centre_modal => set_centre_modal
    procedure :: unchecked => set_unchecked
    procedure :: note_checked => set_note_checked
    procedure :: expand => set_expand
    procedure :: forget => set_forget
  end type expansion_set_t

  interface
    !> Expand about the state (t, eta) (reduction_expansion_build).
    module subroutine exp_build(this, dyn, basis, t, eta, err)
      class(expansion_t), intent(inout) :: this
      type(dynamics_t), intent(inout) :: dyn
      type(basis_t), intent(in) :: basis
      real(wp), intent(in) :: t, eta(:)
      type(error_t), intent(out) :: err
    end subroutine exp_build
    !> X2 at the kinematics' current solution (reduction_expansion_series): the pairs
    !> first <= a <= b by an element pass and a solve, those with a turn (a < first) from the
    !> turns' products.
    module subroutine second_terms(dyn, x1, x2, turns, first)
      type(dynamics_t), intent(inout) :: dyn
      real(wp), intent(in) :: x1(:, :)
      real(wp), intent(out) :: x2(:, :, :)
      type(turn_t), intent(in) :: turns(:)
      integer, intent(in) :: first
    end subroutine second_terms
    !> X3's distinct columns and tri (reduction_expansion_series); the columns along the
    !> first first - 1 directions (turns) from the turns' products.
    module subroutine third_terms(this, dyn, size_x, turns, first)
      type(expansion_t), intent(inout) :: this
      type(dynamics_t), intent(inout) :: dyn
      real(wp), intent(in) :: size_x
      type(turn_t), intent(in) :: turns(:)
      integer, intent(in) :: first
    end subroutine third_terms
    !> Make a kept expansion that serves the state (p, eta) current (reduction_expansion_set).
    module logical function set_find(this, p, eta) result(found)
      class(expansion_set_t), intent(inout) :: this
      real(wp), intent(in) :: p(:), eta(:)
    end function set_find
    !> Keep an accepted state if it is the farthest its expansion has served
    !> (reduction_expansion_set).
    module subroutine set_note_served(this, t, p, eta, eta_dot)
      class(expansion_set_t), intent(inout) :: this
      real(wp), intent(in) :: t, p(:), eta(:), eta_dot(:)
    end subroutine set_note_served
    !> A new expansion about (t, eta), in an empty slot or the one used longest ago
    !> (reduction_expansion_set).
    module subroutine set_expand(this, dyn, basis, t, eta, err)
      class(expansion_set_t), intent(inout) :: this
      type(dynamics_t), intent(inout) :: dyn
      type(basis_t), intent(in) :: basis
      real(wp), intent(in) :: t, eta(:)
      type(error_t), intent(out) :: err
    end subroutine set_expand
    !> Drop every expansion, a new basis (reduction_expansion_set).
    module subroutine set_forget(this)
      class(expansion_set_t), intent(inout) :: this
    end subroutine set_forget
    !> Where on the joints' path to centre a new expansion (reduction_expansion_set).
    module real(wp) function set_centre_time(this, dyn, t, p) result(tc)
      class(expansion_set_t), intent(in) :: this
      type(dynamics_t), intent(in) :: dyn
      real(wp), intent(in) :: t, p(:)
    end function set_centre_time
    !> Where along the modal rates to centre one with the turns exact (reduction_expansion_set).
    module function set_centre_modal(this, eta, eta_dot, tau_max) result(eta_c)
      class(expansion_set_t), intent(in) :: this
      real(wp), intent(in) :: eta(:), eta_dot(:), tau_max
      real(wp) :: eta_c(size(eta))
    end function set_centre_modal
    !> A kept expansion other than skip that served a state farther than where it was
    !> compared with the exact model (0: none), and that state (reduction_expansion_set).
    module integer function set_unchecked(this, skip, t, z, z_rate) result(i)
      class(expansion_set_t), intent(in) :: this
      integer, intent(in) :: skip
      real(wp), intent(out) :: t
      real(wp), allocatable, intent(out) :: z(:), z_rate(:)
    end function set_unchecked
    !> Expansion i (its coordinates x_series) compared with the exact coordinates x at its
    !> farthest state (reduction_expansion_set).
    module subroutine set_note_checked(this, i, model, x, x_series)
      class(expansion_set_t), intent(inout) :: this
      integer, intent(in) :: i
      type(model_t), intent(in) :: model
      real(wp), intent(in) :: x(:), x_series(:)
    end subroutine set_note_checked
  end interface

contains

  !> Why the expanded evaluation cannot represent this model ('' when it can).
  function expansion_unsupported(model) result(why)
    type(model_t), intent(in) :: model
    character(len=:), allocatable :: why
    why = ''
    if (model%n_elastic > 0) why = 'elastic (calculable) element modes'
    if (size(model%moment_lambda) > 0) why = 'moments on spatial nodes'
    if (size(model%actuator_element) > 0) why = 'actuators'
  end function expansion_unsupported

  !> How many expansions of n coordinates and m = n_rh + k terms to keep.
  pure integer function kept_slots(n, m) result(slots)
    integer, intent(in) :: n, m
    integer(kind=8) :: per_expansion
    per_expansion = 8_8 * n * (m + m**2 + m * (m + 1) * (m + 2) / 6)
    slots = int(max(int(MIN_KEPT, 8), min(int(MAX_KEPT, 8), KEPT_BYTES / per_expansion)))
  end function kept_slots

  !> Whether the state (p, eta) is outside this expansion's range (see the module).
  pure logical function exp_needs_update(this, p, eta, tol)
    class(expansion_t), intent(in) :: this
    real(wp), intent(in) :: p(:), eta(:), tol
    exp_needs_update = .true.
    if (this%valid) exp_needs_update = this%beyond(this%spread_at(p, eta), tol)
  end function exp_needs_update

  !> Whether spreads d = (d1, d2) are beyond the tolerance: (d2 / d1)^2 > tol. Type-bound
  !> (as spread_at) so that the set's submodule reaches it: gfortran 12 emits no symbol for a
  !> private module function it has inlined everywhere in the module.
  pure logical function exp_beyond(d, tol)
    real(wp), intent(in) :: d(2), tol
    exp_beyond = d(2)**2 > tol * d(1)**2
  end function exp_beyond

  !> exp_spread of the step from the centre to the state (p, eta).
  pure function exp_spread_at(this, p, eta) result(d)
    class(expansion_t), intent(in) :: this
    real(wp), intent(in) :: p(:), eta(:)
    real(wp) :: d(2), dz(this%m)
    call step_from_centre(this, p, eta, dz)
    d = this%spread(dz)
  end function exp_spread_at

  !> Bounds (d1, d2) of the nodal translations of the series' linear and quadratic terms for
  !> the step dz from z0.
  pure function exp_spread(this, dz) result(d)
    class(expansion_t), intent(in) :: this
    real(wp), intent(in) :: dz(:)
    real(wp) :: d(2)
    integer :: a
    d(1) = dot_product(this%s1, abs(dz))
    d(2) = 0.0_wp
    do a = 1, this%m
      d(2) = d(2) + abs(dz(a)) * dot_product(this%s2(:, a), abs(dz))
    end do
    d(2) = 0.5_wp * d(2)
  end function exp_spread

  !> The reduced mass a + sum_l b(:, :, l) dz_l + sum_lr c(:, :, l, r) dz_l dz_r (m x m), over
  !> the free directions l, r of dz.
  function mass_at(this, dz) result(mz)
    type(expansion_t), intent(in) :: this
    real(wp), intent(in) :: dz(:)
    real(wp) :: mz(this%m, this%m)
    real(wp) :: w(this%m)
    integer :: lo, r, k
    lo = first_free(this)
    k = this%m - lo + 1
    mz = this%a
    if (k == 0) return
    call gemv_add(this%m**2, k, this%b(1, 1, lo), dz(lo:), mz)
    ! c(:, :, lo:m, r) is contiguous for each r.
    do r = lo, this%m
      w(lo:) = dz(r) * dz(lo:)
      call gemv_add(this%m**2, k, this%c(1, 1, lo, r), w(lo:), mz)
    end do
  end function mass_at

  !> dz = (p, eta) - z0, without the temporary of an array constructor (called per
  !> evaluation).
  pure subroutine step_from_centre(this, p, eta, dz)
    type(expansion_t), intent(in) :: this
    real(wp), intent(in) :: p(:), eta(:)
    real(wp), intent(out) :: dz(:)
    dz(1:this%nr) = p - this%z0(1:this%nr)
    if (this%frames%on) dz(1:this%nr) = 0.0_wp
    dz(this%nr + 1:this%m) = eta - this%z0(this%nr + 1:this%m)
  end subroutine step_from_centre

  !> The first direction of dz that may be non-zero: with the turns exact the joints stay at
  !> z0's angles in the series (step_from_centre), and only the modal directions move.
  pure integer function first_free(this) result(lo)
    type(expansion_t), intent(in) :: this
    lo = 1
    if (this%frames%on) lo = this%nr + 1
  end function first_free

  !> Modal accelerations at (t, eta, eta_dot) from the expansion: O(m^4), no model pass.
  !> p, pd, pdd: the prescribed coordinates and their rates at t (dynamics_t%prescribed).
  subroutine exp_accel(this, dyn, t, p, pd, pdd, eta, eta_dot, acc, err)
    class(expansion_t), intent(in) :: this
    type(dynamics_t), intent(in) :: dyn
    real(wp), intent(in) :: t, p(:), pd(:), pdd(:), eta(:), eta_dot(:)
    real(wp), intent(out) :: acc(:)
    type(error_t), intent(out) :: err
    real(wp) :: dz(this%m), zd(this%m), mz(this%m, this%m), f(this%m), v(this%m)
    real(wp) :: w(this%m, this%m), quad(this%m, this%m), rhs(this%k), mee(this%k, this%k)
    real(wp) :: cm(this%m, this%m), fc(this%m)
    integer :: l, info, nr, lo
    nr = this%nr
    call step_from_centre(this, p, eta, dz)
    zd(1:nr) = pd
    zd(nr + 1:) = eta_dot
    mz = mass_at(this, dz)
    f = this%f1
    lo = first_free(this)
    if (lo <= this%m) call gemv_add(this%m, this%m - lo + 1, this%f2(1, lo), dz(lo:), f)
    if (this%frames%on) then
      call this%frames%correction(p - this%z0(1:nr), dz, zd, cm, fc)
      mz = mz + cm
      f = f + fc
    end if
    if (this%loads_vary) f = f + projected_load(this, dyn%load_factor * dyn%loads_at(t) - &
      this%load0, p, dz)
    ! Inertia forces (g0 + g1 dz)[zd, zd]: the tensors contracted with zd zd^T first.
    do l = 1, this%m
      quad(:, l) = zd * zd(l)
    end do
    v = 0.0_wp
    call gemv_add(this%m, this%m**2, this%g0, quad, v)
    w = 0.0_wp
    call gemv_add(this%m**2, this%m**2, this%g1, quad, w)
    call gemv_add(this%m, this%m, w, dz, v)
    ! The stresses s0 + kz dz + dz zd go to the right with v.
    v(nr + 1:) = v(nr + 1:) + this%s0
    call gemv_add(this%k, this%m, this%kz, dz, v(nr + 1:))
    call gemv_add(this%k, this%m, this%dz, zd, v(nr + 1:))
    rhs = f(nr + 1:) - v(nr + 1:)
    do l = 1, nr
      rhs = rhs - mz(nr + 1:, l) * pdd(l)
    end do
    mee = mz(nr + 1:, nr + 1:)
    call chol_factor(mee, info)
    if (info /= 0) then
      call err%set(ERR_MODEL, 'the expanded reduced mass matrix is not positive definite')
      return
    end if
    call chol_solve(mee, rhs)
    acc = rhs
  end subroutine exp_accel

  !> W^T f for loads f that change in time at joint angles p: O(n m^2).
  function projected_load(this, f, p, dz) result(g)
    type(expansion_t), intent(in) :: this
    real(wp), intent(in) :: f(:), p(:), dz(:)
    real(wp) :: g(this%m)
    real(wp), allocatable :: ft(:)
    integer :: l, i, lo
    lo = first_free(this)
    allocate(ft, source=f)
    ! W = L W0 with the turns exact: W^T f = W0^T (L^T f).
    if (this%frames%on) call apply_turns_transposed(this%turns, this%turn_order, p - &
      this%z0(1:this%nr), ft)
    do i = 1, this%m
      g(i) = dot_product(ft, this%x1(:, i))
      do l = lo, this%m
        g(i) = g(i) + dz(l) * dot_product(ft, this%x2(:, i, l))
      end do
    end do
  end function projected_load

  !> Nodal coordinates on the expansion at z = (p, eta): O(n m^3) / 6 with X3's symmetry, over
  !> the free directions only (the modal ones with the turns exact).
  function exp_coordinates(this, z) result(x)
    class(expansion_t), intent(in) :: this
    real(wp), intent(in) :: z(:)
    real(wp) :: x(size(this%x0))
    real(wp) :: dz(this%m), w2(this%m)
    real(wp), allocatable :: xs(:, :), w3(:)
    integer :: a, b, l, lo, c0
    call step_from_centre(this, z(1:this%nr), z(this%nr + 1:), dz)
    lo = first_free(this)
    x = this%x0
    if (lo <= this%m) then
      ! X3's columns with l >= lo follow each other from tri(lo, lo, lo) (third_terms' order).
      c0 = this%tri(lo, lo, lo)
      allocate(w3(c0:size(this%x3, 2)))
      ! X3[dz, dz, dz] / 6 over lo <= l <= a <= b: each distinct triple with its multiplicity
      do b = lo, this%m
        do a = lo, b
          do l = lo, a
            w3(this%tri(l, a, b)) = dz(l) * dz(a) * dz(b) * triple_weight(l, a, b)
          end do
        end do
      end do
      call gemv_add(size(x), this%m - lo + 1, this%x1(1, lo), dz(lo:), x)
      ! X2[dz, dz] / 2: the columns (lo:m, b) of each b are contiguous.
      do b = lo, this%m
        w2(lo:) = (0.5_wp * dz(b)) * dz(lo:)
        call gemv_add(size(x), this%m - lo + 1, this%x2(1, lo, b), w2(lo:), x)
      end do
      call gemv_add(size(x), size(w3), this%x3(1, c0), w3, x)
    end if
    if (this%frames%on) then
      xs = reshape(x, [size(x), 1])
      call this%frames%turn(z(1:this%nr) - this%z0(1:this%nr), xs, .true.)
      x = xs(:, 1)
    end if
  end function exp_coordinates

  !> Permutations of the triple (l, a, b), l <= a <= b, over 6 (X3's term of the series).
  pure real(wp) function triple_weight(l, a, b) result(w)
    integer, intent(in) :: l, a, b
    if (l == a .and. a == b) then
      w = 1.0_wp / 6
    else if (l == a .or. a == b) then
      w = 0.5_wp
    else
      w = 1.0_wp
    end if
  end function triple_weight

  !> Kinetic and potential energy at (z, zd) from the expansion; the loads' potential -f x
  !> from the nodal coordinates x (O(n)).
  function exp_energy(this, z, zd, f, x) result(en)
    class(expansion_t), intent(in) :: this
    real(wp), intent(in) :: z(:), zd(:), f(:), x(:)
    real(wp) :: en(2)
    real(wp) :: dz(this%m), mz(this%m, this%m)
    call step_from_centre(this, z(1:this%nr), z(this%nr + 1:), dz)
    mz = mass_at(this, dz)
    if (this%frames%on) mz = mz + this%frames%kinetic(z(1:this%nr) - this%z0(1:this%nr), dz)
    en(1) = 0.5_wp * dot_product(zd, matmul(mz, zd))
    en(2) = this%es0 + dot_product(this%es1, dz) + 0.5_wp * dot_product(dz, &
      matmul(this%es2, dz)) + this%vg0 - dot_product(this%gw1, dz) - 0.5_wp * &
      dot_product(dz, matmul(this%gw2, dz)) - dot_product(f, x)
    if (this%frames%on) en(2) = en(2) + this%frames%potential(z(1:this%nr) - &
      this%z0(1:this%nr), dz)
  end function exp_energy

  !> The full model's error norm (dynamics_t%error_norm) with DF_dy V = X1's modal columns.
  !> p: the joint angles (with the turns exact, the nodal fields turn with them).
  subroutine exp_error_norm(this, model, dq, eta_old, eta_new, rtol, atol, p, norm)
    class(expansion_t), intent(in) :: this
    type(model_t), intent(in) :: model
    real(wp), intent(in) :: dq(:), eta_old(:), eta_new(:), rtol, atol, p(:)
    real(wp), intent(out) :: norm
    ! dx, x_old, x_new: the step and the nodal vectors that scale it.
    real(wp), allocatable :: xs(:, :)
    real(wp) :: cf(this%k, 3), step(2), largest(2)
    integer :: n
    n = size(this%x0)
    if (this%frames%on .and. this%k > 0) then
      cf(:, 1) = dq
      cf(:, 2) = eta_old
      cf(:, 3) = eta_new
      call this%frames%norm_terms(this%x1(:, this%nr + 1:), this%xr, cf, p - &
        this%z0(1:this%nr), step, largest)
      norm = error_norm_of(step, largest, rtol, atol)
      return
    end if
    allocate(xs(n, 3))
    xs(:, 1) = 0.0_wp
    xs(:, 2) = this%xr
    xs(:, 3) = this%xr
    if (this%k > 0) then
      ! X1's modal columns are contiguous: they pass as an n x k matrix from their first
      ! element.
      call gemv_add(n, this%k, this%x1(1, this%nr + 1), dq, xs(:, 1))
      call gemv_add(n, this%k, this%x1(1, this%nr + 1), eta_old, xs(:, 2))
      call gemv_add(n, this%k, this%x1(1, this%nr + 1), eta_new, xs(:, 3))
    end if
    ! With the turns exact, W = L W0: all three are fields (DF_dy q).
    if (this%frames%on) call this%frames%turn(p - this%z0(1:this%nr), xs, .false.)
    norm = model%error_norm(xs(:, 1), max(abs(xs(:, 2)), abs(xs(:, 3))), rtol, atol)
  end subroutine exp_error_norm
end module reduction_expansion
