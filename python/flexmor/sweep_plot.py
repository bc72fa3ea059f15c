"""Plot a metric of a flexmor-sweep result file over one or two swept parameters.

    flexmor-sweep-plot SWEEP.h5 --metric NAME --x PARAM [--by PARAM] \\
        [--where PARAM=VALUE ...] -o out.png
    flexmor-sweep-plot SWEEP.h5 --metric NAME --x PARAM --y PARAM \\
        [--where PARAM=VALUE ...] -o out.png

Over one parameter (--x): a line of the metric against x; with --by a line per value of that
parameter. Other swept parameters that still vary among the selected cases also get a line per
value combination (legend 'a=1, b=2'); where that would give more than --max-lines lines, the
script stops and asks to fix them with --where PARAM=VALUE (repeatable; a case is kept when it
matches every filter).

Over two parameters (--x and --y): a colour map of the metric. When the selected cases form a
full grid (every x value with every y value, once) the cells are drawn with pcolormesh (failed
or not-run cells left blank and marked x); otherwise a filled contour of the scattered cases
(tricontourf, points overlaid), or coloured points alone on log axes or when there are too few
points to triangulate. Every other varying parameter must be fixed with --where.

The metric may also be 'wall_time_s' (the cost of each case). A parameter axis is logarithmic
with --logx/--logy, or by itself when its values are all positive and span three decades or more
(the metric axis and colour scale likewise; --logc for the colour scale; --no-auto-log turns the
automatic choice off). A value 0 of reduction.n_modes (a full, unreduced run) reads 'full' in
legends.

Failed, not-run and ok cases without a finite metric are left out with a note on stderr. Exit
status 0 on success, 2 with a one-line message (no traceback) for a missing, unreadable or
non-sweep file, an unknown metric or parameter (the available names are listed), a --where value
no case has, or parameters that must be fixed with --where.
"""
from __future__ import annotations

import argparse
import os
import sys
from dataclasses import dataclass

import numpy as np

from flexmor.sweep import (METRIC_UNITS, Sweep, SweepFileError, fmt_param,
                           load_sweep, parse_where, skip_note, value_list, varying,
                           where_mask)

PROG = "flexmor-sweep-plot"


class UserError(Exception):
    """A problem the user can fix: one line, exit status 2."""


@dataclass
class Plan:
    """What to draw: ``selected`` the cases passing --where (any status), ``usable`` those of
    them that are ok with a finite metric, ``groups`` the parameters that split lines."""

    metric: str
    x: str
    y: str | None
    groups: list[str]
    selected: np.ndarray
    usable: np.ndarray
    values: np.ndarray


def make_plan(sweep: Sweep, metric: str, x: str, y: str | None = None, by: str | None = None,
              where: list[tuple[str, float]] | None = None, max_lines: int = 12) -> Plan:
    """Check the names and select the cases; :class:`UserError` or
    :class:`~flexmor_sweep.SweepFileError` with a one-line message on a problem."""
    values = sweep.metric(metric)
    for name in (x, y, by):
        if name is not None:
            sweep.parameter(name)
    axes = [n for n in (x, y, by) if n is not None]
    if len(set(axes)) != len(axes):
        raise UserError(f"--x, --y and --by must be different parameters (got {', '.join(axes)})")
    selected = where_mask(sweep, where or [])
    if not selected.any():
        raise UserError(f"{sweep.path}: no case matches all --where filters")
    others = varying(sweep, selected, exclude=axes)
    if y is not None:
        if others:
            raise UserError(fix_message(sweep, selected, others, "a colour map over --x and --y",
                                        lines=False))
        groups: list[str] = []
    else:
        groups = ([by] if by is not None else []) + others
        n_lines = n_groups(sweep, selected, groups)
        if others and n_lines > max_lines:
            raise UserError(fix_message(sweep, selected, others,
                                        f"a line plot ({n_lines} lines > --max-lines "
                                        f"{max_lines})", lines=True))
    usable = selected & sweep.ok & np.isfinite(values)
    return Plan(metric, x, y, groups, selected, usable, values)


def fix_message(sweep: Sweep, mask: np.ndarray, names: list[str], what: str,
                lines: bool) -> str:
    """The one-line request to fix the varying parameters ``names`` with --where."""
    listed = "; ".join(f"{n} = {value_list(sweep.parameters[n][mask])}" for n in names)
    if len(names) == 1:
        hint = f", use --by {names[0]}, or plot over both with --y {names[0]}" if lines else ""
        return (f"{names[0]} also varies ({listed}): fix it with --where {names[0]}=VALUE for "
                f"{what}{hint}")
    hint = ", or use --by for one of them" if lines else ""
    return (f"{', '.join(names)} also vary ({listed}): fix them with --where PARAM=VALUE for "
            f"{what}{hint}")


def n_groups(sweep: Sweep, mask: np.ndarray, names: list[str]) -> int:
    if not names:
        return 1
    rows = np.column_stack([sweep.parameters[n][mask] for n in names])
    return int(np.unique(rows, axis=0).shape[0])


