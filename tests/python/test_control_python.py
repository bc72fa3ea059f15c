"""flexmor.control and flexmor-bode: the &linear models read into Python, against the modal
analysis (poles), a pinned-tip modal analysis (zeros), closed-form statics (DC gain), SciPy
and python-control (frequency response), and the non-linear model's steady response to a small
harmonic force; the command's output and errors."""
import math
import os
import subprocess
import sys
import warnings

import h5py
import numpy as np
import pytest

import flexmor
from flexmor import control as fxc

from helpers import ROOT, run_scene

TWO_LINK = "\n".join(line for line in (ROOT / "input" / "two_link.nml").read_text().splitlines()
                     if not line.startswith(("&dynamic", "&output")))

E, AREA, INERTIA, RHO, LENGTH = 7.0e10, 1.0e-4, 1.0e-9, 2700.0, 1.0
EI = E * INERTIA


def cantilever(n_elements=3, damping=0.0, tip="", link_extra="", extra=""):
    """A 1 m aluminium cantilever along x, clamped at 'root', free at 'tip'."""
    damp = f", damping = {damping}" if damping else ""
    return ("&node label = 'root', x = 0, y = 0, fixed = .true. /\n"
            f"&node label = 'tip', x = {LENGTH}, y = 0{tip} /\n"
            "&link label = 'arm', from = 'root', to = 'tip', "
            f"n_elements = {n_elements}, E = {E},\n      A = {AREA}, I = {INERTIA}, "
            f"rho = {RHO}{damp}{link_extra} /\n" + extra)


def run_ok(folder, text, name="scene"):
    proc, out = run_scene(folder, text, name=name)
    assert proc.returncode == 0, proc.stderr
    return out


# Stiffness-proportional damping beta: zeta_1 = beta w_1 / 2 = 0.057 at f_1 = 9.01 Hz, so the
# start-up transient of the first mode falls by exp(-zeta_1 w_1 t) = exp(-3.2 t); higher modes
# are damped more (beta w / 2) and mostly overdamped.
BETA = 2.0e-3
MIMO = cantilever(damping=BETA, extra="&modal /\n&linear inputs = 'tip.fy', 'tip.moment', "
                  "outputs = 'tip.y', 'tip.phi' /\n")


@pytest.fixture(scope="module")
def damped(tmp_path_factory):
    """The damped 3-element cantilever's result: &modal and &linear from (tip.fy, tip.moment)
    to (tip.y, tip.phi)."""
    return run_ok(tmp_path_factory.mktemp("damped"), MIMO)


def test_reads_the_linear_group(damped):
    r = flexmor.read_result(damped)
    lin = flexmor.read_linear(damped)
    assert r.linear is not None and r.linear.inputs == lin.inputs == ["tip.fy", "tip.moment"]
    assert lin.outputs == ["tip.y", "tip.phi"] and lin.n_models == 1
    # 3 elements, rigid elongation: 2 bending coordinates per free node, 3 free nodes.
    assert lin.n_states == 12 and lin.A.shape == (1, 12, 12) and lin.B.shape == (1, 12, 2)
    assert lin.C.shape == (1, 2, 12) and lin.D.shape == (1, 2, 2)
    with h5py.File(damped) as f:
        np.testing.assert_array_equal(lin.A, f["linear/A"][...])
        np.testing.assert_array_equal(lin.time, f["linear/time"][...])
    for mine, stored in zip(lin.matrices(0), (lin.A, lin.B, lin.C, lin.D)):
        np.testing.assert_array_equal(mine, stored[0])


