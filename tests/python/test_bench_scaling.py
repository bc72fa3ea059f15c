"""scripts/bench_scaling.py: the scene it builds, the exponent fit, bad arguments, and a --quick
run with the real flexmor (Exudyn left out, so that the test does not depend on it)."""
import csv
import math
import subprocess
import sys

import pytest

from helpers import BIN, ROOT, load_driver

SCRIPT = ROOT / "scripts" / "bench_scaling.py"
bsc = load_driver(SCRIPT)


def run_script(*args, timeout=600):
    return subprocess.run([sys.executable, str(SCRIPT), *map(str, args)], capture_output=True,
                          text=True, timeout=timeout)


def test_scene_has_the_mesh_the_integrator_and_the_reduction():
    text = bsc.scene(16, "integrator = 'galpha', dt = 0.0001", k=4, t_end=0.05)
    assert text.count("n_elements = 16") == 2 and "n_elements = 3" not in text
    assert "&dynamic t_end = 0.05, output_dt = 0.001, integrator = 'galpha', dt = 0.0001 /" in text
    assert "&modal" not in text and "&reduction n_modes = 4 /" in text
    text = bsc.scene(3, "", k=4, expanded=True)
    assert "&reduction n_modes = 4, evaluation = 'expanded' /" in text
    assert "&dynamic t_end = 0.7" in text    # the scene's own analysis


def test_exponent_of_a_power_law_over_8_to_128():
    ns = [2, 4, 8, 16, 32, 64, 128]
    # Below 8 the points do not count: a different law there must not change the fit.
    times = [1.0, 1.0] + [3e-3 * n**1.5 for n in ns[2:]]
    assert math.isclose(bsc.fit_exponent(ns, times), 1.5, rel_tol=1e-12)
    assert math.isnan(bsc.fit_exponent([2, 4], [1.0, 2.0]))


def test_bad_arguments_exit_2(tmp_path):
    proc = run_script("--bin", BIN, "--meshes", "2,x", "--out-dir", tmp_path)
    assert proc.returncode == 2 and "--meshes" in proc.stderr
    proc = run_script("--bin", tmp_path / "nope", "--out-dir", tmp_path)
    assert proc.returncode == 2 and "no flexmor binary" in proc.stderr


@pytest.mark.skipif(not BIN.is_file(), reason="flexmor binary not built")
def test_quick_run_writes_tables_and_plot(tmp_path):
    proc = run_script("--bin", BIN, "--out-dir", tmp_path, "--quick", "--no-exudyn")
    assert proc.returncode == 0, proc.stderr
    with open(tmp_path / "scaling.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert [int(r["elements_per_link"]) for r in rows] == [2, 4]
    # Finite, not positive: at --quick's 40-step runs the difference of two timings can fall
    # below a busy machine's noise.
    for r in rows:
        for key in ("full_ms", "k2_ms", "k4_ms", "k4x_ms"):
            assert math.isfinite(float(r[key]))
    # 2 beams per link with bending dynamic: 2 x 2 x 2 modes.
    assert [int(r["n_dy"]) for r in rows] == [8, 16]
    text = (tmp_path / "scaling.md").read_text()
    assert "| 2 | 8 |" in text and "commit" in text
    assert (tmp_path / "scaling.png").stat().st_size > 5_000


@pytest.mark.skipif(not BIN.is_file(), reason="flexmor binary not built")
def test_quick_whole_runs(tmp_path):
    proc = run_script("--bin", BIN, "--out-dir", tmp_path, "--quick", "--no-exudyn",
                      "--whole-runs")
    assert proc.returncode == 0, proc.stderr
    with open(tmp_path / "whole_runs.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert [int(r["elements_per_link"]) for r in rows] == [2]
    r = rows[0]
    assert int(r["n_expansions"]) >= 1 and int(r["k4x_steps"]) > 0
    # Over the first 0.02 s the dropped modes barely respond (observed 5e-8 m for both).
    assert float(r["k4_tip_m"]) < 1e-5 and float(r["k4x_tip_m"]) < 1e-5
    assert "| 2 |" in (tmp_path / "whole_runs.md").read_text()
