!> The Krylov modal path (reduction_krylov: shift-invert Lanczos on the augmented sparse
!> factors, no dense matrices) against the dense one on small models: the same modes to
!> round-off with prescribed, rigid and dynamic modes and a free hinge (a zero eigenvalue),
!> and to the differences' accuracy with loads;
!> reduced runs, their static correction, error estimate and basis updates alike; clear
!> errors where it does not apply.
program test_krylov_modes
  use core_kinds, only: wp
  use core_error, only: error_t
  use core_strings, only: real_str
  use analysis_run, only: run_t
  use reduction_modal, only: modal_result_t, modal_analysis
  use test_scenes, only: itxt, node_distance
  use testing, only: suite_t
  implicit none
  type(suite_t) :: suite
  character(len=*), parameter :: SHORT = "&dynamic t_end = 1e-3, output_dt = 1e-3 /"
  character(len=*), parameter :: DYN = "&dynamic t_end = 0.3, output_dt = 2e-3, " // &
    "integrator = 'bdf', rtol = 1e-8, atol = 1e-10 /"
  !> Bounds on the modes' relative differences: both paths exact (round-off, observed 3e-14
  !> in the eigenvalues, 6e-12 in the shapes), and with the loads' stiffness differenced:
  !> the dense path's central differences along unit vectors have a truncation error of
  !> about (h / l)^2 / 6 = 5e-10 of the load stiffness (h = 7.3e-6, elements l = 0.136 m),
  !> observed 8e-10 in the eigenvalues and 1.3e-10 in the shapes.
  real(wp), parameter :: EXACT(2) = [1.0e-11_wp, 1.0e-9_wp]
  real(wp), parameter :: DIFFERENCED(2) = [3.0e-8_wp, 3.0e-8_wp]
  !> 100 rtol x the arm's reach [m]
  real(wp), parameter :: TIP_BOUND = 100 * 1.0e-8_wp * 1.22_wp

  call suite%init('krylov modes: sparse shift-invert Lanczos against the dense path')
  call check_modes('prescribed joints, axial modes dynamic', &
    scene("mode = 'prescribed', motion = 'p2'", "elongation = 'dynamic', "), 4, EXACT)
  call check_modes('free elbow (a zero eigenvalue)', scene("mode = 'dynamic'", ""), 3, EXACT)
  ! Loads: the tangent is K0 plus their stiffness, differenced on both paths. A tip pull of
  ! 500 N raises the lowest frequency from 3.06 to 3.72 Hz; gravity adds its own.
  call check_modes('tip pull and gravity', scene("mode = 'prescribed', motion = 'p2'", "") &
    // "&force node = 'tip', fx = 500 /" // new_line('a') // "&scene gravity = 0, -9.81 /" &
    // new_line('a'), 4, DIFFERENCED)
  call check_reduced()
  call check_updates()
  call check_refusals()
  call suite%finish()

contains

  !> The two-link arm, 4 beams per link; elbow: the hinge's mode and motion; extra: more
  !> settings of link 1.
  function scene(elbow, extra) result(text)
    character(len=*), intent(in) :: elbow, extra
    character(len=:), allocatable :: text
    character, parameter :: nl = new_line('a')
    text = "&node label = 'base', x = 0, y = 0, fixed = .true. /" // nl // &
      "&node label = 'elbow', x = 0.545, y = 0 /" // nl // &
      "&node label = 'tip', x = 1.22, y = 0 /" // nl // &
      "&link label = 'l1', from = 'base', to = 'elbow', n_elements = 4, " // extra // &
      "E = 7.3e10, A = 9e-4, I = 1.69e-8, rho = 2700 /" // nl // &
      "&link label = 'l2', from = 'elbow', to = 'tip', n_elements = 4, E = 7.3e10, " // &
      "A = 4e-4, I = 3.33e-9, rho = 2700 /" // nl // &
      "&hinge label = 'j1', node = 'base', link = 'l1', mode = 'prescribed', motion = 'p1' /" &
      // nl // "&hinge label = 'j2', node = 'elbow', link = 'l2', " // elbow // " /" // nl // &
      "&motion label = 'p1', law = 'cubic', end = 1.5707963, duration = 0.25 /" // nl // &
      "&motion label = 'p2', law = 'cubic', end = 1.5707963, duration = 0.25 /" // nl // &
      "&mass node = 'elbow', m = 1 /" // nl // "&mass node = 'tip', m = 3 /" // nl // &
      "&output nodes = 'tip' /" // nl
  end function scene

  subroutine load_run(name, text, run, err)
    character(len=*), intent(in) :: name, text
    type(run_t), intent(out) :: run
    type(error_t), intent(out) :: err
    run%verbose = .false.
    call run%load_text(text, 'test_krylov_' // name // '.nml', err)
    if (err%ok()) call run%execute(err)
  end subroutine load_run

  subroutine must_run(name, text, run)
    character(len=*), intent(in) :: name, text
    type(run_t), intent(out) :: run
    type(error_t) :: err
    call load_run(name, text, run, err)
    call suite%check(err%ok(), name // ' runs')
    if (.not. err%ok()) then
      write(*, '(a)') '    ' // err%message
      call suite%finish()
    end if
  end subroutine must_run

  !> nev modes at the initial configuration by LAPACK and by the Krylov path. Both normalise
  !> to Mbar and make the largest component positive, so the shapes compare entry by entry;
  !> eigenvalues are Rayleigh quotients on both paths (second order in the vectors' error).
  !> The bounds: see EXACT and DIFFERENCED.
  subroutine check_modes(label, text, nev, bound)
    character(len=*), intent(in) :: label, text
    integer, intent(in) :: nev
    real(wp), intent(in) :: bound(2)     !< eigenvalues, shapes
    type(run_t) :: run
    type(modal_result_t) :: dense, sparse
    type(error_t) :: err
    real(wp) :: q0(64), d_lambda, d_shape, d_nodal
    integer :: n
    call must_run('modes', text // SHORT, run)
    n = run%dyn%model%n_dy
    q0 = 0.0_wp
    call modal_analysis(run%dyn, 0.0_wp, q0(:n), nev, dense, err, 'lapack')
    call suite%check(err%ok(), label // ': dense modes')
    call modal_analysis(run%dyn, 0.0_wp, q0(:n), nev, sparse, err, 'krylov')
    call suite%check(err%ok() .and. sparse%solver == 'krylov', label // ': Krylov modes')
    if (.not. err%ok()) then
      write(*, '(a)') '    ' // err%message
      return
    end if
    call suite%check(.not. allocated(sparse%m0) .and. .not. allocated(sparse%k0), &
      label // ': the Krylov path forms no dense matrix')
    d_lambda = maxval(abs(sparse%omega2 - dense%omega2)) / maxval(abs(dense%omega2))
    d_shape = maxval(abs(sparse%shapes - dense%shapes)) / maxval(abs(dense%shapes))
    d_nodal = maxval(abs(sparse%node_shapes - dense%node_shapes)) / &
      maxval(abs(dense%node_shapes))
    write(*, '(4x,a,*(f0.4,:,", "))') label // ': frequencies [Hz] ', dense%frequency_hz
    call suite%check(d_lambda < bound(1), label // ': eigenvalues agree (' // &
      real_str(d_lambda) // ' of the largest)')
    call suite%check(d_shape < bound(2) .and. d_nodal < bound(2), label // &
      ': shapes agree (' // real_str(d_shape) // ', nodal ' // real_str(d_nodal) // ')')
  end subroutine check_modes


  !> Reduced runs on either basis, with the static correction (K0^-1 r: dense Cholesky against
  !> the sparse augmented K0) and the error estimate. The bases agree to round-off; BDF's step
  !> choices amplify that, so the paths agree to its global error, bounded by 100 rtol times
  !> the reach (observed 9e-10 m; estimates 8e-9 relative).
  subroutine check_reduced()
    type(run_t) :: dense, sparse
    character(len=*), parameter :: red = "&reduction n_modes = 3, static_correction = .true., "
    real(wp) :: d_tip, d_est
    call must_run('red_lapack', scene("mode = 'prescribed', motion = 'p2'", "") // DYN // &
      red // "eigensolver = 'lapack' /", dense)
    call must_run('red_krylov', scene("mode = 'prescribed', motion = 'p2'", "") // DYN // &
      red // "eigensolver = 'krylov' /", sparse)
    call suite%check(sparse%red%basis%solver == 'krylov' .and. sparse%red%has_estimate, &
      'reduced run on the Krylov basis keeps its error estimate')
    d_tip = node_distance(dense, sparse, 'tip')
    d_est = maxval(abs(dense%red%estimate - sparse%red%estimate)) / maxval(dense%red%estimate)
    call suite%check(d_tip < TIP_BOUND, 'statically corrected tip paths agree (' // &
      real_str(d_tip) // ' m)')
    call suite%check(d_est < 1.0e-6_wp, 'error estimates agree (' // real_str(d_est) // &
      ' relative; largest ' // real_str(maxval(dense%red%estimate)) // ' m)')
  end subroutine check_reduced

  !> Basis updates: the MAC through Mbar products on the Krylov path. The states at the
  !> checks differ by the paths' difference (see check_reduced), the MACs as much (observed
  !> 6e-10 apart, tips 7e-10 m).
  subroutine check_updates()
    type(run_t) :: dense, sparse
    character(len=*), parameter :: red = "&reduction n_modes = 2, update = 'mac', " // &
      "update_interval = 0.02, mac_threshold = 0.99999, "
    real(wp) :: d_tip, d_mac
    call must_run('upd_lapack', scene("mode = 'prescribed', motion = 'p2'", "") // DYN // &
      red // "eigensolver = 'lapack' /", dense)
    call must_run('upd_krylov', scene("mode = 'prescribed', motion = 'p2'", "") // DYN // &
      red // "eigensolver = 'krylov' /", sparse)
    d_tip = node_distance(dense, sparse, 'tip')
    d_mac = maxval(abs(dense%updates%min_mac - sparse%updates%min_mac))
    call suite%check(dense%updates%n_updates > 0 .and. &
      sparse%updates%n_updates == dense%updates%n_updates .and. d_mac < 1.0e-6_wp, &
      'MAC checks agree (' // itxt(sparse%updates%n_updates) // ' updates, MAC ' // &
      real_str(d_mac) // ' apart)')
    call suite%check(d_tip < TIP_BOUND, 'updated runs agree (' // real_str(d_tip) // ' m)')
  end subroutine check_updates

  !> Where the Krylov path cannot give the dense path's tangent (along a motion; also elastic
  !> modes and moments fixed in space) or there are no sparse factors, 'krylov' is refused
  !> with the reason. With loads a reduced model on a Krylov basis has no
  !> static correction (the sparse factors hold K0, not K_T): refused too.
  subroutine check_refusals()
    type(run_t) :: run
    type(error_t) :: err
    character(len=*), parameter :: red = "&reduction n_modes = 2, eigensolver = 'krylov' /"
    character(len=:), allocatable :: base
    base = scene("mode = 'prescribed', motion = 'p2'", "")
    call load_run('gravity', base // "&scene gravity = 0, -9.81 /" // SHORT // &
      "&reduction n_modes = 2, eigensolver = 'krylov', static_correction = .true. /", run, err)
    call suite%check(.not. err%ok() .and. index(err%message, 'static_correction') > 0 .and. &
      index(err%message, 'loads') > 0, 'static correction refused with loads: ' // err%message)
    call load_run('moving', base // SHORT // "&modal n_modes = 2, solver = 'krylov', " // &
      "along_motion = .true. /", run, err)
    call suite%check(.not. err%ok() .and. index(err%message, "'krylov'") > 0 .and. &
      index(err%message, 'along a motion') > 0, 'refused along a motion: ' // err%message)
    call load_run('dense', base // "&scene linear_solver = 'dense' /" // SHORT // red, run, err)
    call suite%check(.not. err%ok() .and. index(err%message, 'dense path') > 0, &
      'refused on the dense path: ' // err%message)
  end subroutine check_refusals
end program test_krylov_modes
