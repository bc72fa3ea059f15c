"""Summarise a flexmor-sweep result file: one row per case, then totals.

    flexmor-sweep-summary SWEEP.h5 [--csv OUT.csv] [--failed]

Rows: case number (from 1, as flexmor-sweep's progress lines print it: array index + 1), the
swept parameters, status ('ok', 'not run' or the failure kind with its flexmor exit code, e.g.
'numerical (3)'), wall time, MPI rank, the metrics and, for a failed case, its message.

Totals: cases done (ok or failed) out of all, failed (by kind), not run, total and median wall
time of the cases that ran, the per-case cost spread of the ok cases (min/median/max wall time
and the max/min ratio; a large ratio means uneven work per case, which the dynamic hand-out of
cases to MPI ranks absorbs) and the summed wall time per rank.

--failed lists only the failed cases (the totals stay those of the whole sweep). --csv also
writes the listed rows as CSV: columns case (number from 1), <parameters>, status (exit code,
-1 not run), status_text, wall_time_s, rank, <metrics>, message; full precision, NaN as 'nan'.

Exit status 0 on success, 2 with a one-line message (no traceback) for a missing or unreadable
file, a file that is not a sweep file, or an unwritable CSV file.
"""
from __future__ import annotations

import argparse
import csv
import math
import sys
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from flexmor.sweep import (Sweep, SweepFileError, case_number, fmt_value,
                           load_sweep, status_text)

PROG = "flexmor-sweep-summary"


@dataclass
class Totals:
    """Counts and wall-time statistics of a sweep (seconds; NaN where there is no case)."""

    n_cases: int
    n_ok: int
    n_failed: int
    n_not_run: int
    failed_by_kind: dict[str, int] = field(default_factory=dict)
    wall_total: float = math.nan
    wall_median: float = math.nan
    n_timed: int = 0
    cost_min: float = math.nan
    cost_median: float = math.nan
    cost_max: float = math.nan
    cost_ratio: float = math.nan
    wall_by_rank: dict[int, float] = field(default_factory=dict)

    @property
    def n_done(self) -> int:
        return self.n_ok + self.n_failed


def compute_totals(sweep: Sweep) -> Totals:
    """Counts by status and the wall-time statistics of :class:`Totals`."""
    totals = Totals(sweep.n_cases, int(sweep.ok.sum()), int(sweep.failed.sum()),
                    int(sweep.not_run.sum()))
    for code in sweep.status[sweep.failed]:
        kind = status_text(code)
        totals.failed_by_kind[kind] = totals.failed_by_kind.get(kind, 0) + 1
    ran = ~sweep.not_run & np.isfinite(sweep.wall_time_s)
    if ran.any():
        totals.n_timed = int(ran.sum())
        totals.wall_total = float(sweep.wall_time_s[ran].sum())
        totals.wall_median = float(np.median(sweep.wall_time_s[ran]))
        for r in np.unique(sweep.rank[ran]):
            totals.wall_by_rank[int(r)] = float(sweep.wall_time_s[ran & (sweep.rank == r)].sum())
    cost = sweep.wall_time_s[sweep.ok & np.isfinite(sweep.wall_time_s)]
    if cost.size:
        totals.cost_min, totals.cost_max = float(cost.min()), float(cost.max())
        totals.cost_median = float(np.median(cost))
        totals.cost_ratio = totals.cost_max / totals.cost_min if totals.cost_min > 0 else math.inf
    return totals


def case_indices(sweep: Sweep, only_failed: bool = False) -> np.ndarray:
    """Indices of the cases listed: all, or the failed ones."""
    return np.flatnonzero(sweep.failed) if only_failed else np.arange(sweep.n_cases)


def csv_header(sweep: Sweep) -> list[str]:
    return ["case", *sweep.parameter_names, "status", "status_text", "wall_time_s", "rank",
            *sweep.metric_names, "message"]


def csv_row(sweep: Sweep, i: int) -> list[Any]:
    return [case_number(i), *(repr(float(v[i])) for v in sweep.parameters.values()),
            int(sweep.status[i]), status_text(sweep.status[i]), repr(float(sweep.wall_time_s[i])),
            int(sweep.rank[i]),
            *(repr(float(v[i])) for v in sweep.metrics.values()), sweep.messages[i]]


def text_header(sweep: Sweep) -> list[str]:
    return ["case", *sweep.parameter_names, "status", "wall_s", "rank", *sweep.metric_names,
            "message"]


