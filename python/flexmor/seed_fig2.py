"""The seed paper's Fig. 2: tip path of the two-link manipulator, full model against the
reduced models with 1 and 2 modes (fixed basis from the initial configuration), full view and
detail near the upper extreme.

    flexmor-seed-fig2 [--bin build/bin/flexmor] [--input-dir input] [--out-dir .] [--reuse]

Runs two_link.nml, two_link_1mode.nml and two_link_2modes.nml of the repository's input/
folder (--input-dir; unless --reuse finds their result files in --out-dir), writes
seed_fig2.png there and prints, per model, the largest tip distance from the full model, the
solve time and the step count. The defaults of --bin and --input-dir are relative to the
current folder, so that the command runs as it is from the repository's root.
Exit status 0 on success, 2 with a one-line message for a missing binary or a failed run.
"""
from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

import numpy as np

from flexmor.plot_tip_path import plot_paths
from flexmor.results import ResultFileError, load_node_path, run_attributes

PROG = "flexmor-seed-fig2"
MODELS = [("two_link", "full model (12 coordinates)"),
          ("two_link_1mode", "1 mode"),
          ("two_link_2modes", "2 modes")]


class Fig2Error(Exception):
    """A run or a file failed; the message is one line."""


def run_model(binary: Path, input_dir: Path, name: str, out_dir: Path, reuse: bool) -> Path:
    """Result file of <input_dir>/<name>.nml in out_dir, running flexmor unless reusing."""
    result = out_dir / f"{name}.h5"
    if reuse and result.exists():
        return result
    scene = input_dir / f"{name}.nml"
    if not scene.is_file():
        raise Fig2Error(f"{scene}: no such scene file (give the repository's input folder "
                        f"with --input-dir)")
    proc = subprocess.run([str(binary), str(scene), "-o", str(result), "-q"],
                          capture_output=True, text=True)
    if proc.returncode != 0:
        last = (proc.stderr.strip().splitlines() or ["(no message)"])[-1]
        raise Fig2Error(f"{name}: flexmor failed: {last}")
    return result


def tip_distance(xyz: np.ndarray, reference: np.ndarray) -> float:
    """Largest distance between two tip paths sampled at the same times."""
    if xyz.shape != reference.shape:
        raise Fig2Error("the runs have different output times")
    return float(np.max(np.linalg.norm(xyz[:, :2] - reference[:, :2], axis=1)))


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n\n")[0])
    parser.add_argument("--bin", default=str(Path("build", "bin", "flexmor")),
                        help="flexmor executable (default: build/bin/flexmor)")
    parser.add_argument("--input-dir", default="input",
                        help="folder with the two_link*.nml scenes (default: input)")
    parser.add_argument("--out-dir", default=".", help="folder for the result files and plot")
    parser.add_argument("--reuse", action="store_true",
                        help="use existing result files in --out-dir instead of running")
    return parser.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    binary, out_dir = Path(args.bin), Path(args.out_dir)
    try:
        if not binary.is_file():
            raise Fig2Error(f"{binary}: no flexmor executable (build first: scripts/example.sh)")
        if not out_dir.is_dir():
            raise Fig2Error(f"{out_dir}: no such folder")
        series, rows = [], []
        for name, label in MODELS:
            result = run_model(binary, Path(args.input_dir), name, out_dir, args.reuse)
            t, xyz = load_node_path(result, "tip")
            attrs = run_attributes(result)
            series.append((label, t, xyz))
            rows.append((label, tip_distance(xyz, series[0][2]), float(attrs["wall_time_s"]),
                         int(attrs["n_steps"])))
        plot_paths(series, str(out_dir / "seed_fig2.png"))
    except (Fig2Error, ResultFileError, OSError) as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return 2
    print(f"{'model':30s} {'tip distance from full [m]':>27s} {'solve time [s]':>15s} "
          f"{'steps':>7s}")
    for label, dist, wall, steps in rows:
        print(f"{label:30s} {dist:27.3e} {wall:15.3f} {steps:7d}")
    print(f"wrote {out_dir / 'seed_fig2.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
