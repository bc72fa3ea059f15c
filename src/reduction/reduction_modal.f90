!> Modal analysis at a configuration with the prescribed modes locked:
!>   K_T v = omega^2 M0 v   on the dynamic coordinates (reduction_eigen: dense LAPACK dsygvd
!> or ARPACK shift-invert Lanczos for the lowest modes of large models, on the dense matrices
!> or, for large models on the sparse path, on the augmented sparse factors: reduction_krylov).
!> The eigenvectors come back M0-normalised; they are the basis of the reduced models.
module reduction_modal
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_INPUT, ERR_NUMERIC
  use core_strings, only: int_str
  use reduction_eigen, only: lowest_modes
  use reduction_krylov, only: krylov_modes, krylov_modes_applies, mbar_times
  use dynamics_system, only: dynamics_t
  use dynamics_static, only: tangent_stiffness, motion_tangent, has_loads, STABILITY_MARGIN
  use dynamics_frequencies, only: general_modes, is_symmetric, stability_scale
  implicit none
  private
  public :: modal_result_t, modal_analysis, modal_mass_times

  real(wp), parameter :: TWO_PI = 6.28318530717958647692_wp
  !> 'auto' takes the Krylov path (no dense matrices) from this many dynamic coordinates on,
  !> where it applies and at most a tenth of the modes are asked for. Measured on the
  !> two-link (scripts/bench_modal.py, 4 modes), LAPACK / dense ARPACK / Krylov: 64 dynamic
  !> coordinates 1.2 / 1.3 / 0.7 ms, 128: 4.6 / 3.4 / 1.6 ms, 1024: 1.42 / 1.20 / 0.012 s;
  !> under gravity (GMRES, two evaluations per product) LAPACK / Krylov 4.5 / 5.4 ms at 64,
  !> 18 / 6.7 ms at 128.
  integer, parameter :: KRYLOV_AUTO_MIN_N = 100

  type :: modal_result_t
    real(wp), allocatable :: omega2(:)        !< eigenvalues [rad^2/s^2]
    real(wp), allocatable :: frequency_hz(:)  !< sqrt(omega2) / 2 pi (negative sign: unstable)
    real(wp), allocatable :: shapes(:, :)     !< (n_dy, n_modes), M0-normalised
    real(wp), allocatable :: node_shapes(:, :, :)  !< (n_x, n_modes) nodal: DF_dy v
    !> Dense tangent and mass matrix (not allocated on the Krylov path, which forms neither).
    real(wp), allocatable :: m0(:, :), k0(:, :)
    character(len=8) :: solver = ''            !< eigensolver that ran: lapack, arpack, krylov
  end type modal_result_t

