"""Newton-Krylov statics (&static solver = 'krylov', docs/theory.md 7.3) against the dense
difference tangent (solver = 'dense'): the same equilibria and stability verdicts on spatial,
compliant (elastic modes) and non-conservative (moments fixed in space) scenes, a column past its
Euler load on both of Krylov's stability paths (formed matrix and Arnoldi), and the input
errors; scripts/bench_statics.py on small meshes."""
import csv
import os
import subprocess
import sys

import h5py
import numpy as np
import pytest

from helpers import BIN, ROOT, assert_clean_error, load_driver, run_scene


def with_static(text, extra):
    assert "&static " in text
    return text.replace("&static ", f"&static {extra}, ", 1)


def static_result(tmp_path, text, name):
    proc, out = run_scene(tmp_path, text, name=name, quiet=False)
    assert proc.returncode == 0, proc.stderr
    with h5py.File(out) as f:
        return f["static/x"][:], f["static/stable"][:], proc.stdout


@pytest.mark.parametrize("example", ["bend45", "leaf_spring_guide", "cross_spring_pivot",
                                     "roll_up"])
def test_krylov_equals_dense(tmp_path, example):
    """Both solvers at tol = 1e-13 reach the same nodal coordinates at every load step (observed
    up to 1.4e-12 of the largest coordinate, leaf spring guide; 4e-13 for the bend) and the same
    stability flags. Bound 1e-9 of the largest coordinate: far above where both stop (1e-13
    of the model size) and far below what a different equilibrium would give (a missing load
    term moves the bend's tip by metres). The roll-up (16 steps to a full turn by an end
    moment fixed in space) has an unsymmetric tangent; the leaf spring and the cross-spring
    pivot have elastic modes (stiffness through the kinematics)."""
    text = (ROOT / "input" / f"{example}.nml").read_text()
    x = {}
    for solver in ("dense", "krylov"):
        x[solver], stable, said = static_result(
            tmp_path, with_static(text, f"solver = '{solver}', tol = 1e-13"), solver)
        x[solver + "_stable"] = stable
        assert ("Newton-Krylov" in said) == (solver == "krylov")
    size = np.max(np.abs(x["dense"]))
    assert np.max(np.abs(x["dense"] - x["krylov"])) <= 1e-9 * size
    assert np.array_equal(x["dense_stable"], x["krylov_stable"])


def column(n_elements, solver):
    """A planar steel cantilever column, 1 m, EI = 2100 N m^2, rigid in elongation, under an
    axial tip load raised to twice its Euler load pi^2 EI / (4 L^2) = 5181.6 N in 5 steps."""
    return ("&scene title = 'column' /\n"
            "&node label = 'base', x = 0, y = 0, fixed = .true. /\n"
            "&node label = 'tip', x = 0, y = 1 /\n"
            f"&link label = 'col', from = 'base', to = 'tip', n_elements = {n_elements}, "
            "E = 2.1e11, A = 1.0e-4, I = 1.0e-8, rho = 7800, elongation = 'rigid' /\n"
            "&force node = 'tip', fy = -10363.3 /\n"
            f"&static n_steps = 5, solver = '{solver}' /\n"
            "&output nodes = 'tip' /\n")


@pytest.mark.parametrize("n_elements", [10, 20])
def test_column_past_its_euler_load(tmp_path, n_elements):
    """At 0.4, 0.8, 1.2, 1.6 and 2 times the Euler load the straight column is in equilibrium,
    stable below the Euler load and unstable above (the second critical load is 9 times the
    first): flags 1, 1, 0, 0, 0 on both paths. With 10 elements (20 coordinates) Krylov's test
    forms P^-1 K_T, with 20 it runs Arnoldi. The column stays straight (tip x below 1e-9 m)."""
    for solver in ("dense", "krylov"):
        _, stable, _ = static_result(tmp_path, column(n_elements, solver), solver)
        assert stable.tolist() == [1, 1, 0, 0, 0], solver
        with h5py.File(tmp_path / f"{solver}.h5") as f:
            assert np.max(np.abs(f["static/nodes/tip/position"][:, 0])) < 1e-9


@pytest.mark.parametrize("text,fragments", [
    (column(10, "krylov").replace("&scene title = 'column' /",
                                  "&scene title = 'column', linear_solver = 'dense' /"),
     ["&static", "'solver'", "'krylov'", "sparse path"]),
    (column(10, "newton"), ["&static", "'solver'", "'newton'"]),
])
def test_krylov_input_errors(tmp_path, text, fragments):
    proc, out = run_scene(tmp_path, text)
    assert_clean_error(proc, out, *fragments)


