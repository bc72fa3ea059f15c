"""&linear: the linearised state-space model (A, B, C, D) of a configuration, against the
modal analysis (eigenvalues of A), the static compliance (DC gain), stiffness-proportional
damping (real parts of the eigenvalues), a spatial scene, and bad inputs."""
import math

import h5py
import numpy as np
import pytest

from helpers import ROOT, assert_clean_error, run_scene

TWO_LINK = "\n".join(line for line in (ROOT / "input" / "two_link.nml").read_text().splitlines()
                     if not line.startswith(("&dynamic", "&output")))


def model(path):
    with h5py.File(path) as f:
        lin = {k: f[f"linear/{k}"][0] for k in "ABCD"}
        lin["inputs"] = [s.decode() if isinstance(s, bytes) else s for s in f["linear/inputs"][:]]
        lin["modal"] = f["modal/frequency_hz"][:] if "modal" in f else None
    return lin


def test_two_link_eigenvalues_are_the_modes(tmp_path):
    """The two-link at t = 0 with both joints held: A's eigenvalues are +-i 2 pi f of the
    modal analysis (3.0567 and 23.2033 Hz among them; observed 2e-11 relative, bound 1e-8) with
    zero real parts (no damping; observed 1e-12 of the largest; bound 1e-8)."""
    text = TWO_LINK + ("\n&linear inputs = 'tip.fx', 'tip.fy', 'elbow.moment', "
                       "outputs = 'tip.x', 'tip.y', 'elbow.phi' /\n")
    proc, out = run_scene(tmp_path, text)
    assert proc.returncode == 0, proc.stderr
    lin = model(out)
    assert lin["A"].shape == (24, 24) and lin["B"].shape == (24, 3)
    assert lin["C"].shape == (3, 24) and lin["D"].shape == (3, 3)
    assert lin["inputs"] == ["tip.fx", "tip.fy", "elbow.moment"]
    ev = np.linalg.eigvals(lin["A"])
    f = np.sort(np.abs(ev.imag))[::2] / (2 * math.pi)
    assert np.allclose(f, np.sort(lin["modal"]), rtol=1e-8, atol=0)
    assert f[0] == pytest.approx(3.0567, abs=1e-4) and f[1] == pytest.approx(23.2033, abs=1e-4)
    assert np.max(np.abs(ev.real)) < 1e-8 * np.max(np.abs(ev))


def test_dc_gain_is_the_static_compliance(tmp_path):
    """The leaf-spring guide at its last static step: -C A^-1 B + D is the tangent compliance
    of the shuttle that statics writes (both from the same extrapolated difference tangent;
    observed 2e-9 relative, bound 1e-6)."""
    text = (ROOT / "input" / "leaf_spring_guide.nml").read_text().replace(
        "&static n_steps = 11 /", "&static n_steps = 11 /\n&linear inputs = 'shuttle.fx', "
        "'shuttle.fy', 'shuttle.moment', outputs = 'shuttle.x', 'shuttle.y', 'shuttle.phi' /")
    proc, out = run_scene(tmp_path, text)
    assert proc.returncode == 0, proc.stderr
    lin = model(out)
    gain = -lin["C"] @ np.linalg.solve(lin["A"], lin["B"]) + lin["D"]
    with h5py.File(out) as f:
        compliance = f["static/nodes/shuttle/compliance"][-1]
    assert np.max(np.abs(gain - compliance)) < 1e-6 * np.max(np.abs(compliance))


def test_stiffness_proportional_damping(tmp_path):
    """A cantilever with link damping beta (sigma = S (e + beta e')): C = beta K, so each
    mode's eigenvalues are -beta w^2/2 +- i w sqrt(1 - (beta w/2)^2) (observed 2e-13
    relative; bound 1e-6)."""
    beta = 1.0e-4
    text = ("&node label = 'root', x = 0, y = 0, fixed = .true. /\n"
            "&node label = 'tip', x = 1, y = 0 /\n"
            "&link label = 'arm', from = 'root', to = 'tip', n_elements = 3, E = 7.0e10,\n"
            f"      A = 1.0e-4, I = 1.0e-9, rho = 2700, damping = {beta} /\n"
            "&modal /\n&linear inputs = 'tip.fy', outputs = 'tip.y' /\n")
    proc, out = run_scene(tmp_path, text)
    assert proc.returncode == 0, proc.stderr
    lin = model(out)
    w = 2 * math.pi * lin["modal"]
    ev = np.linalg.eigvals(lin["A"])
    ev = ev[ev.imag > 0]
    ev = ev[np.argsort(np.abs(ev))]
    expected = -beta * w**2 / 2 + 1j * w * np.sqrt(1 - (beta * w / 2)**2)
    assert np.allclose(ev, expected, rtol=1e-6, atol=0)


