!> Matrix-free linearised buckling for large models (docs/theory.md 7.3): the multipliers of
!> (K0 + mu K_G) v = 0 as theta = 1/mu, the eigenvalues of
!>   P^-1 (-K_G),   P = K0,   K_G = (K_T(lambda_ref) - K0) / lambda_ref,
!> the largest first, by Arnoldi (ARPACK dnaupd, which = 'LR'). Each step is one product with
!> the load part of K_T at the reference load (two evaluations, dynamics_static_krylov's
!> load_product) and one solve with the
!> sparse factors of K0: O(n), where the dense path differences two n_dy x n_dy tangents and
!> solves a dense eigenproblem, O(n^2) and O(n^3). The eigenvalues are real (the problem is
!> symmetric-definite), so the non-symmetric driver only has to tolerate the products'
!> difference noise.
!>
!> It needs K0 = K_T(0) exactly as the factors hold it: no elastic (calculable) modes, whose
!> stresses at a loaded state would add a geometric term to K_T(0); no moments fixed in space
!> (their K_G is unsymmetric: the dense path keeps its real multipliers only); no extra
!> supports of the buckling problem alone; and K0 regular (the dense path requires it too).
module dynamics_buckling_krylov
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_NUMERIC, ERR_MODEL
  use core_strings, only: int_str
  use core_sort, only: sort_by_value
  use core_arpack, only: dnaupd, dneupd
  use dynamics_system, only: dynamics_t
  use dynamics_static_krylov, only: krylov_statics_t, krylov_tangent_unsupported
  implicit none
  private
  public :: krylov_buckling, krylov_buckling_applies

