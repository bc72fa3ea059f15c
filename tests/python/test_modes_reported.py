"""What the reported frequencies are: lowest first, each with its own mode shape, and, under
moments fixed in space (an unsymmetric tangent), those of the full problem on which the
stability test decides (docs/theory.md 7, 'Moments fixed in space'; docs/output.md)."""
import math

import h5py
import numpy as np
import pytest

from helpers import ROOT, assert_clean_error, run_scene

#: Aluminium strip of input/roll_up.nml: E I about z (in the x-y plane), E Iy about y.
STRIP = dict(E=7.0e10, A=1.0e-4, I=0.8e-9, Iy=2.0e-9, rho=2700.0, L=1.5)


def run_ok(tmp_path, text, name):
    proc, out = run_scene(tmp_path, text, name=name)
    assert proc.returncode == 0, proc.stderr
    return out


def a_eigen_hz(a):
    """Frequencies |Im s| / (2 pi) of the undamped A = [0 I; -M^-1 K 0], one per pair."""
    s = np.linalg.eigvals(a)
    return np.sort(np.abs(s.imag[s.imag >= 0])) / (2 * math.pi)


def cantilever_scene(n, mz):
    return f"""&scene dimension = 3 /
&node label = 'root', x = 0, y = 0, z = 0, fixed = .true. /
&node label = 'tip', x = {STRIP['L']}, y = 0, z = 0 /
&link label = 'strip', from = 'root', to = 'tip', n_elements = {n},
      E = {STRIP['E']}, A = {STRIP['A']}, I = {STRIP['I']}, Iy = {STRIP['Iy']}, J = 1.5e-9,
      G = 2.6e10, rho = {STRIP['rho']} /
&force node = 'tip', mz = {mz} /
&static n_steps = 1, n_frequencies = 2 /
&modal n_modes = 2 /
&output nodes = 'tip' /
"""


def test_roll_up_frequencies_follow_the_stability_test_and_linear(tmp_path):
    """input/roll_up.nml: every step is stable, so no frequency may be negative (the
    symmetric part of the tangent gave -39.2 Hz at the full turn); the modal frequencies are
    the eigenvalues of &linear's A, which holds the full tangent (4.866, 7.743, 12.705,
    12.739 Hz), and each shape is its own frequency's eigenvector of A's -M^-1 K block.
    Bounds: the two tangents are differenced independently, each evaluation a kinematic
    solution to its Newton tolerance (about 1e-12 of the model size) over a step of 6e-6 of
    it, so they differ by about 2e-7 of a column: 1e-5 relative in omega^2 and in the
    eigenvector residual (measured 3.7e-7 at most)."""
    text = (ROOT / "input" / "roll_up.nml").read_text()
    text = text.replace("&static n_steps = 16 /", "&static n_steps = 16, n_frequencies = 4 /\n"
                        "&modal n_modes = 4 /\n&linear inputs = 'tip.fy', outputs = 'tip.y' /")
    with h5py.File(run_ok(tmp_path, text, "roll_up")) as f:
        stable = f["static/stable"][:]
        f_static = f["static/frequency_hz"][:]
        f_modal = f["modal/frequency_hz"][:]
        shapes = f["modal/shapes"][:]
        a = f["linear/A"][0]
    assert np.all(stable == 1)
    assert np.all(f_static > 0), f_static.min()
    assert np.all(np.diff(f_static, axis=1) >= 0)
    n = a.shape[0] // 2
    f_a = a_eigen_hz(a)
    w_modal, w_a = 2 * math.pi * f_modal, 2 * math.pi * f_a[:4]
    assert w_modal**2 == pytest.approx(w_a**2, rel=1e-5), (f_modal, f_a[:4])
    # The last load step is the state of &modal: the same frequencies.
    assert f_static[-1] == pytest.approx(f_modal, rel=1e-6)
    minv_k = -a[n:, :n]
    for k in range(4):
        v = shapes[k]
        r = minv_k @ v - w_modal[k] ** 2 * v
        assert np.linalg.norm(r) < 1e-5 * w_modal[k] ** 2 * np.linalg.norm(v), k


@pytest.mark.parametrize("n", [8, 16])
def test_small_fixed_moment_cantilever_closed_form(tmp_path, n):
    """A cantilever under a small end moment fixed in space (tip rotation M L / (E I) =
    1e-3 rad, the tangent unsymmetric): its two lowest modes are the unloaded cantilever's
    first bending modes in the two planes, 1.8751^2 sqrt(E I / (rho A L^4)) / (2 pi) with I
    and Iy. The load shifts omega^2 by O(M L / (E I)) = 1e-3 of it at most (measured 2e-8:
    to first order only the symmetric part enters), the mesh (cubic beams) by O((L/n)^4),
    the shear flexibility and rotary inertia of the spatial beams by about 10 I / (A L^2) =
    4e-5 and 9e-5 (measured -3.5e-5 and -8.7e-5 from 8 beams on, converged): bound 1e-3.
    n_frequencies at the same state gives the same values."""
    e_i = STRIP["E"] * STRIP["I"]
    mz = 1e-3 * e_i / STRIP["L"]
    with h5py.File(run_ok(tmp_path, cantilever_scene(n, mz), f"c{n}")) as f:
        f_modal = f["modal/frequency_hz"][:]
        f_static = f["static/frequency_hz"][-1]
        assert f["static/stable"][-1] == 1
    beta2 = 1.8751040687 ** 2
    closed = [beta2 * math.sqrt(STRIP["E"] * i / (STRIP["rho"] * STRIP["A"] * STRIP["L"] ** 4))
              / (2 * math.pi) for i in (STRIP["I"], STRIP["Iy"])]
    assert f_modal == pytest.approx(closed, rel=1e-3)
    assert f_static == pytest.approx(f_modal, rel=1e-9)


