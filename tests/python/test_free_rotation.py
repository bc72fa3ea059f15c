"""Spatial node rotations as inputs (&node dynamic = 'rotation', motion_rotation with
rotation_axis) end to end: a free rigid body (a node without links) against the closed forms of
torque-free motion, a cantilever on a driven root against the rigid rotation of its reference
position (dynamics and statics), the full-turn limit of the free rotation's coordinates, and the
input errors."""
import math

import h5py
import numpy as np
import pytest

from helpers import ROOT, assert_clean_error, run_scene
from test_spatial_examples import body_motion

J_BODY = (1.0, 2.0, 3.0)
MASS = 2.0
# The pulse: a table through 0, 1, 0 at 0, 0.05, 0.1 s (a parabola, area 2/3 x 0.1 s).
PULSE_AREA = 2.0 / 3.0 * 0.1


def free_body():
    """input/free_body.nml: a rigid body on a node without links (principal moments 1, 2, 3
    along x, y, z, mass 2), given a moment and force pulse about fixed axes, then torque-free."""
    return (ROOT / "input" / "free_body.nml").read_text()


def run_ok(tmp_path, text, name):
    proc, out = run_scene(tmp_path, text, name=name)
    assert proc.returncode == 0, proc.stderr
    return out


def body_momentum(t, rot, h_space):
    """The constant angular momentum in body axes, R^T H (orientation only, no differences)."""
    return np.einsum("nji,j->ni", rot, h_space)


def cosh_rate(t, signal, d):
    """The rate r of a signal a e^(rt) + b e^(-rt) (cosh) or a cos(rt) + b sin(rt) (cos) from
    s(t + d) + s(t - d) = 2 c s(t), c = cosh(r d) or cos(r d), whatever a and b: c by least
    squares over the run after the pulse."""
    k = int(round(d / (t[1] - t[0])))
    w = np.nonzero((t >= 0.2 + d) & (t <= t[-1] - d))[0]
    s = signal
    return np.sum(s[w] * (s[w + k] + s[w - k])) / (2 * np.sum(s[w] ** 2))