def test_two_link_poles_are_the_modal_frequencies(tmp_path):
    """The benchmark two-link at t = 0 with both joints held: the poles are +-i 2 pi f of the
    &modal frequencies (12 pairs; observed 1.2e-11 relative, bound 1e-8 as in test_linear) and
    the table lists each pair once with zeta at round-off."""
    out = run_ok(tmp_path, TWO_LINK + "\n&linear inputs = 'tip.fy', outputs = 'tip.y' /\n")
    r = flexmor.read_result(out)
    poles = r.linear.poles()
    upper = np.sort_complex(poles[poles.imag > 0] * -1j) * 1j   # sorted by Im s
    expected = 2j * math.pi * np.sort(r.modal.frequency_hz)
    assert upper.size == expected.size == 12
    assert np.max(np.abs(upper - expected) / np.abs(expected)) < 1e-8
    rows = fxc.pole_table(poles)
    assert len(rows) == 12
    np.testing.assert_allclose([row[0] for row in rows], np.sort(r.modal.frequency_hz),
                               rtol=1e-8, atol=0)
    assert max(abs(row[1]) for row in rows) < 1e-8


def test_zeros_are_the_pinned_tip_frequencies(tmp_path):
    """Collocated tip force and tip deflection of an undamped cantilever: the zeros of y/fy are
    the frequencies at which the tip can vibrate without moving, i.e. the natural frequencies
    of the same beam with the tip's y held (a second scene). Holding y over-constrains the
    chain of inextensible elements, so there the last element stretches ('dynamic') and one of
    its bending modes follows the others ('elastic', stiffness kept): the same bending
    structure. 7 zero pairs (observed 3.5e-12 relative; bound 1e-8), all on the imaginary
    axis (observed 3e-14 of |s|, bound 1e-8); |G| at the first zero is a round-off fraction
    of the static gain L^3/3EI (observed 1e-14 of it, bound 1e-6)."""
    free = run_ok(tmp_path, cantilever(4, extra="&linear inputs = 'tip.fy', outputs = 'tip.y' /\n"),
                  name="free")
    pinned = run_ok(tmp_path, cantilever(4, tip=", fix_y = .true.",
                                         link_extra=", elongation = 3*'rigid', 'dynamic',\n"
                                         "      bending = 6*'dynamic', 'elastic', 'dynamic'",
                                         extra="&modal n_modes = 7 /\n"), name="pinned")
    lin = flexmor.read_linear(free)
    zeros = lin.zeros("tip.fy", "tip.y")
    assert zeros.size == 14
    assert np.max(np.abs(zeros.real) / np.abs(zeros)) < 1e-8
    f_zero = np.sort(np.abs(zeros.imag))[::2] / (2 * math.pi)
    f_pinned = flexmor.read_result(pinned).modal.frequency_hz
    np.testing.assert_allclose(f_zero, f_pinned, rtol=1e-8, atol=0)
    g = lin.frequency_response([abs(zeros[0])], input="tip.fy", output="tip.y")
    assert abs(g[0]) < 1e-6 * LENGTH**3 / (3 * EI)


def test_zero_channel_is_an_error(tmp_path):
    """A channel whose B column or C row is zero has no zeros (its pencil is singular)."""
    a = np.array([[0.0, 1.0], [-4.0, -0.1]])
    with pytest.raises(ValueError, match="identically zero"):
        fxc.transmission_zeros(a, np.zeros(2), np.array([1.0, 0.0]))
    assert fxc.transmission_zeros(a, np.zeros(2), np.array([1.0, 0.0]), 2.0).size == 0
    # A single oscillator's force-to-position has no finite zero, its force-to-velocity one
    # at s = 0.
    b = np.array([0.0, 1.0])
    assert fxc.transmission_zeros(a, b, np.array([1.0, 0.0])).size == 0
    z = fxc.transmission_zeros(a, b, np.array([0.0, 1.0]))
    # QZ is backward stable: a simple zero moves by about eps ||pencil|| (~4 eps = 9e-16 here)
    # times its condition number; 1e-12 leaves 1000 for that. Observed 0 (both builds).
    assert z.size == 1 and abs(z[0]) < 1e-12


