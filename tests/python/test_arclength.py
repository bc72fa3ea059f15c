"""Arc-length statics (&static method = 'arc_length') through limit points: the von Mises truss
against its closed-form path, the shallow arch example qualitatively, and bad inputs."""
import re

import h5py
import numpy as np
import pytest

from helpers import ROOT, assert_clean_error, run_scene


def path(out, node="apex"):
    with h5py.File(out) as f:
        return (f["static/load_factor"][:], f[f"static/nodes/{node}/position"][:, 1],
                f["static/stable"][:])


def test_von_mises_truss_follows_the_closed_form(tmp_path):
    """Every converged point lies on F(w) = -2 N (h - w)/l: the Newton tolerance (1e-10 m of
    the 1 m model) times the bar stiffness (2e7 N/m) bounds the force error by 2e-3 N
    (observed 4e-7 N); bound 1e-2 N of the 1e5 N load. The path passes the limit point (the
    largest load of the closed form, sampled by the steps), turns negative on the unstable
    branch and ends stable on the inverted side."""
    proc, out = run_scene(tmp_path, (ROOT / "input" / "von_mises_truss.nml").read_text())
    assert proc.returncode == 0, proc.stderr
    # The unstable branch is what arc-length is for: said as such, with no cure suggested.
    assert "static: the path passes unstable equilibria from load step" in proc.stderr
    assert "perturbation" not in proc.stderr
    lam, y, stable = path(out)
    a, h, ea, f0 = 1.0, 0.2, 2.0e11 * 1.0e-4, 1.0e5
    w = h - y
    l0, l = np.hypot(a, h), np.hypot(a, h - w)
    force = -2 * ea * (l - l0) / l0 * (h - w) / l
    assert np.max(np.abs(lam * f0 - force)) < 1e-2
    ws = np.linspace(0, h, 20001)
    ls = np.hypot(a, h - ws)
    limit = np.max(-2 * ea * (ls - l0) / l0 * (h - ws) / ls) / f0
    assert 0.95 * limit < lam.max() and lam[:np.argmax(w > h)].max() <= limit + 1e-9
    assert lam.min() < 0 and np.all(np.diff(w) > 0) and w[-1] > 2 * h
    assert stable[0] == 1 and stable[-1] == 1 and 0 in stable
    # Stable exactly where the load still rises with the deflection (one degree of freedom),
    # away from the two limit points where dF/dw changes sign.
    dfdw = np.gradient(force, w)
    clear = np.abs(dfdw) > 0.05 * np.max(np.abs(dfdw))
    assert np.all(stable[clear] == (dfdw[clear] > 0))


def test_shallow_arch_snaps_through(tmp_path):
    """The shallow arch example (4 elements per half here): the load rises to a limit point,
    falls to less than half of it while the apex keeps moving down, then rises again past it
    on the inverted side; the unstable branch is marked (it starts a little before the
    limit point: an antisymmetric mode of the arch goes unstable first)."""
    text = (ROOT / "input" / "shallow_arch.nml").read_text().replace(
        "n_elements = 8", "n_elements = 4").replace("7*'dynamic', 'elastic'",
        "3*'dynamic', 'elastic'").replace("14*'dynamic'", "6*'dynamic'")
    assert text.count("n_elements = 4") == 2
    proc, out = run_scene(tmp_path, text)
    assert proc.returncode == 0, proc.stderr
    lam, y, stable = path(out)
    k = int(np.argmax(np.diff(lam) < 0))  # the first step after which the load falls
    assert 0 < k < 20
    later = lam[k:]
    assert later.min() < 0.5 * lam[k] and later[-1] > lam[k]
    assert np.all(np.diff(y) < 0)
    assert stable[0] == 1 and stable[-1] == 1 and 0 in stable


BASE = (ROOT / "input" / "von_mises_truss.nml").read_text()


