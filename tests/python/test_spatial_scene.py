"""Spatial scenes (&scene dimension = 3) end to end: a cantilever of spatial beams against
closed forms (statics in both planes with shear flexibility, the roll-up by an end moment,
bending frequencies), the same cantilever swinging under gravity in its plane against the
planar scene, and the input errors of the dimension split."""
import math

import h5py
import numpy as np
import pytest

from helpers import assert_clean_error, run_scene

L, E, A, I_Z, I_Y, J, G, RHO = 1.5, 7.0e10, 1.0e-4, 0.8e-9, 2.0e-9, 1.5e-9, 2.6e10, 2700.0
K = 5.0 / 6.0


def cantilever(extra, n=4, dim=3, link_extra=""):
    spatial = dim == 3
    return (f"&scene title = 'cantilever', dimension = {dim} /\n"
            f"&node label = 'root', x = 0, y = 0{', z = 0' if spatial else ''}, fixed = .true. /\n"
            f"&node label = 'tip', x = {L}, y = 0 /\n"
            f"&link label = 'beam', from = 'root', to = 'tip', n_elements = {n},\n"
            f"      E = {E}, A = {A}, I = {I_Z}, rho = {RHO}, G = {G}"
            + (f", Iy = {I_Y}, J = {J}" if spatial else "") + link_extra + " /\n" + extra)


def test_static_tip_force_in_both_planes(tmp_path):
    """Cubic Timoshenko elements are exact for a tip force: P L^3/(3 E I) + P L/(k G A) per
    plane, to the geometric non-linearity ((w/L)^2 ~ 1e-10 here); bound 1e-6 relative."""
    p = 1.0e-3
    proc, out = run_scene(tmp_path, cantilever(f"&force node = 'tip', fy = {p}, fz = {p} /\n"
                                               "&static n_steps = 1 /\n"))
    assert proc.returncode == 0, proc.stderr
    with h5py.File(out) as f:
        tip = f["static/nodes/tip/position"][-1]
        lam = f["static/nodes/tip/orientation"][-1]
        assert f["model"].attrs["dimension"] == 3
    shear = p * L / (K * G * A)
    assert tip[1] == pytest.approx(p * L**3 / (3 * E * I_Z) + shear, rel=1e-6)
    assert tip[2] == pytest.approx(p * L**3 / (3 * E * I_Y) + shear, rel=1e-6)
    assert np.linalg.norm(lam) == pytest.approx(1.0, abs=1e-12)


def test_roll_up_by_an_end_moment(tmp_path):
    """mz = 2 pi E I / L rolls the cantilever into a full circle: equal elements under equal
    moments form a closed polygon, so the tip is back at the root (Newton tolerance) and has
    turned a full turn; the observed gap is 1e-15 L, bound 1e-8 L."""
    m = 2 * math.pi * E * I_Z / L
    proc, out = run_scene(tmp_path, cantilever(f"&force node = 'tip', mz = {m} /\n"
                                               "&static n_steps = 16 /\n", n=8))
    assert proc.returncode == 0, proc.stderr
    with h5py.File(out) as f:
        tip = f["static/nodes/tip/position"][-1]
        lam = f["static/nodes/tip/orientation"][-1]
    assert np.linalg.norm(tip) < 1e-8 * L
    assert abs(abs(lam[0]) - 1) < 1e-8            # lambda = -(1, 0, 0, 0): a full turn
    assert np.all(np.abs(lam[1:]) < 1e-8)


def test_bending_frequencies_in_both_planes(tmp_path):
    """Clamped-free, 8 elements: 1.8751^2 sqrt(E I / (rho A L^4)) / 2 pi per plane; shear and
    rotary inertia lower it by about (r/L)^2 ~ 1e-5 (observed 2e-5); bound 1e-3."""
    proc, out = run_scene(tmp_path, cantilever("&modal n_modes = 4 /\n", n=8))
    assert proc.returncode == 0, proc.stderr
    with h5py.File(out) as f:
        freq = f["modal/frequency_hz"][:]
    beta = 1.875104068711961**2 / (2 * math.pi)
    f_z_plane = beta * math.sqrt(E * I_Z / (RHO * A * L**4))
    f_y_plane = beta * math.sqrt(E * I_Y / (RHO * A * L**4))
    assert freq[0] == pytest.approx(f_z_plane, rel=1e-3)
    assert freq[1] == pytest.approx(f_y_plane, rel=1e-3)


