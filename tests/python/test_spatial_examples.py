"""The spatial examples named by the issue list, against closed forms and flexmor's own
converged solutions (generators and closed forms in scripts/spatial_examples.py):
lateral-torsional buckling, Bathe and Bolourchi's 45-degree bend, Simo and Vu-Quoc's
right-angle cantilever, and time laws on spatial forces and moments."""
import math

import h5py
import numpy as np
import pytest

from helpers import ROOT, load_driver, run_scene

EX = load_driver(ROOT / "scripts" / "spatial_examples.py")


def run_ok(tmp_path, text, name):
    proc, out = run_scene(tmp_path, text, name=name)
    assert proc.returncode == 0, proc.stderr
    return out


def test_ltb_gamma_is_the_textbook_constant():
    """The shooting solution reproduces Timoshenko and Gere's 4.013 (to its 4 digits)."""
    assert EX.ltb_gamma() == pytest.approx(4.013, abs=6e-4)


def test_lateral_buckling_against_the_closed_form(tmp_path):
    """Shear-rigid beams converge as h^2 to P = gamma sqrt(E Iy G J)/L^2: the error ratio from
    8 to 16 beams is 4 (observed 4.03), and the Richardson value from 8 and 16 beams lies
    2e-5 from the closed form (bound 2e-4). The example file (32 shear-flexible beams) is
    within 0.2 % (observed 5.5e-4), and its shape turns the tip out of the loaded plane."""
    p_cr = EX.ltb_critical_force()
    loads = {}
    for n in (4, 8, 16):
        out = run_ok(tmp_path, EX.lateral_buckling_scene(n, shear_rigid=True), f"ltb{n}")
        with h5py.File(out) as f:
            loads[n] = f["buckling/load_factor"][0]
    assert (loads[4] - loads[8]) / (loads[8] - loads[16]) == pytest.approx(4.0, abs=0.3)
    richardson = loads[16] + (loads[16] - loads[8]) / 3
    assert richardson == pytest.approx(p_cr, rel=2e-4)
    out = run_ok(tmp_path, (ROOT / "input" / "lateral_buckling.nml").read_text(), "example")
    with h5py.File(out) as f:
        assert f["buckling/load_factor"][0] == pytest.approx(p_cr, rel=2e-3)
        shape = f["buckling/nodes/tip/shape"][0]
    # Unit largest translation: the lateral (z) one; y, in the loaded plane, stays at zero.
    assert abs(shape[2]) == pytest.approx(1.0, abs=1e-9)
    assert abs(shape[1]) < 1e-6


def test_bend45_converges_and_the_example_is_within_target(tmp_path):
    """The bend's tip error goes as h^2 (ratio 8->16 over 16->32 observed 4.0 at every load
    step, checked in [3, 5]); the example's 8 beams are within 0.2 % of the tip displacement
    of the Richardson value from 16 and 32 beams (observed 6e-4 of it)."""
    tips = {}
    for n in (8, 16, 32):
        with h5py.File(run_ok(tmp_path, EX.bend45_scene(n), f"bend{n}")) as f:
            tips[n] = f["static/nodes/tip/position"][:]
    ratio = (np.abs(tips[8] - tips[16]).max(axis=1) / np.abs(tips[16] - tips[32]).max(axis=1))
    assert np.all((ratio > 3) & (ratio < 5)), ratio
    ref = tips[32] + (tips[32] - tips[16]) / 3
    with h5py.File(run_ok(tmp_path, (ROOT / "input" / "bend45.nml").read_text(), "ex")) as f:
        example = f["static/nodes/tip/position"][:]
        start = f["model/nodes/position"][-1]
    displacement = np.linalg.norm(ref - start, axis=1)
    assert np.all(np.linalg.norm(example - ref, axis=1) < 2e-3 * displacement)
    assert np.allclose(example, tips[8], rtol=0, atol=1e-9 * EX.BEND_RADIUS)


