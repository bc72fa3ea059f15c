"""Write the motion of a flexmor result as a ParaView time series (one .vtu per output time).

    flexmor-vtk RESULT.h5 -o DIR [--segments 8] [--every 1] [--name NAME] [-q]

Writes DIR/NAME.pvd (NAME: the result file's name without .h5) and DIR/NAME_<k>.vtu for the
output times k = 0, every, 2 every, ... of the dynamic analysis (``/x`` over ``/time``) or, for
a run without ``&dynamic``, of the static load steps (``/static/x``; the .pvd's time is then
the load factor). Open the .pvd in ParaView.

Each .vtu holds the mechanism at that time: every beam as a polyline of --segments pieces
along the element's cubic interpolation (docs/python.md), every truss as a line, every hinge
as a vertex; point data ``displacement`` (m, 3 components: position minus reference position
of the same point) and cell data ``element_type`` (1 beam, 2 truss, 3 hinge, 5 spatial beam)
and ``element`` (the element's row in /model/elements, from 1); without any of these (bodies
on nodes only) the nodes are vertex cells of type and element 0. Points of a planar model have
z = 0; those of a spatial one (/model dimension 3) their z, spatial beams drawn along the cubic
whose end tangents follow the nodes' Euler parameters (docs/python.md).

Exit status 0 on success, 2 with a one-line message (no traceback) for a missing or unreadable
file, a file without /model or without motion, or an unwritable folder.
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from flexmor.model import Mesh
from flexmor.results import Result, ResultFileError, read_result

PROG = "flexmor-vtk"


def frame_indices(n: int, every: int) -> list[int]:
    """Indices 0, every, 2 every, ... below n, and the last one (so a series always ends at
    the final time)."""
    indices = list(range(0, n, every))
    if n and indices[-1] != n - 1:
        indices.append(n - 1)
    return indices


def meshio_mesh(mesh: Mesh, x: np.ndarray, reference: np.ndarray):
    """The meshio.Mesh of coordinates ``x`` (n_x,), ``reference`` the reference points."""
    import meshio

    points = mesh.points(x)
    line_types, vertex_types = mesh.cell_element_types()
    cells, types, numbers = [], [], []
    if len(mesh.lines):
        cells.append(("line", mesh.lines))
        types.append(line_types)
        numbers.append(mesh.line_element + 1)
    if len(mesh.vertices):
        cells.append(("vertex", mesh.vertices[:, None]))
        types.append(vertex_types)
        numbers.append(mesh.vertex_element + 1)
    if not cells:
        # Point masses or rigid bodies on nodes only (input/free_body.nml): the nodes as vertex
        # cells of no element (VTK needs a cell to show a point).
        n = mesh.model.n_nodes
        cells.append(("vertex", np.arange(n)[:, None]))
        types.append(np.zeros(n, dtype=np.int64))
        numbers.append(np.zeros(n, dtype=np.int64))
    return meshio.Mesh(points, cells, point_data={"displacement": points - reference},
                       cell_data={"element_type": types, "element": numbers})


def write_pvd(path: Path, entries: list[tuple[float, str]]) -> None:
    """A ParaView collection file: ``entries`` of (time, file name relative to ``path``)."""
    lines = ['<?xml version="1.0"?>',
             '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">',
             "  <Collection>"]
    lines += [f'    <DataSet timestep="{value!r}" group="" part="0" file={quoteattr(name)}/>'
              for value, name in entries]
    lines += ["  </Collection>", "</VTKFile>", ""]
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text("\n".join(lines))
    os.replace(tmp, path)


def write_series(result: Result, out_dir: str | os.PathLike, segments: int = 8, every: int = 1,
                 name: str | None = None, progress: bool = False) -> tuple[Path, int]:
    """Write the series of ``result`` into ``out_dir``; returns the .pvd path and the number of
    .vtu files. Raises :class:`ResultFileError` for a file without /model or motion."""
    import meshio

    model = result.require_model()
    values, xs, _ = result.motion()
    mesh = model.mesh(segments)
    reference = mesh.reference_points()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    name = name or Path(result.path).stem
    indices = frame_indices(len(values), every)
    width = max(4, len(str(len(values) - 1)))
    entries = []
    last_report = time.monotonic()
    for count, k in enumerate(indices, 1):
        file_name = f"{name}_{k:0{width}d}.vtu"
        meshio.write(out / file_name, meshio_mesh(mesh, xs[k], reference), file_format="vtu")
        entries.append((float(values[k]), file_name))
        if progress and time.monotonic() - last_report > 5.0:
            print(f"{PROG}: {count}/{len(indices)} files", file=sys.stderr)
            last_report = time.monotonic()
    pvd = out / f"{name}.pvd"
    write_pvd(pvd, entries)
    return pvd, len(entries)


def positive(text: str) -> int:
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"{value} is not a positive whole number")
    return value


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n\n")[0])
    parser.add_argument("result", metavar="RESULT.h5", help="flexmor result file")
    parser.add_argument("-o", "--output", required=True, metavar="DIR",
                        help="folder for the .pvd and .vtu files (created if missing)")
    parser.add_argument("--segments", type=positive, default=8,
                        help="straight pieces per beam (default: 8)")
    parser.add_argument("--every", type=positive, default=1,
                        help="write every K-th output time (and the last; default: 1)")
    parser.add_argument("--name", default=None,
                        help="file name stem (default: the result file's)")
    parser.add_argument("-q", "--quiet", action="store_true", help="no progress or summary")
    return parser.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    try:
        result = read_result(args.result)
        pvd, n = write_series(result, args.output, args.segments, args.every, args.name,
                              progress=not args.quiet)
    except ResultFileError as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(f"{PROG}: error: cannot write into {args.output}: {exc.strerror or exc}",
              file=sys.stderr)
        return 2
    if not args.quiet:
        print(f"wrote {pvd} ({n} time{'s' if n != 1 else ''})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
