!> The basis of a reduced model, dq_dy = V eta (docs/theory.md section 9): the M0-normalised
!> lowest modes at a configuration, how many of them to keep, and how to follow them when the
!> configuration changes (mode tracking by the modal assurance criterion, MAC).
module reduction_basis
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_INPUT, ERR_NUMERIC
  use core_strings, only: int_str, real_str
  use core_linalg, only: chol_factor, chol_solve, lu_factor, lu_solve
  use reduction_krylov, only: k0_factor, k0_solve
  use dynamics_static, only: has_loads
  use reduction_eigen, only: lowest_modes
  use dynamics_system, only: dynamics_t
  use model_system, only: model_t
  use model_control, only: ACT_MODE
  use model_kinematics, only: kin_state_t
  use reduction_modal, only: modal_result_t, modal_analysis
  implicit none
  private
  public :: basis_spec_t, basis_t, compute_basis, track_modes, BANDWIDTH_FRACTION, &
    held_joint_basis, held_joints, keep_stiffness

  !> Share of the prescribed acceleration's energy that defines the motion's bandwidth.
  real(wp), parameter :: BANDWIDTH_FRACTION = 0.99_wp
  real(wp), parameter :: TWO_PI = 6.28318530717958647692_wp

  !> How the basis is chosen (the &reduction group).
  type :: basis_spec_t
    character(len=8) :: selection = 'count'   !< 'count', 'cutoff' or 'auto'
    integer :: n_modes = 0
    real(wp) :: cutoff_hz = 0.0_wp
    real(wp) :: auto_factor = 0.0_wp
    character(len=8) :: eigensolver = 'auto'
    !> Dynamic coordinates (q_dy indices) held in the basis (joints under control, see
    !> held_joint_basis); empty: the modes of the free structure.
    integer, allocatable :: held(:)
  end type basis_spec_t

  type :: basis_t
    real(wp), allocatable :: v(:, :)           !< (n_dy, k), M0-normalised
    real(wp), allocatable :: frequency_hz(:)   !< (k) at the basis configuration
    real(wp), allocatable :: q_ref(:)          !< q_dy = q_ref + V eta
    !> Cholesky factor of the tangent stiffness K0, for the static correction; empty when K0
    !> is not positive definite (a mechanism mode), which disables the correction.
    real(wp), allocatable :: k_chol(:, :)
    !> On the Krylov path instead: the element Jacobians at the basis configuration, from
    !> which the sparse K0 is factored where needed (reduction_krylov's k0_solve); empty when
    !> K0 is singular.
    real(wp), allocatable :: de_k0(:)
    integer :: k0_serial = -1                  !< see k0_solve
    real(wp) :: time = 0.0_wp                  !< when the basis was made (trajectory time)
    real(wp) :: cutoff_hz = 0.0_wp             !< cut-off used by 'cutoff' and 'auto'
    real(wp) :: bandwidth_hz = 0.0_wp          !< motion bandwidth used by 'auto'
    character(len=:), allocatable :: reason    !< why k modes, in words
    character(len=8) :: solver = ''
  contains
    procedure :: k => basis_k
    procedure :: has_k0 => basis_has_k0
    procedure :: static_solve => basis_static_solve
  end type basis_t

contains

  integer function basis_k(this)
    class(basis_t), intent(in) :: this
    basis_k = 0
    if (allocated(this%v)) basis_k = size(this%v, 2)
  end function basis_k

  !> Whether the basis can give K0^-1 r (static correction and error estimate).
  logical function basis_has_k0(this)
    class(basis_t), intent(in) :: this
    basis_has_k0 = allocated(this%k_chol) .or. allocated(this%de_k0)
  end function basis_has_k0

  !> dq = K0^-1 r with K0 at the basis configuration (dense Cholesky factor or sparse); ok
  !> false (dq = 0) where there is none or the sparse K0 could not be factored again.
  subroutine basis_static_solve(this, dyn, r, dq, ok)
    class(basis_t), intent(inout) :: this
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: r(:)
    real(wp), intent(out) :: dq(:)
    logical, intent(out) :: ok
    dq = r
    ok = this%has_k0()
    if (.not. ok) dq = 0.0_wp
    if (allocated(this%k_chol)) then
      call chol_solve(this%k_chol, dq)
    else if (allocated(this%de_k0)) then
      call k0_solve(dyn, this%de_k0, this%k0_serial, r, dq, ok)
    end if
  end subroutine basis_static_solve

  !> Keep what the static solve needs from the modal analysis `modes` just made at the basis
  !> configuration (the kinematics of dyn still there).
  subroutine keep_stiffness(basis, dyn, modes)
    type(basis_t), intent(inout) :: basis
    type(dynamics_t), intent(inout) :: dyn
    type(modal_result_t), intent(in) :: modes
    integer :: info
    if (allocated(basis%k_chol)) deallocate(basis%k_chol)
    if (allocated(basis%de_k0)) deallocate(basis%de_k0)
    if (allocated(modes%k0)) then
      basis%k_chol = modes%k0
      call chol_factor(basis%k_chol, info)
      if (info /= 0) deallocate(basis%k_chol)
    else if (has_loads(dyn)) then
      ! K_T is K0 plus the loads' stiffness, which the sparse factors do not hold.
      return
    else if (k0_factor(dyn, dyn%kin%de_val)) then
      basis%de_k0 = dyn%kin%de_val
      basis%k0_serial = dyn%aug%newton_serial
    end if
  end subroutine keep_stiffness

  !> The basis at (t, q_dy) of `dyn` with the prescribed modes held (at `held` when given,
  !> else at their motion's value at t). k follows the spec. The kinematic state of dyn is
  !> restored afterwards so that a run can go on from where it was.
  subroutine compute_basis(dyn, spec, t, q_dy, held, basis, err)
    type(dynamics_t), intent(inout) :: dyn
    type(basis_spec_t), intent(in) :: spec
    real(wp), intent(in) :: t, q_dy(:)
    real(wp), intent(in), optional :: held(:)
    type(basis_t), intent(out) :: basis
    type(error_t), intent(out) :: err
    type(modal_result_t) :: modes
    type(kin_state_t) :: kin_saved
    real(wp) :: cutoff
    integer :: k, n_dy, nev
    logical :: held_joints_given

    n_dy = dyn%model%n_dy
    if (spec%selection == 'count' .and. (spec%n_modes < 1 .or. spec%n_modes > n_dy)) then
      call err%set(ERR_INPUT, 'group &reduction: variable ''n_modes'': n_modes = ' // &
        int_str(spec%n_modes) // ' must be between 1 and the number of dynamic coordinates (' &
        // int_str(n_dy) // ')')
      return
    end if
    ! The solution (x, q) the run goes on from; the factors are renewed by its next solve.
    call dyn%kin%save_state(kin_saved)
    if (present(held)) dyn%held_rh = held
    call choose_cutoff(dyn, spec, basis, err)
    if (.not. err%ok()) return
    cutoff = basis%cutoff_hz
    ! Ask for enough modes to decide k; with a cut-off, double until one lies above it.
    nev = min(n_dy, 8)
    if (spec%selection == 'count') nev = spec%n_modes
    held_joints_given = .false.
    if (allocated(spec%held)) held_joints_given = size(spec%held) > 0
    do
      call modal_analysis(dyn, t, q_dy, nev, modes, err, solver=spec%eigensolver, &
        dense=held_joints_given, for_basis=.true.)
      if (.not. err%ok()) exit
      if (spec%selection == 'count' .or. nev == n_dy) exit
      if (modes%frequency_hz(nev) > cutoff) exit
      nev = min(n_dy, 2 * nev)
    end do
    if (err%ok()) call keep_stiffness(basis, dyn, modes)
    if (allocated(dyn%held_rh)) deallocate(dyn%held_rh)
    call dyn%kin%restore_state(kin_saved)
    if (.not. err%ok()) return

    select case (spec%selection)
    case ('count')
      k = spec%n_modes
      basis%reason = 'n_modes = ' // int_str(k) // ' given'
    case default
      k = count(modes%frequency_hz <= cutoff)
      basis%reason = int_str(k) // ' of ' // int_str(n_dy) // ' modes below ' // &
        real_str(cutoff) // ' Hz'
      if (spec%selection == 'auto') basis%reason = basis%reason // ' = auto_factor ' // &
        real_str(spec%auto_factor) // ' x motion bandwidth ' // real_str(basis%bandwidth_hz) &
        // ' Hz (' // real_str(100 * BANDWIDTH_FRACTION) // '% of the acceleration energy)'
      if (k == 0 .and. spec%selection == 'cutoff') then
        call err%set(ERR_INPUT, 'group &reduction: no mode below cutoff_hz = ' // &
          real_str(cutoff) // ' Hz (the lowest is ' // real_str(modes%frequency_hz(1)) // &
          ' Hz): raise cutoff_hz or give n_modes')
        return
      end if
      if (k == 0) then
        k = 1
        basis%reason = basis%reason // '; none below it, so the lowest mode is kept'
      end if
    end select
    if (allocated(spec%held)) then
      if (size(spec%held) > 0) then
        call held_joint_basis(modes%k0, modes%m0, spec%held, k, spec%eigensolver, basis%v, &
          basis%frequency_hz, err)
        if (.not. err%ok()) return
        basis%reason = basis%reason // ', ' // int_str(size(spec%held)) // ' joints held'
      end if
    end if
    if (.not. allocated(basis%v)) then
      basis%v = modes%shapes(:, 1:k)
      basis%frequency_hz = modes%frequency_hz(1:k)
    end if
    basis%q_ref = q_dy
    basis%time = t
    basis%solver = modes%solver
  end subroutine compute_basis

  !> A basis for joints under feedback control (Craig-Bampton's fixed-interface idea): the
  !> unit motions of the held joint coordinates `held`, each with the static deflection the
  !> rest takes, Psi = [I; -K_FF^-1 K_FL], and the lowest k - n_L modes with those joints held,
  !> K_FF phi = omega^2 M_FF phi. A stiff controller nearly holds its joint, and links held at
  !> their joints deflect in their held modes, which the free-joint modes span poorly. The
  !> columns are then turned into the reduced system's own modes (Ritz vectors: M-orthonormal,
  !> ordered by frequency), so the basis keeps the form of a modal one.
  subroutine held_joint_basis(k0, m0, held, k, solver, v, frequency_hz, err)
    real(wp), intent(in) :: k0(:, :), m0(:, :)
    integer, intent(in) :: held(:), k
    character(len=*), intent(in) :: solver
    real(wp), allocatable, intent(out) :: v(:, :), frequency_hz(:)
    type(error_t), intent(inout) :: err
    real(wp), allocatable :: psi(:, :), kff(:, :), lambda(:), phi(:, :), v0(:, :), y(:, :)
    integer, allocatable :: free(:), ipiv(:)
    logical :: is_held(size(k0, 1))
    integer :: n, nl, info, j
    n = size(k0, 1)
    nl = size(held)
    if (k < nl .or. k > n) then
      call err%set(ERR_INPUT, 'group &reduction: with joints = ''held'', n_modes = ' // &
        int_str(k) // ' must be between the number of held joints (' // int_str(nl) // &
        ') and of dynamic coordinates (' // int_str(n) // ')')
      return
    end if
    is_held = .false.
    is_held(held) = .true.
    free = pack([(j, j = 1, n)], .not. is_held)
    allocate(v0(n, k), source=0.0_wp)
    kff = k0(free, free)
    psi = -k0(free, held)
    allocate(ipiv(size(free)))
    call lu_factor(kff, ipiv, info)
    if (info /= 0) then
      call err%set(ERR_NUMERIC, 'group &reduction: joints = ''held'': the structure with ' // &
        'the controlled joints held has no stiffness against some motion (a free joint ' // &
        'without a controller, or a mechanism)')
      return
    end if
    call lu_solve(kff, ipiv, psi)
    do j = 1, nl
      v0(held(j), j) = 1.0_wp
      v0(free, j) = psi(:, j)
    end do
    if (k > nl) then
      call lowest_modes(k0(free, free), m0(free, free), k - nl, solver, lambda, phi, err)
      if (.not. err%ok()) return
      v0(free, nl + 1:) = phi
    end if
    call lowest_modes(matmul(transpose(v0), matmul(k0, v0)), &
      matmul(transpose(v0), matmul(m0, v0)), k, 'lapack', lambda, y, err)
    if (.not. err%ok()) return
    v = matmul(v0, y)
    frequency_hz = sign(sqrt(abs(lambda)), lambda) / TWO_PI
  end subroutine held_joint_basis

  !> The dynamic coordinates that controllers drive through a joint (&reduction joints =
  !> 'held'), each once.
  subroutine held_joints(model, held, err)
    type(model_t), intent(in) :: model
    integer, allocatable, intent(out) :: held(:)
    type(error_t), intent(inout) :: err
    integer :: k, j, i
    allocate(held(0))
    do k = 1, size(model%controllers)
      associate (c => model%controllers(k))
        do i = 1, size(c%act_index)
          if (c%act_kind(i) /= ACT_MODE) cycle
          j = model%modes(c%act_index(i))%q - model%n_rh
          if (.not. any(held == j)) held = [held, j]
        end do
      end associate
    end do
    if (size(held) == 0) call err%set(ERR_INPUT, 'group &reduction: variable ''joints'': ' // &
      '''held'' holds the joints that controllers drive, but no &controller drives a hinge ' // &
      'or truss')
  end subroutine held_joints

  !> The cut-off frequency of 'cutoff' and 'auto' selections.
  subroutine choose_cutoff(dyn, spec, basis, err)
    type(dynamics_t), intent(in) :: dyn
    type(basis_spec_t), intent(in) :: spec
    type(basis_t), intent(inout) :: basis
    type(error_t), intent(inout) :: err
    integer :: i
    select case (spec%selection)
    case ('cutoff')
      basis%cutoff_hz = spec%cutoff_hz
    case ('auto')
      basis%bandwidth_hz = 0.0_wp
      do i = 1, dyn%model%n_motions
        associate (b => dyn%model%motions(i)%bandwidth_hz(BANDWIDTH_FRACTION))
          if (b < 0) then
            ! An unbounded spectrum (the velocity step of a ramp): no mode count follows.
            call err%set(ERR_INPUT, 'group &reduction: auto_factor needs motions of finite ' // &
              'bandwidth; motion ''' // dyn%model%motions(i)%label // ''' has none (a ' // &
              'velocity step): give n_modes or cutoff_hz')
            return
          end if
          basis%bandwidth_hz = max(basis%bandwidth_hz, b)
        end associate
      end do
      if (.not. basis%bandwidth_hz > 0) then
        call err%set(ERR_INPUT, 'group &reduction: auto_factor needs a prescribed motion ' // &
          'that moves (all motions are constant): give n_modes or cutoff_hz')
        return
      end if
      basis%cutoff_hz = spec%auto_factor * basis%bandwidth_hz
    case ('count')
    case default
      call err%set(ERR_INPUT, 'group &reduction: unknown selection ''' // &
        trim(spec%selection) // '''')
    end select
  end subroutine choose_cutoff

  !> Order and signs of the candidate modes w (n_dy, nc) to follow the current basis v
  !> (n_dy, k): column i of the result is the candidate with the largest MAC against v(:, i)
  !> (each used once), with its sign flipped so that v(:, i)^T M w_i > 0. `mac(i)` is that MAC.
  !> mv = M v and mw = M w with the current mass matrix.
  subroutine track_modes(v, w, mv, mw, tracked, mac, pick, err)
    real(wp), intent(in) :: v(:, :), w(:, :), mv(:, :), mw(:, :)
    real(wp), intent(out) :: tracked(:, :)
    real(wp), intent(out) :: mac(:)
    integer, intent(out) :: pick(:)
    type(error_t), intent(inout) :: err
    real(wp) :: cross(size(v, 2), size(w, 2)), nv(size(v, 2)), nw(size(w, 2))
    real(wp) :: macs(size(v, 2), size(w, 2))
    logical :: free(size(w, 2))
    integer :: i, j
    if (size(w, 2) < size(v, 2)) then
      call err%set(ERR_NUMERIC, 'mode tracking: fewer candidate modes than basis vectors')
      return
    end if
    cross = matmul(transpose(v), mw)
    do i = 1, size(v, 2)
      nv(i) = dot_product(v(:, i), mv(:, i))
    end do
    do j = 1, size(w, 2)
      nw(j) = dot_product(w(:, j), mw(:, j))
    end do
    macs = cross**2 / spread(nv, 2, size(w, 2)) / spread(nw, 1, size(v, 2))
    free = .true.
    do i = 1, size(v, 2)
      j = maxloc(macs(i, :), dim=1, mask=free)
      free(j) = .false.
      pick(i) = j
      mac(i) = macs(i, j)
      tracked(:, i) = sign(1.0_wp, cross(i, j)) * w(:, j)
    end do
  end subroutine track_modes
end module reduction_basis