def test_right_angle_cantilever_energy(tmp_path):
    """Over the pulse the force does the work W = -int z F' dt = 50 (int_1^2 z - int_0^1 z)
    (integration by parts, F = 0 at both ends), which must equal the energy at t = 2 (observed
    4e-6 relative with Simpson on the 0.01 s output, bound 1e-3); afterwards the energy stays
    constant (observed 3e-5 over 2 s at rtol 1e-5, bound 3e-3)."""
    text = (ROOT / "input" / "right_angle_cantilever.nml").read_text()
    text = text.replace("t_end = 30.0, output_dt = 0.05", "t_end = 4.0, output_dt = 0.01")
    with h5py.File(run_ok(tmp_path, text, "elbow")) as f:
        t = f["time"][:]
        z = f["nodes/elbow/position"][:, 2]
        energy = f["energy/kinetic"][:] + f["energy/potential"][:]
    i1, i2 = np.argmin(abs(t - 1)), np.argmin(abs(t - 2))
    assert t[i1] == pytest.approx(1.0) and t[i2] == pytest.approx(2.0)

    def simpson(y, x):
        h = x[1] - x[0]
        return h / 3 * (y[0] + y[-1] + 4 * y[1:-1:2].sum() + 2 * y[2:-1:2].sum())
    work = 50 * (simpson(z[i1:i2 + 1], t[i1:i2 + 1]) - simpson(z[:i1 + 1], t[:i1 + 1]))
    assert work > 10
    assert energy[i2] == pytest.approx(work, rel=1e-3)
    after = energy[i2:]
    assert np.max(np.abs(after - after[0])) < 3e-3 * after[0]


@pytest.mark.parametrize("component,value", [("fz", 0.5), ("mz", 0.1)])
def test_time_law_scales_spatial_loads_in_statics(tmp_path, component, value):
    """Statics takes the loads at t = 0: a time law worth 0.7 there is the same as a constant
    load 0.7 times as large, to the Newton tolerance (1e-11 of the model size; bound 1e-8 of
    the deflection)."""
    scene = ("&scene title = 'c', dimension = 3 /\n"
             "&node label = 'root', x = 0, y = 0, z = 0, fixed = .true. /\n"
             "&node label = 'tip', x = 1, y = 0, z = 0 /\n"
             "&link label = 'b', from = 'root', to = 'tip', n_elements = 2, E = 7e10,\n"
             "      A = 1e-4, I = 1e-9, Iy = 2e-9, J = 1.5e-9, G = 2.6e10, rho = 2700 /\n"
             "&static n_steps = 1 /\n&output nodes = 'tip' /\n")
    law = "&motion label = 'p', law = 'ramp', start = 0.7, t0 = 0, rate = 5 /\n"
    tips = []
    for text in (scene + f"&force node = 'tip', {component} = {0.7 * value!r} /\n",
                 scene + law + f"&force node = 'tip', {component} = {value}, time_law = 'p' /\n"):
        with h5py.File(run_ok(tmp_path, text, f"s{len(tips)}")) as f:
            tips.append(f["static/nodes/tip/position"][-1] - f["model/nodes/position"][-1])
    deflection = np.max(np.abs(tips[0]))
    assert deflection > 1e-4
    assert np.max(np.abs(tips[1] - tips[0])) < 1e-8 * deflection


def test_spatial_two_link_without_gravity_is_the_planar_arm(tmp_path):
    """Spatial beams and hinges about z reproduce the planar benchmark's tip path: observed
    5.3e-6 m over 0.7 s (the spatial beams add the sections' rotary inertia, which the planar
    beams leave out, and a 1e8 shear factor); bound 5e-5 m, below the planar mesh's own error
    (6e-5 m). z stays exactly 0."""
    text = (ROOT / "input" / "two_link_spatial.nml").read_text()
    text = text.replace("gravity = 0.0, 0.0, -9.81", "gravity = 0.0, 0.0, 0.0")
    text = text.replace("&static n_steps = 1 /", "").replace("&modal n_modes = 6 /", "")
    with h5py.File(run_ok(tmp_path, text, "space")) as f:
        tip3 = f["nodes/tip/position"][:]
    with h5py.File(run_ok(tmp_path, (ROOT / "input" / "two_link.nml").read_text(), "plane")) as f:
        tip2 = f["nodes/tip/position"][:]
    assert np.max(np.abs(tip3[:, :2] - tip2[:, :2])) < 5e-5
    assert np.max(np.abs(tip3[:, 2])) == 0


