!> The lowest modes of a large model without dense matrices (docs/theory.md 8.1):
!>   K0 v = omega^2 Mbar v on the dynamic coordinates, prescribed modes locked,
!> by shift-invert Lanczos (reduction_lanczos) with OP = (K0 - sigma Mbar)^-1 Mbar applied in
!> the augmented sparse form of dynamics_augmented: y = (K0 - sigma Mbar)^-1 DF_dy^T f is the
!> solution of
!>     [ K_x - sigma M   J_k^T ] [ y_x ]   [ f ]
!>     [ J_k             0     ] [ mu  ] = [ 0 ],     y = J_d y_x,
!> with K_x = D_x^T S D_x over the dynamic modes (the iteration matrix of the implicit
!> integrators with mass_scale = -sigma), and Mbar x = DF_dy^T M DF_dy x by one solve, an
!> element pass and one transposed solve. Each Lanczos step is O(n): the dense path forms DF
!> (n_x x n_q) and Mbar by O(n^3) work and O(n^2) memory.
!>
!> With loads the tangent is K_T = K0 + K_L, K_L the loads' (geometric) stiffness, and
!> (K_T - sigma Mbar) y = b is solved as (I + P^-1 K_L) y = P^-1 b, P = K0 - sigma Mbar, by
!> GMRES on products K_L z differenced along z (dynamics_static_krylov's load_product, two
!> evaluations each), as the dense path differences K_T. With elastic (calculable) modes,
!> whose stiffness is in P but comes from the configuration, the whole K_T z is differenced
!> (extrapolated, as the dense tangent of such models is) and GMRES solves
!> P^-1 (K_T - sigma Mbar) y = P^-1 b. Not for moments fixed in space (an unsymmetric
!> tangent: the dense path's full problem) or modes along a motion.
module reduction_krylov
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_NUMERIC
  use reduction_lanczos, only: lanczos_t, LZ_OP, LZ_OP_BX, LZ_B
  use reduction_eigen, only: sort_modes
  use core_gmres, only: gmres_step, gmres_correct
  use dynamics_system, only: dynamics_t
  use dynamics_static, only: has_loads
  use dynamics_static_krylov, only: krylov_statics_t, krylov_tangent_unsupported, &
    difference_step
  implicit none
  private
  public :: krylov_modes, krylov_modes_applies, mbar_times, k0_factor, k0_solve

  !> sigma = -SHIFT_FACTOR tr(K_x) / tr(M) over the free nodal coordinates: far below the
  !> elastic eigenvalues (their nu = 1 / (lambda - sigma) stay well apart), yet it keeps
  !> K0 - sigma Mbar regular where K0 is singular (modes without stiffness), as the dense
  !> ARPACK path's first shift does.
  real(wp), parameter :: SHIFT_FACTOR = 1.0e-8_wp
  !> GMRES for the loaded operator: a cycle runs until its recurrence's residual is GMRES_TOL
  !> of P^-1 b; the true residual, from one more product, then carries the products'
  !> difference noise (1e-9 to 2e-8 relative, measured on a 40-beam arm under gravity and a
  !> tip pull), so below NOISE_TOL it is taken as converged. RESTART and MAX_PRODUCTS bound
  !> the work (a load near a critical one makes I + P^-1 K_L nearly singular: refused).
  real(wp), parameter :: GMRES_TOL = 1.0e-10_wp, NOISE_TOL = 1.0e-7_wp
  integer, parameter :: RESTART = 40, MAX_PRODUCTS = 400

  !> The shifted operator: its factors are dyn's iteration matrix; with loads also the state
  !> the load products difference about (they move the kinematics, which is solved there
  !> again after them).
  type :: shifted_t
    logical :: loaded = .false.
    logical :: elastic = .false.     !< whole products of K_T (elastic modes), see above
    real(wp) :: sigma = 0.0_wp
    type(krylov_statics_t) :: kry
    real(wp) :: t = 0.0_wp
    real(wp), allocatable :: q_dy(:)
  end type shifted_t

contains

  !> '' when the Krylov path gives this model's tangent as the dense path has it, else why
  !> not.
  function krylov_modes_applies(dyn, along_motion) result(why_not)
    type(dynamics_t), intent(in) :: dyn
    logical, intent(in) :: along_motion
    character(len=:), allocatable :: why_not
    why_not = krylov_tangent_unsupported(dyn, elastic_ok=.true.)
    if (why_not == '' .and. along_motion) why_not = 'modes along a motion need the dense tangent'
  end function krylov_modes_applies

  !> The nev lowest modes at (t, q_dy) with the prescribed modes locked: omega^2 ascending,
  !> shapes Mbar-normalised with their largest component positive, node_shapes = DF_dy v.
  !> Leaves the kinematics solved at the state.
  subroutine krylov_modes(dyn, t, q_dy, nev, lambda, v, node_shapes, err)
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: t, q_dy(:)
    integer, intent(in) :: nev
    real(wp), allocatable, intent(out) :: lambda(:), v(:, :), node_shapes(:, :)
    type(error_t), intent(out) :: err
    type(lanczos_t) :: lz
    type(shifted_t) :: op
    real(wp) :: g(size(q_dy)), traces(2), sigma, y(size(q_dy), 1), x(size(q_dy))
    real(wp), allocatable :: mv(:, :), kv(:)
    integer :: n, info, request, j
    logical :: was_locked
    n = size(q_dy)
    was_locked = dyn%locked
    dyn%locked = .true.
    op%elastic = dyn%model%n_elastic > 0
    op%loaded = has_loads(dyn) .or. op%elastic
    op%t = t
    op%q_dy = q_dy
    op%kry%h = difference_step(dyn)
    op%kry%extrapolate = op%elastic
    call dyn%generalised_force(t, q_dy, 0.0_wp * q_dy, g, err)
    if (.not. err%ok()) then
      dyn%locked = was_locked
      return
    end if
    dyn%aug%de_val = dyn%kin%de_val
    call dyn%aug%factor_newton(dyn%model, dyn%mass, 1.0_wp, 0.0_wp, info, mass_scale=0.0_wp, &
      traces=traces)
    if (.not. traces(2) > 0) then
      call err%set(ERR_NUMERIC, "eigensolver 'krylov': no free coordinate has mass")
      dyn%locked = was_locked
      return
    end if
    sigma = -SHIFT_FACTOR * traces(1) / traces(2)
    op%sigma = sigma
    call dyn%aug%factor_newton(dyn%model, dyn%mass, 1.0_wp, 0.0_wp, info, mass_scale=-sigma)
    if (info /= 0) then
      call err%set(ERR_NUMERIC, "eigensolver 'krylov': K0 - sigma Mbar is singular (a " // &
        'dynamic coordinate without mass?)')
      dyn%locked = was_locked
      return
    end if
    call lz%start(n, nev, sigma, 'krylov')
    do
      call lz%next(request)
      select case (request)
      case (LZ_OP)
        x = lz%input()
        call shifted_apply(op, dyn, nodal_mass(dyn, reshape(x, [n, 1])), y(:, 1), err)
      case (LZ_OP_BX)
        x = lz%input()
        call shifted_apply(op, dyn, dyn%aug%nodal_equivalent(dyn%model, reshape(x, [n, 1])), &
          y(:, 1), err)
      case (LZ_B)
        y = mbar_times(dyn, reshape(lz%input(), [n, 1]))
      case default
        exit
      end select
      if (.not. err%ok()) exit
      call lz%output(y(:, 1))
    end do
    if (err%ok()) call lz%finish(lambda, v, err)
    if (.not. err%ok()) then
      dyn%locked = was_locked
      return
    end if
    ! Normalised again and the eigenvalues as Rayleigh quotients: sigma + 1 / nu cancels,
    ! and K0 v is exact (the dynamic modes' stresses are linear in q).
    mv = mbar_times(dyn, v)
    allocate(kv(n))
    do j = 1, nev
      v(:, j) = v(:, j) / sqrt(dot_product(v(:, j), mv(:, j)))
      if (op%elastic) then
        kv = tangent_times(op, dyn, v(:, j), err)
      else
        kv = stiffness_times(dyn, v(:, j))
        if (op%loaded) kv = kv + load_times(op, dyn, v(:, j), err)
      end if
      lambda(j) = dot_product(v(:, j), kv)
      if (v(maxloc(abs(v(:, j)), 1), j) < 0) v(:, j) = -v(:, j)
    end do
    call sort_modes(lambda, v)
    if (op%loaded .and. err%ok()) call dyn%generalised_force(t, q_dy, 0.0_wp * q_dy, g, err)
    dyn%locked = was_locked
    if (.not. err%ok()) return
    allocate(node_shapes(dyn%model%n_x, nev))
    call dyn%kin%apply_df_many(dyn%model, full_columns(dyn, v), node_shapes)
  end subroutine krylov_modes

  !> Mbar w = DF_dy^T M DF_dy w for columns w (n_dy, k) at the kinematics' current state,
  !> with the element masses of the last evaluation.
  function mbar_times(dyn, w) result(mw)
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: w(:, :)
    real(wp) :: mw(size(w, 1), size(w, 2))
    real(wp) :: f(dyn%model%n_x, size(w, 2)), g_q(dyn%model%n_q)
    integer :: j
    f = nodal_mass(dyn, w)
    do j = 1, size(w, 2)
      call dyn%kin%apply_dft(dyn%model, f(:, j), g_q)
      mw(:, j) = g_q(dyn%model%n_rh + 1:)
    end do
  end function mbar_times

  !> Nodal forces M DF_dy w.
  function nodal_mass(dyn, w) result(f)
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: w(:, :)
    real(wp) :: f(dyn%model%n_x, size(w, 2))
    real(wp) :: dx(dyn%model%n_x, size(w, 2))
    call dyn%kin%apply_df_many(dyn%model, full_columns(dyn, w), dx)
    f = dyn%mass%times(dyn%model, dx)
  end function nodal_mass

  !> y = (K_T - sigma Mbar)^-1 DF_dy^T f: the shifted factors, and with loads GMRES on
  !> (I + P^-1 K_L) y = P^-1 DF_dy^T f; the kinematics is solved at the state again after.
  subroutine shifted_apply(op, dyn, f, y, err)
    type(shifted_t), intent(inout) :: op
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: f(:, :)
    real(wp), intent(out) :: y(:)
    type(error_t), intent(inout) :: err
    real(wp) :: y0(size(y), 1), g(size(y))
    call shifted_solve(dyn, f, y0)
    if (.not. op%loaded) then
      y = y0(:, 1)
      return
    end if
    call loaded_gmres(op, dyn, y0(:, 1), y, err)
    if (err%ok()) call dyn%generalised_force(op%t, op%q_dy, 0.0_wp * op%q_dy, g, err)
  end subroutine shifted_apply

  !> K_L z by differences (moves the kinematics off the state).
  function load_times(op, dyn, z, err) result(kz)
    type(shifted_t), intent(inout) :: op
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: z(:)
    type(error_t), intent(inout) :: err
    real(wp) :: kz(size(z))
    kz = 0.0_wp
    if (.not. err%ok()) return
    call op%kry%load_product(dyn, op%t, op%q_dy, z, kz, err)
  end function load_times

  !> K_T z by differences of the whole force, and the kinematics solved at the state again.
  function tangent_times(op, dyn, z, err) result(kz)
    type(shifted_t), intent(inout) :: op
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: z(:)
    type(error_t), intent(inout) :: err
    real(wp) :: kz(size(z)), g(size(z))
    kz = 0.0_wp
    if (.not. err%ok()) return
    call op%kry%product(dyn, op%t, op%q_dy, z, kz, err)
    if (err%ok()) call dyn%generalised_force(op%t, op%q_dy, 0.0_wp * op%q_dy, g, err)
  end function tangent_times

  !> y with (I + P^-1 K_L) y = b, or with elastic modes P^-1 (K_T - sigma Mbar) y = b, by
  !> restarted GMRES (modified Gram-Schmidt, twice: the products carry difference noise).
  subroutine loaded_gmres(op, dyn, b, y, err)
    type(shifted_t), intent(inout) :: op
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: b(:)
    real(wp), intent(out) :: y(:)
    type(error_t), intent(inout) :: err
    real(wp) :: v(size(b), RESTART + 1), hm(RESTART + 1, RESTART), cs(RESTART), sn(RESTART)
    real(wp) :: s(RESTART + 1), w(size(b), 1), r(size(b)), b_norm, beta
    integer :: j, done
    y = 0.0_wp
    b_norm = norm2(b)
    if (b_norm == 0) return
    r = b
    done = 0
    do
      beta = norm2(r)
      if (beta <= GMRES_TOL * b_norm .or. (done > 0 .and. beta <= NOISE_TOL * b_norm)) return
      if (done >= MAX_PRODUCTS) then
        call err%set(ERR_NUMERIC, "eigensolver 'krylov': the loaded operator's GMRES did " // &
          'not converge (a load near a critical one?); try the dense path (lapack)')
        return
      end if
      v(:, 1) = r / beta
      s = 0.0_wp
      s(1) = beta
      do j = 1, RESTART
        call apply_loaded(v(:, j), w(:, 1))
        if (.not. err%ok()) return
        done = done + 1
        call gmres_step(j, w(:, 1), v, hm, cs, sn, s)
        if (abs(s(j + 1)) <= GMRES_TOL * b_norm .or. done >= MAX_PRODUCTS) exit
      end do
      call gmres_correct(min(j, RESTART), v, hm, s, y)
      ! The true residual, not the recurrence's: the noise must not fake convergence.
      call apply_loaded(y, w(:, 1))
      if (.not. err%ok()) return
      r = b - w(:, 1)
    end do
  contains
    !> w = z + P^-1 K_L z, or P^-1 (K_T - sigma Mbar) z
    subroutine apply_loaded(z, w)
      real(wp), intent(in) :: z(:)
      real(wp), intent(out) :: w(:)
      real(wp) :: pz(size(z), 1), kz(size(z), 1)
      if (op%elastic) then
        kz(:, 1) = tangent_times(op, dyn, z, err)
        kz = kz - op%sigma * mbar_times(dyn, reshape(z, [size(z), 1]))
        call shifted_solve(dyn, dyn%aug%nodal_equivalent(dyn%model, kz), pz)
        w = pz(:, 1)
        return
      end if
      call shifted_solve(dyn, dyn%aug%nodal_equivalent(dyn%model, &
        reshape(load_times(op, dyn, z, err), [size(z), 1])), pz)
      w = z + pz(:, 1)
    end subroutine apply_loaded
  end subroutine loaded_gmres

  !> y = (K0 - sigma Mbar)^-1 DF_dy^T f with the shifted factors.
  subroutine shifted_solve(dyn, f, y)
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: f(:, :)
    real(wp), intent(out) :: y(:, :)
    call dyn%aug%accelerations(dyn%model, f, y, newton=.true.)
  end subroutine shifted_solve

  !> K0 v: the dynamic modes' stresses at q_dy = v (linear, no reference stress).
  function stiffness_times(dyn, v) result(kv)
    type(dynamics_t), intent(in) :: dyn
    real(wp), intent(in) :: v(:)
    real(wp) :: kv(size(v)), q(dyn%model%n_q)
    q = 0.0_wp
    q(dyn%model%n_rh + 1:) = v
    kv = dyn%stresses(q, 0.0_wp * q)
  end function stiffness_times

  !> Columns (n_q, k) with zero prescribed part.
  function full_columns(dyn, w) result(dq)
    type(dynamics_t), intent(in) :: dyn
    real(wp), intent(in) :: w(:, :)
    real(wp) :: dq(dyn%model%n_q, size(w, 2))
    dq = 0.0_wp
    dq(dyn%model%n_rh + 1:, :) = w
  end function full_columns

  !> Factor K0 = DF_dy^T K_x DF_dy in augmented form (the iteration matrix without mass) with
  !> the element Jacobians de_k0 of a configuration; false where it is singular (a dynamic
  !> coordinate without stiffness). It takes the iteration matrix's factors, which a reduced
  !> run does not use otherwise, and leaves dyn%aug%de_val = de_k0.
  logical function k0_factor(dyn, de_k0) result(ok)
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: de_k0(:)
    integer :: info
    call dyn%aug%factor_newton(dyn%model, dyn%mass, 1.0_wp, 0.0_wp, info, mass_scale=0.0_wp, &
      de_val=de_k0)
    ok = info == 0
  end function k0_factor

  !> dq = K0^-1 r at the configuration of de_k0 (the static correction of a reduced model
  !> whose basis came from the Krylov path). `serial` is the iteration matrix's
  !> factorisation count when K0 was last factored there: the factors are made again only if
  !> something else has factored that matrix since. One step of iterative refinement with the
  !> exact K0 dq (the stresses) takes out the saddle-point system's round-off. The element
  !> Jacobians of the current state are put back for the evaluations that follow.
  subroutine k0_solve(dyn, de_k0, serial, r, dq, ok)
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: de_k0(:), r(:)
    integer, intent(inout) :: serial
    real(wp), intent(out) :: dq(:)
    logical, intent(out) :: ok
    real(wp) :: saved(size(dyn%aug%de_val)), z(size(r), 1)
    saved = dyn%aug%de_val
    dq = 0.0_wp
    ok = .true.
    if (dyn%aug%newton_serial /= serial) then
      ok = k0_factor(dyn, de_k0)
      serial = dyn%aug%newton_serial
    else
      dyn%aug%de_val = de_k0
    end if
    if (ok) then
      call dyn%aug%accelerations(dyn%model, &
        dyn%aug%nodal_equivalent(dyn%model, reshape(r, [size(r), 1])), z, newton=.true.)
      dq = z(:, 1)
      z(:, 1) = r - stiffness_times(dyn, dq)
      call dyn%aug%accelerations(dyn%model, dyn%aug%nodal_equivalent(dyn%model, z), z, &
        newton=.true.)
      dq = dq + z(:, 1)
    end if
    dyn%aug%de_val = saved
  end subroutine k0_solve
end module reduction_krylov
