!> Newton-Krylov statics for large models (docs/theory.md 7.3): the Newton system
!> K_T dq = g(q) is solved by GMRES without forming K_T, each product K_T v a central
!> difference of the generalised force along v (two evaluations, O(n) each on the sparse
!> path), right-preconditioned by the structural stiffness K0 = DF_dy^T K_x DF_dy, which the
!> augmented sparse system factors in O(n) (dynamics_augmented, the implicit integrators' form
!> with the mass left out). K_T - K0 is the geometric and load stiffness, so GMRES needs as many
!> iterations as K0^-1 K_T has distinct eigenvalue clusters, not n: O(n) per Newton iteration
!> where the dense difference tangent costs 2 n_dy evaluations and an O(n^3) factorisation.
!>
!> Where K0 is singular (a released mode that only the loads stiffen: a pendulum under
!> gravity) the preconditioner is K0 + s M, with s = 1e-8 tr(K_x) / tr(M) over the free
!> coordinates: far below the stiffness of every elastic mode, it only makes P invertible.
!>
!> Stability of a converged equilibrium (K_T positive definite on the dynamic coordinates,
!> as the dense path decides it): with P symmetric positive definite, K_T is so exactly when
!> every eigenvalue of P^-1 K_T is positive (Sylvester), and those are found by Arnoldi (ARPACK
!> dnaupd, smallest real part) on the same products and solves.
module dynamics_static_krylov
  use core_kinds, only: wp
  use core_strings, only: real_str
  use core_error, only: error_t, ERR_NUMERIC
  use core_gmres, only: gmres_step, gmres_correct
  use dynamics_system, only: dynamics_t
  implicit none
  private
  public :: krylov_statics_t, krylov_tangent_unsupported, difference_step

  !> GMRES stops at this residual relative to |g|: Newton then contracts by about this much
  !> per iteration, far below the 0.25 at which static_solve would call convergence slow.
  real(wp), parameter :: GMRES_TOL = 1.0e-6_wp
  integer, parameter :: RESTART = 60, MAX_PRODUCTS = 600

  type :: krylov_statics_t
    real(wp) :: h = 0.0_wp                    !< difference step along a unit (max-norm) v
    real(wp) :: shift = 0.0_wp                !< s of K0 + s M (0: K0 alone)
    !> Products extrapolated from steps h and 2h (Richardson, error O(h^4), 4 evaluations):
    !> for compliances, where the stiff terms' O(h^2) error would show in a soft direction
    !> (dynamics_static's tangent_stiffness `accurate`).
    logical :: extrapolate = .false.
    !> GMRES's relative residual (GMRES_TOL for Newton; compliances ask for more)
    real(wp) :: tol = GMRES_TOL
    integer :: n_products = 0, n_factors = 0
  contains
    procedure :: equilibrium => kry_equilibrium
    procedure :: precondition => kry_precondition
    procedure :: solve => kry_solve
    procedure :: product => kry_product
    procedure :: load_product => kry_load_product
    procedure :: apply_p => kry_apply_p
    procedure :: stable => kry_stable
  end type krylov_statics_t

  interface
    !> Whether the equilibrium q_dy is stable: no real eigenvalue of P^-1 K_T below
    !> -STABLE_MARGIN (complex pairs, from moments fixed in space, are not taken as unstable,
    !> as in dynamics_static's stable_tangent). P is factored afresh at q_dy. Not `decided`
    !> when the Arnoldi iteration does not converge. dynamics_static_krylov_stability.
    module subroutine kry_stable(this, dyn, t, q_dy, stable, decided, err)
      class(krylov_statics_t), intent(inout) :: this
      type(dynamics_t), intent(inout) :: dyn
      real(wp), intent(in) :: t, q_dy(:)
      logical, intent(out) :: stable, decided
      type(error_t), intent(out) :: err
    end subroutine kry_stable
  end interface

contains

  !> The step of the tangents' central differences in q_dy: 6e-6 of the model's size (at least
  !> 1 mm), the same for every coordinate and path so that dense and Krylov tangents agree.
  pure real(wp) function difference_step(dyn) result(h)
    type(dynamics_t), intent(in) :: dyn
    h = 6.0e-6_wp * max(1.0e-3_wp, maxval(abs(dyn%model%x0)))
  end function difference_step

  !> Why the Krylov eigenproblems (buckling, modes) cannot reproduce this model's dense
  !> tangent, '' when they can: they need the sparse factors of K0 and its stresses linear in
  !> q (no elastic modes), and the tangent of a moment fixed in space is not symmetric (the
  !> dense paths solve its full, unsymmetric problem).
  function krylov_tangent_unsupported(dyn, elastic_ok) result(why_not)
    type(dynamics_t), intent(in) :: dyn
    !> The caller differences the whole force (products of K_T, not K_L beside an exact K0)
    logical, intent(in), optional :: elastic_ok
    character(len=:), allocatable :: why_not
    logical :: elastic_refused
    elastic_refused = .true.
    if (present(elastic_ok)) elastic_refused = .not. elastic_ok
    why_not = ''
    if (.not. dyn%sparse) then
      why_not = 'the model is on the dense path (&scene linear_solver)'
    else if (dyn%model%n_elastic > 0 .and. elastic_refused) then
      why_not = 'the model has elastic (calculable) modes'
    else if (size(dyn%model%moment_lambda) > 0) then
      why_not = 'the model has moments fixed in space'
    end if
  end function krylov_tangent_unsupported

  !> Newton from q_dy to the equilibrium g(q_dy) = 0 at the model's current load factor, with
  !> the preconditioner factored once at the start; converged when a correction is at most
  !> tol_abs. Leaves the kinematics at the equilibrium.
  subroutine kry_equilibrium(this, dyn, t, q_dy, tol_abs, max_iter, iterations, err)
    class(krylov_statics_t), intent(inout) :: this
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: t, tol_abs
    real(wp), intent(inout) :: q_dy(:)
    integer, intent(in) :: max_iter
    integer, intent(inout) :: iterations
    type(error_t), intent(out) :: err
    real(wp) :: g(size(q_dy)), dq(size(q_dy))
    integer :: it
    character(len=200) :: msg
    call this%precondition(dyn, t, q_dy, err)
    if (.not. err%ok()) return
    g = dyn%gen_force
    do it = 1, max_iter
      call this%solve(dyn, t, q_dy, g, dq, err)
      if (.not. err%ok()) return
      q_dy = q_dy + dq
      iterations = iterations + 1
      call dyn%generalised_force(t, q_dy, 0.0_wp * q_dy, g, err)
      if (.not. err%ok()) return
      if (maxval(abs(dq)) <= tol_abs) return
    end do
    write(msg, '(a,i0,a,a,a,es9.3)') 'static analysis (krylov): Newton did not converge in ', &
      max_iter, ' iterations at load factor ', real_str(dyn%load_factor), ', last correction ', &
      maxval(abs(dq))
    call err%set(ERR_NUMERIC, trim(msg))
  end subroutine kry_equilibrium

  !> Factor the preconditioner at q_dy (the model locked, as statics has it). Leaves the
  !> generalised force there in dyn%gen_force.
  subroutine kry_precondition(this, dyn, t, q_dy, err)
    class(krylov_statics_t), intent(inout) :: this
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: t, q_dy(:)
    type(error_t), intent(out) :: err
    real(wp) :: g(size(q_dy)), traces(2)
    integer :: info
    call dyn%generalised_force(t, q_dy, 0.0_wp * q_dy, g, err)
    if (.not. err%ok()) return
    this%h = difference_step(dyn)
    dyn%aug%de_val = dyn%kin%de_val
    this%shift = 0.0_wp
    call dyn%aug%factor_newton(dyn%model, dyn%mass, 1.0_wp, 0.0_wp, info, &
      mass_scale=0.0_wp, traces=traces)
    if (info /= 0 .and. traces(2) > 0) then
      this%shift = 1.0e-8_wp * traces(1) / traces(2)
      call dyn%aug%factor_newton(dyn%model, dyn%mass, 1.0_wp, 0.0_wp, info, &
        mass_scale=this%shift)
    end if
    this%n_factors = this%n_factors + 1
    if (info /= 0) call err%set(ERR_NUMERIC, 'static analysis (krylov): the structural ' // &
      'stiffness is singular and nothing has mass to regularise it (a mechanism?); ' // &
      'try &static solver = ''dense''')
  end subroutine kry_precondition

  !> z = P^-1 r with the factors of the last precondition. Where P = K0 is the dynamic modes'
  !> stiffness alone (no elastic modes, no shift), K0 z is exact and cheap (dyn%stresses), and
  !> one step of iterative refinement takes the augmented system's round-off out of z: its
  !> saddle-point form (element stiffnesses EA/l beside constraint rows of order 1) is far worse
  !> conditioned than K0, and buckling and stability read small eigenvalues through it.
  subroutine kry_apply_p(this, dyn, r, z)
    class(krylov_statics_t), intent(in) :: this
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: r(:)
    real(wp), intent(out) :: z(:)
    real(wp) :: z2(size(z), 1), q_full(dyn%model%n_q)
    integer :: pass
    z = 0.0_wp
    z2(:, 1) = r
    q_full = 0.0_wp
    do pass = 1, merge(2, 1, dyn%model%n_elastic == 0 .and. this%shift == 0)
      call dyn%aug%accelerations(dyn%model, dyn%aug%nodal_equivalent(dyn%model, z2), z2, &
        newton=.true.)
      z = z + z2(:, 1)
      q_full(dyn%model%n_rh + 1:) = z
      z2(:, 1) = r - dyn%stresses(q_full, 0.0_wp * q_full)
    end do
  end subroutine kry_apply_p

  !> K_T v = -dg/dq v by central differences of g along v / |v|_1, step h (docs/theory.md
  !> 7.3: the 1-norm bounds the turn of a whole chain, which the truncation error grows with).
  subroutine kry_product(this, dyn, t, q_dy, v, kv, err)
    class(krylov_statics_t), intent(inout) :: this
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: t, q_dy(:), v(:)
    real(wp), intent(out) :: kv(:)
    type(error_t), intent(out) :: err
    call difference_along(this, dyn, t, q_dy, v, .false., kv, err)
  end subroutine kry_product

  !> K_L v = (K_T - S_dd) v, the tangent without the dynamic modes' own (linear) stiffness:
  !> central differences of the load part DF_dy^T f = g + sigma_dy alone, as the dense
  !> tangent differences it. Where K0 = S_dd (no elastic modes), P^-1 K_T = I + P^-1 K_L: the
  !> eigenvalue problems take that form, since P^-1 (K0 v + K_L v) would lose the small
  !> K_L v against K0 v to the solve's round-off, eps cond(K0) |v|.
  subroutine kry_load_product(this, dyn, t, q_dy, v, kv, err)
    class(krylov_statics_t), intent(inout) :: this
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: t, q_dy(:), v(:)
    real(wp), intent(out) :: kv(:)
    type(error_t), intent(out) :: err
    call difference_along(this, dyn, t, q_dy, v, .true., kv, err)
  end subroutine kry_load_product

  !> -(f(q + s v) - f(q - s v)) / (2 s), s = h / |v|_1, of f = g, or of its load part.
  subroutine difference_along(this, dyn, t, q_dy, v, load_only, kv, err)
    type(krylov_statics_t), intent(inout) :: this
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: t, q_dy(:), v(:)
    logical, intent(in) :: load_only
    real(wp), intent(out) :: kv(:)
    type(error_t), intent(out) :: err
    real(wp) :: vsum, fp(size(q_dy)), fm(size(q_dy)), kv2(size(q_dy))
    vsum = sum(abs(v))
    kv = 0.0_wp
    if (vsum == 0) return
    call difference(this%h, kv)
    if (err%ok() .and. this%extrapolate) then
      call difference(2 * this%h, kv2)
      kv = (4 * kv - kv2) / 3
    end if
    if (err%ok()) this%n_products = this%n_products + 1
  contains
    subroutine difference(h, d)
      real(wp), intent(in) :: h
      real(wp), intent(out) :: d(:)
      d = 0.0_wp
      call force_at(q_dy + (h / vsum) * v, fp)
      if (.not. err%ok()) return
      call force_at(q_dy - (h / vsum) * v, fm)
      if (.not. err%ok()) return
      d = -(fp - fm) * (vsum / (2 * h))
    end subroutine difference

    subroutine force_at(q, f)
      real(wp), intent(in) :: q(:)
      real(wp), intent(out) :: f(:)
      real(wp) :: q_full(dyn%model%n_q)
      call dyn%generalised_force(t, q, 0.0_wp * q, f, err)
      if (.not. (err%ok() .and. load_only)) return
      q_full = dyn%full_q(t, q)
      f = f + dyn%stresses(q_full, 0.0_wp * q_full)
    end subroutine force_at
  end subroutine difference_along

  !> dq with K_T dq = g at q_dy, by restarted GMRES right-preconditioned with P (the factors of
  !> the last precondition): K_T P^-1 u = g, dq = P^-1 u. Relative residual this%tol.
  subroutine kry_solve(this, dyn, t, q_dy, g, dq, err)
    class(krylov_statics_t), intent(inout) :: this
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: t, q_dy(:), g(:)
    real(wp), intent(out) :: dq(:)
    type(error_t), intent(out) :: err
    real(wp) :: v(size(g), RESTART + 1), hm(RESTART + 1, RESTART), cs(RESTART), sn(RESTART)
    real(wp) :: s(RESTART + 1), w(size(g)), z(size(g)), u(size(g))
    real(wp) :: beta, g_norm, r(size(g))
    integer :: j, n_done
    character(len=160) :: msg
    u = 0.0_wp
    dq = 0.0_wp
    g_norm = norm2(g)
    if (g_norm == 0) return
    r = g
    n_done = 0
    do
      beta = norm2(r)
      if (beta <= this%tol * g_norm) exit
      if (n_done >= MAX_PRODUCTS) then
        write(msg, '(a,i0,a,es9.2,a)') 'static analysis (krylov): GMRES did not converge in ', &
          MAX_PRODUCTS, ' products (residual ', beta / g_norm, ' of the force; a critical ' // &
          'load?); try &static solver = ''dense'''
        call err%set(ERR_NUMERIC, trim(msg))
        return
      end if
      v(:, 1) = r / beta
      s = 0.0_wp
      s(1) = beta
      do j = 1, RESTART
        call this%apply_p(dyn, v(:, j), z)
        call this%product(dyn, t, q_dy, z, w, err)
        if (.not. err%ok()) return
        n_done = n_done + 1
        call gmres_step(j, w, v, hm, cs, sn, s)
        if (abs(s(j + 1)) <= this%tol * g_norm .or. n_done >= MAX_PRODUCTS .or. &
            j == RESTART) exit
      end do
      call gmres_correct(j, v, hm, s, u)
      ! The true residual (not the recurrence's): one more product, and a check on the noise.
      call this%apply_p(dyn, u, dq)
      call this%product(dyn, t, q_dy, dq, w, err)
      if (.not. err%ok()) return
      r = g - w
      if (abs(s(j + 1)) <= this%tol * g_norm) exit
    end do
    call this%apply_p(dyn, u, dq)
  end subroutine kry_solve
end module dynamics_static_krylov