def text_row(sweep: Sweep, i: int) -> list[str]:
    rank = str(int(sweep.rank[i])) if sweep.rank[i] >= 0 else "-"
    wall = sweep.wall_time_s[i]
    return [str(case_number(i)), *(fmt_value(v[i]) for v in sweep.parameters.values()),
            status_text(sweep.status[i]), f"{wall:.3g}" if np.isfinite(wall) else "-", rank,
            *(f"{v[i]:.6g}" if np.isfinite(v[i]) else "-" for v in sweep.metrics.values()),
            sweep.messages[i] if sweep.failed[i] else ""]


def format_table(header: list[str], rows: list[list[str]]) -> str:
    """Aligned columns: the last (message) left-aligned, the others right-aligned."""
    widths = [max(len(r[k]) for r in [header, *rows]) for k in range(len(header) - 1)]
    lines = []
    for row in [header, *rows]:
        cells = [cell.rjust(w) for cell, w in zip(row, widths)]
        lines.append("  ".join([*cells, row[-1]]).rstrip())
    return "\n".join(lines)


def seconds(value: float) -> str:
    return "-" if math.isnan(value) else f"{value:.3g} s"


def format_totals(t: Totals) -> str:
    kinds = ", ".join(f"{kind}: {n}" for kind, n in sorted(t.failed_by_kind.items()))
    lines = [
        f"done: {t.n_done}/{t.n_cases} cases ({t.n_ok} ok, {t.n_failed} failed)",
        f"failed: {t.n_failed}" + (f" ({kinds})" if kinds else ""),
        f"not run: {t.n_not_run}",
        f"wall time: total {seconds(t.wall_total)}, median {seconds(t.wall_median)} "
        f"over {t.n_timed} cases that ran",
    ]
    if not math.isnan(t.cost_min):
        ratio = "inf" if math.isinf(t.cost_ratio) else f"{t.cost_ratio:.3g}"
        lines.append(f"cost per case (ok cases): min {seconds(t.cost_min)}, median "
                     f"{seconds(t.cost_median)}, max {seconds(t.cost_max)}, max/min {ratio}")
    if t.wall_by_rank:
        busy = t.wall_by_rank
        lines.append(f"ranks: {len(busy)} ran cases; summed wall time per rank min "
                     f"{seconds(min(busy.values()))}, max {seconds(max(busy.values()))}")
    return "\n".join(lines)


def format_heading(sweep: Sweep) -> str:
    a = sweep.attrs
    parts = [f"mode {a['mode']}" if "mode" in a else "", f"{sweep.n_cases} cases",
             f"parameters: {', '.join(sweep.parameter_names)}",
             f"node {a['node']}" if a.get("node") else ""]
    title = f" '{a['title']}'" if a.get("title") else ""
    return f"{sweep.path}{title}: " + "; ".join(p for p in parts if p)


def summary_text(sweep: Sweep, only_failed: bool = False) -> str:
    """The heading, the table (or a line saying there are no failed cases) and the totals."""
    rows = [text_row(sweep, i) for i in case_indices(sweep, only_failed)]
    table = format_table(text_header(sweep), rows) if rows else (
        "no failed cases" if only_failed else "no cases")
    return f"{format_heading(sweep)}\n\n{table}\n\n{format_totals(compute_totals(sweep))}"


def write_csv(sweep: Sweep, output: str, only_failed: bool = False) -> None:
    """The listed rows as CSV (see the module docstring for the columns)."""
    with open(output, "w", newline="", encoding="utf-8") as out:
        writer = csv.writer(out)
        writer.writerow(csv_header(sweep))
        for i in case_indices(sweep, only_failed):
            writer.writerow(csv_row(sweep, int(i)))


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        prog=PROG, description="Table of the cases of a flexmor-sweep result file and totals "
                               "(done, failed, not run, wall time, cost spread).")
    parser.add_argument("file", metavar="SWEEP.h5", help="sweep result file")
    parser.add_argument("--csv", metavar="OUT.csv", default=None,
                        help="also write the listed rows as CSV")
    parser.add_argument("--failed", action="store_true", help="list only the failed cases")
    return parser.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    try:
        sweep = load_sweep(args.file)
    except SweepFileError as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return 2
    print(summary_text(sweep, args.failed))
    if args.csv is not None:
        try:
            write_csv(sweep, args.csv, args.failed)
        except OSError as exc:
            print(f"{PROG}: error: cannot write {args.csv}: {exc.strerror or exc}",
                  file=sys.stderr)
            return 2
        print(f"wrote {args.csv}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