def test_spatial_two_link_static_sag(tmp_path):
    """Under 1/100 of gravity (so the geometric non-linearity, (w/L)^2, is 1e-8) the straight
    arm's sag is the Euler-Bernoulli closed form of two cantilevers in series (link 2 with its
    weight and the tip mass; link 1 with its weight and link 2's shear and moment at the
    elbow), exact at the nodes for cubic elements with consistent loads; bound 1e-5."""
    text = (ROOT / "input" / "two_link_spatial.nml").read_text()
    text = text.replace("gravity = 0.0, 0.0, -9.81", "gravity = 0.0, 0.0, -0.0981")
    text = text.split("&modal")[0] + "&output nodes = 'tip', 'elbow' /\n"
    with h5py.File(run_ok(tmp_path, text, "sag")) as f:
        tip = f["static/nodes/tip/position"][-1]
        elbow = f["static/nodes/elbow/position"][-1]
    g, l1, l2 = 0.0981, 0.545, 0.675
    ei1, ei2 = 7.3e10 * 1.69e-8, 7.3e10 * 3.33e-9
    q1, q2, m_elbow, m_tip = 2700 * 9.0e-4 * g, 2700 * 4.0e-4 * g, 1.0, 3.0
    w2 = q2 * l2**4 / (8 * ei2) + m_tip * g * l2**3 / (3 * ei2)
    shear, moment = q2 * l2 + (m_tip + m_elbow) * g, q2 * l2**2 / 2 + m_tip * g * l2
    w1 = q1 * l1**4 / (8 * ei1) + shear * l1**3 / (3 * ei1) + moment * l1**2 / (2 * ei1)
    slope1 = q1 * l1**3 / (6 * ei1) + shear * l1**2 / (2 * ei1) + moment * l1 / ei1
    assert -elbow[2] == pytest.approx(w1, rel=1e-5)
    assert -tip[2] == pytest.approx(w1 + slope1 * l2 + w2, rel=1e-5)


def test_spatial_two_link_reduced_needs_basis_updates(tmp_path):
    """As the elbow folds, link 2's weight twists link 1; torsion is not among the 4 lowest
    modes of the straight arm, so a fixed basis misses most of the sag change (observed
    error 59 % of the largest sag), while the MAC-updated basis of the example follows the full
    model (observed 6 % out of plane and 8e-4 of the in-plane deflection). Bounds: fixed
    > 30 %, updated < 15 % and 1e-2."""
    with h5py.File(run_ok(tmp_path, (ROOT / "input" / "two_link_spatial.nml").read_text(),
                          "full")) as f:
        full = f["nodes/tip/position"][:]
    reduced_text = (ROOT / "input" / "two_link_spatial_reduced.nml").read_text()
    with h5py.File(run_ok(tmp_path, reduced_text, "mac")) as f:
        mac = f["nodes/tip/position"][:]
    fixed_text = reduced_text.replace(", update = 'mac', update_interval = 0.01", "")
    assert fixed_text != reduced_text
    with h5py.File(run_ok(tmp_path, fixed_text, "fixed")) as f:
        fixed = f["nodes/tip/position"][:]
    sag = np.max(np.abs(full[:, 2]))
    t = np.linspace(0, 0.7, full.shape[0])
    s = np.clip(t / 0.5, 0, 1)
    phi = np.pi / 2 * (3 * s**2 - 2 * s**3)
    rigid = np.stack([0.545 * np.cos(phi) + 0.675 * np.cos(2 * phi),
                      0.545 * np.sin(phi) + 0.675 * np.sin(2 * phi)], axis=1)
    in_plane = np.max(np.abs(full[:, :2] - rigid))
    assert np.max(np.abs(fixed[:, 2] - full[:, 2])) > 0.3 * sag
    assert np.max(np.abs(mac[:, 2] - full[:, 2])) < 0.15 * sag
    assert np.max(np.abs(mac[:, :2] - full[:, :2])) < 1e-2 * in_plane


