"""scripts/bench_control.py: a --quick run with the real binary (FLEXMOR_BIN, set by CTest)
writes its table, CSV and plots with every case ok; and a missing binary is a one-line error."""
import csv
import subprocess
import sys

import pytest

from helpers import BIN, ROOT

SCRIPT = ROOT / "scripts" / "bench_control.py"


def run_script(*args, timeout=600):
    return subprocess.run([sys.executable, str(SCRIPT), *map(str, args)], capture_output=True,
                          text=True, timeout=timeout, env={"PYTHONPATH": str(ROOT / "python"),
                                                           "PATH": "/usr/bin:/bin"})


def test_missing_binary(tmp_path):
    proc = run_script("--bin", tmp_path / "nope", "--out-dir", tmp_path)
    assert proc.returncode == 2
    assert proc.stderr.strip().startswith("bench_control.py: error: no flexmor executable")


@pytest.mark.skipif(not BIN.exists(), reason="flexmor binary not built")
def test_quick_run(tmp_path):
    """Every case runs; the feedforward shrinks the arm's tracking error (0.46 -> 0.19 m
    observed at 0.6 s), and a reduced stage follows the full one within 2 % of the 1 mm step
    (1.6e-6 m observed)."""
    proc = run_script("--bin", BIN, "--out-dir", tmp_path, "--quick")
    assert proc.returncode == 0, proc.stderr
    for name in ("control_tradeoff.md", "control_tradeoff.png", "two_link_pd.png",
                 "stage_pid.png"):
        assert (tmp_path / name).stat().st_size > 0
    with open(tmp_path / "control_tradeoff.csv", newline="") as f:
        rows = {r["name"]: r for r in csv.DictReader(f)}
    assert all(r["status"] == "ok" for r in rows.values())
    assert float(rows["arm-ff-full"]["tracking_error_m"]) < 0.6 * float(
        rows["arm-full"]["tracking_error_m"])
    for k in (1, 2):
        assert float(rows[f"stage-k{k}-fixed"]["diff_from_full_m"]) < 2e-5