def run_bench(*args):
    env = dict(os.environ, PYTHONPATH=str(ROOT / "python"))
    return subprocess.run([sys.executable, str(ROOT / "scripts" / "bench_statics.py"),
                           *map(str, args)], capture_output=True, text=True, timeout=300,
                          env=env)


def test_bench_statics_quick(tmp_path):
    """scripts/bench_statics.py on two small meshes writes its table and CSV: both solvers at
    each mesh, the Krylov rows with their products, the same tip from both solvers (the 4-beam
    dense run within 1e-6 m of the 4-beam Krylov one; the tips are 60 m from the start)."""
    proc = run_bench("--bin", BIN, "--meshes", "2,4", "--repeat", "1", "--guide-meshes", "4",
                     "--out-dir", tmp_path)
    assert proc.returncode == 0, proc.stderr
    text = (tmp_path / "statics.md").read_text()
    assert "| 4 | 24 | krylov |" in text and "| 2 | 12 | dense |" in text
    # The guide on both paths: the same compliance (both extrapolated, about 1e-7 apart).
    with open(tmp_path / "statics_guide.csv") as f:
        guide = list(csv.DictReader(f))
    assert [(r["elements"], r["solver"]) for r in guide] == [("4", "dense"), ("4", "krylov")]
    assert abs(float(guide[1]["cxx"]) / float(guide[0]["cxx"]) - 1) < 1e-5
    with open(tmp_path / "statics.csv") as f:
        rows = list(csv.DictReader(f))
    assert [(r["beams"], r["solver"]) for r in rows] == [
        ("2", "dense"), ("2", "krylov"), ("4", "dense"), ("4", "krylov")]
    assert int(rows[3]["products"]) > 0 and int(rows[2]["products"]) == 0
    assert float(rows[2]["tip_diff_m"]) < 1e-6


@pytest.mark.parametrize("args", [["--meshes", "2,x"], ["--repeat", "0"], ["--guide-meshes", "1"],
                                  ["--bin", "/nonexistent/flexmor"]])
def test_bench_statics_bad_arguments(tmp_path, args):
    proc = run_bench(*args, "--out-dir", tmp_path)
    assert proc.returncode == 2 and "error" in proc.stderr


@pytest.mark.parametrize("n_beams", [32, 64])
def test_krylov_buckling_equals_dense(tmp_path, n_beams):
    """The narrow cantilever's lateral-torsional buckling (scripts/spatial_examples.py's scene,
    2 multipliers) by the dense eigenproblem and matrix-free: the multipliers agree to 6e-7
    and 3e-6 relative at 32 and 64 beams (observed), the shapes (unit largest translation) to
    2e-8. Bounds 5e-5 and 1e-6: both difference the load part with steps that move the chain
    by 6e-6 of its size, whose kinematic noise (1e-11 m against the step) is about 1e-5 of the
    load stiffness. An operator that differenced along the largest component instead of the
    whole chain's motion was 1.5e-4 off at 32 beams and 1.7e-3 at 64. /buckling's n_negative
    is -1 on the matrix-free path (not counted)."""
    text = load_driver(ROOT / "scripts" / "spatial_examples.py").lateral_buckling_scene(n_beams)
    res = {}
    for solver in ("dense", "krylov"):
        proc, out = run_scene(tmp_path, text.replace("&buckling ",
                                                     f"&buckling solver = '{solver}', "),
                              name=solver)
        assert proc.returncode == 0, proc.stderr
        with h5py.File(out) as f:
            res[solver] = (f["buckling/load_factor"][:], f["buckling/shapes"][:],
                           int(f["buckling"].attrs["n_negative"]))
    (mu_d, v_d, neg_d), (mu_k, v_k, neg_k) = res["dense"], res["krylov"]
    assert len(mu_d) == len(mu_k) == 2
    assert np.max(np.abs(mu_k / mu_d - 1)) < 5e-5
    assert np.max(np.abs(v_k - v_d)) < 1e-6
    assert neg_d > 0 and neg_k == -1


def test_krylov_buckling_needs_a_model_it_applies_to(tmp_path):
    """A model with elastic modes (the leaf-spring guide) cannot take the matrix-free buckling:
    the error names why; 'auto' takes the dense path there."""
    text = (ROOT / "input" / "leaf_spring_guide.nml").read_text() + \
        "&buckling solver = 'krylov' /\n"
    proc, out = run_scene(tmp_path, text)
    assert_clean_error(proc, out, "&buckling", "'solver'", "elastic (calculable) modes")


