"""flexmor.sweep and the commands flexmor-sweep-summary, -plot and -tradeoff on small
synthetic sweep files written with the layout of docs/sweep.md ("Result file")."""
import csv
import subprocess
import sys

import h5py
import numpy as np
import pytest

import flexmor.sweep as flexmor_sweep
from flexmor import sweep_plot, sweep_summary, sweep_tradeoff

PNG = b"\x89PNG\r\n\x1a\n"
END, MODES = "motion.phi1.end", "reduction.n_modes"
FAILED_MESSAGE = "numerical: CVODE too many steps at t = 0.31 s (dynamic.rtol 1e-06)"
METRICS = ("max_tip_deflection", "residual_vibration", "n_steps", "n_model_evals",
           "error_estimate", "n_modes", "max_control_error", "final_control_error")


def write_sweep(path, parameters, status, metrics, wall, messages=None, rank=None, title="",
                mode="product"):
    """A sweep file as flexmor-sweep writes it: /cases/... datasets of shape (n_cases,), fixed
    length 'S256' messages, NaN metrics and wall time and rank -1 where not run."""
    status = np.asarray(status, dtype=np.int32)
    n = status.size
    messages = messages or [""] * n
    rank = np.asarray(rank if rank is not None else np.where(status >= 0, 1 + np.arange(n) % 3,
                                                             -1), dtype=np.int32)
    with h5py.File(path, "w") as f:
        cases = f.create_group("cases")
        for name, values in parameters.items():
            cases[f"parameters/{name}"] = np.asarray(values, dtype=np.float64)
        cases["status"] = status
        cases["message"] = np.array([m.encode() for m in messages], dtype="S256")
        cases["wall_time_s"] = np.asarray(wall, dtype=np.float64)
        cases["rank"] = rank
        for name, values in metrics.items():
            cases[f"metrics/{name}"] = np.asarray(values, dtype=np.float64)
        f.attrs["flexmor_version"] = "0.1.0"
        f.attrs["sweep_input"] = "&sweep base = 'two_link.nml' /\n"
        f.attrs["sweep_file"] = "sweep.nml"
        f.attrs["base_input"] = "&dynamic t_end = 0.7 /\n"
        f.attrs["base_scene"] = "two_link.nml"
        f.attrs["mode"] = np.bytes_(mode.encode())  # fixed-length string attribute
        f.attrs["n_cases"] = np.int64(n)
        f.attrs["n_parameters"] = np.int64(len(parameters))
        f.attrs["seed"] = np.int64(1)
        f.attrs["node"] = "tip"
        f.attrs["title"] = title


def deflection(end, modes):
    """Synthetic metric: reference 0.01 * end; k modes err by 0.001 * end / k**2 (0 = full)."""
    k = np.asarray(modes, dtype=float)
    err = np.where(k == 0, 0.0, 0.001 * np.asarray(end) / np.where(k == 0, 1.0, k) ** 2)
    return 0.01 * np.asarray(end) + err


def product_sweep(path, fail_full=False):
    """end in (0.5, 1, 1.5) (slowest) x n_modes in (0 = full, 1, 2, 4): 12 cases; index 9
    (end 1.5, 1 mode; printed as case 10) failed, index 10 (end 1.5, 2 modes; case 11) not run.
    With ``fail_full`` the full case of end 1.0 (index 4, case 5) failed too."""
    ends, modes = np.meshgrid([0.5, 1.0, 1.5], [0, 1, 2, 4], indexing="ij")
    ends, modes = ends.ravel(), modes.ravel()
    status = np.zeros(12, dtype=int)
    status[9], status[10] = 3, -1
    messages = [""] * 12
    messages[9] = FAILED_MESSAGE
    if fail_full:
        status[4] = 2
        messages[4] = "model: singular mass matrix"
    wall = np.where(modes == 0, 1.0 + ends, 0.01 * modes * (1 + ends))
    metric = deflection(ends, modes)
    metrics = {name: metric * (i + 1) for i, name in enumerate(METRICS)}
    metrics["max_tip_deflection"] = metric
    metrics["n_modes"] = modes.astype(float)
    bad = status != 0
    wall = np.where(status < 0, np.nan, wall)
    for values in metrics.values():
        values[bad] = np.nan
    write_sweep(path, {END: ends, MODES: modes}, status, metrics, wall, messages,
                title="two-link motion x modes")
    return ends, modes, status