@pytest.mark.parametrize("axis", ["intermediate", "major"])
def test_free_rigid_body(tmp_path, axis):
    """input/free_body.nml, a free rigid body (node without links, dynamic x, y, z and
    rotation) spun up by a moment pulse about y (intermediate; or z, major), with 1e-4 of it
    about x to start a wobble, runs torque-free for 30 s, 6 to 9 turns: its rotation-vector
    coordinates move their reference at the output times where they pass a quarter turn.
    - the kinetic energy is constant: BDF's error control keeps the error per radian turned
      near rtol, so over Omega t radians it is about rtol Omega t = 4e-9 (observed 4e-9
      relative, intermediate; 5e-11 major); bound ten times that;
    - the angular momentum R J omega (omega from central differences of the 1 ms output; the
      last sample's one-sided difference left out) is the pulse's angular impulse, in closed
      form (observed 1.5e-7 of |H| over the whole run, the differences; bound 3e-5);
    - in body axes R^T H obeys the linearised Euler equations about the spin Omega while the
      wobble is small (t < 4.3 s): the components normal to the spin are combinations of
      exp(+-r t) about the intermediate axis, r = Omega sqrt((J2 - J1)(J3 - J2)/(J1 J3)), and
      oscillate at Omega sqrt((J3 - J1) (J3 - J2)/(J1 J2)) about the major one. The rate from
      s(t + d) + s(t - d) = 2 cosh(r d) s(t) (cos for the major axis), which holds for any mix
      of the two solutions: observed 2.5e-6 off (the wobble reaches 3e-3 rad, non-linear
      effects ~ its square) and 2e-7; bound 1e-4. About the major axis the wobble stays within
      10 times its size at the end of the pulse for the whole run (observed 1.9); about the
      intermediate one it grows until the body flips: R^T H along y changes sign (at 12.9 s);
    - the centre moves at the force's impulse / m (observed 8e-12 relative, the integration
      of the pulse; bound 1e-8, a hundred times the rtol), constant after the pulse (observed
      1.2e-13 m/s; bound 1e-8);
    - the rotation vector (/q) stays within a quarter turn plus the 1 ms output step's turn
      of the moving reference, and jumps back there (the reference moved) once per quarter
      turn: 4 Omega t / (2 pi) times, within one."""
    text = free_body()
    if axis == "intermediate":
        moment, spin, j_spin = np.array([0.004, 40.0, 0.0]), 1, 2.0
    else:
        moment, spin, j_spin = np.array([0.004, 0.0, 60.0]), 2, 3.0
        text = text.replace("my = 40.0", "mz = 60.0")
    assert "mx = 0.004, my = 40.0" in free_body() and "t_end = 30.0" in free_body()
    out = run_ok(tmp_path, text, axis)
    t, omega, rot, kinetic = body_motion(out)
    free = t >= 0.2
    h_exact = moment * PULSE_AREA
    big = np.linalg.norm(h_exact) / j_spin
    turned = big * (t[-1] - 0.1)
    h = np.einsum("nij,jk,nk->ni", rot, np.diag(J_BODY), omega)[free][:-1]
    assert np.max(np.abs(kinetic[free] - kinetic[free][0])) < 10 * 1e-10 * turned * \
        kinetic[free][0]
    assert np.max(np.abs(h - h_exact)) < 3e-5 * np.linalg.norm(h_exact)

    j1, j2, j3 = J_BODY
    body_h = body_momentum(t, rot, h_exact)
    normal = [k for k in range(3) if k != spin]
    early = t <= 4.3
    for k in normal:
        for d in (0.25, 0.5):
            c = cosh_rate(t[early], body_h[early, k], d)
            if axis == "intermediate":
                rate = big * math.sqrt((j2 - j1) * (j3 - j2) / (j1 * j3))
                assert math.acosh(c) / d == pytest.approx(rate, rel=1e-4)
            else:
                rate = big * math.sqrt((j3 - j1) * (j3 - j2) / (j1 * j2))
                assert math.acos(c) / d == pytest.approx(rate, rel=1e-4)
    wobble = np.linalg.norm(body_h[:, normal], axis=1) / np.linalg.norm(h_exact)
    start = wobble[np.argmin(np.abs(t - 0.2))]
    if axis == "intermediate":
        assert wobble[np.argmin(np.abs(t - 4.3))] > 10 * start
        assert body_h[free, spin].max() > 0.99 * np.linalg.norm(h_exact)
        assert body_h[free, spin].min() < -0.99 * np.linalg.norm(h_exact)
    else:
        assert np.max(wobble[free]) < 10 * start

    with h5py.File(out) as f:
        centre = f["nodes/body/position"][:]
        psi = np.linalg.norm(f["q"][:, :3], axis=1)
    velocity = np.gradient(centre, t, axis=0)[free]
    expected = np.array([5.0, 0.0, 2.0]) * PULSE_AREA / MASS
    assert np.max(np.abs(velocity - velocity[0])) < 1e-8
    assert np.max(np.abs(velocity[0] - expected)) < 1e-8 * np.max(np.abs(expected))
    step = np.max(np.linalg.norm(omega, axis=1)) * (t[1] - t[0])
    assert np.max(psi) < math.pi / 2 + step
    moves = np.count_nonzero(np.diff(psi) < -1.0)
    assert abs(moves - 4 * turned / (2 * math.pi)) <= 1


def test_free_rotation_stops_before_a_full_turn(tmp_path):
    """The reference moves only at output times: with one output at 6 s, the body spun at
    4/3 rad/s reaches 1.9 pi (5.97 rad) from it at 4.53 s, and the run stops there with an
    error naming the node, the limit and the remedy (closer output times), for each family of
    integrators (never a NaN or a kinematic failure without reason)."""
    for integrator in ("bdf", "galpha_adaptive"):
        text = free_body().replace("t_end = 30.0", "t_end = 6.0").replace(
            "output_dt = 0.001", "output_dt = 6.0").replace("'bdf'", f"'{integrator}'")
        proc, out = run_scene(tmp_path, text, name=integrator)
        assert_clean_error(proc, out, "node 'body' rotation", "5.97 rad", "full turn", "1.9 pi",
                           "output_dt")


def test_linear_along_a_spinning_body_reads_its_charts(tmp_path):
    """&linear at 3 s along the free body's spin: the state recorded then is in the chart of
    its time (moved at 1.18 and 2.36 s), not in the one at the end of the run (moved again at
    3.53 s). A run to 3.2 s (no move after 3 s) and one to 4 s give the same A and B: observed
    identical; bound 1e-9 relative (the two runs differ only in where CVODE's last steps
    fall). B, the moment about the fixed z axis, depends on the orientation: read in the
    wrong chart it was 0.59 off."""
    base = free_body() + \
        "&linear times = 3.0, inputs = 'body.mz', outputs = 'body.x' /\n"
    mats = []
    for t_end in ("3.2", "4.0"):
        out = run_ok(tmp_path, base.replace("t_end = 30.0", f"t_end = {t_end}"), "lin" + t_end)
        with h5py.File(out) as f:
            assert f["linear/time"][0] == pytest.approx(3.0)
            mats.append((f["linear/A"][0], f["linear/B"][0]))
    for a, b in zip(*mats):
        assert np.max(np.abs(a - b)) <= 1e-9 * np.max(np.abs(a))


