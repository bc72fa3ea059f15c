"""Feedback controllers (docs/input.md, &controller): PID laws on a joint, a truss actuator and
a nodal force, continuous and sampled, with limits, against the closed forms of the linear
closed loops they make; the result datasets; every input error."""
import math
import re

import numpy as np
import pytest

from helpers import ROOT, assert_clean_error, run_scene

h5py = pytest.importorskip("h5py")

#: A rigid 1 m link hinged at a fixed base (as in test_linear.py): J = rho A L^3 / 3.
ARM = ("&node label = 'base', x = 0, y = 0, fixed = .true. /\n"
       "&node label = 'tip', x = 1, y = 0 /\n"
       "&link label = 'arm', from = 'base', to = 'tip', n_elements = 2, E = 7.0e10,\n"
       "      A = 1.0e-4, I = 1.0e-9, rho = 2700, elongation = 'rigid', bending = 'rigid' /\n")
J_ARM = 2700 * 1.0e-4 / 3
RUN = ("&dynamic t_end = {t_end}, output_dt = 0.01, integrator = 'bdf', rtol = 1e-9,"
       " atol = 1e-12 /\n&output nodes = 'tip' /\n")

#: A block of mass M on a guide inclined at ALPHA, held by a truss spring along it (as in
#: test_slider.py), no gravity: a linear oscillator in the elongation s of the truss.
ALPHA = math.radians(30.0)
M, EA, L0 = 2.0, 1.0e4, 0.5
C, S = math.cos(ALPHA), math.sin(ALPHA)
BLOCK = f"""&node label = 'anchor', x = 0.0, y = 0.0, fixed = .true. /
&node label = 'block', x = {L0 * C!r}, y = {L0 * S!r} /
&truss label = 'spring', from = 'anchor', to = 'block', E = {EA}, A = 1.0, mode = 'dynamic' /
&slider label = 'guide', node = 'block', direction = {C!r}, {S!r} /
&mass node = 'block', m = {M} /
&motion label = 'step', law = 'constant', start = 1.0e-3 /
&dynamic t_end = 2.0, output_dt = 0.01, integrator = 'bdf', rtol = 1e-9, atol = 1e-13 /
&output nodes = 'block' /
"""


def linear_response(a, b, x0, t):
    """x(t) of x' = A x + b (A invertible, b constant) from x0: exp(A t)(x0 - xs) + xs with
    the equilibrium xs = -A^-1 b, by the eigenvectors of A (distinct eigenvalues)."""
    w, v = np.linalg.eig(a)
    xs = -np.linalg.solve(a, b)
    c = np.linalg.solve(v, x0 - xs)
    return np.real((v * c) @ np.exp(np.outer(w, t))) + xs[:, None]


def pid_loop(mass, stiffness, gain, kp, ki, kd, force=0.0, ref=0.0):
    """The closed loop m y'' = -k y + g u + f, u = kp (r - y) + ki I + kd (r' - y'),
    I' = r - y, for a constant r (r' = 0 after t = 0), in the state (I, y, y')."""
    a = np.array([[0.0, -1.0, 0.0], [0.0, 0.0, 1.0],
                  [gain * ki / mass, -(stiffness + gain * kp) / mass, -gain * kd / mass]])
    b = np.array([ref, 0.0, (gain * kp * ref + force) / mass])
    return a, b


def arm_angle(out):
    with h5py.File(out) as f:
        tip = f["nodes/tip/position"][:]
        return f["time"][:], np.unwrap(np.arctan2(tip[:, 1], tip[:, 0]))


def run_ok(tmp_path, text, name="scene"):
    proc, out = run_scene(tmp_path, text, name=name)
    assert proc.returncode == 0, proc.stderr
    assert "warning" not in proc.stderr
    return out


