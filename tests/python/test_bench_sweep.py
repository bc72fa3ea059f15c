"""scripts/bench_sweep.py: the pure helpers (sweep text, rank list, load balance, probe and
projection arithmetic), the error paths, and a --quick run with the real flexmor-sweep
(FLEXMOR_SWEEP_BIN from the environment; skipped where it is not set or does not exist)."""
import csv
import math
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from helpers import ROOT, load_driver

SCRIPTS = ROOT / "scripts"
SCRIPT = SCRIPTS / "bench_sweep.py"


bs = load_driver(SCRIPT)

SWEEP_BIN = os.environ.get("FLEXMOR_SWEEP_BIN", "")
LAUNCHER = os.environ.get("MPIEXEC") or shutil.which("mpirun") or shutil.which("mpiexec")


def run_script(*args, timeout=120):
    return subprocess.run([sys.executable, str(SCRIPT), *map(str, args)], capture_output=True,
                          text=True, timeout=timeout)


# --- helpers ----------------------------------------------------------------------------------


def test_sweep_text_has_the_parameters_and_tied_names():
    text = bs.reduced_sweep_text(bs.REDUCED_PARAMETERS)
    assert "&sweep base = 'base.nml', mode = 'product'" in text
    assert "&parameter name = 'reduction.n_modes', values = 1, 2, 3, 4 /" in text
    assert "name = 'motion.phi1.duration', 'motion.phi2.duration', values = 0.3, 0.4, 0.5" in text
    assert "values = 0.0001, 1e-06, 1e-08" in text
    assert bs.n_product(bs.REDUCED_PARAMETERS) == 108
    assert bs.n_product(bs.QUICK_PARAMETERS) == 4
    assert "n = 7 /" in bs.probe_sweep_text(7)


def test_parse_ranks():
    assert bs.parse_ranks("4, 1,2,2") == [1, 2, 4]
    for bad, match in (("2,3", "must include 1"), ("0,1", "at least 1"), ("1,x", "integers"),
                       ("", "at least 1")):
        with pytest.raises(bs.UserError, match=match):
            bs.parse_ranks(bad)


def test_workers_and_subscription():
    assert [bs.workers_of(n) for n in (1, 2, 3, 64)] == [1, 1, 2, 63]
    assert bs.worker_ranks(1) == [0] and bs.worker_ranks(4) == [1, 2, 3]
    assert [bs.subscription(n, 2) for n in (1, 2, 3, 4)] == ["no", "no", "rank0", "workers"]


def make_run(ranks, wall, times, owners):
    run = bs.Run("w", ranks, 0, wall=wall)
    run.case_time = np.asarray(times, dtype=float)
    run.case_rank = np.asarray(owners)
    return run


def test_median_run_and_load_balance_with_an_idle_worker():
    runs = [make_run(4, w, [1.0, 2.0, 3.0], [1, 1, 2]) for w in (5.0, 3.0, 4.0)]
    assert bs.median_run(runs).wall == 4.0
    assert bs.median_run(runs[:2]).wall == 3.0          # even count: the lower middle
    balance = bs.load_balance(runs[0])
    assert balance == {1: (2, 3.0), 2: (1, 3.0), 3: (0, 0.0)}
    point = bs.summarize(bs.Workload("w", "", Path("x"), 3, 3), runs, [4], cores=2)[0]
    assert point.idle == [3] and point.wall == 4.0 and point.case_sum == 6.0
    assert math.isclose(point.overhead, 4.0 - 6.0 / 3)
    assert math.isclose(point.imbalance, 3.0 / 2.0)
    failed = bs.Run("w", 1, 0, status="failed")
    with pytest.raises(ValueError):
        bs.median_run([failed])


def test_summarize_speedups_and_efficiencies():
    load = bs.Workload("w", "", Path("x"), 4, 1)
    runs = [make_run(1, 8.0, [2.0] * 4, [0] * 4), make_run(3, 5.0, [2.0] * 4, [1, 2, 1, 2]),
            make_run(4, 4.0, [3.0] * 4, [1, 2, 3, 1])]
    p1, p3, p4 = bs.summarize(load, runs, [1, 3, 4], cores=2)
    assert p1.speedup == 1.0 and p3.speedup == 1.6 and p4.speedup == 2.0
    assert math.isclose(p3.eff_rank, 1.6 / 3) and math.isclose(p3.eff_worker, 0.8)
    assert math.isclose(p4.eff_worker, 2.0 / 3) and math.isclose(p4.eff_core, 1.0)
    assert p3.rate == 4 / 5.0


