"""scripts/bench_tradeoff.py: the pure helpers (scene substitution, tip error) without the
binary, the error paths with a stand-in binary, and a --quick run with the real one
(FLEXMOR_BIN, set by CTest; skipped where it does not exist)."""
import csv
import math
import os
import stat
import subprocess
import sys

import numpy as np
import pytest

from helpers import BIN, ROOT, load_driver

SCRIPTS = ROOT / "scripts"
SCRIPT = SCRIPTS / "bench_tradeoff.py"


bt = load_driver(SCRIPT)

BASE = (ROOT / "input" / "two_link.nml").read_text()


def run_script(*args, cwd=None, timeout=300):
    return subprocess.run([sys.executable, str(SCRIPT), *map(str, args)], capture_output=True,
                          text=True, timeout=timeout, cwd=cwd)


def read_rows(out_dir):
    with open(out_dir / "tradeoff.csv", newline="") as f:
        return {row["name"]: row for row in csv.DictReader(f)}


# --- scene text ---------------------------------------------------------------------------------


def test_parse_group_of_the_base_scene():
    dyn = bt.parse_group(BASE, "dynamic")
    assert dyn == {"t_end": "0.7", "output_dt": "1.0e-3",
                   "rtol": "1.0e-6", "atol": "1.0e-8"}
    assert bt.parse_group(BASE, "output") == {"nodes": "'tip', 'elbow'"}
    assert bt.parse_group(BASE, "static") == {}


def test_group_span_multiline_comments_and_quotes():
    text = ("! a comment with &dynamic t_end = 9 /\n"
            "&scene title = 'a/b' /\n"
            "  &dynamic t_end = 1.5, ! not the end / here\n"
            "     integrator = 'galpha' /\n"
            "&output nodes = 'tip' /\n")
    start, end = bt.group_span(text, "dynamic")
    assert text[start:end].strip().startswith("&dynamic t_end = 1.5")
    assert text[start:end].endswith("'galpha' /")
    assert bt.parse_group(text, "dynamic") == {"t_end": "1.5", "integrator": "'galpha'"}
    assert bt.parse_group(text, "scene") == {"title": "'a/b'"}
    assert bt.group_span(text, "modal") is None
    with pytest.raises(ValueError, match="closing"):
        bt.group_span("&dynamic t_end = 1\n", "dynamic")


def test_namelist_values_and_compact_numbers():
    assert bt.nml_value(True) == ".true." and bt.nml_value(False) == ".false."
    assert bt.nml_value("mac") == "'mac'" and bt.nml_value(5) == "5"
    assert float(bt.nml_value(2.5e-4)) == 2.5e-4 and float(bt.nml_value(1e-10)) == 1e-10
    assert [bt.fmt_num(v) for v in (1e-3, 2.5e-4, 1e-10, 0.01)] == ["1e-3", "2.5e-4", "1e-10",
                                                                     "1e-2"]


def test_make_scene_full_model():
    text = bt.make_scene(BASE, {"integrator": "galpha", "dt": 2.5e-4, "rho_inf": 0.8}, None)
    assert "&modal" not in text and "&reduction" not in text
    assert bt.parse_group(text, "dynamic") == {"t_end": "0.7", "output_dt": "1.0e-3",
                                              "integrator": "'galpha'", "dt": "0.00025",
                                              "rho_inf": "0.8"}
    # Everything else is left as it was.
    keep = [line for line in BASE.splitlines() if not line.startswith(("&modal", "&dynamic"))]
    assert [line for line in text.splitlines() if not line.startswith("&dynamic")] == keep


def test_make_scene_reduced_model_and_overrides():
    red = {"n_modes": 3, "static_correction": True, "update": "mac", "update_interval": 0.01,
           "mac_threshold": 0.999}
    text = bt.make_scene(BASE, {"integrator": "erk", "rtol": 1e-6, "atol": 1e-8, "erk_order": 5,
                                "t_end": 0.2, "output_dt": 1e-3}, red)
    lines = text.splitlines()
    i = next(k for k, line in enumerate(lines) if line.startswith("&reduction"))
    assert lines[i + 1].startswith("&dynamic")
    assert bt.parse_group(text, "reduction") == {
        "n_modes": "3", "static_correction": ".true.", "update": "'mac'",
        "update_interval": "0.01", "mac_threshold": "0.999"}
    dyn = bt.parse_group(text, "dynamic")
    assert dyn["t_end"] == "0.2" and dyn["integrator"] == "'erk'" and dyn["erk_order"] == "5"
    assert text.count("&dynamic") == 1 and "&modal" not in text


def test_make_scene_replaces_an_existing_reduction():
    base = (ROOT / "input" / "two_link_2modes.nml").read_text()
    full = bt.make_scene(base, {"integrator": "bdf", "rtol": 1e-3, "atol": 1e-5}, None)
    assert "&reduction" not in full
    red = bt.make_scene(base, {"integrator": "bdf"}, {"n_modes": 1})
    assert full.count("&dynamic") == 1 and red.count("&reduction") == 1
    assert bt.parse_group(red, "reduction") == {"n_modes": "1"}