def test_pid_rejects_a_constant_torque(tmp_path):
    """A constant torque on the rigid link's hinge, a PID holding the angle at 0: the closed
    loop J y''' + kd y'' + kp y' + ki y = 0 from rest with y'' = tau/J at the start, and the
    integral drives the angle back to 0 (a PD would leave tau/kp). Observed 1.3e-10 rad at
    BDF rtol 1e-9; bound 1e-8. The written error is -y, the measure y, the input settles at
    -tau."""
    kp, ki, kd, tau = 2.0, 1.0, 0.5, 0.05
    out = run_ok(tmp_path, ARM + f"&hinge label = 'j1', node = 'base', link = 'arm', "
                 f"mode = 'dynamic', torque = {tau} /\n&controller label = 'c1', "
                 f"actuator = 'j1.torque', measure = 'j1.angle', kp = {kp}, ki = {ki}, "
                 f"kd = {kd} /\n" + RUN.format(t_end=10.0))
    t, angle = arm_angle(out)
    a, b = pid_loop(J_ARM, 0.0, 1.0, kp, ki, kd, force=tau)
    closed = linear_response(a, b, np.zeros(3), t)[1]
    assert np.max(np.abs(angle - closed)) < 1e-8
    with h5py.File(out) as f:
        error = f["controllers/c1/error"][:]
        u = f["controllers/c1/input"][:]
        measure = f["controllers/c1/measure"][:]
    assert np.max(np.abs(error + angle)) < 1e-8
    assert np.max(np.abs(measure - angle)) < 1e-8   # the hinge's q is the tip's angle
    assert abs(u[-1] + tau) < 1e-3 * tau      # observed 3e-6 tau at t = 10 s (decay)


@pytest.mark.parametrize("actuator,measure,gain", [
    ("spring.force", "spring.elongation", 1.0),
    ("block.fx", "block.x", C),
])
def test_pid_positions_a_block(tmp_path, actuator, measure, gain):
    """The block on its guide, positioned by a PID on a step of 1 mm: by the truss as a linear
    actuator measuring its elongation s (gain 1), or by a horizontal force on the node
    measuring its x = cos(alpha) s (both the force and the measurement see cos(alpha): the
    loop gain is cos^2 alpha, in y = cos(alpha) s). Closed form of the linear loop; the truss is
    exact along its line. Observed 4e-12 and 1e-11 m; bound 1e-10 m."""
    kp, ki, kd = 4.0e4, 2.0e5, 400.0
    out = run_ok(tmp_path, BLOCK + f"&controller label = 'pos', actuator = '{actuator}', "
                 f"measure = '{measure}', reference = 'step', kp = {kp}, ki = {ki}, "
                 f"kd = {kd} /\n")
    with h5py.File(out) as f:
        t = f["time"][:]
        pos = f["nodes/block/position"][:, :2]
    s = (pos - [L0 * C, L0 * S]) @ np.array([C, S])
    # In the measured y = gain s: m y'' = -k y + gain^2 u.
    a, b = pid_loop(M, EA / L0, gain**2, kp, ki, kd, ref=1.0e-3)
    closed = linear_response(a, b, np.zeros(3), t)[1] / gain
    assert np.max(np.abs(s - closed)) < 1e-10


def test_limited_output_accelerates_uniformly(tmp_path):
    """A PD with a large step on the rigid link and the torque limited to u_max: while the law
    asks for more, the link accelerates as u_max t^2 / (2 J) exactly; it then settles on the
    reference (observed 3.6e-10 rad left at t = 8 s; bound 1e-6). Observed 6e-12 rad in the
    saturated phase; bound 1e-8."""
    u_max, ref = 0.1, 1.0
    out = run_ok(tmp_path, ARM + "&hinge label = 'j1', node = 'base', link = 'arm', "
                 "mode = 'dynamic' /\n&motion label = 'r', law = 'constant', "
                 f"start = {ref} /\n&controller label = 'c1', actuator = 'j1.torque', "
                 f"measure = 'j1.angle', reference = 'r', kp = 1.0, kd = 0.6, "
                 f"u_min = {-u_max}, u_max = {u_max} /\n" + RUN.format(t_end=8.0))
    t, angle = arm_angle(out)
    with h5py.File(out) as f:
        u = f["controllers/c1/input"][:]
    saturated = np.cumprod(np.isclose(u, u_max, rtol=0, atol=1e-14)).astype(bool)
    assert 5 < saturated.sum() < len(t) - 5          # the limit binds, then is left
    assert np.max(np.abs(angle[saturated] - u_max * t[saturated]**2 / (2 * J_ARM))) < 1e-8
    assert np.max(np.abs(u)) <= u_max * (1 + 1e-12)
    assert abs(angle[-1] - ref) < 1e-6