def test_dc_gain_and_frequency_response(damped):
    """The DC gain -C A^-1 B + D of the damped cantilever is the Euler-Bernoulli tip
    compliance [[L^3/3, L^2/2], [L^2/2, L]] / EI (cubic Hermite beams are exact for end loads;
    observed 2e-14 relative, bound 1e-9); G(i w) at w = 1e-9 w_1 equals it to the first-order
    term 2 zeta w / w_1 ~ 1e-10 (observed 1.1e-10, bound 1e-8). At frequencies below, at and
    above the first two modes G agrees with python-control's StateSpace evaluation (observed
    0, bound 1e-10) and, channel by channel, with scipy.signal.freqresp of a StateSpace,
    which goes through zeros and poles found as polynomial roots: the overdamped real poles
    at -502, -507 and -527 /s are close, and such clustered roots lose about half the digits
    (observed 7e-7 relative, bound 1e-5)."""
    lin = flexmor.read_linear(damped)
    compliance = np.array([[LENGTH**3 / 3, LENGTH**2 / 2], [LENGTH**2 / 2, LENGTH]]) / EI
    gain = lin.dc_gain()
    assert np.max(np.abs(gain - compliance)) < 1e-9 * np.max(np.abs(compliance))
    w1 = abs(lin.poles()[0])
    g0 = lin.frequency_response([1e-9 * w1])[0]
    assert np.max(np.abs(g0 - gain)) < 1e-8 * np.max(np.abs(compliance))

    w = w1 * np.array([0.3, 1.0, 2.0, 5.9, 20.0])
    g = lin.frequency_response(w)
    assert g.shape == (5, 2, 2)
    sys_ctl = lin.to_control()
    assert sys_ctl.input_labels == ["tip_fy", "tip_moment"]
    assert sys_ctl.output_labels == ["tip_y", "tip_phi"]
    g_ctl = np.moveaxis(sys_ctl(1j * w), -1, 0)
    assert np.max(np.abs(g_ctl - g) / np.abs(g)) < 1e-10

    sys_sp = lin.to_scipy()
    np.testing.assert_array_equal(sys_sp.A, lin.A[0])
    np.testing.assert_array_equal(sys_sp.B, lin.B[0])
    from scipy import signal

    a, b, c, _ = lin.matrices()
    n = a.shape[0]
    rounding = np.empty(g.shape)
    for k, wk in enumerate(w):
        m = 1j * wk * np.eye(n) - a
        x = np.linalg.solve(m, b)
        rounding[k] = n * np.finfo(float).eps * np.linalg.cond(m) * np.outer(
            np.linalg.norm(c, axis=1), np.linalg.norm(x, axis=0))
    worst = 0.0
    for i, u in enumerate(lin.inputs):
        for j, y in enumerate(lin.outputs):
            # scipy's freqresp takes one input and one output: that channel of to_scipy().
            channel = signal.StateSpace(sys_sp.A, sys_sp.B[:, [i]], sys_sp.C[[j]],
                                        sys_sp.D[[j]][:, [i]])
            with warnings.catch_warnings():
                # The polynomial route warns about its own conditioning: the digits it
                # loses are what the bound allows.
                warnings.simplefilter("ignore", signal.BadCoefficients)
                _, g_sp = signal.freqresp(channel, w)
            single = lin.frequency_response(w, input=u, output=y)
            # One channel's solve and the all-channel one round differently (the BLAS
            # kernel picks the order of the sums): each is within n eps cond(i w I - A)
            # |c_y| |x_u| of the exact C x, so their difference within twice that. Observed:
            # at most 2e-9 of it (1.4e-12 relative with one OpenBLAS kernel, 1e-14 with
            # others). The bound stays below 1e-2 |G| here (observed 1.4e-3), so a channel
            # mixed up would fail.
            assert np.all(np.abs(single - g[:, j, i]) <= 2 * rounding[:, j, i])
            assert np.all(rounding[:, j, i] < 1e-2 * np.abs(g[:, j, i]))
            worst = max(worst, float(np.max(np.abs(g_sp - single) / np.abs(single))))
    assert worst < 1e-5


