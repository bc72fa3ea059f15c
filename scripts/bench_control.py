#!/usr/bin/env python3
"""Closed-loop trade-off: full against reduced models under feedback control.

Two closed loops, each run with the full model and with reduced models (basis fixed, or
updated when the MAC of a kept mode falls below 0.999, checked every 10 ms, or, for the arm,
the controlled joints held, &reduction joints = 'held'): the arm's open
loop has two rigid-body modes (its free joints), so its reduced models keep k = 3..6 modes
(1..4 elastic ones); the stage's k = 1..4.

- ``two-link``: the flexible two-link arm of input/two_link_pd.nml (3 beams per link) driven by
  joint torques from PD controllers (&controller, the gains of that example) tracking the
  benchmark's cubic quarter turns in 0.5 s, without and with rigid-body feedforward; 1.5 s.
  Tracking error: largest distance of the tip from the rigid arm at the reference angles
  during the move (0 to 0.5 s); residual vibration: largest distance of the tip from its end
  position over the last 0.5 s; settling time: when the tip last leaves a 1 mm band around
  the reference path.
- ``stage``: input/stage_pid.nml (the leaf-spring guide under PID, a 1 mm step, 1 N limit),
  0.3 s. Tracking error: the overshoot over 1 mm; residual vibration: largest |x - 1 mm| after
  0.1 s; settling time: when x last leaves a 10 um band (1 %).

For every case: solve time (result attribute wall_time_s, median of --repeats), and the
difference from the full model's output path (tip or shuttle), the error reduction adds.

Usage (with the flexmor package importable: scripts/setup.sh or PYTHONPATH=python):

    python3 scripts/bench_control.py [--bin build/bin/flexmor] [--repeats 3]
        [--out-dir bench_out] [--quick]

Writes ``control_tradeoff.csv``, ``control_tradeoff.md`` (tables with the command, date,
machine and commit), ``control_tradeoff.png`` (difference from the full model against solve
time) and the examples' plots ``two_link_pd.png`` and ``stage_pid.png``. --quick runs k = 1
and 2 (arm: 3 and 4) on shortened runs with one repeat (for the tests). A failed run is recorded with its
error message and the exit status is 1; bad arguments or a missing binary: exit status 2.
"""
from __future__ import annotations

import argparse
import math
import re
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from datetime import datetime
from pathlib import Path
from typing import Sequence

import h5py
import numpy as np

from flexmor.bench import command_line, cpu_model, git_commit, last_line, write_csv

PROG = "bench_control.py"
ROOT = Path(__file__).resolve().parents[1]
DEFAULT_BIN = ROOT / "build" / "bin" / "flexmor"
L1, L2, T_MOVE = 0.545, 0.675, 0.5
STEP = 1.0e-3
CSV_COLUMNS = ("loop", "name", "controller", "k", "basis", "time_median_s", "time_min_s",
               "time_max_s", "tracking_error_m", "residual_vibration_m", "settling_time_s",
               "diff_from_full_m", "status", "message")


class UserError(Exception):
    """A problem the user can fix: one line, exit status 2."""


@dataclass
class Case:
    loop: str
    name: str
    controller: str
    k: int            # 0: full model
    basis: str        # 'fixed' or 'updated' ('' for the full model)
    text: str


@dataclass
class Outcome:
    case: Case
    times: list[float] = field(default_factory=list)
    t: np.ndarray | None = None
    path: np.ndarray | None = None   # (n_t, 2): tip x, y or shuttle x and its force
    status: str = "ok"
    message: str = ""
    metrics: dict[str, float] = field(default_factory=dict)


def two_link_scene(feedforward: bool, t_end: float) -> str:
    """input/two_link_pd.nml with its &hinge PD replaced by &controller groups (the same law,
    here evaluated by the controllers), optionally with feedforward."""
    text = (ROOT / "input" / "two_link_pd.nml").read_text()
    text = re.sub(r",\s*kp = [0-9.]+, kd = [0-9.]+, reference = '(phi[12])' /", " /", text)
    ff = ", feedforward = .true." if feedforward else ""
    for joint, kp, kd in (("joint1", 2000.0, 140.0), ("joint2", 560.0, 40.0)):
        phi = "phi" + joint[-1]
        text += (f"&controller label = '{joint}', actuator = '{joint}.torque', "
                 f"measure = '{joint}.angle', reference = '{phi}', kp = {kp}, kd = {kd}{ff} /\n")
    return re.sub(r"t_end = [0-9.]+", f"t_end = {t_end}", text)