def line_groups(sweep: Sweep, plan: Plan) -> list[tuple[str, np.ndarray]]:
    """``(label, case indices sorted by x)`` per line, from the usable cases; label '' for a
    single line."""
    usable = np.flatnonzero(plan.usable)
    x = sweep.parameters[plan.x]
    if not plan.groups:
        return [("", usable[np.argsort(x[usable], kind="stable")])]
    rows = np.column_stack([sweep.parameters[n][usable] for n in plan.groups])
    keys, inverse = np.unique(rows, axis=0, return_inverse=True)
    lines = []
    for k, key in enumerate(keys):
        idx = usable[inverse.ravel() == k]
        label = ", ".join(f"{n}={fmt_param(n, v)}" for n, v in zip(plan.groups, key))
        lines.append((label, idx[np.argsort(x[idx], kind="stable")]))
    return lines


def is_grid(xs: np.ndarray, ys: np.ndarray) -> bool:
    """Whether the points (xs, ys) are a full grid: every x value with every y value, once."""
    nx, ny = np.unique(xs).size, np.unique(ys).size
    pairs = np.unique(np.column_stack([xs, ys]), axis=0).shape[0]
    return xs.size == nx * ny == pairs


def auto_log(values: np.ndarray) -> bool:
    """Positive values spanning three decades or more."""
    v = values[np.isfinite(values)]
    return bool(v.size > 1 and np.all(v > 0) and v.max() / v.min() >= 1e3)


def cell_edges(centers: np.ndarray, log: bool) -> np.ndarray:
    """Edges of the cells around sorted ``centers``: midpoints (geometric on a log axis),
    the outer edges half a gap out."""
    c = np.log10(centers) if log else np.asarray(centers, dtype=float)
    if c.size == 1:
        half = 0.3 if log else (0.1 * abs(c[0]) or 0.5)
        edges = np.array([c[0] - half, c[0] + half])
    else:
        mid = 0.5 * (c[1:] + c[:-1])
        edges = np.concatenate([[c[0] - (mid[0] - c[0])], mid, [c[-1] + (c[-1] - mid[-1])]])
    return 10.0 ** edges if log else edges


def label_of(name: str) -> str:
    unit = METRIC_UNITS.get(name)
    return f"{name} ({unit})" if unit else name


def plot_lines(sweep: Sweep, plan: Plan, ax, logx: bool, logy: bool) -> str:
    x = sweep.parameters[plan.x]
    lines = line_groups(sweep, plan)
    for label, idx in lines:
        ax.plot(x[idx], plan.values[idx], "o-", ms=4, lw=1.3, label=label or None)
    if len(lines) > 1:
        ax.legend(fontsize=8, loc="best", title=", ".join(plan.groups), title_fontsize=8)
    ax.set_xscale("log" if logx else "linear")
    ax.set_yscale("log" if logy else "linear")
    ax.set_xlabel(plan.x)
    ax.set_ylabel(label_of(plan.metric))
    return "lines"


def plot_map(sweep: Sweep, plan: Plan, fig, ax, logx: bool, logy: bool, logc: bool) -> str:
    """Colour map over x and y; returns the kind drawn: 'pcolormesh', 'tricontourf' or
    'scatter'."""
    from matplotlib.colors import LogNorm, Normalize

    assert plan.y is not None
    xs_all, ys_all = sweep.parameters[plan.x], sweep.parameters[plan.y]
    sel = np.flatnonzero(plan.selected)
    ok = np.flatnonzero(plan.usable)
    z = plan.values[ok]
    norm = LogNorm(z.min(), z.max()) if logc else Normalize(z.min(), z.max())
    ax.set_xscale("log" if logx else "linear")
    ax.set_yscale("log" if logy else "linear")
    if is_grid(xs_all[sel], ys_all[sel]):
        ux, uy = np.unique(xs_all[sel]), np.unique(ys_all[sel])
        grid = np.full((uy.size, ux.size), np.nan)
        grid[np.searchsorted(uy, ys_all[ok]), np.searchsorted(ux, xs_all[ok])] = z
        art = ax.pcolormesh(cell_edges(ux, logx), cell_edges(uy, logy),
                            np.ma.masked_invalid(grid), norm=norm, cmap="viridis")
        kind = "pcolormesh"
    else:
        art, kind = None, "scatter"
        if not (logx or logy) and ok.size >= 3:
            try:
                levels = np.geomspace(z.min(), z.max(), 15) if logc else 14
                art = ax.tricontourf(xs_all[ok], ys_all[ok], z, levels=levels, norm=norm,
                                     cmap="viridis")
                kind = "tricontourf"
            except (RuntimeError, ValueError):  # collinear or too few distinct points
                art = None
        points = ax.scatter(xs_all[ok], ys_all[ok], c=z, norm=norm, cmap="viridis", s=28,
                            edgecolors="k", linewidths=0.5, zorder=3)
        art = art if art is not None else points
    missing = np.setdiff1d(sel, ok)
    if missing.size:
        ax.plot(xs_all[missing], ys_all[missing], "x", color="0.3", ms=7, ls="none",
                label="failed / not run / no value", zorder=4)
        ax.legend(fontsize=8, loc="best")
    fig.colorbar(art, ax=ax, label=label_of(plan.metric))
    ax.set_xlabel(plan.x)
    ax.set_ylabel(plan.y)
    return kind