def three_param_sweep(path):
    """2 x 2 x 2 product of a, b, c, all ok; metric = a + 10 b + 100 c."""
    a, b, c = (g.ravel() for g in np.meshgrid([1.0, 2.0], [3.0, 4.0], [5.0, 6.0],
                                               indexing="ij"))
    write_sweep(path, {"hinge.j1.stiffness": a, "mass.tip.m": b, "dynamic.rtol": c},
                np.zeros(8), {"max_tip_deflection": a + 10 * b + 100 * c}, np.full(8, 0.5))


@pytest.fixture
def sweep_file(tmp_path):
    path = tmp_path / "sweep.h5"
    product_sweep(path)
    return path


def run_script(name, *args):
    """The command of module flexmor.<name>, as its console script runs it."""
    return subprocess.run([sys.executable, "-m", f"flexmor.{name}", *map(str, args)],
                          capture_output=True, text=True, timeout=120)


def assert_one_line_error(err, *fragments):
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert "Traceback" not in err
    for fragment in fragments:
        assert fragment in lines[0], f"{fragment!r} not in {lines[0]!r}"


# --- flexmor_sweep ----------------------------------------------------------------------------


def test_load_sweep(sweep_file):
    s = flexmor_sweep.load_sweep(sweep_file)
    assert s.n_cases == 12
    assert sorted(s.parameters) == [END, MODES]
    np.testing.assert_array_equal(s.parameters[MODES][:4], [0, 1, 2, 4])
    assert s.parameters[END].dtype == np.float64
    assert s.messages[9] == FAILED_MESSAGE and s.messages[0] == ""
    assert all(isinstance(m, str) and "\x00" not in m for m in s.messages)
    assert s.status[9] == 3 and s.status[10] == -1
    assert s.ok.sum() == 10 and s.failed.sum() == 1 and s.not_run.sum() == 1
    assert s.rank[10] == -1 and np.isnan(s.wall_time_s[10])
    assert set(s.metrics) == set(METRICS)
    assert np.isnan(s.metrics["max_tip_deflection"][9])
    assert s.attrs["mode"] == "product" and s.attrs["n_cases"] == 12
    assert s.attrs["title"] == "two-link motion x modes"
    np.testing.assert_array_equal(s.metric("wall_time_s"), s.wall_time_s)


def test_load_sweep_errors(tmp_path, sweep_file):
    with pytest.raises(flexmor_sweep.SweepFileError, match="no such file"):
        flexmor_sweep.load_sweep(tmp_path / "nope.h5")
    junk = tmp_path / "junk.h5"
    junk.write_text("not hdf5")
    with pytest.raises(flexmor_sweep.SweepFileError, match="not a readable HDF5 file"):
        flexmor_sweep.load_sweep(junk)
    single = tmp_path / "run.h5"
    with h5py.File(single, "w") as f:
        f["time"] = np.arange(3.0)
    with pytest.raises(flexmor_sweep.SweepFileError, match="not a sweep file.*single-run"):
        flexmor_sweep.load_sweep(single)
    short = tmp_path / "short.h5"
    product_sweep(short)
    with h5py.File(short, "a") as f:
        del f["cases/wall_time_s"]
        f["cases/wall_time_s"] = np.zeros(5)
    with pytest.raises(flexmor_sweep.SweepFileError, match="wall_time_s has shape"):
        flexmor_sweep.load_sweep(short)
    s = flexmor_sweep.load_sweep(sweep_file)
    with pytest.raises(flexmor_sweep.SweepFileError) as info:
        s.metric("tip_error")
    assert str(sweep_file) in str(info.value) and "max_tip_deflection" in str(info.value)