def test_sampled_converges_to_continuous(tmp_path):
    """The disturbance-rejection loop of the first test sampled with zero-order hold: the hold
    delays the control by about T/2, so the difference from the continuous loop is first
    order in T. Observed differences 3.4e-4, 1.7e-4, 8.4e-5 rad for T = 10, 5, 2.5 ms: ratio
    2.0 per halving (bounds 1.7 to 2.3), and 8.4e-5 rad at 2.5 ms (bound 1e-3)."""
    base = ARM + ("&hinge label = 'j1', node = 'base', link = 'arm', mode = 'dynamic', "
                  "torque = 0.05 /\n&controller label = 'c1', actuator = 'j1.torque', "
                  "measure = 'j1.angle', kp = 2.0, ki = 1.0, kd = 0.5{period} /\n"
                  + RUN.format(t_end=4.0))
    _, cont = arm_angle(run_ok(tmp_path, base.format(period=""), "cont"))
    diffs = []
    for i, period in enumerate([0.01, 0.005, 0.0025]):
        _, samp = arm_angle(run_ok(tmp_path, base.format(period=f", period = {period}"),
                                   f"s{i}"))
        diffs.append(np.max(np.abs(samp - cont)))
    ratios = np.array(diffs[:-1]) / np.array(diffs[1:])
    assert np.all((ratios > 1.7) & (ratios < 2.3)), diffs
    assert diffs[-1] < 1e-3


@pytest.mark.parametrize("ctrl,fragments", [
    ("actuator = 'j9.torque', measure = 'j1.angle', kp = 1.0",
     ["&controller 'c1'", "'actuator'", "'j9'"]),
    ("actuator = 'j1', measure = 'j1.angle', kp = 1.0",
     ["&controller 'c1'", "'actuator'", "name.component"]),
    ("actuator = 'j1.force', measure = 'j1.angle', kp = 1.0",
     ["&controller 'c1'", "'actuator'", "'torque'"]),
    ("actuator = 'j1.torque', measure = 'j1.torque', kp = 1.0",
     ["&controller 'c1'", "'measure'", "'angle'"]),
    ("actuator = 'tip.fz', measure = 'j1.angle', kp = 1.0",
     ["&controller 'c1'", "'actuator'", "fx, fy, moment"]),
    ("actuator = 'base.fx', measure = 'j1.angle', kp = 1.0",
     ["&controller 'c1'", "'actuator'", "fixed"]),
    ("actuator = 'j1.torque', measure = 'tip.q', kp = 1.0",
     ["&controller 'c1'", "'measure'", "x, y, phi"]),
    ("actuator = 'j1.torque', measure = 'j1.angle'", ["&controller 'c1'", "gain"]),
    ("actuator = 'j1.torque', measure = 'j1.angle', kp = -1.0", ["&controller 'c1'", "'kp'"]),
    ("actuator = 'j1.torque', measure = 'j1.angle', kp = 1.0, period = -0.1",
     ["&controller 'c1'", "'period'"]),
    ("actuator = 'j1.torque', measure = 'j1.angle', kp = 1.0, u_min = 1.0, u_max = -1.0",
     ["&controller 'c1'", "'u_min'", "'u_max'"]),
    ("actuator = 'j1.torque', measure = 'j1.angle', kp = 1.0, reference = 'nope'",
     ["&controller 'c1'", "'reference'", "'nope'"]),
    ("measure = 'j1.angle', kp = 1.0", ["&controller 'c1'", "'actuator'"]),    # Two different actuators ('j1.torque' twice is refused by the reader as a repeat).
    ("actuator = 'j1.torque', 'tip.fx', measure = 'j1.angle', kp = 1.0",
     ["&controller 'c1'", "law = 'pid'", "one 'actuator'"]),
    ("actuator = 'j1.torque', measure = 'j1.angle', 'tip.x', kp = 1.0",
     ["&controller 'c1'", "one 'measure'"]),
    ("law = 'user', actuator = 'j1.torque', measure = 'j1.angle', n_states = -1",
     ["&controller 'c1'", "'n_states'"]),
    ("law = 'user', actuator = 'j1.torque', measure = 'j1.angle', kp = 1.0",
     ["&controller 'c1'", "'kp'", "law = 'pid'"]),
    ("actuator = 'j1.torque', measure = 'j1.angle', kp = 1.0, n_states = 2",
     ["&controller 'c1'", "'n_states'", "law = 'user'"]),
    ("law = 'fuzzy', actuator = 'j1.torque', measure = 'j1.angle'",
     ["&controller 'c1'", "'law'", "'fuzzy'"]),
    ("law = 'user', actuator = 'j1.torque', 'j9.torque', measure = 'j1.angle'",
     ["&controller 'c1'", "'actuator'", "'j9'"]),
])
def test_bad_controller(tmp_path, ctrl, fragments):
    text = (ARM + "&hinge label = 'j1', node = 'base', link = 'arm', mode = 'dynamic' /\n"
            f"&controller label = 'c1', {ctrl} /\n" + RUN.format(t_end=0.1))
    proc, out = run_scene(tmp_path, text)
    assert_clean_error(proc, out, "&controller", *fragments[1:])


