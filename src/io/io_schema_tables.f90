!> The scene schema's table: every input variable of a scene file, group by group (see
!> io_schema). A new variable is one entry here, its group's count and SCHEMA's, and a row
!> in docs/input.md (tests/python/test_schema_docs.py compares them).
module io_schema_tables
  use core_kinds, only: wp
  use integrators_system, only: MIN_RTOL, MIN_ATOL
  use io_schema_types, only: var_spec_t, PHYS_MIN, PHYS_MAX, VK_REAL, VK_INT, VK_LOGICAL, &
    VK_STRING, VK_CHOICE, &
    VK_REAL_LIST, VK_STRING_LIST, VK_CHOICE_LIST
  implicit none
  private
  public :: SCHEMA

  type(var_spec_t), parameter :: SCENE_VARS(4) = [ &
    var_spec_t('scene', 'title', VK_STRING, '', '', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'free text, the result file title attribute'), &
    var_spec_t('scene', 'gravity', VK_REAL_LIST, 'm/s^2', '0, 0', .false., &
      -PHYS_MAX, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'gravitational acceleration (gx, gy)'), &
    var_spec_t('scene', 'linear_solver', VK_CHOICE, '', 'auto', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      'auto|dense|sparse', 'dense (LAPACK) or sparse (KLU) linear algebra'), &
    var_spec_t('scene', 'dimension', VK_INT, '', '2', .false., &
      2.0_wp, .false., 3.0_wp, .false., 0.0_wp, &
      '', 'planar (2) or spatial (3)')]
  type(var_spec_t), parameter :: NODE_VARS(17) = [ &
    var_spec_t('node', 'label', VK_STRING, '', '', .true., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'unique name'), &
    var_spec_t('node', 'x', VK_REAL, 'm', '', .true., &
      -PHYS_MAX, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'reference position'), &
    var_spec_t('node', 'y', VK_REAL, 'm', '', .true., &
      -PHYS_MAX, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'reference position'), &
    var_spec_t('node', 'fixed', VK_LOGICAL, '', '.false.', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'default of fix_x, fix_y, fix_phi'), &
    var_spec_t('node', 'fix_x', VK_LOGICAL, '', 'fixed', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'hold that coordinate'), &
    var_spec_t('node', 'fix_y', VK_LOGICAL, '', 'fixed', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'hold that coordinate'), &
    var_spec_t('node', 'fix_phi', VK_LOGICAL, '', 'fixed', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'hold that coordinate'), &
    var_spec_t('node', 'dynamic', VK_CHOICE_LIST, '', '', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      'x|y|phi|z|rotation', 'coordinates that are degrees of freedom'), &
    var_spec_t('node', 'motion_x', VK_STRING, '', '', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'motion prescribing that coordinate'), &
    var_spec_t('node', 'motion_y', VK_STRING, '', '', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'motion prescribing that coordinate'), &
    var_spec_t('node', 'motion_phi', VK_STRING, '', '', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'motion prescribing that coordinate'), &
    var_spec_t('node', 'motion_z', VK_STRING, '', '', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'motion prescribing that coordinate (spatial)'), &
    var_spec_t('node', 'z', VK_REAL, 'm', '0', .false., &
      -PHYS_MAX, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'reference position (spatial scenes)'), &
    var_spec_t('node', 'fix_z', VK_LOGICAL, '', 'fixed', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'support (spatial scenes)'), &
    var_spec_t('node', 'fix_rotation', VK_LOGICAL, '', 'fixed', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'clamp the rotation (spatial scenes)'), &
    var_spec_t('node', 'motion_rotation', VK_STRING, '', '', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'motion driving the rotation angle (spatial)'), &
    var_spec_t('node', 'rotation_axis', VK_REAL_LIST, '', '', .false., &
      -PHYS_MAX, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'axis of motion_rotation, fixed in space')]
  type(var_spec_t), parameter :: LINK_VARS(19) = [ &
    var_spec_t('link', 'label', VK_STRING, '', '', .true., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'unique name'), &
    var_spec_t('link', 'from', VK_STRING, '', '', .true., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'end node labels'), &
    var_spec_t('link', 'to', VK_STRING, '', '', .true., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'end node labels'), &
    var_spec_t('link', 'n_elements', VK_INT, '', '1', .false., &
      1.0_wp, .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'beam elements'), &
    var_spec_t('link', 'E', VK_REAL, 'N/m^2 (Pa)', '', .true., &
      PHYS_MIN, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'Young''s modulus'), &
    var_spec_t('link', 'A', VK_REAL, 'm^2', '', .true., &
      PHYS_MIN, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'cross-section area'), &
    var_spec_t('link', 'I', VK_REAL, 'm^4', '', .true., &
      PHYS_MIN, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'second moment of area'), &
    var_spec_t('link', 'rho', VK_REAL, 'kg/m^3', '', .true., &
      PHYS_MIN, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'density'), &
    var_spec_t('link', 'G', VK_REAL, 'N/m^2', '0', .false., &
      0.0_wp, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'shear modulus, 0 = Euler-Bernoulli'), &
    var_spec_t('link', 'shear_factor', VK_REAL, '', '5/6', .false., &
      PHYS_MIN, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'shear correction factor'), &
    var_spec_t('link', 'elongation', VK_CHOICE_LIST, '', 'rigid', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      'rigid|released|dynamic|elastic', 'elongation class, 1 or n_elements values'), &
    var_spec_t('link', 'bending', VK_CHOICE_LIST, '', 'dynamic', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      'rigid|released|dynamic|elastic', 'bending classes, 1, n_elements or 2 n_elements values'), &
    var_spec_t('link', 'bending_form', VK_CHOICE, '', 'angle', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      'angle|sine', 'bending measure'), &
    var_spec_t('link', 'mass', VK_CHOICE, '', 'consistent', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      'consistent|lumped', 'mass model'), &
    var_spec_t('link', 'damping', VK_REAL, 's', '0', .false., &
      0.0_wp, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'stiffness-proportional time constant'), &
    var_spec_t('link', 'Iy', VK_REAL, 'm^4', 'I', .false., &
      PHYS_MIN, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'second moment about section y (spatial)'), &
    var_spec_t('link', 'J', VK_REAL, 'm^4', '', .false., &
      PHYS_MIN, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'torsion constant (spatial scenes)'), &
    var_spec_t('link', 'orientation', VK_REAL_LIST, '', 'z x chord', .false., &
      -PHYS_MAX, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'section y axis direction (spatial scenes)'), &
    var_spec_t('link', 'rotary_inertia', VK_REAL_LIST, 'kg m', 'rho(Iy+I, Iy, I)', .false., &
      0.0_wp, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'rotary inertia per length about x, y, z (spatial)')]
  type(var_spec_t), parameter :: HINGE_VARS(14) = [ &
    var_spec_t('hinge', 'label', VK_STRING, '', '', .true., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'name'), &
    var_spec_t('hinge', 'node', VK_STRING, '', '', .true., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'node label'), &
    var_spec_t('hinge', 'link', VK_STRING, '', '', .true., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'link label'), &
    var_spec_t('hinge', 'mode', VK_CHOICE, '', 'dynamic', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      'rigid|released|prescribed|dynamic|elastic', 'class of the relative rotation'), &
    var_spec_t('hinge', 'motion', VK_STRING, '', '', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'motion of a prescribed hinge'), &
    var_spec_t('hinge', 'stiffness', VK_REAL, 'N m/rad', '0', .false., &
      0.0_wp, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'torsion spring'), &
    var_spec_t('hinge', 'damping', VK_REAL, 's', '0', .false., &
      0.0_wp, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'stiffness-proportional time constant'), &
    var_spec_t('hinge', 'axis', VK_REAL_LIST, '', '0, 0, 1', .false., &
      -PHYS_MAX, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'hinge axis direction (spatial)'), &
    var_spec_t('hinge', 'type', VK_CHOICE, '', 'revolute', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      'revolute|universal|spherical', 'joint type (spatial)'), &
    var_spec_t('hinge', 'torque', VK_REAL, 'N m', '0', .false., &
      -PHYS_MAX, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'actuator torque on a dynamic hinge'), &
    var_spec_t('hinge', 'torque_law', VK_STRING, '', '', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'motion whose value scales torque'), &
    var_spec_t('hinge', 'kp', VK_REAL, 'N m/rad', '0', .false., &
      0.0_wp, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'PD controller: proportional gain'), &
    var_spec_t('hinge', 'kd', VK_REAL, 'N m s/rad', '0', .false., &
      0.0_wp, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'PD controller: derivative gain'), &
    var_spec_t('hinge', 'reference', VK_STRING, '', '', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'PD controller: motion of the reference angle')]
  type(var_spec_t), parameter :: TRUSS_VARS(11) = [ &
    var_spec_t('truss', 'label', VK_STRING, '', '', .true., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'name'), &
    var_spec_t('truss', 'from', VK_STRING, '', '', .true., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'end node labels'), &
    var_spec_t('truss', 'to', VK_STRING, '', '', .true., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'end node labels'), &
    var_spec_t('truss', 'E', VK_REAL, 'N/m^2', '', .true., &
      PHYS_MIN, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'Young''s modulus'), &
    var_spec_t('truss', 'A', VK_REAL, 'm^2', '', .true., &
      PHYS_MIN, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'area'), &
    var_spec_t('truss', 'rho', VK_REAL, 'kg/m^3', '0', .false., &
      0.0_wp, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'density, 0 = massless'), &
    var_spec_t('truss', 'mode', VK_CHOICE, '', 'dynamic', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      'rigid|released|dynamic|elastic', 'class of the elongation'), &
    var_spec_t('truss', 'mass', VK_CHOICE, '', 'consistent', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      'consistent|lumped', 'mass model'), &
    var_spec_t('truss', 'damping', VK_REAL, 's', '0', .false., &
      0.0_wp, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'stiffness-proportional time constant'), &
    var_spec_t('truss', 'force', VK_REAL, 'N', '0', .false., &
      -PHYS_MAX, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'actuator force along a dynamic truss'), &
    var_spec_t('truss', 'force_law', VK_STRING, '', '', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'motion whose value scales force')]
  type(var_spec_t), parameter :: SLIDER_VARS(6) = [ &
    var_spec_t('slider', 'label', VK_STRING, '', '', .true., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'name'), &
    var_spec_t('slider', 'node', VK_STRING, '', '', .true., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'node label'), &
    var_spec_t('slider', 'direction', VK_REAL_LIST, '', '', .true., &
      -PHYS_MAX, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'guide direction (dx, dy)'), &
    var_spec_t('slider', 'mode', VK_CHOICE, '', 'rigid', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      'rigid|released|dynamic|elastic', 'class of the offset across the guide'), &
    var_spec_t('slider', 'stiffness', VK_REAL, 'N/m', '0', .false., &
      0.0_wp, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'guide spring across the guide'), &
    var_spec_t('slider', 'damping', VK_REAL, 's', '0', .false., &
      0.0_wp, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'stiffness-proportional time constant')]
  type(var_spec_t), parameter :: MASS_VARS(6) = [ &
    var_spec_t('mass', 'node', VK_STRING, '', '', .true., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'node label'), &
    var_spec_t('mass', 'm', VK_REAL, 'kg', '0', .false., &
      0.0_wp, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'point mass'), &
    var_spec_t('mass', 'J', VK_REAL, 'kg m^2', '0', .false., &
      0.0_wp, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'rotary inertia'), &
    var_spec_t('mass', 'inertia', VK_REAL_LIST, 'kg m^2', '', .false., &
      -PHYS_MAX, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'inertia tensor Jxx, Jyy, Jzz, Jxy, Jxz, Jyz (spatial)'), &
    var_spec_t('mass', 'rotation', VK_REAL_LIST, 'rad', 'none', .false., &
      -PHYS_MAX, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'axes of inertia: axis (3) and angle (spatial)'), &
    var_spec_t('mass', 'axes', VK_REAL_LIST, '', 'none', .false., &
      -PHYS_MAX, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'axes of inertia: x axis, vector in x-y plane (3D)')]
  type(var_spec_t), parameter :: FORCE_VARS(9) = [ &
    var_spec_t('force', 'node', VK_STRING, '', '', .true., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'node label'), &
    var_spec_t('force', 'fx', VK_REAL, 'N', '0', .false., &
      -PHYS_MAX, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'force components'), &
    var_spec_t('force', 'fy', VK_REAL, 'N', '0', .false., &
      -PHYS_MAX, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'force components'), &
    var_spec_t('force', 'moment', VK_REAL, 'N m', '0', .false., &
      -PHYS_MAX, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'moment'), &
    var_spec_t('force', 'time_law', VK_STRING, '', '', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'motion whose value multiplies the load'), &
    var_spec_t('force', 'fz', VK_REAL, 'N', '0', .false., &
      -PHYS_MAX, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'force component (spatial scenes)'), &
    var_spec_t('force', 'mx', VK_REAL, 'N m', '0', .false., &
      -PHYS_MAX, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'moment, fixed in space (spatial scenes)'), &
    var_spec_t('force', 'my', VK_REAL, 'N m', '0', .false., &
      -PHYS_MAX, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'moment, fixed in space (spatial scenes)'), &
    var_spec_t('force', 'mz', VK_REAL, 'N m', '0', .false., &
      -PHYS_MAX, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'moment, fixed in space (spatial scenes)')]
  type(var_spec_t), parameter :: MOTION_VARS(14) = [ &
    var_spec_t('motion', 'label', VK_STRING, '', '', .true., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'unique name'), &
    var_spec_t('motion', 'law', VK_CHOICE, '', 'cubic', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      'constant|cubic|quintic|cycloidal|ramp|harmonic|spin_up|sum|table', 'time law'), &
    var_spec_t('motion', 'start', VK_REAL, 'rad', '0', .false., &
      -PHYS_MAX, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'value before t0'), &
    var_spec_t('motion', 't0', VK_REAL, 's', '0', .false., &
      -PHYS_MAX, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'start time'), &
    var_spec_t('motion', 'end', VK_REAL, 'rad', 'law', .false., &
      -PHYS_MAX, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'value after t0 + duration'), &
    var_spec_t('motion', 'duration', VK_REAL, 's', 'law', .false., &
      PHYS_MIN, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'length of the motion'), &
    var_spec_t('motion', 'rate', VK_REAL, 'rad/s', 'law', .false., &
      -PHYS_MAX, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'constant (final) rate'), &
    var_spec_t('motion', 'amplitude', VK_REAL, 'rad', 'law', .false., &
      -PHYS_MAX, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'harmonic amplitude'), &
    var_spec_t('motion', 'frequency', VK_REAL, 'Hz', 'law', .false., &
      PHYS_MIN, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'harmonic frequency'), &
    var_spec_t('motion', 'phase', VK_REAL, 'rad', '0', .false., &
      -PHYS_MAX, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'harmonic phase'), &
    var_spec_t('motion', 'terms', VK_STRING_LIST, '', 'law', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'motions to add'), &
    var_spec_t('motion', 'times', VK_REAL_LIST, 's', 'law', .false., &
      -PHYS_MAX, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'table times'), &
    var_spec_t('motion', 'values', VK_REAL_LIST, 'rad', 'law', .false., &
      -PHYS_MAX, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'table values'), &
    var_spec_t('motion', 'file', VK_STRING, '', 'law', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'table CSV file')]
  type(var_spec_t), parameter :: CONTROLLER_VARS(16) = [ &
    var_spec_t('controller', 'label', VK_STRING, '', '', .true., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'name (output /controllers/<label>)'), &
    var_spec_t('controller', 'law', VK_CHOICE, '', 'pid', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      'pid|user', 'PID, or a law set by the program (API)'), &
    var_spec_t('controller', 'actuator', VK_STRING_LIST, '', '', .true., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'hinge.torque, truss.force or node.fx (...)'), &
    var_spec_t('controller', 'measure', VK_STRING_LIST, '', '', .true., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'hinge.angle, truss.elongation or node.x (...)'), &
    var_spec_t('controller', 'reference', VK_STRING, '', '', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'motion of the reference (none: 0)'), &
    var_spec_t('controller', 'kp', VK_REAL, 'u/y', '0', .false., &
      0.0_wp, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'proportional gain'), &
    var_spec_t('controller', 'ki', VK_REAL, 'u/(y s)', '0', .false., &
      0.0_wp, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'integral gain'), &
    var_spec_t('controller', 'kd', VK_REAL, 'u s/y', '0', .false., &
      0.0_wp, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'derivative gain'), &
    var_spec_t('controller', 'n_states', VK_INT, '', '0', .false., &
      0.0_wp, .false., 10000.0_wp, .false., 0.0_wp, &
      '', 'law = ''user'': number of the law''s own states'), &
    var_spec_t('controller', 'period', VK_REAL, 's', '0', .false., &
      0.0_wp, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'sampling period with zero-order hold (0: none)'), &
    var_spec_t('controller', 'u_min', VK_REAL, 'N (N m)', 'none', .false., &
      -PHYS_MAX, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'lower limit of the actuator'), &
    var_spec_t('controller', 'u_max', VK_REAL, 'N (N m)', 'none', .false., &
      -PHYS_MAX, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'upper limit of the actuator'), &
    var_spec_t('controller', 'feedforward', VK_LOGICAL, '', '.false.', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'add the rigid-body inverse dynamics of reference'), &
    var_spec_t('controller', 'library', VK_STRING, '', '', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'law = ''user'': shared library of the law'), &
    var_spec_t('controller', 'symbol', VK_STRING, '', '', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'law = ''user'': the law''s C function in library'), &
    var_spec_t('controller', 'params', VK_REAL_LIST, '', 'none', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'law = ''user'': values handed to the library''s law')]
  type(var_spec_t), parameter :: STATIC_VARS(8) = [ &
    var_spec_t('static', 'n_steps', VK_INT, '', '10', .false., &
      1.0_wp, .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'load steps'), &
    var_spec_t('static', 'tol', VK_REAL, '', '1e-10', .false., &
      0.0_wp, .true., huge(1.0_wp), .false., 0.0_wp, &
      '', 'Newton tolerance relative to the model size'), &
    var_spec_t('static', 'max_iter', VK_INT, '', '30', .false., &
      1.0_wp, .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'Newton iterations per step'), &
    var_spec_t('static', 'n_frequencies', VK_INT, '', '0', .false., &
      0.0_wp, .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'frequencies written per step'), &
    var_spec_t('static', 'method', VK_CHOICE, '', 'load', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      'load|arc_length', 'load control or arc-length continuation'), &
    var_spec_t('static', 'arc_length', VK_REAL, '', 'auto', .false., &
      PHYS_MIN, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'arc-length step in (q/|q1|, lambda)'), &
    var_spec_t('static', 'max_load_factor', VK_REAL, '', 'none', .false., &
      PHYS_MIN, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'arc-length stops beyond this load factor'), &
    var_spec_t('static', 'solver', VK_CHOICE, '', 'auto', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      'auto|dense|krylov', 'Newton: difference tangent or Newton-Krylov')]
  type(var_spec_t), parameter :: MODAL_VARS(4) = [ &
    var_spec_t('modal', 'n_modes', VK_INT, '', '0', .false., &
      0.0_wp, .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'lowest modes kept, 0 = all'), &
    var_spec_t('modal', 'time', VK_REAL, 's', '0', .false., &
      -PHYS_MAX, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'time of the prescribed motions'), &
    var_spec_t('modal', 'along_motion', VK_LOGICAL, '', '.false.', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'dynamic stiffening of the motion at time'), &
    var_spec_t('modal', 'solver', VK_CHOICE, '', 'auto', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      'auto|lapack|arpack|krylov', 'eigensolver')]
  type(var_spec_t), parameter :: LINEAR_VARS(5) = [ &
    var_spec_t('linear', 'inputs', VK_STRING_LIST, '', '', .true., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'inputs node.component (forces, moments)'), &
    var_spec_t('linear', 'outputs', VK_STRING_LIST, '', '', .true., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'outputs node.component (displacements, rotations)'), &
    var_spec_t('linear', 'time', VK_REAL, 's', '0', .false., &
      -PHYS_MAX, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'time of the prescribed motions'), &
    var_spec_t('linear', 'along_motion', VK_LOGICAL, '', '.false.', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'linearise along the motion (joints moving)'), &
    var_spec_t('linear', 'times', VK_REAL_LIST, 's', 'none', .false., &
      -PHYS_MAX, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'times along the dynamic run')]
  type(var_spec_t), parameter :: BUCKLING_VARS(3) = [ &
    var_spec_t('buckling', 'n_modes', VK_INT, '', '6', .false., &
      1.0_wp, .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'multipliers kept'), &
    var_spec_t('buckling', 'load_factor', VK_REAL, '', '1', .false., &
      PHYS_MIN, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'load factor of the difference'), &
    var_spec_t('buckling', 'solver', VK_CHOICE, '', 'auto', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      'auto|dense|krylov', 'dense eigenproblem or matrix-free Arnoldi')]
  type(var_spec_t), parameter :: DYNAMIC_VARS(14) = [ &
    var_spec_t('dynamic', 't_end', VK_REAL, 's', '', .true., &
      PHYS_MIN, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'end time'), &
    var_spec_t('dynamic', 'output_dt', VK_REAL, 's', '1e-3', .false., &
      PHYS_MIN, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'output interval'), &
    var_spec_t('dynamic', 'integrator', VK_CHOICE, '', 'auto', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      'auto|bdf|galpha|galpha_adaptive|erk', 'time integrator'), &
    var_spec_t('dynamic', 'jacobian', VK_CHOICE, '', 'linearised', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      'linearised|fd|internal', 'Jacobian of the implicit integrators'), &
    var_spec_t('dynamic', 'rtol', VK_REAL, '', '1e-6', .false., &
      MIN_RTOL, .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'relative tolerance'), &
    var_spec_t('dynamic', 'atol', VK_REAL, '', '1e-8', .false., &
      MIN_ATOL, .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'absolute tolerance'), &
    var_spec_t('dynamic', 'max_step', VK_REAL, 's', '0', .false., &
      0.0_wp, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'largest step, 0 = no limit'), &
    var_spec_t('dynamic', 'max_order', VK_INT, '', '0', .false., &
      0.0_wp, .false., 5.0_wp, .false., 0.0_wp, &
      '', 'largest BDF order, 0 = by rtol'), &
    var_spec_t('dynamic', 'erk_order', VK_INT, '', '5', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '2|3|4|5|6|8', 'order of the Runge-Kutta pair'), &
    var_spec_t('dynamic', 'dt', VK_REAL, 's', '1e-3', .false., &
      PHYS_MIN, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'generalized-alpha step'), &
    var_spec_t('dynamic', 'rho_inf', VK_REAL, '', '0.8', .false., &
      0.0_wp, .false., 1.0_wp, .false., 0.0_wp, &
      '', 'spectral radius at infinite frequency'), &
    var_spec_t('dynamic', 'error_check', VK_CHOICE, '', 'none', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      'none|tolerance|modes|mesh', 'second run that measures the global error'), &
    var_spec_t('dynamic', 'error_check_factor', VK_REAL, '', '10', .false., &
      1.0_wp, .true., huge(1.0_wp), .false., 0.0_wp, &
      '', 'tolerances (and dt) divided by this'), &
    var_spec_t('dynamic', 'error_check_modes', VK_INT, '', '2', .false., &
      1.0_wp, .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'modes added for the check')]
  type(var_spec_t), parameter :: REDUCTION_VARS(15) = [ &
    var_spec_t('reduction', 'n_modes', VK_INT, '', 'one of three', .false., &
      1.0_wp, .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'modes kept'), &
    var_spec_t('reduction', 'cutoff_hz', VK_REAL, 'Hz', 'one of three', .false., &
      PHYS_MIN, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'keep modes up to this frequency'), &
    var_spec_t('reduction', 'auto_factor', VK_REAL, '', 'one of three', .false., &
      PHYS_MIN, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'multiple of the motion bandwidth'), &
    var_spec_t('reduction', 'basis_time', VK_REAL, 's', '0', .false., &
      -PHYS_MAX, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'configuration of the basis'), &
    var_spec_t('reduction', 'basis_prescribed', VK_REAL_LIST, 'rad (m)', 'motions', .false., &
      -PHYS_MAX, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'prescribed values of the basis configuration'), &
    var_spec_t('reduction', 'static_correction', VK_LOGICAL, '', '.false.', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'mode-acceleration correction of the output'), &
    var_spec_t('reduction', 'update', VK_CHOICE, '', 'none', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      'none|interval|mac', 'basis updates'), &
    var_spec_t('reduction', 'update_interval', VK_REAL, 's', 'with update', .false., &
      PHYS_MIN, .false., PHYS_MAX, .false., PHYS_MIN, &
      '', 'time between checks'), &
    var_spec_t('reduction', 'mac_threshold', VK_REAL, '', '0.9', .false., &
      0.0_wp, .true., 1.0_wp, .false., 0.0_wp, &
      '', 'MAC below which the basis is replaced'), &
    var_spec_t('reduction', 'eigensolver', VK_CHOICE, '', 'auto', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      'auto|lapack|arpack|krylov', 'eigensolver of the basis'), &
    var_spec_t('reduction', 'joints', VK_CHOICE, '', 'free', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      'free|held', 'controlled joints free or held in the basis'), &
    var_spec_t('reduction', 'evaluation', VK_CHOICE, '', 'full', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      'full|expanded', 'model pass or expansion per evaluation'), &
    var_spec_t('reduction', 'expansion_tol', VK_REAL, '', '1e-3', .false., &
      0.0_wp, .true., 1.0_wp, .false., 0.0_wp, &
      '', 'relative size of the expansion''s dropped terms'), &
    var_spec_t('reduction', 'exact_turns', VK_LOGICAL, '', '.true.', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'joints that turn parts rigidly exact in an expansion'), &
    var_spec_t('reduction', 'estimate_samples', VK_INT, '', '10', .false., &
      0.0_wp, .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'outputs where an expanded run measures its error exactly')]
  type(var_spec_t), parameter :: OUTPUT_VARS(2) = [ &
    var_spec_t('output', 'nodes', VK_STRING_LIST, '', 'all nodes', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'output nodes'), &
    var_spec_t('output', 'compliance_nodes', VK_STRING_LIST, '', '', .false., &
      -huge(1.0_wp), .false., huge(1.0_wp), .false., 0.0_wp, &
      '', 'nodes whose static compliance is written')]
  !> Every variable, group by group.
  type(var_spec_t), parameter :: SCHEMA(167) = [ &
    SCENE_VARS, NODE_VARS, LINK_VARS, HINGE_VARS, TRUSS_VARS, SLIDER_VARS, &
    MASS_VARS, FORCE_VARS, MOTION_VARS, CONTROLLER_VARS, &
    STATIC_VARS, MODAL_VARS, BUCKLING_VARS, LINEAR_VARS, DYNAMIC_VARS, REDUCTION_VARS, &
    OUTPUT_VARS]

end module io_schema_tables
