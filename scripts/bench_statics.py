#!/usr/bin/env python3
"""Cost of a static analysis against model size: Bathe and Bolourchi's 45-degree bend
(input/bend45.nml: tip force raised to 600 in 4 load steps) with n beams, solved by Newton with
the dense difference tangent (&static solver = 'dense') and by Newton-Krylov ('krylov'),
docs/theory.md 7.3; and the linearised lateral-torsional buckling of a narrow cantilever
(input/lateral_buckling.nml's scene with n beams) by the dense eigenproblem and matrix-free
(&buckling solver); and the leaf-spring guide (input/leaf_spring_guide.nml with n elements per
leaf, elastic modes closing its loop) followed by arc-length continuation with the shuttle's
compliance at each step, on both paths.

Per mesh and solver: the processor time of the analysis (root attribute ``cpu_time_s``, the
least of --repeat runs), the Newton iterations, the products with the tangent (Krylov), and the
tip after the last step against the finest Krylov run. The exponent p of time ~ n^p is fitted by
least squares in log-log over the meshes of each solver from 16 beams on.

Usage (the flexmor Python package installed, or PYTHONPATH=python):

    python3 scripts/bench_statics.py [--bin build/bin/flexmor] [--out-dir docs/bench] \\
        [--meshes 8,16,32,64,128,256] [--dense-max 64] [--repeat 2] \\
        [--guide-meshes 8,16,32,64,128]

Writes statics.md, statics.csv and statics_guide.csv into --out-dir with the command, date, machine, flexmor
version and commit. Bad arguments exit with 2, a failed run with 1.
"""
from __future__ import annotations

import argparse
import math
import re
import subprocess
import sys
import tempfile
from datetime import datetime
from pathlib import Path

import h5py
import numpy as np

from flexmor.bench import command_line, cpu_model, git_commit, usable_cores, write_csv
from flexmor.results import run_attributes
from compliant_examples import mesh as guide_mesh
from spatial_examples import bend45_scene, lateral_buckling_scene

ROOT = Path(__file__).resolve().parents[1]


def run_scene(binary, folder, name, text, *options):
    """Write the scene `name`.nml into folder and run it: (stdout, the result's path)."""
    nml, out = Path(folder) / f"{name}.nml", Path(folder) / f"{name}.h5"
    nml.write_text(text)
    proc = subprocess.run([str(binary), str(nml), "-o", str(out), *options],
                          capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"{nml.name}: {proc.stderr.strip()}")
    return proc.stdout, out


def products_of(stdout):
    """The tangent products a Newton-Krylov run reported (0 on the dense path)."""
    found = re.search(r"Newton-Krylov: (\d+) products", stdout)
    return int(found.group(1)) if found else 0


def run_once(binary, folder, n, solver):
    """One run: cpu time [s], Newton iterations, tangent products, tip after the last step."""
    text = bend45_scene(n).replace("&static n_steps = 4 /",
                                   f"&static n_steps = 4, solver = '{solver}' /")
    if f"solver = '{solver}'" not in text:
        raise RuntimeError("the bend scene's &static line changed: update bench_statics.py")
    stdout, out = run_scene(binary, folder, f"bend_{solver}_{n}", text)
    line = next(s for s in stdout.splitlines() if s.startswith("static:"))
    iterations = int(re.search(r"(\d+) Newton iterations", line).group(1))
    with h5py.File(out) as f:
        tip = f["static/nodes/tip/position"][-1]
    return float(run_attributes(out)["cpu_time_s"]), iterations, products_of(line), tip


def buckling_once(binary, folder, n, solver):
    """One buckling run: cpu time [s] and the lowest multiplier [N]."""
    text = lateral_buckling_scene(n).replace("&buckling ", f"&buckling solver = '{solver}', ")
    _, out = run_scene(binary, folder, f"ltb_{solver}_{n}", text, "-q")
    with h5py.File(out) as f:
        mu = float(f["buckling/load_factor"][0])
    return float(run_attributes(out)["cpu_time_s"]), mu