def stage_scene(t_end: float) -> str:
    text = (ROOT / "input" / "stage_pid.nml").read_text()
    return re.sub(r"t_end = [0-9.]+", f"t_end = {t_end}", text)


def reduced(text: str, k: int, basis: str) -> str:
    if k == 0:
        return text
    update = {"updated": ", update = 'mac', update_interval = 0.01, mac_threshold = 0.999",
              "held": ", joints = 'held'"}.get(basis, "")
    return text.replace("&output", f"&reduction n_modes = {k}{update} /\n&output", 1)


def cases(quick: bool) -> list[Case]:
    ks = [1, 2] if quick else [1, 2, 3, 4]
    arm_ks = [2 + k for k in ks]
    t_arm, t_stage = (0.6, 0.15) if quick else (1.5, 0.3)
    out = []
    for ff in (False, True):
        controller = "PD + feedforward" if ff else "PD"
        base = two_link_scene(ff, t_arm)
        out.append(Case("two-link", f"arm-{'ff-' if ff else ''}full", controller, 0, "", base))
        for basis in ("fixed", "updated", "held"):
            for k in arm_ks:
                out.append(Case("two-link", f"arm-{'ff-' if ff else ''}k{k}-{basis}", controller,
                                k, basis, reduced(base, k, basis)))
    base = stage_scene(t_stage)
    out.append(Case("stage", "stage-full", "PID", 0, "", base))
    for basis in ("fixed", "updated"):
        for k in ks:
            out.append(Case("stage", f"stage-k{k}-{basis}", "PID", k, basis,
                            reduced(base, k, basis)))
    return out


def run_case(case: Case, binary: Path, repeats: int, work: Path) -> Outcome:
    outcome = Outcome(case)
    nml, h5 = work / f"{case.name}.nml", work / f"{case.name}.h5"
    nml.write_text(case.text)
    for _ in range(repeats):
        proc = subprocess.run([str(binary), str(nml), "-o", str(h5), "-q"],
                              capture_output=True, text=True, timeout=1800)
        if proc.returncode != 0:
            outcome.status, outcome.message = "failed", last_line(proc.stderr)
            return outcome
        with h5py.File(h5) as f:
            outcome.times.append(float(f.attrs["wall_time_s"]))
    with h5py.File(h5) as f:
        outcome.t = f["time"][:]
        if case.loop == "two-link":
            outcome.path = f["nodes/tip/position"][:, :2]
        else:
            outcome.path = np.column_stack([f["nodes/shuttle/position"][:, 0] - 0.025,
                                            f["controllers/position/input"][:]])
    return outcome


def cubic(t: np.ndarray) -> np.ndarray:
    s = np.clip(t / T_MOVE, 0.0, 1.0)
    return 0.5 * math.pi * (3 * s**2 - 2 * s**3)


def rigid_tip(t: np.ndarray) -> np.ndarray:
    phi1 = cubic(t)
    phi12 = 2 * phi1
    return np.column_stack([L1 * np.cos(phi1) + L2 * np.cos(phi12),
                            L1 * np.sin(phi1) + L2 * np.sin(phi12)])


def last_time_outside(t: np.ndarray, dev: np.ndarray, band: float) -> float:
    outside = np.nonzero(dev > band)[0]
    return float(t[outside[-1]]) if outside.size else 0.0


