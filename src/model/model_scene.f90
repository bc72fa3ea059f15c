!> Scene records: the user's description of a planar system as plain data, as read from a
!> namelist file (io_scene) or made by a program. `model_build` turns a scene into a model.
!> Units are SI throughout: m, kg, s, N, rad.
module model_scene
  use core_kinds, only: wp
  use integrators_system, only: INTEGRATOR_AUTO, INTEGRATOR_BDF, INTEGRATOR_GALPHA, &
    INTEGRATOR_GALPHA_ADAPTIVE, INTEGRATOR_ERK, INTEGRATOR_NAMES, JACOBIAN_LINEARISED, &
    JACOBIAN_FD, JACOBIAN_INTERNAL, JACOBIAN_NAMES
  implicit none
  private
  public :: scene_t, node_rec_t, link_rec_t, hinge_rec_t, truss_rec_t, mass_rec_t, &
    force_rec_t, motion_rec_t, static_rec_t, modal_rec_t, dynamic_rec_t, reduction_rec_t, label_t, &
    buckling_rec_t, slider_rec_t, linear_rec_t, controller_rec_t, auto_integrator, auto_by_stiffness
  ! &dynamic integrator and jacobian are the integrators' own enums: the scene's readers (io)
  ! take them from here, with the records that hold them.
  public :: INTEGRATOR_AUTO, INTEGRATOR_BDF, INTEGRATOR_GALPHA, INTEGRATOR_GALPHA_ADAPTIVE, &
    INTEGRATOR_ERK, INTEGRATOR_NAMES, JACOBIAN_LINEARISED, JACOBIAN_FD, JACOBIAN_INTERNAL, &
    JACOBIAN_NAMES

  !> integrator = 'auto' takes generalized-alpha with error control from this rtol up; below,
  !> BDF when the model is not stiff (auto_by_stiffness).
  real(wp), parameter :: AUTO_GALPHA_RTOL = 1.0e-6_wp
  !> Stiff: the fastest mode turns through more than this many radians over the run (about
  !> 160 periods), more than BDF's higher orders can afford to resolve.
  real(wp), parameter :: AUTO_STIFF_RADIANS = 1.0e3_wp

  type :: label_t
    character(len=:), allocatable :: s
  end type label_t

  type :: node_rec_t
    character(len=:), allocatable :: label
    real(wp) :: x = 0.0_wp, y = 0.0_wp
    logical :: fix_x = .false., fix_y = .false., fix_phi = .false.
    !> Coordinates that are inputs themselves: degrees of freedom (x, y, phi, z) ...
    logical :: dynamic(4) = .false.
    !> ... or prescribed by the motion of that label (not allocated or '': not prescribed),
    !> x = x0 + p(t).
    type(label_t) :: motion(4)
    !> Spatial scenes: z, its support, and the clamp of the node's rotation.
    real(wp) :: z = 0.0_wp
    logical :: fix_z = .false., fix_rotation = .false.
    !> Spatial scenes: the node's rotation a degree of freedom (dynamic = 'rotation'), or
    !> driven by the motion `motion_rotation` ('' none) about the axis `rotation_axis` fixed
    !> in space (3 values).
    logical :: free_rotation = .false.
    character(len=:), allocatable :: motion_rotation
    real(wp), allocatable :: rotation_axis(:)
    !> The first variable given that only a spatial (planar) scene takes, '' if none: checked
    !> against &scene dimension once every group is read.
    character(len=:), allocatable :: spatial_var, planar_var
  end type node_rec_t

  !> A straight link from node `from` to node `to`, meshed into n_elements beams.
  type :: link_rec_t
    character(len=:), allocatable :: label, from, to
    integer :: n_elements = 1
    real(wp) :: e_modulus = 0.0_wp, area = 0.0_wp, inertia = 0.0_wp, density = 0.0_wp
    real(wp) :: shear_modulus = 0.0_wp    !< > 0 makes the beams shear-flexible (Timoshenko)
    real(wp) :: shear_factor = 5.0_wp / 6.0_wp
    !> Mode classes: one value for every element, or one per element.
    type(label_t), allocatable :: elongation(:), bending(:)
    character(len=:), allocatable :: bending_form          !< 'angle' or 'sine'
    character(len=:), allocatable :: mass                  !< 'consistent' or 'lumped'
    real(wp) :: damping = 0.0_wp                           !< stiffness-proportional [s]
    !> Spatial scenes: I is the second moment about the section z axis (bending in the
    !> section's x-y plane, as in the plane), inertia_y about y (< 0: equal to I), torsion the
    !> torsion constant J, orientation the section y axis (not allocated: global z x chord).
    real(wp) :: inertia_y = -1.0_wp, torsion = 0.0_wp
    real(wp), allocatable :: orientation(:)
    !> Rotary inertia per length about the beam axis, section y, section z [kg m]; not
    !> allocated: rho (Iy + I), rho Iy, rho I.
    real(wp), allocatable :: rotary_inertia(:)
    character(len=:), allocatable :: spatial_var
  end type link_rec_t

  !> A hinge at `node` that gives `link` a rotation of its own, relative to the node's.
  type :: hinge_rec_t
    character(len=:), allocatable :: label, node, link, mode, motion
    real(wp) :: stiffness = 0.0_wp, damping = 0.0_wp
    !> Spatial: the hinge axis in the reference frame (turns with the node's rotation).
    real(wp) :: axis(3) = [0.0_wp, 0.0_wp, 1.0_wp]
    !> Spatial joint type: revolute (the rotation about `axis` takes `mode`), universal (the
    !> two rotations normal to `axis` take it, the one about it is rigid) or spherical (all
    !> three take it).
    character(len=:), allocatable :: joint_type
    !> An actuator on a dynamic hinge: a torque [N m], constant or times the value of the
    !> motion `torque_law` ('' none).
    real(wp) :: torque = 0.0_wp
    character(len=:), allocatable :: torque_law
    !> A PD controller on a dynamic hinge: torque kp (r - e) + kd (r' - e') tracking the
    !> motion `reference` ('' none): a spring kp with damping kd/kp and the actuator
    !> kp r + kd r'.
    real(wp) :: kp = 0.0_wp, kd = 0.0_wp
    character(len=:), allocatable :: reference
    character(len=:), allocatable :: spatial_var
  end type hinge_rec_t

  type :: truss_rec_t
    character(len=:), allocatable :: label, from, to, mode, mass
    real(wp) :: e_modulus = 0.0_wp, area = 0.0_wp, density = 0.0_wp, damping = 0.0_wp
    !> A linear actuator along a dynamic truss: a force [N], constant or times the value of
    !> the motion `force_law` ('' none).
    real(wp) :: force = 0.0_wp
    character(len=:), allocatable :: force_law
  end type truss_rec_t

  !> A slider: `node` moves along the line through its reference position along `direction`.
  type :: slider_rec_t
    character(len=:), allocatable :: label, node, mode
    real(wp), allocatable :: direction(:)   !< 2 values (planar) or 3 (spatial)
    real(wp) :: stiffness = 0.0_wp, damping = 0.0_wp
  end type slider_rec_t

  type :: mass_rec_t
    character(len=:), allocatable :: node
    real(wp) :: m = 0.0_wp, j = 0.0_wp
    !> Spatial: inertia tensor about the node in the reference axes, (Jxx, Jyy, Jzz, Jxy,
    !> Jxz, Jyz) [kg m^2]; not allocated: none.
    real(wp), allocatable :: inertia(:)
    !> Spatial: the axes `inertia` is given in, (3, 3) with the body's x, y and z axes as
    !> columns in reference coordinates (from `rotation` or `axes`); not allocated: the
    !> reference axes.
    real(wp), allocatable :: axes(:, :)
    character(len=:), allocatable :: planar_var, spatial_var
  end type mass_rec_t

  type :: force_rec_t
    character(len=:), allocatable :: node
    real(wp) :: fx = 0.0_wp, fy = 0.0_wp, moment = 0.0_wp
    !> Label of a &motion whose value multiplies the load in time ('' or not allocated: constant).
    character(len=:), allocatable :: time_law
    !> Spatial scenes: fz and a moment fixed in space (mx, my, mz).
    real(wp) :: fz = 0.0_wp, m_xyz(3) = 0.0_wp
    character(len=:), allocatable :: spatial_var, planar_var
  end type force_rec_t

  !> A &motion group; each law reads only its own variables (docs/input.md, &motion).
  type :: motion_rec_t
    character(len=:), allocatable :: label, law
    real(wp) :: start = 0.0_wp, end = 0.0_wp, t0 = 0.0_wp, duration = 0.0_wp
    real(wp) :: rate = 0.0_wp, amplitude = 0.0_wp, frequency = 0.0_wp, phase = 0.0_wp
    type(label_t), allocatable :: terms(:)            !< sum: labels of other motions
    real(wp), allocatable :: times(:), values(:)      !< table (read from `file` if given)
  end type motion_rec_t

  !> &static method as an enum (read with io_fields' rd_enum): load control or arc-length
  !> continuation.
  integer, parameter, public :: STATIC_LOAD = 1, STATIC_ARC_LENGTH = 2
  character(len=*), parameter, public :: STATIC_METHOD_NAMES(2) = [character(len=10) :: &
    'load', 'arc_length']

  type :: static_rec_t
    logical :: active = .false.
    integer :: n_steps = 10
    real(wp) :: tol = 1.0e-10_wp
    integer :: max_iter = 30
    integer :: n_frequencies = 0    !< lowest natural frequencies written at each step
    integer :: method = STATIC_LOAD           !< STATIC_*
    real(wp) :: arc_length = 0.0_wp           !< 0: sqrt(2)/n_steps
    real(wp) :: max_load_factor = huge(1.0_wp)
    character(len=:), allocatable :: solver   !< 'auto', 'dense' or 'krylov'
  end type static_rec_t

  type :: modal_rec_t
    logical :: active = .false.
    integer :: n_modes = 0          !< 0 = all
    real(wp) :: time = 0.0_wp       !< prescribed motions are evaluated (and locked) at this time
    !> ... or, .true., kept moving: the motion's dynamic stiffening enters the modes.
    logical :: along_motion = .false.
    character(len=:), allocatable :: solver   !< eigensolver: 'auto', 'lapack', 'arpack', 'krylov'
  end type modal_rec_t

  !> Linearised buckling (docs/input.md, &buckling).
  type :: buckling_rec_t
    logical :: active = .false.
    integer :: n_modes = 6             !< at most this many multipliers, lowest first
    real(wp) :: load_factor = 1.0_wp   !< load factor at which K_G is differenced
    character(len=:), allocatable :: solver   !< 'auto', 'dense' or 'krylov'
  end type buckling_rec_t

  !> A feedback controller (docs/input.md, &controller).
  type :: controller_rec_t
    character(len=:), allocatable :: label, reference
    character(len=:), allocatable :: law          !< 'pid' or 'user'
    type(label_t), allocatable :: actuator(:), measure(:)
    integer :: n_states = 0
    real(wp) :: kp = 0.0_wp, ki = 0.0_wp, kd = 0.0_wp, period = 0.0_wp
    real(wp) :: u_min = -huge(1.0_wp), u_max = huge(1.0_wp)
    logical :: feedforward = .false.
    !> law = 'user' from a shared library: its path (resolved against the scene file's folder
    !> when read), the name of the law's C function in it, and the values handed to the law
    !> (unallocated when the program gives the law).
    character(len=:), allocatable :: library, symbol
    real(wp), allocatable :: params(:)
  end type controller_rec_t

  !> A linearised state-space model (docs/input.md, &linear).
  type :: linear_rec_t
    logical :: active = .false.
    real(wp) :: time = 0.0_wp             !< time of the prescribed motions
    logical :: along_motion = .false.     !< joints moving (as &modal along_motion), else held
    !> Inputs 'node.component' (fx, fy, moment | fx, fy, fz, mx, my, mz) and outputs
    !> 'node.component' (x, y, phi | x, y, z, rx, ry, rz).
    type(label_t), allocatable :: inputs(:), outputs(:)
    !> Times along the dynamic run to linearise at (not allocated: the one configuration).
    real(wp), allocatable :: times(:)
  end type linear_rec_t

  !> &dynamic error_check as an enum (read with io_fields' rd_enum).
  integer, parameter, public :: ERROR_CHECK_NONE = 1, ERROR_CHECK_TOLERANCE = 2, &
    ERROR_CHECK_MODES = 3, ERROR_CHECK_MESH = 4
  character(len=*), parameter, public :: ERROR_CHECK_NAMES(4) = [character(len=9) :: 'none', &
    'tolerance', 'modes', 'mesh']

  type :: dynamic_rec_t
    logical :: active = .false.
    real(wp) :: t_end = 0.0_wp, output_dt = 1.0e-3_wp
    !> integrators_system's INTEGRATOR_* (INTEGRATOR_AUTO until chosen: auto_integrator,
    !> auto_by_stiffness) and JACOBIAN_*
    integer :: integrator = INTEGRATOR_AUTO, jacobian = JACOBIAN_LINEARISED
    real(wp) :: rtol = 1.0e-6_wp, atol = 1.0e-8_wp, max_step = 0.0_wp
    integer :: max_order = 0, erk_order = 5
    real(wp) :: dt = 1.0e-3_wp, rho_inf = 0.8_wp
    !> A second run that measures the first one's global error (ERROR_CHECK_*): tolerances
    !> (and a fixed step) divided by error_check_factor, error_check_modes more modes, or
    !> every link's elements halved.
    integer :: error_check = ERROR_CHECK_NONE
    real(wp) :: error_check_factor = 10.0_wp
    integer :: error_check_modes = 2
  end type dynamic_rec_t

  !> The keywords of &reduction's choices as enums, in the order of their names (read with
  !> io_fields' rd_enum, which checks the names against the schema's choices).
  integer, parameter, public :: UPDATE_NONE = 1, UPDATE_INTERVAL = 2, UPDATE_MAC = 3
  character(len=*), parameter, public :: UPDATE_NAMES(3) = [character(len=8) :: 'none', &
    'interval', 'mac']
  integer, parameter, public :: EVALUATION_FULL = 1, EVALUATION_EXPANDED = 2
  character(len=*), parameter, public :: EVALUATION_NAMES(2) = [character(len=8) :: 'full', &
    'expanded']
  integer, parameter, public :: JOINTS_FREE = 1, JOINTS_HELD = 2
  character(len=*), parameter, public :: JOINTS_NAMES(2) = [character(len=4) :: 'free', 'held']

  !> A reduced dynamic analysis: dq_dy = V eta (docs/input.md, &reduction).
  type :: reduction_rec_t
    logical :: active = .false.
    !> How k is chosen: 'count' (n_modes), 'cutoff' (cutoff_hz) or 'auto' (auto_factor times
    !> the bandwidth of the prescribed motions).
    character(len=:), allocatable :: selection
    integer :: n_modes = 0
    real(wp) :: cutoff_hz = 0.0_wp, auto_factor = 0.0_wp
    real(wp) :: basis_time = 0.0_wp
    real(wp), allocatable :: basis_prescribed(:)   !< optional, overrides basis_time
    logical :: static_correction = .false.
    integer :: update = UPDATE_NONE                !< UPDATE_*
    real(wp) :: update_interval = 0.0_wp, mac_threshold = 0.9_wp
    character(len=:), allocatable :: eigensolver   !< 'auto', 'lapack', 'arpack' or 'krylov'
    !> JOINTS_FREE (modes of the free structure) or JOINTS_HELD (the controlled joints held:
    !> their unit motions plus the modes with them held)
    integer :: joints = JOINTS_FREE
    !> EVALUATION_FULL (the full model evaluated at every call) or EVALUATION_EXPANDED
    !> (reduction_expansion)
    integer :: evaluation = EVALUATION_FULL
    real(wp) :: expansion_tol = 1.0e-3_wp
    !> Joints that turn parts rigidly kept exact in the expansions (reduction_frames)
    logical :: exact_turns = .true.
    !> Outputs (spread evenly) where an expanded run measures its error indicators exactly
    integer :: estimate_samples = 10
  end type reduction_rec_t

  type :: scene_t
    character(len=:), allocatable :: title
    integer :: dimension = 2                       !< 2: planar, 3: spatial
    real(wp) :: gravity(3) = 0.0_wp                !< z only in spatial scenes
    character(len=:), allocatable :: linear_solver   !< 'auto', 'dense' or 'sparse'
    type(node_rec_t), allocatable :: nodes(:)
    type(link_rec_t), allocatable :: links(:)
    type(hinge_rec_t), allocatable :: hinges(:)
    type(truss_rec_t), allocatable :: trusses(:)
    type(slider_rec_t), allocatable :: sliders(:)
    type(mass_rec_t), allocatable :: masses(:)
    type(force_rec_t), allocatable :: forces(:)
    type(motion_rec_t), allocatable :: motions(:)
    type(controller_rec_t), allocatable :: controllers(:)
    type(static_rec_t) :: static
    type(modal_rec_t) :: modal
    type(buckling_rec_t) :: buckling
    type(linear_rec_t) :: linear
    type(dynamic_rec_t) :: dynamic
    type(reduction_rec_t) :: reduction
    type(label_t), allocatable :: output_nodes(:)
    !> Nodes whose tangent compliance the static analysis writes (&output compliance_nodes).
    type(label_t), allocatable :: compliance_nodes(:)
  end type scene_t

contains

  !> The integrator of `integrator = 'auto'` (the default), chosen by measurement on the
  !> two-link benchmark (docs/bench/work_precision.md): generalized-alpha with error control
  !> reaches tip errors down to about 1e-6 m fastest (rtol >= 1e-6). Below, the answer
  !> depends on the model, and INTEGRATOR_AUTO is returned: the run decides by auto_by_stiffness.
  pure integer function auto_integrator(rtol) result(method)
    real(wp), intent(in) :: rtol
    if (rtol >= AUTO_GALPHA_RTOL) then
      method = INTEGRATOR_GALPHA_ADAPTIVE
    else
      method = INTEGRATOR_AUTO
    end if
  end function auto_integrator

  !> The run's choice for rtol < 1e-6, from the fastest natural frequency omega_max [rad/s]
  !> of the model and the time span: BDF's higher orders are faster at tight tolerances on
  !> smooth, non-stiff motion (a driven oscillator), but on a stiff model they must resolve
  !> the fastest mode: the two-link at 8 elements per link and rtol 1e-7 took 276,000 BDF
  !> steps (14 s) where galpha_adaptive takes 7,000 (0.4 s), whose numerical damping leaves
  !> the unresolved modes alone.
  pure integer function auto_by_stiffness(omega_max, t_span) result(method)
    real(wp), intent(in) :: omega_max, t_span
    if (omega_max * t_span > AUTO_STIFF_RADIANS) then
      method = INTEGRATOR_GALPHA_ADAPTIVE
    else
      method = INTEGRATOR_BDF
    end if
  end function auto_by_stiffness
end module model_scene