def guide_once(binary, folder, n, solver):
    """The leaf-spring guide with n elements per leaf, 11 arc-length steps with the shuttle's
    compliance: cpu time [s], products, the last load factor and compliance x-x [m/N]."""
    text = guide_mesh((ROOT / "input" / "leaf_spring_guide.nml").read_text(), n).replace(
        "&static n_steps = 11 /", f"&static n_steps = 11, method = 'arc_length', "
        f"solver = '{solver}' /")
    if "method = 'arc_length'" not in text:
        raise RuntimeError("the guide's &static line changed: update bench_statics.py")
    stdout, out = run_scene(binary, folder, f"guide_{solver}_{n}", text)
    with h5py.File(out) as f:
        lam = float(f["static/load_factor"][-1])
        cxx = float(f["static/nodes/shuttle/compliance"][-1, 0, 0])
    return float(run_attributes(out)["cpu_time_s"]), products_of(stdout), lam, cxx


def guide_section(rows):
    """The guide's table (markdown lines)."""
    lines = ["", "## Compliant mechanism: arc-length and compliance", "",
             "The leaf-spring guide (input/leaf_spring_guide.nml with n elements per leaf), 11 "
             "arc-length steps under its shuttle load, the shuttle's tangent compliance at each "
             "step (docs/theory.md 7.1, 7.2). The load factor after 11 steps depends on each "
             "path's scale c = |K_T^-1 P|; the compliance x-x at that step is the soft stroke "
             "direction's.", "",
             "| elements per leaf | dynamic coordinates | solver | cpu [s] | tangent products | "
             "last load factor | compliance x-x [m/N] |", "| --- | --- | --- | --- | --- | --- | --- |"]
    for r in rows:
        lines.append(f"| {r['elements']} | {6 * r['elements'] - 3} | {r['solver']} | "
                     f"{r['cpu_s']:.3f} | {r['products'] or '-'} | {r['lambda']:.6f} | "
                     f"{r['cxx']:.6e} |")
    return lines