def test_where_filters(sweep_file):
    s = flexmor_sweep.load_sweep(sweep_file)
    assert flexmor_sweep.parse_where(" reduction.n_modes = 2 ") == (MODES, 2.0)
    for bad in ("n_modes", "=2", "a=b"):
        with pytest.raises(ValueError):
            flexmor_sweep.parse_where(bad)
    mask = flexmor_sweep.where_mask(s, [(MODES, 2.0), (END, 1.0)])
    assert np.flatnonzero(mask).tolist() == [6]
    with pytest.raises(flexmor_sweep.SweepFileError, match="values: 0, 1, 2, 4"):
        flexmor_sweep.where_mask(s, [(MODES, 3.0)])
    # the printed 6-digit form selects a value with more digits (pi/2 prints as 1.5708)
    s.parameters[END][4:8] = np.pi / 2
    assert np.flatnonzero(flexmor_sweep.where_mask(s, [(END, 1.5708)])).tolist() == [4, 5, 6, 7]
    assert flexmor_sweep.where_mask(s, [(END, np.pi / 2)]).sum() == 4


# --- sweep_summary ----------------------------------------------------------------------------


def test_summary_table_and_totals(sweep_file, capsys):
    assert sweep_summary.main([str(sweep_file)]) == 0
    out = capsys.readouterr().out
    assert "done: 11/12 cases (10 ok, 1 failed)" in out
    assert "failed: 1 (numerical (3): 1)" in out
    assert "not run: 1" in out
    assert FAILED_MESSAGE in out and "not run" in out
    table = [line for line in out.splitlines() if line.split()[:1] and line.split()[0].isdigit()]
    assert len(table) == 12
    t = sweep_summary.compute_totals(flexmor_sweep.load_sweep(sweep_file))
    s = flexmor_sweep.load_sweep(sweep_file)
    ran = np.isfinite(s.wall_time_s)
    assert t.wall_total == pytest.approx(np.nansum(s.wall_time_s))
    assert t.wall_median == pytest.approx(np.median(s.wall_time_s[ran]))
    ok_wall = s.wall_time_s[s.ok]
    assert (t.cost_min, t.cost_max) == (pytest.approx(ok_wall.min()), pytest.approx(ok_wall.max()))
    assert t.cost_ratio == pytest.approx(ok_wall.max() / ok_wall.min())
    assert "max/min" in out and "cost per case" in out