def test_free_rotation_needs_inertia(tmp_path):
    """A free rotation that nothing gives inertia: the singular mass matrix names it, as for a
    planar dynamic phi without J."""
    text = free_body().replace(", inertia = 1.0, 2.0, 3.0, 0.0, 0.0, 0.0", "")
    proc, out = run_scene(tmp_path, text)
    assert_clean_error(proc, out, "mass matrix is singular", "node 'body' rotation",
                       "no inertia")


def test_free_rotation_on_a_link_end(tmp_path):
    """A rigid rod (1 m, rho A = 0.78 kg/m) with a 1 kg bob, on a pivot whose translations are
    held and whose rotation is free (dynamic = 'rotation' on a link end), released horizontal
    under gravity: a physical pendulum swinging from +90 to -90 degrees, half a turn (where
    Euler parameters as coordinates would fail), its rotation vector within a quarter turn
    of its moving reference (plus the 1 ms output step's turn, < 0.01 rad). Its period is
    4 sqrt(I / (M g d)) K(sin 45 deg) with I = m L^2 + m_r L^2 / 3 + rho Iy L (the sections'
    rotary inertia; the beam's mass is exact for rigid motion) and M g d = g (m + m_r / 2) L:
    the bob's crossings of x = 0 at T/4 and 3T/4 match it to 1.1e-9 and 1.9e-9 (observed;
    bound 1e-7, the rtol and the 1 ms interpolation); the energy is constant to 9e-9 of
    M g d (bound 1e-7), and the bob stays in the x-z plane (bound 1e-9 m)."""
    text = ("&scene title = 'pendulum', dimension = 3, gravity = 0.0, 0.0, -9.81 /\n"
            "&node label = 'pivot', x = 0.0, y = 0.0, z = 0.0, fix_x = .true., "
            "fix_y = .true., fix_z = .true., dynamic = 'rotation' /\n"
            "&node label = 'bob', x = 1.0, y = 0.0, z = 0.0 /\n"
            "&link label = 'rod', from = 'pivot', to = 'bob', E = 2.1e11, A = 1.0e-4, "
            "I = 1.0e-8, J = 2.0e-8, G = 8.0e10, rho = 7800.0, elongation = 'rigid', "
            "bending = 'rigid' /\n"
            "&mass node = 'bob', m = 1.0 /\n"
            "&dynamic t_end = 2.0, output_dt = 0.001, integrator = 'bdf', rtol = 1.0e-10, "
            "atol = 1.0e-12 /\n")
    out = run_ok(tmp_path, text, "pendulum")
    with h5py.File(out) as f:
        t = f["time"][:]
        bob = f["nodes/bob/position"][:]
        energy = f["energy/kinetic"][:] + f["energy/potential"][:]
        psi = f["q"][:, :3]
    length, m, rho, area, i_y, g = 1.0, 1.0, 7800.0, 1.0e-4, 1.0e-8, 9.81
    m_rod = rho * area * length
    inertia = m * length**2 + m_rod * length**2 / 3 + rho * i_y * length
    mgd = g * (m + m_rod / 2) * length
    a, b = 1.0, math.sqrt(0.5)   # K(k) = pi / (2 agm(1, sqrt(1 - k^2))), k^2 = 1/2
    for _ in range(8):
        a, b = (a + b) / 2, math.sqrt(a * b)
    period = 4 * math.sqrt(inertia / mgd) * math.pi / (2 * a)
    x = bob[:, 0]
    i = np.nonzero(np.sign(x[:-1]) != np.sign(x[1:]))[0]
    crossings = t[i] - x[i] * (t[i + 1] - t[i]) / (x[i + 1] - x[i])
    assert len(crossings) == 2
    assert crossings == pytest.approx([period / 4, 3 * period / 4], rel=1e-7)
    assert np.max(np.abs(energy - energy[0])) < 1e-7 * mgd
    assert np.max(np.abs(bob[:, 1])) < 1e-9
    swing = np.arctan2(-bob[:, 2], bob[:, 0])
    assert np.ptp(swing) > 0.99 * math.pi
    assert np.max(np.linalg.norm(psi, axis=1)) < math.pi / 2 + 0.01


