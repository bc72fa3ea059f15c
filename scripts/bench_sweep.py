#!/usr/bin/env python3
"""MPI scaling of flexmor-sweep: cases/s, speed-up and efficiency against the rank count.

Runs sweeps with 1 rank (no mpirun) and under ``mpirun -n N`` for each N of --ranks (default
1,2,3,4), a fresh result file every time, and times the whole command (wall clock, from before
the launch to the exit of mpirun). From each result file it reads the per-case solve times
(``/cases/wall_time_s``) and the rank that ran each case (``/cases/rank``). Workloads:

- ``reduced``: a sweep written into a scratch folder over input/two_link_2modes.nml (reduced
  model) with a spread of per-case cost: ``reduction.n_modes`` 1..4 (slowest), ``dynamic.rtol``
  1e-4/1e-6/1e-8, the motion time (both joints, tied names) 0.3/0.4/0.5 s and the final angle of
  joint 1 pi/4, pi/2, 3pi/4: 108 cases, product order, so the costliest (4-mode) cases come last;
- ``full``: input/sweep_two_link.nml as it is (full model, 12 cases of nearly equal cost);
- ``probe``: the dispatch cost of flexmor-sweep itself, from a one-link scene whose cases all
  fail at once in the scene reader (negative Young's modulus): a 1-case sweep gives the fixed
  cost of a launch (start, validation, file creation, MPI start-up), a many-case sweep the cost
  per case (--probe-cases cases; 10 times as many at 1 rank, where a case costs ~0.1 ms). The
  probe uses the fastest of the repeats (noise only adds). With 1 rank the cost per case is
  reading the case's scene plus writing and flushing its row: an upper bound on rank 0's
  per-case write+flush cost t_w. With N ranks and W = N - 1
  workers, L = W * (cost per case) - t_w is the hand-out latency: what a worker waits per case
  beyond the work and the row write (result message to rank 0, rank 0 noticing it in its
  0.5 ms probe loop, the next case back).

Runs are interleaved (for each repeat, every rank count in turn) so that a drift of the
machine's speed spreads over the rank counts instead of biasing one. During each run the CPU
time of all other processes on the machine is taken from /proc/stat (busy ticks minus the
run's own CPU time): "other CPU" in the tables, a measure of how disturbed the run was.

Derived (per workload and rank count; the median-wall run of the repeats gives the per-case
data): cases/s; speed-up S = wall(1 rank) / wall(N); efficiency per MPI rank S/N, per
computing rank S/W (W = N - 1 workers for N > 1, 1 for N = 1), per core S/min(W, cores);
overhead = wall - sum(case solve times)/W; the summed solve time per worker rank (load
balance) and worker ranks that got no case. The per-case cost distribution comes from the
1-rank run. A projection to --project-ranks ranks (default 64) states its model in the report.

Usage (from anywhere, with the flexmor Python package installed: scripts/setup.sh or
`pip install .`; --bin defaults to build/bin/flexmor-sweep in the repository):

    python3 scripts/bench_sweep.py [--bin BIN] [--mpirun MPIRUN] [--ranks 1,2,3,4] \\
        [--repeats 3] [--repeats-full 1] [--probe-cases 500] [--no-full] \\
        [--project-ranks 64] [--out-dir bench_out] [--quick] [--timeout 600]

Writes ``sweep_scaling.md`` and ``sweep_scaling.csv`` into --out-dir; the CSV has one row per
workload and rank count (kind ``measured``), per probe rank count (``probe``: per_case_s,
latency_s) and per projection (``projection``: wall_min_s/wall_max_s = the model's low/high
wall; speed-up and efficiencies from the high one). The runs get
OMPI_ALLOW_RUN_AS_ROOT=1, OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1, OMPI_MCA_rmaps_base_oversubscribe=1
(more ranks than cores are allowed), OPENBLAS_NUM_THREADS=1 and OMP_NUM_THREADS=1.
--quick (for the tests): 4 reduced cases, ranks 1,2, 40 probe cases, no full workload, one
repeat.

A run that fails (non-zero exit, time-out, a case with an unexpected status) is recorded and
the benchmark goes on; the exit status is then 1. Bad arguments, a missing binary or mpirun:
one-line message and exit status 2.
"""
from __future__ import annotations

import argparse
import math
import os
import platform
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from datetime import datetime
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from flexmor.bench import (command_line, cpu_model, git_commit, last_line, usable_cores,
                           write_csv)
from flexmor.sweep import SweepFileError, fmt_value, load_sweep

PROG = "bench_sweep.py"
ROOT = Path(__file__).resolve().parents[1]
DEFAULT_BIN = ROOT / "build" / "bin" / "flexmor-sweep"
REDUCED_BASE = ROOT / "input" / "two_link_2modes.nml"
FULL_SWEEP = ROOT / "input" / "sweep_two_link.nml"
RUN_ENV = {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
           "OMPI_MCA_rmaps_base_oversubscribe": "1", "OPENBLAS_NUM_THREADS": "1",
           "OMP_NUM_THREADS": "1"}
#: Rank 0's sleep between two bursts of probes for results (src/sweep/sweep_run.f90).
PROBE_SLEEP_S = 0.0005
#: A case of the probe is refused before its model is built: flexmor exit code 1 (input).
PROBE_STATUS = 1

PI = math.pi
REDUCED_PARAMETERS: tuple[tuple[str, tuple[float, ...]], ...] = (
    ("'reduction.n_modes'", (1, 2, 3, 4)),
    ("'dynamic.rtol'", (1e-4, 1e-6, 1e-8)),
    ("'motion.phi1.duration', 'motion.phi2.duration'", (0.3, 0.4, 0.5)),
    ("'motion.phi1.end'", (PI / 4, PI / 2, 3 * PI / 4)),
)
QUICK_PARAMETERS: tuple[tuple[str, tuple[float, ...]], ...] = (
    ("'reduction.n_modes'", (1, 2)),
    ("'dynamic.rtol'", (1e-4,)),
    ("'motion.phi1.duration', 'motion.phi2.duration'", (0.3, 0.5)),
)

PROBE_SCENE = """\
! bench_sweep.py probe: one link, 1 element; every case is refused before its model is built
! (n_elements of 5000 and more: too large), so a case costs reading its scene and writing its
! row, nothing else.
&node label = 'base', x = 0, y = 0, fixed = .true. /
&node label = 'tip', x = 1, y = 0 /
&link label = 'arm', from = 'base', to = 'tip', n_elements = 1,
      E = 7.0e10, A = 1.0e-4, I = 1.0e-9, rho = 2700 /
&hinge label = 'j1', node = 'base', link = 'arm', mode = 'prescribed', motion = 'm1' /
&motion label = 'm1', law = 'cubic', start = 0, end = 0.5, duration = 0.002 /
&mass node = 'tip', m = 0.1 /
&dynamic t_end = 0.003, output_dt = 1e-3 /
"""