def test_spatial_dc_gain(tmp_path):
    """A spatial cantilever: the DC gain from the tip's six force and moment components to
    its six displacements and rotations is the static 6 x 6 compliance (bound 1e-6)."""
    comps_in = ", ".join(f"'tip.{c}'" for c in ("fx", "fy", "fz", "mx", "my", "mz"))
    comps_out = ", ".join(f"'tip.{c}'" for c in ("x", "y", "z", "rx", "ry", "rz"))
    text = ("&scene title = 'c', dimension = 3 /\n"
            "&node label = 'root', x = 0, y = 0, z = 0, fixed = .true. /\n"
            "&node label = 'tip', x = 1, y = 0, z = 0 /\n"
            "&link label = 'b', from = 'root', to = 'tip', n_elements = 2, E = 7e10, A = 1e-4,\n"
            "      I = 1e-9, Iy = 2e-9, J = 1.5e-9, G = 2.6e10, rho = 2700,"
            " elongation = 'dynamic' /\n"
            "&force node = 'tip', fz = 1e-3 /\n&static n_steps = 1 /\n"
            "&output nodes = 'tip', compliance_nodes = 'tip' /\n"
            f"&linear inputs = {comps_in}, outputs = {comps_out} /\n")
    proc, out = run_scene(tmp_path, text)
    assert proc.returncode == 0, proc.stderr
    lin = model(out)
    gain = -lin["C"] @ np.linalg.solve(lin["A"], lin["B"])
    with h5py.File(out) as f:
        compliance = f["static/nodes/tip/compliance"][-1]
    assert np.max(np.abs(gain - compliance)) < 1e-6 * np.max(np.abs(compliance))


@pytest.mark.parametrize("linear,fragments", [
    ("inputs = 'nope.fx', outputs = 'tip.x'", ["&linear", "'inputs'", "'nope.fx'"]),
    ("inputs = 'tip.fz', outputs = 'tip.x'", ["&linear", "'tip.fz'", "'fz'", "fx, fy, moment"]),
    ("inputs = 'tip.fx', outputs = 'tip.rz'", ["&linear", "'outputs'", "'rz'", "x, y, phi"]),
    ("inputs = 'tip.fx'", ["&linear", "'outputs'"]),
    ("inputs = 'tip', outputs = 'tip.x'", ["&linear", "'tip'", "node.component"]),
    ("inputs = 'tip.fy', outputs = 'nope#1.e2'", ["&linear", "'outputs'", "'nope#1.e2'",
                                                  "no element", "'link#k'"]),
    ("inputs = 'tip.fy', outputs = 'arm.sigma2'", ["&linear", "'arm.sigma2'", "no element"]),
    ("inputs = 'tip.fy', outputs = 'arm#1.e4'", ["&linear", "'arm#1.e4'", "beam",
                                                 "modes 1 to 3"]),
    ("inputs = 'tip.fy', outputs = 'arm#1.sigma0'", ["&linear", "'arm#1.sigma0'", "modes 1 to 3"]),
    ("inputs = 'tip.fy', outputs = 'arm#1.e123456789012'", ["&linear", "modes 1 to 3"]),
    ("inputs = 'arm#1.e2', outputs = 'tip.y'", ["&linear", "'inputs'", "'arm#1.e2'",
                                                "output only"]),
    ("inputs = 'tip.fy', outputs = 'tip.e'", ["&linear", "'tip.e'", "x, y, phi"]),
    # The beam's elongation is rigid (the default): its axial force is a multiplier, and
    # 'sigma1' = (S e)_1 read 0 under any axial load.
    ("inputs = 'tip.fx', outputs = 'arm#1.sigma1'", ["&linear", "'arm#1.sigma1'", "rigid",
                                                     "constraint force", "dynamic or elastic"]),
])
def test_bad_linear_input(tmp_path, linear, fragments):
    text = ("&node label = 'root', x = 0, y = 0, fixed = .true. /\n"
            "&node label = 'tip', x = 1, y = 0 /\n"
            "&link label = 'arm', from = 'root', to = 'tip', E = 7.0e10, A = 1.0e-4,\n"
            f"      I = 1.0e-9, rho = 2700 /\n&linear {linear} /\n")
    proc, out = run_scene(tmp_path, text)
    assert_clean_error(proc, out, *fragments)