def driven(axis, law, analysis):
    """A cantilever (2 beams, rigid in elongation) from a root whose translations are fixed
    and whose rotation follows the motion 'turn' about `axis`."""
    return ("&scene title = 'driven root', dimension = 3 /\n"
            "&node label = 'root', x = 0.0, y = 0.0, z = 0.0, fix_x = .true., fix_y = .true., "
            f"fix_z = .true., motion_rotation = 'turn', rotation_axis = {axis} /\n"
            "&node label = 'tip', x = 1.0, y = 0.0, z = 0.0 /\n"
            "&link label = 'arm', from = 'root', to = 'tip', n_elements = 2, E = 2.1e11, "
            "A = 1.0e-4, I = 1.0e-8, J = 2.0e-8, G = 8.0e10, rho = 7800.0, "
            "elongation = 'rigid' /\n"
            f"&motion label = 'turn', {law} /\n" + analysis)


def rotation(axis, angle):
    """Rodrigues' rotation matrices about the unit `axis` by the angles `angle`."""
    n = np.asarray(axis, float) / np.linalg.norm(axis)
    k = np.array([[0, -n[2], n[1]], [n[2], 0, -n[0]], [-n[1], n[0], 0]])
    a = np.atleast_1d(angle)[:, None, None]
    return np.eye(3) + np.sin(a) * k + (1 - np.cos(a)) * (k @ k)


AXES = [(0.0, 0.0, 1.0), (1.0, 2.0, 2.0)]


@pytest.mark.parametrize("axis", AXES)
def test_driven_root_follows_the_rigid_rotation(tmp_path, axis):
    """The root turns by a cycloidal 1 rad in 2 s about z (and about an inclined axis); the
    tip follows the rigid rotation of its reference position up to the quasi-static
    deflection under the arm's inertia loads, rho A L^5 (11/120 theta''_max + 1/8
    theta'_max^2) / (E I) = 1.0e-4 m (tangential and, about the inclined axis, centrifugal):
    observed 5.4e-5 and 5.1e-5 m; bound ten times the estimate."""
    text = driven(", ".join(map(str, axis)),
                  "law = 'cycloidal', start = 0.0, end = 1.0, duration = 2.0",
                  "&dynamic t_end = 2.0, output_dt = 0.01, rtol = 1.0e-8, atol = 1.0e-10 /\n")
    out = run_ok(tmp_path, text, "driven")
    with h5py.File(out) as f:
        t = f["time"][:]
        tip = f["nodes/tip/position"][:]
    s = t / 2.0
    angle = s - np.sin(2 * np.pi * s) / (2 * np.pi)
    expected = rotation(axis, angle) @ np.array([1.0, 0.0, 0.0])
    rho_a, ei = 7800.0 * 1.0e-4, 2.1e11 * 1.0e-8
    estimate = rho_a * (11 / 120 * 2 * np.pi / 2.0**2 + 1 / 8 * (2 / 2.0) ** 2) / ei
    assert np.max(np.linalg.norm(tip - expected, axis=1)) < 10 * estimate
    assert np.max(np.abs(angle - angle[-1])) > 0.9   # it did turn


@pytest.mark.parametrize("axis", AXES)
def test_driven_root_in_statics(tmp_path, axis):
    """Statics steps the prescribed rotation with the load factor (as motion_phi in the plane):
    at step k of 4 the root has turned by k/4 of 2.5 rad and, as the motion is rigid, the tip
    is at the rotated reference position (observed 1e-15 m; bound 1e-9)."""
    text = driven(", ".join(map(str, axis)), "law = 'constant', start = 2.5",
                  "&static n_steps = 4 /\n")
    out = run_ok(tmp_path, text, "static")
    with h5py.File(out) as f:
        tip = f["static/nodes/tip/position"][:]
        factor = f["static/load_factor"][:]
    expected = rotation(axis, 2.5 * factor) @ np.array([1.0, 0.0, 0.0])
    assert len(tip) == 4
    assert np.max(np.linalg.norm(tip - expected, axis=1)) < 1e-9


