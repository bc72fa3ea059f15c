#!/usr/bin/env python3
"""The spatial examples of the issue list (input/bend45.nml, input/lateral_buckling.nml,
input/right_angle_cantilever.nml): scene generators for any mesh, the closed forms they are
checked against, and the convergence tables of the two spatial bending forms (angle, sine).

- bend45: Bathe and Bolourchi's 45-degree bend under a tip force in z (150 to 600 in 4
  steps). No closed form: the reference is flexmor's own 64-element solution, Richardson-
  extrapolated from 32 and 64 elements (the error goes as h^2).
- lateral_buckling: a narrow cantilever under a tip force in its stiff plane, against
  P = gamma sqrt(E Iy G J) / L^2 with gamma the first root of the twist equation
  beta'' + gamma^2 s^2 beta = 0 (s from the free end), computed here by shooting.
- right_angle_cantilever: Simo and Vu-Quoc's elbow; the energy at the end of the pulse equals
  the work of the force, and it is conserved afterwards.

It also times the elbow on meshes of 10 to 160 beams (cost per step against the mesh).

Usage (--bin defaults to build/bin/flexmor in the repository):

    python3 scripts/spatial_examples.py [--bin BIN] [--out docs/bench/spatial_convergence.md]

tests/python/test_spatial_examples.py uses the generators and closed forms of this file.
"""
from __future__ import annotations

import argparse
import platform
import subprocess
import tempfile
import time
from pathlib import Path

import h5py
import numpy as np

ROOT = Path(__file__).resolve().parents[1]

#: The bend: radius, sweep, section and load of the benchmark.
BEND_RADIUS, BEND_ANGLE, BEND_FORCE = 100.0, np.radians(45.0), 600.0
BEND_SECTION = ("E = 1.0e7, G = 5.0e6, shear_factor = 0.8333333333333333, A = 1.0, rho = 1.0,\n"
                "      I = 0.08333333333333333, Iy = 0.08333333333333333, "
                "J = 0.16666666666666667")

#: The narrow cantilever: length, section 10 mm (y) by 1 mm (z), steel.
LTB_L, LTB_H, LTB_T, LTB_E, LTB_NU = 0.1, 1.0e-2, 1.0e-3, 2.1e11, 0.3


def bend45_scene(n, form="angle", n_steps=4):
    """The bend with n straight beams (one per link) whose nodes lie on the arc; centre
    (0, R, 0), clamped at the origin along x."""
    th = BEND_ANGLE * np.arange(n + 1) / n
    x, y = BEND_RADIUS * np.sin(th), BEND_RADIUS * (1 - np.cos(th))
    labels = ["root"] + [f"p{k}" for k in range(1, n)] + ["tip"]
    lines = ["&scene title = '45-degree bend', dimension = 3 /"]
    for k, lab in enumerate(labels):
        fix = ", fixed = .true." if k == 0 else ""
        lines.append(f"&node label = '{lab}', x = {x[k]:.15g}, y = {y[k]:.15g}, z = 0.0{fix} /")
    for k in range(n):
        lines.append(f"&link label = 's{k + 1}', from = '{labels[k]}', to = '{labels[k + 1]}', "
                     f"elongation = 'dynamic', bending_form = '{form}',\n      {BEND_SECTION} /")
    lines += [f"&force node = 'tip', fz = {BEND_FORCE} /", f"&static n_steps = {n_steps} /",
              "&output nodes = 'tip' /"]
    return "\n".join(lines) + "\n"


def torsion_constant(h, t, terms=50):
    """Saint-Venant's torsion constant of an h x t rectangle (h >= t), series solution."""
    n = np.arange(1, 2 * terms, 2)
    s = np.sum(np.tanh(n * np.pi * h / (2 * t)) / n**5)
    return h * t**3 / 3 * (1 - 192 / np.pi**5 * t / h * s)


def ltb_section():
    """E, G, A, I (about z: stiff), Iy (weak), J of the narrow cantilever."""
    g = LTB_E / (2 * (1 + LTB_NU))
    return (LTB_E, g, LTB_H * LTB_T, LTB_T * LTB_H**3 / 12, LTB_H * LTB_T**3 / 12,
            torsion_constant(LTB_H, LTB_T))


def lateral_buckling_scene(n, form="angle", shear_rigid=False):
    """The narrow cantilever with n beams and a 1 N tip force in y; `shear_rigid` makes the
    shear stiffness 1e6 times larger (the closed form is Euler-Bernoulli)."""
    e, g, a, iz, iy, j = (float(v) for v in ltb_section())
    shear = ", shear_factor = 1.0e6" if shear_rigid else ""
    return (
        "&scene title = 'lateral buckling', dimension = 3 /\n"
        "&node label = 'root', x = 0, y = 0, z = 0, fixed = .true. /\n"
        f"&node label = 'tip', x = {LTB_L}, y = 0, z = 0 /\n"
        f"&link label = 'strip', from = 'root', to = 'tip', n_elements = {n}, "
        f"bending_form = '{form}',\n"
        f"      E = {e:.17g}, G = {g:.17g}, A = {a:.17g}, I = {iz:.17g}, Iy = {iy:.17g},\n"
        f"      J = {j:.17g}, rho = 7850{shear} /\n"
        "&force node = 'tip', fy = 1.0 /\n&buckling n_modes = 2 /\n&output nodes = 'tip' /\n")