def test_bad_names_and_index(damped):
    lin = flexmor.read_linear(damped)
    with pytest.raises(flexmor.LinearModelError, match="no input 'tip.fx'; the inputs are "
                       "tip.fy, tip.moment"):
        lin.frequency_response([1.0], input="tip.fx", output="tip.y")
    with pytest.raises(flexmor.LinearModelError, match="no output 'tip.x'"):
        lin.zeros("tip.fy", "tip.x")
    with pytest.raises(flexmor.LinearModelError, match="index 1 out of range"):
        lin.poles(1)
    with pytest.raises(ValueError, match="both"):
        lin.frequency_response([1.0], input="tip.fy")


def test_read_linear_errors(tmp_path, damped):
    with pytest.raises(flexmor.ResultFileError, match="no such file"):
        flexmor.read_linear(tmp_path / "missing.h5")
    modal_only = run_ok(tmp_path, cantilever(extra="&modal /\n"), name="modal")
    with pytest.raises(flexmor.ResultFileError, match="no group /linear"):
        flexmor.read_linear(modal_only)
    assert flexmor.read_result(modal_only).linear is None
    bad = tmp_path / "bad.h5"
    with h5py.File(damped) as src, h5py.File(bad, "w") as f:
        f.attrs["flexmor_version"] = src.attrs["flexmor_version"]
        for name in src["linear"]:
            f[f"linear/{name}"] = src[f"linear/{name}"][...]
        del f["linear/B"]
        f["linear/B"] = np.zeros((1, 12, 3))
    with pytest.raises(flexmor.ResultFileError, match=r"/linear/B has shape \(1, 12, 3\)"):
        flexmor.read_linear(bad)


# --- the linear model against the non-linear one ------------------------------------------------

FORCE = 1.0e-2   # N: the tip moves 5e-5 m statically, 4e-4 m at resonance (0.04 % of L)
SAMPLES = 32     # per period
FIT_TIME = 1.0   # s: the fit covers the last whole periods that span at least this


@pytest.fixture(scope="module")
def linear_model(tmp_path_factory):
    return flexmor.read_linear(run_ok(tmp_path_factory.mktemp("lin"), cantilever(
        damping=BETA, extra="&linear inputs = 'tip.fy', outputs = 'tip.y' /\n")))