def test_planar_motion_equals_the_planar_scene(tmp_path):
    """The cantilever released under gravity in its x-y plane: the spatial scene's tip path
    equals the planar scene's (same mesh and bending form). The spatial beam adds the sections'
    rotary inertia, which the planar beam leaves out: (r/L)^2 = I/(A L^2) ~ 4e-6 of the motion
    (observed ~1e-6 of the deflection); bound 1e-4. Nothing moves out of the plane."""
    dyn = "&dynamic t_end = 0.05, output_dt = 0.005, integrator = 'bdf', rtol = 1e-8, atol = 1e-11 /\n"
    text3 = cantilever(dyn).replace("dimension = 3 /", "dimension = 3, gravity = 0, -9.81, 0 /")
    text2 = cantilever(dyn, dim=2).replace("&scene title = 'cantilever', dimension = 2 /",
                                           "&scene title = 'cantilever', gravity = 0, -9.81 /")
    p3, out3 = run_scene(tmp_path, text3, name="spatial")
    p2, out2 = run_scene(tmp_path, text2, name="planar")
    assert p3.returncode == 0, p3.stderr
    assert p2.returncode == 0, p2.stderr
    with h5py.File(out3) as f3, h5py.File(out2) as f2:
        tip3 = f3["nodes/tip/position"][:]
        tip2 = f2["nodes/tip/position"][:]
    deflection = np.max(np.abs(tip2[:, 1]))
    assert deflection > 1e-3
    assert np.max(np.abs(tip3[:, :2] - tip2[:, :2])) < 1e-4 * deflection
    assert np.max(np.abs(tip3[:, 2])) < 1e-12


@pytest.mark.parametrize("text,fragments", [
    (cantilever("&hinge label = 'h', node = 'root', link = 'beam', axis = 0, 0, 0 /\n"),
     ["&hinge", "'axis'", "zero"]),
    (cantilever("&hinge label = 'h', node = 'root', link = 'beam', axis = 0, 1 /\n"),
     ["&hinge", "'axis'", "3 values"]),
    (cantilever("&hinge label = 'h', node = 'root', link = 'beam', axis = 0, 0, 1 /\n", dim=2),
     ["&hinge 'h'", "'axis'", "dimension = 3"]),
    (cantilever("&hinge label = 'h', node = 'tip', link = 'nope' /\n"),
     ["&hinge 'h'", "'nope'", "not defined"]),
    (cantilever("&hinge label = 'h', node = 'root', link = 'beam', mode = 'prescribed', "
                "motion = 'm' /\n"), ["&hinge 'h'", "'m'", "not defined"]),
    (cantilever("&force node = 'tip', fz = 1, time_law = 'pulse' /\n"),
     ["&force", "'time_law'", "'pulse'", "not defined"]),
    (cantilever("", link_extra=", rotary_inertia = 1, 2"), ["'rotary_inertia'", "3 values"]),
    (cantilever("&slider label = 's', node = 'tip', direction = 1, 0 /\n"),
     ["&slider 's'", "'direction'", "3 values"]),
    (cantilever("&slider label = 's', node = 'tip', direction = 1, 0, 0 /\n", dim=2),
     ["&slider 's'", "'direction'", "2 values"]),
    (cantilever("", link_extra=", rotary_inertia = 1, -2, 1"),
     ["'rotary_inertia'", "negative"]),
    (cantilever("", dim=2, link_extra=", rotary_inertia = 1, 2, 1"),
     ["'rotary_inertia'", "dimension = 3"]),
    (cantilever("", dim=2).replace("y = 0 /", "y = 0, z = 1 /", 1), ["'z'", "dimension = 3"]),
    (cantilever("").replace(f"x = {L}, y = 0 /", f"x = {L}, y = 0, dynamic = 'phi' /"),
     ["&node 'tip'", "'dynamic'", "planar only"]),
    (cantilever("", dim=2).replace(f"x = {L}, y = 0 /", f"x = {L}, y = 0, motion_z = 'm' /"),
     ["&node 'tip'", "'motion_z'", "dimension = 3"]),
    (cantilever("&force node = 'tip', fz = 1 /\n", dim=2), ["&force", "'fz'", "dimension = 3"]),
    (cantilever("&force node = 'tip', moment = 1 /\n"), ["'moment'", "planar only", "'mx'"]),
    (cantilever("&mass node = 'tip', J = 1 /\n"), ["'J'", "planar only", "'inertia'"]),
    (cantilever("").replace(f", J = {J}", ""), ["'J'", "torsion constant"]),
    (cantilever("").replace(f", G = {G}", ""), ["'G'", "spatial scene"]),
    (cantilever("", link_extra=", orientation = 1, 0, 0"), ["'orientation'", "parallel"]),
    (cantilever("&force node = 'mid', mx = 1 /\n&node label = 'mid', x = 3, y = 0 /\n"),
     ["&force", "'mid'", "rotation"]),
    (cantilever("").replace("dimension = 3 /", "dimension = 3, gravity = 0, -9.81 /"),
     ["'gravity'", "3 values"]),
])
def test_dimension_errors(tmp_path, text, fragments):
    proc, out = run_scene(tmp_path, text)
    assert_clean_error(proc, out, *fragments)