def test_spatial_cross_spring_pivot(tmp_path):
    """The pivot's out-of-plane support stiffness at the crossing against the closed form of
    its two leaves (wide-direction Timoshenko bending and torsion, body rotations free):
    observed 2e-8 relative; bound 1e-5 (Newton stops within 1e-11 of the model size, 1.5e-6 of
    the 0.17 um deflection). Its rotational stiffness under a moment about z is 2 E I / L
    (observed 5e-7 at 1.8 mrad; the change with rotation is ~phi^2 = 3e-6; bound 1e-4). Both
    need the extrapolated difference tangent (elastic modes): the plain one made the soft
    rotation's stiffness negative. Also the 6 x 6 compliance and the clamps' reactions."""
    text = (ROOT / "input" / "cross_spring_pivot_spatial.nml").read_text()
    with h5py.File(run_ok(tmp_path, text, "z")) as f:
        dz = f["static/nodes/body/position"][-1, 2]
        freq = f["modal/frequency_hz"][:]
        compliance = f["static/nodes/body/compliance"][-1]
        grounds = [(f[f"static/nodes/{g}/position"][-1], f[f"static/nodes/{g}/reaction"][-1])
                   for g in ("ground1", "ground2")]
    assert 0.1 / dz == pytest.approx(EX.pivot_support_stiffness(), rel=1e-5)
    assert freq[0] > 0
    # The 6 x 6 compliance: symmetric; its z entry is the support stiffness again (the
    # extrapolated difference tangent: observed 2e-8).
    assert np.max(np.abs(compliance - compliance.T)) < 1e-6 * np.max(np.abs(compliance))
    assert 1 / compliance[2, 2] == pytest.approx(EX.pivot_support_stiffness(), rel=1e-5)
    # The clamps' reactions balance the load: force and moment about the origin (the body
    # node, where the load acts). Observed 1e-12 N; bound 1e-8 of the load (Newton).
    force = sum(r[:3] for _, r in grounds) + np.array([0, 0, 0.1])
    moment = sum(np.cross(p, r[:3]) + r[3:] for p, r in grounds)
    assert np.max(np.abs(force)) < 1e-8 * 0.1
    assert np.max(np.abs(moment)) < 1e-8 * 0.1 * 0.05
    text = text.replace("fz = 0.1 /", "mz = 1.0e-4 /")
    with h5py.File(run_ok(tmp_path, text, "rot")) as f:
        lam = f["static/nodes/body/orientation"][-1]
        compliance = f["static/nodes/body/compliance"][-1]
    phi = 2 * np.arctan2(lam[3], lam[0])
    e, i, length = 2.1e11, 6.6666667e-15, 0.05
    assert 1.0e-4 / phi == pytest.approx(2 * e * i / length, rel=1e-4)
    # The tangent there, through the compliance's rotation about z: observed 1.6e-6 from the
    # closed form (Krylov products, the default at 90 coordinates; the dense tangent 1.9e-6;
    # both 1.7e-4 low while the dense columns took the products' step, the leaves' stiff
    # modes at 1e7 N/m beside 0.056 N m/rad). The closed form is the small-rotation limit
    # (the equilibrium above is within 5e-7 of it). Bound 1e-4.
    assert 1 / compliance[5, 5] == pytest.approx(2 * e * i / length, rel=1e-4)


