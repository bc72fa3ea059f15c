#!/usr/bin/env python3
"""The compliant-mechanism examples (input/leaf_spring_guide.nml, input/cross_spring_pivot.nml):
tables, mesh convergence and plots for docs/examples.md and docs/bench/compliant_examples.md.

For the guide: shuttle stroke, parasitic shortening, rotation, support stiffness 1/C_yy and
lateral stiffness 1/C_xx at every load step, against 2 EA/L and 24 EI/L^3. For the pivot:
reaction moment M(phi), centre shift and the translational stiffness along the two leaves at
every step, against 2 EI/L phi and EA/L + 12 EI/L^3. Both with 4, 8 (the examples) and 16
elements per leaf (--meshes), the differences from the finest mesh reported.

Usage (--bin defaults to build/bin/flexmor in the repository; needs the flexmor Python package:
`pip install .`, as scripts/setup.sh does, or PYTHONPATH=python):

    python3 scripts/compliant_examples.py [--bin BIN] [--meshes 4 8 16] [--out-dir docs]

writes <out-dir>/img/leaf_spring_guide.png, <out-dir>/img/cross_spring_pivot.png and
<out-dir>/bench/compliant_examples.md.
"""
from __future__ import annotations

import argparse
import math
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
import flexmor

E = 2.1e11
GUIDE = dict(L=0.1, A=6.0e-6, I=4.5e-14)
PIVOT = dict(L=0.05, A=2.0e-6, I=6.6666667e-15)


def mesh(text: str, n: int) -> str:
    """The example with n elements per leaf; the class lists keep their pattern (the last
    element of leaf2 elastic; in the pivot also the body-side bending of leaf1)."""
    out = text.replace("n_elements = 8", f"n_elements = {n}")
    # Through placeholders, so that one replacement cannot match the result of another.
    pairs = [("15*'dynamic', 'elastic'", f"{2 * n - 1}*'dynamic', 'elastic'"),
             ("7*'dynamic', 'elastic'", f"{n - 1}*'dynamic', 'elastic'"),
             ("14*'dynamic', 2*'elastic'", f"{2 * n - 2}*'dynamic', 2*'elastic'")]
    for i, (old, _) in enumerate(pairs):
        out = out.replace(old, f"@{i}@")
    for i, (_, new) in enumerate(pairs):
        out = out.replace(f"@{i}@", new)
    return out


def run(binary: Path, text: str, work: Path, name: str) -> tuple[flexmor.Result, float]:
    nml, out = work / f"{name}.nml", work / f"{name}.h5"
    nml.write_text(text)
    start = time.perf_counter()
    subprocess.run([str(binary), str(nml), "-o", str(out), "-q"], check=True, timeout=3600)
    return flexmor.read_result(out), time.perf_counter() - start


def guide_table(result: flexmor.Result) -> dict[str, np.ndarray]:
    static = result.static
    node = static.nodes["shuttle"]
    c = node.compliance
    return {"force_N": 2.2 * static.load_factor, "stroke_m": node.position[:, 0] - 0.025,
            "shortening_m": 0.1 - node.position[:, 1], "rotation_rad": node.rotation,
            "support_N_per_m": 1 / c[:, 1, 1], "lateral_N_per_m": 1 / c[:, 0, 0]}


def pivot_table(result: flexmor.Result) -> dict[str, np.ndarray]:
    node = result.static.nodes["body"]
    s = math.sin(math.pi / 4)
    dirs = np.array([[s, s], [-s, s]])
    c = node.compliance[:, :2, :2]
    stiff = 1 / np.einsum("i,nij,j->n", dirs[0], c, dirs[0]), \
        1 / np.einsum("i,nij,j->n", dirs[1], c, dirs[1])
    return {"phi_rad": node.rotation, "moment_Nm": node.reaction[:, 2],
            "shift_m": np.linalg.norm(node.position[:, :2], axis=1),
            "stiffness_d1_N_per_m": stiff[0], "stiffness_d2_N_per_m": stiff[1]}


def rel_diff(a: dict, b: dict, keys) -> dict[str, float]:
    return {k: float(np.max(np.abs(a[k] / b[k] - 1))) for k in keys}


def markdown(rows: list[list[str]]) -> str:
    out = ["| " + " | ".join(rows[0]) + " |", "| " + " | ".join("---" for _ in rows[0]) + " |"]
    out += ["| " + " | ".join(r) + " |" for r in rows[1:]]
    return "\n".join(out)


