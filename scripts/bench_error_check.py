#!/usr/bin/env python3
"""How well &dynamic error_check measures a run's global error, and what it costs, on the
two-link arm (input/two_link.nml: 3 beam elements per link, quarter turns in 0.5 s, 0.7 s).

Tolerance check: for each integrator (galpha_adaptive, bdf) and rtol (--rtols; atol = rtol /
100), a run with error_check = 'tolerance' (the second run at rtol / 10) against a reference
(bdf at rtol 1e-11; galpha_adaptive at rtol 1e-10 bounds its error): the true error (the
largest distance of the output nodes, tip and elbow, from the reference's), the check's largest
distance (over all nodes), their ratio,
and the processor time of the run and of its check. Theory (docs/theory.md 6.2): with a global
error ~ rtol^p the ratio tends to 1 - 10^-p, 0.78 for galpha_adaptive (p = 2/3).

Modes check: reduced runs with n_modes = --modes and error_check = 'modes' (2 more modes)
against the full model at rtol 1e-6, beside the reduction's local error estimate.

Mesh check: --meshes elements per link with error_check = 'mesh' (twice the elements) at
rtol 1e-7, against 24 elements per link; distances at the &node points (elbow, tip).

Usage (the flexmor Python package installed, or PYTHONPATH=python):

    python3 scripts/bench_error_check.py [--bin build/bin/flexmor] [--out-dir docs/bench] \\
        [--rtols 1e-3,1e-4,1e-5,1e-6] [--modes 1,2,4] [--meshes 2,3,4] [--quick]

--quick: 0.1 s of motion, rtol 1e-3, 1 mode and 2 elements per link (for the tests). Writes
error_check.md and error_check.csv into --out-dir with the command, date, machine, flexmor
version and commit. Bad arguments exit with 2, a failed run with 1.
"""
from __future__ import annotations

import argparse
import math
import subprocess
import sys
import tempfile
from datetime import datetime
from pathlib import Path

import numpy as np

from flexmor.bench import command_line, cpu_model, git_commit, usable_cores, write_csv
from flexmor.results import distance_from, read_result

ROOT = Path(__file__).resolve().parents[1]
PROG = "bench_error_check.py"
DYNAMIC = "&dynamic t_end = 0.7, output_dt = 1.0e-3, rtol = 1.0e-6, atol = 1.0e-8 /"


def scene(dynamic: str, reduction: str = "", t_end: float = 0.7, n: int = 3) -> str:
    """input/two_link.nml without &modal, with n beam elements per link, the &dynamic line
    `dynamic` (its T_END replaced) and an optional &reduction line."""
    text = (ROOT / "input" / "two_link.nml").read_text()
    if DYNAMIC not in text or "&modal n_modes = 12 /" not in text or \
            text.count("n_elements = 3") != 2:
        raise RuntimeError("input/two_link.nml's &dynamic, &modal or n_elements changed: "
                           f"update {PROG}")
    text = text.replace("&modal n_modes = 12 /", "").replace("n_elements = 3",
                                                              f"n_elements = {n}")
    return text.replace(DYNAMIC, reduction + "\n" + dynamic.replace("T_END", repr(t_end)))


def run(binary: Path, work: Path, name: str, text: str):
    """Run a scene; returns the Result."""
    nml, out = work / f"{name}.nml", work / f"{name}.h5"
    nml.write_text(text)
    proc = subprocess.run([str(binary), "-q", str(nml), "-o", str(out)], capture_output=True,
                          text=True, timeout=3600)
    if proc.returncode != 0:
        raise RuntimeError(f"{name}: {proc.stderr.strip()}")
    return read_result(out)


def check_row(result, reference) -> dict:
    true, _ = distance_from(result, reference)
    check = result.error_check
    cpu = float(result.attrs["cpu_time_s"])
    check_cpu = float(check["attrs"]["cpu_time_s"])
    row = {"true_m": float(true.max()), "check_m": float(check["distance"].max()),
           "run_s": cpu - check_cpu, "check_s": check_cpu,
           "steps": int(result.attrs["n_steps"]), "check_steps": int(check["attrs"]["n_steps"])}
    row["ratio"] = row["check_m"] / row["true_m"] if row["true_m"] > 0 else math.nan
    return row