def fit_exponent(ns, times):
    keep = [(n, t) for n, t in zip(ns, times) if n >= 16]
    if len(keep) < 2:
        return float("nan")
    x, y = np.log([k[0] for k in keep]), np.log([k[1] for k in keep])
    return float(np.polyfit(x, y, 1)[0])


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--bin", type=Path, default=ROOT / "build" / "bin" / "flexmor")
    p.add_argument("--out-dir", type=Path, default=ROOT / "docs" / "bench")
    p.add_argument("--meshes", default="8,16,32,64,128,256")
    p.add_argument("--dense-max", type=int, default=64)
    p.add_argument("--repeat", type=int, default=2)
    p.add_argument("--guide-meshes", default="8,16,32,64,128",
                   help="elements per leaf of the leaf-spring guide (dense up to --dense-max)")
    args = p.parse_args(argv)
    try:
        meshes = [int(s) for s in args.meshes.split(",")]
        guide_meshes = [int(s) for s in args.guide_meshes.split(",")]
    except ValueError:
        p.error(f"--meshes, --guide-meshes: comma-separated integers expected, got "
                f"{args.meshes!r}, {args.guide_meshes!r}")
    if any(n < 1 for n in meshes) or any(n < 2 for n in guide_meshes) or args.repeat < 1:
        p.error("--meshes and --repeat must be >= 1, --guide-meshes >= 2")
    if not args.bin.is_file():
        p.error(f"--bin: no flexmor binary at {args.bin}")
    rows, buckling = [], []
    with tempfile.TemporaryDirectory() as folder:
        try:
            for n in meshes:
                for solver in ("dense", "krylov"):
                    if solver == "dense" and n > 2 * args.dense_max:
                        continue
                    runs = [buckling_once(args.bin, folder, n, solver)
                            for _ in range(args.repeat)]
                    buckling.append(dict(beams=n, solver=solver,
                                         cpu_s=min(r[0] for r in runs), mu=runs[0][1]))
                    print(f"{n:4d} beams buckling {solver:6s} {buckling[-1]['cpu_s']:8.3f} s  "
                          f"mu {runs[0][1]:.6f} N", flush=True)
            for n in meshes:
                for solver in ("dense", "krylov"):
                    if solver == "dense" and n > args.dense_max:
                        continue
                    runs = [run_once(args.bin, folder, n, solver) for _ in range(args.repeat)]
                    cpu = min(r[0] for r in runs)
                    _, iterations, products, tip = runs[0]
                    rows.append(dict(beams=n, solver=solver, cpu_s=cpu, newton=iterations,
                                     products=products, tip=tip))
                    print(f"{n:4d} beams {solver:6s} {cpu:8.3f} s  {iterations} Newton "
                          f"iterations, {products} products", flush=True)
            guide = []
            for n in guide_meshes:
                for solver in ("dense", "krylov"):
                    if solver == "dense" and n > args.dense_max:
                        continue
                    runs = [guide_once(args.bin, folder, n, solver) for _ in range(args.repeat)]
                    _, products, lam, cxx = runs[0]
                    guide.append(dict(elements=n, solver=solver, cpu_s=min(r[0] for r in runs),
                                      products=products, **{"lambda": lam}, cxx=cxx))
                    print(f"{n:4d} per leaf guide {solver:6s} {guide[-1]['cpu_s']:8.3f} s  "
                          f"lambda {lam:.6f}  C_xx {cxx:.6e}", flush=True)
        except RuntimeError as e:
            print(f"bench_statics: {e}", file=sys.stderr)
            return 1
    finest = max((r for r in rows if r["solver"] == "krylov"), key=lambda r: r["beams"])
    for r in rows:
        r["tip_diff_m"] = float(np.max(np.abs(r["tip"] - finest["tip"])))
    args.out_dir.mkdir(parents=True, exist_ok=True)
    columns = ["beams", "solver", "cpu_s", "newton", "products", "tip_diff_m"]
    write_csv([{k: r[k] for k in columns} for r in rows], columns, args.out_dir / "statics.csv")
    exps = {s: fit_exponent([r["beams"] for r in rows if r["solver"] == s],
                            [r["cpu_s"] for r in rows if r["solver"] == s])
            for s in ("dense", "krylov")}
    lines = ["# Statics against model size: dense tangent and Newton-Krylov", "",
             f"`{command_line('scripts/bench_statics.py', argv)}`", "",
             f"Date: {datetime.now():%Y-%m-%d %H:%M}; machine: {cpu_model()}, "
             f"{usable_cores()} cores; commit {git_commit(ROOT)}.", "",
             "The 45-degree bend (input/bend45.nml with n beams), 4 load steps to 600; "
             "processor time of the analysis, least of "
             f"{args.repeat} runs. Tip difference: after the last step, against the "
             f"{finest['beams']}-beam Krylov run (discretisation error plus solver tolerance).",
             "", "| beams | dynamic coordinates | solver | cpu [s] | Newton iterations | "
             "tangent products | tip difference [m] |",
             "| --- | --- | --- | --- | --- | --- | --- |"]
    for r in rows:
        lines.append(f"| {r['beams']} | {6 * r['beams']} | {r['solver']} | {r['cpu_s']:.3f} | "
                     f"{r['newton']} | {r['products'] or '-'} | {r['tip_diff_m']:.2e} |")
    lines += ["", "Fitted exponent of cpu time ~ n^p from 16 beams on: "
              + ", ".join(f"{s} {e:.2f}" for s, e in exps.items() if not math.isnan(e)) + "."]
    lines += ["", "## Lateral-torsional buckling of the narrow cantilever", "",
              "The lowest multiplier (the critical tip force) and the processor time, both "
              "solvers; the dense path up to twice the meshes of the bend's.", "",
              "| beams | solver | cpu [s] | critical force [N] |", "| --- | --- | --- | --- |"]
    for r in buckling:
        lines.append(f"| {r['beams']} | {r['solver']} | {r['cpu_s']:.3f} | {r['mu']:.6f} |")
    bexps = {s: fit_exponent([r["beams"] for r in buckling if r["solver"] == s],
                             [r["cpu_s"] for r in buckling if r["solver"] == s])
             for s in ("dense", "krylov")}
    lines += ["", "Fitted exponent of the buckling cpu time from 16 beams on: "
              + ", ".join(f"{s} {e:.2f}" for s, e in bexps.items() if not math.isnan(e)) + "."]
    lines += guide_section(guide)
    gcols = ["elements", "solver", "cpu_s", "products", "lambda", "cxx"]
    write_csv(guide, gcols, args.out_dir / "statics_guide.csv")
    (args.out_dir / "statics.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines[-1:]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
