"""flexmor-plot-reduction (flexmor.plot_reduction): the data it plots on synthetic files whose
true error is known, its errors, and a real expanded run against the full model."""
import os
import subprocess
import sys

import h5py
import numpy as np
import pytest

from flexmor import plot_reduction
from flexmor.results import read_result
from helpers import BIN, ROOT, run_scene

OFFSET_RATE = 2.0e-3   # m/s: the reference's tip moves away from the reduced one's in x


def write(path, t, reduction=True, labels=("tip", "elbow"), offset=0.0):
    """A result whose nodes move linearly in time (so that interpolation is exact), the
    reference's ahead by offset * t in x; with reduction, an expanded run's /reduction."""
    with h5py.File(path, "w") as f:
        f.attrs["flexmor_version"] = "0.6.0"
        f["time"] = t
        for k, label in enumerate(labels):
            pos = np.column_stack([(k + 1) * t + offset * t, 0.5 * t, np.zeros_like(t)])
            f[f"nodes/{label}/position"] = pos
        if reduction:
            g = f.create_group("reduction")
            g["residual"] = 1.0 + t
            g["error_estimate"] = 1e-3 * (1.0 + t)
            g["measured/time"] = np.array([0.0, 0.5, 1.0, 0.75])
            g["measured/kind"] = np.array([1, 3, 3, 2], dtype=np.int32)
            g["measured/residual"] = np.array([1.0, 1.5, 2.0, 1.7])
            g["measured/error_estimate"] = np.array([1e-3, 1.5e-3, 2e-3, 1.7e-3])
            g["checks/time"] = np.array([0.25, 0.5])
            g["checks/updated"] = np.array([0, 1], dtype=np.int32)
            g.attrs["n_modes"] = np.int32(4)
            g.attrs["evaluation"] = "expanded"
            g.attrs["n_expansions"] = np.int32(1)
            g.attrs["error_estimate_max"] = 2e-3


def run_cli(*args, cwd):
    """The command in folder cwd, the package from this working tree (as the other tests)."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(ROOT / "python"), os.environ.get("PYTHONPATH", "")]))
    return subprocess.run([sys.executable, "-m", "flexmor.plot_reduction", *map(str, args)],
                          capture_output=True, text=True, timeout=120, cwd=cwd, env=env)


def test_true_error_and_measurements(tmp_path):
    t = np.linspace(0.0, 1.0, 11)
    write(tmp_path / "red.h5", t)
    write(tmp_path / "ref.h5", np.linspace(0.0, 1.0, 101), reduction=False,
          offset=OFFSET_RATE)
    data = plot_reduction.reduction_errors(read_result(tmp_path / "red.h5"),
                                           read_result(tmp_path / "ref.h5"))
    assert data["nodes"] == ["elbow", "tip"]
    np.testing.assert_allclose(data["true"], OFFSET_RATE * t, rtol=0, atol=1e-15)
    assert list(data["measured"]["kind"]) == [1, 3, 3, 2]
    np.testing.assert_array_equal(data["updates"], [0.5])   # the replaced basis only
    only_tip = plot_reduction.reduction_errors(read_result(tmp_path / "red.h5"),
                                               read_result(tmp_path / "ref.h5"), ["tip"])
    assert only_tip["nodes"] == ["tip"]
    proc = run_cli(tmp_path / "red.h5", "--reference", tmp_path / "ref.h5", "-o", "r.png",
                   cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "r.png").stat().st_size > 0
    assert "estimate up to 0.002 m, distance from the reference up to 0.002 m" in proc.stdout
    # Without a reference: the estimate and the measurements alone.
    proc = run_cli(tmp_path / "red.h5", "-o", "alone.png", cwd=tmp_path)
    assert proc.returncode == 0 and (tmp_path / "alone.png").is_file(), proc.stderr


@pytest.mark.parametrize("case, fragment", [
    ("no_reduction", "not a reduced run"),
    ("no_shared_node", "share no output node"),
    ("unknown_node", "node(s) base not in both files"),
    ("short_reference", "do not cover"),
    ("missing", "missing.h5"),
])
def test_clean_errors(tmp_path, case, fragment):
    t = np.linspace(0.0, 1.0, 11)
    write(tmp_path / "red.h5", t)
    write(tmp_path / "ref.h5", t, reduction=False,
          labels=("other",) if case == "no_shared_node" else ("tip",))
    if case == "short_reference":
        write(tmp_path / "ref.h5", np.linspace(0.0, 0.5, 6), reduction=False)
    args = {"no_reduction": ["ref.h5"], "no_shared_node": ["red.h5", "--reference", "ref.h5"],
            "unknown_node": ["red.h5", "--reference", "ref.h5", "--node", "base"],
            "short_reference": ["red.h5", "--reference", "ref.h5"],
            "missing": ["missing.h5"]}[case]
    proc = run_cli(*args, cwd=tmp_path)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("flexmor-plot-reduction: error: "), proc.stderr
    assert fragment in lines[0], lines[0]
    assert not list(tmp_path.glob("*.png"))


def test_node_needs_a_reference(tmp_path):
    write(tmp_path / "red.h5", np.linspace(0.0, 1.0, 11))
    proc = run_cli("red.h5", "--node", "tip", cwd=tmp_path)
    assert proc.returncode == 2 and "--node needs --reference" in proc.stderr


@pytest.mark.skipif(not BIN.is_file(), reason="flexmor binary not built")
def test_spin_up_against_the_full_model(tmp_path):
    """input/spin_up.nml with 3 modes, expanded, against the full model: the plotted estimate
    is the run's, every kind of measurement is there, and the true error is of the estimate's
    size (the estimate is the quasi-static response of the dropped modes, not a bound):
    2.31e-4 m against 2.29e-4 m observed, a ratio within 0.1 to 10 required."""
    spin = (ROOT / "input" / "spin_up.nml").read_text()
    proc, full = run_scene(tmp_path, spin, "full")
    assert proc.returncode == 0, proc.stderr
    proc, red = run_scene(tmp_path, spin + "&reduction n_modes = 3, evaluation = 'expanded' /\n",
                          "red")
    assert proc.returncode == 0, proc.stderr
    data = plot_reduction.reduction_errors(read_result(red), read_result(full))
    with h5py.File(red) as f:
        assert np.max(data["estimate"]) == pytest.approx(
            f["reduction"].attrs["error_estimate_max"], rel=1e-12)
    assert set(data["measured"]["kind"]) == {1, 2, 3}
    ratio = np.max(data["true"]) / np.max(data["estimate"])
    assert 0.1 < ratio < 10, ratio
    proc = run_cli(red, "--reference", full, "-o", "spin.png", cwd=tmp_path)
    assert proc.returncode == 0 and (tmp_path / "spin.png").is_file(), proc.stderr