def test_reduced_model_in_space(tmp_path):
    """Gravity with a z component swings the cantilever in both planes; the reduced model with
    the 3 lowest modes (both first bending modes among them) follows the full one: observed
    1.7e-3 of the deflection over 0.2 s, bound 3e-2."""
    scene = ("&dynamic t_end = 0.2, output_dt = 0.01 /\n"
             "&output nodes = 'tip' /\n")
    full = cantilever(scene).replace("dimension = 3 /", "dimension = 3, gravity = 0, -9.81, -3 /")
    p1, out1 = run_scene(tmp_path, full, name="full")
    p2, out2 = run_scene(tmp_path, full + "&reduction n_modes = 3 /\n", name="reduced")
    assert p1.returncode == 0, p1.stderr
    assert p2.returncode == 0, p2.stderr
    with h5py.File(out1) as f1, h5py.File(out2) as f2:
        a = f1["nodes/tip/position"][:]
        b = f2["nodes/tip/position"][:]
    deflection = np.max(np.hypot(a[:, 1], a[:, 2]))
    assert deflection > 1e-2 and np.max(np.abs(a[:, 2])) > 1e-4
    assert np.max(np.abs(a - b)) < 3e-2 * deflection


def test_tip_body_twists_the_cantilever(tmp_path):
    """A rigid body (inertia tensor) on the tip: the torsion mode is that of the body on the
    shaft's torsion spring G J / L, with a third of the shaft's own polar inertia (Rayleigh with
    the linear twist the beams interpolate, exact for this shape): the closed form
    omega^2 = (G J / L) / (Jxx + rho (Iy + Iz) L / 3). Observed 1e-8 relative; bound 1e-5."""
    jxx = 0.01
    proc, out = run_scene(tmp_path, cantilever(
        f"&mass node = 'tip', inertia = {jxx}, 0.02, 0.02, 0, 0, 0 /\n&modal /\n"))
    assert proc.returncode == 0, proc.stderr
    with h5py.File(out) as f:
        freq = f["modal/frequency_hz"][:]
    omega = math.sqrt(G * J / L / (jxx + RHO * (I_Y + I_Z) * L / 3))
    closest = freq[np.argmin(np.abs(freq - omega / (2 * math.pi)))]
    assert closest == pytest.approx(omega / (2 * math.pi), rel=1e-5)


@pytest.mark.parametrize("text,fragments", [
    (cantilever("&mass node = 'tip', inertia = 1, 1, 3, 0, 0, 0 /\n"),
     ["'inertia'", "not the inertia tensor of a body"]),
    (cantilever("&mass node = 'tip', inertia = 1, 1, 1, 2, 0, 0 /\n"),
     ["'inertia'", "not the inertia tensor of a body"]),
    (cantilever("&mass node = 'tip', inertia = 1, 1, 1 /\n"), ["'inertia'", "6 values"]),
    (cantilever("&mass node = 'tip', m = 1, rotation = 0, 0, 1, 0.5 /\n"),
     ["'rotation'", "'inertia'", "not given"]),
    (cantilever("&mass node = 'tip', inertia = 1, 1, 1, 0, 0, 0, rotation = 0, 0, 1 /\n"),
     ["'rotation'", "4 values"]),
    (cantilever("&mass node = 'tip', inertia = 1, 1, 1, 0, 0, 0, rotation = 0, 0, 0, 1 /\n"),
     ["'rotation'", "axis is zero"]),
    (cantilever("&mass node = 'tip', inertia = 1, 1, 1, 0, 0, 0 /\n", dim=2),
     ["'inertia'", "dimension = 3"]),
    (cantilever("&node label = 'lone', x = 0, y = 1, z = 0 /\n"
                "&mass node = 'lone', m = 1, inertia = 1, 1, 1, 0, 0, 0 /\n"),
     ["'lone'", "no rotation"]),
])
def test_body_errors(tmp_path, text, fragments):
    proc, out = run_scene(tmp_path, text)
    assert_clean_error(proc, out, *fragments)