def test_rigid_body_frequencies_come_lowest_first_with_their_shapes(tmp_path):
    """A free spatial beam has six zero frequencies (rigid motion), which the Rayleigh
    quotients give as rounding (1e-37 to 1e-22 Hz) in no particular order: /modal/frequency_hz
    must still ascend, and each shape must be the eigenvector of its own frequency: the
    -M^-1 K block of &linear's A, whose differences (step h = 6e-6 of the model size) carry
    rounding of about eps / h = 4e-11 of K, times its largest eigenvalue. Bound 1e-9 of
    max(omega_k^2, the lowest elastic omega^2) (measured 5e-12)."""
    text = """&scene dimension = 3 /
&node label = 'a', x = 0, y = 0, z = 0, dynamic = 'x', 'y', 'z', 'rotation' /
&node label = 'b', x = 1, y = 0, z = 0 /
&link label = 'bar', from = 'a', to = 'b', n_elements = 4,
      E = 7.0e10, A = 1.0e-4, I = 0.8e-9, Iy = 2.0e-9, J = 1.5e-9, G = 2.6e10, rho = 2700 /
&modal /
&linear inputs = 'b.fy', outputs = 'b.y' /
"""
    proc, out = run_scene(tmp_path, text, name="free", quiet=False)
    assert proc.returncode == 0, proc.stderr
    # The progress line printed the rounding zeros as '.000' (f0.3 drops the leading zero).
    line = next(l for l in proc.stdout.splitlines() if l.startswith("modal: frequencies"))
    assert line.split("]: ", 1)[1].startswith("0.000, 0.000"), line
    assert " .000" not in line and "-.000" not in line, line
    with h5py.File(out) as f:
        f_modal = f["modal/frequency_hz"][:]
        shapes = f["modal/shapes"][:]
        a = f["linear/A"][0]
    assert np.all(np.diff(f_modal) >= 0), f_modal[:8]
    n = a.shape[0] // 2
    assert np.all(np.abs(f_modal[:6]) < 1e-3) and f_modal[6] > 10
    minv_k = -a[n:, :n]
    w2 = (2 * math.pi * f_modal) ** 2
    for k in range(len(f_modal)):
        r = minv_k @ shapes[k] - w2[k] * shapes[k]
        assert np.linalg.norm(r) < 1e-9 * max(w2[k], w2[6]) * np.linalg.norm(shapes[k]), k


def test_fixed_end_moment_gives_no_divergence_buckling(tmp_path):
    """A cantilever under an end moment fixed in space cannot diverge (Ziegler): the internal
    moment is M e_z everywhere, so the twist carries GJ phi' = M w' and the lateral bending
    E Iy w'' = -M phi; with phi = w = w' = 0 at the root, phi = M w / GJ and w'' + k^2 w = 0
    leave only w = 0. The symmetric part of K_G gave multipliers 0.664 (twice), 2.09, ... on
    input/roll_up.nml, while the load path stays stable to the full load; the full K_G has
    no real positive multiplier: /buckling is empty, with a warning that names the complex
    ones. Under a compressive end force the same unsymmetric path still finds Euler's
    divergence, pi^2 E I / (4 L^2) in each plane (a 1e-4 N m moment beside 1 N: measured
    -2.8e-5 and -7.1e-5 at 8 beams, the spatial beams' shear; bound 1e-3)."""
    text = (ROOT / "input" / "roll_up.nml").read_text()
    text = text.replace("&static n_steps = 16 /", "&buckling /")
    proc, out = run_scene(tmp_path, text, name="roll_up_buckling")
    assert proc.returncode == 0, proc.stderr
    assert "no real positive load multiplier" in proc.stderr and "complex" in proc.stderr
    with h5py.File(out) as f:
        assert f["buckling/load_factor"].shape == (0,)
    column = cantilever_scene(8, 1e-4).replace("mz = 0.0001", "fx = -1.0, mz = 1e-4")
    column = column.replace("&static n_steps = 1, n_frequencies = 2 /\n&modal n_modes = 2 /",
                            "&buckling n_modes = 2 /")
    with h5py.File(run_ok(tmp_path, column, "column")) as f:
        mu = f["buckling/load_factor"][:]
    euler = [math.pi**2 * STRIP["E"] * i / (4 * STRIP["L"] ** 2)
             for i in (STRIP["I"], STRIP["Iy"])]
    assert mu == pytest.approx(euler, rel=1e-3)


