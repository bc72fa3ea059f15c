#!/usr/bin/env python3
"""Cost per step against model size, and work against precision, on the two-link benchmark
(``input/two_link.nml`` with n beam elements per link), flexmor beside Exudyn.

Part 1, scaling: time per step for n = 2, 4, ..., 128 elements per link of

- the full model and the reduced models k = 2 and 4 (``&reduction n_modes = k``) and k = 4
  with ``evaluation = 'expanded'``, flexmor's
  fixed-step generalized-alpha at dt = 1e-4 s (rho_inf 0.8);
- Exudyn's model of the same benchmark (python/flexmor/exudyn_two_link.py: planar
  geometrically exact beams, generalized-alpha at h = 1e-4 s, its sparse solver), when Exudyn
  is installed (``pip install exudyn``; skipped otherwise) and up to --exudyn-max elements per
  link.

The time per step is the difference of two runs, to t1 and 2 t1 (--t-end; 5 t1 and 10 t1 for
the expanded evaluation, whose steps are cheap), divided by the difference of their step
counts: set-up, the reduced basis and output writing cancel. Each of --repeat pairs runs back
to back, and the median of the pairs' values is reported; the full model's pairs alternate
with Exudyn's, and full / Exudyn is the median of those rounds' ratios, so that the machine's
drift falls on both alike. flexmor's
time is the processor time of its analyses (root attribute ``cpu_time_s``), Exudyn's the
process time of SolveDynamic: both are what other jobs on the machine do not inflate. Peak memory is the maximum resident set of the longer flexmor run
(/usr/bin/time). The exponent p of time ~ n^p is fitted by least squares in log-log over
8 <= n <= 128.

Whole runs (--whole-runs): the scene's own 0.7 s analysis (galpha_adaptive, rtol 1e-6) at
--whole-meshes, full against k = 4 with the full and with the expanded evaluation: times, steps,
expansions and the reduced tips' distance from the full one (whole_runs.csv/.md).

Part 2, work-precision (--work-precision): the largest distance over 0 <= t <= 0.7 s of the tip
from a converged solution (flexmor, 32 elements per link, generalized-alpha at dt = 2e-5 s;
the same at 16 elements per link shows how converged it is) against solve time, for flexmor
meshes 1, 2, 3, 4 and 8 per link with every integrator (bdf with max_order 2 and 5,
galpha_adaptive and galpha at several tolerances/steps) and for Exudyn at 6, 8, 10, 12, 16, 24, 32
and 48 per link with several h (its beam needs about 48 per link for a 1e-5 m tip error). For the tip error targets 1e-3, 1e-4 and 1e-5 m: the fastest configuration of
each code and their ratio.

Usage (the flexmor Python package installed, or PYTHONPATH=python):

    python3 scripts/bench_scaling.py [--bin build/bin/flexmor] [--out-dir docs/bench] \\
        [--meshes 2,3,4,8,16,32,64,128] [--t-end 0.1] [--exudyn-max 64] [--no-exudyn] \\
        [--whole-runs] [--whole-meshes 3,8,16,32,64] [--work-precision] [--repeat 3] [--quick]

A time per step is the median of --repeat pairs of runs, a whole run's time the least of
--repeat runs (the one other jobs disturbed least). Writes scaling.csv, scaling.md and scaling.png (and work_precision.csv/.md/.png) into
--out-dir, each with the command, date, machine, flexmor version and commit. --quick: meshes
2 and 4, t_end 0.004 s, no work-precision, for the tests. A failing run is recorded with its
error and the benchmark goes on (exit status 1 at the end); bad arguments exit with 2.
"""
from __future__ import annotations

import argparse
import math
import os
import re
import subprocess
import sys
import tempfile
from datetime import datetime
from pathlib import Path

import h5py
import numpy as np

from flexmor import exudyn_two_link
from flexmor.bench import command_line, cpu_model, git_commit, last_line, usable_cores, write_csv
from flexmor.results import load_node_path, run_attributes

ROOT = Path(__file__).resolve().parents[1]
BASE = (ROOT / "input" / "two_link.nml").read_text()
DT = 1.0e-4
# The expanded evaluation's step costs about 1 % of the full one's: its windows are this many
# times longer, so that the difference of two runs' times stands well above their noise.
EXPANDED_WINDOW = 5
TARGETS = (1.0e-3, 1.0e-4, 1.0e-5)


