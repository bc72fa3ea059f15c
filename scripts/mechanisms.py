#!/usr/bin/env python3
"""The slider-crank and four-bar examples (input/slider_crank.nml, input/four_bar.nml):
closed-form rigid mechanisms, scene variants, measurements and the plots of docs/examples.md.

For each example it runs the scene as given (4 beam elements on the flexible link), with 2, 8
and 16 elements, and with the flexible link 100 times stiffer (E x 100), and prints

- the largest distance of the output point (the slider 'B', the rocker pin 'B') from the rigid
  mechanism's closed-form position at the same crank angle, for the stiff and flexible links;
- the largest transverse deflection of the flexible link's midpoint from its chord, and the
  largest difference of that deflection history from the 16-element solution (mesh
  convergence).

Usage (the flexmor Python package need not be installed; --bin defaults to build/bin/flexmor
in the repository):

    python3 scripts/mechanisms.py [--bin BIN] [--out-dir docs/img] [--work-dir DIR]

writes slider_crank.png and four_bar.png into --out-dir. tests/python/test_mechanisms.py uses
the closed forms and measurements of this file.
"""
from __future__ import annotations

import argparse
import re
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import h5py
import numpy as np

ROOT = Path(__file__).resolve().parents[1]

#: Per example: scene file, flexible link, its output point, the crank's driven coordinate.
EXAMPLES = {
    "slider_crank": ("slider_crank.nml", "rod", "B", "link 'crank' phi at node 'O'"),
    "four_bar": ("four_bar.nml", "coupler", "B", "link 'crank' phi at node 'O2'"),
}


def slider_crank_x(theta, r, l):
    """Slider position of the rigid in-line slider-crank: r cos(theta) + sqrt(l^2 - r^2 sin^2)."""
    return r * np.cos(theta) + np.sqrt(l**2 - (r * np.sin(theta))**2)


def four_bar_b(theta, o2, o4, a0, b0, coupler=None):
    """Rocker pin B of the rigid four-bar at crank angle theta (absolute, from the x axis),
    with link lengths and assembly branch from the reference positions o2, o4, a0, b0: B is
    where the circles about A (coupler length) and O4 (rocker length) meet, on the side of
    the line A-O4 where the reference B lies. `coupler` overrides the coupler's length."""
    o2, o4, a0, b0 = (np.asarray(p, dtype=float) for p in (o2, o4, a0, b0))
    crank, rocker = np.linalg.norm(a0 - o2), np.linalg.norm(b0 - o4)
    coupler = np.linalg.norm(b0 - a0) if coupler is None else coupler
    (px, py), (qx, qy) = o4 - a0, b0 - a0
    side = np.sign(px * qy - py * qx)
    theta = np.atleast_1d(theta)
    a = o2 + crank * np.stack([np.cos(theta), np.sin(theta)], axis=1)
    d = o4 - a
    dist = np.linalg.norm(d, axis=1)
    along = (dist**2 + coupler**2 - rocker**2) / (2 * dist)
    across = np.sqrt(coupler**2 - along**2)
    u = d / dist[:, None]
    n = np.stack([-u[:, 1], u[:, 0]], axis=1)
    return a + along[:, None] * u + side * across[:, None] * n


def variant(text: str, link: str, n_elements: int | None = None,
            e_scale: float | None = None) -> str:
    """The scene with the &link `link` meshed into n_elements and/or its E scaled, and without
    &output (so that every node is written whatever the mesh)."""
    pattern = re.compile(r"&link\s+label\s*=\s*'" + re.escape(link) + r"'.*?/", re.S)
    group = pattern.search(text)
    if group is None:
        raise ValueError(f"no &link '{link}' in the scene")
    new = group.group(0)
    if n_elements is not None:
        new = re.sub(r"n_elements\s*=\s*\d+", f"n_elements = {n_elements}", new)
    if e_scale is not None:
        e = float(re.search(r"\bE\s*=\s*([0-9.eEdD+-]+)", new).group(1))
        new = re.sub(r"\bE\s*=\s*[0-9.eEdD+-]+", f"E = {e * e_scale!r}", new)
    text = text[:group.start()] + new + text[group.end():]
    return re.sub(r"^&output.*?/\s*$", "", text, flags=re.M | re.S)


def run_scene(binary: Path, text: str, out: Path, timeout: float = 600) -> Path:
    """Run flexmor on a scene text; RuntimeError with its message on failure."""
    nml = out.with_suffix(".nml")
    nml.write_text(text)
    proc = subprocess.run([str(binary), str(nml), "-o", str(out), "-q"], capture_output=True,
                          text=True, timeout=timeout)
    if proc.returncode != 0:
        raise RuntimeError(f"flexmor {nml.name}: {proc.stderr.strip()}")
    return out


@dataclass
class Motion:
    """What the examples measure: crank angle theta (rad), the output point's position from
    the simulation and from the rigid closed form, and the flexible link's midpoint deflection
    across its chord."""

    time: np.ndarray
    theta: np.ndarray
    point: np.ndarray
    rigid: np.ndarray
    midpoint_deflection: np.ndarray

    @property
    def deviation(self) -> np.ndarray:
        """Distance of the output point from the rigid mechanism's."""
        return np.linalg.norm(self.point - self.rigid, axis=1)


