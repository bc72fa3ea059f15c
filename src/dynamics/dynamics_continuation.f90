!> Arc-length continuation of static equilibria (docs/theory.md section 7.2): the load factor
!> lambda becomes an unknown beside q_dy, so that the path can be followed through limit
!> points (snap-through of an arch, a post-buckled column) where load control stops.
!>
!> With velocities zero the generalised force is affine in lambda at a fixed configuration,
!> F(q, lambda) = F(q, 0) + lambda P(q), P = F(q, 1) - F(q, 0) (the loads, without the
!> stiffness). Each step predicts along the path tangent (K_T v = P, direction (v, 1)
!> normalised) and corrects by Newton on F = 0 together with the Riks normal-plane condition
!> (the correction stays orthogonal to the predictor), solved by bordering with two solves of
!> K_T per iteration. Lengths are measured in the plane of (q / c, lambda), c = |K_0^-1 P| the
!> linear response to the full load, so that an arc of sqrt(2)/n is one load step's worth near
!> the start whatever the units of q. A step that does not converge is halved (up to
!> MAX_HALVINGS times) and grows back after easy steps.
!>
!> The two solves with K_T are either LU factors of the dense difference tangent (modified
!> Newton, O(n^2) evaluations per refresh, O(n^3) factors) or, on the Newton-Krylov path of
!> large models (dynamics_static_krylov), GMRES on products of the tangent preconditioned by
!> the sparse structural stiffness: O(n) per product, so that long paths of large compliant
!> mechanisms stay affordable. Krylov corrections are full Newton steps (no factors to keep).
module dynamics_continuation
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_NUMERIC, ERR_INPUT
  use core_linalg, only: lu_factor, lu_solve
  use core_strings, only: int_str, real_str
  use core_progress, only: progress_t
  use dynamics_system, only: dynamics_t
  use dynamics_static, only: tangent_stiffness, stable_tangent, static_uses_krylov
  use dynamics_static_krylov, only: krylov_statics_t
  implicit none
  private
  public :: arc_length_solve

  integer, parameter :: MAX_HALVINGS = 12
  !> Pivots of K_T this much below the largest: the bordered solve treats K_T as singular,
  !> exactly at a bifurcation (not at a limit point, where the border keeps it regular).
  real(wp), parameter :: SINGULAR_PIVOT = 1.0e-14_wp