def test_user_law_needs_a_law(tmp_path):
    """law = 'user' without `library` takes its law from a program through the API: the
    flexmor program has none and says where one comes from (the library test
    test_user_control checks the same for run_t); without a &dynamic analysis the controllers
    are not run, so the open-loop analyses work."""
    ctrl = ("&hinge label = 'j1', node = 'base', link = 'arm', mode = 'dynamic' /\n"
            "&controller label = 'ext', law = 'user', actuator = 'j1.torque', "
            "measure = 'j1.angle', n_states = 1, period = 0.01 /\n")
    proc, out = run_scene(tmp_path, ARM + ctrl + RUN.format(t_end=0.1))
    assert_clean_error(proc, out, "&controller 'ext'", "'law'", "'user'", "'library'",
                       "set_control_law")
    run_ok(tmp_path, ARM + ctrl + "&modal n_modes = 1 /\n", "modal")


def test_controller_on_a_prescribed_joint(tmp_path):
    """A controller drives a degree of freedom: a prescribed hinge is refused."""
    text = (ARM.replace("bending = 'rigid'", "bending = 'dynamic'")
            + "&hinge label = 'j1', node = 'base', link = 'arm', mode = 'prescribed', "
            "motion = 'm' /\n&motion label = 'm', law = 'constant', start = 0.0 /\n"
            "&controller label = 'c1', actuator = 'j1.torque', measure = 'j1.angle', "
            "kp = 1.0 /\n" + RUN.format(t_end=0.1))
    proc, out = run_scene(tmp_path, text)
    assert_clean_error(proc, out, "&controller 'c1'", "'actuator'", "not dynamic")


def test_two_controllers_with_one_label(tmp_path):
    ctrl = ("&controller label = 'c1', actuator = 'j1.torque', measure = 'j1.angle', "
            "kp = 1.0 /\n")
    text = (ARM + "&hinge label = 'j1', node = 'base', link = 'arm', mode = 'dynamic' /\n"
            + ctrl + ctrl + RUN.format(t_end=0.1))
    proc, out = run_scene(tmp_path, text)
    assert_clean_error(proc, out, "&controller 'c1'", "twice")


def test_reduced_closed_loop_equals_full(tmp_path):
    """The rigid link has one dynamic coordinate: its one-mode reduced model is the full model,
    so the reduced closed loop (the controller's state integrated with eta) gives the same
    response to round-off and integrator tolerance. Observed 2e-13 rad; bound 1e-8."""
    base = (ARM + "&hinge label = 'j1', node = 'base', link = 'arm', mode = 'dynamic', "
            "torque = 0.05 /\n&controller label = 'c1', actuator = 'j1.torque', "
            "measure = 'j1.angle', kp = 2.0, ki = 1.0, kd = 0.5 /\n" + RUN.format(t_end=4.0))
    _, full = arm_angle(run_ok(tmp_path, base, "full"))
    _, red = arm_angle(run_ok(tmp_path, base + "&reduction n_modes = 1 /\n", "red"))
    assert np.max(np.abs(red - full)) < 1e-8


def test_stage_example_settles(tmp_path):
    """input/stage_pid.nml: the PID brings the shuttle to the 1 mm step (integral action: no
    steady error; observed 4.6e-8 m at t = 0.3 s, bound 1e-6 m) with the force the guide's
    stiffness needs, 24 EI/L^3 x 1 mm = 0.2268 N (observed 0.22725 N: the guide stiffens
    slightly with the stroke; bound 2 %). The 1 N limit binds at the start. A one-mode reduced
    model follows the full one to 1.6e-6 m (0.16 % of the step; bound 2 %)."""
    text = (ROOT / "input" / "stage_pid.nml").read_text()
    out = run_ok(tmp_path, text, "full")
    with h5py.File(out) as f:
        x = f["nodes/shuttle/position"][:, 0] - 0.025
        u = f["controllers/position/input"][:]
    assert abs(x[-1] - 1.0e-3) < 1e-6
    assert abs(u[-1] / (24 * 2.1e11 * 4.5e-14 / 0.1**3 * 1.0e-3) - 1) < 2e-2
    assert u[0] == pytest.approx(1.0, abs=1e-12) and np.max(u) <= 1.0 + 1e-12
    out = run_ok(tmp_path, text.replace("&output", "&reduction n_modes = 1 /\n&output"), "red")
    with h5py.File(out) as f:
        x_red = f["nodes/shuttle/position"][:, 0] - 0.025
    assert np.max(np.abs(x_red - x)) < 2e-5


