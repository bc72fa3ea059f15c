!> Static equilibrium with load stepping, and the tangent stiffness used by statics and the
!> modal analysis. Prescribed coordinates are stepped with the loads (displacement control:
!> at load factor lambda they take lambda times their values). With the prescribed modes locked and no velocity, the generalised force is
!>   F(q_dy) = DF_dy^T f(x(q)) - sigma_dy(q),   K_T = -dF/dq_dy = S_dd - d(DF_dy^T f)/dq_dy.
!> S_dd is assembled exactly (sigma is linear in q); the load part, which holds the geometric
!> stiffness of the loads and gravity, is differentiated numerically (central differences of
!> exact kinematic solutions), and skipped when the model carries no load.
!>
!> Stability of a converged equilibrium: it is stable when K_T is positive definite on the
!> dynamic coordinates (the prescribed ones are held by their motions and take no part), i.e.
!> when the lowest omega^2 of K_T v = omega^2 Mbar v, the modal problem at that state, is
!> positive. The test is a Cholesky factorisation (dpotrf) of K_T + eps s Mbar, s = max_i
!> |K_ii| / Mbar_ii (at most the largest |omega^2|), eps = STABILITY_MARGIN: a yes/no
!> answer is all that is needed, Cholesky gives it at half the cost of the LU of a Newton
!> iteration, and the shift by the mass matrix makes the round-off margin independent of the
!> units of the coordinates (rotations and translations) and of how they are scaled. LDL^T
!> (dsytrf) would give the inertia, the number of unstable directions, but its pivots have no
!> scale to tell a negative eigenvalue from a zero one. A neutral direction, omega^2 = 0 (a
!> dynamic coordinate without stiffness: a released hinge or rigid-body mode nothing loads),
!> counts as stable within the margin; Newton cannot solve on a singular K_T anyway and stops
!> with the 'singular' error before any check.
module dynamics_static
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_NUMERIC, ERR_INPUT
  use core_linalg, only: lu_factor, lu_solve, chol_factor, gen_eig_values
  use dynamics_system, only: dynamics_t
  use core_progress, only: progress_t
  use core_strings, only: int_str, real_str
  use dynamics_static_krylov, only: krylov_statics_t, difference_step
  use dynamics_frequencies, only: is_symmetric, stability_scale
  implicit none
  private
  public :: tangent_stiffness, motion_tangent, static_solve, static_uses_krylov, stable_tangent, &
    STABILITY_MARGIN, has_loads, load_force

  !> omega^2 above -STABILITY_MARGIN s counts as stable (see the module comment): above the
  !> round-off of the Cholesky factors and of the difference tangent, and below the lowest
  !> omega^2 of ordinary meshes near a critical load: a cantilever of 4 beam elements at 1 %
  !> below P_cr has omega^2 = 1e-6 s, and s grows with the fourth power of the element count,
  !> so that a load within 0.02 % of P_cr is told apart at 50 elements, within 0.3 % at 100.
  real(wp), parameter :: STABILITY_MARGIN = 1.0e-12_wp
  !> solver = 'auto' takes Newton-Krylov (dynamics_static_krylov) on the sparse path above
  !> this many dynamic coordinates: measured on the 45-degree bend (docs/bench/statics.md).
  integer, parameter :: KRYLOV_ABOVE = 40