contains

  !> `n_steps` arc-length steps from q_dy at load factor 0 (q_dy: start on entry, last
  !> equilibrium on exit), step `arc` (<= 0: sqrt(2)/n_steps), stopping early once lambda
  !> reaches `max_load_factor`. Per converged step: lambda_steps, x_steps, q_steps and
  !> stable. `n_done` is the number of steps taken.
  subroutine arc_length_solve(dyn, t, n_steps, arc, max_load_factor, tol, max_iter, q_dy, &
      lambda_steps, x_steps, q_steps, stable, n_done, iterations, err, progress, solver, &
      products)
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: t, arc, max_load_factor, tol
    integer, intent(in) :: n_steps, max_iter
    real(wp), intent(inout) :: q_dy(:)
    real(wp), intent(out) :: lambda_steps(:), x_steps(:, :), q_steps(:, :)
    logical, intent(out) :: stable(:)
    integer, intent(out) :: n_done, iterations
    type(error_t), intent(out) :: err
    type(progress_t), intent(inout), optional :: progress
    !> 'dense', 'krylov' or 'auto' (default), as static_solve chooses
    character(len=*), intent(in), optional :: solver
    !> Products with the tangent that the Krylov path took (0 on the dense path)
    integer, intent(out), optional :: products
    real(wp), allocatable :: k(:, :)
    real(wp) :: p(size(q_dy)), v(size(q_dy))
    real(wp) :: tq(size(q_dy)), tl, q_pred(size(q_dy)), l_pred, lambda, c, ds, ds_max
    real(wp) :: q(size(q_dy)), l, scale
    type(krylov_statics_t) :: kry
    integer :: halvings, it
    logical :: converged, krylov, loaded
    character(len=:), allocatable :: failure
    n_done = 0
    iterations = 0
    if (present(products)) products = 0
    call static_uses_krylov(dyn, size(q_dy), solver, krylov, err)
    if (.not. err%ok()) return
    if (.not. krylov) allocate(k(size(q_dy), size(q_dy)))
    dyn%locked = .true.
    dyn%kin%keep_failed_guess = .true.
    lambda = 0.0_wp
    scale = max(1.0e-3_wp, maxval(abs(dyn%model%x0)))
    loaded = any(dyn%model%force /= 0) .or. any(dyn%model%gravity /= 0) .or. &
      size(dyn%model%load_motion) > 0 .or. size(dyn%model%moment_lambda) > 0
    ! Prescribed inputs are held at their full values: the start is the equilibrium without
    ! loads there, which the reference need not be (a pivot turned by a prescribed angle).
    if (loaded) call start_equilibrium(err)
    ! The scale of q: the linear response to the full load at the start.
    if (.not. err%ok()) then
      continue
    else if (krylov) then
      call krylov_load(q_dy, lambda, p, v, err)
    else
      call tangent_and_load(dyn, t, q_dy, lambda, k, p, err)
    end if
    ! Without a load there is no path to follow: the tangent would be 0/0. (Without any load
    ! P is zero only up to the kinematics' round-off: decided by the model, not by P.)
    if (err%ok() .and. (.not. loaded .or. .not. any(p /= 0))) then
      if (loaded) then
        ! Loads that do no work on the dynamic coordinates at the start: a perfect column
        ! loaded along its axis, whose path leaves the start only by bifurcation.
        call err%set(ERR_INPUT, 'group &static: variable ''method'': arc-length ' // &
          'continuation follows the load factor, and at the start the loads do no work on ' // &
          'the dynamic coordinates (e.g. a straight column loaded along its axis, which ' // &
          'leaves the straight path only by bifurcation): add a small perturbing load, ' // &
          'or use method = ''load''')
      else
        call err%set(ERR_INPUT, 'group &static: variable ''method'': arc-length ' // &
          'continuation follows the load factor, and the loads it scales are zero on ' // &
          'every degree of freedom (no &force, gravity or other load acts on them)')
      end if
      call finish(dyn)
      return
    end if
    if (err%ok() .and. krylov) then
      call kry%precondition(dyn, t, q_dy, err)
      if (err%ok()) call kry%solve(dyn, t, q_dy, p, v, err)
    else if (err%ok()) then
      call solve_tangent(k, p, v, err)
    end if
    if (.not. err%ok()) then
      call err%prefix('arc-length start: ')
      call finish(dyn)
      return
    end if
    c = max(norm2(v), tiny(1.0_wp))
    ds_max = arc
    if (ds_max <= 0) ds_max = sqrt(2.0_wp) / n_steps
    ds = ds_max
    tq = v / c
    tl = 1.0_wp
    call normalise(tq, tl)
    do while (n_done < n_steps)
      if (present(progress)) then
        if (progress%due()) call progress%report_load(n_done + 1, n_steps, lambda)
      end if
      halvings = 0
      failure = ''
      do
        q_pred = q_dy + ds * tq * c
        l_pred = lambda + ds * tl
        q = q_pred
        l = l_pred
        if (krylov) then
          call correct_krylov(q, l, v, converged)
        else
          call correct(q, l, converged)
        end if
        if (.not. err%ok()) then
          if (err%code /= ERR_NUMERIC) exit
          ! Kept for the message if no halving helps: an arc far too long for the path ends
          ! in kinematics that cannot be solved, and the cure is a shorter arc.
          failure = err%message
          call err%clear()
          converged = .false.
        end if
        if (converged) exit
        halvings = halvings + 1
        if (halvings > MAX_HALVINGS) exit
        ds = ds / 2
      end do
      if (.not. err%ok()) exit
      if (.not. converged) then
        if (len(failure) > 0) failure = '; the last try: ' // failure
        call err%set(ERR_NUMERIC, 'static arc-length: no equilibrium found from load factor ' // &
          real_str(lambda) // ' after ' // int_str(MAX_HALVINGS) // ' halvings of the arc ' // &
          '(a bifurcation or a mechanism: try a smaller arc_length or a small perturbing load)' &
          // failure)
        exit
      end if
      ! The new tangent, oriented to continue in the direction just travelled (Krylov: K_T^-1 P
      ! of the last correction, at a state within tol of this one).
      if (.not. krylov) then
        call tangent_and_load(dyn, t, q, l, k, p, err)
        if (err%ok()) call solve_tangent(k, p, v, err)
      end if
      if (.not. err%ok()) exit
      n_done = n_done + 1
      if (krylov) then
        call krylov_stable(q, l, stable(n_done), err)
        if (.not. err%ok()) exit
      else
        stable(n_done) = stable_tangent(k, dyn%mbar)
      end if
      block
        real(wp) :: new_q(size(q_dy)), new_l
        new_q = v / c
        new_l = 1.0_wp
        call normalise(new_q, new_l)
        if (dot_product(new_q, (q - q_dy) / c) + new_l * (l - lambda) < 0) then
          new_q = -new_q
          new_l = -new_l
        end if
        tq = new_q
        tl = new_l
      end block
      q_dy = q
      lambda = l
      lambda_steps(n_done) = lambda
      q_steps(:, n_done) = q_dy
      x_steps(:, n_done) = dyn%kin%x
      if (halvings == 0) ds = min(ds_max, 2 * ds)
      if (lambda >= max_load_factor) exit
    end do
    if (present(products)) products = kry%n_products
    call finish(dyn)

  contains

    !> Newton at load factor 0 from q_dy (the reference or the last static state).
    subroutine start_equilibrium(err)
      type(error_t), intent(out) :: err
      real(wp) :: f(size(q_dy)), dq(size(q_dy)), lu(size(q_dy), size(q_dy))
      integer :: ipiv(size(q_dy))
      dyn%load_factor = 0.0_wp
      if (krylov) then
        call kry%equilibrium(dyn, t, q_dy, tol * scale, max_iter, iterations, err)
      else
        do it = 1, max_iter
          call tangent_and_load(dyn, t, q_dy, 0.0_wp, k, p, err, f)
          if (err%ok()) call factor(k, lu, ipiv, err)
          if (.not. err%ok()) exit
          call solve_factored(lu, ipiv, f, f, dq, p)
          q_dy = q_dy + dq
          iterations = iterations + 1
          if (maxval(abs(dq)) <= tol * scale) exit
        end do
        if (err%ok() .and. it > max_iter) call err%set(ERR_NUMERIC, 'Newton did not ' // &
          'converge in ' // int_str(max_iter) // ' iterations')
      end if
      if (.not. err%ok()) call err%prefix('Newton found no equilibrium without loads, with ' &
        // 'the prescribed inputs at their full values (arc-length does not step them; for ' // &
        'displacement control use method = ''load''): ')
    end subroutine start_equilibrium

    !> P and F at (q, l), leaving the model at load factor l.
    subroutine krylov_load(q, l, p, f, err)
      real(wp), intent(in) :: q(:), l
      real(wp), intent(out) :: p(:), f(:)
      type(error_t), intent(out) :: err
      call load_and_force(dyn, t, q, l, p, f, err)
      dyn%load_factor = l
    end subroutine krylov_load

    !> Newton as `correct`, each correction's two solves by GMRES (the preconditioner
    !> factored at the predictor); v: K_T^-1 P of the last correction.
    subroutine correct_krylov(q, l, v, converged)
      real(wp), intent(inout) :: q(:), l
      real(wp), intent(inout) :: v(:)
      logical, intent(out) :: converged
      real(wp) :: a(size(q)), b(size(q)), f(size(q)), dl
      converged = .false.
      do it = 1, max_iter
        call krylov_load(q, l, p, f, err)
        if (err%ok() .and. it == 1) call kry%precondition(dyn, t, q, err)
        if (err%ok()) call kry%solve(dyn, t, q, f, a, err)
        if (err%ok()) call kry%solve(dyn, t, q, p, b, err)
        if (.not. err%ok()) return
        call load_increment(q, l, a, b, dl)
        if (.not. err%ok()) return
        q = q + a + b * dl
        l = l + dl
        v = b
        iterations = iterations + 1
        if (maxval(abs(a + b * dl)) <= tol * scale .and. abs(dl) <= tol) then
          converged = .true.
          return
        end if
      end do
    end subroutine correct_krylov

    !> The stability of the equilibrium (q, l) as static_solve's Krylov path decides it (the
    !> dense test where Arnoldi does not, and for moments fixed in space); leaves the
    !> kinematics at (q, l).
    subroutine krylov_stable(q, l, stable, err)
      real(wp), intent(in) :: q(:), l
      logical, intent(out) :: stable
      type(error_t), intent(out) :: err
      real(wp) :: f(size(q))
      logical :: decided
      decided = .false.
      if (size(dyn%model%moment_lambda) == 0) call kry%stable(dyn, t, q, stable, decided, err)
      if (err%ok() .and. .not. decided) then
        if (.not. allocated(k)) allocate(k(size(q), size(q)))
        call tangent_stiffness(dyn, t, q, k, err)
        if (err%ok()) stable = stable_tangent(k, dyn%mbar)
      end if
      if (err%ok()) call dyn%generalised_force(t, q, 0.0_wp * q, f, err)
    end subroutine krylov_stable

    !> The load factor's part dl of the bordered correction (a + b dl, dl): the one that keeps
    !> (q, l) on the normal plane through the predictor.
    subroutine load_increment(q, l, a, b, dl)
      real(wp), intent(in) :: q(:), l, a(:), b(:)
      real(wp), intent(out) :: dl
      real(wp) :: g, den
      dl = 0.0_wp
      g = dot_product(tq, (q - q_pred) / c) + tl * (l - l_pred)
      den = dot_product(tq, b) / c + tl
      if (abs(den) < tiny(1.0_wp)) then
        call err%set(ERR_NUMERIC, 'static arc-length: the path is tangent to the constraint')
        return
      end if
      dl = -(g + dot_product(tq, a) / c) / den
    end subroutine load_increment

    !> Newton from (q, l) on F = 0 and the normal-plane condition through the predictor.
    subroutine correct(q, l, converged)
      real(wp), intent(inout) :: q(:), l
      logical, intent(out) :: converged
      real(wp) :: a(size(q)), b(size(q)), f(size(q)), dl, step, prev
      real(wp) :: lu(size(q), size(q))
      integer :: ipiv(size(q))
      logical :: refresh
      converged = .false.
      refresh = .true.
      prev = huge(1.0_wp)
      do it = 1, max_iter
        ! Modified Newton as in static_solve: new factors of K_T at the start and whenever a
        ! correction is not at most a quarter of the last (a difference tangent costs 2 n_dy
        ! evaluations, the loads two).
        if (refresh) then
          call tangent_and_load(dyn, t, q, l, k, p, err, f)
          if (err%ok()) call factor(k, lu, ipiv, err)
        else
          call load_and_force(dyn, t, q, l, p, f, err)
        end if
        if (.not. err%ok()) return
        call solve_factored(lu, ipiv, f, p, a, b)
        call load_increment(q, l, a, b, dl)
        if (.not. err%ok()) return
        step = max(maxval(abs(a + b * dl)) / scale, abs(dl))
        if (.not. refresh .and. step > prev) then
          refresh = .true.
          cycle
        end if
        q = q + a + b * dl
        l = l + dl
        iterations = iterations + 1
        if (maxval(abs(a + b * dl)) <= tol * scale .and. abs(dl) <= tol) then
          converged = .true.
          return
        end if
        refresh = step > 0.25_wp * prev
        prev = step
      end do
    end subroutine correct
  end subroutine arc_length_solve

  !> The load vector P and F(q, lambda) = F(q, 0) + lambda P at q (two evaluations).
  subroutine load_and_force(dyn, t, q, lambda, p, f, err)
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: t, q(:), lambda
    real(wp), intent(out) :: p(:), f(:)
    type(error_t), intent(out) :: err
    real(wp) :: a(size(q)), f0(size(q))
    dyn%load_factor = 0.0_wp
    call dyn%generalised_force(t, q, 0.0_wp * q, f0, err)
    if (.not. err%ok()) return
    dyn%load_factor = 1.0_wp
    call dyn%generalised_force(t, q, 0.0_wp * q, a, err)
    if (.not. err%ok()) return
    p = a - f0
    f = f0 + lambda * p
  end subroutine load_and_force

  !> K_T at (q, lambda) and the load vector P; optionally F(q, lambda) itself.
  subroutine tangent_and_load(dyn, t, q, lambda, k, p, err, f)
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: t, q(:), lambda
    real(wp), intent(out) :: k(:, :), p(:)
    type(error_t), intent(out) :: err
    real(wp), intent(out), optional :: f(:)
    real(wp) :: fl(size(q))
    call load_and_force(dyn, t, q, lambda, p, fl, err)
    if (.not. err%ok()) return
    if (present(f)) f = fl
    dyn%load_factor = lambda
    call tangent_stiffness(dyn, t, q, k, err)
  end subroutine tangent_and_load

  !> LU factors of K_T, or an error at a singular one.
  subroutine factor(k, lu, ipiv, err)
    real(wp), intent(in) :: k(:, :)
    real(wp), intent(out) :: lu(:, :)
    integer, intent(out) :: ipiv(:)
    type(error_t), intent(inout) :: err
    real(wp) :: rcond
    integer :: info
    lu = k
    call lu_factor(lu, ipiv, info, rcond)
    if (info /= 0 .or. rcond < SINGULAR_PIVOT) call err%set(ERR_NUMERIC, 'static ' // &
      'arc-length: the tangent stiffness is singular (a bifurcation point or a mechanism)')
  end subroutine factor

  !> K a = f and K b = p with the factors of K (the Newton correction is a + b dlambda).
  subroutine solve_factored(lu, ipiv, f, p, a, b)
    real(wp), intent(in) :: lu(:, :), f(:), p(:)
    integer, intent(in) :: ipiv(:)
    real(wp), intent(out) :: a(:), b(:)
    real(wp) :: rhs(size(f), 2)
    rhs(:, 1) = f
    rhs(:, 2) = p
    call lu_solve(lu, ipiv, rhs)
    a = rhs(:, 1)
    b = rhs(:, 2)
  end subroutine solve_factored

  !> The path tangent's q part, K v = P.
  subroutine solve_tangent(k, p, v, err)
    real(wp), intent(in) :: k(:, :), p(:)
    real(wp), intent(out) :: v(:)
    type(error_t), intent(inout) :: err
    real(wp) :: lu(size(k, 1), size(k, 2)), dummy(size(p))
    integer :: ipiv(size(p))
    call factor(k, lu, ipiv, err)
    if (err%ok()) call solve_factored(lu, ipiv, p, p, v, dummy)
  end subroutine solve_tangent

  pure subroutine normalise(tq, tl)
    real(wp), intent(inout) :: tq(:), tl
    real(wp) :: n
    n = sqrt(dot_product(tq, tq) + tl**2)
    tq = tq / n
    tl = tl / n
  end subroutine normalise

  subroutine finish(dyn)
    type(dynamics_t), intent(inout) :: dyn
    dyn%locked = .false.
    dyn%load_factor = 1.0_wp
    dyn%kin%keep_failed_guess = .false.
  end subroutine finish
end module dynamics_continuation
