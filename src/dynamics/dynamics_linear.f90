!> Linearised state-space model at a configuration or at a state along a run (docs/theory.md
!> 8.2): with the state
!> z = (dq_dy, dq_dy'), inputs u (forces or moments on node components) and outputs y (the
!> displacements or rotations of node components),
!>   z' = A z + B u,   y = C z + D u,
!>   A = [0, I; -M^-1 K, -M^-1 Cd],  B = [0; M^-1 W_u^T],  C = [W_y, 0],  D = 0,
!> M the reduced mass matrix, K the tangent stiffness (joints locked, or along the motion:
!> dynamics_static's tangent_stiffness or motion_tangent), Cd = -d(M a)/d(q_dy') the damping
!> and gyroscopic part (central differences in the velocity), and W the rows of DF_dy of the
!> chosen node components (dynamics_response's node_rows: a node's rotation in space is
!> 2 E(lambda) d(lambda), and a moment the matching generalised force).
module dynamics_linear
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_NUMERIC
  use core_linalg, only: lu_factor, lu_solve, chol_factor, chol_solve
  use dynamics_system, only: dynamics_t
  use dynamics_static, only: tangent_stiffness, motion_tangent
  use dynamics_response, only: node_rows
  implicit none
  private
  public :: linear_model_t, linearise

  !> One linearisation; n_z = 2 n_dy, or 2 k for a reduced model (k_reduced = k > 0).
  type :: linear_model_t
    real(wp) :: time = 0.0_wp
    integer :: k_reduced = 0
    real(wp), allocatable :: a(:, :), b(:, :), c(:, :), d(:, :)
  end type linear_model_t

