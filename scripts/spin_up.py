#!/usr/bin/env python3
"""The plot of docs/examples.md for input/spin_up.nml: hub angle and the tip's deflection from
the rotating hub line against time.

    python3 scripts/spin_up.py [--bin build/bin/flexmor] [--out docs/img/spin_up.png]
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

HUB = "link 'beam' phi at node 'base'"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--bin", type=Path, default=ROOT / "build" / "bin" / "flexmor")
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "img" / "spin_up.png")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "spin_up.h5"
        subprocess.run([str(args.bin), str(ROOT / "input" / "spin_up.nml"), "-o", str(out),
                        "-q"], check=True, timeout=3600)
        r = flexmor.read_result(out)
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
    return 0


if __name__ == "__main__":
    sys.exit(main())