@pytest.mark.parametrize("solver", ["dense", "krylov"])
def test_load_step_beyond_reach_says_where(tmp_path, solver):
    """A 1 m cantilever under a tip force whose linear deflection is 170 m, in one step: the
    first Newton correction leaves the reach of the structure and its kinematics cannot be
    solved. The error named neither the static analysis nor the step ('kinematic Newton
    iteration did not converge'); now it does, with the cure."""
    text = """&scene linear_solver = 'sparse' /
&node label = 'root', x = 0, y = 0, fixed = .true. /
&node label = 'tip', x = 1, y = 0 /
&link label = 'arm', from = 'root', to = 'tip', n_elements = 8,
      E = 2.0e11, A = 1.0e-4, I = 1.0e-9, rho = 7800 /
&force node = 'tip', fy = -1.0e5 /
&static n_steps = 1, solver = '""" + solver + """' /
"""
    proc, out = run_scene(tmp_path, text)
    assert_clean_error(proc, out, "static analysis, load step 1 of 1 (load factor 1",
                       "more n_steps")


def compliance_of(tmp_path, text, node, name):
    proc, out = run_scene(tmp_path, text, name=name)
    assert proc.returncode == 0, proc.stderr
    with h5py.File(out) as f:
        return f[f"static/nodes/{node}/compliance"][:]


@pytest.mark.parametrize("example,node", [("leaf_spring_guide", "shuttle"),
                                          ("cross_spring_pivot", "body")])
def test_krylov_compliance_equals_dense(tmp_path, example, node):
    """Compliances at every load step from GMRES on extrapolated products (relative residual
    1e-10) and from the dense extrapolated tangent: both O(h^4) in the difference step, so
    they agree to about 1e-7 of the largest entry (observed 1.6e-7 for the guide, whose leaves'
    tension is 1e4 times stiffer than its stroke, 8e-10 for the pivot); bound 1e-5."""
    text = (ROOT / "input" / f"{example}.nml").read_text()
    c = {s: compliance_of(tmp_path, with_static(text, f"solver = '{s}'"), node, s)
         for s in ("dense", "krylov")}
    for k in range(len(c["dense"])):
        size = np.max(np.abs(c["dense"][k]))
        assert np.max(np.abs(c["krylov"][k] - c["dense"][k])) < 1e-5 * size, k


def test_krylov_spatial_compliance_is_the_derivative_of_the_static_solution(tmp_path):
    """The spatial cross-spring pivot (90 coordinates, 6 components per node) on the Krylov
    path against central differences of the static solution: its fy column with fy = +-0.01 N
    (difference error O(d^2 C'') and Newton's 1e-14 m / d: below 1e-8 of the column; observed
    2e-12) and its rotational compliance about z with mz = +-1e-5 N m (the rotation from the
    Euler parameters, 2 atan(l3 / l0); error about 1e-9 relative; observed 1e-8 -- the
    dense difference tangent was 1.7e-4 off there with the products' step); bounds
    1e-6 of the column's largest entry and 1e-5 relative."""
    text = (ROOT / "input" / "cross_spring_pivot_spatial.nml").read_text().replace(
        "&modal n_modes = 6 /", "")
    c = compliance_of(tmp_path, with_static(text, "solver = 'krylov'"), "body", "c")[-1]

    def body(extra, name):
        mod = with_static(text, "solver = 'krylov', tol = 1e-14").replace(
            "fz = 0.1 /", f"fz = 0.1, {extra} /")
        proc, out = run_scene(tmp_path, mod, name=name)
        assert proc.returncode == 0, proc.stderr
        with h5py.File(out) as f:
            lam = f["static/nodes/body/orientation"][-1]
            return f["static/nodes/body/position"][-1], 2 * np.arctan2(lam[3], lam[0])

    (p_plus, _), (p_minus, _) = body("fy = 0.01", "fyp"), body("fy = -0.01", "fym")
    col = (p_plus - p_minus) / 0.02
    assert np.max(np.abs(col - c[:3, 1])) < 1e-6 * np.max(np.abs(c[:3, 1]))
    (_, th_plus), (_, th_minus) = body("mz = 1e-05", "mzp"), body("mz = -1e-05", "mzm")
    assert abs((th_plus - th_minus) / 2e-5 / c[5, 5] - 1) < 1e-5


def guide_modes(tmp_path, n, modal):
    """The leaf-spring guide with n elements per leaf, 4 load steps to its 2.2 N, then
    &modal: the lowest 4 frequencies and the eigensolver that ran."""
    text = (ROOT / "input" / "leaf_spring_guide.nml").read_text()
    text = text.replace("n_elements = 8", f"n_elements = {n}").replace(
        "elongation = 7*'dynamic', 'elastic', bending = 14*'dynamic', 2*'elastic'",
        f"elongation = {n - 1}*'dynamic', 'elastic', bending = {2 * n - 2}*'dynamic', "
        "2*'elastic'").replace(", compliance_nodes = 'shuttle'", "").replace(
        "&static n_steps = 11 /", f"&static n_steps = 4 /\n&modal n_modes = 4{modal} /")
    proc, out = run_scene(tmp_path, text, name=f"m{n}{len(modal)}")
    assert proc.returncode == 0, proc.stderr
    with h5py.File(out) as f:
        return f["modal/frequency_hz"][:], f["modal"].attrs["eigensolver"]


