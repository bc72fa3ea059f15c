"""Animate the motion of a flexmor result with matplotlib (GIF or MP4).

    flexmor-animate RESULT.h5 -o anim.gif|anim.mp4 [--scale 1] [--fps 25] [--every 1] \\
        [--segments 8] [--dpi 100]

One frame per output time (every --every-th, and the last) of the dynamic analysis, or per
static load step for a run without ``&dynamic``. Beams are drawn along their cubic
interpolation, trusses as lines, hinges as dots; the reference configuration faint behind.
--scale S draws reference + S x displacement at every drawn point (S = 1: the true motion;
larger S makes small elastic deflections visible, though it also scales the rigid motion).
The axes are fixed and cover the whole motion; each frame shows its time.

GIF is written with Pillow (which matplotlib brings), MP4 with ffmpeg, which must be on PATH.
Exit status 0 on success, 2 with a one-line message (no traceback) for a missing or unreadable
file, a file without /model or motion, an unknown extension or a missing ffmpeg.
"""
from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import numpy as np

from flexmor.model import ELEMENT_TYPE_IDS
from flexmor.results import Result, ResultFileError, read_result
from flexmor.to_vtk import frame_indices, positive

PROG = "flexmor-animate"
COLORS = {ELEMENT_TYPE_IDS["beam"]: "C0", ELEMENT_TYPE_IDS["truss"]: "C2"}


class AnimateError(Exception):
    """A problem the user can fix: one line, exit status 2."""


def drawn_points(result: Result, segments: int, scale: float, every: int
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, str, object]:
    """``(values, points, reference, what, mesh)``: the frames' times (or load factors),
    drawn points (n_frames, n_points, 3) = reference + scale * displacement, the reference
    points (n_points, 3), 'time' or 'load factor', and the :class:`~flexmor.model.Mesh`."""
    model = result.require_model()
    values, xs, what = result.motion()
    mesh = model.mesh(segments)
    reference = mesh.reference_points()
    indices = frame_indices(len(values), every)
    points = reference + scale * (mesh.points(xs[indices]) - reference)
    return values[indices], points, reference, what, mesh


def limits(points: np.ndarray, reference: np.ndarray, pad: float = 0.05
           ) -> tuple[float, float, float, float]:
    """Axis limits covering every frame and the reference, padded by ``pad`` of the extent."""
    xy = np.concatenate([points.reshape(-1, 3)[:, :2], reference[:, :2]])
    lo, hi = xy.min(axis=0), xy.max(axis=0)
    extent = float(max(hi - lo)) or 1.0
    lo, hi = lo - pad * extent, hi + pad * extent
    return float(lo[0]), float(hi[0]), float(lo[1]), float(hi[1])


def writer_for(output: str, fps: int):
    """The matplotlib writer for the output's extension; :class:`AnimateError` otherwise."""
    from matplotlib import animation

    suffix = Path(output).suffix.lower()
    if suffix == ".gif":
        return animation.PillowWriter(fps=fps)
    if suffix == ".mp4":
        if not animation.writers.is_available("ffmpeg"):
            raise AnimateError("ffmpeg not found on PATH, needed for .mp4 (install it, e.g. "
                               "apt-get install ffmpeg, or write a .gif)")
        return animation.FFMpegWriter(fps=fps)
    raise AnimateError(f"{output}: unknown extension '{suffix}' (use .gif or .mp4)")


def animate(result: Result, output: str, scale: float = 1.0, fps: int = 25, every: int = 1,
            segments: int = 8, dpi: int = 100) -> int:
    """Render the animation of ``result`` into ``output``; returns the number of frames."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib import animation
    from matplotlib.collections import LineCollection

    writer = writer_for(output, fps)
    values, points, reference, what, mesh = drawn_points(result, segments, scale, every)
    line_types, _ = mesh.cell_element_types()
    colors = [COLORS.get(int(t), "C0") for t in line_types]
    xmin, xmax, ymin, ymax = limits(points, reference)
    # The figure takes the motion's aspect ratio (within limits), so little of it is blank.
    aspect = min(max((ymax - ymin) / (xmax - xmin), 0.4), 1.5)
    fig, ax = plt.subplots(figsize=(6.4, 0.9 + 5.0 * aspect), layout="constrained")
    ax.set_xlim(xmin, xmax)
    ax.set_ylim(ymin, ymax)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.grid(True, lw=0.3)
    ax.add_collection(LineCollection(reference[mesh.lines, :2], colors="0.6", linewidths=1.0,
                                     alpha=0.35, zorder=1))
    lines = LineCollection(points[0][mesh.lines, :2], colors=colors, linewidths=2.0, zorder=2)
    ax.add_collection(lines)
    nodes = ax.plot(points[0, :mesh.model.n_nodes, 0], points[0, :mesh.model.n_nodes, 1], "o",
                    color="0.2", ms=2.5, zorder=3)[0]
    hinges = ax.plot(points[0, mesh.vertices, 0], points[0, mesh.vertices, 1], "o", mfc="white",
                     mec="C3", ms=6, zorder=4)[0]
    title = str(result.attrs.get("title", "") or Path(result.path).stem)
    ax.set_title(title + (f" (displacement x {scale:g})" if scale != 1.0 else ""), fontsize=10)
    label = ax.text(0.02, 0.97, "", transform=ax.transAxes, va="top", fontsize=10,
                    family="monospace")
    unit = " s" if what == "time" else ""

    def update(i: int):
        frame = points[i]
        lines.set_segments(frame[mesh.lines, :2])
        nodes.set_data(frame[:mesh.model.n_nodes, 0], frame[:mesh.model.n_nodes, 1])
        hinges.set_data(frame[mesh.vertices, 0], frame[mesh.vertices, 1])
        label.set_text(f"{what} = {values[i]:.6g}{unit}")
        return lines, nodes, hinges, label

    anim = animation.FuncAnimation(fig, update, frames=len(values), blit=False,
                                   cache_frame_data=False)
    try:
        anim.save(output, writer=writer, dpi=dpi)
    finally:
        plt.close(fig)
    return len(values)


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n\n")[0])
    parser.add_argument("result", metavar="RESULT.h5", help="flexmor result file")
    parser.add_argument("-o", "--output", required=True, metavar="ANIM",
                        help="animation to write: .gif (Pillow) or .mp4 (ffmpeg)")
    parser.add_argument("--scale", type=float, default=1.0,
                        help="displacement scale S: drawn = reference + S x displacement "
                             "(default: 1)")
    parser.add_argument("--fps", type=positive, default=25, help="frames per second (25)")
    parser.add_argument("--every", type=positive, default=1,
                        help="one frame per K output times (and the last; default: 1)")
    parser.add_argument("--segments", type=positive, default=8,
                        help="straight pieces per beam (default: 8)")
    parser.add_argument("--dpi", type=positive, default=100, help="resolution (default: 100)")
    args = parser.parse_args(argv)
    if not np.isfinite(args.scale):
        parser.error("--scale must be a finite number")
    return args


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    try:
        out_dir = os.path.dirname(os.path.abspath(args.output))
        if not os.path.isdir(out_dir):
            raise AnimateError(f"{args.output}: the folder {out_dir} does not exist")
        writer_for(args.output, args.fps)  # an unusable output fails before reading
        n = animate(read_result(args.result), args.output, args.scale, args.fps, args.every,
                    args.segments, args.dpi)
    except (AnimateError, ResultFileError) as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(f"{PROG}: error: cannot write {args.output}: {exc.strerror or exc}",
              file=sys.stderr)
        return 2
    print(f"wrote {args.output} ({n} frames)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