@pytest.mark.parametrize("axis,force,i_bend", [("0, 0, 1", "fy", I_Z), ("0, 2, 0", "fz", I_Y)])
def test_hinge_spring_at_the_root(tmp_path, axis, force, i_bend):
    """A dynamic hinge with a torsion spring k at the clamped root, about z or y: the tip
    deflection under a small tip force is the cantilever's plus the hinge's rigid turn,
    P L^3/(3 E I) + P L/(k_s G A) + P L^2/k (the bending modes of the hinge are rigid);
    bound 1e-6 relative, as in the hinge-free closed form above."""
    p, k = 1.0e-3, 50.0
    proc, out = run_scene(tmp_path, cantilever(
        f"&hinge label = 'h', node = 'root', link = 'beam', mode = 'dynamic', stiffness = {k},"
        f" axis = {axis} /\n&force node = 'tip', {force} = {p} /\n&static n_steps = 1 /\n"))
    assert proc.returncode == 0, proc.stderr
    with h5py.File(out) as f:
        tip = f["static/nodes/tip/position"][-1]
    expected = p * L**3 / (3 * E * i_bend) + p * L / (K * G * A) + p * L**2 / k
    assert tip[1 if force == "fy" else 2] == pytest.approx(expected, rel=1e-6)


def test_space_truss_tripod(tmp_path):
    """Three bars from feet at 120 degrees on a circle of radius a to an apex at height h, a
    vertical load P on the apex: each bar carries P/(3 cos alpha) (cos alpha = h/l), so the apex
    sinks by P l/(3 E A cos^2 alpha) and stays on the axis. The geometric non-linearity is of
    the order of the sink over h (1e-5 at 1 kN: observed 1.3e-5); at 1 N it is 1e-8, bound
    1e-6 relative."""
    a, h, e, area, p = 1.0, 1.5, 2.0e11, 1.0e-4, 1.0
    feet = "".join(f"&node label = 'f{k}', x = {a * math.cos(2 * math.pi * k / 3)!r}, "
                   f"y = {a * math.sin(2 * math.pi * k / 3)!r}, z = 0, fixed = .true. /\n"
                   for k in range(3))
    bars = "".join(f"&truss label = 'b{k}', from = 'f{k}', to = 'apex', E = {e}, A = {area}, "
                   f"rho = 7850 /\n" for k in range(3))
    text = ("&scene title = 'tripod', dimension = 3 /\n" + feet
            + f"&node label = 'apex', x = 0, y = 0, z = {h} /\n" + bars
            + f"&force node = 'apex', fz = {-p} /\n&static n_steps = 1 /\n"
            "&output nodes = 'apex' /\n")
    proc, out = run_scene(tmp_path, text)
    assert proc.returncode == 0, proc.stderr
    with h5py.File(out) as f:
        apex = f["static/nodes/apex/position"][-1]
    length = math.hypot(a, h)
    cos_a = h / length
    assert h - apex[2] == pytest.approx(p * length / (3 * e * area * cos_a**2), rel=1e-6)
    assert np.max(np.abs(apex[:2])) < 1e-9 * h


def test_helix_under_an_inclined_end_moment(tmp_path):
    """An end moment M fixed in space at 60 degrees to the axis of an isotropic cantilever
    (I = Iy): the internal moment is M everywhere, so the tangent turns about M at the rate
    |M|/EI and the centreline is a helix about M (Kirchhoff), tip at
    cos(a) m L + (EI/|M|) (sin(th) t_perp + (1 - cos th) m x t_perp), th = |M| L / EI
    (0.3 of a full turn here). The error goes as h^2 (observed ratios 3.6 and 3.9 from 4 to 8
    to 16 beams, checked in [3, 5]); Richardson from 8 and 16 beams is 1e-4 L from the helix
    (bound 1e-3 L)."""
    alpha, ii = math.radians(60), I_Y
    m_abs = 0.3 * 2 * math.pi * E * ii / L
    m = np.array([math.cos(alpha), 0, math.sin(alpha)])
    t_perp = np.array([1.0, 0.0, 0.0]) - math.cos(alpha) * m
    th = m_abs * L / (E * ii)
    helix = (math.cos(alpha) * m * L + E * ii / m_abs
             * (math.sin(th) * t_perp + (1 - math.cos(th)) * np.cross(m, t_perp)))
    tips = {}
    for n in (4, 8, 16):
        text = cantilever(f"&force node = 'tip', mx = {float(m_abs * m[0])!r}, "
                          f"mz = {float(m_abs * m[2])!r} /\n"
                          "&static n_steps = 8 /\n&output nodes = 'tip' /\n", n=n)
        text = text.replace(f"I = {I_Z}", f"I = {ii}")
        proc, out = run_scene(tmp_path, text, name=f"helix{n}")
        assert proc.returncode == 0, proc.stderr
        with h5py.File(out) as f:
            tips[n] = f["static/nodes/tip/position"][-1]
    err = {n: np.linalg.norm(tips[n] - helix) for n in tips}
    assert 3 < err[4] / err[8] < 5 and 3 < err[8] / err[16] < 5, err
    assert np.linalg.norm(tips[16] + (tips[16] - tips[8]) / 3 - helix) < 1e-3 * L