def measure(outcome: Outcome, full: Outcome | None) -> None:
    t, path = outcome.t, outcome.path
    if outcome.case.loop == "two-link":
        dev = np.linalg.norm(path - rigid_tip(t), axis=1)
        late = t >= t[-1] - 0.5
        outcome.metrics = {
            "tracking_error_m": float(np.max(dev[t <= T_MOVE])),
            "residual_vibration_m": float(np.max(np.linalg.norm(path[late] - path[-1], axis=1))),
            "settling_time_s": last_time_outside(t, dev, 1.0e-3)}
        diff = None if full is None else np.linalg.norm(path - full.path, axis=1)
    else:
        x = path[:, 0]
        outcome.metrics = {
            "tracking_error_m": float(max(np.max(x) - STEP, 0.0)),
            "residual_vibration_m": float(np.max(np.abs(x[t >= 0.1] - STEP))) if t[-1] > 0.1
            else float("nan"),
            "settling_time_s": last_time_outside(t, np.abs(x - STEP), 0.01 * STEP)}
        diff = None if full is None else np.abs(x - full.path[:, 0])
    outcome.metrics["diff_from_full_m"] = 0.0 if diff is None else float(np.max(diff))


def row(o: Outcome) -> dict:
    times = o.times or [float("nan")]
    return {"loop": o.case.loop, "name": o.case.name, "controller": o.case.controller,
            "k": o.case.k or "full", "basis": o.case.basis or "–",
            "time_median_s": statistics.median(times), "time_min_s": min(times),
            "time_max_s": max(times), **{c: o.metrics.get(c, float("nan")) for c in
                                         CSV_COLUMNS[8:12]},
            "status": o.status, "message": o.message}


