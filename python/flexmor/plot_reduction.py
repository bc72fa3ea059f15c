"""Plot what a reduced run says of its own error, over time, against the true error when a
reference run (the full model, or a finer reduction) is given.

Two panels: the error estimate (m) at the outputs, the exact measurements of an expanded run
(``/reduction/measured``: where the first expansion was made, the farthest accepted state an
expansion served, the output samples) and the basis updates; with ``--reference`` the largest distance
of the output nodes the two files share from the reference's, interpolated to the reduced
run's output times. Below, the residual norm of the full equations.

    flexmor-plot-reduction REDUCED.h5 [--reference FULL.h5] [--node tip ...] \\
        [-o reduction.png] [--dpi 150]

Exit status 0 on success, 2 with a one-line message (no traceback) for a missing or unreadable
file, a file without ``/reduction``, nodes the files do not share, a reference that does not
cover the reduced run's times, or bad arguments.
"""
from __future__ import annotations

import argparse
import os
import sys
from typing import Any

import numpy as np

from flexmor.cli import read_with_reference, reference_plot_args
from flexmor.results import Result, ResultFileError, distance_from

PROG = "flexmor-plot-reduction"

#: Codes of /reduction/measured/kind (docs/output.md) and how they are drawn.
MEASURED_KINDS = {1: ("first expansion", "v"), 2: ("farthest state served", "D"),
                  3: ("output sample", "o")}


def reduction_errors(reduced: Result, reference: Result | None = None,
                     nodes: list[str] | None = None) -> dict[str, Any]:
    """The plot's data: ``t``, per-output ``estimate`` (None without a definite K0) and
    ``residual``, ``measured`` (dict of time, kind, estimate, residual; None for a full
    evaluation), ``updates`` (times the basis was replaced), ``attrs`` of /reduction and, with
    a reference, ``true`` (largest distance of ``nodes``, default every shared output node,
    at each output) and ``nodes``."""
    red = reduced.reduction
    if red is None:
        raise ResultFileError(f"{reduced.path}: not a reduced run (no /reduction group; a "
                              f"scene with &reduction writes it)")
    if reduced.time is None:
        raise ResultFileError(f"{reduced.path}: no dataset /time (a reduced run needs &dynamic)")
    data: dict[str, Any] = {"t": reduced.time, "attrs": red["attrs"],
                            "estimate": red.get("error_estimate"), "residual": red["residual"],
                            "measured": None, "updates": np.zeros(0), "true": None, "nodes": []}
    if "measured/time" in red:
        data["measured"] = {"time": red["measured/time"], "kind": red["measured/kind"],
                            "residual": red["measured/residual"],
                            "estimate": red.get("measured/error_estimate")}
    if "checks/time" in red:
        data["updates"] = red["checks/time"][red["checks/updated"] == 1]
    if reference is None:
        return data
    distance, shared = distance_from(reduced, reference, nodes)
    data["true"] = distance
    data["nodes"] = shared
    return data


def plot_reduction(data: dict[str, Any], output: str, title: str = "", dpi: int = 150) -> None:
    """Draw the two panels of ``data`` (reduction_errors) into ``output``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax_err, ax_res) = plt.subplots(2, 1, figsize=(9.0, 6.5), sharex=True,
                                         gridspec_kw={"height_ratios": [2, 1]})
    t, measured = data["t"], data["measured"]
    # An expanded run's outputs hold the latest measurement: steps, not a curve.
    steps = "steps-post" if measured is not None else "default"
    if data["estimate"] is not None:
        ax_err.plot(t, data["estimate"], color="C0", lw=1.2, drawstyle=steps,
                    label="error estimate (largest nodal translation of K0^-1 r)")
    if data["true"] is not None:
        ax_err.plot(t, data["true"], color="C3", lw=1.2,
                    label=f"distance from the reference ({', '.join(data['nodes'])})")
    ax_res.plot(t, data["residual"], color="C0", lw=1.2, drawstyle=steps)
    if measured is not None:
        for code, (label, marker) in MEASURED_KINDS.items():
            pick = measured["kind"] == code
            if not np.any(pick):
                continue
            if measured["estimate"] is not None:
                ax_err.plot(measured["time"][pick], measured["estimate"][pick], marker,
                            color="C1", ms=5, ls="none", label=f"measured: {label}")
            ax_res.plot(measured["time"][pick], measured["residual"][pick], marker, color="C1",
                        ms=5, ls="none")
    for i, t_update in enumerate(data["updates"]):
        for ax in (ax_err, ax_res):
            ax.axvline(t_update, color="0.5", ls=":", lw=1.0,
                       label="basis update" if (i == 0 and ax is ax_err) else None)
    for ax in (ax_err, ax_res):
        values = np.concatenate([line.get_ydata() for line in ax.get_lines()
                                 if len(np.atleast_1d(line.get_ydata())) > 0
                                 and line.get_linestyle() != ":"] or [np.zeros(1)])
        if np.any(values > 0):
            ax.set_yscale("log")
        ax.grid(True, which="both", lw=0.3)
    ax_err.set_ylabel("error [m]")
    ax_res.set_ylabel("residual norm")
    ax_res.set_xlabel("time [s]")
    ax_err.legend(fontsize=8, loc="best")
    if title:
        ax_err.set_title(title, fontsize=10)
    fig.tight_layout()
    try:
        fig.savefig(output, dpi=dpi)
    finally:
        plt.close(fig)


def title_of(path: str, attrs: dict[str, Any]) -> str:
    """One line: the file, evaluation, modes and the run's largest estimate."""
    parts = [os.path.basename(path), f"{attrs.get('n_modes', '?')} modes",
             f"evaluation {attrs.get('evaluation', 'full')}"]
    if "n_expansions" in attrs:
        parts.append(f"{attrs['n_expansions']} expansions")
    if "error_estimate_max" in attrs:
        parts.append(f"estimate up to {attrs['error_estimate_max']:.2g} m")
    return ", ".join(parts)


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    return reference_plot_args(
        PROG, "Plot a reduced run's error estimate, residual and exact measurements over "
        "time, against the true error when a reference run is given.",
        "REDUCED.h5", "result file of a reduced run", "FULL.h5",
        "result file of a reference run of the same scene (full model)", "reduction.png", argv)


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    data = read_with_reference(PROG, args, reduction_errors)
    if data is None:
        return 2
    try:
        plot_reduction(data, args.output, title_of(args.file, data["attrs"]), args.dpi)
    except (OSError, ValueError) as exc:
        print(f"{PROG}: error: cannot write {args.output}: {exc}", file=sys.stderr)
        return 2
    line = f"wrote {args.output}"
    if "error_estimate_max" in data["attrs"]:
        line += f"; estimate up to {data['attrs']['error_estimate_max']:.3g} m"
    if data["true"] is not None:
        line += f", distance from the reference up to {np.max(data['true']):.3g} m"
    print(line)
    return 0


if __name__ == "__main__":
    sys.exit(main())