def title_of(sweep: Sweep, plan: Plan, where: list[tuple[str, float]]) -> str:
    over = plan.x if plan.y is None else f"{plan.x} and {plan.y}"
    title = f"{plan.metric} over {over}"
    if where:
        title += " (" + ", ".join(f"{n}={fmt_param(n, v)}" for n, v in where) + ")"
    if sweep.attrs.get("title"):
        title = f"{sweep.attrs['title']}\n{title}"
    return title


def draw(sweep: Sweep, plan: Plan, output: str, where: list[tuple[str, float]],
         logs: tuple[bool, bool, bool], dpi: int = 150) -> str:
    """Draw ``plan`` into ``output``; returns the kind drawn ('lines', 'pcolormesh',
    'tricontourf', 'scatter')."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    logx, logy, logc = logs
    fig, ax = plt.subplots(figsize=(7.0, 5.0))
    try:
        if plan.y is None:
            kind = plot_lines(sweep, plan, ax, logx, logy)
        else:
            kind = plot_map(sweep, plan, fig, ax, logx, logy, logc)
        ax.grid(True, lw=0.3)
        ax.set_title(title_of(sweep, plan, where), fontsize=10)
        fig.tight_layout()
        fig.savefig(output, dpi=dpi)
    finally:
        plt.close(fig)
    return kind


def log_choice(sweep: Sweep, plan: Plan, args: argparse.Namespace) -> tuple[bool, bool, bool]:
    auto = not args.no_auto_log
    ok = plan.usable
    logx = args.logx or (auto and auto_log(sweep.parameters[plan.x][ok]))
    y_values = plan.values[ok] if plan.y is None else sweep.parameters[plan.y][ok]
    logy = args.logy or (auto and auto_log(y_values))
    logc = plan.y is not None and (args.logc or (auto and auto_log(plan.values[ok])))
    for flag, name, on in (("--logx", plan.x, logx), ("--logy", plan.y or plan.metric, logy)):
        vals = y_values if flag == "--logy" else sweep.parameters[plan.x][ok]
        if on and np.any(vals <= 0):
            raise UserError(f"{flag}: {name} has values <= 0")
    if logc and np.any(plan.values[ok] <= 0):
        raise UserError(f"--logc: {plan.metric} has values <= 0")
    return logx, logy, logc


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        prog=PROG, description="Plot a metric of a flexmor-sweep result file over one swept "
                               "parameter (lines) or two (colour map).")
    parser.add_argument("file", metavar="SWEEP.h5", help="sweep result file")
    parser.add_argument("--metric", required=True, help="metric to plot (or wall_time_s)")
    parser.add_argument("--x", required=True, metavar="PARAM", help="parameter on the x axis")
    parser.add_argument("--y", metavar="PARAM", default=None,
                        help="parameter on the y axis: colour map of the metric")
    parser.add_argument("--by", metavar="PARAM", default=None,
                        help="a line per value of this parameter (line plots)")
    parser.add_argument("--where", metavar="PARAM=VALUE", action="append", default=[],
                        help="keep only the cases with PARAM = VALUE (repeatable)")
    parser.add_argument("-o", "--output", default=None,
                        help="image to write (default: <metric>.png)")
    parser.add_argument("--logx", action="store_true", help="log x axis")
    parser.add_argument("--logy", action="store_true", help="log y axis")
    parser.add_argument("--logc", action="store_true", help="log colour scale (maps)")
    parser.add_argument("--no-auto-log", action="store_true",
                        help="no log axis unless asked for")
    parser.add_argument("--max-lines", type=int, default=12,
                        help="most lines before --where is required (default: 12)")
    parser.add_argument("--dpi", type=int, default=150, help="resolution (default: 150)")
    args = parser.parse_args(argv)
    if args.by is not None and args.y is not None:
        parser.error("--by is for line plots; with --y fix the other parameters with --where")
    if args.output is None:
        args.output = f"{args.metric}.png"
    return args


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    try:
        where = [parse_where(w) for w in args.where]
        sweep = load_sweep(args.file)
        plan = make_plan(sweep, args.metric, args.x, args.y, args.by, where, args.max_lines)
        note = skip_note(sweep, plan.selected, plan.values, args.metric)
        if note:
            print(f"{PROG}: note: {note}", file=sys.stderr)
        if not plan.usable.any():
            raise UserError(f"{args.file}: no ok case with a finite {args.metric} to plot")
        logs = log_choice(sweep, plan, args)
        out_dir = os.path.dirname(os.path.abspath(args.output))
        if not os.path.isdir(out_dir):
            raise UserError(f"{args.output}: the folder {out_dir} does not exist")
    except (SweepFileError, UserError, ValueError) as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return 2
    try:
        draw(sweep, plan, args.output, where, logs, args.dpi)
    except (OSError, ValueError) as exc:
        print(f"{PROG}: error: cannot write {args.output}: {exc}", file=sys.stderr)
        return 2
    print(f"wrote {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