contains

  !> '' when the Krylov path applies to this model, else why not (see the module comment).
  function krylov_buckling_applies(dyn, has_held) result(why_not)
    type(dynamics_t), intent(in) :: dyn
    logical, intent(in) :: has_held
    character(len=:), allocatable :: why_not
    why_not = krylov_tangent_unsupported(dyn)
    if (why_not == '' .and. has_held) why_not = 'the buckling problem has supports of its own'
  end function krylov_buckling_applies

  !> The at most n_modes largest theta > cutoff * (the largest |theta| found) and their shapes
  !> q (n_dy) and DF_dy q (n_x), at (t, q_dy) with the loads at lambda_ref; dyn%load_factor is
  !> restored. `n_found` < n_modes when fewer converged or passed the cutoff.
  !> `resolved`, `max_rescale` and `max_rescales`: the load part of the products is scaled up
  !> as dynamics_buckling does the dense difference (the same round-off, here of the
  !> structure's stresses in the load force): its load factor is `lambda` on return.
  subroutine krylov_buckling(dyn, t, q_dy, n_modes, lambda_ref, cutoff, theta, shapes, &
      node_shapes, err, resolved, max_rescale, max_rescales, lambda)
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: t, q_dy(:), lambda_ref, cutoff, resolved, max_rescale
    integer, intent(in) :: n_modes, max_rescales
    real(wp), allocatable, intent(out) :: theta(:), shapes(:, :), node_shapes(:, :)
    type(error_t), intent(out) :: err
    real(wp), intent(out) :: lambda
    type(krylov_statics_t) :: kry
    real(wp) :: saved, x(size(q_dy)), k0x(size(q_dy)), klx(size(q_dy)), ratio
    integer :: i, attempt
    logical :: was_locked
    saved = dyn%load_factor
    was_locked = dyn%locked
    ! As the dense tangent has it: the prescribed modes held still at t.
    dyn%locked = .true.
    dyn%load_factor = 0.0_wp
    call kry%precondition(dyn, t, q_dy, err)
    ! A K0 that the factors cannot take as it is (shifted, or not at all: nothing has mass
    ! to shift it with) is a mechanism, as the dense path says (and with its exit status);
    ! the factorisation's own message names the static analysis and its solver.
    if (err%code == ERR_NUMERIC .or. (err%ok() .and. kry%shift /= 0)) then
      call err%clear()
      call err%set(ERR_MODEL, 'buckling analysis: the structural stiffness K0 is singular ' // &
        '(a mechanism: a dynamic coordinate without stiffness, e.g. a released hinge or a ' // &
        'free rigid-body motion)')
    end if
    ! The sizes of K0 x and of the load part K_L x along a fixed vector with no structure
    ! (every coordinate, varied signs), where the load part has no reason to vanish.
    lambda = lambda_ref
    x = [(sin(1.0_wp + 2.3_wp * i), i = 1, size(q_dy))]
    if (err%ok()) call kry%product(dyn, t, q_dy, x, k0x, err)
    do attempt = 1, max_rescales + 1
      if (.not. err%ok()) exit
      dyn%load_factor = lambda
      call kry%load_product(dyn, t, q_dy, x, klx, err)
      if (.not. err%ok()) exit
      if (norm2(klx) >= resolved * norm2(k0x) .or. attempt > max_rescales) exit
      ratio = norm2(klx) / norm2(k0x)
      lambda = lambda * merge(1 / ratio, max_rescale, ratio > 1 / max_rescale)
    end do
    if (err%ok()) then
      dyn%load_factor = lambda
      call arnoldi(kry, dyn, t, q_dy, n_modes, lambda, theta, shapes, err)
    end if
    dyn%load_factor = saved
    if (err%ok()) then
      call keep_positive(theta, shapes, cutoff)
      call nodal_shapes(dyn, t, q_dy, shapes, node_shapes, err)
    end if
    dyn%locked = was_locked
  end subroutine krylov_buckling

  subroutine arnoldi(kry, dyn, t, q_dy, n_modes, lambda_ref, theta, shapes, err)
    type(krylov_statics_t), intent(inout) :: kry
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: t, q_dy(:), lambda_ref
    integer, intent(in) :: n_modes
    real(wp), allocatable, intent(out) :: theta(:), shapes(:, :)
    type(error_t), intent(out) :: err
    integer :: n, nev, ncv, ido, info, iparam(11), ipntr(14), lworkl, i
    real(wp) :: tol, resid(size(q_dy)), kv(size(q_dy)), sigma(2)
    real(wp), allocatable :: v(:, :), workd(:), workl(:), dr(:), di(:), z(:, :), workev(:)
    logical, allocatable :: sel(:)
    n = size(q_dy)
    nev = min(n_modes, n - 2)
    ncv = min(n, max(2 * nev + 1, 20))
    if (nev < 1) then
      call err%set(ERR_NUMERIC, 'buckling analysis (krylov): too few dynamic coordinates ' // &
        '(' // int_str(n) // ') for the Arnoldi iteration; use &buckling solver = ''dense''')
      return
    end if
    lworkl = 3 * ncv**2 + 6 * ncv
    allocate(v(n, ncv), workd(3 * n), workl(lworkl), dr(nev + 1), di(nev + 1), z(n, nev + 1), &
      workev(3 * ncv), sel(ncv))
    tol = 1.0e-10_wp
    ido = 0
    info = 0
    iparam = 0
    iparam(1) = 1
    iparam(3) = 500
    iparam(7) = 1
    do
      call dnaupd(ido, 'I', n, 'LR', nev, tol, resid, ncv, v, n, iparam, ipntr, workd, &
        workl, lworkl, info)
      if (ido /= 1 .and. ido /= -1) exit
      ! theta x = -P^-1 K_G x, K_G = K_L(lambda_ref) / lambda_ref: the load part's tangent
      ! alone (no elastic modes), never K0 x + K_G x solved and K0's part taken off again.
      associate (x => workd(ipntr(1):ipntr(1) + n - 1), y => workd(ipntr(2):ipntr(2) + n - 1))
        call kry%load_product(dyn, t, q_dy, x, kv, err)
        if (.not. err%ok()) return
        call kry%apply_p(dyn, kv, y)
        y = -y / lambda_ref
      end associate
    end do
    if (info /= 0) then
      call err%set(ERR_NUMERIC, 'buckling analysis (krylov): the Arnoldi iteration did not ' // &
        'converge (ARPACK info ' // int_str(info) // '); use &buckling solver = ''dense''')
      return
    end if
    sigma = 0.0_wp
    call dneupd(.true., 'A', sel, dr, di, z, n, sigma(1), sigma(2), workev, 'I', n, 'LR', nev, &
      tol, resid, ncv, v, n, iparam, ipntr, workd, workl, lworkl, info)
    if (info /= 0 .or. iparam(5) < nev) then
      call err%set(ERR_NUMERIC, 'buckling analysis (krylov): ' // int_str(iparam(5)) // &
        ' of ' // int_str(nev) // ' multipliers converged (ARPACK info ' // int_str(info) // &
        '); use &buckling solver = ''dense''')
      return
    end if
    ! The problem is symmetric-definite: the eigenvalues are real and so are the vectors
    ! (a complex pair here would be difference noise between two equal theta).
    theta = dr(1:nev)
    shapes = z(:, 1:nev)
    do i = 1, nev
      shapes(:, i) = shapes(:, i) / maxval(abs(shapes(:, i)))
    end do
    if (any(abs(di(1:nev)) > 1.0e-6_wp * maxval(abs(dr(1:nev))))) call err%set(ERR_NUMERIC, &
      'buckling analysis (krylov): complex multipliers (is the load conservative?); use ' // &
      '&buckling solver = ''dense''')
  end subroutine arnoldi

  !> Keep theta > cutoff * max|theta|, largest first.
  subroutine keep_positive(theta, shapes, cutoff)
    real(wp), allocatable, intent(inout) :: theta(:), shapes(:, :)
    real(wp), intent(in) :: cutoff
    integer, allocatable :: order(:)
    integer :: i
    order = pack([(i, i = 1, size(theta))], theta > cutoff * maxval(abs(theta)))
    call sort_by_value(order, -theta)
    theta = theta(order)
    shapes = shapes(:, order)
  end subroutine keep_positive

  !> DF_dy q of each shape, with the kinematics solved at q_dy again (the products left it at
  !> a perturbed state).
  subroutine nodal_shapes(dyn, t, q_dy, shapes, node_shapes, err)
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: t, q_dy(:), shapes(:, :)
    real(wp), allocatable, intent(out) :: node_shapes(:, :)
    type(error_t), intent(out) :: err
    real(wp) :: g(size(q_dy)), dq(dyn%model%n_q, size(shapes, 2))
    call dyn%generalised_force(t, q_dy, 0.0_wp * q_dy, g, err)
    if (.not. err%ok()) return
    dq(1:dyn%model%n_rh, :) = 0.0_wp
    dq(dyn%model%n_rh + 1:, :) = shapes
    allocate(node_shapes(dyn%model%n_x, size(shapes, 2)))
    call dyn%kin%apply_df_many(dyn%model, dq, node_shapes)
  end subroutine nodal_shapes
end module dynamics_buckling_krylov