contains

  !> Whether the generalised force has a configuration-dependent part besides the constant
  !> stiffness of the dynamic modes: loads, gravity or elastic modes.
  logical function has_loads(dyn)
    type(dynamics_t), intent(in) :: dyn
    has_loads = dyn%model%n_elastic > 0 .or. (dyn%load_factor /= 0 .and. &
      (any(dyn%model%force /= 0) .or. any(dyn%model%gravity /= 0) .or. &
      size(dyn%model%load_motion) > 0 .or. size(dyn%model%moment_lambda) > 0))
  end function has_loads

  !> The step of the dense tangents' column differences (along unit coordinates): the Krylov
  !> products' step, a tenth of it with elastic modes. There a unit coordinate of a fine mesh
  !> strains the stiff elastic closure, and even the extrapolated difference erred with the
  !> mesh: the leaf-spring guide at 64 elements per leaf had its first frequency 2.7 % high
  !> (12.016 Hz for 11.6949), its arc-length scale 2 % off, the shallow arch at 64 per half
  !> left its path and the spatial pivot's rotational compliance was 1.7e-4 off. At a tenth
  !> all agree with the Krylov path (whose products along the response strain it little) to
  !> 1e-6 or better; ten times the step made the guide's tangent indefinite.
  pure real(wp) function column_step(dyn) result(h)
    type(dynamics_t), intent(in) :: dyn
    h = difference_step(dyn)
    if (dyn%model%n_elastic > 0) h = h / 10
  end function column_step

  !> Load part of the generalised force, DF_dy^T f, at (t, q_dy) with the model locked.
  subroutine load_force(dyn, t, q_dy, fl, err)
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: t, q_dy(:)
    real(wp), intent(out) :: fl(:)
    type(error_t), intent(out) :: err
    real(wp) :: q(dyn%model%n_q)
    q = dyn%full_q(t, q_dy)
    call dyn%generalised_force(t, q_dy, 0.0_wp * q_dy, fl, err)
    fl = fl + dyn%stresses(q, 0.0_wp * q)
  end subroutine load_force

  !> Tangent stiffness K_T at (t, q_dy); leaves the mass matrix of that state in dyn%mbar.
  !> `accurate` extrapolates the central differences (Richardson, steps h and 2h: error
  !> O(h^4) instead of O(h^2)) at twice the cost; the default with elastic modes. Newton does
  !> not need it; stability, frequencies and compliances do
  !> when stiff elastic modes (EA/l0) sit beside a soft direction: the O(h^2) error of their
  !> difference tangent, about 1e-5 of a bending stiffness, is 1e-3 of a guide's lateral one.
  subroutine tangent_stiffness(dyn, t, q_dy, k, err, accurate)
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: t, q_dy(:)
    real(wp), intent(out) :: k(:, :)
    type(error_t), intent(out) :: err
    logical, intent(in), optional :: accurate
    real(wp) :: d1(size(q_dy)), d2(size(q_dy)), d_mode(size(q_dy), size(q_dy))
    real(wp) :: h, a(size(q_dy)), v0(size(q_dy))
    integer :: j
    logical :: was_locked, extrapolate
    was_locked = dyn%locked
    dyn%locked = .true.
    ! Elastic (calculable) modes put their stiffness into the difference too, beside the soft
    ! direction a compliant mechanism exists for: a spatial cross-spring pivot turns at
    ! 2EI/L = 0.06 N m/rad beside leaves stiff at 1e7 N/m, and the O(h^2) error of the plain
    ! difference made that stiffness negative. Extrapolated, it is right.
    extrapolate = dyn%model%n_elastic > 0
    if (present(accurate)) extrapolate = accurate
    call dyn%mode_stiffness(k, d_mode)
    if (has_loads(dyn)) then
      h = column_step(dyn)
      do j = 1, size(q_dy)
        call central_difference(dyn, t, q_dy, j, h, d1, err)
        if (.not. err%ok()) exit
        if (extrapolate) then
          call central_difference(dyn, t, q_dy, j, 2 * h, d2, err)
          if (.not. err%ok()) exit
          d1 = (4 * d1 - d2) / 3
        end if
        k(:, j) = k(:, j) - d1
      end do
      ! Conservative loads have a symmetric tangent: symmetrising removes difference noise.
      ! A moment fixed in space is not conservative under 3D rotations; Newton (LU) needs its
      ! true, unsymmetric tangent.
      if (size(dyn%model%moment_lambda) == 0) k = 0.5_wp * (k + transpose(k))
    end if
    v0 = 0.0_wp
    if (err%ok()) call dyn%evaluate_dense(t, q_dy, v0, a, err)
    dyn%locked = was_locked
  end subroutine tangent_stiffness

  !> Tangent stiffness along a motion: K = -dF/dq_dy of the generalised force F = Mbar a of
  !> the equations of motion at rest relative to the prescribed motion (v_dy = 0), the
  !> prescribed coordinates moving with their rates and accelerations at t. Beside the load
  !> and geometric stiffness it holds the dynamic stiffening and softening of that motion
  !> (a spinning beam's centrifugal tension; docs/theory.md 8). Differenced and extrapolated
  !> like tangent_stiffness' accurate form; symmetrised (at a relative equilibrium, a = 0,
  !> the centrifugal potential makes it symmetric; the rest is difference noise). Leaves
  !> dyn%mbar at q_dy.
  subroutine motion_tangent(dyn, t, q_dy, k, err, v_dy, accel)
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: t, q_dy(:)
    real(wp), intent(out) :: k(:, :)
    type(error_t), intent(out) :: err
    !> The state's velocity (a state along a dynamic run); default 0, at rest relative to the
    !> prescribed motions. Not symmetrised then: the state need not be an equilibrium.
    real(wp), intent(in), optional :: v_dy(:)
    !> The state's acceleration a0 when it is not the full model's own: a reduced model's
    !> state accelerates with V eta'' (dynamics_linear).
    real(wp), intent(in), optional :: accel(:)
    real(wp) :: h, d1(size(q_dy)), d2(size(q_dy)), v0(size(q_dy)), a(size(q_dy))
    real(wp) :: a0(size(q_dy))
    integer :: j
    logical :: was_locked
    was_locked = dyn%locked
    dyn%locked = .false.
    v0 = 0.0_wp
    if (present(v_dy)) v0 = v_dy
    ! Off an equilibrium the state accelerates (a0): linearising M(q) q'' = F brings in
    ! -(dM/dq dq) a0, so the difference is of M(q) (a(q) - a0) (= F - M a0).
    call dyn%evaluate_dense(t, q_dy, v0, a0, err)
    if (.not. err%ok()) then
      dyn%locked = was_locked
      return
    end if
    if (present(accel)) a0 = accel
    h = column_step(dyn)
    do j = 1, size(q_dy)
      call force_difference(h, d1)
      if (err%ok()) call force_difference(2 * h, d2)
      if (.not. err%ok()) exit
      k(:, j) = -(4 * d1 - d2) / 3
    end do
    if (err%ok()) then
      if (.not. present(v_dy)) k = 0.5_wp * (k + transpose(k))
      call dyn%evaluate_dense(t, q_dy, v0, a, err)
    end if
    dyn%locked = was_locked

  contains

    !> Central difference of Mbar a along q_dy(j), step hs.
    subroutine force_difference(hs, d)
      real(wp), intent(in) :: hs
      real(wp), intent(out) :: d(:)
      real(wp) :: qp(size(q_dy)), fp(size(q_dy))
      qp = q_dy
      qp(j) = q_dy(j) + hs
      call dyn%evaluate_dense(t, qp, v0, a, err)
      if (.not. err%ok()) return
      fp = matmul(dyn%mbar, a - a0)
      qp(j) = q_dy(j) - hs
      call dyn%evaluate_dense(t, qp, v0, a, err)
      if (.not. err%ok()) return
      d = (fp - matmul(dyn%mbar, a - a0)) / (2 * hs)
    end subroutine force_difference
  end subroutine motion_tangent

  !> Central difference of the load force in the direction of q_dy(j), step h.
  subroutine central_difference(dyn, t, q_dy, j, h, d, err)
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: t, q_dy(:), h
    integer, intent(in) :: j
    real(wp), intent(out) :: d(:)
    type(error_t), intent(out) :: err
    real(wp) :: fp(size(q_dy)), fm(size(q_dy)), qp(size(q_dy))
    qp = q_dy
    qp(j) = q_dy(j) + h
    call load_force(dyn, t, qp, fp, err)
    if (.not. err%ok()) return
    qp(j) = q_dy(j) - h
    call load_force(dyn, t, qp, fm, err)
    d = (fp - fm) / (2 * h)
  end subroutine central_difference

  !> Whether the equilibrium with tangent stiffness k and mass matrix m is stable, up to the
  !> round-off margin of the module comment. A symmetric k (conservative loads): k positive
  !> definite. An unsymmetric one (moments fixed in space, which are not conservative under
  !> 3D rotations): no real eigenvalue omega^2 of k v = omega^2 m v below zero (divergence;
  !> the symmetric part's definiteness does not decide it). Complex pairs (flutter) are not
  !> taken as unstable: the roll-up by an end moment has one near the full turn, yet a
  !> dynamic run from that equilibrium shows no growth, so it is not trusted as a verdict.
  logical function stable_tangent(k, m) result(stable)
    real(wp), intent(in) :: k(:, :), m(:, :)
    real(wp), allocatable :: a(:, :)
    real(wp) :: s, wr(size(k, 1)), wi(size(k, 1))
    integer :: info
    s = stability_scale(k, m)
    if (is_symmetric(k)) then
      allocate(a, source=k + (STABILITY_MARGIN * s) * m)
      call chol_factor(a, info)
      stable = info == 0
    else
      call gen_eig_values(k, m, wr, wi, info)
      stable = info == 0 .and. all(wr > -STABILITY_MARGIN * s .or. &
        abs(wi) > STABILITY_MARGIN * s)
    end if
  end function stable_tangent

  !> Newton-Raphson with the load applied in n_steps equal increments (modified: the tangent
  !> is refreshed at the start of a step and when convergence slows, as differencing it costs
  !> 2 n_dy evaluations), or Newton-Krylov (dynamics_static_krylov: no tangent, O(n) per
  !> iteration), by `solver`. q_dy holds the start
  !> on entry and the equilibrium on exit; x_steps(:, k) the nodal coordinates after step k,
  !> stable(k) whether that equilibrium is stable (stable_tangent of the last Newton matrix,
  !> taken within the Newton tolerance of it). `progress` is polled once per Newton iteration.
  subroutine static_solve(dyn, t, n_steps, tol, max_iter, q_dy, x_steps, iterations, err, &
      stable, progress, q_steps, solver, products)
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: t, tol
    integer, intent(in) :: n_steps, max_iter
    real(wp), intent(inout) :: q_dy(:)
    real(wp), intent(out) :: x_steps(:, :)
    integer, intent(out) :: iterations
    type(error_t), intent(out) :: err
    logical, intent(out), optional :: stable(:)
    type(progress_t), intent(inout), optional :: progress
    real(wp), intent(out), optional :: q_steps(:, :)   !< q_dy after each step
    !> 'dense' (the difference tangent, LU), 'krylov' (Newton-Krylov, the sparse path only) or
    !> 'auto' (the default: krylov on the sparse path above KRYLOV_ABOVE coordinates)
    character(len=*), intent(in), optional :: solver
    !> Products with the tangent that Newton-Krylov took (0 on the dense path)
    integer, intent(out), optional :: products
    real(wp), allocatable :: k(:, :), kf(:, :)
    real(wp) :: r(size(q_dy)), a(size(q_dy)), v0(size(q_dy)), rhs(size(q_dy), 1)
    type(krylov_statics_t) :: kry
    logical :: krylov, decided
    real(wp) :: lambda, scale, rcond, r_prev, q_last(size(q_dy))
    integer :: step, it, info, ipiv(size(q_dy))
    logical :: refresh, fresh
    character(len=200) :: msg
    if (n_steps < 1 .or. max_iter < 1 .or. tol <= 0) then
      call err%set(ERR_INPUT, 'group &static: n_steps and max_iter must be >= 1 and tol > 0')
      return
    end if
    call static_uses_krylov(dyn, size(q_dy), solver, krylov, err)
    if (.not. err%ok()) return
    if (.not. krylov) allocate(k(size(q_dy), size(q_dy)), kf(size(q_dy), size(q_dy)))
    v0 = 0.0_wp
    iterations = 0
    scale = max(1.0e-3_wp, maxval(abs(dyn%model%x0)))
    if (present(stable)) stable = .true.
    dyn%locked = .true.
    dyn%ramp_prescribed = .true.
    q_last = q_dy
    do step = 1, n_steps
      lambda = real(step, wp) / n_steps
      dyn%load_factor = lambda
      ! Secant predictor: equal steps along a smooth path change q_dy by about as much as the
      ! last one did (a large saving under displacement control, where the unchanged q_dy
      ! would stretch stiff elastic modes by the whole prescribed increment).
      a = q_dy
      if (step > 1) q_dy = q_dy + (q_dy - q_last)
      q_last = a
      if (krylov) then
        if (present(progress)) then
          if (progress%due()) call progress%report_load(step, n_steps, lambda)
        end if
        call kry%equilibrium(dyn, t, q_dy, tol * scale, max_iter, iterations, err)
        if (.not. err%ok()) exit
        if (present(stable)) then
          ! Moments fixed in space give complex pairs that Arnoldi converges on slowly, if at
          ! all: there, and where it does not converge, the dense test decides (O(n^2)).
          decided = .false.
          if (size(dyn%model%moment_lambda) == 0) &
            call kry%stable(dyn, t, q_dy, stable(step), decided, err)
          if (.not. err%ok()) exit
          if (.not. decided) then
            if (.not. allocated(k)) allocate(k(size(q_dy), size(q_dy)))
            call tangent_stiffness(dyn, t, q_dy, k, err)
            if (.not. err%ok()) exit
            stable(step) = stable_tangent(k, dyn%mbar)
          end if
          call dyn%generalised_force(t, q_dy, v0, a, err)
          if (.not. err%ok()) exit
        end if
        x_steps(:, step) = dyn%kin%x
        if (present(q_steps)) q_steps(:, step) = q_dy
        cycle
      end if
      refresh = .true.
      r_prev = huge(1.0_wp)
      do it = 1, max_iter
        if (present(progress)) then
          if (progress%due()) call progress%report_load(step, n_steps, lambda)
        end if
        fresh = refresh
        if (refresh) then
          call tangent_stiffness(dyn, t, q_dy, k, err)
          if (.not. err%ok()) exit
          kf = k
          call lu_factor(kf, ipiv, info, rcond)
          if (info /= 0 .or. rcond < 1.0e-12_wp) then
            call err%set(ERR_NUMERIC, 'static analysis: the tangent stiffness is singular ' &
              // 'at load factor ' // real_str(lambda) // ' (buckling or a mechanism)')
            exit
          end if
          refresh = .false.
        else
          call dyn%generalised_force(t, q_dy, v0, a, err)
          if (.not. err%ok()) then
            ! A correction with old factors that leaves the kinematics unsolvable: take it
            ! back and go on with a fresh tangent.
            if (err%code /= ERR_NUMERIC) exit
            call err%clear()
            q_dy = q_dy - r
            refresh = .true.
            cycle
          end if
        end if
        rhs(:, 1) = dyn%gen_force
        call lu_solve(kf, ipiv, rhs)
        if (.not. fresh .and. maxval(abs(rhs(:, 1))) > r_prev) then
          refresh = .true.
          cycle
        end if
        r = rhs(:, 1)
        q_dy = q_dy + r
        iterations = iterations + 1
        if (maxval(abs(r)) <= tol * scale) exit
        ! Modified Newton: keep the factors while each correction is at most a quarter of the
        ! last (then the error left is at most a third of the last correction); a growing
        ! correction is never taken.
        refresh = maxval(abs(r)) > 0.25_wp * r_prev
        r_prev = maxval(abs(r))
      end do
      if (err%ok() .and. it > max_iter) then
        write(msg, '(es10.3)') maxval(abs(r))
        call err%set(ERR_NUMERIC, 'static analysis: Newton did not converge in ' // &
          int_str(max_iter) // ' iterations at load factor ' // real_str(lambda) // &
          ', last correction ' // trim(adjustl(msg)))
      end if
      if (.not. err%ok()) exit
      ! The stability of the equilibrium needs the tangent at it (within tol).
      if (present(stable)) then
        if (.not. (fresh .and. it == 1)) call tangent_stiffness(dyn, t, q_dy, k, err)
        if (.not. err%ok()) exit
        stable(step) = stable_tangent(k, dyn%mbar)
      end if
      call dyn%evaluate_dense(t, q_dy, v0, a, err)
      if (.not. err%ok()) exit
      x_steps(:, step) = dyn%kin%x
      if (present(q_steps)) q_steps(:, step) = q_dy
    end do
    ! Failures of the kinematics or the model at a Newton iterate (a load step so large that
    ! the first correction leaves the reach of the structure) say where they happened.
    if (.not. err%ok()) then
      if (index(err%message, 'static analysis') /= 1) then
        if (err%code == ERR_NUMERIC) err%message = err%message // ' (smaller load steps: ' // &
          'more n_steps)'
        call err%prefix('static analysis, load step ' // int_str(step) // ' of ' // &
          int_str(n_steps) // ' (load factor ' // real_str(lambda) // '): ')
      end if
    end if
    if (present(products)) products = kry%n_products
    dyn%locked = .false.
    dyn%ramp_prescribed = .false.
    dyn%load_factor = 1.0_wp
  end subroutine static_solve

  !> Whether statics of n_dy coordinates takes the Newton-Krylov path: `solver` 'dense',
  !> 'krylov' or 'auto' (absent: krylov on the sparse path above KRYLOV_ABOVE coordinates).
  subroutine static_uses_krylov(dyn, n_dy, solver, krylov, err)
    type(dynamics_t), intent(in) :: dyn
    integer, intent(in) :: n_dy
    character(len=*), intent(in), optional :: solver
    logical, intent(out) :: krylov
    type(error_t), intent(out) :: err
    krylov = dyn%sparse .and. n_dy > KRYLOV_ABOVE
    if (present(solver)) then
      if (solver == 'dense') krylov = .false.
      if (solver == 'krylov') krylov = .true.
    end if
    if (krylov .and. .not. dyn%sparse) call err%set(ERR_INPUT, 'group &static: variable ' // &
      '''solver'' = ''krylov'' needs the sparse path (&scene linear_solver = ''sparse'' or ' // &
      '''auto'' with more than 12 nodal coordinates)')
  end subroutine static_uses_krylov
end module dynamics_static