def _names(f: h5py.File) -> list[str]:
    return [n.decode() if isinstance(n, bytes) else str(n)
            for n in f["model/coordinates/name"][:]]


def measure(path: Path, example: str) -> Motion:
    """The Motion of a result file of `example` (or of one of its variants)."""
    _, link, point, drive = EXAMPLES[example]
    with h5py.File(path) as f:
        names = _names(f)
        x = f["x"][:]
        labels = [n.decode() if isinstance(n, bytes) else str(n) for n in f["model/nodes/label"][:]]
        ref = {lab: f["model/nodes/position"][i, :2] for i, lab in enumerate(labels)}

        def xy(node):
            return np.stack([x[:, names.index(f"{node} x")], x[:, names.index(f"{node} y")]], 1)

        time = f["time"][:]
        a, b = (xy(f"node '{n}'") for n in ("A", point))
        inner = sorted({int(m.group(1)) for n in names
                        if (m := re.fullmatch(re.escape(link) + r"\.(\d+) x", n))})
        n_el = len(inner) + 1
        if n_el % 2:
            raise ValueError(f"{path}: the link '{link}' has an odd number of elements")
        mid = xy(f"{link}.{n_el // 2}")
    crank0 = ref["A"] - ref["O" if example == "slider_crank" else "O2"]
    theta = np.arctan2(crank0[1], crank0[0]) + x[:, names.index(drive)]
    if example == "slider_crank":
        r = np.linalg.norm(crank0)
        rigid = np.stack([slider_crank_x(theta, r, np.linalg.norm(ref["B"] - ref["A"])),
                          np.zeros_like(theta)], axis=1)
    else:
        rigid = four_bar_b(theta, ref["O2"], ref["O4"], ref["A"], ref["B"])
    chord = (b - a) / np.linalg.norm(b - a, axis=1)[:, None]
    offset = mid - (a + b) / 2
    deflection = chord[:, 0] * offset[:, 1] - chord[:, 1] * offset[:, 0]
    return Motion(time, theta, b, rigid, deflection)


def run_example(binary: Path, example: str, work: Path,
                meshes=(2, 4, 8, 16), e_scale: float = 100.0) -> dict:
    """Run the example's variants; returns {'mesh': {n: Motion}, 'stiff': Motion}."""
    scene, link, _, _ = EXAMPLES[example]
    text = (ROOT / "input" / scene).read_text()
    out = {"mesh": {}}
    for n in meshes:
        path = run_scene(binary, variant(text, link, n_elements=n), work / f"{example}_{n}.h5")
        out["mesh"][n] = measure(path, example)
    path = run_scene(binary, variant(text, link, e_scale=e_scale), work / f"{example}_stiff.h5")
    out["stiff"] = measure(path, example)
    return out


def report(example: str, runs: dict) -> list[str]:
    meshes = runs["mesh"]
    finest = max(meshes)
    lines = [f"{example}: stiff link (E x 100): largest distance from the rigid mechanism "
             f"{runs['stiff'].deviation.max():.3e} m"]
    for n, m in sorted(meshes.items()):
        line = (f"  {n:2d} elements: distance from rigid {m.deviation.max():.3e} m, midpoint "
                f"deflection {np.abs(m.midpoint_deflection).max():.3e} m")
        if n != finest:
            diff = np.abs(m.midpoint_deflection - meshes[finest].midpoint_deflection).max()
            line += f", differs from {finest} elements by {diff:.3e} m"
        lines.append(line)
    return lines


def plot(example: str, runs: dict, png: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    name = "slider" if example == "slider_crank" else "rocker pin B"
    link = EXAMPLES[example][1]
    for n, m in sorted(runs["mesh"].items()):
        deg = np.degrees(m.theta - m.theta[0])
        top.plot(deg, 1e6 * m.deviation, label=f"{n} elements")
        bottom.plot(deg, 1e3 * m.midpoint_deflection, label=f"{n} elements")
    stiff = runs["stiff"]
    top.plot(np.degrees(stiff.theta - stiff.theta[0]), 1e6 * stiff.deviation, "k--",
             label="E x 100, 4 elements")
    top.set_ylabel(f"{name}: distance from\nrigid mechanism [um]")
    bottom.set_ylabel(f"{link} midpoint deflection\nacross its chord [mm]")
    bottom.set_xlabel("crank rotation [deg]")
    top.legend(fontsize=8)
    top.set_title(f"input/{EXAMPLES[example][0]}")
    for ax in (top, bottom):
        ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(png, dpi=110)
    plt.close(fig)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--bin", type=Path, default=ROOT / "build" / "bin" / "flexmor")
    parser.add_argument("--out-dir", type=Path, default=ROOT / "docs" / "img")
    parser.add_argument("--work-dir", type=Path, default=None,
                        help="keep the result files here (default: a temporary folder)")
    args = parser.parse_args(argv)
    if not args.bin.is_file():
        print(f"mechanisms.py: error: no flexmor binary at {args.bin} (give --bin)",
              file=sys.stderr)
        return 2
    args.out_dir.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        work = args.work_dir or Path(tmp)
        work.mkdir(parents=True, exist_ok=True)
        for example in EXAMPLES:
            runs = run_example(args.bin, example, work)
            print("\n".join(report(example, runs)))
            plot(example, runs, args.out_dir / f"{example}.png")
            print(f"wrote {args.out_dir / (example + '.png')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