def test_krylov_modes_of_a_model_with_elastic_modes(tmp_path):
    """Modes of the loaded leaf-spring guide (elastic modes close its loop) on the Krylov path,
    the whole tangent differenced and extrapolated: at 8 elements per leaf the dense path's
    frequencies to 1e-7 (observed 8e-8; both O(h^4)); bound 1e-5. At 32 per leaf `auto` takes
    Krylov, and the first (stroke) mode converges with the mesh: 8e-6 from the 8-element one
    (the higher ones, bending waves in the leaves, 1e-4 to 7e-4); bound 1e-4."""
    f_dense, s_dense = guide_modes(tmp_path, 8, ", solver = 'lapack'")
    f_kry, s_kry = guide_modes(tmp_path, 8, ", solver = 'krylov'")
    assert (s_dense, s_kry) == ("lapack", "krylov")
    assert np.max(np.abs(f_kry / f_dense - 1)) < 1e-5
    f_fine, s_fine = guide_modes(tmp_path, 32, "")
    assert s_fine == "krylov"
    assert abs(f_fine[0] / f_kry[0] - 1) < 1e-4


def test_dense_tangent_of_a_fine_compliant_mesh(tmp_path):
    """The dense path's column differences with elastic modes take a tenth of the products'
    step: at 64 elements per leaf the guide's four lowest frequencies from LAPACK on the dense
    tangent match the Krylov path's to 4e-6 (observed; both differences, O(h^4)). With the
    products' step the first was 2.7 % off (12.016 Hz for 11.6949 Hz). Bound 1e-4."""
    f_dense, s_dense = guide_modes(tmp_path, 64, ", solver = 'lapack'")
    f_kry, s_kry = guide_modes(tmp_path, 64, ", solver = 'krylov'")
    assert (s_dense, s_kry) == ("lapack", "krylov")
    assert np.max(np.abs(f_dense / f_kry - 1)) < 1e-4


def static_frequencies(tmp_path, case, solver):
    """/static/frequency_hz and /static/stable of the leaf-spring guide at 16 elements per leaf
    (4 load steps) or of the 20-element column past its Euler load, on the given path."""
    if case == "guide":
        text = (ROOT / "input" / "leaf_spring_guide.nml").read_text().replace(
            "n_elements = 8", "n_elements = 16").replace(
            "elongation = 7*'dynamic', 'elastic', bending = 14*'dynamic', 2*'elastic'",
            "elongation = 15*'dynamic', 'elastic', bending = 30*'dynamic', 2*'elastic'").replace(
            ", compliance_nodes = 'shuttle'", "").replace(
            "&static n_steps = 11 /",
            f"&static n_steps = 4, n_frequencies = 3, solver = '{solver}' /")
    else:
        text = column(20, solver).replace("&static n_steps = 5,",
                                          "&static n_steps = 5, n_frequencies = 3,")
    assert "n_frequencies = 3" in text
    proc, out = run_scene(tmp_path, text, name=f"{case}_{solver}")
    assert proc.returncode == 0, proc.stderr
    with h5py.File(out) as f:
        return f["static/frequency_hz"][:], f["static/stable"][:]


@pytest.mark.parametrize("case", ["guide", "column"])
def test_krylov_static_frequencies_equal_dense(tmp_path, case):
    """`&static n_frequencies` on the Krylov path: stable steps by the sparse shift-invert
    Lanczos (no dense tangent), unstable ones by the dense tangent, as the dense path gives
    them all. The leaf-spring guide at 16 elements per leaf (93 coordinates, elastic modes) and
    the column past its Euler load (flags 1, 1, 0, 0, 0: negative frequencies from step 3):
    observed 1.2e-7 and 6e-8 relative (both tangents O(h^4)); bound 1e-5."""
    f_d, s_d = static_frequencies(tmp_path, case, "dense")
    f_k, s_k = static_frequencies(tmp_path, case, "krylov")
    assert np.array_equal(s_d, s_k)
    if case == "column":
        assert s_d.tolist() == [1, 1, 0, 0, 0] and np.all(f_d[2:, 0] < 0)
    assert np.max(np.abs(f_k / f_d - 1)) < 1e-5