def test_feedforward_tracks_a_rigid_link_exactly(tmp_path):
    """With feedforward the controller adds the torque the rigid-body model needs to follow
    its reference, J r'' here (the cubic law: r'' = (6 - 12 t/T)/T^2 until T): the rigid link
    then follows the reference exactly and the PD has nothing to correct. Observed error
    3.7e-11 rad and torque J r'' to 5.7e-11 N m (BDF rtol 1e-9); bounds 1e-8."""
    out = run_ok(tmp_path, ARM + "&hinge label = 'j1', node = 'base', link = 'arm', "
                 "mode = 'dynamic' /\n&motion label = 'r', law = 'cubic', start = 0.0, "
                 "end = 1.0, duration = 0.5 /\n&controller label = 'c1', actuator = 'j1.torque', "
                 "measure = 'j1.angle', reference = 'r', kp = 1.0, kd = 0.3, "
                 "feedforward = .true. /\n" + RUN.format(t_end=1.0))
    with h5py.File(out) as f:
        t = f["time"][:]
        error = f["controllers/c1/error"][:]
        u = f["controllers/c1/input"][:]
    s = np.clip(t / 0.5, 0.0, 1.0)
    r_ddot = np.where(t < 0.5, (6 - 12 * s) / 0.5**2, 0.0)
    assert np.max(np.abs(error)) < 1e-8
    assert np.max(np.abs(u - J_ARM * r_ddot)) < 1e-8


@pytest.mark.parametrize("extra,ctrl,fragments", [
    ("", "actuator = 'j1.torque', measure = 'tip.y', reference = 'r', kp = 1.0",
     ["&controller 'c1'", "'feedforward'", "measure the hinge"]),
    ("", "actuator = 'j1.torque', measure = 'j1.angle', kp = 1.0",
     ["&controller 'c1'", "'feedforward'", "'reference'"]),
    ("&hinge label = 'j2', node = 'tip', link = 'arm', mode = 'dynamic' /\n"
     "&mass node = 'tip', m = 1.0, J = 0.01 /\n",
     "actuator = 'j1.torque', measure = 'j1.angle', reference = 'r', kp = 1.0",
     ["feedforward", "'j2'", "freely"]),
])
def test_bad_feedforward(tmp_path, extra, ctrl, fragments):
    """Feedforward needs a controller that measures the joint it drives, a reference, and a
    rigid model that the references determine (no free joint without a feedforward)."""
    text = (ARM + "&hinge label = 'j1', node = 'base', link = 'arm', mode = 'dynamic' /\n"
            + extra + "&motion label = 'r', law = 'cubic', start = 0.0, end = 1.0, "
            f"duration = 0.5 /\n&controller label = 'c1', {ctrl}, feedforward = .true. /\n"
            + RUN.format(t_end=0.1))
    proc, out = run_scene(tmp_path, text)
    assert_clean_error(proc, out, *fragments)


#: The rigid link in space, hinged about z at the fixed base (its rotation clamped): the
#: section's rotary inertia is left out so that J is the planar link's.
ARM_3D = ("&scene dimension = 3 /\n"
          "&node label = 'base', x = 0, y = 0, z = 0, fixed = .true. /\n"
          "&node label = 'tip', x = 1, y = 0, z = 0 /\n"
          "&link label = 'arm', from = 'base', to = 'tip', n_elements = 2, E = 7.0e10,\n"
          "      A = 1.0e-4, I = 1.0e-9, Iy = 1.0e-9, J = 2.0e-9, G = 2.7e10, rho = 2700,\n"
          "      rotary_inertia = 0, 0, 0, elongation = 'rigid', bending = 'rigid' /\n"
          "&hinge label = 'j1', node = 'base', link = 'arm', axis = 0, 0, 1, "
          "mode = 'dynamic', torque = 0.05 /\n")