def test_large_twist_is_exact(tmp_path):
    """A torque M = G J theta / L on the tip twists the cantilever by theta: the angle form's
    torsion mode is l0 times the twist, so any mesh is exact up to pi per element (here
    theta = 3 rad on 4 elements, 0.75 rad each, past the sine form's limit point at 45
    degrees); bound 1e-9 rad (Newton)."""
    theta = 3.0
    proc, out = run_scene(tmp_path, cantilever(
        f"&force node = 'tip', mx = {G * J * theta / L!r} /\n&static n_steps = 6 /\n"
        "&output nodes = 'tip' /\n", n=4))
    assert proc.returncode == 0, proc.stderr
    with h5py.File(out) as f:
        lam = f["static/nodes/tip/orientation"][-1]
        tip = f["static/nodes/tip/position"][-1]
    assert 2 * math.atan2(lam[1], lam[0]) == pytest.approx(theta, abs=1e-9)
    assert np.allclose(tip, [L, 0, 0], rtol=0, atol=1e-12 * L)


@pytest.mark.parametrize("joint,moment,expected", [
    ("universal", "mx", lambda m, k: m * L / (G * J)),
    ("universal", "mz", lambda m, k: m / k + m * L / (E * I_Z)),
    ("spherical", "mx", lambda m, k: m / k + m * L / (G * J)),
    ("spherical", "my", lambda m, k: m / k + m * L / (E * I_Y)),
    ("revolute", "my", lambda m, k: m * L / (E * I_Y)),
])
def test_joint_types_at_the_root(tmp_path, joint, moment, expected):
    """A joint with springs k at the root of a cantilever along x, axis x: a small end moment
    turns the tip by the beam's compliance plus the joint's where the joint type releases that
    rotation (universal: the two normal to the axis; spherical: all three; revolute: only the
    one about the axis). The linear compliance is off by the non-linear terms, O(theta^2) =
    1e-6 at rotations of 1e-3 rad (observed up to 2.8e-7 relative, 0.28 theta^2, both builds):
    bound 10 theta^2 = 1e-5 (1e-6 was within 3.6x). A wrong joint type (a rotation released or
    held that should not be) changes the result by m/k or m L/EI, O(1) relative."""
    k, m = 20.0, 1.0e-3 * 20.0
    axis = {"mx": 1, "my": 2, "mz": 3}[moment]
    proc, out = run_scene(tmp_path, cantilever(
        f"&hinge label = 'h', node = 'root', link = 'beam', mode = 'dynamic', stiffness = {k},"
        f" axis = 1, 0, 0, type = '{joint}' /\n&force node = 'tip', {moment} = {m} /\n"
        "&static n_steps = 1 /\n&output nodes = 'tip' /\n"))
    assert proc.returncode == 0, proc.stderr
    with h5py.File(out) as f:
        lam = f["static/nodes/tip/orientation"][-1]
    angle = 2 * math.atan2(lam[axis], lam[0])
    assert angle == pytest.approx(expected(m, k), rel=10 * 1.0e-3**2)


