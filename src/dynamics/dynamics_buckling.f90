!> Linearised buckling (docs/theory.md, section 7): with the prescribed modes locked, the
!> tangent stiffness at a fixed configuration is affine in the load factor,
!>   K_T(lambda) = K0 + lambda K_G,   K_G = (K_T(lambda_ref) - K0) / lambda_ref,
!> K0 the structural part and K_G the load (geometric) part per unit load factor, both from
!> dynamics_static's tangent_stiffness (K_T at load factor 0 is K0 exactly: its load part is
!> skipped). Buckling load multipliers mu and shapes v solve (K0 + mu K_G) v = 0. With K0
!> positive definite this is the symmetric-definite problem
!>   -K_G v = theta K0 v,   theta = 1 / mu,
!> (LAPACK dsygvd through sym_gen_eig): every theta is real whatever the sign pattern of K_G,
!> the largest positive theta is the lowest positive mu, a negative theta a multiplier of the
!> reversed load, and a theta of zero (a direction the loads do not soften or stiffen, e.g.
!> axial stretching) a multiplier at infinity. Only positive multipliers are reported, lowest
!> first: a load that only pulls (tension everywhere) has none, and the result is then empty.
!> Moments fixed in space make K_G unsymmetric: then only real theta of that full problem count
!> (divergence, as the static stability test; divergence_multipliers).
!> Since the load part is linear in the load at a fixed configuration, lambda_ref matters only
!> through the round-off of the difference tangent. Load that elastic (calculable) modes carry
!> (an indeterminate load path) deforms the configuration before it stresses them: its share
!> comes from the change of the tangent along the linear pre-buckling response
!> (path_stiffness).
!>
!> Supports the model cannot carry (a statically indeterminate column: the formulation needs
!> statically determinate structures, docs/theory.md section 12) can be added to the buckling
!> problem alone as nodal coordinates held at zero in the shape (`held`): the problem is then
!> solved on the null space of those rows of DF_dy. The pre-buckling reactions of such
!> supports are zero (a straight column), so the load part is unchanged.
module dynamics_buckling
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_INPUT, ERR_MODEL, ERR_NUMERIC
  use core_linalg, only: sym_gen_eig, chol_factor, chol_solve, gen_eig_values
  use core_strings, only: int_str
  use core_sort, only: sort_by_value
  use dynamics_system, only: dynamics_t
  use dynamics_static, only: tangent_stiffness, load_force
  use dynamics_static_krylov, only: difference_step
  use dynamics_buckling_krylov, only: krylov_buckling, krylov_buckling_applies
  implicit none
  private
  public :: buckling_result_t, buckling_analysis, THETA_CUTOFF

  !> theta = 1/mu below THETA_CUTOFF times the largest |theta| counts as zero (mu at infinity):
  !> the round-off of the central-difference K_G is about 1e-11 of its largest entries, while
  !> the k-th Euler multiplier of a column is k^2 times the first, so real multipliers stay
  !> above the cutoff up to k = 1e4.
  real(wp), parameter :: THETA_CUTOFF = 1.0e-8_wp
  !> solver = 'auto' takes the matrix-free path (dynamics_buckling_krylov) where it applies
  !> above this many dynamic coordinates, as statics does (dynamics_static's KRYLOV_ABOVE).
  integer, parameter :: KRYLOV_ABOVE = 40
  !> The load part of the tangent is differenced as K_T(lambda) - K0 (the load force is
  !> evaluated as the generalised force plus the structure's stresses), so it carries the
  !> round-off of K0, about 1e-15 of its largest entries: a load part below RESOLVED of K0
  !> (a 1e-12 N load, or a tiny load_factor) would be mostly round-off, and silently wrong
  !> multipliers came of it. Being linear in the load factor at a fixed configuration, it
  !> is then differenced again at a load factor scaled up to bring it to the size of K0, at
  !> most MAX_RESCALES times by at most MAX_RESCALE each (a load part that stays below is
  !> none: loads the configuration does not turn, e.g. forces on a linear spring).
  real(wp), parameter :: RESOLVED = 1.0e-5_wp, MAX_RESCALE = 1.0e12_wp
  integer, parameter :: MAX_RESCALES = 6
  !> Bounds of &buckling load_factor (its reciprocal the upper one): beyond them the loads
  !> themselves would underflow or overflow.
  real(wp), parameter :: MIN_LAMBDA_REF = 1.0e-30_wp

  !> Result of one buckling analysis; n = the number of positive multipliers kept.
  type :: buckling_result_t
    real(wp), allocatable :: load_factor(:)     !< (n) multipliers mu of the loads, lowest first
    real(wp), allocatable :: shapes(:, :)       !< (n_dy, n), unit largest nodal translation
    real(wp), allocatable :: node_shapes(:, :)  !< (n_x, n) nodal: DF_dy v, same scaling
    real(wp), allocatable :: k0(:, :), kg(:, :) !< K0 and K_G (per unit load factor)
    !> multipliers of the reversed load left out (-1: not counted, the matrix-free path)
    integer :: n_negative = 0
    !> complex theta left out (moments fixed in space: no divergence in their directions)
    integer :: n_complex = 0
    !> the load factor K_G was differenced at: &buckling load_factor, or above it where the
    !> load part would have been lost in the round-off of K0 (RESOLVED)
    real(wp) :: reference_load_factor = 1.0_wp
  end type buckling_result_t

contains

  !> Buckling multipliers at (t, q_dy) (the prescribed modes locked at t): at most n_modes
  !> of them, lowest first, K_G differenced at load factor lambda_ref. dyn%load_factor is
  !> restored on return.
  !> `held`: nodal coordinate indices (model%node_coord) held at zero in the shapes.
  !> `solver`: 'dense', 'krylov' (matrix-free, where dynamics_buckling_krylov applies) or
  !> 'auto' (the default: krylov where it applies above KRYLOV_ABOVE coordinates).
  subroutine buckling_analysis(dyn, t, q_dy, n_modes, lambda_ref, res, err, held, solver)
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: t, q_dy(:), lambda_ref
    integer, intent(in) :: n_modes
    type(buckling_result_t), intent(out) :: res
    type(error_t), intent(out) :: err
    integer, intent(in), optional :: held(:)
    character(len=*), intent(in), optional :: solver
    character(len=:), allocatable :: why_not
    logical :: krylov
    real(wp), allocatable :: kt(:, :), a(:, :), theta(:), v(:, :), z(:, :), k0z(:, :), kgz(:, :)
    real(wp) :: saved, big, lambda, ratio
    integer :: n, info, i, nk, nz, attempt
    integer, allocatable :: keep(:)
    logical, allocatable :: real_theta(:)
    logical :: unsymmetric
    n = dyn%model%n_dy
    if (n_modes < 1) then
      call err%set(ERR_INPUT, 'group &buckling: variable ''n_modes'' must be at least 1')
      return
    end if
    if (lambda_ref <= 0) then
      call err%set(ERR_INPUT, 'group &buckling: variable ''load_factor'' must be positive')
      return
    end if
    if (lambda_ref < MIN_LAMBDA_REF .or. lambda_ref > 1 / MIN_LAMBDA_REF) then
      call err%set(ERR_INPUT, 'group &buckling: variable ''load_factor'' must lie within ' // &
        '1e-30 to 1e30 (the load stiffness is linear in it: the default 1 serves)')
      return
    end if
    if (n == 0) then
      call err%set(ERR_INPUT, 'group &buckling: the model has no dynamic coordinate ' // &
        '(everything is fixed or prescribed), so nothing can buckle')
      return
    end if
    ! A &force with a time_law is a load too (held in load_motion, not in force): statics
    ! and buckling take it at its value at t = 0.
    if (.not. (any(dyn%model%force /= 0) .or. any(dyn%model%gravity /= 0) .or. &
        size(dyn%model%moment_lambda) > 0 .or. size(dyn%model%load_motion) > 0)) then
      call err%set(ERR_INPUT, 'group &buckling: the scene has no load (no &force and no ' // &
        'gravity) to take the buckling multipliers of')
      return
    end if
    why_not = krylov_buckling_applies(dyn, present(held))
    krylov = len(why_not) == 0 .and. n > KRYLOV_ABOVE
    if (present(solver)) then
      if (solver == 'dense') krylov = .false.
      if (solver == 'krylov') then
        if (len(why_not) > 0) then
          call err%set(ERR_INPUT, 'group &buckling: variable ''solver'' = ''krylov'' does ' // &
            'not apply: ' // why_not // ' (use ''dense'' or ''auto'')')
          return
        end if
        krylov = .true.
      end if
    end if
    if (krylov) then
      call krylov_buckling(dyn, t, q_dy, n_modes, lambda_ref, THETA_CUTOFF, theta, &
        res%shapes, res%node_shapes, err, RESOLVED, MAX_RESCALE, MAX_RESCALES, &
        res%reference_load_factor)
      if (.not. err%ok()) return
      nk = min(n_modes, size(theta))
      res%load_factor = 1 / theta(1:nk)
      res%shapes = res%shapes(:, 1:nk)
      res%node_shapes = res%node_shapes(:, 1:nk)
      res%n_negative = -1
      call normalise(dyn, res)
      return
    end if
    allocate(res%k0(n, n), kt(n, n))
    saved = dyn%load_factor
    dyn%load_factor = 0.0_wp
    call tangent_stiffness(dyn, t, q_dy, res%k0, err)
    lambda = lambda_ref
    do attempt = 1, MAX_RESCALES + 1
      if (.not. err%ok()) exit
      dyn%load_factor = lambda
      call tangent_stiffness(dyn, t, q_dy, kt, err)
      if (.not. err%ok()) exit
      ! K0 = 0 (a mechanism, refused below): no round-off to resolve against.
      if (maxval(abs(kt - res%k0)) >= RESOLVED * maxval(abs(res%k0)) .or. &
        attempt > MAX_RESCALES) exit
      ratio = maxval(abs(kt - res%k0)) / maxval(abs(res%k0))
      lambda = lambda * rescale(ratio)
    end do
    if (err%ok()) then
      res%kg = (kt - res%k0) / lambda
      call path_stiffness(dyn, t, q_dy, res%k0, res%kg, err)
    end if
    dyn%load_factor = saved
    if (.not. err%ok()) then
      call err%prefix('buckling analysis: ')
      return
    end if
    ! Symmetric for conservative loads (the symmetrisation removes difference noise). Of a
    ! moment fixed in space, not conservative in 3D, the whole K_G enters: its symmetric part
    ! gave the roll-up by an end moment a multiplier of 0.664 where the load path stays stable
    ! to the full load (divergence_multipliers).
    res%reference_load_factor = lambda
    unsymmetric = size(dyn%model%moment_lambda) > 0
    if (.not. unsymmetric) res%kg = 0.5_wp * (res%kg + transpose(res%kg))
    z = identity(n)
    if (present(held)) then
      do i = 1, size(held)
        call restrict(z, matmul(dyn%kin%df(held(i), dyn%model%n_rh + 1:), z), &
          maxval(abs(dyn%kin%df(:, dyn%model%n_rh + 1:))))
      end do
    end if
    nz = size(z, 2)
    k0z = matmul(transpose(z), matmul(res%k0, z))
    kgz = matmul(transpose(z), matmul(res%kg, z))
    allocate(a, source=k0z)
    call chol_factor(a, info)
    if (info /= 0) then
      call err%set(ERR_MODEL, 'buckling analysis: the structural stiffness K0 is not ' // &
        'positive definite (a mechanism: a dynamic coordinate without stiffness, e.g. a ' // &
        'released hinge or a free rigid-body motion)')
      return
    end if
    allocate(theta(nz), v(nz, nz), real_theta(nz))
    real_theta = .true.
    if (unsymmetric) then
      call divergence_multipliers(kgz, k0z, theta, v, real_theta, big, info)
      res%n_complex = count(.not. real_theta)
    else
      call sym_gen_eig(-kgz, k0z, theta, v, info)
    end if
    if (info /= 0) then
      call err%set(ERR_NUMERIC, 'buckling analysis: LAPACK ' // &
        trim(merge('dggev ', 'dsygvd', unsymmetric)) // ' failed (info = ' // &
        int_str(info) // ')')
      return
    end if
    if (.not. unsymmetric) then
      ! Rayleigh quotients of dsygvd's vectors: second-order accurate in the vector, free of
      ! the rounding of dsygvd's reduction with the Cholesky factor of an ill-conditioned K0.
      do i = 1, nz
        theta(i) = -dot_product(v(:, i), matmul(kgz, v(:, i))) / &
          dot_product(v(:, i), matmul(k0z, v(:, i)))
      end do
      big = maxval(abs(theta))
    end if
    allocate(keep(0))
    ! Largest theta first = lowest mu first (the polish may swap close neighbours: sort).
    do i = 1, nz
      if (real_theta(i) .and. theta(i) > THETA_CUTOFF * big) keep = [keep, i]
    end do
    res%n_negative = count(real_theta .and. theta < -THETA_CUTOFF * big)
    call sort_by_value(keep, -theta)
    nk = min(n_modes, size(keep))
    keep = keep(1:nk)
    res%load_factor = 1 / theta(keep)
    res%shapes = matmul(z, v(:, keep))
    res%node_shapes = matmul(dyn%kin%df(:, dyn%model%n_rh + 1:), res%shapes)
    call normalise(dyn, res)
  end subroutine buckling_analysis

  !> theta = 1/mu of -K_G v = theta K0 v with K_G unsymmetric (moments fixed in space), by
  !> LAPACK dggev. Buckling is then divergence, a real theta, as the static stability test
  !> decides it (dynamics_static's stable_tangent); a complex theta (is_real false) is no
  !> static critical load and is left out. big: the largest |theta|; a theta whose imaginary
  !> part is below THETA_CUTOFF of it counts as real (the round-off of the difference K_G).
  !> v: real eigenvectors (a complex pair's real and imaginary parts, unused).
  subroutine divergence_multipliers(kg, k0, theta, v, is_real, big, info)
    real(wp), intent(in) :: kg(:, :), k0(:, :)
    real(wp), intent(out) :: theta(:), v(:, :), big
    logical, intent(out) :: is_real(:)
    integer, intent(out) :: info
    real(wp) :: wi(size(theta))
    call gen_eig_values(-kg, k0, theta, wi, info, v)
    big = 0
    if (info /= 0) return
    big = maxval(abs(cmplx(theta, wi, wp)))
    is_real = abs(wi) <= THETA_CUTOFF * big
  end subroutine divergence_multipliers

  !> Adds to kg the change of the unloaded tangent along the linear pre-buckling response
  !> dq = K0^-1 (F(1) - F(0)) per unit load factor (F the loads' and elastic modes'
  !> generalised force, dynamics_static's load_force): the stresses the load puts into elastic
  !> (calculable) modes, which carry part of it where the load path is statically
  !> indeterminate, and their geometric stiffness (the leaf-spring guide: 18.36 N without it,
  !> 2 pi^2 EI / L^2 = 18.65 N). A central difference of K_T(q_dy + e dq) at load factor 0,
  !> the largest nodal step PATH_STEPS times the tangent's own difference step. Nothing to add
  !> without elastic modes (the dynamic modes' stresses are linear in q: no change of K_T)
  !> or where K0 is not positive definite (a mechanism, refused later).
  subroutine path_stiffness(dyn, t, q_dy, k0, kg, err)
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: t, q_dy(:), k0(:, :)
    real(wp), intent(inout) :: kg(:, :)
    type(error_t), intent(out) :: err
    real(wp), parameter :: PATH_STEPS = 100.0_wp
    real(wp) :: f0(size(q_dy)), dq(size(q_dy)), l(size(q_dy), size(q_dy)), saved, e, dx
    real(wp), allocatable :: kp(:, :), km(:, :)
    integer :: info
    if (dyn%model%n_elastic == 0) return
    saved = dyn%load_factor
    dyn%load_factor = 0.0_wp
    call load_force(dyn, t, q_dy, f0, err)
    dyn%load_factor = 1.0_wp
    if (err%ok()) call load_force(dyn, t, q_dy, dq, err)
    dyn%load_factor = 0.0_wp
    if (err%ok()) then
      dq = dq - f0
      l = k0
      call chol_factor(l, info)
      if (info == 0) then
        call chol_solve(l, dq)
        dx = maxval(abs(matmul(dyn%kin%df(:, dyn%model%n_rh + 1:), dq)))
        if (dx > 0) then
          e = PATH_STEPS * difference_step(dyn) / dx
          allocate(kp, km, mold=k0)
          call tangent_stiffness(dyn, t, q_dy + e * dq, kp, err, accurate=.true.)
          if (err%ok()) call tangent_stiffness(dyn, t, q_dy - e * dq, km, err, accurate=.true.)
          if (err%ok()) kg = kg + (kp - km) / (2 * e)
          ! Back at q_dy: the shapes take DF there.
          if (err%ok()) call dyn%evaluate_dense(t, q_dy, 0.0_wp * q_dy, f0, err)
        end if
      end if
    end if
    dyn%load_factor = saved
  end subroutine path_stiffness

  !> The factor that brings a load part `ratio` times the size of K0 to about its size.
  pure real(wp) function rescale(ratio) result(f)
    real(wp), intent(in) :: ratio
    f = MAX_RESCALE
    if (ratio > 1 / MAX_RESCALE) f = 1 / ratio
  end function rescale

  pure function identity(n) result(a)
    integer, intent(in) :: n
    real(wp) :: a(n, n)
    integer :: i
    a = 0
    do i = 1, n
      a(i, i) = 1
    end do
  end function identity

  !> Restrict the basis z (columns) to c^T z y = 0 by eliminating the component of y with the
  !> largest |c_j| (partial pivoting); a row already satisfied (c = 0 to round-off of `scale`,
  !> the size of DF_dy) changes nothing.
  subroutine restrict(z, c, scale)
    real(wp), allocatable, intent(inout) :: z(:, :)
    real(wp), intent(in) :: c(:), scale
    real(wp), allocatable :: e(:, :)
    integer :: m, j, k, col
    m = size(c)
    if (m == 0) return
    j = maxloc(abs(c), dim=1)
    if (abs(c(j)) <= 1.0e-12_wp * scale) return
    allocate(e(m, m - 1), source=0.0_wp)
    col = 0
    do k = 1, m
      if (k == j) cycle
      col = col + 1
      e(k, col) = 1
      e(j, col) = -c(k) / c(j)
    end do
    z = matmul(z, e)
  end subroutine restrict

  !> Scale each shape to a unit largest nodal translation, its largest translation component
  !> positive (a shape that moves no node: unit largest component instead).
  subroutine normalise(dyn, res)
    type(dynamics_t), intent(in) :: dyn
    type(buckling_result_t), intent(inout) :: res
    real(wp) :: s, d, c
    integer :: k, i, n_slot
    integer, allocatable :: ic(:)
    ! Translations: x, y and, in a spatial model, z (node_coord rows 1, 2, 4).
    n_slot = merge(3, 2, dyn%model%dim == 3)
    do k = 1, size(res%load_factor)
      s = 0
      c = 0
      do i = 1, size(dyn%model%node_coord, 2)
        ic = dyn%model%node_coord([1, 2, 4], i)
        ic = ic(1:n_slot)
        if (any(ic <= 0)) cycle
        d = norm2(res%node_shapes(ic, k))
        if (d > s) then
          s = d
          c = res%node_shapes(ic(maxloc(abs(res%node_shapes(ic, k)), dim=1)), k)
        end if
      end do
      if (s <= 0) then
        s = maxval(abs(res%shapes(:, k)))
        c = res%shapes(maxloc(abs(res%shapes(:, k)), dim=1), k)
      end if
      if (s <= 0) cycle
      s = sign(1 / s, c)
      res%shapes(:, k) = s * res%shapes(:, k)
      res%node_shapes(:, k) = s * res%node_shapes(:, k)
    end do
  end subroutine normalise
end module dynamics_buckling