def scene(n: int, dynamic: str, k: int = 0, t_end: float = 0.02, output_dt: float = 1e-3,
          expanded: bool = False) -> str:
    """The benchmark with n elements per link, the given &dynamic settings (none: the scene's
    own) and, for k > 0, a reduced model of k modes (with the expanded evaluation if asked)."""
    text = BASE.replace("n_elements = 3", f"n_elements = {n}")
    text = re.sub(r"&modal[^/]*/", "", text)
    if dynamic:
        text = re.sub(r"&dynamic[^/]*/",
                      f"&dynamic t_end = {t_end!r}, output_dt = {output_dt!r}, {dynamic} /", text)
    if k:
        text += f"\n&reduction n_modes = {k}" + (", evaluation = 'expanded'" if expanded
                                                  else "") + " /\n"
    return text


class RunFailed(RuntimeError):
    pass


def run_flexmor(binary: Path, work: Path, name: str, text: str, timeout: float = 3600):
    """Run a scene; returns (attributes, peak RSS in MiB, result path)."""
    nml = work / f"{name}.nml"
    out = work / f"{name}.h5"
    nml.write_text(text)
    cmd = [str(binary), "-q", str(nml), "-o", str(out)]
    timer = Path("/usr/bin/time")
    if timer.exists():
        cmd = [str(timer), "-f", "maxrss_kb=%M"] + cmd
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    if proc.returncode != 0:
        raise RunFailed(last_line(proc.stderr) or f"exit status {proc.returncode}")
    match = re.search(r"maxrss_kb=(\d+)", proc.stderr)
    rss = int(match.group(1)) / 1024 if match else float("nan")
    return run_attributes(out), rss, out


def flexmor_pair(binary, work, name, n, dynamic, k, t1, expanded=False):
    """One pair of runs to t1 and 2 t1 back to back: (time per step, peak RSS of the longer
    run, dynamic coordinates)."""
    a1 = run_flexmor(binary, work, f"{name}_1", scene(n, dynamic, k, t1, expanded=expanded))[0]
    a2, rss, _ = run_flexmor(binary, work, f"{name}_2", scene(n, dynamic, k, 2 * t1,
                                                             expanded=expanded))
    step = (solve_time(a2) - solve_time(a1)) / (a2["n_steps"] - a1["n_steps"])
    return step, rss, int(a2["n_dynamic_coordinates"])


def per_step_flexmor(binary, work, name, n, dynamic, k, t1, repeat=1, expanded=False):
    """Time per step from `repeat` pairs of runs to t1 and to 2 t1, each pair run back to back:
    the median of the pairs' differences. Pairs follow the machine's slow drift together (a
    batch of t1 runs, then one of 2 t1 runs, did not: at 3 elements per link the expanded
    evaluation's step measured 1.0 us in one run and 2.5 us in the next)."""
    diffs, rss, n_dy = [], 0.0, 0
    for _ in range(repeat):
        step, rss2, n_dy = flexmor_pair(binary, work, name, n, dynamic, k, t1, expanded)
        diffs.append(step)
        rss = max(rss, rss2)
    return float(np.median(diffs)), rss, n_dy


def full_beside_exudyn(binary, work, n, dynamic, t1, repeat):
    """The full model's and Exudyn's time per step in `repeat` rounds, each a flexmor pair and
    an Exudyn pair back to back, so that the machine's drift (25 % and more over minutes
    here) falls on both alike: medians of each code's pairs, the median of the rounds' ratios,
    the peak RSS, the dynamic coordinates and the loosest Newton tolerance Exudyn needed."""
    ours, theirs, ratios, rss, tol, n_dy = [], [], [], 0.0, 0.0, 0
    for _ in range(repeat):
        step, rss2, n_dy = flexmor_pair(binary, work, f"s{n}_full", n, dynamic, 0, t1)
        r1, r2 = exudyn_pair(n, t1)
        other = (r2["cpu_s"] - r1["cpu_s"]) / (r2["n_steps"] - r1["n_steps"])
        ours.append(step)
        theirs.append(other)
        ratios.append(step / other)
        rss = max(rss, rss2)
        tol = max(tol, r2["newton_rtol"])
    return (float(np.median(ours)), float(np.median(theirs)), float(np.median(ratios)), rss,
            n_dy, tol)


