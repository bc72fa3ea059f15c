"""Bode and pole-zero plots of one input-output channel of a result's ``&linear`` model, and a
table of its poles (natural frequency in Hz, damping ratio) and the channel's zeros.

    flexmor-bode RESULT.h5 [--input NAME] [--output NAME] [--index K] \\
        [--bode bode.png] [--pole-zero pole_zero.png] [--fmin HZ] [--fmax HZ] [--points N]

The input and output default to the first of ``&linear inputs`` and ``outputs``, the index to
the first linearisation (0-based, as ``/linear/time``). Exit status 0 on success, 2 with one
line ``flexmor-bode: error: ...`` (no traceback) for a missing or unreadable file, a file
without ``/linear``, an unknown input or output name, an index out of range or bad arguments.
"""
from __future__ import annotations

import argparse
import os
import sys

import numpy as np

from flexmor.control import (LinearModelError, default_band, plot_bode, plot_pole_zero,
                             pole_table, read_linear, response_grid, unit_of)
from flexmor.results import ResultFileError

PROG = "flexmor-bode"


def format_table(rows: list[tuple[float, float | None, float, complex]], what: str) -> str:
    """The rows of :func:`flexmor.control.pole_table` as a text table."""
    lines = [f"{what} ({len(rows)}; complex pairs once, Im >= 0):",
             f"{'#':>4}  {'f_n (Hz)':>12}  {'zeta':>10}  {'f_d (Hz)':>12}  "
             f"{'Re s (1/s)':>13}  {'Im s (rad/s)':>13}"]
    for i, (fn, zeta, fd, s) in enumerate(rows, 1):
        z = "-" if zeta is None else f"{zeta:10.4g}"
        lines.append(f"{i:>4}  {fn:12.6g}  {z:>10}  {fd:12.6g}  {s.real:13.6g}  {s.imag:13.6g}")
    return "\n".join(lines)


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        prog=PROG,
        description="Bode plot and pole-zero plot of one input-output channel of the &linear "
                    "state-space model in a flexmor result file; prints the poles (natural "
                    "frequency in Hz, damping ratio) and the channel's transmission zeros.")
    parser.add_argument("file", metavar="RESULT.h5", help="flexmor result file with /linear")
    parser.add_argument("--input", default=None,
                        help="input name as in &linear inputs, e.g. tip.fy (default: the first)")
    parser.add_argument("--output", default=None,
                        help="output name as in &linear outputs, e.g. tip.y (default: the "
                             "first)")
    parser.add_argument("--index", type=int, default=0,
                        help="linearisation index, 0-based as /linear/time (default: 0)")
    parser.add_argument("--bode", default="bode.png", help="Bode plot to write (default: "
                        "bode.png; the format from the extension)")
    parser.add_argument("--pole-zero", default="pole_zero.png",
                        help="pole-zero plot to write (default: pole_zero.png)")
    parser.add_argument("--fmin", type=float, default=None,
                        help="lowest frequency in Hz (default: a decade below the lowest pole)")
    parser.add_argument("--fmax", type=float, default=None,
                        help="highest frequency in Hz (default: a decade above the highest "
                             "pole, at most 5 decades above fmin); also bounds the pole-zero "
                             "plot at |s| = 2 pi fmax")
    parser.add_argument("--points", type=int, default=1000,
                        help="log-spaced frequencies (default: 1000; the damped frequencies "
                             "of the poles are added)")
    parser.add_argument("--dpi", type=int, default=150, help="resolution (default: 150)")
    args = parser.parse_args(argv)
    for name in ("fmin", "fmax"):
        value = getattr(args, name)
        if value is not None and not (np.isfinite(value) and value > 0):
            parser.error(f"--{name} must be a positive number of Hz")
    if args.fmin is not None and args.fmax is not None and not args.fmin < args.fmax:
        parser.error("--fmin must be below --fmax")
    if args.points < 2:
        parser.error("--points must be at least 2")
    return args


def _check_folder(path: str) -> None:
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise OSError(f"{path}: the folder {folder} does not exist")


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    try:
        lin = read_linear(args.file)
        k = lin.index(args.index)
        i = lin.input_index(args.input if args.input is not None else 0)
        j = lin.output_index(args.output if args.output is not None else 0)
        for path in (args.bode, args.pole_zero):
            _check_folder(path)
        u, y = lin.inputs[i], lin.outputs[j]
        poles = lin.poles(k)
        zeros = lin.zeros(i, j, k)
    except (ResultFileError, LinearModelError, OSError, ValueError) as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return 2
    low, high = default_band(poles)
    fmin = args.fmin if args.fmin is not None else (low if args.fmax is None
                                                    else min(low, args.fmax / 10))
    fmax = args.fmax if args.fmax is not None else max(high, fmin * 10)
    f_hz = response_grid(poles, fmin, fmax, args.points)
    g = lin.frequency_response(2 * np.pi * f_hz, k, u, y)
    unit = f"{unit_of(y)}/{unit_of(u)}" if unit_of(y) and unit_of(u) else ""
    if unit.endswith("/N m"):
        unit = unit[:-3] + "(N m)"
    title = f"{y} / {u}, linearisation {k} (t = {lin.time[k]:g} s)"
    try:
        plot_bode(f_hz, g, args.bode, title, unit, poles, args.dpi)
        hidden = plot_pole_zero(poles, zeros, args.pole_zero, title, 2 * np.pi * fmax, args.dpi)
    except (OSError, ValueError) as exc:
        print(f"{PROG}: error: cannot write the plots: {exc}", file=sys.stderr)
        return 2
    print(f"{args.file}: {y} / {u}, linearisation {k} of {lin.n_models} (t = {lin.time[k]:g} s),"
          f" {lin.n_states} states")
    print(format_table(pole_table(poles), "poles"))
    print(format_table(pole_table(zeros), f"zeros of {y} / {u}"))
    print(f"wrote {args.bode} ({f_hz.size} frequencies, {fmin:.4g} to {fmax:.4g} Hz)")
    print(f"wrote {args.pole_zero}" + (f" ({hidden} poles and zeros beyond |s| = "
                                        f"{2 * np.pi * fmax:.4g} /s not shown)" if hidden else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
