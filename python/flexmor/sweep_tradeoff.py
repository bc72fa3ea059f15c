"""Speed/accuracy trade-off of a flexmor-sweep that varies model fidelity.

    flexmor-sweep-tradeoff SWEEP.h5 --metric max_tip_deflection \\
        --fidelity reduction.n_modes [--fidelity dynamic.rtol ...] [--relative] \\
        [--higher PARAM] [--lower PARAM] [--where PARAM=VALUE ...] -o tradeoff.png

The --fidelity parameters set how accurate a case is; every other swept parameter (the motion,
a load, ...) sets the problem. Cases are grouped by the values of the other parameters; within a
group the reference is the highest-fidelity case that ran ok, and the error of a case is
``|metric - metric_ref|`` (divided by ``|metric_ref|`` with --relative).

Which way a fidelity parameter improves is inferred from its name (the part after the last
'.'): higher is better for ``n_modes``, ``n_elements`` and other ``n_*`` counts; lower is
better for ``rtol``, ``atol``, ``dt`` and other ``*tol`` / ``*_dt`` names. --higher PARAM or
--lower PARAM overrides (or supplies) the direction. Convention: a value 0 of ``n_modes``
(e.g. reduction.n_modes = 0) is a full, unreduced run, the highest fidelity of all, and reads
'full' in the table and legend.

With several fidelity parameters the reference of a group is the case that is best in every
one of them; where no case is (e.g. a zip sweep), the best in the order the --fidelity options
are given, with a note on stderr. A note also says when a group's highest-fidelity case failed
or has not run (the best case that ran ok is then the reference).

Output: the plot (wall time on x, error on y, both log; colour = fidelity level, low to high;
references, error 0, are not drawn, their median wall time is the dashed line) and, on stdout,
one row per fidelity level: cases, how many were references, median wall time, median speed-up
over the group's reference (t_ref / t), median and max error.

Failed and not-run cases are left out with a note on stderr. Exit status 0 on success, 2 with a
one-line message (no traceback) for a missing, unreadable or non-sweep file, an unknown metric
or parameter (the available names are listed), or a fidelity parameter whose direction cannot
be inferred.
"""
from __future__ import annotations

import argparse
import math
import os
import sys
from dataclasses import dataclass, field

import numpy as np

from flexmor.sweep import (METRIC_UNITS, Sweep, SweepFileError, case_number,
                           fmt_param, load_sweep, parse_where, skip_note, where_mask)

PROG = "flexmor-sweep-tradeoff"

HIGHER_NAMES = ("n_modes", "n_elements")
LOWER_NAMES = ("rtol", "atol", "dt")


class UserError(Exception):
    """A problem the user can fix: one line, exit status 2."""


def infer_higher(name: str) -> bool | None:
    """True when a higher value of parameter ``name`` means higher fidelity, False when a lower
    one does, None when the name does not tell."""
    last = name.rsplit(".", 1)[-1].lower()
    if last in HIGHER_NAMES or last.startswith("n_"):
        return True
    if last in LOWER_NAMES or last.endswith("tol") or last.endswith("_dt"):
        return False
    return None


def directions(fidelity: list[str], higher: list[str], lower: list[str]) -> list[tuple[str, bool]]:
    """``(name, higher_is_better)`` per fidelity parameter; :class:`UserError` when a direction
    is contradictory, not inferable, or given for a parameter not in --fidelity."""
    if len(set(fidelity)) != len(fidelity):
        raise UserError(f"--fidelity given twice for the same parameter: {', '.join(fidelity)}")
    for name in [*higher, *lower]:
        if name not in fidelity:
            raise UserError(f"--higher/--lower {name}: not a --fidelity parameter")
    both = set(higher) & set(lower)
    if both:
        raise UserError(f"both --higher and --lower for {', '.join(sorted(both))}")
    result = []
    for name in fidelity:
        up = True if name in higher else False if name in lower else infer_higher(name)
        if up is None:
            raise UserError(f"cannot tell whether higher or lower values of {name} mean higher "
                            f"fidelity: add --higher {name} or --lower {name}")
        result.append((name, up))
    return result