def test_probe_latency_and_projection_bounds():
    probe = bs.Probe(startup={1: 0.4, 2: 0.5, 3: 0.6},
                     per_case={1: 1e-4, 2: 5.1e-3, 3: 2.1e-3})
    assert math.isclose(probe.latency(2), 5.0e-3)
    assert math.isclose(probe.latency(3), 2 * 2.1e-3 - 1e-4)
    assert probe.dispatch_latency() == (2, probe.latency(2))
    noisy = bs.Probe(startup={1: 0.4}, per_case={1: -1e-5})   # below the resolution
    assert math.isnan(noisy.write_cost) and noisy.dispatch_latency()[0] == 0
    proj = bs.Projection("w", 64, 6300, case_cost=0.1, case_max=0.3, latency=5e-3,
                         write_cost=1e-4, startup=0.6, startup_serial=0.4)
    assert proj.workers == 63 and proj.limited_by == "workers"
    assert math.isclose(proj.rate, 63 / 0.105)
    assert math.isclose(proj.wall_high, 0.6 + 6300 / proj.rate + 0.3 + 5e-3)
    assert proj.wall_low <= proj.wall_high
    assert math.isclose(proj.serial, 0.4 + 630.0)
    cheap = bs.Projection("w", 64, 100, case_cost=1e-3, case_max=2e-3, latency=1e-3,
                          write_cost=1e-3, startup=0.5, startup_serial=0.4)
    assert cheap.limited_by == "rank 0" and cheap.rate == 1000.0
    assert cheap.wall_low <= cheap.wall_high


# --- command line -----------------------------------------------------------------------------


def test_missing_binary_is_a_one_line_error(tmp_path):
    proc = run_script("--bin", tmp_path / "nope", "--out-dir", tmp_path / "out")
    assert proc.returncode == 2
    assert proc.stderr.count("\n") == 1 and "no flexmor-sweep executable" in proc.stderr
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("args, message", [
    (["--ranks", "2,4"], "must include 1"),
    (["--repeats", "0"], "at least 1"),
    (["--probe-cases", "1"], "--probe-cases"),
    (["--project-ranks", "1"], "--project-ranks"),
])
def test_bad_arguments(tmp_path, args, message):
    fake = tmp_path / "flexmor-sweep"
    fake.write_text("#!/bin/sh\nexit 0\n")
    fake.chmod(0o755)
    proc = run_script("--bin", fake, *args)
    assert proc.returncode == 2
    assert proc.stderr.startswith("bench_sweep.py: error:") and message in proc.stderr


# --- the real binary --------------------------------------------------------------------------


@pytest.mark.skipif(not SWEEP_BIN or not Path(SWEEP_BIN).is_file(),
                    reason="FLEXMOR_SWEEP_BIN not set or not built")
@pytest.mark.skipif(LAUNCHER is None, reason="no mpirun/mpiexec")
def test_quick_run(tmp_path):
    out = tmp_path / "bench"
    proc = run_script("--quick", "--bin", SWEEP_BIN, "--out-dir", out, timeout=120)
    assert proc.returncode == 0, proc.stderr
    md = (out / "sweep_scaling.md").read_text()
    for text in ("# MPI scaling of flexmor-sweep", "## Scaling: `reduced`",
                 "## Dispatch cost of flexmor-sweep (probe)", "## Projection to 64 ranks",
                 "## How to read", "reduction.n_modes = 2"):
        assert text in md, text
    with open(out / "sweep_scaling.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    measured = [r for r in rows if r["kind"] == "measured"]
    assert [(r["workload"], r["ranks"]) for r in measured] == [("reduced", "1"),
                                                              ("reduced", "2")]
    assert all(r["status"] == "ok" and float(r["wall_median_s"]) > 0 for r in measured)
    assert measured[1]["busy_max_s"] and not measured[1]["idle_workers"]
    probe = {r["ranks"]: r for r in rows if r["kind"] == "probe"}
    # A difference of two measured times: noise can make it slightly negative, so only that
    # it was measured is checked (never the sign or size of a wall time).
    assert set(probe) == {"1", "2"} and math.isfinite(float(probe["2"]["latency_s"]))
    assert probe["1"]["n_cases"] == "400" and probe["2"]["n_cases"] == "40"
    assert any(r["kind"] == "projection" and r["ranks"] == "64" for r in rows)


def test_make_probe_uses_the_fastest_runs():
    def point(n_cases, ranks, walls):
        runs = [make_run(ranks, w, [math.nan] * n_cases, [-1] * n_cases) for w in walls]
        load = bs.Workload("w", "", Path("x"), n_cases, len(walls))
        return bs.summarize(load, runs, [ranks], cores=2)[0]

    one = [point(1, 1, [0.5, 0.4, 0.9]), point(1, 2, [0.6, 0.5])]
    many = [point(1001, 1, [0.6, 0.5]), point(101, 2, [1.0, 0.9, 3.0])]
    probe = bs.make_probe(one, many)
    assert probe.startup == {1: 0.4, 2: 0.5}
    assert math.isclose(probe.per_case[1], 0.1 / 1000) and math.isclose(probe.per_case[2],
                                                                         0.4 / 100)
    assert math.isclose(probe.latency(2), 0.004 - 0.0001)