def ltb_gamma():
    """First root gamma of beta(1) = 0 for beta'' + gamma^2 u^2 beta = 0, beta(0) = 1,
    beta'(0) = 0 (u = distance from the free end over L): RK4 on 4000 steps (error ~1e-13)
    and bisection. The textbook value is 4.013."""
    def end_value(gamma, steps=4000):
        h = 1.0 / steps
        y = np.array([1.0, 0.0])

        def f(u, y):
            return np.array([y[1], -gamma**2 * u**2 * y[0]])
        u = 0.0
        for _ in range(steps):
            k1 = f(u, y)
            k2 = f(u + h / 2, y + h / 2 * k1)
            k3 = f(u + h / 2, y + h / 2 * k2)
            k4 = f(u + h, y + h * k3)
            y = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
            u += h
        return y[0]
    lo, hi = 3.0, 5.0
    assert end_value(lo) > 0 > end_value(hi)
    for _ in range(60):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if end_value(mid) > 0 else (lo, mid)
    return (lo + hi) / 2


def ltb_critical_force():
    """The closed-form critical tip force [N] of the narrow cantilever."""
    e, g, _, _, iy, j = ltb_section()
    return ltb_gamma() * np.sqrt(e * iy * g * j) / LTB_L**2


def pivot_support_stiffness(e=2.1e11, nu=0.3, width=0.01, thickness=2.0e-4, length=0.05,
                            shear_factor=5 / 6):
    """Out-of-plane stiffness [N/m] of input/cross_spring_pivot_spatial.nml at the crossing
    (the body's node): the two leaves, clamped at the ground, carry the body's z translation
    and its rotations about x and y through their bending in the wide direction (Timoshenko,
    exact for end loads) and their torsion G J / L; the body's rotations settle where the
    moments vanish. Leaf i runs along d_i at +-45 degrees from y, its body end at
    p_i = (L/2) d_i."""
    g = e / (2 * (1 + nu))
    area, i_wide = width * thickness, thickness * width**3 / 12
    j = torsion_constant(width, thickness)
    phi = 12 * e * i_wide / (shear_factor * g * area * length**2)
    bend = e * i_wide / (length**3 * (1 + phi)) * np.array(
        [[12, -6 * length], [-6 * length, (4 + phi) * length**2]])
    k = np.zeros((3, 3))
    for d in (np.array([1.0, 1.0, 0.0]) / np.sqrt(2), np.array([-1.0, 1.0, 0.0]) / np.sqrt(2)):
        p, n = length / 2 * d, np.cross([0.0, 0.0, 1.0], d)
        # End deflection w, slope dw/ds = -theta.n and twist theta.d from (z, theta_x, theta_y).
        t = np.array([[1.0, p[1], -p[0]], [0.0, -n[0], -n[1]], [0.0, d[0], d[1]]])
        leaf = np.zeros((3, 3))
        leaf[:2, :2] = bend
        leaf[2, 2] = g * j / length
        k += t.T @ leaf @ t
    return 1 / np.linalg.inv(k)[0, 0]


def southwell_coefficient(mode):
    """Southwell coefficient alpha of clamped-free bending mode 1 or 2 of a uniform blade
    spinning about an axis through its root (no hub radius): first-order perturbation of the
    frequency by the centrifugal tension T(x) = rho A Omega^2 (L^2 - x^2)/2,
    alpha = int (L^2 - x^2)/2 phi'^2 dx / int phi^2 dx with the exact cantilever mode phi
    (L = 1; trapezoidal rule on 200,000 intervals). 1.1933 and 6.4782."""
    beta = {1: 1.8751040687119611, 2: 4.694091132974175}[mode]
    sigma = (np.cosh(beta) + np.cos(beta)) / (np.sinh(beta) + np.sin(beta))
    x = np.linspace(0.0, 1.0, 200001)
    phi = np.cosh(beta * x) - np.cos(beta * x) - sigma * (np.sinh(beta * x) - np.sin(beta * x))
    dphi = beta * (np.sinh(beta * x) + np.sin(beta * x)
                   - sigma * (np.cosh(beta * x) - np.cos(beta * x)))
    return np.trapezoid(0.5 * (1 - x**2) * dphi**2, x) / np.trapezoid(phi**2, x)


def run(binary, folder, name, text):
    """Run flexmor on `text`; returns the result path and the wall time [s]."""
    nml, out = Path(folder) / f"{name}.nml", Path(folder) / f"{name}.h5"
    nml.write_text(text)
    t0 = time.perf_counter()
    subprocess.run([str(binary), str(nml), "-o", str(out), "-q"], check=True,
                   capture_output=True, text=True)
    return out, time.perf_counter() - t0


