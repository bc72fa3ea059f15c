#!/usr/bin/env python3
"""The plots of docs/examples.md for input/spin_up.nml: hub angle and the tip's deflection from
the rotating hub line against time; and the scene reduced to 3 modes with the expanded
evaluation, its error estimate against its true distance from the full model
(flexmor-plot-reduction).

    python3 scripts/spin_up.py [--bin build/bin/flexmor] [--out docs/img/spin_up.png] \
        [--reduction-out docs/img/spin_up_reduction.png]
"""
from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
import flexmor
from flexmor import plot_reduction

HUB = "link 'beam' phi at node 'base'"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--bin", type=Path, default=ROOT / "build" / "bin" / "flexmor")
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "img" / "spin_up.png")
    ap.add_argument("--reduction-out", type=Path,
                    default=ROOT / "docs" / "img" / "spin_up_reduction.png")
    args = ap.parse_args(argv)
    scene = (ROOT / "input" / "spin_up.nml").read_text()
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "spin_up.h5"
        subprocess.run([str(args.bin), str(ROOT / "input" / "spin_up.nml"), "-o", str(out),
                        "-q"], check=True, timeout=3600)
        r = flexmor.read_result(out)
        reduced_nml = Path(tmp) / "spin_up_reduced.nml"
        reduced_nml.write_text(scene + "&reduction n_modes = 3, evaluation = 'expanded' /\n")
        reduced = Path(tmp) / "spin_up_reduced.h5"
        subprocess.run([str(args.bin), str(reduced_nml), "-o", str(reduced), "-q"], check=True,
                       timeout=3600)
        data = plot_reduction.reduction_errors(flexmor.read_result(reduced), r)
    model = r.require_model()
    hub = r.x[:, list(model.coordinate_names).index(HUB)]
    tip = r.nodes["tip"].position
    deflection = -tip[:, 0] * np.sin(hub) + tip[:, 1] * np.cos(hub)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    ax[0].plot(r.time, hub)
    ax[0].set(xlabel="t [s]", ylabel="hub angle [rad]", title="spin-up law (w = 4 rad/s, T = 15 s)")
    ax[1].plot(r.time, deflection)
    ax[1].set(xlabel="t [s]", ylabel="tip deflection [m]",
              title="tip deflection from the rotating hub line")
    for a in ax:
        a.grid(alpha=0.3)
    fig.tight_layout()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=110)
    print(f"wrote {args.out}: largest deflection {np.abs(deflection).max():.4f} m")
    args.reduction_out.parent.mkdir(parents=True, exist_ok=True)
    plot_reduction.plot_reduction(data, str(args.reduction_out),
                                  "input/spin_up.nml, 3 modes, evaluation 'expanded', "
                                  "against the full model")
    print(f"wrote {args.reduction_out}: estimate up to "
          f"{data['attrs']['error_estimate_max']:.3g} m, the tip up to "
          f"{np.max(data['true']):.3g} m from the full model's")
    return 0


if __name__ == "__main__":
    sys.exit(main())