def test_spherical_pendulum_period(tmp_path):
    """A bob (mass m, rotary inertia j about its centre) on a rigid, nearly massless rod from
    a spherical joint, released from rest at 60 degrees from the vertical in a plane between x
    and y: it swings in that plane with the physical pendulum's period
    4 sqrt((m L^2 + j)/(m g L)) K(sin(30 deg)) (complete elliptic integral by the AGM). The
    bob's j also gives the spin about the rod, free in a spherical joint, an inertia (a
    massless spin would make the mass matrix nearly singular). The zero crossings of the
    horizontal offset give the period to the output step's interpolation (1e-5 of it):
    observed 3e-6; bound 1e-3."""
    length, g, theta0, psi, j = 1.0, 9.81, math.radians(60), math.radians(30), 1.0e-2
    k_mod = math.sin(theta0 / 2)
    a, b = 1.0, math.sqrt(1 - k_mod**2)
    for _ in range(30):
        a, b = (a + b) / 2, math.sqrt(a * b)
    period = 4 * math.sqrt((length**2 + j) / (g * length)) * math.pi / (2 * a)
    bob = length * np.array([math.sin(theta0) * math.cos(psi), math.sin(theta0) * math.sin(psi),
                             -math.cos(theta0)])
    text = (f"&scene title = 'pendulum', dimension = 3, gravity = 0, 0, {-g} /\n"
            "&node label = 'pivot', x = 0, y = 0, z = 0, fixed = .true. /\n"
            f"&node label = 'bob', x = {float(bob[0])!r}, y = {float(bob[1])!r}, "
            f"z = {float(bob[2])!r} /\n"
            "&link label = 'rod', from = 'pivot', to = 'bob', E = 2e11, A = 1e-4, I = 1e-8,\n"
            "      J = 2e-8, G = 8e10, rho = 1e-3, elongation = 'rigid', bending = 'rigid',\n"
            "      orientation = 0, 0, 1 /\n"
            "&hinge label = 'ball', node = 'pivot', link = 'rod', mode = 'dynamic', "
            "type = 'spherical' /\n"
            f"&mass node = 'bob', m = 1.0, inertia = {j}, {j}, {j}, 0, 0, 0 /\n"
            f"&dynamic t_end = {2.2 * period}, output_dt = 1e-3, integrator = 'galpha_adaptive',"
            " rtol = 1e-7, atol = 1e-9 /\n&output nodes = 'bob' /\n")
    proc, out = run_scene(tmp_path, text)
    assert proc.returncode == 0, proc.stderr
    with h5py.File(out) as f:
        t = f["time"][:]
        p = f["nodes/bob/position"][:]
    # In the tilt plane: the offset along (cos psi, sin psi); none across it.
    along = p[:, 0] * math.cos(psi) + p[:, 1] * math.sin(psi)
    across = -p[:, 0] * math.sin(psi) + p[:, 1] * math.cos(psi)
    assert np.max(np.abs(across)) < 1e-6 * length
    crossings = [t[i] - along[i] * (t[i + 1] - t[i]) / (along[i + 1] - along[i])
                 for i in range(len(t) - 1) if along[i] > 0 >= along[i + 1]]
    assert len(crossings) >= 2
    assert crossings[1] - crossings[0] == pytest.approx(period, rel=1e-3)
    assert np.max(np.abs(np.linalg.norm(p, axis=1) - length)) < 1e-9


def test_root_reaction_and_static_frequencies(tmp_path):
    """A tip force F = (0, fy, fz) on the cantilever: the clamp's reaction is -F and the
    moment -(r_tip x F) about the root, to the Newton tolerance (bound 1e-9 relative); with
    n_frequencies the static step's frequencies equal &modal's at the same state."""
    fy, fz = 1.0e-3, -2.0e-3
    proc, out = run_scene(tmp_path, cantilever(
        f"&force node = 'tip', fy = {fy}, fz = {fz} /\n&static n_steps = 1, n_frequencies = 3 /\n"
        "&modal n_modes = 3 /\n&output nodes = 'root', 'tip' /\n"))
    assert proc.returncode == 0, proc.stderr
    with h5py.File(out) as f:
        reaction = f["static/nodes/root/reaction"][-1]
        tip = f["static/nodes/tip/position"][-1]
        static_f = f["static/frequency_hz"][-1]
        modal_f = f["modal/frequency_hz"][:]
        assert f["static/nodes/root/reaction"].attrs["units"] == "N, N, N, N m, N m, N m"
    force = np.array([0.0, fy, fz])
    assert np.allclose(reaction[:3], -force, rtol=0, atol=1e-9 * abs(fz))
    assert np.allclose(reaction[3:], -np.cross(tip, force), rtol=0, atol=1e-9 * abs(fz) * L)
    assert np.allclose(static_f, modal_f, rtol=1e-9)


