"""Plot the x-y path of a node from one or more flexmor result files.

Two panels, as in Fig. 2 of the seed paper: the full path (equal axes) and a detail view near
the upper extreme of the path (a window around the point of maximum y). Several files are
overlaid, e.g. full and reduced models; legend labels are the file names or --label.

    flexmor-plot-tip-path RESULT.h5 [MORE.h5 ...] -o tip_path.png \\
        [--node tip] [--label NAME ...] [--zoom 0.05]

Exit status 0 on success, 2 with a one-line message (no traceback) for a missing or unreadable
file, a node label the file does not have (the available labels are listed) or bad arguments.
"""
from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import numpy as np

from flexmor.results import ResultFileError, load_node_path

PROG = "flexmor-plot-tip-path"


def default_labels(paths: list[str]) -> list[str]:
    """File names without extension; the paths as given where those are not unique."""
    stems = [Path(p).stem for p in paths]
    if len(set(stems)) == len(stems):
        return stems
    return list(paths)


def zoom_window(paths_xy: list[np.ndarray],
                fraction: float = 0.05) -> tuple[float, float, float, float]:
    """Detail window ``(xmin, xmax, ymin, ymax)`` near the upper extreme of the paths.

    ``paths_xy`` holds arrays of shape (nt, >=2). The window spans the points of maximum y of
    all paths, padded by ``fraction`` times the largest extent of the paths (x or y), more below
    the peak than above it (the paths come from below and turn there)."""
    peaks = np.array([xy[int(np.argmax(xy[:, 1])), :2] for xy in paths_xy])
    extent = max(float(np.ptp(xy[:, k])) for xy in paths_xy for k in (0, 1))
    if not extent > 0.0:  # a path that does not move: any small window around the point
        extent = max(1e-3, float(np.max(np.abs(peaks))) * 1e-3)
    pad = fraction * extent
    xmin = float(peaks[:, 0].min()) - pad
    xmax = float(peaks[:, 0].max()) + pad
    ymin = float(peaks[:, 1].min()) - 1.5 * pad
    ymax = float(peaks[:, 1].max()) + 0.5 * pad
    return xmin, xmax, ymin, ymax


def plot_paths(series: list[tuple[str, np.ndarray, np.ndarray]], output: str, node: str = "tip",
               fraction: float = 0.05, dpi: int = 150) -> tuple[float, float, float, float]:
    """Draw the two panels for ``series`` of ``(label, t, xyz)`` into ``output`` (PNG, PDF or
    any format matplotlib knows from the extension). Returns the detail window."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Rectangle

    window = zoom_window([xyz for _, _, xyz in series], fraction)
    xmin, xmax, ymin, ymax = window
    fig, (ax_full, ax_zoom) = plt.subplots(1, 2, figsize=(11.0, 5.0))
    t_min = min(float(t[0]) for _, t, _ in series if t.size)
    t_max = max(float(t[-1]) for _, t, _ in series if t.size)

    for i, (label, t, xyz) in enumerate(series):
        color = f"C{i}"
        style = "-" if i == 0 else ("--", "-.", ":")[(i - 1) % 3]
        ax_full.plot(xyz[:, 0], xyz[:, 1], style, color=color, lw=1.5, label=label)
        ax_full.plot(xyz[0, 0], xyz[0, 1], "o", color=color, ms=4)
        ax_zoom.plot(xyz[:, 0], xyz[:, 1], style, color=color, lw=1.5, label=label)
        k = int(np.argmax(xyz[:, 1]))
        ax_zoom.plot(xyz[k, 0], xyz[k, 1], "o", color=color, ms=4)
        ax_zoom.annotate(f"t = {t[k]:.3g} s", (xyz[k, 0], xyz[k, 1]), textcoords="offset points",
                         xytext=(6, 4 + 10 * i), fontsize=8, color=color)

    ax_full.add_patch(Rectangle((xmin, ymin), xmax - xmin, ymax - ymin, fill=False, ls=":",
                                lw=1.0, ec="0.3"))
    ax_full.set_aspect("equal", adjustable="datalim")
    ax_full.set_title(f"Path of node '{node}', t = {t_min:.3g} to {t_max:.3g} s (o: start)")
    ax_zoom.set_xlim(xmin, xmax)
    ax_zoom.set_ylim(ymin, ymax)
    ax_zoom.set_aspect("equal", adjustable="box")
    ax_zoom.set_title("Detail near the upper extreme")
    for ax in (ax_full, ax_zoom):
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.grid(True, lw=0.3)
        ax.legend(fontsize=8, loc="best")
    ax_zoom.ticklabel_format(useOffset=False)
    fig.tight_layout()
    try:
        fig.savefig(output, dpi=dpi)
    finally:
        plt.close(fig)
    return window


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        prog=PROG,
        description="Plot the x-y path of a node (default 'tip') from flexmor result files: "
                    "full view and detail near the upper extreme.")
    parser.add_argument("files", nargs="+", metavar="RESULT.h5", help="flexmor result files")
    parser.add_argument("-o", "--output", default=None,
                        help="image to write (default: <node>_path.png)")
    parser.add_argument("--node", default="tip", help="node label (default: tip)")
    parser.add_argument("--label", action="append", default=None,
                        help="legend label, once per file in order (default: file names)")
    parser.add_argument("--zoom", type=float, default=0.05,
                        help="detail window padding as a fraction of the path's extent "
                             "(default: 0.05)")
    parser.add_argument("--dpi", type=int, default=150, help="resolution (default: 150)")
    args = parser.parse_args(argv)
    if args.label is not None and len(args.label) != len(args.files):
        parser.error(f"{len(args.label)} --label given for {len(args.files)} files")
    if not args.zoom > 0.0:
        parser.error("--zoom must be positive")
    if args.output is None:
        args.output = f"{args.node}_path.png"
    return args


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    labels = args.label if args.label is not None else default_labels(args.files)
    try:
        series = []
        for path, label in zip(args.files, labels):
            t, xyz = load_node_path(path, args.node)
            if t.size == 0:
                raise ResultFileError(f"{path}: node '{args.node}' has no samples (nt = 0)")
            series.append((label, t, xyz))
    except ResultFileError as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return 2
    out_dir = os.path.dirname(os.path.abspath(args.output))
    if not os.path.isdir(out_dir):
        print(f"{PROG}: error: {args.output}: the folder {out_dir} does not exist", file=sys.stderr)
        return 2
    try:
        plot_paths(series, args.output, args.node, args.zoom, args.dpi)
    except (OSError, ValueError) as exc:
        print(f"{PROG}: error: cannot write {args.output}: {exc}", file=sys.stderr)
        return 2
    print(f"wrote {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
