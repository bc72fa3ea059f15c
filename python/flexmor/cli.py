"""What the plotting commands that compare a run with a reference share: their arguments
(a result file, ``--reference``, ``--node``, ``-o``, ``--dpi``), reading both files and the
check of the output folder before anything is drawn."""
from __future__ import annotations

import argparse
import os
import sys
from typing import Any, Callable

from flexmor.results import Result, ResultFileError, read_result


def reference_plot_args(prog: str, description: str, file_metavar: str, file_help: str,
                        reference_metavar: str, reference_help: str, default_output: str,
                        argv: list[str] | None) -> argparse.Namespace:
    """Parse ``FILE [--reference REF] [--node N ...] [-o OUT] [--dpi D]``; --node needs
    --reference and --dpi must be positive (argparse's usage error, exit status 2)."""
    parser = argparse.ArgumentParser(prog=prog, description=description)
    parser.add_argument("file", metavar=file_metavar, help=file_help)
    parser.add_argument("--reference", metavar=reference_metavar, default=None,
                        help=reference_help)
    parser.add_argument("--node", action="append", default=None,
                        help="output node of the true error, repeatable (default: every "
                             "output node the files share)")
    parser.add_argument("-o", "--output", default=default_output,
                        help=f"image to write (default: {default_output})")
    parser.add_argument("--dpi", type=int, default=150, help="resolution (default: 150)")
    args = parser.parse_args(argv)
    if args.node and args.reference is None:
        parser.error("--node needs --reference")
    if args.dpi <= 0:
        parser.error("--dpi must be positive")
    return args


def missing_output_folder(prog: str, output: str) -> bool:
    """True, with a one-line message on stderr, when the folder of ``output`` does not
    exist."""
    out_dir = os.path.dirname(os.path.abspath(output))
    if os.path.isdir(out_dir):
        return False
    print(f"{prog}: error: {output}: the folder {out_dir} does not exist", file=sys.stderr)
    return True


def read_with_reference(prog: str, args: argparse.Namespace,
                        data: Callable[[Result, Result | None, list[str] | None], Any]) -> Any:
    """``data(run, reference or None, args.node)`` from the files of ``args``, and that the
    output folder exists; None, with a one-line message on stderr, when a file cannot be read,
    ``data`` refuses them (ResultFileError) or the folder is missing."""
    try:
        run = read_result(args.file)
        reference = read_result(args.reference) if args.reference else None
        result = data(run, reference, args.node)
    except ResultFileError as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return None
    return None if missing_output_folder(prog, args.output) else result