@pytest.mark.parametrize("f_force", [4.5, 9.0, 18.0])
def test_harmonic_response_matches_the_nonlinear_model(tmp_path, linear_model, f_force):
    """The damped cantilever under a tip force FORCE sin(2 pi f t) (law 'harmonic'), run with
    the full non-linear equations for about 7 s (BDF, rtol 1e-10): a least-squares fit of
    a sin + b cos + c to the tip deflection over the last whole periods (5, 9, 18 of them:
    at least 1 s) gives
    (a + i b)/FORCE = G(i w) of the &linear model, at f = 4.5 Hz (below the first mode,
    9.011 Hz), 9.0 Hz (inside its half-power band) and 18 Hz (above).

    Error budget (relative to |G|): the first mode's transient exp(-zeta_1 w_1 t) has fallen to
    6e-9 when the fit starts (t >= 5.9 s); the integrator's error at rtol 1e-10 was observed at
    4e-9, 1.1e-7 and 1.4e-8 (at rtol 1e-8 it is 1.4e-6 at resonance, where the slow build-up
    accumulates phase error); the geometric non-linearity scales with the amplitude squared
    (observed 8.6e-6 at 10 FORCE at resonance, hence ~9e-8 here). Observed 4.8e-9, 1.1e-7,
    1.4e-8; bound 2e-6 (18x the largest), far below the 3e-5 that a transient cut off at 3 s
    would leave."""
    period = 1.0 / f_force
    n_periods = round(7.0 * f_force)
    t_end = n_periods * period
    dt = period / SAMPLES
    text = cantilever(damping=BETA, extra=(
        f"&motion label = 'h', law = 'harmonic', amplitude = 1.0, frequency = {f_force} /\n"
        f"&force node = 'tip', fy = {FORCE}, time_law = 'h' /\n"
        f"&dynamic t_end = {t_end!r}, output_dt = {dt!r}, integrator = 'bdf', rtol = 1e-10,"
        " atol = 1e-14 /\n&output nodes = 'tip' /\n"))
    out = run_ok(tmp_path, text)
    with h5py.File(out) as f:
        t = f["time"][:]
        y = f["nodes/tip/position"][:, 1]
    n_fit = math.ceil(FIT_TIME * f_force) * SAMPLES
    # The last n_fit samples before t_end: whole periods on a uniform grid, so the fit's sin,
    # cos and constant are orthogonal to the non-linearity's harmonics 2 w, 3 w.
    t_fit, y_fit = t[-n_fit - 1:-1], y[-n_fit - 1:-1]
    np.testing.assert_allclose(np.diff(t_fit), dt, rtol=1e-9)
    assert t[-1] == pytest.approx(t_end, rel=1e-12) and t_fit[0] > 5.8
    w = 2 * math.pi * f_force
    basis = np.column_stack([np.sin(w * t_fit), np.cos(w * t_fit), np.ones_like(t_fit)])
    (a, b, _), *_ = np.linalg.lstsq(basis, y_fit, rcond=None)
    g_fit = (a + 1j * b) / FORCE
    g_lin = linear_model.frequency_response([w], input="tip.fy", output="tip.y")[0]
    # The three frequencies are where the test says they are relative to the first mode.
    s1 = linear_model.poles()[0]
    f1, half_band = abs(s1) / (2 * math.pi), -s1.real / (2 * math.pi)
    assert {4.5: f_force < f1 / 1.5, 9.0: abs(f_force - f1) < half_band,
            18.0: f_force > 1.5 * f1}[f_force]
    print(f"f = {f_force} Hz: |G| = {abs(g_lin):.6g} m/N, arg G = "
          f"{math.degrees(np.angle(g_lin)):.4f} deg, |G_fit/G - 1| = {abs(g_fit / g_lin - 1):.2e}")
    assert abs(g_fit / g_lin - 1) < 2e-6, (g_fit, g_lin, abs(g_fit / g_lin - 1))


# --- flexmor-bode ---------------------------------------------------------------------------------


def bode(*args, cwd=None):
    # The repository's package from any folder (CTest's PYTHONPATH is absolute, a hand-set
    # PYTHONPATH=python is not).
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(ROOT / "python"), *filter(None, [os.environ.get("PYTHONPATH")])]))
    return subprocess.run([sys.executable, "-m", "flexmor.bode", *map(str, args)],
                          capture_output=True, text=True, timeout=300, cwd=cwd, env=env)


def test_bode_command_writes_plots_and_poles(tmp_path, damped):
    png_bode, png_pz = tmp_path / "b.png", tmp_path / "pz.png"
    proc = bode(damped, "--input", "tip.moment", "--output", "tip.y", "--bode", png_bode,
                "--pole-zero", png_pz, "--fmax", "100")
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == ""
    for png in (png_bode, png_pz):
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 10_000
    lin = flexmor.read_linear(damped)
    rows = fxc.pole_table(lin.poles())
    lines = proc.stdout.splitlines()
    assert "tip.y / tip.moment" in lines[0]
    # The first pole row: natural frequency, damping ratio beta w_1 / 2 and damped frequency.
    first = lines[lines.index(next(line for line in lines if line.startswith("poles"))) + 2]
    fn, zeta, fd = (float(v) for v in first.split()[1:4])
    assert fn == pytest.approx(rows[0][0], rel=1e-5) and fn == pytest.approx(9.011, abs=1e-3)
    assert zeta == pytest.approx(BETA * 2 * math.pi * fn / 2, rel=1e-3)
    assert fd == pytest.approx(fn * math.sqrt(1 - zeta**2), rel=1e-5)
    assert sum(1 for line in lines if line.startswith("wrote ")) == 2
    assert "zeros of tip.y / tip.moment" in proc.stdout