def test_pid_on_a_spatial_hinge(tmp_path):
    """The constant-torque rejection of the first test on a spatial revolute hinge (its twist
    about the axis, e1 = 2 atan2(mu . n, mu0)): the same closed form. Observed 1.3e-10 rad;
    bound 1e-8."""
    kp, ki, kd, tau = 2.0, 1.0, 0.5, 0.05
    out = run_ok(tmp_path, ARM_3D + "&controller label = 'c1', actuator = 'j1.torque', "
                 f"measure = 'j1.angle', kp = {kp}, ki = {ki}, kd = {kd} /\n"
                 + RUN.format(t_end=5.0))
    t, angle = arm_angle(out)
    a, b = pid_loop(J_ARM, 0.0, 1.0, kp, ki, kd, force=tau)
    assert np.max(np.abs(angle - linear_response(a, b, np.zeros(3), t)[1])) < 1e-8


def test_measured_mode_by_number(tmp_path):
    """'spring.e1' names the truss's first mode, the same coordinate as 'spring.elongation':
    the same run to the last bit."""
    results = []
    for i, measure in enumerate(["spring.elongation", "spring.e1"]):
        out = run_ok(tmp_path, BLOCK + f"&controller label = 'pos', actuator = 'spring.force', "
                     f"measure = '{measure}', reference = 'step', kp = 4.0e4, kd = 400.0 /\n",
                     f"m{i}")
        with h5py.File(out) as f:
            results.append(f["nodes/block/position"][:])
    assert np.array_equal(results[0], results[1])


@pytest.mark.parametrize("measure,fragments", [
    ("arm#1.e9", ["'measure'", "modes e1 to e3"]),
    ("arm#1.e1", ["'measure'", "rigid", "dynamic or prescribed"]),
    ("arm#7.e1", ["'measure'", "no hinge, truss or node", "'arm#7'"]),
])
def test_bad_measured_mode(tmp_path, measure, fragments):
    text = (ARM + "&hinge label = 'j1', node = 'base', link = 'arm', mode = 'dynamic' /\n"
            f"&controller label = 'c1', actuator = 'j1.torque', measure = '{measure}', "
            "kp = 1.0 /\n" + RUN.format(t_end=0.1))
    proc, out = run_scene(tmp_path, text)
    assert_clean_error(proc, out, "&controller 'c1'", *fragments)


def test_controller_and_hinge_pd_on_one_hinge(tmp_path):
    """&hinge kp is a PD of its own on the hinge: a &controller on it as well is refused."""
    text = (ARM + "&hinge label = 'j1', node = 'base', link = 'arm', mode = 'dynamic', "
            "kp = 1.0 /\n&controller label = 'c1', actuator = 'j1.torque', "
            "measure = 'j1.angle', kp = 1.0 /\n" + RUN.format(t_end=0.1))
    proc, out = run_scene(tmp_path, text)
    assert_clean_error(proc, out, "&controller 'c1'", "'actuator'", "kp")


def test_python_reads_the_controllers(tmp_path):
    """flexmor.read_result gives each controller's error and input at the output times."""
    import flexmor
    out = run_ok(tmp_path, ARM + "&hinge label = 'j1', node = 'base', link = 'arm', "
                 "mode = 'dynamic', torque = 0.05 /\n&controller label = 'c1', "
                 "actuator = 'j1.torque', measure = 'j1.angle', kp = 2.0, kd = 0.5 /\n"
                 + RUN.format(t_end=0.5))
    r = flexmor.read_result(out)
    assert set(r.controllers) == {"c1"}
    assert r.controllers["c1"]["input"].shape == r.time.shape
    with h5py.File(out) as f:
        assert np.array_equal(r.controllers["c1"]["error"], f["controllers/c1/error"][:])


def arm_under_pd(reduction=""):
    """input/two_link_pd.nml with its joint PD as &controller groups (1 s), and a &reduction."""
    text = (ROOT / "input" / "two_link_pd.nml").read_text()
    text = re.sub(r",\s*kp = [0-9.]+, kd = [0-9.]+, reference = '(phi[12])' /", " /", text)
    text = text.replace("t_end = 1.5", "t_end = 1.0")
    for joint, kp, kd in (("joint1", 2000.0, 140.0), ("joint2", 560.0, 40.0)):
        text += (f"&controller label = '{joint}', actuator = '{joint}.torque', measure = "
                 f"'{joint}.angle', reference = 'phi{joint[-1]}', kp = {kp}, kd = {kd} /\n")
    return text + reduction