def solve_time(attrs) -> float:
    """flexmor's processor time of the analyses (cpu_time_s), like Exudyn's process time; the
    wall time where a result file predates it."""
    return float(attrs.get("cpu_time_s", attrs["wall_time_s"]))


def run_exudyn(n, h, t_end, tolerances=(1e-6, 1e-5, 1e-4)):
    """Exudyn's run; from 32 elements per link its Newton iteration stalls at a relative
    tolerance of 1e-6 (round-off of the stiff axial and shear modes), so a failed run is
    repeated at the next of `tolerances` (1e-5, then 1e-4: needed at 64). Returns its result
    with the tolerance that worked."""
    for tol in tolerances:
        try:
            return {**exudyn_two_link.run(n, h, t_end, newton_rtol=tol), "newton_rtol": tol}
        except Exception as e:      # Exudyn raises its own SolverError
            failure = e
    raise failure


def exudyn_pair(n, t1):
    """Exudyn's runs to t1 and 2 t1 at one Newton tolerance: the longer run is likelier to
    stall, and a pair whose runs took different tolerances would subtract unlike steps (a
    step at 1e-5 costs fewer iterations than one at 1e-6)."""
    r2 = run_exudyn(n, DT, 2 * t1)
    r1 = run_exudyn(n, DT, t1, (r2["newton_rtol"], 1e-5, 1e-4))
    if r1["newton_rtol"] != r2["newton_rtol"]:
        r2 = run_exudyn(n, DT, 2 * t1, (r1["newton_rtol"],))
    return r1, r2


def fit_exponent(ns, times):
    pts = [(math.log(n), math.log(t)) for n, t in zip(ns, times)
           if 8 <= n <= 128 and t and t > 0 and math.isfinite(t)]
    if len(pts) < 2:
        return float("nan")
    x, y = np.array(pts).T
    return float(np.polyfit(x, y, 1)[0])


def header(args, argv) -> list[str]:
    exu = exudyn_two_link.version() if exudyn_two_link.available() else "not installed"
    version = (ROOT / "VERSION").read_text().strip()
    return [f"Command: `{command_line('scripts/bench_scaling.py', argv)}`",
            f"Date: {datetime.now().strftime('%Y-%m-%d %H:%M')}; machine: {cpu_model()}, "
            f"{usable_cores()} cores; flexmor {version}, commit {git_commit(ROOT)}; Exudyn {exu}."]


def ms(x):
    return "–" if x is None or not math.isfinite(x) else f"{1e3 * x:.3f}"