def test_step_response_matches_the_nonlinear_model(tmp_path):
    """A cantilever (3 beams, light stiffness-proportional damping) under a small tip force
    switched on at t = 0: the linear model's step response y(t) = C A^-1 (exp(A t) - I) B u
    (by A's eigen-decomposition) follows the non-linear run's tip deflection. The differences
    are the geometric non-linearity ((w/L)^2 ~ 1e-8 at this load) and the integrator's error
    at rtol 1e-8; observed 2.5e-8 of the peak, bound 1e-5."""
    force = 1.0e-2
    body = ("&node label = 'root', x = 0, y = 0, fixed = .true. /\n"
            "&node label = 'tip', x = 1, y = 0 /\n"
            "&link label = 'arm', from = 'root', to = 'tip', n_elements = 3, E = 7.0e10,\n"
            "      A = 1.0e-4, I = 1.0e-9, rho = 2700, damping = 1.0e-4 /\n")
    proc, out = run_scene(tmp_path, body + "&linear inputs = 'tip.fy', outputs = 'tip.y' /\n",
                          name="lin")
    assert proc.returncode == 0, proc.stderr
    lin = model(out)
    step = ("&motion label = 'on', law = 'constant', start = 1.0 /\n"
            f"&force node = 'tip', fy = {force}, time_law = 'on' /\n"
            "&dynamic t_end = 0.2, output_dt = 1e-3, integrator = 'bdf', rtol = 1e-8,"
            " atol = 1e-12 /\n&output nodes = 'tip' /\n")
    proc, out = run_scene(tmp_path, body + step, name="step")
    assert proc.returncode == 0, proc.stderr
    with h5py.File(out) as f:
        t = f["time"][:]
        y = f["nodes/tip/position"][:, 1]
    lam, vec = np.linalg.eig(lin["A"])
    b = np.linalg.solve(vec, lin["B"][:, 0] * force)
    # exp(A t) - I applied through the eigenbasis, then A^-1: (exp(lam t) - 1) / lam.
    z = (vec @ (((np.exp(np.outer(t, lam)) - 1) / lam) * b).T).real
    y_lin = lin["C"][0] @ z
    assert np.max(np.abs(y)) > 1e-5
    assert np.max(np.abs(y - y_lin)) < 1e-5 * np.max(np.abs(y))


def test_along_a_run(tmp_path):
    """&linear times: linearised at states of the dynamic run. The blade of
    input/rotating_blade.nml (6 beams) spun up smoothly to 10 rad/s by t = 2 s and linearised
    at t = 3 s, with its small residual vibration and the Coriolis terms: A's eigenvalues are
    the modes along the motion (&modal along_motion at that time; observed 2e-7, bound 1e-5)
    with real parts below 1e-5 of them (observed 7e-7 /s). Two times give two models."""
    text = (ROOT / "input" / "rotating_blade.nml").read_text()
    text = text.replace("law = 'ramp', t0 = 0.0, rate = 10.0", "law = 'spin_up', rate = 10.0, "
                        "duration = 2.0").replace("n_elements = 16", "n_elements = 6")
    text = text.replace("time = 1.0, along_motion = .true. /", "time = 3.0, along_motion = "
                        ".true. /\n&linear inputs = 'tip.fz', outputs = 'tip.z', "
                        "times = 0.0, 3.0 /\n&dynamic t_end = 3.0, output_dt = 0.01, "
                        "rtol = 1e-8, atol = 1e-10 /")
    proc, out = run_scene(tmp_path, text)
    assert proc.returncode == 0, proc.stderr
    with h5py.File(out) as f:
        a = f["linear/A"][:]
        times = f["linear/time"][:]
        modal = f["modal/frequency_hz"][:]
    assert a.shape[0] == 2 and np.allclose(times, [0.0, 3.0])
    ev = np.linalg.eigvals(a[1])
    f = np.sort(np.abs(ev.imag))[::2] / (2 * math.pi)
    assert np.allclose(f[:4], modal, rtol=1e-5, atol=0)
    assert np.max(np.abs(ev.real)) < 1e-5 * 2 * math.pi * modal[0]


