"""Plot a run's error check (``&dynamic error_check``): the largest distance of its nodes from
the second, more accurate run at every output time, a reduced run's local error estimate
beside it, and with ``--reference`` the true error (the largest distance of the output nodes
both files share from a reference run's). Where the check compared rotations
(``/error_check/rotation``) a second panel shows them, with the reference's likewise.

    flexmor-plot-error-check RUN.h5 [--reference REF.h5] [--node tip ...] \\
        [-o error_check.png] [--dpi 150]

Exit status 0 on success, 2 with a one-line message (no traceback) for a missing or unreadable
file, a file without ``/error_check``, nodes the files do not share, a reference that does not
cover the run's times, or bad arguments.
"""
from __future__ import annotations

import argparse
import os
import sys
from typing import Any

import numpy as np

from flexmor.cli import read_with_reference, reference_plot_args
from flexmor.results import Result, ResultFileError, distance_from, rotation_from

PROG = "flexmor-plot-error-check"


def error_check_data(run: Result, reference: Result | None = None,
                     nodes: list[str] | None = None) -> dict[str, Any]:
    """``t``, ``distance`` (the check's, per output), ``rotation`` (the check's, or None where
    it compared none), ``attrs`` of /error_check, ``estimate`` (a reduced run's local error
    estimate per output, else None) and, with a reference, ``true`` (distance_from) and its
    ``nodes``, and ``true_rotation`` (rotation_from; None where the output nodes have no
    rotations)."""
    check = run.error_check
    if check is None:
        raise ResultFileError(f"{run.path}: no error check (no /error_check group; &dynamic "
                              f"error_check = 'tolerance', 'modes' or 'mesh' writes it)")
    estimate = run.reduction.get("error_estimate") if run.reduction is not None else None
    data: dict[str, Any] = {"t": run.time, "distance": check["distance"],
                            "rotation": check.get("rotation"), "attrs": check["attrs"],
                            "true": None, "nodes": [], "true_rotation": None,
                            "turned_nodes": [], "estimate": estimate}
    if reference is not None:
        data["true"], data["nodes"] = distance_from(run, reference, nodes)
        if data["rotation"] is not None:
            try:
                data["true_rotation"], data["turned_nodes"] = rotation_from(run, reference,
                                                                            nodes)
            except ResultFileError:
                pass  # the output nodes have no rotations: the panel shows the check alone
    return data


def plot_error_check(data: dict[str, Any], output: str, title: str = "",
                     dpi: int = 150) -> None:
    """Draw ``data`` (error_check_data) into ``output``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    turned = data.get("rotation") is not None
    fig, axes = plt.subplots(2 if turned else 1, 1, figsize=(9.0, 7.5 if turned else 4.5),
                             sharex=True, squeeze=False)
    ax = axes[0, 0]
    attrs = data["attrs"]
    ax.plot(data["t"], data["distance"], color="C0", lw=1.2,
            label=f"distance from the second run ({attrs.get('second_run', '?')}): "
                  f"the error check")
    if data["true"] is not None:
        ax.plot(data["t"], data["true"], color="C3", lw=1.2,
                label=f"distance from the reference ({', '.join(data['nodes'])})")
    if data["estimate"] is not None:
        ax.plot(data["t"], data["estimate"], color="C2", lw=1.0, ls="--",
                drawstyle="steps-post",
                label="the reduction's local error estimate (/reduction/error_estimate)")
    _finish_axes(ax, [data[k] for k in ("distance", "true", "estimate")],
                 "largest nodal distance [m]")
    if title:
        ax.set_title(title, fontsize=10)
    if turned:
        ax = axes[1, 0]
        ax.plot(data["t"], data["rotation"], color="C0", lw=1.2,
                label="rotation from the second run's: the error check")
        if data.get("true_rotation") is not None:
            ax.plot(data["t"], data["true_rotation"], color="C3", lw=1.2,
                    label=f"rotation from the reference's ({', '.join(data['turned_nodes'])})")
        _finish_axes(ax, [data["rotation"], data.get("true_rotation")],
                     "largest nodal rotation [rad]")
    axes[-1, 0].set_xlabel("time [s]")
    fig.tight_layout()
    try:
        fig.savefig(output, dpi=dpi)
    finally:
        plt.close(fig)


def _finish_axes(ax: Any, series: list[np.ndarray | None], ylabel: str) -> None:
    """Log scale where anything is above 0, grid, label and legend."""
    values = np.concatenate([v for v in series if v is not None])
    if np.any(values > 0):
        ax.set_yscale("log")
    ax.grid(True, which="both", lw=0.3)
    ax.set_ylabel(ylabel)
    ax.legend(fontsize=8, loc="best")


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    return reference_plot_args(
        PROG, "Plot a run's error check (&dynamic error_check) over time, against the "
        "true error when a reference run is given.",
        "RUN.h5", "result file of a run with error_check", "REF.h5",
        "result file of a converged run of the same scene", "error_check.png", argv)


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    data = read_with_reference(PROG, args, error_check_data)
    if data is None:
        return 2
    attrs = data["attrs"]
    title = (f"{os.path.basename(args.file)}: error check ({attrs.get('kind', '?')}), up to "
             f"{float(np.max(data['distance'])):.2g} m at {attrs.get('node_max', '?')}")
    try:
        plot_error_check(data, args.output, title, args.dpi)
    except (OSError, ValueError) as exc:
        print(f"{PROG}: error: cannot write {args.output}: {exc}", file=sys.stderr)
        return 2
    line = f"wrote {args.output}; check up to {float(np.max(data['distance'])):.3g} m"
    if data["true"] is not None:
        line += f", distance from the reference up to {float(np.max(data['true'])):.3g} m"
    if data["rotation"] is not None:
        line += f"; rotations up to {float(np.max(data['rotation'])):.3g} rad"
        if data["true_rotation"] is not None:
            line += f", from the reference up to {float(np.max(data['true_rotation'])):.3g} rad"
    print(line)
    return 0


if __name__ == "__main__":
    sys.exit(main())