CSV_COLUMNS = (
    "kind", "workload", "ranks", "workers", "cores", "oversubscribed", "repeats", "n_cases",
    "wall_median_s", "wall_min_s", "wall_max_s", "cpu_s", "other_cpu_s", "cases_per_s", "speedup",
    "eff_per_rank", "eff_per_worker", "eff_per_core", "case_time_sum_s", "case_time_mean_s",
    "overhead_s", "busy_min_s", "busy_max_s", "imbalance", "idle_workers", "per_case_s",
    "latency_s", "status", "message",
)


class UserError(Exception):
    """A problem the user can fix (bad argument, missing binary): one line, exit status 2."""


# --- sweep files ------------------------------------------------------------------------------


def parameter_line(names: str, values: Sequence[float]) -> str:
    """``&parameter name = ..., values = ... /`` with integral values written as integers."""
    text = ", ".join(str(int(v)) if float(v).is_integer() else repr(float(v)) for v in values)
    return f"&parameter name = {names}, values = {text} /"


def reduced_sweep_text(parameters: Sequence[tuple[str, Sequence[float]]]) -> str:
    lines = ["! bench_sweep.py: reduced two-link model, per-case cost spread (product order,",
             "! first parameter slowest).",
             "&sweep base = 'base.nml', mode = 'product', node = 'tip',",
             "       title = 'bench_sweep: reduced two-link, cost spread' /"]
    lines += [parameter_line(names, values) for names, values in parameters]
    return "\n".join(lines) + "\n"


def probe_sweep_text(n: int) -> str:
    """``n`` cases, every one an input error (n_elements = 5000, 5001, ...: too large). Not a
    value beyond a variable's range (E < 0): the sweep refuses those before any case runs."""
    return ("&sweep base = 'probe_base.nml', mode = 'product', node = 'tip',\n"
            "       title = 'bench_sweep: dispatch probe' /\n"
            f"&parameter name = 'link.arm.n_elements', start = 5000, stop = {5000 + n - 1}, "
            f"n = {n} /\n")


def n_product(parameters: Sequence[tuple[str, Sequence[float]]]) -> int:
    return math.prod(len(values) for _, values in parameters)


@dataclass
class Workload:
    """One sweep to run at every rank count."""

    key: str
    title: str
    sweep: Path
    n_cases: int
    repeats: int
    expected_status: int = 0
    group: str | None = None  # parameter for the per-level cost table
    description: str = ""
    only_ranks: tuple[int, ...] | None = None  # run at these rank counts only

    def runs_at(self, ranks: int) -> bool:
        return self.only_ranks is None or ranks in self.only_ranks


def make_workloads(args: argparse.Namespace, work: Path) -> list[Workload]:
    """Write the generated sweeps into ``work``; the full workload runs input/ as it is."""
    params = QUICK_PARAMETERS if args.quick else REDUCED_PARAMETERS
    shutil.copy(REDUCED_BASE, work / "base.nml")
    (work / "reduced.nml").write_text(reduced_sweep_text(params))
    (work / "probe_base.nml").write_text(PROBE_SCENE)
    (work / "probe1.nml").write_text(probe_sweep_text(1))
    (work / "probe.nml").write_text(probe_sweep_text(args.probe_cases))
    (work / "probe_serial.nml").write_text(probe_sweep_text(10 * args.probe_cases))
    n_red = n_product(params)
    desc = "; ".join(f"{names.replace(chr(39), '')} = "
                     + ", ".join(fmt_value(v) for v in values) for names, values in params)
    loads = [Workload("reduced", "reduced model, cost spread", work / "reduced.nml", n_red,
                      args.repeats, group="reduction.n_modes",
                      description=f"input/two_link_2modes.nml; product of {desc} (first "
                                  "varies slowest: the costliest cases come last)")]
    if not args.no_full:
        loads.append(Workload("full", "full model, uniform cost", FULL_SWEEP, 12,
                              args.repeats_full, group="motion.phi1.duration",
                              description="input/sweep_two_link.nml as it is (base "
                                          "input/two_link.nml)"))
    loads.append(Workload("probe1", "dispatch probe, 1 case", work / "probe1.nml", 1,
                          args.repeats, expected_status=PROBE_STATUS))
    loads.append(Workload("probe", f"dispatch probe, {args.probe_cases} cases",
                          work / "probe.nml", args.probe_cases, args.repeats,
                          expected_status=PROBE_STATUS, only_ranks=tuple(
                              n for n in args.ranks if n > 1)))
    loads.append(Workload("probe_serial", f"dispatch probe, {10 * args.probe_cases} cases",
                          work / "probe_serial.nml", 10 * args.probe_cases, args.repeats,
                          expected_status=PROBE_STATUS, only_ranks=(1,)))
    return loads


# --- running ----------------------------------------------------------------------------------


@dataclass
class Run:
    """One timed launch of flexmor-sweep."""

    workload: str
    ranks: int
    rep: int
    wall: float = math.nan
    cpu: float = math.nan
    other_cpu: float = math.nan
    status: str = "ok"
    message: str = ""
    case_time: np.ndarray = field(default_factory=lambda: np.zeros(0))
    case_rank: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    parameters: dict[str, np.ndarray] = field(default_factory=dict)
    version: str = ""


def machine_busy_s() -> float:
    """CPU seconds all processes of the machine have used (user, nice, system, irq, softirq,
    steal from /proc/stat); NaN where it cannot be read."""
    try:
        fields = Path("/proc/stat").read_text().splitlines()[0].split()
        ticks = [int(v) for v in fields[1:9]]
    except (OSError, IndexError, ValueError):
        return math.nan
    user, nice, system, _idle, _iowait, irq, softirq, steal = ticks
    return (user + nice + system + irq + softirq + steal) / os.sysconf("SC_CLK_TCK")


def children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def command(binary: Path, mpirun: str | None, sweep: Path, out: Path, ranks: int) -> list[str]:
    cmd = [str(binary), str(sweep), "-o", str(out), "-q"]
    if ranks > 1:
        cmd = [str(mpirun), "-n", str(ranks), *cmd]
    return cmd