@pytest.mark.parametrize("extra,fragments", [
    ("times = 0.1 /", ["&linear", "'times'", "no &dynamic"]),
    ("times = 0.1, time = 0.2 /", ["&linear", "'times'", "excludes"]),
    ("times = 5.0 /\n&dynamic t_end = 0.01 /", ["&linear", "'times'", "within"]),
])
def test_bad_linear_times(tmp_path, extra, fragments):
    text = ("&node label = 'root', x = 0, y = 0, fixed = .true. /\n"
            "&node label = 'tip', x = 1, y = 0 /\n"
            "&link label = 'arm', from = 'root', to = 'tip', E = 7.0e10, A = 1.0e-4,\n"
            "      I = 1.0e-9, rho = 2700 /\n"
            f"&linear inputs = 'tip.fy', outputs = 'tip.y', {extra}\n")
    proc, out = run_scene(tmp_path, text)
    assert_clean_error(proc, out, *fragments)


ARM = ("&node label = 'base', x = 0, y = 0, fixed = .true. /\n"
       "&node label = 'tip', x = 1, y = 0 /\n"
       "&link label = 'arm', from = 'base', to = 'tip', n_elements = 2, E = 7.0e10,\n"
       "      A = 1.0e-4, I = 1.0e-9, rho = 2700, elongation = 'rigid', bending = 'rigid' /\n")
J_ARM = 2700 * 1.0e-4 / 3   # rho A L^3 / 3 of the rigid 1 m link about its hinge


RUN = ("&dynamic t_end = {t_end}, output_dt = 0.01, integrator = 'bdf', rtol = 1e-9,"
       " atol = 1e-12 /\n&output nodes = 'tip' /\n")


def arm_angle(tmp_path, text):
    """Run a scene of the rigid arm; times and the arm's angle (from its tip)."""
    proc, out = run_scene(tmp_path, text)
    assert proc.returncode == 0, proc.stderr
    assert "warning" not in proc.stderr
    with h5py.File(out) as f:
        t = f["time"][:]
        tip = f["nodes/tip/position"][:]
    return t, np.unwrap(np.arctan2(tip[:, 1], tip[:, 0]))


@pytest.mark.parametrize("law,scale", [("", 1.0),
                                       (", torque_law = 'half'", 0.5)])
def test_actuator_spins_a_rigid_link(tmp_path, law, scale):
    """A hinge driven by a constant actuator torque (mode 'dynamic', no spring, no gravity)
    turns the rigid link by tau t^2 / (2 J), J = rho A L^3/3; a torque_law scales it (a
    'constant' law of 0.5). Observed 3e-12; bound 1e-8 (BDF at rtol 1e-9)."""
    tau = 0.09
    motion = "&motion label = 'half', law = 'constant', start = 0.5 /\n" if law else ""
    t, angle = arm_angle(tmp_path, ARM + "&hinge label = 'j1', node = 'base', link = 'arm', "
                         f"mode = 'dynamic', torque = {tau}{law} /\n" + motion
                         + RUN.format(t_end=1.0))
    assert np.allclose(angle, scale * tau * t**2 / (2 * J_ARM), rtol=0, atol=1e-8)


