!> Modal analysis at a configuration with the prescribed modes locked:
!>   K_T v = omega^2 M0 v   on the dynamic coordinates (reduction_eigen: dense LAPACK dsygvd
!> or ARPACK shift-invert Lanczos for the lowest modes of large models).
!> The eigenvectors come back M0-normalised; they are the basis of the reduced models.
module reduction_modal
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_INPUT
  use reduction_eigen, only: lowest_modes
  use dynamics_system, only: dynamics_t
  use dynamics_static, only: tangent_stiffness, motion_tangent
  implicit none
  private
  public :: modal_result_t, modal_analysis

  real(wp), parameter :: TWO_PI = 6.28318530717958647692_wp

  type :: modal_result_t
    real(wp), allocatable :: omega2(:)        !< eigenvalues [rad^2/s^2]
    real(wp), allocatable :: frequency_hz(:)  !< sqrt(omega2) / 2 pi (negative sign: unstable)
    real(wp), allocatable :: shapes(:, :)     !< (n_dy, n_modes), M0-normalised
    real(wp), allocatable :: node_shapes(:, :, :)  !< (n_x, n_modes) nodal: DF_dy v
    real(wp), allocatable :: m0(:, :), k0(:, :)
    character(len=8) :: solver = ''            !< eigensolver that ran: 'lapack' or 'arpack'
  end type modal_result_t

contains

  !> n_modes = 0 asks for all of them (always LAPACK). solver: 'auto' (default), 'lapack' or
  !> 'arpack', as reduction_eigen's lowest_modes.
  subroutine modal_analysis(dyn, t, q_dy, n_modes, res, err, solver, along_motion)
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: t, q_dy(:)
    integer, intent(in) :: n_modes
    type(modal_result_t), intent(out) :: res
    type(error_t), intent(out) :: err
    character(len=*), intent(in), optional :: solver
    !> With the prescribed motion's rates at t (dynamic stiffening: motion_tangent), not held.
    logical, intent(in), optional :: along_motion
    logical :: moving
    real(wp), allocatable :: lambda(:), v(:, :)
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
    allocate(res%k0(n, n))
    moving = .false.
    if (present(along_motion)) moving = along_motion
    if (moving) then
      call motion_tangent(dyn, t, q_dy, res%k0, err)
    else
      call tangent_stiffness(dyn, t, q_dy, res%k0, err)
    end if
    if (.not. err%ok()) return
    ! Modes need a symmetric stiffness: of the load stiffness of a moment fixed in space (not
    ! conservative in 3D) only the symmetric part is kept.
    res%k0 = 0.5_wp * (res%k0 + transpose(res%k0))
    res%m0 = dyn%mbar
    call lowest_modes(res%k0, res%m0, nm, name, lambda, v, err, res%solver)
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
end module reduction_modal