contains

  !> n_modes = 0 asks for all of them (always LAPACK). solver: 'auto' (default), 'lapack',
  !> 'arpack' (as reduction_eigen's lowest_modes) or 'krylov' (reduction_krylov).
  subroutine modal_analysis(dyn, t, q_dy, n_modes, res, err, solver, along_motion, dense, &
      for_basis)
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: t, q_dy(:)
    integer, intent(in) :: n_modes
    type(modal_result_t), intent(out) :: res
    type(error_t), intent(out) :: err
    character(len=*), intent(in), optional :: solver
    !> With the prescribed motion's rates at t (dynamic stiffening: motion_tangent), not held.
    logical, intent(in), optional :: along_motion
    !> The caller needs res%k0 and res%m0 (a held-joint basis): no Krylov path.
    logical, intent(in), optional :: dense
    !> A reduced model's basis: with loads 'auto' keeps the dense path, whose K_T gives the
    !> static correction and the error estimate (the Krylov path gives them from K0 alone,
    !> so only without loads).
    logical, intent(in), optional :: for_basis
    logical :: moving, need_dense
    character(len=:), allocatable :: why_not
    real(wp), allocatable :: lambda(:), v(:, :), shapes_x(:, :)
    character(len=:), allocatable :: name
    integer :: n, nm
    n = dyn%model%n_dy
    nm = n_modes
    name = 'auto'
    if (present(solver)) name = trim(adjustl(solver))
    ! All modes: a Lanczos method has nothing to gain and ARPACK cannot deliver all of them.
    ! (An unknown name is left for lowest_modes to report.)
    if (nm == 0) then
      nm = n
      if (any(name == [character(len=6) :: 'auto', 'arpack'])) name = 'lapack'
    end if
    if (nm > n) then
      call err%set(ERR_INPUT, 'group &modal: n_modes is larger than the number of dynamic ' // &
        'coordinates')
      return
    end if
    moving = .false.
    if (present(along_motion)) moving = along_motion
    need_dense = .false.
    if (present(dense)) need_dense = dense
    why_not = krylov_modes_applies(dyn, moving)
    if (need_dense) why_not = 'the held-joint basis needs the dense K0 and Mbar'
    if (present(for_basis)) then
      if (for_basis .and. has_loads(dyn) .and. name == 'auto') why_not = 'loads'
      ! The Krylov basis's static correction and error estimate solve with K0 and refine
      ! with the dynamic modes' stiffness alone, which misses the elastic modes'.
      if (for_basis .and. dyn%model%n_elastic > 0) why_not = 'the model has elastic ' // &
        '(calculable) modes, whose stiffness a reduced basis''s K0 solves do not hold'
    end if
    if (name == 'auto' .and. why_not == '' .and. n >= KRYLOV_AUTO_MIN_N .and. &
      nm <= n / 10) name = 'krylov'
    if (name == 'krylov') then
      if (why_not /= '') then
        call err%set(ERR_INPUT, "eigensolver 'krylov': " // why_not // "; use 'auto'")
      else if (nm > n - 2) then
        call err%set(ERR_INPUT, "eigensolver 'krylov': needs at most n - 2 modes (n = " // &
          int_str(n) // ', asked ' // int_str(nm) // ')')
      else
        call krylov_modes(dyn, t, q_dy, nm, res%omega2, res%shapes, shapes_x, err)
      end if
      if (.not. err%ok()) then
        call err%prefix('modal analysis: ')
        return
      end if
      res%frequency_hz = sign(sqrt(abs(res%omega2)), res%omega2) / TWO_PI
      res%node_shapes = reshape(shapes_x, [dyn%model%n_x, nm, 1])
      res%solver = 'krylov'
      return
    end if
    allocate(res%k0(n, n))
    if (moving) then
      call motion_tangent(dyn, t, q_dy, res%k0, err)
    else
      call tangent_stiffness(dyn, t, q_dy, res%k0, err)
    end if
    if (.not. err%ok()) return
    res%m0 = dyn%mbar
    if (is_symmetric(res%k0)) then
      call lowest_modes(res%k0, res%m0, nm, name, lambda, v, err, res%solver)
    else
      call unsymmetric_modes(res, nm, lambda, v, err)
      if (present(for_basis)) then
        if (for_basis .and. err%ok()) call m_orthonormalise(res%m0, v)
      end if
    end if
    if (.not. err%ok()) then
      call err%prefix('modal analysis: ')
      return
    end if
    res%omega2 = lambda
    res%frequency_hz = sign(sqrt(abs(res%omega2)), res%omega2) / TWO_PI
    res%shapes = v
    allocate(res%node_shapes(dyn%model%n_x, nm, 1))
    res%node_shapes(:, :, 1) = matmul(dyn%kin%df(:, dyn%model%n_rh + 1:), res%shapes)
  end subroutine modal_analysis

  !> Modes of an unsymmetric tangent (moments fixed in space, not conservative in 3D): those
  !> of the full problem, on which the stability test decides (dynamics_frequencies), by
  !> LAPACK whatever the solver asked. res%k0 then keeps the symmetric part, which a reduced
  !> model's static correction factors by Cholesky.
  subroutine unsymmetric_modes(res, nm, lambda, v, err)
    type(modal_result_t), intent(inout) :: res
    integer, intent(in) :: nm
    real(wp), allocatable, intent(out) :: lambda(:), v(:, :)
    type(error_t), intent(inout) :: err
    integer :: info
    call general_modes(res%k0, res%m0, nm, STABILITY_MARGIN * stability_scale(res%k0, &
      res%m0), lambda, v, info)
    if (info /= 0) then
      call err%set(ERR_NUMERIC, 'LAPACK dggev failed on the unsymmetric tangent of the ' // &
        'moments fixed in space (info = ' // int_str(info) // ')')
      return
    end if
    res%solver = 'lapack'
    res%k0 = 0.5_wp * (res%k0 + transpose(res%k0))
  end subroutine unsymmetric_modes

  !> Gram-Schmidt in the Mbar inner product, lowest mode first: a reduced model's basis must
  !> be Mbar-orthonormal (its velocities are V^T Mbar v), which the right eigenvectors of an
  !> unsymmetric tangent are not; the span, and so the reduced model's modes, stay the same.
  subroutine m_orthonormalise(m, v)
    real(wp), intent(in) :: m(:, :)
    real(wp), intent(inout) :: v(:, :)
    real(wp) :: mv(size(v, 1))
    integer :: i, j, pass
    do j = 1, size(v, 2)
      ! Twice: the second pass removes what the first one's rounding left.
      do pass = 1, 2
        do i = 1, j - 1
          v(:, j) = v(:, j) - dot_product(v(:, i), matmul(m, v(:, j))) * v(:, i)
        end do
      end do
      mv = matmul(m, v(:, j))
      v(:, j) = v(:, j) / sqrt(dot_product(v(:, j), mv))
    end do
  end subroutine m_orthonormalise

  !> Mbar w at the configuration of the modal analysis res, which must be the last one the
  !> kinematics of dyn solved (the Krylov path keeps no Mbar).
  function modal_mass_times(dyn, res, w) result(mw)
    type(dynamics_t), intent(inout) :: dyn
    type(modal_result_t), intent(in) :: res
    real(wp), intent(in) :: w(:, :)
    real(wp) :: mw(size(w, 1), size(w, 2))
    if (allocated(res%m0)) then
      mw = matmul(res%m0, w)
    else
      mw = mbar_times(dyn, w)
    end if
  end function modal_mass_times
end module reduction_modal