def fidelity_scores(sweep: Sweep, fidelity: list[tuple[str, bool]]) -> np.ndarray:
    """(n_cases, n_fidelity) scores, larger = higher fidelity: the value, or minus the value
    when lower is better; n_modes 0 (full model) scores +inf."""
    columns = []
    for name, up in fidelity:
        v = np.array(sweep.parameter(name), dtype=float)
        if name.rsplit(".", 1)[-1] == "n_modes":
            v = np.where(v == 0, np.inf, v)
        columns.append(v if up else -v)
    return np.column_stack(columns)


def level_label(fidelity: list[tuple[str, bool]], values: tuple[float, ...] | np.ndarray) -> str:
    return ", ".join(f"{n}={fmt_param(n, v)}" for (n, _), v in zip(fidelity, values))


@dataclass
class Tradeoff:
    """Per case (n_cases,): ``group`` id (-1 when not used), ``reference`` case index (-1),
    ``error`` (NaN when not used); ``usable`` the cases compared; ``notes`` for stderr."""

    metric: str
    fidelity: list[tuple[str, bool]]
    relative: bool
    usable: np.ndarray
    group: np.ndarray
    group_labels: list[str]
    reference: np.ndarray
    error: np.ndarray
    scores: np.ndarray
    notes: list[str] = field(default_factory=list)


def pick_reference(scores: np.ndarray) -> tuple[int, bool]:
    """Row of the case best in every column (``(row, True)``), else the lexicographic best in
    column order (``(row, False)``)."""
    for i in range(scores.shape[0]):
        if np.all(scores[i] >= scores):
            return i, True
    order = np.lexsort(scores.T[::-1])  # last key is the primary: column 0
    return int(order[-1]), False


def compute_tradeoff(sweep: Sweep, metric: str, fidelity: list[tuple[str, bool]],
                     relative: bool = False, selected: np.ndarray | None = None) -> Tradeoff:
    """Group the cases, pick each group's reference and the error of every case."""
    values = sweep.metric(metric)
    selected = np.ones(sweep.n_cases, bool) if selected is None else selected
    usable = selected & sweep.ok & np.isfinite(values) & np.isfinite(sweep.wall_time_s)
    scores = fidelity_scores(sweep, fidelity)
    names = {n for n, _ in fidelity}
    problem = [n for n in sweep.parameter_names if n not in names]
    t = Tradeoff(metric, fidelity, relative, usable, np.full(sweep.n_cases, -1), [],
                 np.full(sweep.n_cases, -1), np.full(sweep.n_cases, np.nan), scores)
    rows = (np.column_stack([sweep.parameters[n] for n in problem]) if problem
            else np.zeros((sweep.n_cases, 0)))
    keys = np.unique(rows[usable], axis=0) if usable.any() else np.zeros((0, rows.shape[1]))
    for g, key in enumerate(keys):
        in_group = selected & np.all(rows == key, axis=1)
        label = ", ".join(f"{n}={fmt_param(n, v)}" for n, v in zip(problem, key)) or "all"
        t.group_labels.append(label)
        _fill_group(sweep, t, values, g, label, in_group)
    return t


def _fill_group(sweep: Sweep, t: Tradeoff, values: np.ndarray, g: int, label: str,
                in_group: np.ndarray) -> None:
    idx = np.flatnonzero(in_group & t.usable)
    row, dominant = pick_reference(t.scores[idx])
    ref = int(idx[row])
    if not dominant:
        level = level_label(t.fidelity, _level(sweep, t, ref))
        t.notes.append(f"group {label}: no case is best in every fidelity parameter; reference "
                       f"case {case_number(ref)} ({level})")
    better = [int(i) for i in np.flatnonzero(in_group & ~t.usable)
              if np.all(t.scores[i] >= t.scores[ref]) and np.any(t.scores[i] > t.scores[ref])]
    if better:
        t.notes.append(f"group {label}: higher-fidelity case(s) "
                       f"{', '.join(str(case_number(i)) for i in better)} did not run ok; "
                       f"reference is case {case_number(ref)}")
    t.group[idx] = g
    t.reference[idx] = ref
    error = np.abs(values[idx] - values[ref])
    if t.relative:
        scale = abs(values[ref])
        if scale == 0:
            t.notes.append(f"group {label}: reference {t.metric} is 0; no relative error")
            error = np.full(idx.size, np.nan)
        else:
            error = error / scale
    t.error[idx] = error
    t.error[ref] = 0.0