def run_once(load: Workload, ranks: int, rep: int, args: argparse.Namespace,
             work: Path) -> Run:
    """Launch the sweep into a fresh file, time it, read cases' times and ranks."""
    run = Run(load.key, ranks, rep)
    out = work / f"{load.key}-n{ranks}-r{rep}.h5"
    out.unlink(missing_ok=True)
    env = dict(os.environ, **RUN_ENV)
    cpu0, busy0 = children_cpu(), machine_busy_s()
    t0 = time.perf_counter()
    try:
        proc = subprocess.run(command(args.bin, args.mpirun, load.sweep, out, ranks),
                              capture_output=True, text=True, timeout=args.timeout, env=env,
                              cwd=work)
    except subprocess.TimeoutExpired:
        run.status, run.message = "failed", f"timed out after {args.timeout:g} s"
        return run
    except OSError as exc:
        run.status, run.message = "failed", f"cannot run: {exc}"
        return run
    run.wall = time.perf_counter() - t0
    run.cpu = children_cpu() - cpu0
    run.other_cpu = max(machine_busy_s() - busy0 - run.cpu, 0.0)
    if proc.returncode != 0:
        run.status = "failed"
        run.message = f"exit {proc.returncode}: {last_line(proc.stderr) or last_line(proc.stdout)}"
        return run
    try:
        sweep = load_sweep(out)
    except SweepFileError as exc:
        run.status, run.message = "failed", str(exc)
        return run
    run.case_time, run.case_rank = sweep.wall_time_s, sweep.rank
    run.parameters, run.version = sweep.parameters, str(sweep.attrs.get("flexmor_version", ""))
    bad = np.flatnonzero(sweep.status != load.expected_status)
    if bad.size:
        run.status = "failed"
        first = int(bad[0])
        run.message = (f"{bad.size} of {sweep.n_cases} case(s) with status other than "
                       f"{load.expected_status}, e.g. case {first + 1}: status "
                       f"{int(sweep.status[first])} {sweep.messages[first]}".strip())
    if load.expected_status == 0:
        run.case_time = np.where(sweep.status == 0, run.case_time, np.nan)
    out.unlink(missing_ok=True)
    return run


def run_all(loads: list[Workload], args: argparse.Namespace, work: Path) -> list[Run]:
    """Per workload: the repeats in turn, each over all rank counts (so slow drifts of the
    machine spread over the rank counts instead of biasing one)."""
    runs = []
    for load in loads:
        for rep in range(load.repeats):
            for ranks in filter(load.runs_at, args.ranks):
                run = run_once(load, ranks, rep, args, work)
                runs.append(run)
                state = (f"{run.wall:7.2f} s wall, {run.cpu:7.2f} s CPU, other processes "
                         f"{run.other_cpu:6.2f} s CPU" if run.status == "ok"
                         else f"FAILED: {run.message}")
                print(f"{load.key:<8s} N={ranks:<3d} repeat {rep + 1}/{load.repeats}: {state}",
                      flush=True)
    return runs


# --- analysis ---------------------------------------------------------------------------------


def subscription(ranks: int, cores: int) -> str:
    """'no' (a core per rank), 'rank0' (only rank 0, which mostly sleeps, shares a core) or
    'workers' (more workers than cores: they time-share)."""
    if ranks <= cores:
        return "no"
    return "rank0" if workers_of(ranks) <= cores else "workers"


def finite_mean(values: np.ndarray) -> float:
    """Mean of the finite values, NaN if there is none."""
    finite = values[np.isfinite(values)]
    return float(finite.mean()) if finite.size else math.nan


def workers_of(ranks: int) -> int:
    """Ranks that compute cases: N - 1 (rank 0 only hands out and writes), 1 for N = 1."""
    return max(ranks - 1, 1)


def worker_ranks(ranks: int) -> list[int]:
    return [0] if ranks == 1 else list(range(1, ranks))


