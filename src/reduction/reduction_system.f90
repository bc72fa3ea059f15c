!> A reduced model (docs/theory.md section 9): q_dy = q_ref + V eta, the full non-linear
!> equations of motion evaluated by the full model and projected with V^T:
!>     (V^T Mbar V) eta'' = V^T gen_force.
!> It is an `ode2_system_t` in eta, so every integrator of flexmor advances it.
!>
!> Along the reduced trajectory it also measures what the reduction leaves out: the residual of
!> the full equations r = gen_force - Mbar V eta'' (zero when V spans all modes), reported as
!> its energy norm sqrt(r^T Mbar^-1 r), and as a displacement estimate: K0^-1 r is the
!> quasi-static response of the dropped modes (mode-acceleration method), whose largest nodal
!> translation is the estimate, and which the static correction adds to the output.
module reduction_system
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_MODEL, ERR_NUMERIC
  use core_linalg, only: chol_factor, chol_solve
  use model_system, only: model_t
  use model_kinematics, only: kin_state_t
  use dynamics_system, only: dynamics_t, check_finite
  use integrators_system, only: ode2_system_t, system_fd_jacobian, JACOBIAN_FD
  use reduction_basis, only: basis_t
  use reduction_expansion, only: expansion_set_t
  implicit none
  private
  public :: reduced_t

  !> What a measurement of the error indicators was taken at (expanded runs; the codes of
  !> /reduction/measured/kind).
  integer, parameter :: MEASURED_EXPANSION = 1  !< where the first expansion was made
  integer, parameter :: MEASURED_FARTHEST = 2   !< the farthest accepted state one served
  integer, parameter :: MEASURED_SAMPLE = 3     !< an output (estimate_samples)

  !> The exact measurements of the error indicators along an expanded run, in order.
  type :: measurements_t
    integer :: n = 0
    real(wp), allocatable :: time(:), residual(:), estimate(:)
    integer, allocatable :: kind(:)
  contains
    procedure :: add => measurements_add
    procedure :: clear => measurements_clear
  end type measurements_t

  type, extends(ode2_system_t) :: reduced_t
    type(dynamics_t) :: dyn                   !< the full model, evaluated at q_ref + V eta
    type(basis_t) :: basis
    logical :: static_correction = .false.
    !> Output index of each record call of the current integration (0: not an output time,
    !> e.g. a basis update that falls between outputs).
    integer, allocatable :: out_index(:)
    real(wp), allocatable :: eta_hist(:, :), eta_dot_hist(:, :)
    real(wp), allocatable :: residual(:)      !< sqrt(r^T Mbar^-1 r) at the output times
    real(wp), allocatable :: estimate(:)      !< largest nodal translation of K0^-1 r [m]
    logical :: has_estimate = .true.          !< false once a basis has no definite K0
    !> State at the last record call: where the next segment starts.
    real(wp), allocatable :: last_eta(:), last_eta_dot(:)
    !> With keep_bases (&linear times): every basis of the run, the first and each update
    !> (V, q_ref, time only), and per output which one the state is relative to.
    logical :: keep_bases = .false.
    type(basis_t), allocatable :: bases(:)
    integer, allocatable :: basis_of(:)
    !> evaluation = 'expanded' (reduction_system_expanded): evaluations from the expansion,
    !> which is redone where it goes stale. The error indicators are measured exactly where
    !> the first expansion is made, at the farthest accepted state each served and at
    !> estimate_samples outputs spread over the run; each output reports the latest
    !> measurement.
    logical :: expanded = .false.
    type(expansion_set_t) :: expansions
    integer :: estimate_samples = 10
    integer :: sample_every = 0                !< outputs between samples, 0: none
    type(measurements_t) :: measured
  contains
    procedure :: keep_basis => red_keep_basis
    procedure :: accel => red_accel
    procedure :: record => red_record
    procedure :: jacobian => red_jacobian
    procedure :: full_state => red_full_state
    procedure :: error_norm => red_error_norm
    procedure :: allocate_history => red_allocate_history
    procedure :: check_expansions => red_check_expansions
    procedure :: step_accepted => red_step_accepted
    procedure :: wants_steps => red_wants_steps
    procedure :: residual_max => red_residual_max
    procedure :: estimate_max => red_estimate_max
    !> Type-bound so that the submodule links to it: gfortran 12 emits no symbol for a
    !> private module procedure it has inlined.
    procedure :: indicators => red_indicators
  end type reduced_t

  interface
    !> Accelerations from the expansion, expanded anew (with the error indicators measured
    !> there, exactly) when the state has left its range (reduction_system_expanded).
    module subroutine expanded_accel(this, t, eta, eta_dot, a, err)
      class(reduced_t), intent(inout) :: this
      real(wp), intent(in) :: t, eta(:), eta_dot(:)
      real(wp), intent(out) :: a(:)
      type(error_t), intent(out) :: err
    end subroutine expanded_accel
    !> Compare each kept expansion (but skip) that served a state beyond where it was last
    !> compared with the exact model at the farthest such state (reduction_system_expanded).
    module subroutine red_check_expansions(this, skip)
      class(reduced_t), intent(inout) :: this
      integer, intent(in), optional :: skip
    end subroutine red_check_expansions
    !> An accepted step: with the expanded evaluation, the farthest state each expansion
    !> served (reduction_system_expanded).
    module subroutine red_step_accepted(this, t, q, v)
      class(reduced_t), intent(inout) :: this
      real(wp), intent(in) :: t, q(:), v(:)
    end subroutine red_step_accepted
    !> An output of the expanded evaluation (reduction_system_expanded).
    module subroutine expanded_store(this, kg, t, eta, eta_dot, q_dy, v_dy, err)
      type(reduced_t), intent(inout) :: this
      integer, intent(in) :: kg
      real(wp), intent(in) :: t, eta(:), eta_dot(:), q_dy(:), v_dy(:)
      type(error_t), intent(out) :: err
    end subroutine expanded_store
  end interface