def test_spatial_slider_block(tmp_path):
    """A block on a guide along d (inclined in space), held by a truss spring along the guide
    from a fixed anchor: gravity's component along the guide, m g.d, moves it by m (g.d) L0/EA
    and it stays on the guide (bound 1e-10 m, Newton). With guide springs K across (mode
    'dynamic') and no gravity it has the frequencies sqrt(EA/(L0 m)) and sqrt(K/m) twice
    (a 3 x 3 eigenproblem, 1e-9 relative)."""
    m_blk, ea, l0, k_guide, g = 2.0, 1.0e4, 0.5, 3.0e3, 9.81
    d = np.array([1.0, 2.0, 2.0]) / 3
    block = [float(v) for v in l0 * d]
    base = ("&scene title = 'block', dimension = 3, gravity = 0, 0, {gz} /\n"
            "&node label = 'anchor', x = 0, y = 0, z = 0, fixed = .true. /\n"
            f"&node label = 'block', x = {block[0]!r}, y = {block[1]!r}, z = {block[2]!r} /\n"
            f"&truss label = 'spring', from = 'anchor', to = 'block', E = {ea}, A = 1.0, "
            "mode = 'dynamic' /\n"
            "&slider label = 'guide', node = 'block', {extra}direction = 1, 2, 2 /\n"
            f"&mass node = 'block', m = {m_blk} /\n&output nodes = 'block' /\n")
    proc, out = run_scene(tmp_path, base.format(gz=-g, extra="") + "&static n_steps = 1 /\n",
                          name="sag")
    assert proc.returncode == 0, proc.stderr
    with h5py.File(out) as f:
        pos = f["static/nodes/block/position"][-1]
    along = pos @ d - l0
    assert abs(along - m_blk * (-g * d[2]) * l0 / ea) < 1e-10
    assert np.linalg.norm(pos - (pos @ d) * d) < 1e-10
    text = base.format(gz=0, extra=f"mode = 'dynamic', stiffness = {k_guide}, ") + "&modal /\n"
    proc, out = run_scene(tmp_path, text, name="modes")
    assert proc.returncode == 0, proc.stderr
    with h5py.File(out) as f:
        omega = f["modal/frequency_hz"][:] * 2 * math.pi
    expected = sorted([math.sqrt(ea / l0 / m_blk), math.sqrt(k_guide / m_blk),
                       math.sqrt(k_guide / m_blk)])
    assert np.allclose(omega, expected, rtol=1e-9, atol=0), (omega, expected)


def test_node_inputs_in_space(tmp_path):
    """Translations as node inputs in a spatial scene. (1) The root's z prescribed (motion_z,
    a 'constant' law of 0.01 m, stepped by &static): the cantilever moves up rigidly, tip z
    = 0.01 m to the Newton tolerance. (2) A block whose z is a degree of freedom (dynamic =
    'z') on a vertical truss spring (its elongation then follows from z: 'elastic'): static
    sag m g L / EA and frequency sqrt(EA / (L m)) (bounds 1e-9 relative)."""
    text = cantilever("&motion label = 'lift', law = 'constant', start = 0.01 /\n"
                      "&static n_steps = 2 /\n&output nodes = 'tip' /\n")
    text = text.replace("z = 0, fixed = .true. /", "z = 0, fixed = .true., fix_z = .false., "
                        "motion_z = 'lift' /")
    proc, out = run_scene(tmp_path, text, name="lift")
    assert proc.returncode == 0, proc.stderr
    with h5py.File(out) as f:
        tip = f["static/nodes/tip/position"][-1]
    assert np.allclose(tip, [L, 0, 0.01], rtol=0, atol=1e-10)
    m_blk, ea, length, g = 3.0, 2.0e4, 0.4, 9.81
    text = (f"&scene title = 'block', dimension = 3, gravity = 0, 0, {-g} /\n"
            f"&node label = 'anchor', x = 0, y = 0, z = {-length}, fixed = .true. /\n"
            "&node label = 'block', x = 0, y = 0, z = 0, fix_x = .true., fix_y = .true., "
            "dynamic = 'z' /\n"
            f"&truss label = 'spring', from = 'anchor', to = 'block', E = {ea}, A = 1, "
            "mode = 'elastic' /\n"
            f"&mass node = 'block', m = {m_blk} /\n&static n_steps = 1 /\n&modal /\n"
            "&output nodes = 'block' /\n")
    proc, out = run_scene(tmp_path, text, name="block")
    assert proc.returncode == 0, proc.stderr
    with h5py.File(out) as f:
        z = f["static/nodes/block/position"][-1, 2]
        omega = f["modal/frequency_hz"][0] * 2 * math.pi
    assert z == pytest.approx(-m_blk * g * length / ea, rel=1e-9)
    assert omega == pytest.approx(math.sqrt(ea / (length * m_blk)), rel=1e-9)