def test_bode_command_help():
    proc = bode("--help")
    assert proc.returncode == 0 and "usage: flexmor-bode" in proc.stdout


@pytest.mark.parametrize("args,fragment", [
    (["missing.h5"], "missing.h5: no such file"),
    (["modal.h5"], "no group /linear"),
    (["damped.h5", "--input", "tip.fx"], "no input 'tip.fx'; the inputs are tip.fy, tip.moment"),
    (["damped.h5", "--output", "tip.x"], "no output 'tip.x'; the outputs are tip.y, tip.phi"),
    (["damped.h5", "--index", "1"], "linearisation index 1 out of range"),
    (["damped.h5", "--index", "-1"], "linearisation index -1 out of range"),
    (["damped.h5", "--bode", "nowhere/b.png"], "does not exist"),
])
def test_bode_command_errors(tmp_path, damped, args, fragment):
    (tmp_path / "damped.h5").write_bytes(damped.read_bytes())
    run_ok(tmp_path, cantilever(extra="&modal /\n"), name="modal")
    proc = bode(*args, cwd=tmp_path)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("flexmor-bode: error: "), proc.stderr
    assert fragment in lines[0]
    assert "Traceback" not in proc.stderr and not list(tmp_path.glob("*.png"))


def test_rigid_body_mode_has_no_dc_gain(tmp_path):
    """A rigid link on a free dynamic hinge (no spring): a double pole at 0, so the DC gain
    is refused; the frequency response away from 0 is the rigid body's -1/(J w^2) from torque
    to angle (J = rho A L^3/3; observed 3e-16 relative, bound 1e-9). The double pole is a
    Jordan block, A = [[0, 1], [0, 0]]: a rounding delta in its stiffness entry would split it
    into +-sqrt(delta), so the bound on |pole| is in sqrt(eps), not eps: with delta up to
    eps ||A|| (||A|| = 1), sqrt(eps) = 1.5e-8 rad/s; bound 10x that. Observed 0 in both builds
    (the rigid arm has no stiffness term at all); the old 1e-12 would fail at delta = 1e-24. A
    spurious stiffness k (a bug) gives sqrt(k / J) (J = 0.09 kg m^2): 3e-3 rad/s at 1e-6 N m."""
    text = ("&node label = 'base', x = 0, y = 0, fixed = .true. /\n"
            "&node label = 'tip', x = 1, y = 0 /\n"
            "&link label = 'arm', from = 'base', to = 'tip', n_elements = 2, E = 7.0e10,\n"
            "      A = 1.0e-4, I = 1.0e-9, rho = 2700, elongation = 'rigid', bending = 'rigid' /\n"
            "&hinge label = 'j1', node = 'base', link = 'arm', mode = 'dynamic' /\n"
            "&linear inputs = 'j1.torque', outputs = 'j1.angle' /\n")
    lin = flexmor.read_linear(run_ok(tmp_path, text))
    assert np.max(np.abs(lin.poles())) < 10 * math.sqrt(np.finfo(float).eps)
    with pytest.raises(ValueError, match="singular"):
        lin.dc_gain()
    w = np.array([0.5, 3.0, 40.0])
    j_arm = RHO * AREA * LENGTH**3 / 3
    g = lin.frequency_response(w, input="j1.torque", output="j1.angle")
    np.testing.assert_allclose(g, -1 / (j_arm * w**2), rtol=1e-9, atol=0)
    # At w = 0, on the poles, G is infinite: a ValueError naming the file and the frequency,
    # not numpy's bare LinAlgError('Singular matrix'), and the same from the module function.
    with pytest.raises(ValueError, match=r"infinite at w = 0 rad/s") as info:
        lin.frequency_response([3.0, 0.0], input="j1.torque", output="j1.angle")
    assert str(lin.path) in str(info.value)
    with pytest.raises(ValueError, match="infinite at w = 0"):
        fxc.frequency_response(*lin.matrices(), [0.0])