def test_linear_joint_inputs_and_outputs(tmp_path):
    """A rigid link on a hinge spring k: from (torque, tip force) to (angle, tip y) the DC
    gain is [[1, L], [L, L^2]] / k and A's eigenvalues are +-i sqrt(k/J) (bound 1e-9)."""
    k = 5.0
    text = (ARM + f"&hinge label = 'j1', node = 'base', link = 'arm', mode = 'dynamic', "
            f"stiffness = {k} /\n"
            "&linear inputs = 'j1.torque', 'tip.fy', outputs = 'j1.angle', 'tip.y' /\n")
    proc, out = run_scene(tmp_path, text)
    assert proc.returncode == 0, proc.stderr
    lin = model(out)
    gain = -lin["C"] @ np.linalg.solve(lin["A"], lin["B"])
    assert np.allclose(gain, np.ones((2, 2)) / k, rtol=1e-9, atol=0)
    ev = np.linalg.eigvals(lin["A"])
    assert np.allclose(np.sort(ev.imag), [-math.sqrt(k / J_ARM), math.sqrt(k / J_ARM)],
                       rtol=1e-9, atol=0)


@pytest.mark.parametrize("hinge,linear,fragments", [
    ("mode = 'rigid', torque = 1.0", "", ["&hinge", "'torque'", "dynamic"]),
    ("mode = 'dynamic', torque = 1.0, torque_law = 'nope'", "",
     ["&hinge 'j1'", "'torque_law'", "'nope'", "not defined"]),
    ("mode = 'dynamic', stiffness = 5.0",
     "&linear inputs = 'j1.angle', outputs = 'tip.y' /\n", ["&linear", "'j1.angle'", "'torque'"]),
    ("mode = 'prescribed', motion = 'm'",
     "&motion label = 'm', law = 'constant', start = 0 /\n"
     "&linear inputs = 'tip.fy', outputs = 'j1.angle' /\n", ["&linear", "'j1'", "not dynamic"]),
])
def test_bad_actuator_and_joint_io(tmp_path, hinge, linear, fragments):
    # A flexible link, so that a model with a prescribed hinge still has degrees of freedom.
    text = (ARM.replace("bending = 'rigid'", "bending = 'dynamic'")
            + f"&hinge label = 'j1', node = 'base', link = 'arm', {hinge} /\n" + linear)
    proc, out = run_scene(tmp_path, text)
    assert_clean_error(proc, out, *fragments)


def test_pd_controlled_joint_step_response(tmp_path):
    """A PD controller on the hinge of a rigid link (kp, kd, tracking a reference step of
    0.2 rad held from t = 0) gives the closed-form second-order response
    J e'' + kd e' + kp e = kp r: r (1 - exp(-zeta wn t)(cos wd t + zeta/sqrt(1 - zeta^2)
    sin wd t)), wn = sqrt(kp/J), zeta = kd/(2 sqrt(kp J)); observed 5e-9 rad, bound 1e-7."""
    kp, kd, ref = 2.0, 0.1, 0.2
    t, angle = arm_angle(tmp_path, ARM + "&hinge label = 'j1', node = 'base', link = 'arm', "
                         f"mode = 'dynamic', kp = {kp}, kd = {kd}, reference = 'r' /\n"
                         f"&motion label = 'r', law = 'constant', start = {ref} /\n"
                         + RUN.format(t_end=2.0))
    wn, zeta = math.sqrt(kp / J_ARM), kd / (2 * math.sqrt(kp * J_ARM))
    wd = wn * math.sqrt(1 - zeta**2)
    closed = ref * (1 - np.exp(-zeta * wn * t) * (np.cos(wd * t)
                                                   + zeta / math.sqrt(1 - zeta**2) * np.sin(wd * t)))
    assert np.max(np.abs(angle - closed)) < 1e-7


@pytest.mark.parametrize("hinge,fragments", [
    ("mode = 'dynamic', kd = 0.1, reference = 'r'", ["&hinge", "'kp'"]),
    ("mode = 'dynamic', kp = 2.0, stiffness = 1.0, reference = 'r'", ["&hinge", "not both"]),
    ("mode = 'dynamic', kp = -2.0, reference = 'r'", ["&hinge", "'kp'"]),
    ("mode = 'dynamic', kp = 2.0, reference = 'nope'", ["&hinge 'j1'", "'reference'", "'nope'"]),
    ("mode = 'rigid', kp = 2.0, reference = 'r'", ["&hinge", "'kp'", "dynamic"]),
])
def test_bad_pd_controller(tmp_path, hinge, fragments):
    text = (ARM + f"&hinge label = 'j1', node = 'base', link = 'arm', {hinge} /\n"
            "&motion label = 'r', law = 'constant', start = 0.2 /\n")
    proc, out = run_scene(tmp_path, text)
    assert_clean_error(proc, out, *fragments)