contains

  !> The expanded evaluation keeps the farthest accepted state of each expansion.
  logical function red_wants_steps(this)
    class(reduced_t), intent(in) :: this
    red_wants_steps = this%expanded
  end function red_wants_steps

  !> The full model's coordinates and velocities of a reduced state.
  subroutine red_full_state(this, eta, eta_dot, q_dy, v_dy)
    class(reduced_t), intent(in) :: this
    real(wp), intent(in) :: eta(:), eta_dot(:)
    real(wp), intent(out) :: q_dy(:), v_dy(:)
    q_dy = this%basis%q_ref + matmul(this%basis%v, eta)
    v_dy = matmul(this%basis%v, eta_dot)
  end subroutine red_full_state

  !> The full model's norm of the error V d_eta (on the nodal coordinates).
  subroutine red_error_norm(this, dq, q_old, q_new, rtol, atol, norm)
    class(reduced_t), intent(inout) :: this
    real(wp), intent(in) :: dq(:), q_old(:), q_new(:), rtol, atol
    real(wp), intent(out) :: norm
    if (this%expanded .and. this%expansions%current > 0) then
      call this%expansions%item(this%expansions%current)%error_norm(this%dyn%model, dq, &
        q_old, q_new, rtol, atol, this%expansions%p_last, norm)
      return
    end if
    call this%dyn%error_norm(matmul(this%basis%v, dq), this%basis%q_ref + &
      matmul(this%basis%v, q_old), this%basis%q_ref + matmul(this%basis%v, q_new), rtol, &
      atol, norm)
  end subroutine red_error_norm

  subroutine red_allocate_history(this, nt)
    class(reduced_t), intent(inout) :: this
    integer, intent(in) :: nt
    integer :: k
    k = this%basis%k()
    call this%expansions%forget()
    call this%dyn%allocate_history(nt)
    if (allocated(this%eta_hist)) deallocate(this%eta_hist, this%eta_dot_hist, this%residual, &
      this%estimate)
    allocate(this%eta_hist(k, nt), this%eta_dot_hist(k, nt), this%residual(nt))
    allocate(this%estimate(nt))
    this%estimate = 0.0_wp
    call this%measured%clear()
    ! The outputs after the first (the initial state) in estimate_samples equal runs: the
    ! last output is always one of them.
    this%sample_every = 0
    if (this%estimate_samples > 0 .and. nt > 1) this%sample_every = max(1, &
      (nt - 2) / this%estimate_samples + 1)
    if (this%keep_bases) then
      if (allocated(this%bases)) deallocate(this%bases)
      allocate(this%bases(0))
      this%basis_of = [(0, k = 1, nt)]
      call this%keep_basis()
    end if
  end subroutine red_allocate_history

  !> Append the current basis to the kept ones (with keep_bases).
  subroutine red_keep_basis(this)
    class(reduced_t), intent(inout) :: this
    type(basis_t) :: kept
    if (.not. this%keep_bases) return
    kept%v = this%basis%v
    kept%q_ref = this%basis%q_ref
    kept%time = this%basis%time
    this%bases = [this%bases, kept]
  end subroutine red_keep_basis

  !> Nodal shapes of the basis at the last evaluation, W = DF_dy V (n_x, k): one solve with
  !> k right-hand sides and the factors of the kinematic Jacobian, no dense DF.
  subroutine basis_shapes(this, w)
    class(reduced_t), intent(inout) :: this
    real(wp), intent(out) :: w(:, :)
    real(wp) :: dq(this%dyn%model%n_q, size(w, 2))
    integer :: nr
    nr = this%dyn%model%n_rh
    dq(1:nr, :) = 0.0_wp
    dq(nr + 1:, :) = this%basis%v
    call this%dyn%kin%apply_df_many(this%dyn%model, dq, w)
  end subroutine basis_shapes

  !> Reduced accelerations from (W^T M W) eta'' = W^T f - V^T sigma_dy, with W = DF_dy V:
  !> O(n k) work and memory (docs/theory.md section 9). Leaves the reduced mass matrix in mr.
  subroutine reduced_accel(this, t, eta, eta_dot, a, err, mr_out)
    class(reduced_t), intent(inout) :: this
    real(wp), intent(in) :: t, eta(:), eta_dot(:)
    real(wp), intent(out) :: a(:)
    type(error_t), intent(out) :: err
    real(wp), intent(out), optional :: mr_out(:, :)
    real(wp) :: q_dy(this%dyn%model%n_dy), v_dy(this%dyn%model%n_dy)
    real(wp) :: w(this%dyn%model%n_x, size(eta))
    call this%full_state(eta, eta_dot, q_dy, v_dy)
    call this%dyn%prepare(t, q_dy, v_dy, err)
    if (.not. err%ok()) return
    call prepared_accel(this, t, a, w, err, mr_out)
  end subroutine reduced_accel

  !> reduced_accel at the state the model was prepared at; w: the basis's nodal shapes there.
  subroutine prepared_accel(this, t, a, w, err, mr_out)
    class(reduced_t), intent(inout) :: this
    real(wp), intent(in) :: t
    real(wp), intent(out) :: a(:), w(:, :)
    type(error_t), intent(out) :: err
    real(wp), intent(out), optional :: mr_out(:, :)
    real(wp) :: mr(size(a), size(a))
    integer :: info
    call basis_shapes(this, w)
    mr = matmul(transpose(w), this%dyn%mass%times(this%dyn%model, w))
    a = matmul(this%dyn%nodal_force, w) - matmul(this%dyn%sigma_now, this%basis%v)
    if (present(mr_out)) mr_out = mr
    call chol_factor(mr, info)
    if (info /= 0) then
      call err%set(ERR_MODEL, 'the reduced mass matrix V^T Mbar V is singular')
      return
    end if
    call chol_solve(mr, a)
    call check_finite(a, t, err)
  end subroutine prepared_accel

  subroutine red_accel(this, t, q, v, a, status)
    class(reduced_t), intent(inout) :: this
    real(wp), intent(in) :: t, q(:), v(:)
    real(wp), intent(out) :: a(:)
    integer, intent(out) :: status
    type(error_t) :: err
    if (this%expanded) then
      call expanded_accel(this, t, q, v, a, err)
    else
      call reduced_accel(this, t, q, v, a, err)
    end if
    call this%dyn%report(err, status)
    if (status /= 0) a = 0.0_wp
  end subroutine red_accel

  !> The largest residual norm of the run: at the outputs and every exact measurement.
  real(wp) function red_residual_max(this) result(r)
    class(reduced_t), intent(in) :: this
    r = maxval(this%residual)
    if (this%measured%n > 0) r = max(r, maxval(this%measured%residual(1:this%measured%n)))
  end function red_residual_max

  !> The largest error estimate [m] of the run, as red_residual_max.
  real(wp) function red_estimate_max(this) result(e)
    class(reduced_t), intent(in) :: this
    e = maxval(this%estimate)
    if (this%measured%n > 0) e = max(e, maxval(this%measured%estimate(1:this%measured%n)))
  end function red_estimate_max

  !> V^T of the full model's linearised Jacobian: -(V^T Mbar V)^-1 V^T [K0, D0] V, with the
  !> constant K0 of the dynamic modes applied element by element and that of elastic elements
  !> through W = DF_dy V.
  subroutine red_jacobian(this, t, q, v, dadq, dadv, status)
    class(reduced_t), intent(inout) :: this
    real(wp), intent(in) :: t, q(:), v(:)
    real(wp), intent(out) :: dadq(:, :), dadv(:, :)
    integer, intent(out) :: status
    real(wp) :: a(size(q)), mr(size(q), size(q))
    real(wp), allocatable :: kv(:, :), dv(:, :), w(:, :)
    integer :: j, info
    type(error_t) :: err
    if (this%dyn%jacobian_kind == JACOBIAN_FD .or. this%expanded) then
      call system_fd_jacobian(this, t, q, v, dadq, dadv, status)
      return
    end if
    call reduced_accel(this, t, q, v, a, err, mr)
    call this%dyn%report(err, status)
    if (status /= 0) return
    allocate(kv, dv, mold=this%basis%v)
    allocate(w(this%dyn%model%n_x, size(q)))
    call basis_shapes(this, w)
    call this%dyn%structural_action(this%basis%v, w, kv, dv)
    dadq = -matmul(transpose(this%basis%v), kv)
    dadv = -matmul(transpose(this%basis%v), dv)
    call chol_factor(mr, info)
    do j = 1, size(q)
      call chol_solve(mr, dadq(:, j))
      call chol_solve(mr, dadv(:, j))
    end do
  end subroutine red_jacobian

  !> Store the reduced state, the full state it stands for (statically corrected when asked)
  !> and the error measures, at output k of the current integration.
  subroutine red_record(this, k, t, q, v, status)
    class(reduced_t), intent(inout) :: this
    integer, intent(in) :: k
    real(wp), intent(in) :: t, q(:), v(:)
    integer, intent(out) :: status
    real(wp) :: q_dy(this%dyn%model%n_dy), v_dy(this%dyn%model%n_dy)
    real(wp) :: dq(this%dyn%model%n_dy)
    integer :: kg
    type(error_t) :: err
    this%last_eta = q
    this%last_eta_dot = v
    status = 0
    kg = this%out_index(k)
    if (kg == 0) return
    call this%full_state(q, v, q_dy, v_dy)
    this%eta_hist(:, kg) = q
    this%eta_dot_hist(:, kg) = v
    if (this%keep_bases) this%basis_of(kg) = size(this%bases)
    if (this%expanded) then
      call expanded_store(this, kg, t, q, v, q_dy, v_dy, err)
      call this%dyn%report(err, status)
      return
    end if
    call this%indicators(t, q, v, q_dy, v_dy, this%residual(kg), this%estimate(kg), dq, err)
    call this%dyn%report(err, status)
    if (status /= 0) return
    if (this%static_correction) then
      call this%dyn%record(kg, t, q_dy + dq, v_dy, status)
    else
      call this%dyn%store(kg, t, q_dy, v_dy)
    end if
  end subroutine red_record

  !> The error indicators at a reduced state, exactly: the residual's norm and, with a definite
  !> K0, the estimate from dq = K0^-1 r (the static correction). Leaves the full model
  !> evaluated at the state.
  subroutine red_indicators(this, t, eta, eta_dot, q_dy, v_dy, residual, estimate, dq, err)
    class(reduced_t), intent(inout) :: this
    real(wp), intent(in) :: t, eta(:), eta_dot(:), q_dy(:), v_dy(:)
    real(wp), intent(out) :: residual, estimate, dq(:)
    type(error_t), intent(out) :: err
    real(wp) :: a(size(eta)), r(size(dq)), a_full(size(dq))
    real(wp) :: w(this%dyn%model%n_x, size(eta))
    logical :: ok
    ! The full evaluation prepares the model at the state; the reduced one then shares it.
    call this%dyn%evaluate(t, q_dy, v_dy, a_full, err)
    if (.not. err%ok()) then
      call err%prefix('error indicator: ')
      return
    end if
    call prepared_accel(this, t, a, w, err)
    if (err%ok()) call full_residual(this, w, a, a_full, r, residual)
    if (.not. err%ok()) return
    estimate = 0.0_wp
    dq = 0.0_wp
    if (this%basis%has_k0()) then
      call this%basis%static_solve(this%dyn, r, dq, ok)
      if (.not. ok) then
        call err%set(ERR_NUMERIC, 'reduced model: the stiffness K0 at the basis ' // &
          'configuration, regular when the basis was made, is singular on refactoring')
        return
      end if
      estimate = this%dyn%model%largest_translation(nodal_motion(this, dq))
    else
      this%has_estimate = .false.
    end if
  end subroutine red_indicators

  !> The residual of the full equations r = DF_dy^T (f - M W a_eta) - sigma_dy (W = DF_dy V)
  !> at the prepared state, by one transposed solve, and its norm sqrt(r^T Mbar^-1 r):
  !> Mbar^-1 r = a_full - V a_eta with the full model's accelerations a_full there.
  subroutine full_residual(this, w, a_eta, a_full, r, norm)
    type(reduced_t), intent(inout) :: this
    real(wp), intent(in) :: w(:, :), a_eta(:), a_full(:)
    real(wp), intent(out) :: r(:), norm
    real(wp) :: g(this%dyn%model%n_x, 1), r_q(this%dyn%model%n_q)
    g = this%dyn%mass%times(this%dyn%model, matmul(w, reshape(a_eta, [size(a_eta), 1])))
    call this%dyn%kin%apply_dft(this%dyn%model, this%dyn%nodal_force - g(:, 1), r_q)
    r = r_q(this%dyn%model%n_rh + 1:) - this%dyn%sigma_now
    norm = sqrt(max(0.0_wp, dot_product(r, a_full - matmul(this%basis%v, a_eta))))
  end subroutine full_residual

  !> Nodal displacement DF_dy dq of a change dq of the dynamic coordinates.
  function nodal_motion(this, dq) result(dx)
    type(reduced_t), intent(inout) :: this
    real(wp), intent(in) :: dq(:)
    real(wp) :: dx(this%dyn%model%n_x), dq_full(this%dyn%model%n_q)
    dq_full = 0.0_wp
    dq_full(this%dyn%model%n_rh + 1:) = dq
    call this%dyn%kin%apply_df(this%dyn%model, dq_full, dx)
  end function nodal_motion

  !> Append a measurement, the arrays growing by doubling.
  subroutine measurements_add(this, t, residual, estimate, kind)
    class(measurements_t), intent(inout) :: this
    real(wp), intent(in) :: t, residual, estimate
    integer, intent(in) :: kind
    real(wp), allocatable :: rt(:, :)
    integer, allocatable :: kt(:)
    integer :: cap
    if (.not. allocated(this%time)) call this%clear()
    if (this%n == size(this%time)) then
      cap = max(16, 2 * this%n)
      allocate(rt(cap, 3), kt(cap))
      rt(1:this%n, 1) = this%time(1:this%n)
      rt(1:this%n, 2) = this%residual(1:this%n)
      rt(1:this%n, 3) = this%estimate(1:this%n)
      kt(1:this%n) = this%kind(1:this%n)
      this%time = rt(:, 1)
      this%residual = rt(:, 2)
      this%estimate = rt(:, 3)
      call move_alloc(kt, this%kind)
    end if
    this%n = this%n + 1
    this%time(this%n) = t
    this%residual(this%n) = residual
    this%estimate(this%n) = estimate
    this%kind(this%n) = kind
  end subroutine measurements_add

  subroutine measurements_clear(this)
    class(measurements_t), intent(inout) :: this
    this%n = 0
    this%time = [real(wp) ::]
    this%residual = [real(wp) ::]
    this%estimate = [real(wp) ::]
    this%kind = [integer ::]
  end subroutine measurements_clear
end module reduction_system
