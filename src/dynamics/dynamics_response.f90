!> What flexure designers read off a static equilibrium (docs/theory.md section 6.2): the
!> reactions at fixed and prescribed coordinates, the tangent compliance of chosen nodes and
!> the natural frequencies, at each converged step.
!>
!> Reactions: at rest the nodal forces f (loads, weight, minus the stresses of elastic
!> elements) balance the stresses of the kinematic rows (rigid, prescribed, dynamic modes) at
!> the calculable coordinates, J_c^T sigma = f_c, which the LU factors of the kinematic
!> solution give at the cost of one transposed solve. The reaction at any other coordinate is
!> what the internal forces leave unbalanced there, R = D_x^T sigma - f.
!>
!> Compliance: a force df on the node's coordinates does work DF_n^T df on q_dy, so
!> dx_n = DF_n K_T^-1 DF_n^T df; rows of held coordinates of DF_n are zero, hence those rows
!> and columns of the compliance are zero. On the Newton-Krylov path (large models) K_T^-1 is
!> applied by GMRES on extrapolated products (dynamics_static_krylov), DF_n^T and DF_n by one
!> transposed and one plain solve of the kinematics: O(n) per component, no dense tangent.
!>
!> Per node the components are (x, y, phi) in a planar model and (x, y, z, rotation about x,
!> y, z) in a spatial one. There a node's small rotation in global axes is
!> d(theta) = 2 E(lambda) d(lambda), so its rows of DF_n are 2 E DF_lambda, and a moment M does
!> the work of the force 2 E^T M on lambda: the moment of a reaction r_lambda on the Euler
!> parameters is E r_lambda / 2 (E E^T = I; the normalisation's multiplier, along lambda,
!> drops out since E lambda = 0).
module dynamics_response
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_NUMERIC
  use core_linalg, only: lu_factor, lu_solve, sym_gen_eig
  use dynamics_system, only: dynamics_t
  use dynamics_static, only: tangent_stiffness, STABILITY_MARGIN
  use dynamics_static_krylov, only: krylov_statics_t
  use dynamics_frequencies, only: general_modes, is_symmetric, stability_scale
  use elements_rotation, only: euler_e
  implicit none
  private
  public :: static_response_t, node_rows

  real(wp), parameter :: PI = 4 * atan(1.0_wp)
  !> GMRES's relative residual for a compliance: its stiff directions (a leaf's tension) are
  !> 1e-4 of its soft one, so Newton's 1e-6 left them 1e-3 off.
  real(wp), parameter :: COMPLIANCE_TOL = 1.0e-10_wp

  type :: static_response_t
    !> Coordinates (the model's node_coord columns: x, y, phi, z, first Euler parameter; 0 if
    !> none) of the nodes whose reactions and compliances are kept.
    integer, allocatable :: reaction_coords(:, :), compliance_coords(:, :)
    integer :: n_frequencies = 0
    integer :: n_comp = 3                            !< 3 (planar) or 6 (spatial) per node
    !> (n_comp, node, step): fx, fy, mz or fx, fy, fz, mx, my, mz [N, N m]
    real(wp), allocatable :: reaction(:, :, :)
    real(wp), allocatable :: compliance(:, :, :, :)  !< (n_comp, n_comp, node, step)
    real(wp), allocatable :: frequency_hz(:, :)      !< (n_frequencies, step)
  contains
    procedure :: init => response_init
    procedure :: record => response_record
  end type static_response_t