def test_two_link_pd_example_settles(tmp_path):
    """input/two_link_pd.nml: joint PD controllers track the benchmark's cubic quarter turns.
    Without feedforward of the arm's inertia the tip lags the rigid path during the move
    (observed up to 0.46 m); once the references stop, the controllers bring the tip to the
    rigid end position (observed 8.6e-5 m at t = 1.5 s; bound 1e-3 m)."""
    proc, out = run_scene(tmp_path, (ROOT / "input" / "two_link_pd.nml").read_text())
    assert proc.returncode == 0, proc.stderr
    with h5py.File(out) as f:
        tip = f["nodes/tip/position"][-1]
    end = np.array([0.545 * math.cos(math.pi / 2) + 0.675 * math.cos(math.pi),
                    0.545 * math.sin(math.pi / 2) + 0.675 * math.sin(math.pi)])
    assert np.linalg.norm(tip[:2] - end) < 1e-3


# A cantilever of 4 beams (8 dynamic coordinates: the elongations are rigid) with a tip mass; &reduction needs a
# &dynamic, kept to one step.
CANTILEVER = ("&node label = 'root', x = 0, y = 0, fixed = .true. /\n"
              "&node label = 'tip', x = 1, y = 0 /\n"
              "&link label = 'arm', from = 'root', to = 'tip', n_elements = 4, E = 7.0e10,\n"
              "      A = 1.0e-4, I = 1.0e-9, rho = 2700 /\n&mass node = 'tip', m = 0.1 /\n"
              "&dynamic t_end = 1e-3, output_dt = 1e-3 /\n")
N_DY_CANTILEVER = 8


def reduced_model(tmp_path, k, extra=""):
    text = (CANTILEVER + f"&reduction n_modes = {k} /\n&modal n_modes = {N_DY_CANTILEVER} /\n"
            "&linear inputs = 'tip.fy', 'tip.moment', outputs = 'tip.y', 'tip.phi' /\n" + extra)
    proc, out = run_scene(tmp_path, text, name=f"k{k}")
    assert proc.returncode == 0, proc.stderr
    lin = model(out)
    with h5py.File(out) as f:
        lin["reduced"] = f["linear"].attrs["reduced"]
        lin["n_modes"] = int(f["linear"].attrs["n_modes"])
    return lin


@pytest.mark.parametrize("k", [1, 3, 5])
def test_reduced_eigenvalues_are_the_lowest_modes(tmp_path, k):
    """&linear time with &reduction: the k-mode modal basis at the same locked configuration
    makes V^T K V = diag(omega^2), V^T M V = I, so A (2k x 2k) has +-i 2 pi f of the full
    model's k lowest modes (observed 6e-15 relative, real parts 7e-17 of the largest;
    bound 1e-10)."""
    lin = reduced_model(tmp_path, k)
    assert lin["A"].shape == (2 * k, 2 * k) and lin["B"].shape == (2 * k, 2)
    assert lin["C"].shape == (2, 2 * k)
    assert lin["reduced"] == "yes" and lin["n_modes"] == k
    ev = np.linalg.eigvals(lin["A"])
    f = np.sort(np.abs(ev.imag))[::2] / (2 * math.pi)
    assert np.allclose(f, lin["modal"][:k], rtol=1e-10, atol=0)
    assert np.max(np.abs(ev.real)) < 1e-10 * np.max(np.abs(ev))