def _level(sweep: Sweep, t: Tradeoff, i: int) -> tuple[float, ...]:
    return tuple(float(sweep.parameters[n][i]) for n, _ in t.fidelity)


@dataclass
class LevelRow:
    label: str
    n: int
    n_ref: int
    wall_median: float
    speedup_median: float
    error_median: float
    error_max: float


def level_rows(sweep: Sweep, t: Tradeoff) -> list[LevelRow]:
    """One row per fidelity level (value combination) of the compared cases, lowest fidelity
    first."""
    idx = np.flatnonzero(t.group >= 0)
    if idx.size == 0:
        return []
    levels = np.column_stack([sweep.parameters[n][idx] for n, _ in t.fidelity])
    keys, inverse = np.unique(levels, axis=0, return_inverse=True)
    inverse = inverse.ravel()
    order = sorted(range(len(keys)), key=lambda k: tuple(t.scores[idx[inverse == k][0]]))
    rows = []
    for k in order:
        cases = idx[inverse == k]
        wall = sweep.wall_time_s[cases]
        speedup = sweep.wall_time_s[t.reference[cases]] / wall
        err = t.error[cases]
        finite = err[np.isfinite(err)]
        rows.append(LevelRow(
            level_label(t.fidelity, keys[k]), int(cases.size),
            int(np.sum(t.reference[cases] == cases)), float(np.median(wall)),
            float(np.median(speedup)) if np.all(wall > 0) else math.nan,
            float(np.median(finite)) if finite.size else math.nan,
            float(np.max(finite)) if finite.size else math.nan))
    return rows


def format_rows(rows: list[LevelRow], t: Tradeoff) -> str:
    kind = "rel_error" if t.relative else "error"
    header = ["fidelity", "cases", "refs", "wall_median_s", "speedup_median",
              f"{kind}_median", f"{kind}_max"]
    cells = [[r.label, str(r.n), str(r.n_ref), f"{r.wall_median:.4g}", f"{r.speedup_median:.3g}",
              f"{r.error_median:.3g}", f"{r.error_max:.3g}"] for r in rows]
    widths = [max(len(c[k]) for c in [header, *cells]) for k in range(len(header))]
    lines = [header[0].ljust(widths[0]) + "  " + "  ".join(
        h.rjust(w) for h, w in zip(header[1:], widths[1:]))]
    for c in cells:
        lines.append(c[0].ljust(widths[0]) + "  " + "  ".join(
            v.rjust(w) for v, w in zip(c[1:], widths[1:])))
    return "\n".join(lines)