def test_singular_static_tangent_message(tmp_path):
    """A free body under a load in statics is a mechanism: the error names the load factor as
    a number, 'load factor 0.5 (' (it read 'load factor  0.50000', f8.5 with its blank)."""
    text = """&scene dimension = 3 /
&node label = 'body', x = 0, y = 0, z = 0, dynamic = 'x', 'y', 'z', 'rotation' /
&mass node = 'body', m = 2.0, inertia = 1.0, 2.0, 3.0, 0.0, 0.0, 0.0 /
&force node = 'body', fx = 1.0 /
&static n_steps = 2 /
"""
    proc, out = run_scene(tmp_path, text, name="free_static")
    assert_clean_error(proc, out, "singular at load factor 0.5 (buckling or a mechanism)")


@pytest.mark.parametrize("solver", ["dense", "krylov"])
def test_static_newton_failure_message(tmp_path, solver):
    """One Newton iteration cannot bend a cantilever 0.13 rad: both static solvers say so
    with the load factor as a number and no padding ('load factor 1, last correction 2.257E-03';
    the Krylov path read 'load factor  1.00000, last correction  2.257E-03')."""
    text = cantilever_scene(8, 0.0).replace("&scene dimension = 3 /",
                                            "&scene dimension = 3, linear_solver = 'sparse' /")
    text = text.replace("mz = 0.0", "fy = 5.0").replace(
        "&static n_steps = 1, n_frequencies = 2 /",
        f"&static n_steps = 1, max_iter = 1, solver = '{solver}' /")
    proc, out = run_scene(tmp_path, text, name=f"newton_{solver}")
    assert_clean_error(proc, out, "did not converge in 1 iterations at load factor 1, last "
                       "correction ")
    assert "  " not in proc.stderr.strip(), proc.stderr


def test_reduced_basis_of_an_unsymmetric_tangent(tmp_path):
    """The reduced model of the rolled-up strip: its basis is the span of the 4 lowest right
    eigenvectors of the full problem, made Mbar-orthonormal. The span is invariant, so the
    reduced linear model (&linear with &reduction) has exactly those 4 frequencies, and
    /reduction/frequency_hz lists them lowest first (measured 1e-10 and 5e-12 relative; bounds
    1e-5 in omega^2 and 1e-6 in f, as for the full model: each analysis differences its own
    tangent)."""
    text = (ROOT / "input" / "roll_up.nml").read_text()
    text = text.replace("&output nodes", "&modal n_modes = 4 /\n&reduction n_modes = 4 /\n"
                        "&linear inputs = 'tip.fy', outputs = 'tip.y' /\n"
                        "&dynamic t_end = 0.01, output_dt = 0.005 /\n&output nodes")
    with h5py.File(run_ok(tmp_path, text, "roll_up_reduced")) as f:
        assert f["linear"].attrs["reduced"] == "yes"
        f_reduced = a_eigen_hz(f["linear/A"][0])
        f_modal = f["modal/frequency_hz"][:]
        f_basis = f["reduction/frequency_hz"][:]
    assert f_reduced**2 == pytest.approx(f_modal**2, rel=1e-5)
    assert f_basis == pytest.approx(f_modal, rel=1e-6)


def test_buckling_takes_timed_loads_at_t0(tmp_path):
    """A &force with a time_law is a load: &buckling refused the scene ('no &force and no
    gravity'). It takes it at its value at t = 0, as statics does: a law that is 1 there gives
    Euler's pi^2 E I / (4 L^2) in each plane (measured -2.6e-5 and -6.9e-5 at 8 beams, the
    spatial beams' shear; bound 1e-3); one that starts at 0 gives none, with a warning that
    says why."""
    base = cantilever_scene(8, 0.0).replace("&force node = 'tip', mz = 0.0 /", "")
    base = base.replace("&static n_steps = 1, n_frequencies = 2 /\n&modal n_modes = 2 /",
                        "&force node = 'tip', fx = -1.0, time_law = 'law' /\n"
                        "&buckling n_modes = 2 /")
    one = base + "&motion label = 'law', law = 'table', times = 0, 1, values = 1, 1 /\n"
    with h5py.File(run_ok(tmp_path, one, "timed_one")) as f:
        mu = f["buckling/load_factor"][:]
    euler = [math.pi**2 * STRIP["E"] * i / (4 * STRIP["L"] ** 2)
             for i in (STRIP["I"], STRIP["Iy"])]
    assert mu == pytest.approx(euler, rel=1e-3)
    zero = base + ("&motion label = 'law', law = 'cubic', start = 0, end = 1, "
                   "duration = 1 /\n")
    proc, out = run_scene(tmp_path, zero, name="timed_zero")
    assert proc.returncode == 0, proc.stderr
    assert "time_law count at their value at t = 0" in proc.stderr
    with h5py.File(out) as f:
        assert f["buckling/load_factor"].shape == (0,)