def bench(args, work: Path) -> list[dict]:
    rows = []
    t_end = 0.1 if args.quick else 0.7
    ref = run(args.bin, work, "reference", scene(
        "&dynamic t_end = T_END, rtol = 1e-11, atol = 1e-13, integrator = 'bdf' /",
        t_end=t_end))
    # A second reference by the other method: their distance bounds the reference's error.
    other = run(args.bin, work, "reference2", scene(
        "&dynamic t_end = T_END, rtol = 1e-10, atol = 1e-12, integrator = 'galpha_adaptive' /",
        t_end=t_end))
    args.reference_m = float(distance_from(other, ref)[0].max())
    for integrator in ("galpha_adaptive", "bdf"):
        for rtol in args.rtols:
            result = run(args.bin, work, f"{integrator}_{rtol:g}", scene(
                f"&dynamic t_end = T_END, rtol = {rtol!r}, atol = {rtol / 100!r}, "
                f"integrator = '{integrator}', error_check = 'tolerance' /", t_end=t_end))
            row = {"kind": "tolerance", "setting": f"{integrator}, rtol {rtol:g}"}
            row.update(check_row(result, ref))
            rows.append(row)
            print(f"{row['setting']}: true {row['true_m']:.2e} m, check {row['check_m']:.2e} m, "
                  f"ratio {row['ratio']:.2f}", flush=True)
    full = run(args.bin, work, "full", scene("&dynamic t_end = T_END /", t_end=t_end))
    for k in args.modes:
        result = run(args.bin, work, f"k{k}", scene(
            "&dynamic t_end = T_END, error_check = 'modes' /", f"&reduction n_modes = {k} /",
            t_end=t_end))
        row = {"kind": "modes", "setting": f"{k} mode{'s' if k > 1 else ''} (check: {k + 2})"}
        row.update(check_row(result, full))
        row["estimate_m"] = float(result.reduction["attrs"].get("error_estimate_max", math.nan))
        rows.append(row)
        print(f"{row['setting']}: true {row['true_m']:.2e} m, check {row['check_m']:.2e} m, "
              f"ratio {row['ratio']:.2f}, local estimate {row['estimate_m']:.2e} m", flush=True)
    fine = run(args.bin, work, "mesh_reference", scene(
        "&dynamic t_end = T_END, rtol = 1e-7, atol = 1e-9 /", t_end=t_end, n=24))
    for n in args.meshes:
        result = run(args.bin, work, f"mesh{n}", scene(
            "&dynamic t_end = T_END, rtol = 1e-7, atol = 1e-9, error_check = 'mesh' /",
            t_end=t_end, n=n))
        row = {"kind": "mesh", "setting": f"{n} elements per link (check: {2 * n})"}
        row.update(check_row(result, fine))
        rows.append(row)
        print(f"{row['setting']}: true {row['true_m']:.2e} m, check {row['check_m']:.2e} m, "
              f"ratio {row['ratio']:.2f}", flush=True)
    return rows


def write_tables(args, argv, rows):
    columns = ["kind", "setting", "true_m", "check_m", "ratio", "estimate_m", "run_s", "check_s",
               "steps", "check_steps"]
    write_csv(rows, columns, args.out_dir / "error_check.csv")
    version = (ROOT / "VERSION").read_text().strip()
    lines = ["# Error check: the second run's distance against the true error", "",
             f"Command: `{command_line('scripts/' + PROG, argv)}`",
             f"Date: {datetime.now().strftime('%Y-%m-%d %H:%M')}; machine: {cpu_model()}, "
             f"{usable_cores()} cores; flexmor {version}, commit {git_commit(ROOT)}.", "",
             "input/two_link.nml (3 beam elements per link), "
             f"{0.1 if args.quick else 0.7} s. True error: largest distance of the output "
             "nodes (tip, elbow) from a reference (tolerance: bdf at rtol 1e-11, "
             f"{args.reference_m:.1e} m from galpha_adaptive at rtol 1e-10; modes: the full "
             "model at rtol 1e-6; mesh: 24 elements per link at rtol 1e-7, at the &node points). "
             "Check: largest distance of all nodes (mesh: the &node points) from the second run "
             "(tolerance: rtol and atol / 10; modes: 2 more; mesh: twice the elements). Times: "
             "processor time of the run and of its check.", "",
             "| check | run | true error [m] | check [m] | check / true | local estimate [m] | "
             "run [s] | check [s] | steps | check's steps |",
             "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for r in rows:
        est = r.get("estimate_m")
        lines.append(f"| {r['kind']} | {r['setting']} | {r['true_m']:.2e} | {r['check_m']:.2e} | "
                     f"{r['ratio']:.2f} | {'–' if est is None else f'{est:.2e}'} | "
                     f"{r['run_s']:.3f} | {r['check_s']:.3f} | {r['steps']} | "
                     f"{r['check_steps']} |")
    (args.out_dir / "error_check.md").write_text("\n".join(lines) + "\n")


def parse_args(argv):
    p = argparse.ArgumentParser(prog=PROG, description=__doc__.splitlines()[0])
    p.add_argument("--bin", type=Path, default=ROOT / "build" / "bin" / "flexmor")
    p.add_argument("--out-dir", type=Path, default=ROOT / "docs" / "bench")
    p.add_argument("--rtols", default="1e-3,1e-4,1e-5,1e-6")
    p.add_argument("--modes", default="1,2,4")
    p.add_argument("--meshes", default="2,3,4")
    p.add_argument("--quick", action="store_true")
    args = p.parse_args(argv)
    try:
        args.rtols = [float(x) for x in args.rtols.split(",")]
        args.modes = [int(x) for x in args.modes.split(",")]
        args.meshes = [int(x) for x in args.meshes.split(",")]
    except ValueError:
        p.exit(2, f"{PROG}: --rtols, --modes and --meshes must be numbers separated by commas, "
                  f"got '{args.rtols}', '{args.modes}', '{args.meshes}'\n")
    if not all(0 < r < 1 for r in args.rtols) or not all(k >= 1 for k in args.modes) or \
            not all(1 <= n <= 12 for n in args.meshes):
        p.exit(2, f"{PROG}: --rtols must lie in (0, 1), --modes be >= 1 and --meshes 1 to 12 "
                  f"(the reference has 24)\n")
    if not args.bin.is_file():
        p.exit(2, f"{PROG}: no flexmor executable at {args.bin} (--bin)\n")
    if not args.out_dir.is_dir():
        p.exit(2, f"{PROG}: --out-dir {args.out_dir} is not a folder\n")
    if args.quick:
        args.rtols, args.modes, args.meshes = [1e-3], [1], [2]
    args.reference_m = math.nan
    return args


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    args = parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="flexmor_bench_check_") as tmp:
        try:
            rows = bench(args, Path(tmp))
        except (RuntimeError, subprocess.TimeoutExpired) as exc:
            print(f"{PROG}: a run failed: {exc}", file=sys.stderr)
            return 1
    write_tables(args, argv, rows)
    print(f"wrote {args.out_dir / 'error_check.md'}, error_check.csv")
    return 0


if __name__ == "__main__":
    sys.exit(main())