def plots(guide: dict, pivot: dict, out_dir: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    ea_l = 2 * E * GUIDE["A"] / GUIDE["L"]
    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    ax[0].semilogy(np.r_[0, guide["stroke_m"]] * 1e3, np.r_[ea_l, guide["support_N_per_m"]], "o-")
    ax[0].set(xlabel="stroke u [mm]", ylabel="support stiffness 1/C_yy [N/m]",
              title="leaf-spring guide: support stiffness")
    ax[0].grid(True, which="both", alpha=0.3)
    ax[1].plot(guide["force_N"], guide["stroke_m"] * 1e3, "o-", label="stroke u")
    ax[1].plot(guide["force_N"], guide["shortening_m"] * 1e3, "s-", label="shortening")
    ax[1].set(xlabel="force fx [N]", ylabel="[mm]", title="stroke and parasitic shortening")
    ax[1].legend()
    ax[1].grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out_dir / "leaf_spring_guide.png", dpi=110)
    plt.close(fig)
    k0 = 2 * E * PIVOT["I"] / PIVOT["L"]
    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    ax[0].plot(pivot["phi_rad"], pivot["moment_Nm"] * 1e3, "o-", label="flexmor")
    ax[0].plot(pivot["phi_rad"], k0 * pivot["phi_rad"] * 1e3, "--", label="2EI/L phi")
    ax[0].set(xlabel="rotation phi [rad]", ylabel="moment M [N mm]",
              title="cross-spring pivot: moment")
    ax[0].legend()
    ax[0].grid(alpha=0.3)
    ax[1].plot(pivot["phi_rad"], pivot["shift_m"] * 1e6, "o-")
    ax[1].set(xlabel="rotation phi [rad]", ylabel="centre shift [um]",
              title="centre shift of the body node")
    ax[1].grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out_dir / "cross_spring_pivot.png", dpi=110)
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--bin", type=Path, default=ROOT / "build" / "bin" / "flexmor")
    ap.add_argument("--meshes", type=int, nargs="+", default=[4, 8, 16])
    ap.add_argument("--out-dir", type=Path, default=ROOT / "docs")
    args = ap.parse_args(argv)
    guide_text = (ROOT / "input" / "leaf_spring_guide.nml").read_text()
    pivot_text = (ROOT / "input" / "cross_spring_pivot.nml").read_text()
    guides, pivots, times = {}, {}, {}
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        for n in args.meshes:
            r, times[("guide", n)] = run(args.bin, mesh(guide_text, n), work, f"guide{n}")
            guides[n] = guide_table(r)
            r, times[("pivot", n)] = run(args.bin, mesh(pivot_text, n), work, f"pivot{n}")
            pivots[n] = pivot_table(r)
    fine = max(args.meshes)
    example = 8 if 8 in args.meshes else min(args.meshes)
    g, p = guides[example], pivots[example]
    lines = [f"# Compliant-mechanism examples: measured",
             "",
             f"`python3 scripts/compliant_examples.py --meshes {' '.join(map(str, args.meshes))}` "
             f"on {machine()}, "
             f"commit {git_commit()}, binary {args.bin.name} "
             f"({'Release' if 'rel' in str(args.bin) else 'as built'}).",
             "",
             f"## Parallel leaf-spring guide ({example} elements per leaf)",
             "",
             markdown([["fx [N]", "stroke u [mm]", "shortening [um]", "rotation [urad]",
                        "support 1/C_yy [N/m]", "lateral 1/C_xx [N/m]"]] +
                      [[f"{g['force_N'][i]:.1f}", f"{g['stroke_m'][i] * 1e3:.4f}",
                        f"{g['shortening_m'][i] * 1e6:.3f}", f"{g['rotation_rad'][i] * 1e6:.2f}",
                        f"{g['support_N_per_m'][i]:.6g}", f"{g['lateral_N_per_m'][i]:.6g}"]
                       for i in range(len(g["force_N"]))]),
             "",
             f"Closed forms at zero deflection: support 2EA/L = "
             f"{2 * E * GUIDE['A'] / GUIDE['L']:.6g} N/m, lateral 24EI/L^3 = "
             f"{24 * E * GUIDE['I'] / GUIDE['L']**3:.6g} N/m (the shuttle's tilt, allowed by "
             f"the leaves' stretch, lowers the latter by 0.09 %).",
             "",
             f"## Cross-spring pivot ({example} elements per leaf)",
             "",
             markdown([["phi [rad]", "M [N mm]", "M / (2EI/L phi)", "centre shift [um]",
                        "stiffness along d1 [N/m]", "along d2 [N/m]"]] +
                      [[f"{p['phi_rad'][i]:.2f}", f"{p['moment_Nm'][i] * 1e3:.5f}",
                        f"{p['moment_Nm'][i] / (2 * E * PIVOT['I'] / PIVOT['L'] * p['phi_rad'][i]):.5f}",
                        f"{p['shift_m'][i] * 1e6:.3f}", f"{p['stiffness_d1_N_per_m'][i]:.5g}",
                        f"{p['stiffness_d2_N_per_m'][i]:.5g}"]
                       for i in range(len(p["phi_rad"])) if (i + 1) % 5 == 0]),
             "",
             f"Closed forms at zero rotation: 2EI/L = {2 * E * PIVOT['I'] / PIVOT['L']:.6g} N m/rad, "
             f"EA/L + 12EI/L^3 = {E * PIVOT['A'] / PIVOT['L'] + 12 * E * PIVOT['I'] / PIVOT['L']**3:.6g} N/m.",
             "",
             f"## Mesh convergence (largest relative difference from {fine} elements per leaf)",
             ""]
    rows = [["elements", "guide stroke", "guide support stiffness", "pivot M", "pivot shift",
             "guide run [s]", "pivot run [s]"]]
    for n in args.meshes:
        dg = rel_diff(guides[n], guides[fine], ["stroke_m", "support_N_per_m"])
        dp = rel_diff(pivots[n], pivots[fine], ["moment_Nm", "shift_m"])
        rows.append([str(n), f"{dg['stroke_m']:.2e}", f"{dg['support_N_per_m']:.2e}",
                     f"{dp['moment_Nm']:.2e}", f"{dp['shift_m']:.2e}",
                     f"{times[('guide', n)]:.2f}", f"{times[('pivot', n)]:.2f}"])
    lines += [markdown(rows), ""]
    (args.out_dir / "bench").mkdir(parents=True, exist_ok=True)
    (args.out_dir / "img").mkdir(parents=True, exist_ok=True)
    (args.out_dir / "bench" / "compliant_examples.md").write_text("\n".join(lines))
    plots(g, p, args.out_dir / "img")
    print("\n".join(lines))
    return 0


def machine() -> str:
    """The CPU model (Linux), else the platform's machine name."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip() + f" ({os_cpus()} cores)"
    except OSError:
        pass
    return platform.machine()


def os_cpus() -> int:
    import os
    return os.cpu_count() or 1


def git_commit() -> str:
    try:
        return subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"],
                              capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


if __name__ == "__main__":
    sys.exit(main())