@pytest.mark.parametrize("old, new, fragments", [
    ("arc_length = 0.1", "arc_length = 0", ["&static", "'arc_length'", "positive"]),
    ("method = 'arc_length', n_steps = 40, arc_length = 0.1", "n_steps = 4, max_load_factor = 2",
     ["&static", "'max_load_factor'", "method = 'arc_length'"]),
    ("method = 'arc_length'", "method = 'riks'", ["&static", "'method'", "'riks'",
                                                   "load or arc_length"]),
    # No load: 0/0 in the first tangent (a floating-point trap in Debug, a misleading
    # 'tangent to the constraint' in Release, before the check).
    ("fy = -1.0e5", "fy = 0.0", ["&static", "'method'", "loads it scales are zero"]),
])
def test_bad_input(tmp_path, old, new, fragments):
    assert old in BASE
    proc, out = run_scene(tmp_path, BASE.replace(old, new))
    assert_clean_error(proc, out, *fragments)


def column(loads, static):
    """A 1 m cantilever column (8 elements, Euler load pi^2 EI / (4 L^2) = 493.5 N) under
    `loads` (a tip force, a slight transverse part to take the buckled branch), &static
    `static`, with its lowest two modes."""
    return f"""&node label = 'root', x = 0, y = 0, fixed = .true. /
&node label = 'tip', x = 1, y = 0 /
&link label = 'arm', from = 'root', to = 'tip', n_elements = 8,
      E = 2.0e11, A = 1.0e-4, I = 1.0e-9, rho = 7800 /
&force node = 'tip', {loads} /
&static {static} /
&modal n_modes = 2 /
&output nodes = 'tip' /
"""


def test_modes_at_the_end_of_a_path_that_stops_short(tmp_path):
    """A path stopped by max_load_factor at lambda ~ 0.36 of twice the Euler load: the modes
    are those of that equilibrium under its own loads, the same as after load steps to
    lambda times the loads. They were taken under the full loads (above critical) and came
    out unstable (-10 Hz instead of 5.0 Hz). Both runs reach the same equilibrium to the
    Newton tolerance (1e-10 of 1 m; tips 1.3e-11 m apart observed, bound 1e-8 m: 8 elements
    of 1e-10 with 10x) and difference the same tangent there; the frequency's sensitivity to
    the state is O(1) per metre of tip, so 1e-8 m of tip moves it by ~1e-8: bound 1e-6
    relative, far below the 2x error of the wrong load."""
    proc, out = run_scene(tmp_path, column("fx = -1000.0, fy = -1.0",
                                           "method = 'arc_length', n_steps = 40, "
                                           "max_load_factor = 0.35"), "arc")
    assert proc.returncode == 0, proc.stderr
    with h5py.File(out) as f:
        lam = float(f["static/load_factor"][-1])
        f_arc = f["modal/frequency_hz"][:]
        tip = f["static/nodes/tip/position"][-1]
    assert 0.35 <= lam < 0.5
    proc, out = run_scene(tmp_path, column(f"fx = {-1000.0 * lam!r}, fy = {-lam!r}",
                                           "n_steps = 10"), "load")
    assert proc.returncode == 0, proc.stderr
    with h5py.File(out) as f:
        f_load = f["modal/frequency_hz"][:]
        tip_load = f["static/nodes/tip/position"][-1]
    assert np.max(np.abs(tip - tip_load)) < 1e-8
    assert np.all(f_load > 0) and np.max(np.abs(f_arc / f_load - 1)) < 1e-6, (f_arc, f_load)


def test_dynamic_after_a_path_that_stops_short_warns(tmp_path):
    """&dynamic after an arc-length path that ends below load factor 1 starts from that
    equilibrium under the full loads: said in a warning (the run succeeds)."""
    text = column("fy = -1.0", "method = 'arc_length', n_steps = 3, max_load_factor = 0.5")
    proc, out = run_scene(tmp_path, text + "&dynamic t_end = 0.01 /\n")
    assert proc.returncode == 0, proc.stderr
    assert "arc-length path ends at load factor 0.66" in proc.stderr
    assert "&dynamic starts from that equilibrium under the full loads" in proc.stderr