def test_reduced_dc_gain_converges(tmp_path):
    """The reduced DC gain W_y V (V^T K V)^-1 V^T W_u^T is the modal sum over the kept modes,
    sum phi_y phi_u / omega^2: for the collocated pairs (tip.fy, tip.y) and (tip.moment,
    tip.phi) every term is positive, so the gains grow monotonically with k towards the full
    compliance, which k = n_dy reproduces to round-off (observed 1.6e-12 relative; bound
    1e-10). One mode gives the tip deflection within 0.45% and the rotation within 30%."""
    full = reduced_model(tmp_path, N_DY_CANTILEVER)
    text = CANTILEVER + ("&linear inputs = 'tip.fy', 'tip.moment', outputs = 'tip.y', "
                         "'tip.phi' /\n")
    proc, out = run_scene(tmp_path, text, name="full")
    assert proc.returncode == 0, proc.stderr
    reference = model(out)
    with h5py.File(out) as f:
        assert f["linear"].attrs["reduced"] == "no" and f["linear"].attrs["n_modes"] == 0

    def dc(lin):
        return -lin["C"] @ np.linalg.solve(lin["A"], lin["B"])

    exact = dc(reference)
    assert np.max(np.abs(dc(full) - exact)) < 1e-10 * np.max(np.abs(exact))
    gains = [np.diag(dc(reduced_model(tmp_path, k))) for k in range(1, N_DY_CANTILEVER + 1)]
    assert np.all(np.diff(gains, axis=0) >= -1e-12 * np.abs(exact.diagonal()))
    assert np.allclose(gains[-1], exact.diagonal(), rtol=1e-10, atol=0)
    assert abs(gains[0][0] / exact[0, 0] - 1) < 5e-2


@pytest.mark.parametrize("reduction,linear,fragments", [
    ("n_modes = 9", "", ["&reduction", "n_modes = 9", "between 1 and", "(8)"]),
    ("n_modes = 2", ", times = 0.5", ["&linear", "'times'", "within"]),
    ("n_modes = 2, basis_prescribed = 0.1", "", ["&reduction", "'basis_prescribed'", "got 1"]),
])
def test_bad_reduced_linear(tmp_path, reduction, linear, fragments):
    """The reduced model's basis is made before the run for &linear time, so the reduction's
    errors come from there too; times outside the reduced run are refused as for a full one."""
    text = (CANTILEVER + f"&reduction {reduction} /\n"
            f"&linear inputs = 'tip.fy', outputs = 'tip.y'{linear} /\n")
    proc, out = run_scene(tmp_path, text)
    assert_clean_error(proc, out, *fragments)


def test_mode_outputs_of_a_cantilever(tmp_path):
    """Element modes as outputs on a cantilever of 4 beams (l = L/4) under a tip force F: the
    Hermite beam is exact for its cubic deflection, so the root beam's bending mode
    e2 = l theta_p (theta relative to the chord) is -F l^2 (3L - l)/(6 EI) and its stress
    sigma2 = (S e)_2 = EI/l^2 (4 theta_p + 2 theta_q) = -F L / l, the root moment F L over l,
    and sigma3 = -F (L - l) / l, the moment at its other end over l; a dynamic mode's C row is
    the unit row. Observed 5e-13 relative; bound 1e-9."""
    ei, length, n = 7.0e10 * 1.0e-9, 1.0, 4
    l = length / n
    text = ("&node label = 'root', x = 0, y = 0, fixed = .true. /\n"
            "&node label = 'tip', x = 1, y = 0 /\n"
            f"&link label = 'arm', from = 'root', to = 'tip', n_elements = {n}, E = 7.0e10,\n"
            "      A = 1.0e-4, I = 1.0e-9, rho = 2700 /\n"
            "&linear inputs = 'tip.fy', outputs = 'arm#1.e2', 'arm#1.sigma2', "
            "'arm#1.sigma3' /\n")
    proc, out = run_scene(tmp_path, text)
    assert proc.returncode == 0, proc.stderr
    lin = model(out)
    gain = (-lin["C"] @ np.linalg.solve(lin["A"], lin["B"]))[:, 0]
    expected = [-l**2 * (3 * length - l) / (6 * ei), -length / l, -(length - l) / l]
    assert np.allclose(gain, expected, rtol=1e-9, atol=0)
    assert lin["C"][0, 0] == 1 and np.all(lin["C"][0, 1:] == 0)