def test_rotating_blade_frequencies(tmp_path):
    """The blade spinning at Omega = 10 rad/s (input/rotating_blade.nml, modes at t = 1 s, the
    hub turned 10 rad): flapwise omega^2 = omega0^2 + alpha Omega^2 with the Southwell
    coefficients alpha (first-order perturbation, 1.1933 and 6.4782; observed 4.7e-4 and
    3.7e-4 relative, the O(Omega^2/omega0^2) terms and the sections' rotary inertia; bound
    5e-3), and lagwise lower by exactly Omega^2 (the in-plane centrifugal softening). The
    lag-flap difference departs from Omega^2 by terms that grow with the mode as (beta_n r)^2
    (r^2 = I/A = 1e-5 m^2, beta_n L = 1.8751, 4.6941: 3.5e-5, 2.2e-4), as the sections' rotary
    inertia does: observed 9.3e-5 and 6.4e-4 (2.6 and 2.9 (beta_n r)^2, both builds); bound
    30 (beta_n r)^2, 10x (the former 1e-3 for both modes was within 1.6x of mode 2). Without
    the softening the difference would be 0 (off by 1). The same modes at t = 0.2 s (hub at
    2 rad) to 1e-9: they do not depend on where the blade points."""
    text = (ROOT / "input" / "rotating_blade.nml").read_text()
    omega = {}
    for name, modal in (("spin", "time = 1.0, along_motion = .true."),
                        ("early", "time = 0.2, along_motion = .true."),
                        ("rest", "time = 1.0")):
        scene = text.replace("time = 1.0, along_motion = .true.", modal)
        with h5py.File(run_ok(tmp_path, scene, name)) as f:
            omega[name] = f["modal/frequency_hz"][:] * 2 * np.pi
    spin, rest = omega["spin"], omega["rest"]
    big = 10.0
    # Modes in pairs (lag below flap) per bending order; at rest the pairs coincide.
    assert np.allclose(rest[0::2], rest[1::2], rtol=1e-9)
    for k, mode in ((0, 1), (2, 2)):
        lag, flap = spin[k], spin[k + 1]
        alpha = (flap**2 - rest[k]**2) / big**2
        assert alpha == pytest.approx(EX.southwell_coefficient(mode), rel=5e-3)
        beta_r2 = {1: 1.8751, 2: 4.6941}[mode]**2 * 1.0e-9 / 1.0e-4  # (beta_n r)^2, L = 1
        assert (flap**2 - lag**2) / big**2 == pytest.approx(1.0, abs=30 * beta_r2)
    assert np.allclose(omega["early"], spin, rtol=1e-9)


def body_motion(path):
    """Times, Euler parameters, body angular velocity 2 G(lambda) lambda' (central differences
    of the output), and the global rotation matrices of a node's orientation history."""
    with h5py.File(path) as f:
        t = f["time"][:]
        lam = f["nodes/body/orientation"][:]
        kinetic = f["energy/kinetic"][:]
    l0, l1, l2, l3 = lam.T
    g = np.stack([np.stack([-l1, l0, l3, -l2], -1), np.stack([-l2, -l3, l0, l1], -1),
                  np.stack([-l3, l2, -l1, l0], -1)], 1)
    omega = 2 * np.einsum("nij,nj->ni", g, np.gradient(lam, t, axis=0))
    rot = np.stack([
        np.stack([l0**2 + l1**2 - l2**2 - l3**2, 2 * (l1 * l2 - l0 * l3), 2 * (l1 * l3 + l0 * l2)], -1),
        np.stack([2 * (l1 * l2 + l0 * l3), l0**2 - l1**2 + l2**2 - l3**2, 2 * (l2 * l3 - l0 * l1)], -1),
        np.stack([2 * (l1 * l3 - l0 * l2), 2 * (l2 * l3 + l0 * l1), l0**2 - l1**2 - l2**2 + l3**2], -1)],
        1)
    return t, omega, rot, kinetic