@pytest.mark.parametrize("loads, static, fragments", [
    # A straight column loaded along its axis: the load exists but does no work on the
    # dynamic coordinates at the start; it was reported as 'no &force ... acts on them'.
    ("fx = -1000.0", "method = 'arc_length', n_steps = 5",
     ["&static", "'method'", "do no work on the dynamic coordinates", "perturbing load"]),
    # An arc a million times too long: no halving reaches kinematics that can be solved; it
    # ended on the bare 'kinematic Newton iteration did not converge'.
    ("fy = -1.0", "method = 'arc_length', n_steps = 3, arc_length = 1.0e6",
     ["static arc-length: no equilibrium found", "halvings", "smaller arc_length",
      "the last try: kinematic Newton"]),
])
def test_column_bad_paths(tmp_path, loads, static, fragments):
    proc, out = run_scene(tmp_path, column(loads, static))
    assert_clean_error(proc, out, *fragments)


def arch(solver):
    return (ROOT / "input" / "shallow_arch.nml").read_text().replace(
        "method = 'arc_length'", f"method = 'arc_length', solver = '{solver}'")


def test_krylov_path_equals_dense_through_limit_points(tmp_path):
    """The shallow arch (45 dynamic coordinates, elastic modes) through both limit points with
    the dense difference tangent and with Newton-Krylov (GMRES for both bordering solves):
    the same 40 stability flags and the same path. The points are placed by arc length in
    (q / c, lambda), and c = |K_T^-1 P| comes from each path's own tangent, whose difference
    error is about 1e-5 relative (theory.md 7.1), so equal steps land within about 1e-5 x lambda
    (lambda <= 0.6) of each other: observed 5.5e-6 in lambda and 4.9e-8 m at the apex (rise
    6 mm). Bounds 1e-4 and 1e-6 m. The stability tests cost at most 2 n = 90 products each
    (Arnoldi, then the formed matrix), 3,600 in all, and Newton's solves tens each (observed
    4,086 products in all): bound 15,000, where Arnoldi alone took 45,772."""
    res = {}
    for solver in ("dense", "krylov"):
        proc, out = run_scene(tmp_path, arch(solver), name=solver, quiet=False)
        assert proc.returncode == 0, proc.stderr
        assert ("Newton-Krylov" in proc.stdout) == (solver == "krylov")
        res[solver] = path(out)
    products = int(re.search(r"Newton-Krylov: (\d+) products", proc.stdout).group(1))
    assert products < 15000
    (lam_d, y_d, st_d), (lam_k, y_k, st_k) = res["dense"], res["krylov"]
    assert len(lam_d) == len(lam_k) == 40
    assert np.array_equal(st_d, st_k) and 0 in st_d
    assert np.max(np.abs(lam_d - lam_k)) < 1e-4
    assert np.max(np.abs(y_d - y_k)) < 1e-6


def leaf_guide(n, static):
    """input/leaf_spring_guide.nml with n elements per leaf (the last of leaf 2 elastic)."""
    text = (ROOT / "input" / "leaf_spring_guide.nml").read_text()
    text = text.replace("n_elements = 8", f"n_elements = {n}").replace(
        "elongation = 7*'dynamic', 'elastic', bending = 14*'dynamic', 2*'elastic'",
        f"elongation = {n - 1}*'dynamic', 'elastic', bending = {2 * n - 2}*'dynamic', "
        "2*'elastic'").replace(", compliance_nodes = 'shuttle'", "")
    return text.replace("&static n_steps = 11 /", static)