contains

  subroutine response_init(this, reaction_coords, compliance_coords, n_frequencies, n_steps, &
      dim)
    class(static_response_t), intent(inout) :: this
    integer, intent(in) :: reaction_coords(:, :), compliance_coords(:, :)
    integer, intent(in) :: n_frequencies, n_steps, dim
    this%reaction_coords = reaction_coords
    this%compliance_coords = compliance_coords
    this%n_frequencies = n_frequencies
    this%n_comp = merge(6, 3, dim == 3)
    allocate(this%reaction(this%n_comp, size(reaction_coords, 2), n_steps))
    allocate(this%compliance(this%n_comp, this%n_comp, size(compliance_coords, 2), n_steps))
    allocate(this%frequency_hz(n_frequencies, n_steps))
    this%reaction = 0.0_wp
    this%compliance = 0.0_wp
    this%frequency_hz = 0.0_wp
  end subroutine response_init

  !> Step `step` at the equilibrium q_dy (dyn%load_factor and the prescribed values as the
  !> static analysis left them at that step). `krylov`: compliances without the dense tangent
  !> (when no frequencies need it anyway). `frequencies` false: the caller has them (the
  !> Krylov modes of a stable step), so they do not call for the dense tangent.
  subroutine response_record(this, dyn, t, q_dy, step, err, krylov, frequencies)
    class(static_response_t), intent(inout) :: this
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: t, q_dy(:)
    integer, intent(in) :: step
    type(error_t), intent(out) :: err
    logical, intent(in), optional :: krylov, frequencies
    real(wp), allocatable :: k(:, :)
    real(wp) :: r(dyn%model%n_x), acc(size(q_dy))
    logical :: was_locked, need_compliance, dense, need_frequencies
    integer :: i
    was_locked = dyn%locked
    dyn%locked = .true.
    need_compliance = size(this%compliance_coords, 2) > 0
    need_frequencies = this%n_frequencies > 0
    if (present(frequencies)) need_frequencies = need_frequencies .and. frequencies
    dense = need_frequencies
    if (present(krylov)) dense = dense .or. .not. krylov
    ! The tangent (2 or 4 n_dy evaluations) only when asked for; reactions need the nodal
    ! forces and kinematic factors of one evaluation (O(n): no dense mass matrix).
    if (.not. dense) then
      call dyn%generalised_force(t, q_dy, 0.0_wp * q_dy, acc, err)
      if (.not. err%ok()) then
        dyn%locked = was_locked
        return
      end if
      r = reactions(dyn)
      do i = 1, size(this%reaction_coords, 2)
        this%reaction(:, i, step) = node_reaction(dyn, r, this%reaction_coords(:, i), &
          this%n_comp)
      end do
      do i = 1, size(this%compliance_coords, 2)
        call compliance_krylov(dyn, t, q_dy, this%compliance_coords(:, i), this%n_comp, &
          this%compliance(:, :, i, step), err)
        if (.not. err%ok()) exit
      end do
      dyn%locked = was_locked
      return
    end if
    if (need_compliance .or. need_frequencies) then
      allocate(k(size(q_dy), size(q_dy)))
      call tangent_stiffness(dyn, t, q_dy, k, err, &
        accurate=need_compliance .or. dyn%model%n_elastic > 0)
    else
      call dyn%generalised_force(t, q_dy, 0.0_wp * q_dy, acc, err)
    end if
    if (err%ok()) then
      r = reactions(dyn)
      do i = 1, size(this%reaction_coords, 2)
        this%reaction(:, i, step) = node_reaction(dyn, r, this%reaction_coords(:, i), &
          this%n_comp)
      end do
      if (need_compliance) call compliance(dyn, k, this%compliance_coords, this%n_comp, &
        this%compliance(:, :, :, step), err)
    end if
    if (err%ok() .and. need_frequencies) &
      call lowest_frequencies(k, dyn%mbar, this%frequency_hz(:, step), err)
    dyn%locked = was_locked
  end subroutine response_record

  !> Reaction at every coordinate that is not calculable (0 at calculable ones) at the last
  !> evaluation of dyn, which must be at rest.
  function reactions(dyn) result(r)
    type(dynamics_t), intent(inout) :: dyn
    real(wp) :: r(dyn%model%n_x)
    real(wp) :: sigma(dyn%model%n_c, 1)
    real(wp), allocatable :: e(:), de(:, :)
    integer :: iel, j, row, nm
    associate (m => dyn%model)
      sigma(:, 1) = dyn%nodal_force(m%calc_coord)
      call dyn%kin%jacobian_solve(sigma, transposed=.true.)
      r = -dyn%nodal_force
      do iel = 1, m%n_elements
        associate (el => m%elements(iel)%e)
          nm = el%n_modes()
          allocate(e(nm), de(nm, size(el%dofs)))
          call el%evaluate(dyn%kin%x(el%dofs), e, de)
          do j = 1, nm
            row = m%modes(m%mode_first(iel) + j - 1)%row
            if (row > 0) r(el%dofs) = r(el%dofs) + de(j, :) * sigma(row, 1)
          end do
          deallocate(e, de)
        end associate
      end do
      r(m%calc_coord) = 0.0_wp
    end associate
  end function reactions

  !> A node's reaction from the per-coordinate reactions r: (x, y, phi) in the plane,
  !> (x, y, z, moment) in space; 0 where the node has no such coordinate.
  function node_reaction(dyn, r, ic, n_comp) result(g)
    type(dynamics_t), intent(in) :: dyn
    real(wp), intent(in) :: r(:)
    integer, intent(in) :: ic(:), n_comp
    real(wp) :: g(n_comp)
    integer :: a, il
    g = 0.0_wp
    do a = 1, 3
      if (first_three(ic, a, n_comp) > 0) g(a) = r(first_three(ic, a, n_comp))
    end do
    if (n_comp == 6) then
      il = ic(5)
      if (il > 0) g(4:6) = 0.5_wp * matmul(euler_e(dyn%kin%x(il:il + 3)), r(il:il + 3))
    end if
  end function node_reaction

  !> Rows of DF_dy for a node's components: d(x, y, phi) in the plane, d(x, y, z) and the
  !> global rotation 2 E(lambda) d(lambda) in space; zero rows where the node has none.
  function node_rows(dyn, ic, n_comp) result(d)
    type(dynamics_t), intent(in) :: dyn
    integer, intent(in) :: ic(:), n_comp
    real(wp) :: d(n_comp, dyn%model%n_dy)
    real(wp) :: g(dyn%model%n_x, n_comp)
    integer :: a
    g = node_weights(dyn, ic, n_comp)
    do a = 1, n_comp
      d(a, :) = matmul(g(:, a), dyn%kin%df(:, dyn%model%n_rh + 1:))
    end do
  end function node_rows

  !> The node's components as weights on the nodal coordinates, G with G^T dx = (its
  !> translations, its small rotation): unit columns in the plane, 2 E(lambda)^T on the Euler
  !> parameters in space (zero columns where the node has no such component).
  function node_weights(dyn, ic, n_comp) result(g)
    type(dynamics_t), intent(in) :: dyn
    integer, intent(in) :: ic(:), n_comp
    real(wp) :: g(dyn%model%n_x, n_comp)
    integer :: a, il
    g = 0.0_wp
    do a = 1, 3
      if (first_three(ic, a, n_comp) > 0) g(first_three(ic, a, n_comp), a) = 1.0_wp
    end do
    if (n_comp == 6) then
      il = ic(5)
      if (il > 0) g(il:il + 3, 4:6) = 2 * transpose(euler_e(dyn%kin%x(il:il + 3)))
    end if
  end function node_weights

  !> A node's compliance DF_n K_T^-1 DF_n^T on the Newton-Krylov path: DF_n^T by transposed
  !> solves of the kinematics at q_dy, K_T^-1 by GMRES on extrapolated products (the stiff
  !> terms' O(h^2) error would show in the soft directions), DF_n by solves at q_dy again.
  subroutine compliance_krylov(dyn, t, q_dy, ic, n_comp, c, err)
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: t, q_dy(:)
    integer, intent(in) :: ic(:), n_comp
    real(wp), intent(out) :: c(:, :)
    type(error_t), intent(out) :: err
    type(krylov_statics_t) :: kry
    real(wp) :: g(dyn%model%n_x, n_comp), rq(dyn%model%n_q), y(size(q_dy), n_comp)
    real(wp) :: dq(dyn%model%n_q, n_comp), dx(dyn%model%n_x, n_comp), f(size(q_dy))
    integer :: a, nr
    nr = dyn%model%n_rh
    c = 0.0_wp
    kry%extrapolate = .true.
    kry%tol = COMPLIANCE_TOL
    call kry%precondition(dyn, t, q_dy, err)
    if (.not. err%ok()) return
    g = node_weights(dyn, ic, n_comp)
    do a = 1, n_comp
      y(:, a) = 0.0_wp
      if (.not. any(g(:, a) /= 0)) cycle
      ! The products move the kinematics: DF^T is taken at q_dy each time.
      call dyn%generalised_force(t, q_dy, 0.0_wp * q_dy, f, err)
      if (.not. err%ok()) return
      call dyn%kin%apply_dft(dyn%model, g(:, a), rq)
      call kry%solve(dyn, t, q_dy, rq(nr + 1:), y(:, a), err)
      if (.not. err%ok()) then
        call err%prefix('static compliance: ')
        return
      end if
    end do
    call dyn%generalised_force(t, q_dy, 0.0_wp * q_dy, f, err)
    if (.not. err%ok()) return
    dq = 0.0_wp
    dq(nr + 1:, :) = y
    call dyn%kin%apply_df_many(dyn%model, dq, dx)
    do a = 1, n_comp
      c(a, :) = matmul(g(:, a), dx)
    end do
  end subroutine compliance_krylov

  !> Coordinate of a node's component a = 1..3: x, y, phi in the plane (n_comp = 3), x, y, z
  !> in space (node_coord rows 1, 2, 4); 0 if the node has none.
  pure integer function first_three(ic, a, n_comp) result(idx)
    integer, intent(in) :: ic(:), a, n_comp
    integer, parameter :: PLANAR(3) = [1, 2, 3], SPATIAL(3) = [1, 2, 4]
    idx = merge(ic(PLANAR(a)), ic(SPATIAL(a)), n_comp == 3)
  end function first_three

  subroutine compliance(dyn, k, coords, n_comp, c, err)
    type(dynamics_t), intent(in) :: dyn
    real(wp), intent(in) :: k(:, :)
    integer, intent(in) :: coords(:, :), n_comp
    real(wp), intent(out) :: c(:, :, :)
    type(error_t), intent(inout) :: err
    real(wp) :: dfn(n_comp, size(k, 1)), y(size(k, 1), n_comp), kf(size(k, 1), size(k, 1))
    real(wp) :: rcond
    integer :: i, info, ipiv(size(k, 1)), worst
    kf = k
    call lu_factor(kf, ipiv, info, rcond, worst)
    if (info /= 0 .or. rcond < 1.0e-13_wp) then
      call err%set(ERR_NUMERIC, 'static compliance: the tangent stiffness is singular ' // &
        '(a mechanism or a critical load): the compliance is unbounded')
      return
    end if
    do i = 1, size(coords, 2)
      dfn = node_rows(dyn, coords(:, i), n_comp)
      y = transpose(dfn)
      call lu_solve(kf, ipiv, y)
      c(:, :, i) = matmul(dfn, y)
    end do
  end subroutine compliance

  !> Lowest natural frequencies of K_T v = omega^2 Mbar v [Hz], lowest first; a negative
  !> omega^2 (an unstable equilibrium) is reported as a negative frequency,
  !> -sqrt(-omega^2)/(2 pi). An unsymmetric K_T (moments fixed in space) gives the full
  !> problem's modes (dynamics_frequencies), on which the stability test decides too.
  subroutine lowest_frequencies(k, mbar, f, err)
    real(wp), intent(in) :: k(:, :), mbar(:, :)
    real(wp), intent(out) :: f(:)
    type(error_t), intent(inout) :: err
    real(wp), allocatable :: lambda(:), v(:, :)
    integer :: info
    if (is_symmetric(k)) then
      allocate(lambda(size(k, 1)), v(size(k, 1), size(k, 1)))
      call sym_gen_eig(k, mbar, lambda, v, info)
    else
      call general_modes(k, mbar, size(f), STABILITY_MARGIN * stability_scale(k, mbar), &
        lambda, v, info)
    end if
    if (info /= 0) then
      call err%set(ERR_NUMERIC, 'static frequencies: the eigenvalue problem failed (is the ' // &
        'mass matrix positive definite?)')
      return
    end if
    f = sign(sqrt(abs(lambda(1:size(f)))), lambda(1:size(f))) / (2 * PI)
  end subroutine lowest_frequencies
end module dynamics_response
