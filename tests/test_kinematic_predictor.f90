!> The kinematic predictor from noted rates (docs/theory.md section 4), on the two-link model of
!> input/two_link.nml, with J_c factorised dense and sparse. Along a trajectory
!> q(s) = q0 + s qd + s^2/2 qdd + s^3/6 j from a solution at q0,
!>   - the predicted x leaves a kinematic residual of order 3 in s with the rates noted at q0,
!>     of order 2 without them (the first-order predictor x0 + DF dq);
!>   - at s = 0 the predictor is the first-order one (bitwise) and the rates stay noted; at
!>     s /= 0 they are used up;
!>   - a solve from either predictor reaches the same x (to the Newton tolerance).
program test_kinematic_predictor
  use core_kinds, only: wp
  use core_error, only: error_t
  use testing, only: suite_t
  use fd_helpers, only: lcg_t
  use io_namelist, only: nml_file_t
  use model_scene, only: scene_t
  use model_system, only: model_t
  use model_kinematics, only: kinematics_t
  use dynamics_system, only: dynamics_t
  use test_scenes, only: source_dir, make_dynamics_from
  implicit none
  type(suite_t) :: ts
  type(lcg_t) :: rng
  type(nml_file_t) :: f
  type(scene_t) :: scene
  type(dynamics_t) :: dyn
  type(error_t) :: err
  !> The trajectory of the current model and the label of its J_c storage.
  real(wp), allocatable :: q0(:), qd(:), qdd(:), jerk(:)
  character(len=:), allocatable :: tag
  call ts%init('test_kinematic_predictor')
  call f%load(source_dir() // '/input/two_link.nml', err)
  if (err%ok()) call make_dynamics_from(f, scene, dyn, err)
  call ts%check(err%ok(), 'two-link model built from input/two_link.nml')
  if (err%ok()) then
    call predictor_tests(dyn%model, .false.)
    call predictor_tests(dyn%model, .true.)
  end if
  call ts%finish()

contains

  subroutine predictor_tests(model, sparse)
    type(model_t), intent(in) :: model
    logical, intent(in) :: sparse
    ! Steps where the joints turn 0.02 and 0.01 rad: the residuals (1e-6 m and less) stand far
    ! above round-off, and the next order's terms are a few per cent of them.
    real(wp), parameter :: H = 1.0e-2_wp
    type(kinematics_t) :: kin
    real(wp), allocatable :: x_first(:), x_before(:)
    real(wp) :: r2(2), r3(2)
    integer :: nd, k
    tag = merge(' (sparse J_c)', ' (dense J_c) ', sparse)
    nd = model%n_dy
    q0 = [0.7_wp, -1.1_wp, rng%uniform_vec(nd, -4.0e-3_wp, 4.0e-3_wp)]
    qd = [2.0_wp, -3.0_wp, rng%uniform_vec(nd, -0.05_wp, 0.05_wp)]
    qdd = [-20.0_wp, 15.0_wp, rng%uniform_vec(nd, -5.0_wp, 5.0_wp)]
    jerk = [300.0_wp, -200.0_wp, rng%uniform_vec(nd, -50.0_wp, 50.0_wp)]
    call kin%init(model, sparse)
    kin%continuation = .true.
    call kin%solve(model, q0, err)
    call ts%check(err%ok(), 'kinematics solved at q0' // tag)
    if (.not. err%ok()) return
    do k = 1, 2
      r2(k) = predicted_residual(kin, model, H / k, .false.)
      r3(k) = predicted_residual(kin, model, H / k, .true.)
    end do
    call ts%order(r2(1), r2(2), 2, 'first-order predictor, residual' // tag)
    call ts%order(r3(1), r3(2), 3, 'predictor with rates, residual' // tag)

    ! s = 0: the first-order predictor exactly, the rates kept for the next step.
    call back_at_q0(kin, model, .true.)
    x_before = kin%x
    call kin%predict(model, q_at(H), 0.0_wp)
    call ts%check(kin%rates%valid, 'rates still noted after a prediction at their time' // tag)
    x_first = kin%x
    kin%x = x_before
    call kin%predict(model, q_at(H))
    call ts%check(all(kin%x == x_first), 'at s = 0 the first-order predictor, bitwise' // tag)
    call ts%check(.not. kin%rates%valid, 'rates used up by a prediction at another time' // tag)

    ! The same solution from either start.
    call back_at_q0(kin, model, .false.)
    call kin%solve(model, q_at(H), err)
    x_first = kin%x
    call back_at_q0(kin, model, .true.)
    call kin%solve(model, q_at(H), err, H)
    call ts%check(err%ok(), 'solve from the predictor with rates' // tag)
    ! Newton stops at a residual of 1e-11 m or rad; J_c is well conditioned on this model.
    call ts%close_array(kin%x, x_first, 0.0_wp, 1.0e-8_wp, &
      'same solution from either predictor' // tag)
  end subroutine predictor_tests

  function q_at(s) result(q)
    real(wp), intent(in) :: s
    real(wp) :: q(size(q0))
    q = q0 + s * (qd + s / 2 * (qdd + s / 3 * jerk))
  end function q_at

  !> max |residual| at q(s) right after the prediction from the solution at q0.
  real(wp) function predicted_residual(kin, model, s, with_rates) result(rmax)
    type(kinematics_t), intent(inout) :: kin
    type(model_t), intent(in) :: model
    real(wp), intent(in) :: s
    logical, intent(in) :: with_rates
    real(wp) :: r(model%n_c)
    call back_at_q0(kin, model, with_rates)
    if (with_rates) then
      call kin%predict(model, q_at(s), s)
    else
      call kin%predict(model, q_at(s))
    end if
    call kin%residual(model, q_at(s), r)
    rmax = maxval(abs(r))
  end function predicted_residual

  !> Solve at q0 again (factors at its solution) and note the trajectory's rates if asked.
  subroutine back_at_q0(kin, model, with_rates)
    type(kinematics_t), intent(inout) :: kin
    type(model_t), intent(in) :: model
    logical, intent(in) :: with_rates
    real(wp) :: xd(model%n_x), xdd(model%n_x)
    call kin%solve(model, q0, err)
    call ts%check(err%ok(), 'kinematics solved again at q0' // tag)
    if (.not. with_rates) return
    call kin%apply_df(model, qd, xd)
    call kin%second(model, qd, xdd, xd_known=xd, qdd=qdd)
    call kin%note_rates(0.0_wp, qd, qdd, xd, xdd)
  end subroutine back_at_q0
end program test_kinematic_predictor