def median_run(runs: list[Run]) -> Run:
    """The run with the median wall time (the lower middle one for an even count)."""
    ok = sorted((r for r in runs if r.status == "ok"), key=lambda r: r.wall)
    if not ok:
        raise ValueError("no successful run")
    return ok[(len(ok) - 1) // 2]


def load_balance(run: Run) -> dict[int, tuple[int, float]]:
    """Per worker rank: (cases run, summed solve time); ranks that got no case included."""
    out = {}
    for rank in worker_ranks(run.ranks):
        mine = run.case_rank == rank
        out[rank] = (int(mine.sum()), float(np.nansum(run.case_time[mine])))
    return out


@dataclass
class Point:
    """A workload at one rank count: the timing summary over the repeats."""

    workload: str
    ranks: int
    n_cases: int
    cores: int
    runs: list[Run]
    status: str = "ok"
    message: str = ""
    wall: float = math.nan
    wall_min: float = math.nan
    wall_max: float = math.nan
    cpu: float = math.nan
    other_cpu: float = math.nan
    case_sum: float = math.nan
    case_mean: float = math.nan
    balance: dict[int, tuple[int, float]] = field(default_factory=dict)
    speedup: float = math.nan

    @property
    def workers(self) -> int:
        return workers_of(self.ranks)

    @property
    def rate(self) -> float:
        return self.n_cases / self.wall

    @property
    def overhead(self) -> float:
        return self.wall - self.case_sum / self.workers

    @property
    def eff_rank(self) -> float:
        return self.speedup / self.ranks

    @property
    def eff_worker(self) -> float:
        return self.speedup / self.workers

    @property
    def eff_core(self) -> float:
        return self.speedup / min(self.workers, self.cores)

    @property
    def idle(self) -> list[int]:
        return [rank for rank, (n, _) in self.balance.items() if n == 0]

    @property
    def imbalance(self) -> float:
        """Largest summed solve time of a worker over the mean of the workers."""
        busy = [b for _, b in self.balance.values()]
        mean = sum(busy) / len(busy) if busy else 0.0
        return max(busy) / mean if mean > 0 else math.nan


def summarize(load: Workload, runs: list[Run], ranks_list: list[int], cores: int) -> list[Point]:
    points = []
    for ranks in filter(load.runs_at, ranks_list):
        mine = [r for r in runs if r.workload == load.key and r.ranks == ranks]
        point = Point(load.key, ranks, load.n_cases, cores, mine)
        failed = [r for r in mine if r.status != "ok"]
        if failed:
            point.status = "failed"
            point.message = failed[0].message
        ok = [r for r in mine if r.status == "ok"]
        if ok:
            walls = [r.wall for r in ok]
            point.wall, point.wall_min, point.wall_max = (statistics.median(walls), min(walls),
                                                          max(walls))
            point.cpu = statistics.median(r.cpu for r in ok)
            point.other_cpu = statistics.median(r.other_cpu for r in ok)
            med = median_run(ok)
            point.case_sum = float(np.nansum(med.case_time))
            point.case_mean = finite_mean(med.case_time)
            point.balance = load_balance(med)
        points.append(point)
    base = next((p for p in points if p.ranks == 1 and math.isfinite(p.wall)), None)
    for point in points:
        if base is not None and math.isfinite(point.wall):
            point.speedup = base.wall / point.wall
    return points


@dataclass
class Probe:
    """Launch and per-case costs of flexmor-sweep itself, per rank count."""

    startup: dict[int, float]      # wall of a 1-case sweep
    per_case: dict[int, float]     # (wall(n) - wall(1)) / (n - 1)

    @property
    def write_cost(self) -> float:
        """1 rank: scene read + row write + flush per case; upper bound of rank 0's cost (NaN
        when not measured or below the resolution, i.e. not positive)."""
        value = self.per_case.get(1, math.nan)
        return value if value > 0 else math.nan

    def latency(self, ranks: int) -> float:
        """Extra time per case and worker under MPI: W * per_case(N) - per_case(1)."""
        if ranks == 1 or ranks not in self.per_case:
            return math.nan
        return workers_of(ranks) * self.per_case[ranks] - np.nan_to_num(self.write_cost)

    def dispatch_latency(self) -> tuple[int, float]:
        """(N, L) of the smallest measured rank count > 1 (N = 2 if measured: one worker, no
        time sharing on any machine with 2 cores); (0, NaN) without one."""
        candidates = sorted(n for n in self.per_case if n > 1)
        if not candidates:
            return 0, math.nan
        return candidates[0], self.latency(candidates[0])


def make_probe(points1: list[Point], points: list[Point]) -> Probe:
    """Start-up and per-case cost from the fastest runs of the 1-case and many-case probes."""
    startup = {p.ranks: p.wall_min for p in points1 if math.isfinite(p.wall_min)}
    per_case = {}
    for p in points:
        if math.isfinite(p.wall_min) and p.ranks in startup and p.n_cases > 1:
            per_case[p.ranks] = (p.wall_min - startup[p.ranks]) / (p.n_cases - 1)
    return Probe(startup, per_case)


@dataclass
class Projection:
    """Makespan model for P ranks (W = P - 1 workers, one core each)."""

    workload: str
    ranks: int
    n_cases: int
    case_cost: float       # per case, all in, from the 1-rank run: (wall - startup) / n
    case_max: float        # longest case, all in
    latency: float         # hand-out latency per case and worker
    write_cost: float      # rank 0's service time per case (upper bound)
    startup: float         # launch with P ranks
    startup_serial: float  # launch with 1 rank
    outside_solve: float = math.nan  # c minus the mean solve time (scene set-up, metrics, row)

    @property
    def workers(self) -> int:
        return workers_of(self.ranks)

    @property
    def rate_workers(self) -> float:
        return self.workers / (self.case_cost + self.latency)

    @property
    def rate_rank0(self) -> float:
        return 1.0 / self.write_cost if self.write_cost > 0 else math.inf

    @property
    def rate(self) -> float:
        return min(self.rate_workers, self.rate_rank0)

    @property
    def limited_by(self) -> str:
        return "rank 0" if self.rate_rank0 < self.rate_workers else "workers"

    @property
    def wall_low(self) -> float:
        """No tail beyond the last case's own length: max(n / rate, longest case)."""
        return self.startup + max(self.n_cases / self.rate, self.case_max + self.latency)

    @property
    def wall_high(self) -> float:
        """Greedy list scheduling bound: the longest case (and its hand-out) may start at the
        very end."""
        return self.startup + self.n_cases / self.rate + self.case_max + self.latency

    @property
    def serial(self) -> float:
        """Wall of the same n cases with 1 rank."""
        return self.startup_serial + self.n_cases * self.case_cost


def project(point1: Point, probe: Probe, ranks: int, n_cases: int, cores: int) -> Projection:
    """The model from the 1-rank run of a workload and the probe's costs."""
    s1 = probe.startup.get(1, 0.0)
    cost = (point1.wall - s1) / point1.n_cases
    med = median_run(point1.runs)
    mean_solve = finite_mean(med.case_time)
    case_max = float(np.max(med.case_time[np.isfinite(med.case_time)])) + (cost - mean_solve)
    _, latency = probe.dispatch_latency()
    startup = max((v for n, v in probe.startup.items() if n > 1), default=s1)
    return Projection(point1.workload, ranks, n_cases, cost, case_max,
                      latency if math.isfinite(latency) else 0.0, probe.write_cost, startup,
                      s1, cost - mean_solve)


def model_wall(point1: Point, point: Point, probe: Probe,
               cores: int) -> tuple[float, float, float, float]:
    """The model applied to a measured rank count N > 1: (low, high) with min(W, cores)
    workers and the 1-rank case costs, then (low, high) with W workers and the case solve
    times as measured at N (stretched by contention or time sharing)."""
    proj = project(point1, probe, point.ranks, point1.n_cases, cores)
    start = probe.startup.get(point.ranks, proj.startup)
    n, lat = point1.n_cases, proj.latency

    def bounds(workers: int, cost: float, longest: float) -> tuple[float, float]:
        rate = min(workers / (cost + lat), proj.rate_rank0)
        return start + max(n / rate, longest + lat), start + n / rate + longest + lat

    low, high = bounds(min(point.workers, cores), proj.case_cost, proj.case_max)
    stretch = point.case_mean / point1.case_mean
    low2, high2 = bounds(point.workers, proj.case_cost + point.case_mean - point1.case_mean,
                         proj.case_max * stretch)
    return low, high, low2, high2


# --- per-case cost ----------------------------------------------------------------------------


@dataclass
class CostStats:
    label: str
    n: int
    total: float
    mean: float
    minimum: float
    median: float
    maximum: float

    @property
    def ratio(self) -> float:
        return self.maximum / self.minimum if self.minimum > 0 else math.inf


def cost_stats(label: str, times: np.ndarray) -> CostStats:
    t = times[np.isfinite(times)]
    if t.size == 0:
        return CostStats(label, 0, 0.0, math.nan, math.nan, math.nan, math.nan)
    return CostStats(label, int(t.size), float(t.sum()), float(t.mean()), float(t.min()),
                     float(np.median(t)), float(t.max()))


def cost_levels(run: Run, group: str | None) -> list[CostStats]:
    """Cost per value of the ``group`` parameter (empty without one)."""
    if group is None or group not in run.parameters:
        return []
    values = run.parameters[group]
    return [cost_stats(f"{group} = {fmt_value(v)}", run.case_time[values == v])
            for v in np.unique(values)]


# --- machine ----------------------------------------------------------------------------------


def mpi_version(mpirun: str | None) -> str:
    if mpirun is None:
        return "not used"
    try:
        proc = subprocess.run([mpirun, "--version"], capture_output=True, text=True, timeout=30,
                              env=dict(os.environ, **RUN_ENV))
    except (OSError, subprocess.SubprocessError):
        return f"`{mpirun}`"
    first = next((line.strip() for line in proc.stdout.splitlines() if line.strip()), "")
    return f"{first} (`{mpirun}`)" if first else f"`{mpirun}`"


# --- output -----------------------------------------------------------------------------------


def _f(value: float, fmt: str = ".3f") -> str:
    return "–" if value is None or not math.isfinite(value) else format(value, fmt)


def _csv(value: float | int | str) -> float | int | str:
    if isinstance(value, float) and not math.isfinite(value):
        return ""
    return value


def point_row(p: Point, kind: str = "measured", repeats: int = 0) -> dict[str, Any]:
    busy = [b for _, b in p.balance.values()]
    return {k: _csv(v) for k, v in {
        "kind": kind, "workload": p.workload, "ranks": p.ranks, "workers": p.workers,
        "cores": p.cores, "oversubscribed": subscription(p.ranks, p.cores),
        "repeats": repeats or len(p.runs), "n_cases": p.n_cases, "wall_median_s": p.wall,
        "wall_min_s": p.wall_min, "wall_max_s": p.wall_max, "cpu_s": p.cpu,
        "other_cpu_s": p.other_cpu,
        "cases_per_s": p.rate if math.isfinite(p.wall) else math.nan, "speedup": p.speedup,
        "eff_per_rank": p.eff_rank, "eff_per_worker": p.eff_worker, "eff_per_core": p.eff_core,
        "case_time_sum_s": p.case_sum, "case_time_mean_s": p.case_mean,
        "overhead_s": p.overhead if math.isfinite(p.wall) else math.nan,
        "busy_min_s": min(busy) if busy else math.nan,
        "busy_max_s": max(busy) if busy else math.nan, "imbalance": p.imbalance,
        "idle_workers": " ".join(map(str, p.idle)), "per_case_s": math.nan,
        "latency_s": math.nan, "status": p.status, "message": p.message,
    }.items()}


def probe_rows(probe: Probe, points: list[Point]) -> list[dict[str, Any]]:
    rows = []
    for p in points:
        row = point_row(p, kind="probe")
        row["workload"] = "probe"
        row["per_case_s"] = _csv(probe.per_case.get(p.ranks, math.nan))
        row["latency_s"] = _csv(probe.latency(p.ranks))
        rows.append(row)
    return rows


def projection_row(proj: Projection, cores: int) -> dict[str, Any]:
    speed_low = proj.serial / proj.wall_high
    return {k: _csv(v) for k, v in {
        "kind": "projection", "workload": proj.workload, "ranks": proj.ranks,
        "workers": proj.workers, "cores": proj.ranks, "oversubscribed": "no", "repeats": "",
        "n_cases": proj.n_cases, "wall_median_s": math.nan, "wall_min_s": proj.wall_low,
        "wall_max_s": proj.wall_high, "cpu_s": math.nan, "other_cpu_s": math.nan,
        "cases_per_s": proj.n_cases / proj.wall_high, "speedup": speed_low,
        "eff_per_rank": speed_low / proj.ranks, "eff_per_worker": speed_low / proj.workers,
        "eff_per_core": speed_low / proj.ranks, "case_time_sum_s": proj.n_cases * proj.case_cost,
        "case_time_mean_s": proj.case_cost, "overhead_s": math.nan, "busy_min_s": math.nan,
        "busy_max_s": math.nan, "imbalance": math.nan, "idle_workers": "",
        "per_case_s": proj.write_cost, "latency_s": proj.latency, "status": "model",
        "message": f"limited by {proj.limited_by}; speed-up etc. from the high wall estimate",
    }.items()}


def balance_text(p: Point) -> str:
    if not p.balance:
        return "–"
    parts = [f"r{rank}: {n} / {busy:.2f} s" for rank, (n, busy) in p.balance.items()]
    return "; ".join(parts)


def scaling_table(points: list[Point]) -> list[str]:
    lines = ["| N ranks | workers | wall [s] median (min–max) | CPU [s] | other CPU [s] "
             "| cases/s | speed-up | eff./rank | eff./worker | eff./core | Σ case time [s] "
             "| mean case [s] | overhead [s] | per worker rank: cases / Σ time | status |",
             "|" + " --- |" * 15]
    for p in points:
        wall = (f"{p.wall:.2f} ({p.wall_min:.2f}–{p.wall_max:.2f})" if math.isfinite(p.wall)
                else "–")
        over = {"no": "", "rank0": " (rank 0 shares a core)",
                "workers": f" ({p.workers} workers on {p.cores} cores)"}[
                    subscription(p.ranks, p.cores)]
        status = "ok" if p.status == "ok" else f"failed: {p.message}".replace("|", "\\|")
        lines.append("| " + " | ".join([
            f"{p.ranks}{over}", str(p.workers), wall, _f(p.cpu, ".2f"), _f(p.other_cpu, ".2f"),
            _f(p.rate if math.isfinite(p.wall) else math.nan, ".2f"), _f(p.speedup, ".2f"),
            _f(p.eff_rank, ".2f"), _f(p.eff_worker, ".2f"), _f(p.eff_core, ".2f"),
            _f(p.case_sum, ".2f"), _f(p.case_mean, ".4f"),
            _f(p.overhead if math.isfinite(p.wall) else math.nan, ".2f"), balance_text(p),
            status]) + " |")
    return lines


def cost_table(stats: list[CostStats]) -> list[str]:
    lines = ["| cases | n | Σ [s] | mean [s] | min [s] | median [s] | max [s] | max/min |",
             "|" + " --- |" * 8]
    for s in stats:
        lines.append(f"| {s.label} | {s.n} | {s.total:.2f} | {_f(s.mean, '.4f')} | "
                     f"{_f(s.minimum, '.4f')} | {_f(s.median, '.4f')} | {_f(s.maximum, '.4f')} "
                     f"| {_f(s.ratio, '.1f')} |")
    return lines


def notes(results: dict[str, list[Point]], probe: Probe, cores: int) -> list[str]:
    """Observations found by simple rules in the numbers."""
    out = []
    for key, points in results.items():
        ok = [p for p in points if math.isfinite(p.speedup)]
        for prev, cur in zip(ok, ok[1:]):
            if cur.speedup < prev.speedup * 0.97:
                out.append(f"`{key}`: N = {cur.ranks} is slower than N = {prev.ranks} "
                           f"(speed-up {cur.speedup:.2f} against {prev.speedup:.2f}).")
        two = next((p for p in ok if p.ranks == 2), None)
        if two is not None and two.speedup < 1.0:
            out.append(f"`{key}`: N = 2 (one worker) is {100 * (1 - two.speedup):.0f} % slower "
                       "than 1 rank: the same one computing process plus the MPI launch and the "
                       "hand-out latency per case.")
        base = next((p for p in ok if p.ranks == 1), None)
        for p in ok:
            grow = (p.case_mean / base.case_mean if base is not None and base.case_mean > 0
                    else math.nan)
            if p.ranks > 1 and p.workers > cores and grow > 1.1:
                out.append(f"`{key}`: at N = {p.ranks} ({p.workers} workers on {cores} "
                           f"cores) the mean case solve time is {grow:.2f}x that of 1 rank: "
                           "wall_time_s is wall clock, and time-shared workers stretch it.")
            elif p.ranks > 1 and grow > 1.05:
                out.append(f"`{key}`: at N = {p.ranks} ({p.workers} worker(s), a core each) "
                           f"the mean case solve time is {grow:.2f}x that of 1 rank: the "
                           "cases themselves ran slower (shared caches/memory, clock, rank 0's "
                           "wake-ups, other load), not the dispatch.")
            if p.ranks > 1 and p.speedup > 1.03 * min(p.workers, cores):
                out.append(f"`{key}`: at N = {p.ranks} the speed-up {p.speedup:.2f} exceeds "
                           f"what {min(p.workers, cores)} computing core(s) can give: the "
                           "1-rank run was slowed (the machine's speed drifts; see the min–max "
                           "of the repeats and the mean case times).")
            if p.idle:
                out.append(f"`{key}`: at N = {p.ranks} worker rank(s) "
                           f"{', '.join(map(str, p.idle))} ran no case.")
            if p.ranks > 1 and math.isfinite(p.imbalance) and p.imbalance > 1.15:
                out.append(f"`{key}`: at N = {p.ranks} the busiest worker's summed case time is "
                           f"{p.imbalance:.2f}x the workers' mean.")
    for key, points in results.items():
        for p in points:
            if math.isfinite(p.other_cpu) and p.other_cpu > 0.1 * p.wall:
                out.append(f"`{key}`, N = {p.ranks}: other processes used {p.other_cpu:.1f} s "
                           f"of CPU during the (median) {p.wall:.1f} s run: disturbed "
                           "(a core of this machine was partly taken).")
    pick, lat = probe.dispatch_latency()
    if math.isfinite(lat) and lat > PROBE_SLEEP_S:
        out.append(f"Hand-out latency L = {1e3 * lat:.1f} ms per case and worker (probe, N = "
                   f"{pick}): more than rank 0's {1e3 * PROBE_SLEEP_S:.1f} ms probe sleep, i.e. "
                   f"about {lat / PROBE_SLEEP_S:.1f} sleep periods per case.")
    return out


def write_markdown(path: Path, header: dict[str, str], loads: list[Workload],
                   results: dict[str, list[Point]], probe: Probe,
                   probe_points: list[Point], projections: list[Projection],
                   checks: list[tuple[str, Point, tuple[float, float, float, float]]],
                   cores: int) -> None:
    lines = ["# MPI scaling of flexmor-sweep", ""]
    lines += [f"- {key}: {value}" for key, value in header.items()]
    lines += ["", "## Workloads", ""]
    lines += ["| workload | sweep | cases | per-case solve time min / median / max [s] | max/min "
              "| Σ solve time, 1 rank [s] |", "|" + " --- |" * 6]
    stats_by_key: dict[str, CostStats] = {}
    for load in loads:
        if load.key not in results:
            continue
        p1 = next((p for p in results[load.key] if p.ranks == 1 and p.runs), None)
        ok1 = [r for r in p1.runs if r.status == "ok"] if p1 else []
        s = cost_stats("all", median_run(ok1).case_time) if ok1 else cost_stats("all",
                                                                                 np.zeros(0))
        stats_by_key[load.key] = s
        lines.append(f"| `{load.key}`: {load.title} | {load.description} | {load.n_cases} | "
                     f"{_f(s.minimum, '.4f')} / {_f(s.median, '.4f')} / {_f(s.maximum, '.4f')} "
                     f"| {_f(s.ratio, '.1f')} | {s.total:.2f} |")
    for load in loads:
        if load.key not in results:
            continue
        points = results[load.key]
        lines += ["", f"## Scaling: `{load.key}` ({load.title}, {load.n_cases} cases, "
                      f"{load.repeats} repeat(s))", ""]
        lines += scaling_table(points)
        p1 = next((p for p in points if p.ranks == 1), None)
        ok1 = [r for r in p1.runs if r.status == "ok"] if p1 else []
        if ok1:
            levels = cost_levels(median_run(ok1), load.group)
            if levels:
                lines += ["", f"Per-case solve time at 1 rank, by {load.group}:", ""]
                lines += cost_table([stats_by_key[load.key], *levels])
    lines += ["", "## Dispatch cost of flexmor-sweep (probe)", "",
              "Cases that fail at once in the scene reader; fastest of the repeats; per case = "
              "(wall of the n-case sweep − wall of the 1-case sweep) / (n − 1); L = W · per "
              "case − per case at 1 rank (what a worker waits per case for rank 0 beyond the "
              "work and the row write).", "",
              "| N ranks | start-up (1-case sweep) [s] | n cases | wall [s] | other CPU [s] "
              "| per case [ms] | cases/s | L per case and worker [ms] |", "|" + " --- |" * 8]
    for p in probe_points:
        pc = probe.per_case.get(p.ranks, math.nan)
        lines.append(f"| {p.ranks} | {_f(probe.startup.get(p.ranks, math.nan))} | {p.n_cases} "
                     f"| {_f(p.wall_min, '.3f')} | {_f(p.other_cpu, '.2f')} | "
                     f"{_f(1e3 * pc, '.3f')} | {_f(1.0 / pc if pc > 0 else math.nan, '.0f')} | "
                     f"{_f(1e3 * probe.latency(p.ranks), '.2f')} |")
    pick, lat = probe.dispatch_latency()
    lines += ["", f"- Rank 0's per-case cost t_w ≤ {_f(1e3 * probe.write_cost, '.3f')} ms "
                  "(1 rank: reading the case's scene up to its error, writing and flushing its "
                  "row): rank 0 can take at most 1/t_w = "
                  f"{_f(1.0 / probe.write_cost if probe.write_cost > 0 else math.nan, '.0f')} "
                  "results/s.",
              f"- Hand-out latency used below: L = {_f(1e3 * lat, '.2f')} ms (N = {pick})."]
    if projections:
        p0 = projections[0]
        lines += ["", f"## Projection to {p0.ranks} ranks", "",
                  f"Model: W = {p0.workers} workers, each on a core of its own, each case costing "
                  "what it cost here with 1 rank, all in: c = (wall(1 rank) − start-up) / n "
                  "(solve, scene set-up, metrics, row write). A worker's cycle is c + L, so the "
                  "workers deliver W / (c + L) cases/s; rank 0 takes at most 1 / t_w. Rate = the "
                  "smaller. Wall for n cases, greedy hand-out in file order (list scheduling): "
                  "between s + max(n / rate, c_max + L) (no tail) and s + n / rate + c_max + L "
                  "(the longest case, c_max = longest solve + c − mean solve, handed out last; "
                  "Graham's bound). s = the largest measured start-up (mpirun with more ranks, "
                  "or over several nodes, starts slower). Speed-up against s(1) + n · c; the "
                  "speed-up and efficiencies use the high (pessimistic) wall.", "",
                  "| workload | n cases | c [s] | of it outside the solve [ms] | c_max [s] "
                  "| workers' rate [cases/s] | rank 0 limit [cases/s] | limited by "
                  "| wall [s] low–high | speed-up | eff./rank | eff./worker |",
                  "|" + " --- |" * 12]
        for proj in projections:
            speed = proj.serial / proj.wall_high
            lines.append(
                f"| `{proj.workload}` | {proj.n_cases} | {proj.case_cost:.4f} | "
                f"{1e3 * proj.outside_solve:.1f} | {proj.case_max:.4f} | {proj.rate_workers:.0f} | {_f(proj.rate_rank0, '.0f')} "
                f"| {proj.limited_by} | {proj.wall_low:.2f}–{proj.wall_high:.2f} | "
                f"{speed:.1f} | {speed / proj.ranks:.2f} | {speed / proj.workers:.2f} |")
        lines += ["", "Rank 0 becomes the limit when W · t_w > c + L, i.e. for cases cheaper "
                      f"than about {_f(p0.workers * p0.write_cost - p0.latency, '.4f')} s at "
                      f"W = {p0.workers}; the hand-out latency costs each worker L / (c + L) of "
                      "its time (" + ", ".join(
                          f"`{key}` {100 * pr.latency / (pr.case_cost + pr.latency):.1f} %"
                          for key, pr in {pr.workload: pr for pr in projections}.items())
                  + ").",
                  "",
                  "Assumptions: one rank per core and no slowdown of a case when all cores are "
                  "busy (shared memory bandwidth, clock, other jobs); L and t_w as measured here "
                  "(shared-memory MPI on one node; across nodes add the network latency to L); "
                  "rank 0 needs no core of its own (it sleeps 0.5 ms between bursts of probes); no failed "
                  "cases; start-up as measured for at most "
                  f"{max(probe.startup, default=1)} ranks."]
    if checks:
        lines += ["", "### Model check against the measurements", "",
                  "The same model at the measured rank counts, with the start-up measured "
                  "at that N: (a) min(W, cores) workers and the 1-rank case costs; (b) W "
                  "workers and the mean case solve time measured at that N (its stretch "
                  "over 1 rank given; the longest case stretched alike). (a) is what the "
                  "projection assumes; where the measurement exceeds (a) but agrees with "
                  "(b), cases ran slower at that N (cores shared or busy), not the dispatch.",
                  "",
                  "| workload | N ranks | (a) model wall [s] | case stretch | (b) model wall [s] "
                  "| measured wall [s] |", "|" + " --- |" * 6]
        for key, p, (low, high, low2, high2) in checks:
            base = next(q for q in results[key] if q.ranks == 1)
            lines.append(f"| `{key}` | {p.ranks} | {low:.2f}–{high:.2f} | "
                         f"{_f(p.case_mean / base.case_mean, '.2f')}x | {low2:.2f}–{high2:.2f} "
                         f"| {_f(p.wall, '.2f')} |")
    found = notes(results, probe, cores)
    lines += ["", "## Observations (found by rules in the numbers)", ""]
    lines += [f"- {n}" for n in found] if found else ["- none"]
    lines += [
        "", "## How to read", "",
        f"N is the number of MPI ranks (N = 1: no mpirun, rank 0 runs the cases itself). For "
        "N > 1 rank 0 only hands out cases and writes each result, so W = N − 1 ranks compute: "
        "efficiency per worker (speed-up / W) is the one that should stay near 1; efficiency per "
        "rank (speed-up / N) counts rank 0 as lost. This machine has "
        f"{cores} core(s): more than {cores} workers time-share the cores, so efficiency per "
        f"core (speed-up / min(W, cores)) is the fair measure there, and N = {cores + 1} "
        "(one worker per core, rank 0 asleep in its 0.5 ms probe loop) is the sweet spot; ranks "
        f"beyond {cores + 1} only add time sharing. `wall` is the whole command (launch, "
        "validation, file creation, every case, exit); `Σ case time` sums the per-case solve "
        "times from the result file (the median run's; these are wall clock, so time sharing "
        "stretches them); `overhead` = wall − Σ case time / W is what the cases' solve times do "
        "not explain: start-up, per-case scene set-up and metrics, hand-out latency, the "
        "tail (workers idle while the last cases finish) and, when oversubscribed, "
        "negative contributions from stretched case times. The per-worker column gives each "
        "worker rank's case count and summed solve time (load balance); a worker with 0 cases "
        "was idle. The 64-rank projection is a model, not a measurement: see its assumptions.",
    ]
    path.write_text("\n".join(lines) + "\n")


# --- main -------------------------------------------------------------------------------------


def parse_ranks(text: str) -> list[int]:
    try:
        ranks = sorted({int(part) for part in text.split(",") if part.strip()})
    except ValueError:
        raise UserError(f"--ranks '{text}': expected a comma-separated list of integers") from None
    if not ranks or ranks[0] < 1:
        raise UserError(f"--ranks '{text}': rank counts must be at least 1")
    if ranks[0] != 1:
        raise UserError(f"--ranks '{text}': must include 1 (the baseline of the speed-ups)")
    return ranks


def parse_args(argv: Sequence[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        prog=PROG, description="MPI scaling of flexmor-sweep (cases/s, speed-up, efficiency "
                               "against the number of ranks) with a projection to many ranks.")
    parser.add_argument("--bin", type=Path, default=DEFAULT_BIN,
                        help=f"flexmor-sweep executable (default: "
                             f"{DEFAULT_BIN.relative_to(ROOT)} in the repository)")
    parser.add_argument("--mpirun", default=None,
                        help="MPI launcher (default: $MPIEXEC, else mpirun, else mpiexec on "
                             "PATH)")
    parser.add_argument("--ranks", default=None,
                        help="comma-separated rank counts, must include 1 (default 1,2,3,4; "
                             "1,2 with --quick)")
    parser.add_argument("--repeats", type=int, default=None,
                        help="runs per rank count of the reduced workload and the probe, the "
                             "median wall is reported (default 3; 1 with --quick)")
    parser.add_argument("--repeats-full", type=int, default=1,
                        help="runs per rank count of the full-model workload (default 1)")
    parser.add_argument("--probe-cases", type=int, default=None,
                        help="cases of the dispatch probe (default 500; 40 with --quick)")
    parser.add_argument("--no-full", action="store_true",
                        help="skip the full-model workload (input/sweep_two_link.nml)")
    parser.add_argument("--project-ranks", type=int, default=64,
                        help="rank count of the projection (default 64)")
    parser.add_argument("--out-dir", type=Path, default=Path("bench_out"),
                        help="folder for sweep_scaling.md/.csv (default: bench_out)")
    parser.add_argument("--quick", action="store_true",
                        help="4 reduced cases, ranks 1,2, 40 probe cases, no full workload, "
                             "one repeat (for the tests)")
    parser.add_argument("--timeout", type=float, default=600.0,
                        help="limit per launch in seconds; a launch past it counts as failed "
                             "(default 600)")
    return parser.parse_args(argv)


def check_args(args: argparse.Namespace) -> None:
    args.ranks = parse_ranks(args.ranks or ("1,2" if args.quick else "1,2,3,4"))
    if args.repeats is None:
        args.repeats = 1 if args.quick else 3
    if args.probe_cases is None:
        args.probe_cases = 40 if args.quick else 500
    if args.quick:
        args.no_full = True
    if args.repeats < 1 or args.repeats_full < 1:
        raise UserError("--repeats and --repeats-full must be at least 1")
    if args.probe_cases < 2:
        raise UserError("--probe-cases must be at least 2")
    if args.project_ranks < 2:
        raise UserError("--project-ranks must be at least 2")
    if not args.timeout > 0.0:
        raise UserError("--timeout must be positive")
    if not args.bin.is_file() or not os.access(args.bin, os.X_OK):
        raise UserError(f"{args.bin}: no flexmor-sweep executable there; build it first "
                        "(cmake -S . -B build -DCMAKE_BUILD_TYPE=Release && cmake --build "
                        "build) or give --bin")
    args.bin = args.bin.resolve()
    if max(args.ranks) > 1:
        launcher = (args.mpirun or os.environ.get("MPIEXEC") or shutil.which("mpirun")
                    or shutil.which("mpiexec"))
        found = shutil.which(launcher) if launcher else None
        if found is None:
            raise UserError(f"{launcher or 'mpirun'}: MPI launcher not found; give --mpirun "
                            "or --ranks 1")
        args.mpirun = found
    else:
        args.mpirun = None
    for path in (REDUCED_BASE, FULL_SWEEP):
        if not path.is_file():
            raise UserError(f"{path}: input missing")
    if args.out_dir.exists() and not args.out_dir.is_dir():
        raise UserError(f"{args.out_dir}: exists and is not a folder")


def main(argv: Sequence[str] | None = None) -> int:
    args = parse_args(argv)
    try:
        check_args(args)
    except UserError as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return 2
    start = time.perf_counter()
    load_start = os.getloadavg()[0]
    cores = usable_cores()
    with tempfile.TemporaryDirectory(prefix="bench_sweep_") as tmp:
        work = Path(tmp)
        loads = make_workloads(args, work)
        print(f"{PROG}: ranks {','.join(map(str, args.ranks))}, {cores} cores, workloads "
              f"{', '.join(f'{w.key} ({w.n_cases} cases x {w.repeats})' for w in loads)}",
              flush=True)
        runs = run_all(loads, args, work)
    elapsed = time.perf_counter() - start
    results = {w.key: summarize(w, runs, args.ranks, cores) for w in loads}
    probe_points = results.pop("probe_serial") + results.pop("probe")
    probe = make_probe(results.pop("probe1"), probe_points)
    measured = [w for w in loads if w.key in results]

    projections: list[Projection] = []
    checks: list[tuple[str, Point, tuple[float, float, float, float]]] = []
    if probe.startup:
        for load in measured:
            p1 = next(p for p in results[load.key] if p.ranks == 1)
            if not math.isfinite(p1.wall):
                continue
            w = workers_of(args.project_ranks)
            for n in dict.fromkeys((load.n_cases, 100 * w)):
                projections.append(project(p1, probe, args.project_ranks, n, cores))
            for p in results[load.key]:
                if p.ranks > 1 and math.isfinite(p.wall):
                    checks.append((load.key, p, model_wall(p1, p, probe, cores)))

    version = next((r.version for r in runs if r.version), "unknown")
    header = {
        "Command": f"`{command_line(PROG, argv)}` (in `{os.getcwd()}`)",
        "Date": datetime.now().astimezone().isoformat(timespec="seconds"),
        "Machine": f"{cpu_model()}, {cores} cores ({os.cpu_count()} CPUs), {platform.system()} "
                   f"{platform.release()}; 1-min load average {load_start:.2f} at the start, "
                   f"{os.getloadavg()[0]:.2f} at the end (other processes skew times). With "
                   f"{cores} cores, N = {cores + 1} puts rank 0 (mostly asleep) on a shared "
                   f"core and N > {cores + 1} makes the workers time-share the cores.",
        "flexmor": f"version {version}, binary `{args.bin}`, git commit {git_commit(ROOT)}",
        "MPI": mpi_version(args.mpirun) + "; environment " + ", ".join(
            f"{k}={v}" for k, v in RUN_ENV.items()),
        "Timing": "wall clock of the whole command (launch to exit), fresh result file each "
                  "run; median (min–max) of the repeats; CPU = user + system time of the "
                  "command and its children (median)",
        "Whole benchmark": f"{elapsed:.0f} s",
    }
    rows = [point_row(p, repeats=next(w.repeats for w in loads if w.key == key))
            for key, points in results.items() for p in points]
    rows += probe_rows(probe, probe_points)
    rows += [projection_row(proj, cores) for proj in projections]
    try:
        args.out_dir.mkdir(parents=True, exist_ok=True)
        write_csv(rows, CSV_COLUMNS, args.out_dir / "sweep_scaling.csv")
        write_markdown(args.out_dir / "sweep_scaling.md", header, measured, results, probe,
                       probe_points, projections, checks, cores)
    except OSError as exc:
        print(f"{PROG}: error: cannot write into {args.out_dir}: {exc}", file=sys.stderr)
        return 2
    print(f"wrote {args.out_dir / 'sweep_scaling.md'}, sweep_scaling.csv ({elapsed:.0f} s in "
          "all)")
    failed = [f"{r.workload} N={r.ranks} repeat {r.rep + 1}" for r in runs if r.status != "ok"]
    if failed:
        print(f"{PROG}: {len(failed)} run(s) failed: {', '.join(failed)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