def test_held_joint_basis_for_a_controlled_arm(tmp_path):
    """The two-link arm under joint PD: the modes of the free structure (joints free: two
    rigid-body modes, then elastic modes from 55 Hz) span the deflection of links that the
    controllers nearly hold at their joints poorly; the joints' unit motions plus the modes
    with the joints held (joints = 'held') span it well. With 4 modes (2 elastic) the tip
    leaves the full model's path by 9.3e-2 m (free) and 6.2e-4 m (held) observed; bounds:
    held below 6e-3 m and at least 10 times closer than free."""
    def tip(name, reduction=""):
        out = run_ok(tmp_path, arm_under_pd(reduction), name)
        with h5py.File(out) as f:
            return f["nodes/tip/position"][:, :2]
    full = tip("full")
    free = np.max(np.linalg.norm(tip("free", "&reduction n_modes = 4 /\n") - full, axis=1))
    held = np.max(np.linalg.norm(
        tip("held", "&reduction n_modes = 4, joints = 'held' /\n") - full, axis=1))
    assert held < 6e-3
    assert 10 * held < free
    # Updated as the arm turns (the held-joint basis of the configuration reached, replaced
    # when a MAC falls below 0.999): observed 1.7e-4 m at 1 s.
    updated = np.max(np.linalg.norm(tip("updated", "&reduction n_modes = 4, joints = 'held', "
                                        "update = 'mac', update_interval = 0.01, "
                                        "mac_threshold = 0.999 /\n") - full, axis=1))
    assert updated < 2e-3


@pytest.mark.parametrize("reduction,fragments", [
    ("n_modes = 1, joints = 'held'", ["&reduction", "n_modes = 1", "held joints (2)"]),
    ("cutoff_hz = 100.0, joints = 'held'", ["&reduction", "'joints'", "n_modes"]),
])
def test_bad_held_joint_basis(tmp_path, reduction, fragments):
    proc, out = run_scene(tmp_path, arm_under_pd(f"&reduction {reduction} /\n"))
    assert_clean_error(proc, out, *fragments)


def test_held_joints_need_a_controller(tmp_path):
    text = (ROOT / "input" / "two_link_pd.nml").read_text().replace(
        "&output", "&reduction n_modes = 4, joints = 'held' /\n&output")
    proc, out = run_scene(tmp_path, text)
    assert_clean_error(proc, out, "&reduction", "'joints'", "no &controller")


def test_open_loop_truss_actuator(tmp_path):
    """&truss force on the block's dynamic truss, from rest: m s'' = -k s + F, so
    s = F/k (1 - cos(w t)), w = sqrt(k/m) (the truss is massless): 32 undamped periods, whose
    phase error at BDF rtol 1e-9 is what remains: it grows as C rtol per radian, C = 1 to 10 for
    the error control, so C rtol A w T with A = 5e-3 m and w T = 201 rad (observed 5.1e-9 m,
    C = 5.1; 5e-8 m was within 9.8x): bound 10 x 10 rtol A w T = 1e-7 m. A wrong force or law
    factor is off by O(A). Halved by a force_law of 0.5."""
    k, f = EA / L0, 50.0
    w = math.sqrt(k / M)
    for i, (law, scale) in enumerate([("", 1.0), (", force_law = 'half'", 0.5)]):
        text = BLOCK.replace("mode = 'dynamic' /", f"mode = 'dynamic', force = {f}{law} /")
        if law:
            text += "&motion label = 'half', law = 'constant', start = 0.5 /\n"
        text = text.replace("&motion label = 'step', law = 'constant', start = 1.0e-3 /\n", "")
        out = run_ok(tmp_path, text, f"open{i}")
        with h5py.File(out) as h:
            t = h["time"][:]
            pos = h["nodes/block/position"][:, :2]
        s = (pos - [L0 * C, L0 * S]) @ np.array([C, S])
        bound = 10 * 10 * 1e-9 * 5e-3 * w * t[-1]  # 10 x C rtol A w T with C = 10
        assert np.max(np.abs(s - scale * f / k * (1 - np.cos(w * t)))) < bound


def test_truss_force_needs_a_dynamic_truss(tmp_path):
    text = BLOCK.replace("mode = 'dynamic' /", "mode = 'rigid', force = 1.0 /")
    proc, out = run_scene(tmp_path, text)
    assert_clean_error(proc, out, "&truss", "'force'", "dynamic")