def test_summary_failed_only_and_csv(sweep_file, tmp_path, capsys):
    out_csv = tmp_path / "cases.csv"
    assert sweep_summary.main([str(sweep_file), "--csv", str(out_csv)]) == 0
    with open(out_csv, newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 12
    assert list(rows[0])[:3] == ["case", END, MODES]
    assert [r["case"] for r in rows] == [str(n) for n in range(1, 13)]  # numbered from 1
    assert rows[9]["status"] == "3" and rows[9]["message"] == FAILED_MESSAGE
    assert rows[10]["status"] == "-1" and rows[10]["max_tip_deflection"] == "nan"
    assert float(rows[1]["max_tip_deflection"]) == pytest.approx(deflection(0.5, 1))
    capsys.readouterr()

    failed_csv = tmp_path / "failed.csv"
    assert sweep_summary.main([str(sweep_file), "--failed", "--csv", str(failed_csv)]) == 0
    out = capsys.readouterr().out
    table = [line for line in out.splitlines() if line.split()[:1] and line.split()[0].isdigit()]
    assert len(table) == 1 and table[0].split()[0] == "10" and FAILED_MESSAGE in table[0]
    assert "done: 11/12" in out
    with open(failed_csv, newline="") as f:
        assert [r["case"] for r in csv.DictReader(f)] == ["10"]


def test_summary_no_failures(tmp_path, capsys):
    path = tmp_path / "ok.h5"
    three_param_sweep(path)
    assert sweep_summary.main([str(path), "--failed"]) == 0
    out = capsys.readouterr().out
    assert "no failed cases" in out and "done: 8/8 cases (8 ok, 0 failed)" in out


# --- sweep_plot -------------------------------------------------------------------------------


def test_plot_one_parameter_by(sweep_file, tmp_path, capsys):
    out = tmp_path / "lines.png"
    assert sweep_plot.main([str(sweep_file), "--metric", "max_tip_deflection", "--x", MODES,
                            "--by", END, "-o", str(out)]) == 0
    assert out.read_bytes()[:8] == PNG
    err = capsys.readouterr().err
    assert "1 failed (case 10)" in err and "1 not run (case 11)" in err
    s = flexmor_sweep.load_sweep(sweep_file)
    plan = sweep_plot.make_plan(s, "max_tip_deflection", MODES, by=END)
    lines = sweep_plot.line_groups(s, plan)
    assert [label for label, _ in lines] == [f"{END}=0.5", f"{END}=1", f"{END}=1.5"]
    assert [idx.tolist() for _, idx in lines] == [[0, 1, 2, 3], [4, 5, 6, 7], [8, 11]]


def test_plot_groups_other_varying_parameters(sweep_file, tmp_path):
    s = flexmor_sweep.load_sweep(sweep_file)
    plan = sweep_plot.make_plan(s, "max_tip_deflection", END)
    assert plan.groups == [MODES]
    labels = [label for label, _ in sweep_plot.line_groups(s, plan)]
    assert labels == [f"{MODES}=full", f"{MODES}=1", f"{MODES}=2", f"{MODES}=4"]
    with pytest.raises(sweep_plot.UserError, match="--where"):
        sweep_plot.make_plan(s, "max_tip_deflection", END, max_lines=2)


def test_plot_where_filter(sweep_file, tmp_path):
    s = flexmor_sweep.load_sweep(sweep_file)
    plan = sweep_plot.make_plan(s, "max_tip_deflection", END, where=[(MODES, 0.0)])
    assert plan.groups == []
    assert np.flatnonzero(plan.usable).tolist() == [0, 4, 8]
    out = tmp_path / "full.png"
    assert sweep_plot.main([str(sweep_file), "--metric", "max_tip_deflection", "--x", END,
                            "--where", f"{MODES}=0", "-o", str(out)]) == 0
    assert out.read_bytes()[:8] == PNG


def test_plot_two_parameters_grid(sweep_file, tmp_path):
    s = flexmor_sweep.load_sweep(sweep_file)
    plan = sweep_plot.make_plan(s, "max_tip_deflection", END, y=MODES)
    assert sweep_plot.is_grid(s.parameters[END], s.parameters[MODES])
    out = tmp_path / "map.png"
    kind = sweep_plot.draw(s, plan, str(out), [], (False, False, False))
    assert kind == "pcolormesh" and out.read_bytes()[:8] == PNG
    assert sweep_plot.main([str(sweep_file), "--metric", "wall_time_s", "--x", END, "--y", MODES,
                            "-o", str(tmp_path / "cost.png")]) == 0


def test_plot_two_parameters_scattered(tmp_path):
    rng = np.random.default_rng(1)
    a, b = rng.uniform(0, 1, 20), rng.uniform(1, 2, 20)
    path = tmp_path / "random.h5"
    write_sweep(path, {"a.x": a, "a.y": b}, np.zeros(20), {"max_tip_deflection": a * b},
                np.ones(20), mode="random")
    s = flexmor_sweep.load_sweep(path)
    assert not sweep_plot.is_grid(a, b)
    plan = sweep_plot.make_plan(s, "max_tip_deflection", "a.x", y="a.y")
    kind = sweep_plot.draw(s, plan, str(tmp_path / "tri.png"), [], (False, False, False))
    assert kind == "tricontourf"
    kind = sweep_plot.draw(s, plan, str(tmp_path / "sc.png"), [], (True, False, False))
    assert kind == "scatter"


def test_plot_map_needs_where_for_third_parameter(tmp_path, capsys):
    path = tmp_path / "three.h5"
    three_param_sweep(path)
    args = [str(path), "--metric", "max_tip_deflection", "--x", "hinge.j1.stiffness",
            "--y", "mass.tip.m", "-o", str(tmp_path / "m.png")]
    assert sweep_plot.main(args) == 2
    assert_one_line_error(capsys.readouterr().err, "dynamic.rtol", "--where", "5, 6")
    assert sweep_plot.main(args + ["--where", "dynamic.rtol=6"]) == 0
    assert (tmp_path / "m.png").read_bytes()[:8] == PNG


def test_plot_unknown_names(sweep_file, tmp_path, capsys):
    out = str(tmp_path / "x.png")
    assert sweep_plot.main([str(sweep_file), "--metric", "tip_error", "--x", END, "-o", out]) == 2
    assert_one_line_error(capsys.readouterr().err, "'tip_error'", "available:",
                          "max_tip_deflection", "wall_time_s")
    assert sweep_plot.main([str(sweep_file), "--metric", "n_steps", "--x", "dt", "-o", out]) == 2
    assert_one_line_error(capsys.readouterr().err, "'dt'", f"{END}, {MODES}")
    assert sweep_plot.main([str(sweep_file), "--metric", "n_steps", "--x", END,
                            "--where", f"{MODES}=3", "-o", out]) == 2
    assert_one_line_error(capsys.readouterr().err, "values: 0, 1, 2, 4")


# --- sweep_tradeoff ---------------------------------------------------------------------------


def test_tradeoff_directions():
    assert sweep_tradeoff.infer_higher("reduction.n_modes") is True
    assert sweep_tradeoff.infer_higher("link.link1.n_elements") is True
    assert sweep_tradeoff.infer_higher("dynamic.rtol") is False
    assert sweep_tradeoff.infer_higher("dynamic.dt") is False
    assert sweep_tradeoff.infer_higher("hinge.j1.stiffness") is None
    assert sweep_tradeoff.directions(["x.k"], ["x.k"], []) == [("x.k", True)]
    with pytest.raises(sweep_tradeoff.UserError, match="--higher hinge.j1.stiffness"):
        sweep_tradeoff.directions(["hinge.j1.stiffness"], [], [])


def test_tradeoff_groups_reference_and_errors(sweep_file):
    s = flexmor_sweep.load_sweep(sweep_file)
    t = sweep_tradeoff.compute_tradeoff(s, "max_tip_deflection", [(MODES, True)])
    assert t.group_labels == [f"{END}=0.5", f"{END}=1", f"{END}=1.5"]
    # n_modes 0 (full model) is the reference of every group
    assert t.reference[[0, 1, 2, 3]].tolist() == [0] * 4
    assert t.reference[[4, 5, 6, 7]].tolist() == [4] * 4
    assert t.reference[[8, 11]].tolist() == [8, 8]
    assert t.group[9] == -1 and t.group[10] == -1 and np.isnan(t.error[9])
    ends, modes = s.parameters[END], s.parameters[MODES]
    used = t.group >= 0
    expected = np.where(modes == 0, 0.0, 0.001 * ends / np.maximum(modes, 1) ** 2)
    np.testing.assert_allclose(t.error[used], expected[used], rtol=1e-12, atol=1e-18)
    rel = sweep_tradeoff.compute_tradeoff(s, "max_tip_deflection", [(MODES, True)], True)
    np.testing.assert_allclose(rel.error[used], expected[used] / (0.01 * ends[used]), rtol=1e-12)

    rows = sweep_tradeoff.level_rows(s, t)
    assert [r.label for r in rows] == [f"{MODES}=1", f"{MODES}=2", f"{MODES}=4", f"{MODES}=full"]
    assert [r.n for r in rows] == [2, 2, 3, 3] and [r.n_ref for r in rows] == [0, 0, 0, 3]
    assert rows[-1].error_max == 0.0 and rows[-1].speedup_median == pytest.approx(1.0)
    assert rows[0].error_max == pytest.approx(0.001 * 1.0)
    assert rows[0].error_median == pytest.approx(0.001 * 0.75)
    assert rows[2].wall_median == pytest.approx(0.04 * 2.0)
    assert rows[2].speedup_median == pytest.approx(2.0 / 0.08)


def test_tradeoff_failed_reference_falls_back(tmp_path):
    path = tmp_path / "fail_full.h5"
    product_sweep(path, fail_full=True)
    s = flexmor_sweep.load_sweep(path)
    t = sweep_tradeoff.compute_tradeoff(s, "max_tip_deflection", [(MODES, True)])
    assert t.reference[[5, 6, 7]].tolist() == [7, 7, 7]  # 4 modes, the best that ran
    assert any("case(s) 5 did not run ok; reference is case 8" in n for n in t.notes)


def test_tradeoff_two_fidelity_parameters(tmp_path):
    modes, rtol, load = (g.ravel() for g in np.meshgrid([0, 2], [1e-3, 1e-6], [1.0, 2.0],
                                                        indexing="ij"))
    metric = load * (1 + 0.1 * (modes == 2) + rtol)
    path = tmp_path / "two.h5"
    write_sweep(path, {MODES: modes, "dynamic.rtol": rtol, "mass.tip.m": load}, np.zeros(8),
                {"max_tip_deflection": metric}, 0.1 + modes + np.log10(1 / rtol))
    s = flexmor_sweep.load_sweep(path)
    fidelity = sweep_tradeoff.directions([MODES, "dynamic.rtol"], [], [])
    assert fidelity == [(MODES, True), ("dynamic.rtol", False)]
    t = sweep_tradeoff.compute_tradeoff(s, "max_tip_deflection", fidelity)
    assert len(t.group_labels) == 2
    refs = set(t.reference.tolist())
    assert all(modes[r] == 0 and rtol[r] == 1e-6 for r in refs) and len(refs) == 2
    rows = sweep_tradeoff.level_rows(s, t)
    assert rows[-1].label == f"{MODES}=full, dynamic.rtol=1e-06" and rows[-1].n_ref == 2


def test_tradeoff_cli_table_and_plot(sweep_file, tmp_path, capsys):
    out = tmp_path / "tradeoff.png"
    assert sweep_tradeoff.main([str(sweep_file), "--metric", "max_tip_deflection",
                                "--fidelity", MODES, "-o", str(out)]) == 0
    assert out.read_bytes()[:8] == PNG
    captured = capsys.readouterr()
    lines = captured.out.splitlines()
    assert lines[0].split()[:4] == ["fidelity", "cases", "refs", "wall_median_s"]
    assert lines[1].split()[0] == f"{MODES}=1" and lines[4].split()[0] == f"{MODES}=full"
    assert "1 failed (case 10)" in captured.err
    assert sweep_tradeoff.main([str(sweep_file), "--metric", "nope", "--fidelity", MODES,
                                "-o", str(out)]) == 2
    assert_one_line_error(capsys.readouterr().err, "'nope'", "available:")
    assert sweep_tradeoff.main([str(sweep_file), "--fidelity", "modes", "--higher", "modes",
                                "-o", str(out)]) == 2
    assert_one_line_error(capsys.readouterr().err, "no parameter 'modes'")


# --- clean errors from the command line -------------------------------------------------------


def test_cli_missing_file(tmp_path):
    missing = tmp_path / "missing.h5"
    for name, extra in (("sweep_summary", []),
                        ("sweep_plot", ["--metric", "n_steps", "--x", END]),
                        ("sweep_tradeoff", ["--fidelity", MODES])):
        proc = run_script(name, missing, *extra, "-o" if extra else "--failed",
                          *([tmp_path / "x.png"] if extra else []))
        assert proc.returncode == 2, (name, proc.stderr)
        assert_one_line_error(proc.stderr, "flexmor-" + name.replace("_", "-"), "missing.h5",
                              "no such file")


def test_cli_not_a_sweep_file(tmp_path):
    single = tmp_path / "run.h5"
    with h5py.File(single, "w") as f:
        f["time"] = np.arange(3.0)
        f["nodes/tip/position"] = np.zeros((3, 3))
    proc = run_script("sweep_summary", single)
    assert proc.returncode == 2
    assert_one_line_error(proc.stderr, "run.h5", "not a sweep file")


def test_cli_unknown_metric(sweep_file, tmp_path):
    proc = run_script("sweep_plot", sweep_file, "--metric", "tip_error", "--x", END,
                      "-o", tmp_path / "x.png")
    assert proc.returncode == 2
    assert_one_line_error(proc.stderr, "no metric 'tip_error'", "available:", "n_model_evals")
    assert not (tmp_path / "x.png").exists()
