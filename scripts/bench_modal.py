#!/usr/bin/env python3
"""Cost of a modal analysis against model size: the two-link arm (input/two_link.nml) with n
beams per link, its 4 lowest modes with the joints held, by the dense solvers (&modal solver =
'lapack', 'arpack': K_T, Mbar and DF formed) and by the Krylov path ('krylov': shift-invert
Lanczos on the sparse factors, docs/theory.md 8.1); unloaded and under gravity (whose
stiffness both paths difference).

Per mesh, load case and solver: the processor time of the analysis (root attribute
``cpu_time_s``, the least of --repeat runs), the peak resident memory of the process, and the
largest relative difference of the frequencies from the Krylov run's. Dense runs stop at
--dense-max beams per link (their time grows as n^3).

Usage (the flexmor Python package installed, or PYTHONPATH=python):

    python3 scripts/bench_modal.py [--bin build/bin/flexmor] [--out-dir docs/bench] \\
        [--meshes 8,16,32,64,128,256,512] [--dense-max 256] [--repeat 3]

Writes modal.md and modal.csv into --out-dir with the command, date, machine, flexmor version
and commit. Bad arguments exit with 2, a failed run with 1.
"""
from __future__ import annotations

import argparse
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

ROOT = Path(__file__).resolve().parents[1]
SOLVERS = ("lapack", "arpack", "krylov")
CASES = {"unloaded": "", "gravity": "gravity = 0.0, -9.81, "}


def scene(n: int, solver: str, loads: str) -> str:
    """The two-link with n beams per link, no dynamic analysis, 4 modes by `solver`; `loads`:
    more &scene settings (gravity)."""
    text = (ROOT / "input" / "two_link.nml").read_text()
    text = text.replace("n_elements = 3", f"n_elements = {n}")
    if "&scene title" not in text:
        raise RuntimeError("input/two_link.nml's &scene line changed: update bench_modal.py")
    text = text.replace("&scene title", "&scene " + loads + "title")
    text = re.sub(r"&(modal|dynamic)[^/]*/", "", text)
    return text + f"&modal n_modes = 4, solver = '{solver}' /\n"


def run_once(binary, folder, n, solver, case):
    """One run: cpu time [s], peak RSS [MiB], frequencies [Hz]."""
    nml = Path(folder) / f"modal_{case}_{solver}_{n}.nml"
    out = nml.with_suffix(".h5")
    nml.write_text(scene(n, solver, CASES[case]))
    cmd = [str(binary), "-q", str(nml), "-o", str(out)]
    timer = Path("/usr/bin/time")
    if timer.exists():
        cmd = [str(timer), "-f", "maxrss_kb=%M"] + cmd
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"{nml.name}: {proc.stderr.strip()}")
    found = re.search(r"maxrss_kb=(\d+)", proc.stderr)
    with h5py.File(out) as f:
        freq = f["modal/frequency_hz"][:]
        used = f["modal"].attrs["eigensolver"]
    if used != solver:
        raise RuntimeError(f"{nml.name}: asked {solver}, ran {used}")
    return (float(run_attributes(out)["cpu_time_s"]),
            int(found.group(1)) / 1024 if found else float("nan"), freq)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--bin", default=str(ROOT / "build" / "bin" / "flexmor"))
    p.add_argument("--out-dir", default=str(ROOT / "docs" / "bench"))
    p.add_argument("--meshes", default="8,16,32,64,128,256,512")
    p.add_argument("--dense-max", type=int, default=256)
    p.add_argument("--repeat", type=int, default=3)
    args = p.parse_args(argv)
    try:
        meshes = [int(m) for m in args.meshes.split(",")]
    except ValueError:
        p.exit(2, f"bench_modal.py: --meshes must be integers separated by commas, got "
                  f"'{args.meshes}'\n")
    if any(m < 2 for m in meshes) or args.repeat < 1:
        p.exit(2, "bench_modal.py: meshes need at least 2 beams per link, --repeat >= 1\n")
    binary = Path(args.bin)
    if not binary.is_file():
        p.exit(2, f"bench_modal.py: no flexmor binary at {binary}\n")
    out_dir = Path(args.out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)

    rows = []
    with tempfile.TemporaryDirectory() as work:
        for case in CASES:
            for n in meshes:
                row = {"case": case, "elements_per_link": n, "n_dy": 4 * n}
                freqs = {}
                for solver in SOLVERS:
                    if solver != "krylov" and n > args.dense_max:
                        continue
                    try:
                        runs = [run_once(binary, work, n, solver, case)
                                for _ in range(args.repeat)]
                    except RuntimeError as e:
                        print(f"bench_modal.py: {e}", file=sys.stderr)
                        return 1
                    row[f"{solver}_s"] = min(r[0] for r in runs)
                    row[f"{solver}_rss_mib"] = max(r[1] for r in runs)
                    freqs[solver] = runs[0][2]
                for solver in ("lapack", "arpack"):
                    if solver in freqs:
                        row[f"{solver}_freq_diff"] = float(
                            np.max(np.abs(freqs[solver] - freqs["krylov"]) / freqs["krylov"]))
                rows.append(row)
                print(case, n, {k: v for k, v in row.items() if k.endswith("_s")}, flush=True)

    columns = ["case", "elements_per_link", "n_dy"] + [
        f"{s}_{q}" for s in SOLVERS for q in ("s", "rss_mib")] + [
        "lapack_freq_diff", "arpack_freq_diff"]
    write_csv(rows, columns, out_dir / "modal.csv")

    def cell(row, key, fmt):
        return format(row[key], fmt) if key in row else "–"

    lines = ["# Modal analysis against model size: dense solvers and the Krylov path", "",
             f"Command: `{command_line('scripts/bench_modal.py', argv)}`",
             f"Date: {datetime.now():%Y-%m-%d %H:%M}; machine: {cpu_model()}, "
             f"{usable_cores()} cores; commit {git_commit(ROOT)}.", "",
             "input/two_link.nml with n beams per link (4 n dynamic coordinates), its 4 lowest "
             "modes with the joints held (`&modal n_modes = 4, solver = ...`), unloaded and "
             "under gravity. Processor time of the analysis (least of the repeats) and peak "
             "memory of the process; frequency difference: largest relative difference from "
             "the Krylov run's.", "",
             "| case | beams per link | n_dy | LAPACK [s] | ARPACK [s] | Krylov [s] | "
             "LAPACK / Krylov | peak MiB dense ARPACK | peak MiB Krylov | freq. diff. LAPACK |",
             "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for r in rows:
        ratio = r["lapack_s"] / r["krylov_s"] if "lapack_s" in r else None
        lines.append(
            f"| {r['case']} | {r['elements_per_link']} | {r['n_dy']} | "
            f"{cell(r, 'lapack_s', '.4f')} | {cell(r, 'arpack_s', '.4f')} | "
            f"{cell(r, 'krylov_s', '.4f')} | {'–' if ratio is None else f'{ratio:.1f}'} | "
            f"{cell(r, 'arpack_rss_mib', '.0f')} | {cell(r, 'krylov_rss_mib', '.0f')} | "
            f"{cell(r, 'lapack_freq_diff', '.1e')} |")
    (out_dir / "modal.md").write_text("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