@pytest.mark.parametrize("axis", ["intermediate", "major"])
def test_torque_free_body(tmp_path, axis):
    """input/torque_free_body.nml after its spin-up pulse: the kinetic energy is constant
    (observed 4e-10 relative in Debug, 4e-14 in Release; bound 1e-7, ten times the
    integrator's rtol), and so is the angular momentum R J omega in space (omega from central
    differences of the 1 ms output and the rtol of the run: observed 2e-6 of |H|; bound
    3e-5). About the intermediate axis the wobble (the body's y axis from H) grows at
    Omega sqrt((J2 - J1)(J3 - J2)/(J1 J3)) (fit of log over 2..10 s: observed 1.3e-3 off,
    the fit over a slightly elliptic wobble; bound 2e-2); about the major axis (z, the spin
    given about z) it stays within 10 times its size at the end of the pulse (observed 1.9)."""
    text = (ROOT / "input" / "torque_free_body.nml").read_text()
    spin = np.array([0.0, 1.0, 0.0])
    if axis == "major":
        text = text.replace("mx = 1.0e-4, my = 40.0", "mx = 1.0e-4, mz = 60.0")
        text = text.replace("axis = 0.0, 1.0, 0.0", "axis = 0.0, 0.0, 1.0")
        spin = np.array([0.0, 0.0, 1.0])
    t, omega, rot, kinetic = body_motion(run_ok(tmp_path, text, axis))
    jb = np.diag([1.0, 2.0, 3.0])
    free = t >= 0.2
    h = np.einsum("nij,jk,nk->ni", rot, jb, omega)[free]
    assert np.max(np.abs(kinetic[free] - kinetic[free][0])) < 1e-7 * kinetic[free][0]
    assert np.max(np.abs(h - h[0])) < 3e-5 * np.linalg.norm(h[0])
    body_axis = np.einsum("nij,j->ni", rot, spin)
    wobble = np.arccos(np.clip(body_axis @ (h[0] / np.linalg.norm(h[0])), -1, 1))
    if axis == "intermediate":
        big = np.linalg.norm(h[0]) / 2.0
        rate = big * math.sqrt((2 - 1) * (3 - 2) / (1 * 3))
        window = (t >= 2) & (t <= 10)
        assert np.polyfit(t[window], np.log(wobble[window]), 1)[0] == pytest.approx(rate, rel=2e-2)
    else:
        assert np.max(wobble[free]) < 10 * wobble[np.argmin(np.abs(t - 0.2))]


def test_free_floating_body(tmp_path):
    """The torque-free body made free-floating: its centre of mass is a node with dynamic x,
    y, z (mass 2 kg) and a clamped rotation, carrying the body through the ball joint. A
    force pulse with the moment pulse gives it the velocity impulse / m = F (2/3 x 0.1 s) / m
    (the 3-point table is a parabola; observed 5.8e-6 relative, the integration of the pulse
    at rtol 1e-8; bound 1e-4), which then stays constant (observed 5e-13 m/s; bound 1e-8 m/s),
    while the rotation is that of the fixed-pivot body (angular momentum conserved).
    The joint's bending is singular only when the spin axis turns half over."""
    text = (ROOT / "input" / "torque_free_body.nml").read_text()
    text = text.replace("x = 0.0,  y = 0.0, z = 0.0, fixed = .true. /",
                        "x = 0.0, y = 0.0, z = 0.0, fix_rotation = .true., "
                        "dynamic = 'x', 'y', 'z' /\n&mass node = 'pivot', m = 2.0 /")
    text = text.replace("my = 40.0, time_law", "my = 40.0, fx = 5.0, fz = 2.0, time_law")
    text = text.replace("t_end = 10.0", "t_end = 2.0").replace("nodes = 'body'",
                                                              "nodes = 'body', 'pivot'")
    out = run_ok(tmp_path, text, "free")
    with h5py.File(out) as f:
        t = f["time"][:]
        centre = f["nodes/pivot/position"][:]
    free = t >= 0.2
    velocity = np.gradient(centre, t, axis=0)[free]
    expected = np.array([5.0, 0.0, 2.0]) * (2 / 3 * 0.1) / 2.0
    assert np.max(np.abs(velocity - velocity[0])) < 1e-8
    assert np.max(np.abs(velocity[0] - expected)) < 1e-4 * np.max(np.abs(expected))
    t2, omega, rot, _ = body_motion(out)
    h = np.einsum("nij,jk,nk->ni", rot, np.diag([1.0, 2.0, 3.0]), omega)[t2 >= 0.2]
    assert np.max(np.abs(h - h[0])) < 3e-5 * np.linalg.norm(h[0])
