!> Exact joint angles for an expansion (reduction_expansion; docs/theory.md section 9, "Exact
!> turns"). When every prescribed coordinate turns a part of a planar model rigidly
!> (reduction_turns), the configuration at joint angles p0 + delta and modal coordinates eta is
!> that at (p0, eta) with the parts turned, x = L(delta) y + angles, and every field of the
!> series turns with L. Each element with inertia lies in one part j (its nodes and the node
!> turned about), turned by psi_j (the sum of delta over j and its parents), so that on its
!> coordinates L v = R_j (v + 1 tau_j(v)): a rotation and a translation tau_j, linear in the
!> fields' values at the parts' centres,
!>     s_j = s_parent + (R_parent - R_j) v_centre,   tau_j = R_j^T s_j.
!> The masses being invariant under rotation, the reduced mass at (p0 + delta, eta) is that at
!> (p0, eta) plus, over the parts,
!>     C = tau^T G + G^T tau + m_j tau^T tau,   G = momenta r_j . W of the part's masses,
!> and the weights (r_j of unit gravities: weights are the masses times a uniform translation)
!> and nodal loads change likewise. The expansion keeps W, G and the centres' rows as series
!> in the modal step only; the angles enter through R exactly, so that the joints may travel
!> any distance on one expansion. The inertia forces of C are its Christoffel terms.
module reduction_frames
  use core_kinds, only: wp
  use model_system, only: model_t
  use dynamics_augmented, only: element_mass_t
  use reduction_turns, only: turn_t, rotation
  use core_linalg, only: gemv_add
  implicit none
  private
  public :: frames_t

  real(wp), parameter :: EYE(2, 2) = reshape([1.0_wp, 0.0_wp, 0.0_wp, 1.0_wp], [2, 2])

  !> The parts of an expansion and their projected series (a: column of W, l, r: the dz
  !> factors, j: part).
  type :: frames_t
    logical :: on = .false.
    integer :: nr = 0, m = 0
    integer, allocatable :: parent(:), order(:)   !< order: parents first
    logical, allocatable :: inside(:, :)          !< inside(i, j): delta_i turns part j
    integer, allocatable :: centre(:, :), coord_part(:), el_part(:)
    integer, allocatable :: pair_of(:)            !< the other position coordinate of a node
    real(wp), allocatable :: mass(:), mass_el(:)  !< translational mass: all, elements only
    real(wp) :: g(2) = 0.0_wp                     !< gravity with the load factor
    !> The centres' rows of x0, X1, X2 and X3 (2, [m, [m, [m,]]] j).
    real(wp), allocatable :: y0(:, :), c1(:, :, :), c2(:, :, :, :), c3(:, :, :, :, :)
    !> Momenta G = r . W (all masses) to second order, weights r_el . W to first.
    real(wp), allocatable :: g0(:, :, :), g1(:, :, :, :), g2(:, :, :, :, :)
    real(wp), allocatable :: w0(:, :, :), w1(:, :, :, :), moment0(:, :)
    !> Nodal loads f and J f of each part on W to first order, and their sum.
    real(wp), allocatable :: l0(:, :, :), l1(:, :, :, :), lsum(:, :)
    real(wp), allocatable :: r0(:, :)             !< element momenta at x0 (n, 2 nr)
    !> The turned nodes (x, y) part by part, part j's from part_run(j) to part_run(j + 1) - 1,
    !> and the turned angle coordinates (coordinate, part).
    integer, allocatable :: turned_pairs(:, :), part_run(:), turned_angles(:, :)
    !> The coordinates that no turn moves as fields (frames_norm_terms), and every
    !> coordinate's kind in the error norm (model_t%error_kind).
    integer, allocatable :: still(:), error_kind(:)
  contains
    procedure :: setup => frames_setup
    procedure :: mass_change => frames_mass_change
    procedure :: correction => frames_correction
    procedure :: kinetic => frames_kinetic
    procedure :: potential => frames_potential
    procedure :: turn => frames_turn
    procedure :: norm_terms => frames_norm_terms
  end type frames_t

  interface
    !> The parts of the turns and the series' projections at x0 with the element masses
    !> `mass` there, constant nodal loads load0 and gravity (both with the load factor); on
    !> stays .false. where a part's masses would not turn with it (reduction_frames_setup).
    module subroutine frames_setup(this, model, mass, x0, x1, x2, x3, tri, turns, load0, &
      gravity)
      class(frames_t), intent(inout) :: this
      type(model_t), intent(in) :: model
      type(element_mass_t), intent(in) :: mass
      real(wp), intent(in) :: x0(:), x1(:, :), x2(:, :, :), x3(:, :), load0(:), gravity(2)
      integer, intent(in) :: tri(:, :, :)
      type(turn_t), intent(in) :: turns(:)
    end subroutine frames_setup
    !> The first-order change of the element masses along X1_l (element masses mass_l at
    !> x0 + h X1_l): into G's and the weights' terms along l (reduction_frames_setup). x2:
    !> X2 flat, (n, m^2).
    module subroutine frames_mass_change(this, model, mass_l, l, h, x1, x2)
      class(frames_t), intent(inout) :: this
      type(model_t), intent(in) :: model
      type(element_mass_t), intent(in) :: mass_l
      integer, intent(in) :: l
      real(wp), intent(in) :: h, x1(:, :), x2(:, :)
    end subroutine frames_mass_change
  end interface

contains

  !> The mass c and generalised forces f (both m) the turns by delta add at the modal step dz
  !> (dz(1:nr) = 0) and rates zd: C, minus C's Christoffel terms less those at delta = 0
  !> (the expansion's own inertia forces hold these), plus the weights' and loads' change.
  subroutine frames_correction(this, delta, dz, zd, c, f)
    class(frames_t), intent(in) :: this
    real(wp), intent(in) :: delta(:), dz(:), zd(:)
    real(wp), intent(out) :: c(:, :), f(:)
    real(wp) :: ser(2, this%m, 6, this%nr), s(2, this%m, this%nr), rot(2, 2, this%nr)
    real(wp) :: gam(this%m), gr(2), ge(2), lw(2)
    integer :: j, a, l
    call part_series(this, delta, dz, zd, ser, rot)
    f = unturned_christoffel(this, zd, ser)
    call frame_terms(this, rot, zd, ser, c, gam, s)
    f = f - gam
    do j = 1, this%nr
      gr = matmul(transpose(rot(:, :, j)), this%g) - this%g
      do a = this%nr + 1, this%m
        ge = this%w0(:, a, j)
        lw = this%l0(:, a, j)
        do l = this%nr + 1, this%m
          ge = ge + dz(l) * this%w1(:, a, l, j)
          lw = lw + dz(l) * this%l1(:, a, l, j)
        end do
        f(a) = f(a) + gr(1) * ge(1) + gr(2) * ge(2) + (rot(1, 1, j) - 1) * lw(1) - &
          rot(2, 1, j) * lw(2) + (this%mass_el(j) * this%g(1) + this%lsum(1, j)) * s(1, a, j) + &
          (this%mass_el(j) * this%g(2) + this%lsum(2, j)) * s(2, a, j)
      end do
    end do
  end subroutine frames_correction

  !> The mass the turns by delta add at the modal step dz (the kinetic energy's).
  function frames_kinetic(this, delta, dz) result(c)
    class(frames_t), intent(in) :: this
    real(wp), intent(in) :: delta(:), dz(:)
    real(wp) :: c(this%m, this%m)
    real(wp) :: ser(2, this%m, 6, this%nr), s(2, this%m, this%nr), rot(2, 2, this%nr)
    real(wp) :: gam(this%m), zd(this%m)
    zd = 0.0_wp
    call part_series(this, delta, dz, zd, ser, rot)
    call frame_terms(this, rot, zd, ser, c, gam, s)
  end function frames_kinetic

  !> Each part's rotation and, from its series at dz, the centre's W rows, G and their rates
  !> (series_rates): ser(:, :, 1:3, j) for W, ser(:, :, 4:6, j) for G.
  subroutine part_series(this, delta, dz, zd, ser, rot)
    type(frames_t), intent(in) :: this
    real(wp), intent(in) :: delta(:), dz(:), zd(:)
    real(wp), intent(out) :: ser(:, :, :, :), rot(:, :, :)
    integer :: j
    do j = 1, this%nr
      rot(:, :, j) = rotation(sum(delta, mask=this%inside(:, j)))
      ! Whole arrays and the part's index: no copies of sections per call.
      call series_rates(this%m, this%nr, j, 0, this%c1, this%c2, this%c3, dz, zd, ser)
      call series_rates(this%m, this%nr, j, 3, this%g0, this%g1, this%g2, dz, zd, ser)
    end do
  end subroutine part_series

  !> The change of the elements' weights' potential by the turns (the nodal loads' follows
  !> from the turned coordinates).
  real(wp) function frames_potential(this, delta, dz) result(v)
    class(frames_t), intent(in) :: this
    real(wp), intent(in) :: delta(:), dz(:)
    real(wp) :: sp(2, this%nr), yc(2), moment(2), rp(2, 2), rj(2, 2)
    integer :: o, j, l, r, a
    v = 0.0_wp
    do o = 1, this%nr
      j = this%order(o)
      yc = this%y0(:, j)
      moment = this%moment0(:, j)
      ! dz is the modal step only (dz(1:nr) = 0).
      do l = this%nr + 1, this%m
        yc = yc + dz(l) * this%c1(:, l, j)
        moment = moment + dz(l) * this%w0(:, l, j)
        do r = this%nr + 1, this%m
          yc = yc + dz(l) * dz(r) / 2 * this%c2(:, l, r, j)
          moment = moment + dz(l) * dz(r) / 2 * this%w1(:, l, r, j)
          do a = this%nr + 1, this%m
            yc = yc + dz(l) * dz(r) * dz(a) / 6 * this%c3(:, a, l, r, j)
          end do
        end do
      end do
      rj = rotation(sum(delta, mask=this%inside(:, j)))
      rp = EYE
      sp(:, j) = 0.0_wp
      if (this%parent(j) > 0) then
        rp = rotation(sum(delta, mask=this%inside(:, this%parent(j))))
        sp(:, j) = sp(:, this%parent(j))
      end if
      sp(:, j) = sp(:, j) + matmul(rp - rj, yc)
      v = v - dot_product(this%g, matmul(rj - EYE, moment)) - this%mass_el(j) * &
        dot_product(this%g, sp(:, j))
    end do
  end function frames_potential

  !> v <- L(delta) v for each column of v, fields or (positions) configurations, whose angle
  !> coordinates also turn by their parts' angles: on part j, L v = R_j v + s_j with
  !> s_j = s_parent + (R_parent - R_j) v_centre from the unturned values, one pass per column
  !> (the turns composed, O(n) with one rotation per node; the test's reference applies them
  !> one by one).
  pure subroutine frames_turn(this, delta, v, positions)
    class(frames_t), intent(in) :: this
    real(wp), intent(in) :: delta(:)
    real(wp), intent(inout) :: v(:, :)
    logical, intent(in) :: positions
    real(wp) :: rot(2, 2, this%nr), s(2, size(v, 2), this%nr), psi(this%nr)
    real(wp) :: vx, vy, r11, r12, r21, r22, s1, s2
    integer :: j, c, t, ix, iy
    call part_shifts(this, delta, v, rot, s, psi)
    ! Part by part: its rotation and translation stay in registers over its nodes.
    do c = 1, size(v, 2)
      do j = 1, this%nr
        r11 = rot(1, 1, j)
        r12 = rot(1, 2, j)
        r21 = rot(2, 1, j)
        r22 = rot(2, 2, j)
        s1 = s(1, c, j)
        s2 = s(2, c, j)
        do t = this%part_run(j), this%part_run(j + 1) - 1
          ix = this%turned_pairs(1, t)
          iy = this%turned_pairs(2, t)
          vx = v(ix, c)
          vy = v(iy, c)
          v(ix, c) = r11 * vx + r12 * vy + s1
          v(iy, c) = r21 * vx + r22 * vy + s2
        end do
      end do
    end do
    if (.not. positions) return
    do t = 1, size(this%turned_angles, 2)
      associate (i => this%turned_angles(1, t))
        v(i, :) = v(i, :) + psi(this%turned_angles(2, t))
      end associate
    end do
  end subroutine frames_turn

  !> Each part's angle psi(j) and rotation rot(:, :, j), and for every column c of the unturned
  !> fields v the translation the turns give it, s(:, c, j) = s(:, c, parent) + (R_parent -
  !> R_j) v_centre (frames_turn's L v = R_j v + s_j on part j).
  pure subroutine part_shifts(this, delta, v, rot, s, psi)
    type(frames_t), intent(in) :: this
    real(wp), intent(in) :: delta(:), v(:, :)
    real(wp), intent(out) :: rot(:, :, :), s(:, :, :), psi(:)
    real(wp) :: rp(2, 2), vc(2)
    integer :: o, j, p, c
    do j = 1, this%nr
      psi(j) = sum(delta, mask=this%inside(:, j))
      rot(:, :, j) = rotation(psi(j))
    end do
    do o = 1, this%nr
      j = this%order(o)
      p = this%parent(j)
      rp = EYE
      if (p > 0) rp = rot(:, :, p)
      do c = 1, size(v, 2)
        vc = [v(this%centre(1, j), c), v(this%centre(2, j), c)]
        s(:, c, j) = matmul(rp - rot(:, :, j), vc)
        if (p > 0) s(:, c, j) = s(:, c, j) + s(:, c, p)
      end do
    end do
  end subroutine part_shifts

  !> The error norm's terms (model_t%error_norm) of three turned fields without forming them:
  !> the step L X1 cf(:, 1) and the motions L (xr + X1 cf(:, c)), c = 2, 3, with L the turns
  !> by delta on fields (frames_turn) and x1 X1's modal columns. step(kind): the step's largest
  !> component, largest(kind): the motions' (kind: model_t%error_kind). The three products,
  !> then one pass over the turned nodes that turns each node's values in registers and keeps
  !> the maxima, instead of three turned fields and the norm's own pass (at every step).
  subroutine frames_norm_terms(this, x1, xr, cf, delta, step, largest)
    class(frames_t), intent(in) :: this
    real(wp), intent(in), contiguous :: x1(:, :)
    real(wp), intent(in) :: xr(:), cf(:, :), delta(:)
    real(wp), intent(out) :: step(2), largest(2)
    real(wp) :: rot(2, 2, this%nr), s(2, 3, this%nr), psi(this%nr)
    real(wp) :: r11, r12, r21, r22, st, lg
    real(wp), allocatable :: y(:, :)
    integer :: j, t, ix, iy
    ! The unturned fields [0, xr, xr] + X1 cf (on the heap, as models may be large); BLAS's
    ! dgemm costs more than three dgemv at these sizes.
    allocate(y(size(xr), 3))
    y(:, 1) = 0.0_wp
    y(:, 2) = xr
    y(:, 3) = xr
    do t = 1, 3
      call gemv_add(size(x1, 1), size(x1, 2), x1, cf(:, t), y(:, t))
    end do
    call part_shifts(this, delta, y, rot, s, psi)
    step = 0.0_wp
    largest = -huge(1.0_wp)
    ! The turned pairs are nodes' x and y: translations, one kind.
    st = 0.0_wp
    lg = -huge(1.0_wp)
    do j = 1, this%nr
      r11 = rot(1, 1, j)
      r12 = rot(1, 2, j)
      r21 = rot(2, 1, j)
      r22 = rot(2, 2, j)
      do t = this%part_run(j), this%part_run(j + 1) - 1
        ix = this%turned_pairs(1, t)
        iy = this%turned_pairs(2, t)
        st = max(st, abs(r11 * y(ix, 1) + r12 * y(iy, 1) + s(1, 1, j)), &
          abs(r21 * y(ix, 1) + r22 * y(iy, 1) + s(2, 1, j)))
        lg = max(lg, abs(r11 * y(ix, 2) + r12 * y(iy, 2) + s(1, 2, j)), &
          abs(r21 * y(ix, 2) + r22 * y(iy, 2) + s(2, 2, j)), &
          abs(r11 * y(ix, 3) + r12 * y(iy, 3) + s(1, 3, j)), &
          abs(r21 * y(ix, 3) + r22 * y(iy, 3) + s(2, 3, j)))
      end do
    end do
    if (size(this%turned_pairs, 2) > 0) call note(this%error_kind(this%turned_pairs(1, 1)), &
      st, lg, lg, step, largest)
    do t = 1, size(this%still)
      ix = this%still(t)
      call note(this%error_kind(ix), y(ix, 1), y(ix, 2), y(ix, 3), step, largest)
    end do
  contains
    !> A coordinate of the error norm's kind with the step d and the motions a, b.
    pure subroutine note(kind, d, a, b, step, largest)
      integer, intent(in) :: kind
      real(wp), intent(in) :: d, a, b
      real(wp), intent(inout) :: step(2), largest(2)
      step(kind) = max(step(kind), abs(d))
      largest(kind) = max(largest(kind), abs(a), abs(b))
    end subroutine note
  end subroutine frames_norm_terms

  !> C, its Christoffel terms gam at the rates zd and the parts' translations s_j of W's
  !> columns, for the parts' rotations rot and series ser (part_series). With a = tau zd,
  !> b = G zd, the rates' derivatives A(:, i) = (d_i tau) zd and B(:, i) = (d_i G) zd (joint
  !> angles' through R, modal coordinates' through the series):
  !>     gam = C_dot zd - (zd^T d_i C zd / 2)_i,   zd^T d_i C zd / 2 = A_i . b + a . B_i + m a . A_i,
  !> so that nothing of size m^3 is formed.
  subroutine frame_terms(this, rot, zd, ser, c, gam, s)
    type(frames_t), intent(in) :: this
    real(wp), intent(in) :: rot(:, :, :), zd(:), ser(:, :, :, :)
    real(wp), intent(out) :: c(:, :), gam(:), s(:, :, :)
    ! Per part: s_dot (2, m), sz(:, i) = (d_i s) zd (2, m)
    real(wp) :: s_dot(2, this%m, this%nr), sz(2, this%m, this%nr)
    real(wp) :: tau(2, this%m), tau_dot(2, this%m), am(2, this%m), d(2, 2), ww(2), js(2)
    real(wp) :: rp(2, 2), rt(2, 2), psi_dot, psi_dot_p, va(2), vb(2), vc(2), vd(2), mj
    integer :: o, j, p, i, nr, m
    nr = this%nr
    m = this%m
    c = 0.0_wp
    gam = 0.0_wp
    do o = 1, nr
      j = this%order(o)
      p = this%parent(j)
      mj = this%mass(j)
      psi_dot = sum(zd(1:nr), mask=this%inside(:, j))
      rp = EYE
      psi_dot_p = 0.0_wp
      if (p > 0) then
        rp = rot(:, :, p)
        psi_dot_p = sum(zd(1:nr), mask=this%inside(:, p))
      end if
      d = rp - rot(:, :, j)
      associate (w => ser(:, :, 1, j), w_dot => ser(:, :, 2, j), wz => ser(:, :, 3, j), &
        g => ser(:, :, 4, j), g_dot => ser(:, :, 5, j), gz => ser(:, :, 6, j))
        ww = times_vector(w, zd)
        ! d (R_p - R_j) / dt = psi_dot_p J R_p - psi_dot J R_j
        s(:, :, j) = times(d, w)
        s_dot(:, :, j) = times(d, w_dot) + perp_cols(times(psi_dot_p * rp - psi_dot * &
          rot(:, :, j), w))
        sz(:, nr + 1:, j) = times(d, wz(:, nr + 1:))
        do i = 1, nr
          sz(:, i, j) = 0.0_wp
          if (p > 0) then
            if (this%inside(i, p)) sz(:, i, j) = perp(matmul(rp, ww))
          end if
          if (this%inside(i, j)) sz(:, i, j) = sz(:, i, j) - perp(matmul(rot(:, :, &
            j), ww))
        end do
        if (p > 0) then
          s(:, :, j) = s(:, :, j) + s(:, :, p)
          s_dot(:, :, j) = s_dot(:, :, j) + s_dot(:, :, p)
          sz(:, :, j) = sz(:, :, j) + sz(:, :, p)
        end if
        ! tau = R^T s; d_i R^T = -R^T J where delta_i turns the part
        rt = transpose(rot(:, :, j))
        tau = times(rt, s(:, :, j))
        tau_dot = times(rt, s_dot(:, :, j) - psi_dot * perp_cols(s(:, :, j)))
        am = times(rt, sz(:, :, j))
        js = matmul(rt, perp(times_vector(s(:, :, j), zd)))
        do i = 1, nr
          if (this%inside(i, j)) am(:, i) = am(:, i) - js
        end do
        va = times_vector(tau, zd)
        vb = times_vector(g, zd)
        vc = times_vector(tau_dot, zd)
        vd = times_vector(g_dot, zd)
        do i = 1, m
          c(:, i) = c(:, i) + tau(1, :) * (g(1, i) + mj * tau(1, i)) + tau(2, :) * (g(2, i) + &
            mj * tau(2, i)) + g(1, :) * tau(1, i) + g(2, :) * tau(2, i)
          gam(i) = gam(i) + tau_dot(1, i) * (vb(1) + mj * va(1)) + tau_dot(2, i) * (vb(2) + &
            mj * va(2)) + g(1, i) * vc(1) + g(2, i) * vc(2) + tau(1, i) * (vd(1) + mj * vc(1)) &
            + tau(2, i) * (vd(2) + mj * vc(2)) + g_dot(1, i) * va(1) + g_dot(2, i) * va(2) - &
            am(1, i) * (vb(1) + mj * va(1)) - am(2, i) * (vb(2) + mj * va(2)) - &
            va(1) * gz(1, i) - va(2) * gz(2, i)
        end do
      end associate
    end do
  end subroutine frame_terms

  !> frame_terms' gam at delta = 0: there every R is the identity, s and tau vanish, and of
  !> gam only tau_dot . b + G . (tau_dot zd) - A . b remain, with tau_dot = s_dot and A the
  !> joint angles' rows of (d_i s) zd.
  function unturned_christoffel(this, zd, ser) result(gam)
    type(frames_t), intent(in) :: this
    real(wp), intent(in) :: zd(:), ser(:, :, :, :)
    real(wp) :: gam(this%m)
    real(wp) :: s_dot(2, this%m, this%nr), sz(2, this%nr, this%nr), ww(2), vb(2), vc(2)
    real(wp) :: psi_dot, psi_dot_p
    integer :: o, j, p, i, nr
    nr = this%nr
    gam = 0.0_wp
    do o = 1, nr
      j = this%order(o)
      p = this%parent(j)
      psi_dot = sum(zd(1:nr), mask=this%inside(:, j))
      psi_dot_p = 0.0_wp
      if (p > 0) psi_dot_p = sum(zd(1:nr), mask=this%inside(:, p))
      associate (w => ser(:, :, 1, j), g => ser(:, :, 4, j))
        ww = times_vector(w, zd)
        s_dot(:, :, j) = (psi_dot_p - psi_dot) * perp_cols(w)
        do i = 1, nr
          sz(:, i, j) = 0.0_wp
          if (p > 0) then
            if (this%inside(i, p)) sz(:, i, j) = perp(ww)
          end if
          if (this%inside(i, j)) sz(:, i, j) = sz(:, i, j) - perp(ww)
        end do
        if (p > 0) then
          s_dot(:, :, j) = s_dot(:, :, j) + s_dot(:, :, p)
          sz(:, :, j) = sz(:, :, j) + sz(:, :, p)
        end if
        vb = times_vector(g, zd)
        vc = times_vector(s_dot(:, :, j), zd)
        do i = 1, this%m
          gam(i) = gam(i) + s_dot(1, i, j) * vb(1) + s_dot(2, i, j) * vb(2) + g(1, i) * vc(1) + &
            g(2, i) * vc(2)
        end do
        do i = 1, nr
          gam(i) = gam(i) - sz(1, i, j) * vb(1) - sz(2, i, j) * vb(2)
        end do
      end associate
    end do
  end function unturned_christoffel

  !> Part j's (2, m) series v0 + v1 dz + v2 [dz, dz] / 2 of W's columns at dz (vr(:, :, at + 1,
  !> j)), its rate along zd (at + 2) and (d_l v) zd (vr(:, l, at + 3, j)), along the modal
  !> directions l > nr only (the series is at the joints' angles p0: along them, v does not
  !> change).
  pure subroutine series_rates(m, nr, j, at, v0, v1, v2, dz, zd, vr)
    integer, intent(in) :: m, nr, j, at
    ! The (2, m) columns flat (sequence association): the modal directions' columns are one
    ! contiguous run of 2 m (m - nr) numbers, and the dz contraction runs over all at once.
    real(wp), intent(in) :: v0(2 * m, nr), v1(2 * m * m, nr), v2(2 * m * m, m, nr), dz(m), &
      zd(m)
    real(wp), intent(inout) :: vr(2 * m, 6, nr)
    real(wp) :: dv(2 * m * m), v(2 * m), v_dot(2 * m)
    integer :: l, r, a, lo, hi, c
    lo = 2 * m * nr + 1
    hi = 2 * m * m
    dv(lo:hi) = v1(lo:hi, j)
    do r = nr + 1, m
      dv(lo:hi) = dv(lo:hi) + dz(r) * v2(lo:hi, r, j)
    end do
    v = v0(:, j)
    v_dot = 0.0_wp
    vr(:, at + 3, j) = 0.0_wp
    do l = nr + 1, m
      c = 2 * m * (l - 1)
      v = v + (0.5_wp * dz(l)) * (v1(c + 1:c + 2 * m, j) + dv(c + 1:c + 2 * m))
      v_dot = v_dot + zd(l) * dv(c + 1:c + 2 * m)
      do a = 1, m
        vr(2 * l - 1, at + 3, j) = vr(2 * l - 1, at + 3, j) + dv(c + 2 * a - 1) * zd(a)
        vr(2 * l, at + 3, j) = vr(2 * l, at + 3, j) + dv(c + 2 * a) * zd(a)
      end do
    end do
    vr(:, at + 1, j) = v
    vr(:, at + 2, j) = v_dot
  end subroutine series_rates

  !> r v for a 2 x 2 r and a (2, n) v.
  pure function times(r, v) result(rv)
    real(wp), intent(in) :: r(2, 2), v(:, :)
    real(wp) :: rv(2, size(v, 2))
    rv(1, :) = r(1, 1) * v(1, :) + r(1, 2) * v(2, :)
    rv(2, :) = r(2, 1) * v(1, :) + r(2, 2) * v(2, :)
  end function times

  !> v z for a (2, n) v.
  pure function times_vector(v, z) result(vz)
    real(wp), intent(in) :: v(:, :), z(:)
    real(wp) :: vz(2)
    vz(1) = dot_product(v(1, :), z)
    vz(2) = dot_product(v(2, :), z)
  end function times_vector

  !> J v, column by column.
  pure function perp_cols(v) result(jv)
    real(wp), intent(in) :: v(:, :)
    real(wp) :: jv(2, size(v, 2))
    jv(1, :) = -v(2, :)
    jv(2, :) = v(1, :)
  end function perp_cols

  pure function perp(v) result(jv)
    real(wp), intent(in) :: v(2)
    real(wp) :: jv(2)
    jv = [-v(2), v(1)]
  end function perp
end module reduction_frames