def scaling(args, binary, work, argv):
    rows, failed = [], False
    use_exudyn = not args.no_exudyn and exudyn_two_link.available()
    galpha = f"integrator = 'galpha', dt = {DT!r}"
    for n in args.meshes:
        row = {"elements_per_link": n}
        row["exudyn_ms"] = float("nan")
        beside = use_exudyn and n <= args.exudyn_max
        if beside:
            try:
                (t, te, row["full_over_exudyn"], row["full_rss_mib"], row["n_dy"],
                 row["exudyn_newton_rtol"]) = full_beside_exudyn(binary, work, n, galpha,
                                                                 args.t_end, args.repeat)
                row["full_ms"], row["exudyn_ms"] = 1e3 * t, 1e3 * te
            except (RunFailed, subprocess.TimeoutExpired) as e:
                row["full_ms"] = float("nan")
                row["full_error"] = str(e)
                failed = True
            except Exception as e:     # Exudyn raises its own SolverError
                row["exudyn_error"] = last_line(str(e))
                beside = False
        for k, label in ((0, "full"), (2, "k2"), (4, "k4"), (4, "k4x")):
            if label == "full" and "full_ms" in row:
                continue
            try:
                t1 = args.t_end * (EXPANDED_WINDOW if label == "k4x" else 1)
                t, rss, n_dy = per_step_flexmor(binary, work, f"s{n}_{label}", n, galpha, k,
                                                t1, args.repeat, label == "k4x")
                row[f"{label}_ms"] = 1e3 * t
                row[f"{label}_rss_mib"] = rss
                row["n_dy"] = n_dy
            except (RunFailed, subprocess.TimeoutExpired) as e:
                row[f"{label}_ms"] = float("nan")
                row[f"{label}_error"] = str(e)
                failed = True
        if not beside:
            row["full_over_exudyn"] = float("nan")
        rows.append(row)
        print(f"n = {n:4d}: full {row['full_ms']:.4f} ms, k=2 {row.get('k2_ms', math.nan):.4f}, "
              f"k=4 {row.get('k4_ms', math.nan):.4f}, k=4 expanded "
              f"{row.get('k4x_ms', math.nan):.4f}, Exudyn {row['exudyn_ms']:.4f} ms/step",
              flush=True)
    ns = [r["elements_per_link"] for r in rows]
    expo = {key: fit_exponent(ns, [r.get(f"{key}_ms", math.nan) for r in rows])
            for key in ("full", "k2", "k4", "k4x", "exudyn")}
    columns = ["elements_per_link", "n_dy", "full_ms", "k2_ms", "k4_ms", "k4x_ms", "exudyn_ms",
               "exudyn_newton_rtol", "full_over_exudyn", "full_rss_mib", "k2_rss_mib", "k4_rss_mib", "k4x_rss_mib",
               "full_error", "k2_error", "k4_error", "k4x_error", "exudyn_error"]
    write_csv(rows, columns, args.out_dir / "scaling.csv")
    lines = ["# Time per step against model size (two-link benchmark)", "", *header(args, argv),
             "", f"Generalized-alpha, fixed step {DT} s, rho_inf 0.8; processor time per step from runs "
             f"to {args.t_end} and {2 * args.t_end} s (set-up cancels), run in pairs back to back: the median of "
             f"{args.repeat} pairs. The full model's pairs alternate with Exudyn's, and full / Exudyn "
             "is the median of those rounds' ratios (the machine's drift falls on both alike). "
             "Exudyn: planar geometrically "
             "exact beams, its generalized-alpha at the same step, sparse solver "
             "(python/flexmor/exudyn_two_link.py); its Newton relative tolerance is 1e-6, "
             "loosened to 1e-5 or 1e-4 where it stalls (from 32 elements per link), the same "
             "for both runs of a pair (column Newton rtol: the loosest a pair needed; a looser "
             "tolerance takes fewer iterations per step).", "",
             "k = 4 expanded: `&reduction evaluation = 'expanded'` (docs/theory.md section 9); "
             "its time per step includes the expansions made in the window, which is "
             f"{EXPANDED_WINDOW} times longer (runs to {EXPANDED_WINDOW * args.t_end:g} and "
             f"{2 * EXPANDED_WINDOW * args.t_end:g} s): its steps cost about 1 % of the full "
             "model's.", "",
             "| elements per link | n_dy | full [ms] | k = 2 [ms] | k = 4 [ms] | "
             "k = 4 expanded [ms] | Exudyn [ms] | Newton rtol | full / Exudyn | peak RSS full [MiB] |",
             "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for r in rows:
        ratio = r["full_over_exudyn"]
        tol = f"{r['exudyn_newton_rtol']:g}" if "exudyn_newton_rtol" in r else "–"
        lines.append(f"| {r['elements_per_link']} | {r.get('n_dy', '–')} | {ms(r['full_ms'] / 1e3)} | "
                     f"{ms(r.get('k2_ms', math.nan) / 1e3)} | {ms(r.get('k4_ms', math.nan) / 1e3)} | "
                     f"{ms(r.get('k4x_ms', math.nan) / 1e3)} | "
                     f"{ms(r['exudyn_ms'] / 1e3)} | {tol} | "
                     f"{'–' if not math.isfinite(ratio) else f'{ratio:.2f}'} | "
                     f"{r.get('full_rss_mib', math.nan):.0f} |")
    lines += ["", "Fitted exponent p of time per step ~ n^p over 8 <= n <= 128: " + ", ".join(
        f"{k} {v:.2f}" for k, v in expo.items() if math.isfinite(v)) + "."]
    errors = [(r["elements_per_link"], key, r[key]) for r in rows for key in r if key.endswith("_error")]
    if errors:
        lines += ["", "Failed runs:"] + [f"- n = {n}, {key[:-6]}: {msg}" for n, key, msg in errors]
    (args.out_dir / "scaling.md").write_text("\n".join(lines) + "\n")
    plot_scaling(rows, args.out_dir / "scaling.png")
    return failed


def plot_scaling(rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 4.2))
    ns = [r["elements_per_link"] for r in rows]
    for key, label in (("full_ms", "flexmor full"), ("k2_ms", "flexmor k = 2"),
                       ("k4_ms", "flexmor k = 4"), ("k4x_ms", "flexmor k = 4 expanded"),
                       ("exudyn_ms", "Exudyn")):
        ys = [r.get(key, math.nan) for r in rows]
        if any(math.isfinite(y) for y in ys):
            ax.loglog(ns, ys, "o-", label=label)
    ax.set_xlabel("beam elements per link")
    ax.set_ylabel("time per step [ms]")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def whole_runs(args, binary, work, argv):
    """Whole runs of the scene's own analysis (0.7 s, generalized-alpha with error control at
    rtol 1e-6) at each mesh: the full model, k = 4 with the full evaluation and k = 4 expanded;
    times, steps, expansions and the reduced runs' tip distance from the full run."""
    rows, failed = [], False
    t_end = 0.02 if args.quick else 0.7
    for n in args.whole_meshes:
        row = {"elements_per_link": n}
        paths = {}
        for k, label in ((0, "full"), (4, "k4"), (4, "k4x")):
            text = scene(n, "", k, expanded=label == "k4x").replace("t_end = 0.7",
                                                                    f"t_end = {t_end!r}")
            try:
                attrs, _, paths[label] = min((run_flexmor(binary, work, f"w{n}_{label}", text)
                                              for _ in range(args.repeat)),
                                             key=lambda r: solve_time(r[0]))
                row[f"{label}_s"] = solve_time(attrs)
                row[f"{label}_steps"] = int(attrs["n_steps"])
            except (RunFailed, subprocess.TimeoutExpired) as e:
                row[f"{label}_s"] = float("nan")
                row[f"{label}_error"] = str(e)
                failed = True
        if "full" in paths:
            t_full, xyz_full = load_node_path(paths["full"], "tip")
            for label in ("k4", "k4x"):
                if label in paths:
                    t, xyz = load_node_path(paths[label], "tip")
                    row[f"{label}_tip_m"] = tip_error(t_full, xyz_full[:, :2], t, xyz[:, :2])
        if "k4x" in paths:
            with h5py.File(paths["k4x"]) as f:
                row["n_expansions"] = int(f["reduction"].attrs["n_expansions"])
        row["full_over_k4x"] = row["full_s"] / row["k4x_s"]
        rows.append(row)
        print(f"n = {n:4d}: whole run full {row['full_s']:.3f} s, k=4 {row['k4_s']:.3f} s, "
              f"k=4 expanded {row['k4x_s']:.3f} s", flush=True)
    columns = ["elements_per_link", "full_s", "full_steps", "k4_s", "k4_steps", "k4_tip_m",
               "k4x_s", "k4x_steps", "k4x_tip_m", "n_expansions", "full_over_k4x",
               "full_error", "k4_error", "k4x_error"]
    write_csv(rows, columns, args.out_dir / "whole_runs.csv")
    lines = ["# Whole runs: full model, reduced (k = 4) and reduced with the expanded evaluation",
             "", *header(args, argv), "",
             f"input/two_link.nml with n beam elements per link and its own analysis ({t_end} s, "
             "generalized-alpha with error control, rtol 1e-6); processor time of the analyses "
             "(the basis included), least of the repeats. Tip: largest distance of the reduced "
             "run's tip from the full run's at the same mesh.", "",
             "| elements per link | full [s] | steps | k = 4 [s] | steps | tip [m] | "
             "k = 4 expanded [s] | steps | tip [m] | expansions | full / expanded |",
             "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for r in rows:
        lines.append(
            f"| {r['elements_per_link']} | {r['full_s']:.3f} | {r.get('full_steps', '–')} | "
            f"{r['k4_s']:.3f} | {r.get('k4_steps', '–')} | {r.get('k4_tip_m', math.nan):.1e} | "
            f"{r['k4x_s']:.3f} | {r.get('k4x_steps', '–')} | {r.get('k4x_tip_m', math.nan):.1e} | "
            f"{r.get('n_expansions', '–')} | {r['full_over_k4x']:.1f} |")
    (args.out_dir / "whole_runs.md").write_text("\n".join(lines) + "\n")
    return failed


def tip_error(t_ref, xy_ref, t, xy):
    x = np.interp(t_ref, t, xy[:, 0])
    y = np.interp(t_ref, t, xy[:, 1])
    return float(np.max(np.hypot(x - xy_ref[:, 0], y - xy_ref[:, 1])))


def work_precision(args, binary, work, argv):
    t_end = 0.7
    ref_dyn = "integrator = 'galpha', dt = 2e-5"
    _, _, ref_path = run_flexmor(binary, work, "ref32", scene(32, ref_dyn, 0, t_end))
    t_ref, xyz = load_node_path(ref_path, "tip")
    xy_ref = xyz[:, :2]
    _, _, check = run_flexmor(binary, work, "ref16", scene(16, ref_dyn, 0, t_end))
    t16, xyz16 = load_node_path(check, "tip")
    ref_check = tip_error(t_ref, xy_ref, t16, xyz16[:, :2])
    configs = []
    for n in (1, 2, 3, 4, 8):
        for order in (2, 5):
            for rtol in (1e-3, 1e-4, 1e-5, 1e-6):
                configs.append((n, f"bdf order {order}, rtol {rtol:g}",
                                f"integrator = 'bdf', max_order = {order}, rtol = {rtol!r}, "
                                f"atol = {rtol * 1e-2!r}"))
        for rtol in (1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 1e-6, 1e-7):
            configs.append((n, f"galpha_adaptive, rtol {rtol:g}",
                            f"integrator = 'galpha_adaptive', rtol = {rtol!r}, atol = {rtol * 1e-2!r}"))
        for dt in (1e-3, 5e-4, 2e-4, 1e-4):
            configs.append((n, f"galpha, dt {dt:g}", f"integrator = 'galpha', dt = {dt!r}"))
    rows, failed = [], False
    for n, label, dyn in configs:
        try:
            attrs, _, path = run_flexmor(binary, work, "wp", scene(n, dyn, 0, t_end))
            t, xyz = load_node_path(path, "tip")
            rows.append({"code": "flexmor", "elements_per_link": n, "settings": label,
                         "time_s": solve_time(attrs), "steps": attrs["n_steps"],
                         "tip_error_m": tip_error(t_ref, xy_ref, t, xyz[:, :2])})
        except (RunFailed, subprocess.TimeoutExpired) as e:
            rows.append({"code": "flexmor", "elements_per_link": n, "settings": label,
                         "error": str(e)})
            failed = True
        print(rows[-1], flush=True)
    if not args.no_exudyn and exudyn_two_link.available():
        for n in (6, 8, 10, 12, 16, 24, 32, 48):
            for h in (1e-3, 5e-4, 2e-4, 1e-4):
                try:
                    r = run_exudyn(n, h, t_end)
                    rows.append({"code": "Exudyn", "elements_per_link": n,
                                 "settings": f"generalized-alpha, h {h:g}"
                                             + (f", Newton rtol {r['newton_rtol']:g}" if r["newton_rtol"] > 1e-6
                                                else ""),
                                 "time_s": r["cpu_s"],
                                 "steps": r["n_steps"],
                                 "tip_error_m": tip_error(t_ref, xy_ref, r["time"], r["tip"])})
                except Exception as e:
                    rows.append({"code": "Exudyn", "elements_per_link": n,
                                 "settings": f"generalized-alpha, h {h:g}", "error": last_line(str(e))})
                print(rows[-1], flush=True)
    columns = ["code", "elements_per_link", "settings", "time_s", "steps", "tip_error_m", "error"]
    write_csv(rows, columns, args.out_dir / "work_precision.csv")
    lines = ["# Work against precision (two-link benchmark, 0.7 s)", "", *header(args, argv), "",
             "Tip error: largest distance over time from a converged solution (flexmor, 32 "
             f"elements per link, generalized-alpha dt 2e-5 s; the 16-element run is {ref_check:.1e} m "
             "from it). Time: flexmor's processor time of the analyses, Exudyn's SolveDynamic process time.", "",
             "| target [m] | flexmor fastest | time [s] | Exudyn fastest | time [s] | Exudyn / flexmor |",
             "| --- | --- | --- | --- | --- | --- |"]
    for target in TARGETS:
        best = {}
        for code in ("flexmor", "Exudyn"):
            ok = [r for r in rows if r["code"] == code and r.get("tip_error_m", math.inf) <= target]
            best[code] = min(ok, key=lambda r: r["time_s"]) if ok else None
        f, e = best["flexmor"], best["Exudyn"]
        ratio = f"{e['time_s'] / f['time_s']:.1f}" if e and f else "–"
        lines.append(f"| {target:g} | {config_text(f)} | {time_text(f)} | "
                     f"{config_text(e) if e else 'none reached'} | {time_text(e)} | {ratio} |")
    lines += ["", "All runs (sorted by code, mesh, time):", "",
              "| code | elements per link | settings | time [s] | steps | tip error [m] |",
              "| --- | --- | --- | --- | --- | --- |"]
    for r in sorted(rows, key=lambda r: (r["code"], r["elements_per_link"], r.get("time_s", 1e9))):
        lines.append(f"| {r['code']} | {r['elements_per_link']} | {r['settings']} | "
                     f"{r.get('time_s', math.nan):.3f} | {r.get('steps', '–')} | "
                     f"{r.get('tip_error_m', math.nan):.2e} |" if "error" not in r else
                     f"| {r['code']} | {r['elements_per_link']} | {r['settings']} | failed: "
                     f"{r['error']} | | |")
    (args.out_dir / "work_precision.md").write_text("\n".join(lines) + "\n")
    plot_work_precision(rows, args.out_dir / "work_precision.png")
    return failed


def config_text(row):
    return f"{row['elements_per_link']} el., {row['settings']}" if row else "–"


def time_text(row):
    return f"{row['time_s']:.3f}" if row else "–"


def plot_work_precision(rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    groups = {}
    for r in rows:
        if "tip_error_m" not in r:
            continue
        method = r["settings"].split(",")[0]
        groups.setdefault((r["code"], method), []).append(r)
    for (code, method), rs in sorted(groups.items()):
        ax.loglog([r["time_s"] for r in rs], [r["tip_error_m"] for r in rs],
                  "o" if code == "flexmor" else "s", label=f"{code} {method}", alpha=0.7)
    for target in TARGETS:
        ax.axhline(target, color="gray", lw=0.5)
    ax.set_xlabel("solve time [s]")
    ax.set_ylabel("tip error [m]")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def parse(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--bin", type=Path, default=ROOT / "build" / "bin" / "flexmor")
    p.add_argument("--out-dir", type=Path, default=ROOT / "docs" / "bench")
    p.add_argument("--meshes", default="2,3,4,8,16,32,64,128")
    p.add_argument("--whole-meshes", default="3,8,16,32,64",
                   help="meshes of the whole-run comparison (--whole-runs)")
    p.add_argument("--whole-runs", action="store_true")
    p.add_argument("--t-end", type=float, default=0.1)
    p.add_argument("--exudyn-max", type=int, default=64)
    p.add_argument("--no-exudyn", action="store_true")
    p.add_argument("--work-precision", action="store_true")
    p.add_argument("--quick", action="store_true")
    p.add_argument("--repeat", type=int, default=3,
                   help="pairs of runs per time per step (their median counts) and runs per whole "
                        "run (the least counts); default 3")
    args = p.parse_args(argv)
    try:
        args.meshes = [int(m) for m in args.meshes.split(",")]
        args.whole_meshes = [int(m) for m in args.whole_meshes.split(",")]
    except ValueError:
        p.exit(2, f"bench_scaling.py: --meshes and --whole-meshes must be integers separated "
                  f"by commas, got '{args.meshes}', '{args.whole_meshes}'\n")
    if any(m < 1 for m in args.meshes + args.whole_meshes) or not args.t_end > 0 or \
            args.repeat < 1:
        p.exit(2, "bench_scaling.py: meshes must be >= 1, --t-end > 0 and --repeat >= 1\n")
    if not args.bin.exists():
        p.exit(2, f"bench_scaling.py: no flexmor binary at {args.bin} (build it or give --bin)\n")
    if args.quick:
        args.meshes, args.t_end, args.work_precision, args.repeat = [2, 4], 0.004, False, 1
        args.whole_meshes = [2]
    return args


def main(argv=None):
    args = parse(argv)
    args.out_dir.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="flexmor_bench_") as tmp:
        work = Path(tmp)
        failed = scaling(args, args.bin, work, argv)
        if args.whole_runs:
            failed = whole_runs(args, args.bin, work, argv) or failed
        if args.work_precision:
            failed = work_precision(args, args.bin, work, argv) or failed
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