def test_shaft_spins_many_turns(tmp_path):
    """A spatial hinge's angle is defined modulo 4 pi (Euler parameters), yet a prescribed
    shaft may turn on: the kinematics matches it modulo that period. A blade spun up to
    10 rad/s in 1 s (spin_up) and run on to t = 3 s turns 25 rad, four turns: the tip follows
    the hub (steady lag deflection of a stiff blade, observed 4e-7 rad; bound 1e-4 rad) in the
    plane z = 0."""
    text = ("&scene title = 'spin', dimension = 3 /\n"
            "&node label = 'hub', x = 0, y = 0, z = 0, fixed = .true. /\n"
            "&node label = 'tip', x = 1, y = 0, z = 0 /\n"
            "&link label = 'blade', from = 'hub', to = 'tip', n_elements = 4, E = 7e10,\n"
            "      A = 1e-4, I = 1e-9, Iy = 1e-9, J = 2e-9, G = 2.6e10, rho = 2700 /\n"
            "&hinge label = 'shaft', node = 'hub', link = 'blade', mode = 'prescribed', "
            "motion = 'spin' /\n"
            "&motion label = 'spin', law = 'spin_up', rate = 10.0, duration = 1.0 /\n"
            "&dynamic t_end = 3.0, output_dt = 0.01, rtol = 1e-6, atol = 1e-8 /\n"
            "&output nodes = 'tip' /\n")
    proc, out = run_scene(tmp_path, text)
    assert proc.returncode == 0, proc.stderr
    with h5py.File(out) as f:
        tip = f["nodes/tip/position"][:]
    angle = np.unwrap(np.arctan2(tip[:, 1], tip[:, 0]))
    assert angle[-1] == pytest.approx(10.0 * (3.0 - 0.5), abs=1e-4)
    assert np.max(np.abs(tip[:, 2])) == 0


def test_inertia_in_rotated_axes(tmp_path):
    """&mass rotation: the inertia given in axes turned by 90 degrees about z (body x along
    global y) is the tensor with Jxx and Jyy swapped: the same frequencies as that tensor
    given directly. The rotation's round-off (1e-16) reaches the frequencies through the
    eigensolver, whose relative error on omega^2 is up to eps (omega_max/omega_min)^2 =
    2e-16 (2713/3.3)^2 = 1.5e-10 on the lowest mode; bound 1e-9 (observed up to 1.6e-12)."""
    freqs = []
    for mass in ("inertia = 0.02, 0.01, 0.02, 0, 0, 0, rotation = 0, 0, 1, "
                 f"{math.pi / 2!r}", "inertia = 0.01, 0.02, 0.02, 0, 0, 0"):
        proc, out = run_scene(tmp_path, cantilever(f"&mass node = 'tip', {mass} /\n&modal /\n"),
                              name=f"m{len(freqs)}")
        assert proc.returncode == 0, proc.stderr
        with h5py.File(out) as f:
            freqs.append(f["modal/frequency_hz"][:])
    assert np.allclose(freqs[0], freqs[1], rtol=1e-9, atol=0)


def test_inertia_in_axes_given_by_two_vectors(tmp_path):
    """&mass axes: the body x axis along (1, 1, 0) and the x-y plane through (0, 2, 0) (y
    orthogonalised to (-1, 1, 0)/sqrt 2) is the turn by 45 degrees about z; the same
    frequencies as `rotation = 0, 0, 1, pi/4`. The two constructions differ by round-off,
    which the eigensolver turns into up to eps (omega_max/omega_min)^2 = 1.5e-10 relative
    (see test_inertia_in_rotated_axes); bound 1e-9 (observed up to 1.6e-12)."""
    freqs = []
    for axes in (f"rotation = 0, 0, 1, {math.pi / 4!r}", "axes = 1, 1, 0, 0, 2, 0"):
        text = cantilever(f"&mass node = 'tip', inertia = 0.02, 0.01, 0.03, 0.001, 0, 0, "
                          f"{axes} /\n&modal /\n")
        proc, out = run_scene(tmp_path, text, name=f"a{len(freqs)}")
        assert proc.returncode == 0, proc.stderr
        with h5py.File(out) as f:
            freqs.append(f["modal/frequency_hz"][:])
    assert np.allclose(freqs[0], freqs[1], rtol=1e-9, atol=0)


@pytest.mark.parametrize("axes,fragments", [
    ("inertia = 1, 1, 1, 0, 0, 0, axes = 0, 0, 0, 0, 1, 0", ["'axes'", "must not be zero"]),
    ("inertia = 1, 1, 1, 0, 0, 0, axes = 1, 0, 0, 2, 0, 0", ["'axes'", "parallel"]),
    ("inertia = 1, 1, 1, 0, 0, 0, axes = 1, 0, 0", ["'axes'", "6 values"]),
    ("m = 1, axes = 1, 0, 0, 0, 1, 0", ["'axes'", "'inertia'", "not given"]),
    ("inertia = 1, 1, 1, 0, 0, 0, axes = 1, 0, 0, 0, 1, 0, rotation = 0, 0, 1, 1",
     ["'rotation'", "'axes'", "give one"]),
])
def test_axes_errors(tmp_path, axes, fragments):
    proc, out = run_scene(tmp_path, cantilever(f"&mass node = 'tip', {axes} /\n"))
    assert_clean_error(proc, out, *fragments)