def planar(node_extra):
    return ("&scene title = 'planar' /\n"
            "&node label = 'a', x = 0, y = 0, fixed = .true. /\n"
            f"&node label = 'b', x = 1, y = 0{node_extra} /\n"
            "&link label = 'l', from = 'a', to = 'b', E = 2e11, A = 1e-4, I = 1e-8, rho = 7800 /\n"
            "&motion label = 'turn', law = 'ramp', rate = 1 /\n")


def spatial(node_extra, extra=""):
    return ("&scene title = 'spatial', dimension = 3 /\n"
            "&node label = 'a', x = 0, y = 0, z = 0, fixed = .true. /\n"
            f"&node label = 'b', x = 1, y = 0, z = 0{node_extra} /\n"
            "&link label = 'l', from = 'a', to = 'b', E = 2e11, A = 1e-4, I = 1e-8, J = 2e-8, "
            "G = 8e10, rho = 7800 /\n"
            "&motion label = 'turn', law = 'ramp', rate = 1 /\n" + extra)


@pytest.mark.parametrize("text,fragments", [
    (planar(", dynamic = 'rotation'"), ["&node 'b'", "'dynamic'", "dimension = 3"]),
    (spatial(", motion_phi = 'turn'"), ["&node 'b'", "'motion_phi'", "planar only",
                                        "dynamic = 'rotation'"]),
    (planar(", motion_rotation = 'turn', rotation_axis = 0, 0, 1"),
     ["&node 'b'", "'motion_rotation'", "dimension = 3"]),
    (spatial(", motion_rotation = 'turn'"),
     ["&node", "'motion_rotation'", "needs 'rotation_axis'"]),
    (spatial(", motion_rotation = 'turn', rotation_axis = 0, 0, 0"),
     ["&node", "'rotation_axis'", "must not be zero"]),
    (spatial(", motion_rotation = 'turn', rotation_axis = 0, 1"),
     ["&node", "'rotation_axis'", "3 values"]),
    (spatial(", rotation_axis = 0, 0, 1"), ["&node", "'rotation_axis'", "without"]),
    (spatial(", dynamic = 'rotation', motion_rotation = 'turn', rotation_axis = 0, 0, 1"),
     ["&node", "both dynamic", "driven"]),
    (spatial(", dynamic = 'rotation', fix_rotation = .true."),
     ["&node", "fix_rotation", "cannot also be dynamic or driven"]),
    (spatial(", motion_rotation = 'nope', rotation_axis = 0, 0, 1"),
     ["&node 'b'", "'motion_rotation'", "'nope'", "not defined"]),
    (spatial("", "&node label = 'lone', x = 0, y = 2, z = 0, dynamic = 'x' /\n"
             "&mass node = 'lone', m = 1, inertia = 1, 1, 1, 0, 0, 0 /\n"),
     ["'lone'", "no rotation", "dynamic = 'rotation'"]),
])
def test_rotation_input_errors(tmp_path, text, fragments):
    proc, out = run_scene(tmp_path, text)
    assert_clean_error(proc, out, *fragments)


def test_unused_motion_warning_knows_motion_rotation(tmp_path):
    """A motion used only by motion_rotation is not reported unused; a spare one is."""
    text = driven("0, 0, 1", "law = 'constant', start = 0.5",
                  "&motion label = 'spare', law = 'constant', start = 1 /\n"
                  "&static n_steps = 1 /\n")
    proc, _ = run_scene(tmp_path, text, quiet=False)
    assert proc.returncode == 0, proc.stderr
    said = proc.stdout + proc.stderr
    assert "'spare'" in said and "'turn'" not in said


def test_python_reads_node_rotation_models(tmp_path):
    """flexmor.model reads results with the hidden elements of node rotations (rotvec,
    hinge3d from a clamped frame) and draws them: the mesh points at the last output are the
    nodes' positions (exactly: the same numbers)."""
    from flexmor.model import read_model
    texts = {"free": free_body().replace("t_end = 30.0", "t_end = 0.5"),
             "driven": driven("0, 0, 1", "law = 'constant', start = 0.5",
                              "&static n_steps = 1 /\n")}
    for name, text in texts.items():
        out = run_ok(tmp_path, text, name)
        with h5py.File(out) as f:
            model = read_model(f)
            x = f["x"][-1] if "x" in f else f["static/x"][-1]
            node = "body" if name == "free" else "tip"
            pos = (f["nodes"] if "x" in f else f["static/nodes"])[node]["position"][-1]
        assert ("rotvec" if name == "free" else "hinge3d") in model.element_types
        points = model.mesh().points(x)
        assert np.array_equal(points[model.node_labels.index(node)], pos)