def bend_tips(binary, folder, n, form="angle"):
    """Tip positions (4, 3) after each load step, and the wall time."""
    out, wall = run(binary, folder, f"bend_{form}_{n}", bend45_scene(n, form))
    with h5py.File(out) as f:
        return f["static/nodes/tip/position"][:], wall


def ltb_load(binary, folder, n, form="angle", shear_rigid=False):
    """Lowest buckling load [N] and the wall time."""
    out, wall = run(binary, folder, f"ltb_{form}_{n}_{shear_rigid}",
                    lateral_buckling_scene(n, form, shear_rigid))
    with h5py.File(out) as f:
        return f["buckling/load_factor"][0], wall


def convergence_tables(binary, folder):
    """Markdown tables: the bend's tip error per load step and the buckling load's error, per
    mesh and bending form, against the Richardson-extrapolated 64/32-element angle solution
    (bend) and the closed form (buckling, shear-rigid)."""
    meshes = (8, 16, 32, 64)
    rows = ["## 45-degree bend: largest tip-coordinate error per load step",
            "", "Reference: 64 and 32 beams (angle form), Richardson-extrapolated "
            "(h^2). Tip displacement at 600: about 60.", "",
            "| form | beams | F = 150 | 300 | 450 | 600 | wall [s] |", "| --- | --- | --- | --- | --- | --- | --- |"]
    tips = {(form, n): bend_tips(binary, folder, n, form) for form in ("angle", "sine")
            for n in meshes}
    ref = tips["angle", 64][0] + (tips["angle", 64][0] - tips["angle", 32][0]) / 3
    for (form, n), (tip, wall) in tips.items():
        err = np.abs(tip - ref).max(axis=1)
        rows.append(f"| {form} | {n} | " + " | ".join(f"{e:.2e}" for e in err)
                    + f" | {wall:.2f} |")
    rows += ["", "Reference tip positions (x, y, z):", ""]
    for k, f in enumerate((150, 300, 450, 600)):
        rows.append(f"- F = {f}: ({ref[k, 0]:.4f}, {ref[k, 1]:.4f}, {ref[k, 2]:.4f})")
    p_cr = ltb_critical_force()
    rows += ["", "## Lateral-torsional buckling of the narrow cantilever", "",
             f"Closed form (gamma = {ltb_gamma():.6f}): P = {p_cr:.4f} N.", "",
             "| form | beams | P shear-flexible [N] | P shear-rigid [N] | rel. error (rigid) | wall [s] |",
             "| --- | --- | --- | --- | --- | --- |"]
    for form in ("angle", "sine"):
        for n in meshes:
            p, wall = ltb_load(binary, folder, n, form)
            pr, _ = ltb_load(binary, folder, n, form, shear_rigid=True)
            rows.append(f"| {form} | {n} | {p:.4f} | {pr:.4f} | {(pr - p_cr) / p_cr:.2e} | "
                        f"{wall:.2f} |")
    return "\n".join(rows) + "\n"


def elbow_scaling(binary, folder, per_leg=(5, 10, 20, 40, 80)):
    """Markdown table: wall time per step and per evaluation of the elbow (fixed-step
    generalized-alpha, dt 1 ms, 1 s) against the number of beams: the cost per step of a
    spatial model grows linearly with the mesh."""
    text = (ROOT / "input" / "right_angle_cantilever.nml").read_text().replace(
        "&dynamic t_end = 30.0, output_dt = 0.05, rtol = 1.0e-5, atol = 1.0e-6 /",
        "&dynamic t_end = 1.0, output_dt = 0.05, integrator = 'galpha', dt = 1.0e-3 /")
    rows = ["## Cost per step of a spatial model (the elbow, 1 s at dt = 1 ms)", "",
            "| beams | steps | evaluations | wall [s] | per step [ms] | per evaluation and beam [us] |",
            "| --- | --- | --- | --- | --- | --- |"]
    for n in per_leg:
        out, _ = run(binary, folder, f"elbow_{n}", text.replace("n_elements = 10",
                                                                 f"n_elements = {n}"))
        with h5py.File(out) as f:
            wall, steps = f.attrs["wall_time_s"], int(f.attrs["n_steps"])
            evals = int(f.attrs["n_model_evals"])
        rows.append(f"| {2 * n} | {steps} | {evals} | {wall:.2f} | {1e3 * wall / steps:.3f} | "
                    f"{1e6 * wall / evals / (2 * n):.1f} |")
    return "\n".join(rows) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--bin", default=str(ROOT / "build" / "bin" / "flexmor"))
    parser.add_argument("--out", default=str(ROOT / "docs" / "bench" / "spatial_convergence.md"))
    args = parser.parse_args()
    commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True).stdout.strip()
    with tempfile.TemporaryDirectory() as folder:
        tables = convergence_tables(args.bin, folder) + "\n" + elbow_scaling(args.bin, folder)
    head = ("# Spatial beams: convergence of the angle and sine forms\n\n"
            f"`python3 scripts/spatial_examples.py` on {platform.node()} "
            f"({platform.processor() or platform.machine()}), commit {commit}.\n\n")
    Path(args.out).write_text(head + tables)
    print(head + tables)


if __name__ == "__main__":
    main()