contains

  !> The state-space model at (t, q_dy) at rest relative to the prescribed motions. `inputs`
  !> and `outputs` hold, per column, a node's coordinates (model%node_coord column) and in
  !> row NODE_SLOTS + 1 the component (1..3 planar x, y, phi; 1..6 spatial x, y, z and the
  !> rotations about x, y, z).
  !> `v_dy`: a state along a dynamic run (the motions moving, the structure with this
  !> velocity): K and Cd are then the derivatives at (q_dy, v_dy), whatever `along_motion`.
  !> `basis`: the model reduced to q_dy = q_ref + V eta (q_dy, v_dy the reconstructed state);
  !> the Galerkin projection M_r = V^T M V, K_r = V^T K V, Cd_r = V^T Cd V, W_r = W V, with
  !> the state's acceleration the reduced one, V eta'', so that it is the exact linearisation
  !> of the reduced equations V^T (F - Mbar V eta'') = 0 (docs/theory.md 8.2).
  !> `accel`: the state's acceleration when it is not the model's own (a test's reference).
  subroutine linearise(dyn, t, q_dy, inputs, outputs, along_motion, lin, err, v_dy, basis, &
      accel)
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: t, q_dy(:)
    integer, intent(in) :: inputs(:, :), outputs(:, :)
    logical, intent(in) :: along_motion
    type(linear_model_t), intent(out) :: lin
    type(error_t), intent(out) :: err
    real(wp), intent(in), optional :: v_dy(:), basis(:, :), accel(:)
    real(wp), allocatable :: k(:, :), m(:, :), cd(:, :), wu(:, :), wy(:, :), rhs(:, :), a0(:)
    integer, allocatable :: ipiv(:)
    integer :: n, info, i
    n = dyn%model%n_dy
    allocate(k(n, n))
    if (present(accel)) then
      a0 = accel
    else if (present(basis) .and. (along_motion .or. present(v_dy))) then
      call reduced_acceleration(dyn, t, q_dy, basis, a0, err, v_dy)
      if (.not. err%ok()) return
    end if
    if (present(v_dy) .or. along_motion) then
      if (allocated(a0)) then
        call motion_tangent(dyn, t, q_dy, k, err, v_dy, a0)
      else
        call motion_tangent(dyn, t, q_dy, k, err, v_dy)
      end if
    else
      call tangent_stiffness(dyn, t, q_dy, k, err)
    end if
    if (.not. err%ok()) return
    m = dyn%mbar
    call velocity_derivative(dyn, t, q_dy, along_motion .or. present(v_dy), cd, err, v_dy)
    if (.not. err%ok()) return
    wu = component_rows(dyn, inputs)
    wy = component_rows(dyn, outputs)
    if (present(basis)) then
      k = matmul(transpose(basis), matmul(k, basis))
      m = matmul(transpose(basis), matmul(m, basis))
      cd = matmul(transpose(basis), matmul(cd, basis))
      wu = matmul(wu, basis)
      wy = matmul(wy, basis)
      n = size(basis, 2)
      lin%k_reduced = n
    end if
    ! M^-1 [K, Cd, W_u^T] with one factorisation.
    allocate(rhs(n, 2 * n + size(inputs, 2)), ipiv(n))
    rhs(:, 1:n) = k
    rhs(:, n + 1:2 * n) = cd
    rhs(:, 2 * n + 1:) = transpose(wu)
    call lu_factor(m, ipiv, info)
    if (info /= 0) then
      call err%set(ERR_NUMERIC, 'linearisation: the mass matrix is singular (a dynamic ' // &
        'coordinate without inertia)')
      return
    end if
    call lu_solve(m, ipiv, rhs)
    lin%time = t
    allocate(lin%a(2 * n, 2 * n), source=0.0_wp)
    do i = 1, n
      lin%a(i, n + i) = 1.0_wp
    end do
    lin%a(n + 1:, 1:n) = -rhs(:, 1:n)
    lin%a(n + 1:, n + 1:) = -rhs(:, n + 1:2 * n)
    allocate(lin%b(2 * n, size(inputs, 2)), source=0.0_wp)
    lin%b(n + 1:, :) = rhs(:, 2 * n + 1:)
    allocate(lin%c(size(outputs, 2), 2 * n), source=0.0_wp)
    lin%c(:, 1:n) = wy
    allocate(lin%d(size(outputs, 2), size(inputs, 2)), source=0.0_wp)
  end subroutine linearise

  !> The acceleration of the reduced model's state, V eta'' with (V^T Mbar V) eta'' = V^T F
  !> = V^T Mbar a (a the full model's at the same state): off an equilibrium it, not a, is
  !> what multiplies dMbar/dq in the reduced equations.
  subroutine reduced_acceleration(dyn, t, q_dy, basis, a0, err, v_dy)
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: t, q_dy(:), basis(:, :)
    real(wp), allocatable, intent(out) :: a0(:)
    type(error_t), intent(out) :: err
    real(wp), intent(in), optional :: v_dy(:)
    real(wp) :: v(size(q_dy)), a(size(q_dy)), mr(size(basis, 2), size(basis, 2))
    real(wp) :: eta_dd(size(basis, 2))
    integer :: info
    logical :: was_locked
    v = 0.0_wp
    if (present(v_dy)) v = v_dy
    was_locked = dyn%locked
    dyn%locked = .false.
    call dyn%evaluate_dense(t, q_dy, v, a, err)
    dyn%locked = was_locked
    if (.not. err%ok()) return
    mr = matmul(transpose(basis), matmul(dyn%mbar, basis))
    eta_dd = matmul(transpose(basis), matmul(dyn%mbar, a))
    call chol_factor(mr, info)
    if (info /= 0) then
      call err%set(ERR_NUMERIC, 'linearisation: the reduced mass matrix V^T Mbar V is ' // &
        'singular')
      return
    end if
    call chol_solve(mr, eta_dd)
    a0 = matmul(basis, eta_dd)
  end subroutine reduced_acceleration

  !> Cd = -d(Mbar a)/d(q_dy') at q_dy' = 0 by central differences (Richardson-extrapolated):
  !> stiffness-proportional damping and, along a motion, the gyroscopic terms.
  subroutine velocity_derivative(dyn, t, q_dy, along_motion, cd, err, v_dy)
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: t, q_dy(:)
    logical, intent(in) :: along_motion
    real(wp), allocatable, intent(out) :: cd(:, :)
    type(error_t), intent(out) :: err
    real(wp), intent(in), optional :: v_dy(:)
    real(wp) :: v(size(q_dy)), v_base(size(q_dy)), a(size(q_dy)), f1(size(q_dy))
    real(wp) :: f2(size(q_dy)), h
    logical :: was_locked
    integer :: j
    allocate(cd(size(q_dy), size(q_dy)))
    was_locked = dyn%locked
    dyn%locked = .not. along_motion
    ! A velocity step small against the model's motion: 1e-6 of its size per second.
    h = 1.0e-6_wp * max(1.0e-3_wp, maxval(abs(dyn%model%x0)))
    v_base = 0.0_wp
    if (present(v_dy)) v_base = v_dy
    v = v_base
    do j = 1, size(q_dy)
      call difference(h, f1)
      if (err%ok()) call difference(2 * h, f2)
      if (.not. err%ok()) exit
      cd(:, j) = -(4 * f1 - f2) / 3
    end do
    if (err%ok()) call dyn%evaluate_dense(t, q_dy, v_base, a, err)
    dyn%locked = was_locked

  contains

    subroutine difference(hs, d)
      real(wp), intent(in) :: hs
      real(wp), intent(out) :: d(:)
      real(wp) :: fp(size(q_dy))
      v = v_base
      v(j) = v_base(j) + hs
      call dyn%evaluate_dense(t, q_dy, v, a, err)
      if (.not. err%ok()) return
      fp = matmul(dyn%mbar, a)
      v(j) = v_base(j) - hs
      call dyn%evaluate_dense(t, q_dy, v, a, err)
      if (.not. err%ok()) return
      d = (fp - matmul(dyn%mbar, a)) / (2 * hs)
      v = v_base
    end subroutine difference
  end subroutine velocity_derivative

  !> Rows of DF_dy of the chosen components: column i of `which` is a node's coordinates and,
  !> last, the component number; or, with component 0, a dynamic coordinate's index in q_dy
  !> first (a joint's angle or torque); or, with component -1, an element, its mode and 1 for
  !> the mode's stress (mode_row).
  function component_rows(dyn, which) result(w)
    type(dynamics_t), intent(in) :: dyn
    integer, intent(in) :: which(:, :)
    real(wp) :: w(size(which, 2), dyn%model%n_dy)
    real(wp), allocatable :: rows(:, :)
    integer :: i, n_comp, nc
    n_comp = merge(6, 3, dyn%model%dim == 3)
    nc = size(which, 1)
    do i = 1, size(which, 2)
      if (which(nc, i) == -1) then
        w(i, :) = mode_row(dyn, which(1, i), which(2, i), which(3, i) == 1)
        cycle
      end if
      if (which(nc, i) == 0) then
        ! A dynamic coordinate itself (a joint angle, or the torque on it): q_dy(which(1, i)).
        w(i, :) = 0.0_wp
        w(i, which(1, i)) = 1.0_wp
        cycle
      end if
      rows = node_rows(dyn, which(1:nc - 1, i), n_comp)
      w(i, :) = rows(which(nc, i), :)
    end do
  end function component_rows

  !> d e_j / d q_dy = De_j DF_dy of element iel's mode j at the current configuration, or with
  !> `stress` d sigma_j / d q_dy = (S De)_j DF_dy (sigma = S e; the unit row for a dynamic mode
  !> and S's row of the element's dynamic modes when all its modes are).
  function mode_row(dyn, iel, j, stress) result(w)
    type(dynamics_t), intent(in) :: dyn
    integer, intent(in) :: iel, j
    logical, intent(in) :: stress
    real(wp) :: w(dyn%model%n_dy)
    real(wp), allocatable :: e(:), de(:, :), s(:, :), r(:)
    associate (el => dyn%model%elements(iel)%e, nr => dyn%model%n_rh)
      allocate(e(el%n_modes()), de(el%n_modes(), size(el%dofs)))
      call el%evaluate(dyn%kin%x(el%dofs), e, de)
      if (stress) then
        allocate(s(el%n_modes(), el%n_modes()))
        call el%stiffness(s)
        r = matmul(s(j, :), de)
      else
        r = de(j, :)
      end if
      w = matmul(r, dyn%kin%df(el%dofs, nr + 1:))
    end associate
  end function mode_row
end module dynamics_linear