FRAME = ("&node label = 'a', x = 0, y = 0, fixed = .true. /\n"
         "&node label = 'b', x = 2, y = 0, fix_x = .true., fix_y = .true. /\n"
         "&node label = 'c', x = 1, y = 1 /\n"
         "&link label = 'l1', from = 'a', to = 'c', n_elements = 2, E = 7.0e10, A = 1.0e-4,\n"
         "      I = 1.0e-9, rho = 2700 /\n"
         "&link label = 'l2', from = 'b', to = 'c', E = 7.0e10, A = 1.0e-4, I = 1.0e-9,\n"
         "      rho = 2700, elongation = 'elastic' /\n"
         "&hinge label = 'h', node = 'c', link = 'l2', mode = 'released' /\n"
         "&force node = 'c', fx = {force} /\n&static n_steps = 1, tol = 1e-13 /\n")


def test_mode_output_rows_by_differences(tmp_path):
    """A frame: a cantilever l1 with a pinned strut l2 (elastic elongation) hinged to its tip
    (released). The hinge angle is no coordinate: its C row is De DF_dy, and between the
    static solutions under F and 1.01 F it predicts the change of the angle (computed from the
    hinge's end rotations in /static/x) from that of q_dy: observed 1.7e-7 relative (the
    geometric non-linearity over the step, ~ the rotations of 1e-7 rad); bound 2e-6. The
    strut's axial stress row is EA/l0 times its elongation's (observed 1e-16; bound 1e-12)."""
    runs = []
    for i, force in enumerate((1.0, 1.01)):
        text = FRAME.format(force=force) + ("&linear inputs = 'c.fx', outputs = 'h.e1', "
                                            "'l2#1.e1', 'l2#1.sigma1' /\n")
        proc, out = run_scene(tmp_path, text, name=f"frame{i}")
        assert proc.returncode == 0, proc.stderr
        with h5py.File(out) as f:
            labels = [s.decode() for s in f["model/elements/label"][:]]
            phi = f["model/elements/coordinates"][labels.index("h")][:2] - 1
            x = f["static/x"][-1]
            runs.append({"q": f["static/q"][:], "angle": x[phi[1]] - x[phi[0]],
                         "C": f["linear/C"][0]})
    n = runs[0]["q"].size
    row = runs[0]["C"][0, :n]
    assert np.count_nonzero(np.abs(row) > 1e-12 * np.max(np.abs(row))) > 1
    predicted = row @ (runs[1]["q"] - runs[0]["q"])
    change = runs[1]["angle"] - runs[0]["angle"]
    assert abs(predicted / change - 1) < 2e-6
    ea_l0 = 7.0e10 * 1.0e-4 / math.sqrt(2)
    assert np.allclose(runs[0]["C"][2], ea_l0 * runs[0]["C"][1], rtol=0,
                       atol=1e-12 * np.max(np.abs(runs[0]["C"][2])))


def test_reduced_run_times_in_the_result_file(tmp_path):
    """&linear times along a reduced run: one 2k-state model per sample, marked reduced; at
    t = 0 the cantilever is at rest in the basis configuration, so its eigenvalues are the
    k lowest modes (observed 4e-13 relative; bound 1e-10). tests/test_linear_reduced.f90 checks the models along a moving run."""
    text = (CANTILEVER + "&reduction n_modes = 3 /\n&modal n_modes = 3 /\n"
            "&linear inputs = 'tip.fy', outputs = 'tip.y', 'arm#1.sigma2', times = 0, 1e-3 /\n")
    proc, out = run_scene(tmp_path, text)
    assert proc.returncode == 0, proc.stderr
    with h5py.File(out) as f:
        a = f["linear/A"][:]
        assert a.shape == (2, 6, 6) and f["linear/C"].shape == (2, 2, 6)
        assert f["linear"].attrs["reduced"] == "yes" and f["linear"].attrs["n_modes"] == 3
        modal = f["modal/frequency_hz"][:]
    ev = np.linalg.eigvals(a[0])
    fr = np.sort(np.abs(ev.imag))[::2] / (2 * math.pi)
    assert np.allclose(fr, modal, rtol=1e-10, atol=0)