def plot_tradeoff(sweep: Sweep, t: Tradeoff, output: str, dpi: int = 150) -> int:
    """Draw wall time vs error (log-log) coloured by fidelity level; returns the number of
    points drawn (compared cases with a positive error)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    drawn = np.flatnonzero((t.group >= 0) & (t.reference != np.arange(sweep.n_cases))
                           & np.isfinite(t.error) & (t.error > 0))
    rows = level_rows(sweep, t)
    fig, ax = plt.subplots(figsize=(7.5, 5.0))
    try:
        cmap = plt.get_cmap("viridis")
        for k, row in enumerate(rows):
            cases = [i for i in drawn if level_label(t.fidelity, _level(sweep, t, i)) == row.label]
            if not cases:
                continue
            color = cmap(k / max(1, len(rows) - 1))
            ax.scatter(sweep.wall_time_s[cases], t.error[cases], color=color, s=30,
                       edgecolors="k", linewidths=0.4, label=row.label, zorder=3)
        refs = np.unique(t.reference[t.group >= 0])
        if refs.size:
            ax.axvline(float(np.median(sweep.wall_time_s[refs])), color="0.4", ls="--", lw=1.0,
                       label="reference (median wall time)")
        ax.set_xscale("log")
        ax.set_yscale("log")
        unit = "" if t.relative else METRIC_UNITS.get(t.metric, "")
        kind = "relative error" if t.relative else "error"
        ax.set_xlabel("wall time (s)")
        ax.set_ylabel(f"{kind} of {t.metric}" + (f" ({unit})" if unit else ""))
        title = f"Speed/accuracy: {len(t.group_labels)} group(s), reference = highest fidelity"
        if sweep.attrs.get("title"):
            title = f"{sweep.attrs['title']}\n{title}"
        ax.set_title(title, fontsize=10)
        ax.grid(True, which="both", lw=0.3)
        ax.legend(fontsize=8, loc="best")
        fig.tight_layout()
        fig.savefig(output, dpi=dpi)
    finally:
        plt.close(fig)
    return int(drawn.size)


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        prog=PROG, description="Wall time against error relative to the highest-fidelity case, "
                               "per group of the non-fidelity parameters.")
    parser.add_argument("file", metavar="SWEEP.h5", help="sweep result file")
    parser.add_argument("--metric", default="max_tip_deflection",
                        help="metric whose error is measured (default: max_tip_deflection)")
    parser.add_argument("--fidelity", action="append", required=True, metavar="PARAM",
                        help="a parameter that sets the model fidelity (repeatable)")
    parser.add_argument("--higher", action="append", default=[], metavar="PARAM",
                        help="higher values of PARAM are higher fidelity")
    parser.add_argument("--lower", action="append", default=[], metavar="PARAM",
                        help="lower values of PARAM are higher fidelity")
    parser.add_argument("--relative", action="store_true",
                        help="error relative to |metric of the reference|")
    parser.add_argument("--where", metavar="PARAM=VALUE", action="append", default=[],
                        help="keep only the cases with PARAM = VALUE (repeatable)")
    parser.add_argument("-o", "--output", default="tradeoff.png",
                        help="image to write (default: tradeoff.png)")
    parser.add_argument("--dpi", type=int, default=150, help="resolution (default: 150)")
    return parser.parse_args(argv)


def prepare(args: argparse.Namespace) -> tuple[Sweep, Tradeoff]:
    where = [parse_where(w) for w in args.where]
    fidelity = directions(args.fidelity, args.higher, args.lower)
    sweep = load_sweep(args.file)
    sweep.metric(args.metric)
    for name, _ in fidelity:
        sweep.parameter(name)
    selected = where_mask(sweep, where)
    t = compute_tradeoff(sweep, args.metric, fidelity, args.relative, selected)
    note = skip_note(sweep, selected, sweep.metric(args.metric), args.metric)
    if note:
        t.notes.insert(0, note)
    singles = int(sum(np.sum(t.group == g) == 1 for g in range(len(t.group_labels))))
    if singles:
        t.notes.append(f"{singles} of {len(t.group_labels)} group(s) hold a single case (its own "
                       f"reference): nothing to compare there; are the non-fidelity parameters "
                       f"sampled at random?")
    if not t.group_labels:
        raise UserError(f"{args.file}: no ok case with a finite {args.metric} to compare")
    out_dir = os.path.dirname(os.path.abspath(args.output))
    if not os.path.isdir(out_dir):
        raise UserError(f"{args.output}: the folder {out_dir} does not exist")
    return sweep, t


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    try:
        sweep, t = prepare(args)
    except (SweepFileError, UserError, ValueError) as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return 2
    for note in t.notes:
        print(f"{PROG}: note: {note}", file=sys.stderr)
    print(format_rows(level_rows(sweep, t), t))
    try:
        drawn = plot_tradeoff(sweep, t, args.output, args.dpi)
    except (OSError, ValueError) as exc:
        print(f"{PROG}: error: cannot write {args.output}: {exc}", file=sys.stderr)
        return 2
    compared = int(np.sum((t.group >= 0) & (t.reference != np.arange(sweep.n_cases))))
    if drawn < compared:
        print(f"{PROG}: note: {compared - drawn} non-reference case(s) with error 0 (or no "
              f"error) not drawn on the log axis", file=sys.stderr)
    print(f"wrote {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
