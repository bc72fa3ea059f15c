"""Animate the motion of a flexmor result with matplotlib (GIF or MP4).

    flexmor-animate RESULT.h5 -o anim.gif|anim.mp4 [--scale 1] [--fps 25] [--every 1] \\
        [--segments 8] [--dpi 100] [--view 30 -60]

One frame per output time (every --every-th, and the last) of the dynamic analysis, or per
static load step for a run without ``&dynamic``. Beams are drawn along their cubic
interpolation, trusses as lines, hinges as dots; the reference configuration faint behind.
A planar model is drawn in its x-y plane; a spatial one (``/model`` dimension 3) on matplotlib
3D axes in an orthographic projection seen from --view ELEV AZIM (degrees, default 30 -60:
matplotlib's default), with equal scales on x, y and z.
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
COLORS = {ELEMENT_TYPE_IDS["beam"]: "C0", ELEMENT_TYPE_IDS["truss"]: "C2",
          ELEMENT_TYPE_IDS["beam3d"]: "C0"}


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


def limits_3d(points: np.ndarray, reference: np.ndarray, pad: float = 0.05
              ) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper corners (3,) of a cube covering every frame and the reference, padded by
    ``pad`` of its edge: equal ranges on the three axes keep the drawing undistorted."""
    xyz = np.concatenate([points.reshape(-1, 3), reference])
    lo, hi = xyz.min(axis=0), xyz.max(axis=0)
    edge = float(max(hi - lo)) or 1.0
    centre = (lo + hi) / 2
    half = (0.5 + pad) * edge
    return centre - half, centre + half


def _axes_2d(plt, points, reference, mesh, colors):
    """Planar figure: the x-y plane at equal scale. Returns (figure, axes, draw(frame))."""
    from matplotlib.collections import LineCollection

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
    n = mesh.model.n_nodes
    nodes = ax.plot(points[0, :n, 0], points[0, :n, 1], "o", color="0.2", ms=2.5, zorder=3)[0]
    hinges = ax.plot(points[0, mesh.vertices, 0], points[0, mesh.vertices, 1], "o", mfc="white",
                     mec="C3", ms=6, zorder=4)[0]

    def draw(frame):
        lines.set_segments(frame[mesh.lines, :2])
        nodes.set_data(frame[:n, 0], frame[:n, 1])
        hinges.set_data(frame[mesh.vertices, 0], frame[mesh.vertices, 1])
        return lines, nodes, hinges

    return fig, ax, draw


def _axes_3d(plt, points, reference, mesh, colors, view):
    """Spatial figure: matplotlib's 3D axes, a perspective-free (orthographic) view from
    elevation, azimuth ``view`` (degrees) onto a cube of equal axis ranges."""
    from mpl_toolkits.mplot3d.art3d import Line3DCollection

    lo, hi = limits_3d(points, reference)
    fig = plt.figure(figsize=(6.4, 6.0), layout="constrained")
    ax = fig.add_subplot(projection="3d", proj_type="ortho")
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    ax.set_box_aspect((1, 1, 1))
    ax.view_init(elev=view[0], azim=view[1])
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_zlabel("z (m)")
    # Without lines (bodies on nodes only) there is no collection: matplotlib's 3D projection
    # of an empty one fails.
    lines = None
    if len(mesh.lines):
        ax.add_collection3d(Line3DCollection(reference[mesh.lines], colors="0.6",
                                             linewidths=1.0, alpha=0.35))
        lines = Line3DCollection(points[0][mesh.lines], colors=colors, linewidths=2.0)
        ax.add_collection3d(lines)
    n = mesh.model.n_nodes
    nodes = ax.plot(points[0, :n, 0], points[0, :n, 1], points[0, :n, 2], "o", color="0.2",
                    ms=2.5)[0]

    def draw(frame):
        nodes.set_data_3d(frame[:n, 0], frame[:n, 1], frame[:n, 2])
        if lines is None:
            return (nodes,)
        lines.set_segments(frame[mesh.lines])
        return lines, nodes

    return fig, ax, draw


def animate(result: Result, output: str, scale: float = 1.0, fps: int = 25, every: int = 1,
            segments: int = 8, dpi: int = 100, view: tuple[float, float] = (30.0, -60.0)
            ) -> int:
    """Render the animation of ``result`` into ``output``; returns the number of frames. A
    planar model is drawn in its x-y plane, a spatial one (``/model`` dimension 3) on 3D axes
    seen from ``view`` = (elevation, azimuth) in degrees (matplotlib's default view)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib import animation

    writer = writer_for(output, fps)
    values, points, reference, what, mesh = drawn_points(result, segments, scale, every)
    line_types, _ = mesh.cell_element_types()
    colors = [COLORS.get(int(t), "C0") for t in line_types]
    if mesh.model.spatial:
        fig, ax, draw = _axes_3d(plt, points, reference, mesh, colors, view)
    else:
        fig, ax, draw = _axes_2d(plt, points, reference, mesh, colors)
    title = str(result.attrs.get("title", "") or Path(result.path).stem)
    ax.set_title(title + (f" (displacement x {scale:g})" if scale != 1.0 else ""), fontsize=10)
    # 3D axes place text in data space: the time goes on the figure instead.
    where = {"transform": fig.transFigure} if mesh.model.spatial else {"transform": ax.transAxes}
    label = (fig if mesh.model.spatial else ax).text(0.02, 0.97, "", va="top", fontsize=10,
                                                     family="monospace", **where)
    unit = " s" if what == "time" else ""

    def update(i: int):
        label.set_text(f"{what} = {values[i]:.6g}{unit}")
        return (*draw(points[i]), label)

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
    parser.add_argument("--view", type=float, nargs=2, default=(30.0, -60.0),
                        metavar=("ELEV", "AZIM"),
                        help="spatial models: elevation and azimuth of the view in degrees "
                             "(default: 30 -60; planar models are drawn in their x-y plane)")
    args = parser.parse_args(argv)
    if not np.isfinite(args.scale):
        parser.error("--scale must be a finite number")
    if not np.isfinite(args.view).all():
        parser.error("--view must be two finite numbers")
    return args


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    try:
        out_dir = os.path.dirname(os.path.abspath(args.output))
        if not os.path.isdir(out_dir):
            raise AnimateError(f"{args.output}: the folder {out_dir} does not exist")
        writer_for(args.output, args.fps)  # an unusable output fails before reading
        n = animate(read_result(args.result), args.output, args.scale, args.fps, args.every,
                    args.segments, args.dpi, tuple(args.view))
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