def test_large_compliant_path_is_on_the_krylov_path_and_in_equilibrium(tmp_path):
    """The leaf-spring guide with 32 elements per leaf (189 dynamic coordinates: `auto` takes
    Newton-Krylov above 40) along 6 arc-length steps. Each point must be the
    equilibrium at its own load factor: load control with the force scaled to that factor
    (2 Newton-Krylov load steps) reaches the same shuttle position. Both stop at tol 1e-10 of
    the model size (0.1 m); with GMRES's 1e-6 residual per correction the positions agree to
    about 1e-11 m (observed below 1e-12 m); bound 1e-9 m of the 5 mm stroke."""
    proc, out = run_scene(tmp_path, leaf_guide(32, "&static method = 'arc_length', n_steps = 6 /"),
                          name="arc", quiet=False)
    assert proc.returncode == 0, proc.stderr
    assert "Newton-Krylov" in proc.stdout
    lam, _, stable = path(out, "shuttle")
    with h5py.File(out) as f:
        x_arc = f["static/nodes/shuttle/position"][:, :2]
    assert len(lam) == 6 and np.all(np.diff(lam) > 0) and np.all(stable == 1)
    for k in (0, 5):
        text = leaf_guide(32, "&static n_steps = 2 /").replace(
            "fx = 2.2", f"fx = {float(2.2 * lam[k])!r}")
        proc, out_k = run_scene(tmp_path, text, name=f"load{k}")
        assert proc.returncode == 0, proc.stderr
        with h5py.File(out_k) as f:
            x_load = f["static/nodes/shuttle/position"][-1, :2]
        assert np.max(np.abs(x_load - x_arc[k])) < 1e-9, k


def pivot_arc(rotation, load):
    """input/cross_spring_pivot.nml (body turned by a prescribed angle) by arc-length, with
    a load on the body."""
    text = (ROOT / "input" / "cross_spring_pivot.nml").read_text().replace(
        "start = 0.3 /", f"start = {rotation!r} /").replace(
        "&static n_steps = 30 /", "&static method = 'arc_length', n_steps = 4 /")
    assert f"start = {rotation!r}" in text and "arc_length" in text
    return text + (f"&force node = 'body', {load} /\n" if load else "")


def test_arc_length_needs_loads_not_only_prescribed_inputs(tmp_path):
    """Displacement control alone (the pivot turned by its prescribed angle, no load): the
    arc-length scales loads only, so it is refused as having none (it used to take P's
    round-off for a load and fail 12 halvings later, advising a smaller arc)."""
    proc, out = run_scene(tmp_path, pivot_arc(0.3, ""))
    assert_clean_error(proc, out, "&static", "'method'", "loads it scales are zero")


def test_arc_length_start_too_far_from_the_reference_says_why(tmp_path):
    """The pivot turned by 0.3 rad at once: the equilibrium without loads, from which the path
    starts, is beyond Newton's reach from the reference; the message says so and points to
    load stepping, not to a bifurcation."""
    proc, out = run_scene(tmp_path, pivot_arc(0.3, "fx = 1.0"))
    assert_clean_error(proc, out, "arc-length start", "without loads",
                       "prescribed inputs at their full values", "method = 'load'")


def test_arc_length_starts_from_the_prescribed_equilibrium(tmp_path):
    """The pivot turned by 0.02 rad and pulled by fx = 1 N along 4 arc-length steps: each
    point is the equilibrium at its load factor with the rotation held, as load stepping to a
    force scaled to that factor finds it (2 steps, the rotation stepped with it). Both stop at
    tol 1e-10 of the model size (0.035 m): agreement to about 1e-12 m (observed 2e-18 m);
    bound 1e-9 m, against a body displaced 2e-6 m."""
    proc, out = run_scene(tmp_path, pivot_arc(0.02, "fx = 1.0"))
    assert proc.returncode == 0, proc.stderr
    lam, _, _ = path(out, "body")
    with h5py.File(out) as f:
        x_arc = f["static/nodes/body/position"][:, :2]
    assert len(lam) == 4 and np.all(np.diff(lam) > 0)
    for k in (0, 3):
        text = pivot_arc(0.02, f"fx = {float(lam[k])!r}").replace(
            "method = 'arc_length', n_steps = 4", "n_steps = 2")
        proc, out_k = run_scene(tmp_path, text, name=f"load{k}")
        assert proc.returncode == 0, proc.stderr
        with h5py.File(out_k) as f:
            x_load = f["static/nodes/body/position"][-1, :2]
        assert np.max(np.abs(x_load - x_arc[k])) < 1e-9, k