def test_case_list_is_complete():
    cases = bt.build_cases(False, 3, 0.01, 0.999)
    names = [c.name for c in cases]
    assert len(names) == len(set(names)) == 6 + 4 + 32 + 1
    reduced = [c for c in cases if c.reduction is not None]
    assert {c.reduction["n_modes"] for c in reduced} == {1, 2, 3, 4}
    assert {c.dynamic["integrator"] for c in reduced} == {"bdf", "erk"}
    updated = [c for c in reduced if c.reduction["update"] == "mac"]
    assert len(updated) == 16 and all(c.reduction["update_interval"] == 0.01 for c in updated)
    assert all(c.repeats == 3 for c in cases)
    quick = bt.build_cases(True, 1, 0.01, 0.999)
    assert [c.name for c in quick] == ["full-bdf-rtol1e-3", "red-k1-fixed-bdf",
                                       "red-k2-fixed-bdf"]


# --- tip error ----------------------------------------------------------------------------------


def test_tip_error_is_the_largest_distance():
    t = np.linspace(0.0, 0.2, 201)
    ref = np.column_stack([np.cos(t), np.sin(t), np.zeros_like(t)])
    other = ref.copy()
    other[50, :2] += [3e-4, -4e-4]  # distance 5e-4
    other[120, 0] += 1e-4
    assert bt.tip_error(t, ref, t, other) == pytest.approx(5e-4, rel=1e-12)
    assert bt.tip_error(t, ref, t, ref) == 0.0


def test_tip_error_needs_the_same_time_grid():
    t = np.linspace(0.0, 0.2, 201)
    xyz = np.zeros((201, 3))
    with pytest.raises(ValueError, match="time grids"):
        bt.tip_error(t, xyz, t[:-1], xyz[:-1])
    with pytest.raises(ValueError, match="time grids"):
        bt.tip_error(t, xyz, t + 1e-4, xyz)


# --- command line without the real binary -------------------------------------------------------


def test_missing_binary_is_a_one_line_error(tmp_path):
    proc = run_script("--quick", "--bin", tmp_path / "nope", "--out-dir", tmp_path / "out")
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("bench_tradeoff.py: error: "), proc.stderr
    assert "scripts/example.sh" in proc.stderr and "Traceback" not in proc.stderr
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("args, fragment", [(["--repeats", "0"], "--repeats"),
                                            (["--mac-threshold", "1.5"], "--mac-threshold"),
                                            (["--update-interval", "0"], "--update-interval")])
def test_bad_arguments(tmp_path, args, fragment):
    proc = run_script("--quick", "--bin", sys.executable, "--out-dir", tmp_path, *args)
    assert proc.returncode == 2 and fragment in proc.stderr and "Traceback" not in proc.stderr


def test_failing_runs_are_recorded(tmp_path):
    fake = tmp_path / "flexmor"
    fake.write_text("#!/bin/sh\necho 'flexmor: error: x.nml:1: no convergence' >&2\nexit 3\n")
    fake.chmod(fake.stat().st_mode | stat.S_IXUSR)
    out = tmp_path / "out"
    proc = run_script("--quick", "--bin", fake, "--out-dir", out)
    assert proc.returncode == 1, proc.stdout + proc.stderr
    assert "Traceback" not in proc.stderr and "FAILED" in proc.stdout
    rows = read_rows(out)
    assert len(rows) == 5
    for row in rows.values():
        assert row["status"] == "failed"
        assert row["message"] == "exit 3: flexmor: error: x.nml:1: no convergence"
    assert "failed: exit 3" in (out / "tradeoff.md").read_text()
    assert (out / "tradeoff.png").exists()


# --- the real thing -----------------------------------------------------------------------------


@pytest.mark.skipif(not os.path.isfile(BIN), reason=f"no flexmor binary at {BIN} (FLEXMOR_BIN)")
def test_quick_benchmark(tmp_path):
    out = tmp_path / "bench"
    proc = run_script("--quick", "--bin", BIN, "--out-dir", out, cwd=tmp_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    for name in ("tradeoff.csv", "tradeoff.md", "tradeoff.png"):
        assert (out / name).stat().st_size > 0, name
    md = (out / "tradeoff.md").read_text()
    command = next(line for line in md.splitlines() if line.startswith("- Command: "))
    assert "bench_tradeoff.py" in command and "--quick" in command
    machine = next(line for line in md.splitlines() if line.startswith("- Machine: "))
    assert "cores" in machine
    assert "- Repeats: 1" in md and "wall_time_s" in md

    rows = read_rows(out)
    assert set(rows) == {"ref-bdf-rtol1e-8", "ref-check-bdf-rtol1e-7", "full-bdf-rtol1e-3",
                         "red-k1-fixed-bdf", "red-k2-fixed-bdf"}
    for name, row in rows.items():
        assert row["status"] == "ok", (name, row["message"])
        error = float(row["tip_error_m"])
        assert math.isfinite(error) and error >= 0.0, name
        assert float(row["time_median_s"]) > 0.0 and int(row["n_steps"]) > 0
    assert float(rows["ref-bdf-rtol1e-8"]["tip_error_m"]) == 0.0
    k1, k2 = (float(rows[f"red-k{k}-fixed-bdf"]["tip_error_m"]) for k in (1, 2))
    assert k2 < k1
    for k in (1, 2):
        row = rows[f"red-k{k}-fixed-bdf"]
        assert row["n_modes"] == str(k) and math.isfinite(float(row["error_estimate_max_m"]))
        assert float(row["residual_max"]) >= 0.0