def markdown(rows: list[dict], header: list[str]) -> str:
    lines = header + [""]
    for loop in ("two-link", "stage"):
        lines += [f"## {loop}", "",
                  "| case | controller | k | basis | time [s] | tracking error [m] | "
                  "residual vibration [m] | settling [s] | difference from full [m] | status |",
                  "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
        for r in rows:
            if r["loop"] != loop:
                continue
            lines.append(
                f"| `{r['name']}` | {r['controller']} | {r['k']} | {r['basis']} | "
                f"{r['time_median_s']:.3f} ({r['time_min_s']:.3f}–{r['time_max_s']:.3f}) | "
                f"{r['tracking_error_m']:.2e} | {r['residual_vibration_m']:.2e} | "
                f"{r['settling_time_s']:.3f} | {r['diff_from_full_m']:.2e} | "
                f"{r['status']}{(': ' + r['message']) if r['message'] else ''} |")
        lines.append("")
    return "\n".join(lines)


def plots(outcomes: list[Outcome], out_dir: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ok = [o for o in outcomes if o.status == "ok"]
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    for ax, loop in zip(axes, ("two-link", "stage")):
        for o in ok:
            if o.case.loop != loop or o.case.k == 0:
                continue
            marker = {"fixed": "o", "updated": "s", "held": "^"}[o.case.basis]
            color = "C1" if "feedforward" in o.case.controller else "C0"
            ax.loglog(statistics.median(o.times), max(o.metrics["diff_from_full_m"], 1e-16),
                      marker, color=color, mfc="none" if o.case.basis == "fixed" else color)
            ax.annotate(f"k={o.case.k}", (statistics.median(o.times),
                        max(o.metrics["diff_from_full_m"], 1e-16)), fontsize=7)
        full = [o for o in ok if o.case.loop == loop and o.case.k == 0]
        for o in full:
            ax.axvline(statistics.median(o.times), color="0.6", ls="--", lw=0.8)
        ax.set_title(f"{loop}: reduced vs full (dashed: full model's time)", fontsize=9)
        ax.set_xlabel("solve time [s]")
        ax.set_ylabel("largest difference from the full model [m]")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].plot([], [], "o", color="C0", mfc="none", label="PD, fixed basis")
    axes[0].plot([], [], "s", color="C0", label="PD, updated basis")
    axes[0].plot([], [], "o", color="C1", mfc="none", label="PD + feedforward, fixed")
    axes[0].plot([], [], "s", color="C1", label="PD + feedforward, updated")
    axes[0].plot([], [], "^", color="C0", label="PD, joints held")
    axes[0].plot([], [], "^", color="C1", label="PD + feedforward, joints held")
    axes[0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out_dir / "control_tradeoff.png", dpi=110)
    plt.close(fig)

    arm = {o.case.controller: o for o in ok if o.case.loop == "two-link" and o.case.k == 0}
    if arm:
        fig, ax = plt.subplots(figsize=(6.5, 3.8))
        for label, o in sorted(arm.items()):
            ax.semilogy(o.t, np.maximum(np.linalg.norm(o.path - rigid_tip(o.t), axis=1), 1e-12),
                        label=label)
        ax.axvline(T_MOVE, color="0.6", ls="--", lw=0.8)
        ax.set_xlabel("t [s]")
        ax.set_ylabel("tip distance from the reference path [m]")
        ax.set_title("input/two_link_pd.nml: joint PD, without and with feedforward", fontsize=9)
        ax.legend(fontsize=8)
        ax.grid(True, which="both", alpha=0.3)
        fig.tight_layout()
        fig.savefig(out_dir / "two_link_pd.png", dpi=110)
        plt.close(fig)
    stage = [o for o in ok if o.case.loop == "stage" and o.case.k == 0]
    if stage:
        o = stage[0]
        fig, (a1, a2) = plt.subplots(2, 1, figsize=(6.5, 5), sharex=True)
        a1.plot(o.t * 1e3, o.path[:, 0] * 1e3)
        a1.axhline(STEP * 1e3, color="0.6", ls="--", lw=0.8)
        a1.set_ylabel("shuttle x [mm]")
        a2.plot(o.t * 1e3, o.path[:, 1])
        a2.set_ylabel("actuator force [N]")
        a2.set_xlabel("t [ms]")
        a1.set_title("input/stage_pid.nml: 1 mm step under PID (force limited to 1 N)",
                     fontsize=9)
        fig.tight_layout()
        fig.savefig(out_dir / "stage_pid.png", dpi=110)
        plt.close(fig)


def parse_args(argv: Sequence[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n\n")[0])
    parser.add_argument("--bin", type=Path, default=DEFAULT_BIN, help="flexmor executable")
    parser.add_argument("--repeats", type=int, default=None,
                        help="runs per case, median time (default 3, --quick 1)")
    parser.add_argument("--out-dir", type=Path, default=Path("bench_out"))
    parser.add_argument("--quick", action="store_true", help="small subset, for the tests")
    return parser.parse_args(argv)


def main(argv: Sequence[str] | None = None) -> int:
    args = parse_args(argv)
    try:
        if not args.bin.is_file():
            raise UserError(f"no flexmor executable at {args.bin} (build it, or give --bin)")
        repeats = args.repeats if args.repeats is not None else (1 if args.quick else 3)
        if repeats < 1:
            raise UserError(f"--repeats must be >= 1, got {repeats}")
        args.out_dir.mkdir(parents=True, exist_ok=True)
    except (UserError, OSError) as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return 2
    start = time.time()
    commit = git_commit(ROOT)
    outcomes = []
    with tempfile.TemporaryDirectory() as tmp:
        for case in cases(args.quick):
            print(f"{case.name} ...", flush=True)
            outcomes.append(run_case(case, args.bin, repeats, Path(tmp)))
    fulls = {(o.case.loop, o.case.controller): o for o in outcomes
             if o.case.k == 0 and o.status == "ok"}
    for o in outcomes:
        if o.status == "ok":
            measure(o, fulls.get((o.case.loop, o.case.controller)))
    rows = [row(o) for o in outcomes]
    write_csv(rows, CSV_COLUMNS, args.out_dir / "control_tradeoff.csv")
    header = ["# Closed-loop trade-off: full and reduced models under feedback control", "",
              f"- Command: `{command_line(PROG, argv)}`",
              f"- Date: {datetime.now().astimezone().isoformat(timespec='seconds')}",
              f"- Machine: {cpu_model()}, git commit {commit}",
              f"- Repeats: {repeats} per case; whole benchmark {time.time() - start:.0f} s",
              "- Scenes: input/two_link_pd.nml (as &controller groups, 1.5 s) and "
              "input/stage_pid.nml (0.3 s); reduced: k modes, basis fixed or updated "
              "(MAC 0.999, every 10 ms); the arm's k counts its 2 rigid-body modes. Metrics: see "
              "scripts/bench_control.py's docstring."]
    (args.out_dir / "control_tradeoff.md").write_text(markdown(rows, header))
    plots(outcomes, args.out_dir)
    failed = [o for o in outcomes if o.status != "ok"]
    for o in failed:
        print(f"{PROG}: {o.case.name} failed: {o.message}", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
