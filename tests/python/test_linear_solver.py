"""&scene linear_solver: the sparse path (KLU, docs/theory.md 5.2) and the dense one give the same
trajectories to round-off through whole runs (full and reduced, implicit and explicit
integrators, elastic modes and a nodal degree of freedom), 'auto' resolves by size, and bad
values are refused with a clear message."""
import re
from pathlib import Path

import h5py
import numpy as np
import pytest

from helpers import assert_clean_error, run_scene

ROOT = Path(__file__).resolve().parents[2]


# Fixed steps and a tight Newton tolerance, so that both paths take the same steps and differ
# only by round-off and Newton's stopping point (an adaptive method's step sequences part ways
# at round-off and the paths then differ by the integration tolerance).
FIXED = "&dynamic t_end = {t_end}, output_dt = 1e-3, integrator = '{method}', dt = 2e-4, " \
    "rtol = 1e-9, atol = 1e-11 /"


def scene(name, solver, t_end=None, extra="", method=None):
    text = (ROOT / "input" / f"{name}.nml").read_text()
    if method is not None:
        fixed = FIXED.format(t_end=t_end, method=method)
        text = re.sub(r"&dynamic[^/]*/", fixed, text) if "&dynamic" in text else \
            text + fixed + "\n"
    if "&scene " in text:
        text = text.replace("&scene ", f"&scene linear_solver = '{solver}', ", 1)
    else:
        text = f"&scene linear_solver = '{solver}' /\n" + text
    if t_end is not None and method is None:
        text = re.sub(r"t_end = [0-9.eE+-]+", f"t_end = {t_end}", text, count=1)
    return text + extra


def run_both(tmp_path, name, **kw):
    out = {}
    for solver in ("dense", "sparse"):
        (tmp_path / solver).mkdir()
        proc, path = run_scene(tmp_path / solver, scene(name, solver, **kw), name=name)
        assert proc.returncode == 0, proc.stderr
        with h5py.File(path) as f:
            assert f.attrs["linear_solver"] == solver
            # Every Newton matrix factorised is counted: at least the first, at most one per
            # step besides those after Jacobian refreshes.
            assert 1 <= f.attrs["n_factorisations"] <= f.attrs["n_steps"] + \
                f.attrs["n_jac_evals"]
            out[solver] = (f["x"][:], f["time"][:])
    return out


@pytest.mark.parametrize("name,t_end,extra,bound", [
    # Generalized-alpha, fixed step, Newton to 1e-10 of rtol-weighted size: observed
    # differences 3e-14 to 9e-12 m over the four cases (the sparse path refactors its Newton
    # matrix where steps end, so its iterations stop elsewhere within that tolerance); bound
    # 1e-9 m.
    ("two_link", 0.1, "", 1e-9),
    # A reduced model (2 modes).
    ("two_link", 0.1, "&reduction n_modes = 2 /\n", 1e-9),
    # A nodal degree of freedom (the slider) and released hinges.
    ("slider_crank", 0.05, "", 1e-9),
    # Elastic modes (statically indeterminate) under a load.
    ("leaf_spring_guide", 0.02, "", 1e-9),
])
def test_sparse_equals_dense(tmp_path, name, t_end, extra, bound):
    out = run_both(tmp_path, name, t_end=t_end, extra=extra, method="galpha")
    (xd, td), (xs, ts) = out["dense"], out["sparse"]
    assert np.array_equal(td, ts)
    assert np.max(np.abs(xs - xd)) <= bound


def test_auto_resolves_by_size(tmp_path):
    small = (ROOT / "input" / "two_link.nml").read_text().replace(
        "n_elements = 3", "n_elements = 1").replace("&modal n_modes = 12 /", "")
    (tmp_path / "small").mkdir()
    (tmp_path / "big").mkdir()
    proc, path = run_scene(tmp_path / "small", re.sub(r"t_end = [0-9.]+", "t_end = 0.001", small))
    assert proc.returncode == 0, proc.stderr
    with h5py.File(path) as f:
        assert f.attrs["linear_solver"] == "dense"      # 9 coordinates
    big = small.replace("n_elements = 1", "n_elements = 16")
    proc, path = run_scene(tmp_path / "big", re.sub(r"t_end = [0-9.]+", "t_end = 0.001", big))
    assert proc.returncode == 0, proc.stderr
    with h5py.File(path) as f:
        assert f.attrs["linear_solver"] == "sparse"     # 99 coordinates


def test_bad_value_is_refused(tmp_path):
    proc, out = run_scene(tmp_path, scene("two_link", "klu"))
    assert_clean_error(proc, out, "&scene", "linear_solver", "klu", "auto", "dense", "sparse")
