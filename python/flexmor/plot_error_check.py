"""Plot a run's error check (``&dynamic error_check``): the largest distance of its nodes from
the second, more accurate run at every output time, a reduced run's local error estimate
beside it, and with ``--reference`` the true error (the largest distance of the output nodes
both files share from a reference run's).

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
from flexmor.results import Result, ResultFileError, distance_from

PROG = "flexmor-plot-error-check"


def error_check_data(run: Result, reference: Result | None = None,
                     nodes: list[str] | None = None) -> dict[str, Any]:
    """``t``, ``distance`` (the check's, per output), ``attrs`` of /error_check, ``estimate``
    (a reduced run's local error estimate per output, else None) and, with a reference,
    ``true`` (distance_from) and its ``nodes``."""
    check = run.error_check
    if check is None:
        raise ResultFileError(f"{run.path}: no error check (no /error_check group; &dynamic "
                              f"error_check = 'tolerance', 'modes' or 'mesh' writes it)")
    estimate = run.reduction.get("error_estimate") if run.reduction is not None else None
    data: dict[str, Any] = {"t": run.time, "distance": check["distance"],
                            "attrs": check["attrs"], "true": None, "nodes": [],
                            "estimate": estimate}
    if reference is not None:
        data["true"], data["nodes"] = distance_from(run, reference, nodes)
    return data


def plot_error_check(data: dict[str, Any], output: str, title: str = "",
                     dpi: int = 150) -> None:
    """Draw ``data`` (error_check_data) into ``output``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(9.0, 4.5))
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
    values = np.concatenate([data["distance"]] +
                            [data[k] for k in ("true", "estimate") if data[k] is not None])
    if np.any(values > 0):
        ax.set_yscale("log")
    ax.grid(True, which="both", lw=0.3)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("largest nodal distance [m]")
    ax.legend(fontsize=8, loc="best")
    if title:
        ax.set_title(title, fontsize=10)
    fig.tight_layout()
    try:
        fig.savefig(output, dpi=dpi)
    finally:
        plt.close(fig)


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
    print(line)
    return 0


if __name__ == "__main__":
    sys.exit(main())