def test_linear_model_of_a_truss_actuator(tmp_path):
    """&linear with the truss's force as input and its elongation as output: 1/(m s^2 + k),
    so the DC gain is 1/k and the eigenvalues +-i sqrt(k/m) (a 2-state model). Observed 1e-12
    relative; bound 1e-8. A hinge component on a truss is refused."""
    block = BLOCK.replace("&motion label = 'step', law = 'constant', start = 1.0e-3 /\n", "")
    out = run_ok(tmp_path, block + "&linear inputs = 'spring.force', "
                 "outputs = 'spring.elongation', 'block.x' /\n")
    with h5py.File(out) as f:
        a, b, c = f["linear/A"][0], f["linear/B"][0], f["linear/C"][0]
    k = EA / L0
    dc = -c @ np.linalg.solve(a, b)
    assert dc[0, 0] == pytest.approx(1 / k, rel=1e-8)
    assert dc[1, 0] == pytest.approx(C / k, rel=1e-8)
    assert np.allclose(np.sort(np.linalg.eigvals(a).imag), [-math.sqrt(k / M), math.sqrt(k / M)],
                       rtol=1e-8, atol=0)
    (tmp_path / "bad").mkdir()
    proc, out = run_scene(tmp_path / "bad", block + "&linear inputs = 'spring.torque', "
                          "outputs = 'block.x' /\n")
    assert_clean_error(proc, out, "&linear", "'inputs'", "'force'")


def test_pid_holds_a_spatial_cantilever_tip(tmp_path):
    """A spatial cantilever (4 beams, shear-flexible, damped) whose tip a PID positions in z
    by a force 'tip.fz': the integral removes the steady error, and the force that holds the
    tip at r is the tip stiffness (124 N/m) times r, 1 / (L^3/(3 E Iy) + L/(k G A)) r, to the
    geometric non-linearity ((r/L)^2 ~ 1e-6: observed 4.6e-7 relative; bound 1e-4). Steady
    error observed 2.5e-13 m; bound 1e-8 m."""
    length, e, area, iy, g = 1.5, 7.0e10, 1.0e-4, 2.0e-9, 2.6e10
    r = 1.0e-3
    text = ("&scene dimension = 3 /\n"
            "&node label = 'root', x = 0, y = 0, z = 0, fixed = .true. /\n"
            f"&node label = 'tip', x = {length}, y = 0, z = 0 /\n"
            f"&link label = 'beam', from = 'root', to = 'tip', n_elements = 4, E = {e}, "
            f"A = {area}, I = 0.8e-9, Iy = {iy}, J = 1.5e-9, G = {g}, rho = 2700, "
            "damping = 1.0e-3 /\n"
            f"&motion label = 'r', law = 'constant', start = {r} /\n"
            "&controller label = 'z', actuator = 'tip.fz', measure = 'tip.z', reference = 'r', "
            "kp = 500.0, ki = 2000.0, kd = 5.0 /\n"
            "&dynamic t_end = 6.0, output_dt = 0.01, rtol = 1e-8, atol = 1e-11 /\n")
    out = run_ok(tmp_path, text)
    with h5py.File(out) as f:
        z = f["nodes/tip/position"][:, 2]
        u = f["controllers/z/input"][:]
    k_tip = 1 / (length**3 / (3 * e * iy) + length / (5 / 6 * g * area))
    assert abs(z[-1] - r) < 1e-8
    assert u[-1] == pytest.approx(k_tip * r, rel=1e-4)


def test_unstable_sampling_is_explained(tmp_path):
    """The arm's joints drive flexible links, whose ends turn against their bending: the
    inertia a joint torque sees at the instant is small (1/G = 7.7e-5 kg m^2 at joint 1), so
    the continuous PD has a fast pole -kd G = -1.8e6 /s, and holding kd's output over
    T = 0.1 ms (kd G T = 181) makes it grow by a factor of about 1 - kd G T per sample. The
    run fails, and its error says why and how fast to sample."""
    text = arm_under_pd().replace("kd = 140.0", "kd = 140.0, period = 1.0e-4").replace(
        "kd = 40.0", "kd = 40.0, period = 1.0e-4").replace("t_end = 1.0", "t_end = 0.01")
    proc, out = run_scene(tmp_path, text)
    assert_clean_error(proc, out, "may be unstable", "'joint1'", "kd G T", "sample faster")
