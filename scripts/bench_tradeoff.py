#!/usr/bin/env python3
"""Speed/accuracy trade-off of full and reduced models on the two-link benchmark.

Runs scene variants of ``input/two_link.nml`` (3 elements per link, t_end 0.7 s), one after
the other, and measures for each the solve time (root attribute ``wall_time_s``, median of
--repeats runs; min and max kept) and the tip error: the largest distance over time between
the node 'tip' and that of a reference solution (full model, BDF, rtol 1e-10, atol 1e-12;
its convergence is checked against rtol 1e-9).

Cases:

- full model, BDF, rtol 1e-3 .. 1e-8 (atol = rtol * 1e-2); generalized-alpha, dt 1e-3 ..
  1e-4 s (rho_inf 0.8);
- reduced model, k = 1..4 modes, basis fixed ('none') or updated ('mac' check every
  --update-interval s against --mac-threshold), static correction off/on, integrated with BDF
  (rtol 1e-6, atol 1e-8, as input/two_link.nml) or explicit Runge-Kutta ('erk', order 5,
  same tolerances); plus k = 2, fixed basis, BDF rtol 1e-3 (step counts against the full
  model at rtol 1e-3).

The variants are made by text substitution of the base scene: its ``&dynamic`` group is
replaced, a ``&reduction`` group added, ``&modal`` (not needed) removed; output_dt stays
1e-3 s so that every run has the reference's time grid.

Usage (from anywhere, with the flexmor Python package installed: scripts/setup.sh or
`pip install .`; --bin defaults to build/bin/flexmor in the repository):

    python3 scripts/bench_tradeoff.py [--bin BIN] [--repeats 3] [--out-dir bench_out] \\
        [--quick] [--update-interval 0.01] [--mac-threshold 0.999] [--timeout 900]

Writes into --out-dir: ``tradeoff.csv`` (every column), ``tradeoff.md`` (table sorted by group
then time, with a header naming the command, date, machine, version and commit) and
``tradeoff.png`` (tip error against solve time, log-log). --quick runs a small subset
(reference at rtol 1e-8, t_end 0.2 s, one repeat) for the tests.

A run that fails (non-zero exit) is recorded with the last line of its stderr and the
benchmark goes on; the exit status is then 1. Bad arguments or a missing binary: one-line
message and exit status 2.
"""
from __future__ import annotations

import argparse
import math
import os
import platform
import re
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from datetime import datetime
from pathlib import Path
from typing import Any, Sequence

import h5py
import numpy as np

from flexmor.bench import command_line, cpu_model, git_commit, last_line, write_csv
from flexmor.results import ResultFileError, load_node_path, run_attributes

PROG = "bench_tradeoff.py"
ROOT = Path(__file__).resolve().parents[1]
BASE_SCENE = ROOT / "input" / "two_link.nml"
DEFAULT_BIN = ROOT / "build" / "bin" / "flexmor"
TIP = "tip"
OUTPUT_DT = 1.0e-3

# Table and plot order of the groups.
GROUPS = ("reference", "full BDF", "full galpha", "reduced fixed", "reduced updated")

CSV_COLUMNS = (
    "name", "group", "integrator", "rtol", "atol", "dt", "rho_inf", "erk_order", "n_modes",
    "update", "update_interval", "mac_threshold", "static_correction", "t_end", "repeats",
    "time_median_s", "time_min_s", "time_max_s", "n_steps", "n_rhs_evals", "n_model_evals",
    "tip_error_m", "residual_max", "error_estimate_max_m", "n_updates", "status", "message",
)


class UserError(Exception):
    """A problem the user can fix (bad argument, missing binary): one line, exit status 2."""


# --- scene text -------------------------------------------------------------------------------


def fmt_num(value: float) -> str:
    """Compact scientific form for names and labels: 1e-3, 2.5e-4, 1e-10."""
    mantissa, exponent = f"{value:.3e}".split("e")
    mantissa = mantissa.rstrip("0").rstrip(".")
    return f"{mantissa}e{int(exponent)}"


def nml_value(value: Any) -> str:
    """A Python value as a namelist value: .true./.false., 'string', integer, shortest float."""
    if isinstance(value, bool):
        return ".true." if value else ".false."
    if isinstance(value, str):
        return "'" + value.replace("'", "''") + "'"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return repr(value)
    raise TypeError(f"no namelist form for {value!r}")


def group_span(text: str, group: str) -> tuple[int, int] | None:
    """``(start, end)`` of the namelist group ``&group ... /`` in ``text`` (end after the ``/``),
    or None. The group must start a line (after blanks); the closing ``/`` is the first one
    outside quotes and ``!`` comments, so a group may span lines."""
    match = re.search(rf"^[ \t]*&{re.escape(group)}\b", text, flags=re.MULTILINE | re.IGNORECASE)
    if match is None:
        return None
    quote = ""
    in_comment = False
    for i in range(match.end(), len(text)):
        c = text[i]
        if in_comment:
            in_comment = c != "\n"
        elif quote:
            if c == quote:
                quote = ""
        elif c in "'\"":
            quote = c
        elif c == "!":
            in_comment = True
        elif c == "/":
            return match.start(), i + 1
    raise ValueError(f"namelist group &{group} has no closing '/'")


def group_body(text: str, group: str) -> str | None:
    """The text between ``&group`` and its closing ``/`` (None if there is no such group)."""
    span = group_span(text, group)
    if span is None:
        return None
    inner = text[span[0]:span[1] - 1]
    return re.sub(rf"^[ \t]*&{re.escape(group)}\b", "", inner, flags=re.IGNORECASE)


def split_outside_quotes(text: str, sep: str = ",") -> list[str]:
    """``text`` split at ``sep`` where it is not inside '...' or "..."."""
    parts, current, quote = [], [], ""
    for c in text:
        if quote:
            quote = "" if c == quote else quote
        elif c in "'\"":
            quote = c
        elif c == sep:
            parts.append("".join(current))
            current = []
            continue
        current.append(c)
    parts.append("".join(current))
    return parts


def parse_group(text: str, group: str) -> dict[str, str]:
    """Variables of a group as ``{name (lower case): raw value text}``, comments dropped; a
    list value keeps its commas (``'tip', 'elbow'``). Empty if there is no such group."""
    body = group_body(text, group)
    if body is None:
        return {}
    body = " ".join(split_outside_quotes(line, "!")[0] for line in body.splitlines())
    values: dict[str, str] = {}
    name = None
    for part in split_outside_quotes(body):
        match = re.fullmatch(r"\s*([A-Za-z_]\w*)\s*=(.*)", part, flags=re.DOTALL)
        if match:
            name = match.group(1).lower()
            values[name] = match.group(2).strip()
        elif name is not None and part.strip():
            values[name] += ", " + part.strip()
    return values


def group_line(group: str, values: dict[str, Any]) -> str:
    """``&group a = 1, b = 'x' /``; values already given as text (str from parse_group) must be
    wrapped in :class:`Raw`."""
    items = ", ".join(f"{k} = {v if isinstance(v, Raw) else nml_value(v)}"
                      for k, v in values.items())
    return f"&{group} {items} /" if items else f"&{group} /"


class Raw(str):
    """A namelist value that is already text (written as is)."""


def remove_group(text: str, group: str) -> str:
    """``text`` without the group (and the rest of its line if that is blank)."""
    span = group_span(text, group)
    if span is None:
        return text
    start, end = span
    rest = text[end:]
    newline = rest.find("\n")
    if newline >= 0 and not rest[:newline].strip():
        end += newline + 1
    return text[:start] + text[end:]


def make_scene(base: str, dynamic: dict[str, Any], reduction: dict[str, Any] | None) -> str:
    """Scene text from the base scene: its &dynamic group replaced by one with the base's
    t_end and output_dt (``dynamic`` may override them) and the variables in ``dynamic``;
    &modal and any &reduction removed; a &reduction group from ``reduction`` (if given) put
    just before &dynamic."""
    base_dyn = parse_group(base, "dynamic")
    if not base_dyn:
        raise ValueError("the base scene has no &dynamic group")
    values: dict[str, Any] = {k: Raw(base_dyn[k]) for k in ("t_end", "output_dt") if k in base_dyn}
    values.update(dynamic)
    text = remove_group(remove_group(base, "modal"), "reduction")
    start, end = group_span(text, "dynamic")  # type: ignore[misc]
    new = group_line("dynamic", values)
    if reduction is not None:
        new = group_line("reduction", reduction) + "\n" + new
    return text[:start] + new + text[end:]


# --- results ----------------------------------------------------------------------------------


def tip_error(t_ref: np.ndarray, xyz_ref: np.ndarray, t: np.ndarray, xyz: np.ndarray) -> float:
    """Largest Euclidean distance over time between two paths on the same time grid."""
    if t.shape != t_ref.shape or not np.allclose(t, t_ref, rtol=0.0, atol=1e-9):
        raise ValueError(f"time grids differ ({t.size} and {t_ref.size} samples)")
    if xyz.shape != xyz_ref.shape:
        raise ValueError(f"position shapes differ ({xyz.shape} and {xyz_ref.shape})")
    return float(np.max(np.linalg.norm(xyz - xyz_ref, axis=1)))


def reduction_attributes(path: Path) -> dict[str, Any]:
    """residual_max, error_estimate_max, n_updates of /reduction (empty for full runs)."""
    with h5py.File(path, "r") as f:
        group = f.get("reduction")
        if not isinstance(group, h5py.Group):
            return {}
        return {k: group.attrs[k].item() for k in ("residual_max", "error_estimate_max",
                                                     "n_updates") if k in group.attrs}


# --- cases ------------------------------------------------------------------------------------


@dataclass
class Case:
    """One scene variant and how often to time it."""

    name: str
    group: str
    label: str  # compact plot label
    dynamic: dict[str, Any]
    reduction: dict[str, Any] | None = None
    repeats: int = 1


@dataclass
class Outcome:
    """What the runs of one case gave."""

    case: Case
    status: str = "ok"
    message: str = ""
    times: list[float] = field(default_factory=list)
    attrs: dict[str, Any] = field(default_factory=dict)
    red: dict[str, Any] = field(default_factory=dict)
    tip_error: float = math.nan
    path: Path | None = None


def bdf(rtol: float, atol: float | None = None) -> dict[str, Any]:
    return {"integrator": "bdf", "rtol": rtol, "atol": rtol * 1e-2 if atol is None else atol}


def galpha(dt: float, rho_inf: float = 0.8) -> dict[str, Any]:
    return {"integrator": "galpha", "dt": dt, "rho_inf": rho_inf}


def erk(rtol: float = 1e-6, atol: float = 1e-8, order: int = 5) -> dict[str, Any]:
    return {"integrator": "erk", "rtol": rtol, "atol": atol, "erk_order": order}


def reduced_case(k: int, updated: bool, static: bool, dyn: dict[str, Any], repeats: int,
                 interval: float, threshold: float, suffix: str = "") -> Case:
    red: dict[str, Any] = {"n_modes": k, "static_correction": static}
    if updated:
        red.update(update="mac", update_interval=interval, mac_threshold=threshold)
    else:
        red["update"] = "none"
    integ = dyn["integrator"] + (str(dyn["erk_order"]) if dyn["integrator"] == "erk" else "")
    name = f"red-k{k}-{'mac' if updated else 'fixed'}{'-sc' if static else ''}-{integ}{suffix}"
    group = "reduced updated" if updated else "reduced fixed"
    label = f"k{k}" + (f",{fmt_num(dyn['rtol'])}" if suffix else "")
    return Case(name, group, label, dyn, red, repeats=repeats)


def reference_cases(quick: bool) -> tuple[Case, Case]:
    """The reference and the run one decade looser that checks its convergence."""
    rtol = 1e-8 if quick else 1e-10
    ref = Case(f"ref-bdf-rtol{fmt_num(rtol)}", "reference", "ref", bdf(rtol))
    check = Case(f"ref-check-bdf-rtol{fmt_num(rtol * 10)}", "reference", "check", bdf(rtol * 10))
    return ref, check


def build_cases(quick: bool, repeats: int, interval: float, threshold: float) -> list[Case]:
    """The measured cases (without the reference pair)."""
    if quick:
        return [Case("full-bdf-rtol1e-3", "full BDF", "1e-3", bdf(1e-3), repeats=repeats),
                *(reduced_case(k, False, False, bdf(1e-6, 1e-8), repeats, interval, threshold)
                  for k in (1, 2))]
    cases = [Case(f"full-bdf-rtol{fmt_num(r)}", "full BDF", fmt_num(r), bdf(r), repeats=repeats)
             for r in (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8)]
    cases += [Case(f"full-galpha-dt{fmt_num(dt)}", "full galpha", fmt_num(dt), galpha(dt),
                   repeats=repeats) for dt in (1e-3, 5e-4, 2.5e-4, 1e-4)]
    for dyn in (bdf(1e-6, 1e-8), erk(1e-6, 1e-8, 5)):
        for updated in (False, True):
            for static in (False, True):
                cases += [reduced_case(k, updated, static, dyn, repeats, interval, threshold)
                          for k in (1, 2, 3, 4)]
    cases.append(reduced_case(2, False, False, bdf(1e-3), repeats, interval, threshold,
                              suffix="-rtol1e-3"))
    return cases


# --- running ----------------------------------------------------------------------------------


def run_once(binary: Path, scene: Path, out: Path, timeout: float) -> str:
    """Run flexmor once; '' on success, else a one-line reason."""
    out.unlink(missing_ok=True)
    env = dict(os.environ)
    env.setdefault("OPENBLAS_NUM_THREADS", "1")
    env.setdefault("OMP_NUM_THREADS", "1")
    try:
        proc = subprocess.run([str(binary), str(scene), "-o", str(out), "-q"], capture_output=True,
                              text=True, timeout=timeout, env=env, cwd=scene.parent)
    except subprocess.TimeoutExpired:
        return f"timed out after {timeout:g} s"
    except OSError as exc:
        return f"cannot run {binary}: {exc}"
    if proc.returncode != 0:
        return f"exit {proc.returncode}: {last_line(proc.stderr) or last_line(proc.stdout)}"
    if not out.exists():
        return "exit 0 but no result file"
    return ""


def run_case(case: Case, base: str, binary: Path, work: Path, timeout: float,
             t_end: float | None) -> Outcome:
    """Write the scene, run it ``case.repeats`` times, read times and counters."""
    outcome = Outcome(case)
    dynamic = dict(case.dynamic)
    if t_end is not None:
        dynamic["t_end"] = t_end
    dynamic["output_dt"] = OUTPUT_DT
    scene = work / f"{case.name}.nml"
    scene.write_text(make_scene(base, dynamic, case.reduction))
    out = work / f"{case.name}.h5"
    for _ in range(case.repeats):
        reason = run_once(binary, scene, out, timeout)
        if reason:
            outcome.status, outcome.message = "failed", reason
            return outcome
        try:
            attrs = run_attributes(out)
        except ResultFileError as exc:
            outcome.status, outcome.message = "failed", str(exc)
            return outcome
        outcome.times.append(float(attrs["wall_time_s"]))
        outcome.attrs = attrs
    outcome.red = reduction_attributes(out)
    outcome.path = out
    return outcome


def add_error(outcome: Outcome, reference: tuple[np.ndarray, np.ndarray] | None) -> None:
    """Tip error against the reference path (NaN when either is missing)."""
    if outcome.status != "ok" or outcome.path is None or reference is None:
        return
    try:
        t, xyz = load_node_path(outcome.path, TIP)
        outcome.tip_error = tip_error(reference[0], reference[1], t, xyz)
    except (ResultFileError, ValueError) as exc:
        outcome.status, outcome.message = "failed", f"tip error: {exc}"


def progress(i: int, n: int, outcome: Outcome) -> str:
    head = f"[{i:2d}/{n}] {outcome.case.name:<28s}"
    if outcome.status != "ok":
        return f"{head} FAILED: {outcome.message}"
    med = statistics.median(outcome.times)
    err = f"{outcome.tip_error:.2e} m" if math.isfinite(outcome.tip_error) else "-"
    return (f"{head} {med:8.3f} s (median of {len(outcome.times)}), "
            f"{outcome.attrs.get('n_steps', '?')} steps, tip error {err}")


# --- output -----------------------------------------------------------------------------------


def csv_row(outcome: Outcome, t_end: float) -> dict[str, Any]:
    case, dyn, red = outcome.case, outcome.case.dynamic, outcome.case.reduction or {}
    times = outcome.times if outcome.status == "ok" else []
    row: dict[str, Any] = {
        "name": case.name, "group": case.group, "integrator": dyn["integrator"],
        "rtol": dyn.get("rtol", ""), "atol": dyn.get("atol", ""), "dt": dyn.get("dt", ""),
        "rho_inf": dyn.get("rho_inf", ""), "erk_order": dyn.get("erk_order", ""),
        "n_modes": red.get("n_modes", ""), "update": red.get("update", ""),
        "update_interval": red.get("update_interval", ""),
        "mac_threshold": red.get("mac_threshold", ""),
        "static_correction": ("yes" if red.get("static_correction") else "no") if red else "",
        "t_end": t_end, "repeats": case.repeats,
        "time_median_s": statistics.median(times) if times else "",
        "time_min_s": min(times) if times else "", "time_max_s": max(times) if times else "",
        "tip_error_m": outcome.tip_error if math.isfinite(outcome.tip_error) else "",
        "residual_max": outcome.red.get("residual_max", ""),
        "error_estimate_max_m": outcome.red.get("error_estimate_max", ""),
        "n_updates": outcome.red.get("n_updates", ""),
        "status": outcome.status, "message": outcome.message,
    }
    for key in ("n_steps", "n_rhs_evals", "n_model_evals"):
        row[key] = outcome.attrs.get(key, "") if outcome.status == "ok" else ""
    return row


def sort_key(row: dict[str, Any]) -> tuple[int, int, float]:
    group = GROUPS.index(row["group"]) if row["group"] in GROUPS else len(GROUPS)
    ok = row["status"] == "ok" and row["time_median_s"] != ""
    return group, 0 if ok else 1, float(row["time_median_s"]) if ok else 0.0


def _e(value: Any, digits: int = 2) -> str:
    return "–" if value == "" or value is None else f"{float(value):.{digits}e}"


def settings_text(row: dict[str, Any]) -> str:
    if row["integrator"] == "galpha":
        return f"dt {fmt_num(row['dt'])}, ρ∞ {row['rho_inf']}"
    text = f"rtol {fmt_num(row['rtol'])}, atol {fmt_num(row['atol'])}"
    return text + (f", order {row['erk_order']}" if row["integrator"] == "erk" else "")


def basis_text(row: dict[str, Any]) -> str:
    if row["update"] in ("", None):
        return "–"
    if row["update"] == "none":
        return "fixed"
    return f"{row['update']} {row['update_interval']:g} s / {row['mac_threshold']:g}"


def table_line(row: dict[str, Any], baseline: float | None) -> str:
    ok = row["status"] == "ok"
    time_text = (f"{row['time_median_s']:.3f} ({row['time_min_s']:.3f}–{row['time_max_s']:.3f})"
                 if ok else "–")
    speedup = (f"{baseline / row['time_median_s']:.1f}"
               if ok and baseline and row["time_median_s"] > 0 else "–")
    status = "ok" if ok else f"failed: {row['message']}".replace("|", "\\|")
    cells = [f"`{row['name']}`", row["group"], row["integrator"], settings_text(row),
             str(row["n_modes"]) if row["n_modes"] != "" else "full", basis_text(row),
             row["static_correction"] or "–", time_text, speedup, str(row["n_steps"] or "–"),
             str(row["n_model_evals"] or "–"), _e(row["tip_error_m"]),
             _e(row["error_estimate_max_m"]), _e(row["residual_max"]),
             str(row["n_updates"]) if row["n_updates"] != "" else "–", status]
    return "| " + " | ".join(cells) + " |"


def core_count() -> str:
    total = os.cpu_count() or 0
    try:
        usable = len(os.sched_getaffinity(0))
    except AttributeError:
        usable = total
    return f"{total}" if usable == total else f"{total} ({usable} usable by this process)"


def baseline_time(rows: list[dict[str, Any]]) -> tuple[str, float] | None:
    """The full BDF case at the base scene's own tolerance (rtol 1e-6), for the speed-up."""
    for row in rows:
        if row["name"] == "full-bdf-rtol1e-6" and row["status"] == "ok":
            return row["name"], float(row["time_median_s"])
    return None


def write_markdown(rows: list[dict[str, Any]], path: Path, header: dict[str, str]) -> None:
    base = baseline_time(rows)
    lines = ["# Speed/accuracy trade-off, two-link benchmark", ""]
    lines += [f"- {key}: {value}" for key, value in header.items()]
    lines += [
        "- Time: median (min–max) over the repeats of the result attribute `wall_time_s` "
        "(solve time, excluding reading the scene and writing the result); the reference pair "
        "is run once.",
        "- Tip error: largest distance over time between node 'tip' and the reference's.",
        "- Speed-up: time of `" + base[0] + "` (input/two_link.nml's own settings) divided by "
        "the case's time." if base else "- Speed-up: – (no full BDF rtol 1e-6 case in this run).",
        "- est. error, residual, updates: `/reduction` attributes error_estimate_max [m], "
        "residual_max and n_updates of reduced runs.",
        "",
        "| case | group | integrator | settings | k | basis | static corr. | time [s] | speed-up "
        "| steps | model evals | tip error [m] | est. error [m] | residual max | updates "
        "| status |",
        "|" + " --- |" * 16,
    ]
    lines += [table_line(row, base[1] if base else None) for row in sorted(rows, key=sort_key)]
    path.write_text("\n".join(lines) + "\n")


FAMILY_COLORS = {"full BDF": "C0", "full galpha": "C1", "reduced fixed": "C2",
                 "reduced updated": "C3"}
INTEGRATOR_MARKERS = {"bdf": "o", "galpha": "s", "erk": "^"}


def series_key(row: dict[str, Any]) -> tuple[str, str, str, str]:
    """Points joined by one line: same family, integrator, static correction and tolerance."""
    tol = "" if row["group"].startswith("full") else str(row["rtol"])
    return row["group"], row["integrator"], row["static_correction"], tol


def refinement(row: dict[str, Any]) -> float:
    """Order of the points along a series line: k up, or rtol/dt down."""
    if row["n_modes"] != "":
        return float(row["n_modes"])
    return -float(row["dt"] if row["integrator"] == "galpha" else row["rtol"])


def plot(rows: list[dict[str, Any]], labels: dict[str, str], path: Path, title: str) -> None:
    """Tip error against solve time, log-log; colour = family, marker = integrator, filled
    marker = static correction on (reduced)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    points = [r for r in rows if r["group"] in FAMILY_COLORS and r["status"] == "ok"
              and r["tip_error_m"] != "" and float(r["tip_error_m"]) > 0.0]
    fig, ax = plt.subplots(figsize=(9.0, 6.5))
    series: dict[tuple[str, str, str, str], list[dict[str, Any]]] = {}
    for row in points:
        series.setdefault(series_key(row), []).append(row)
    for (group, integ, static, _), members in series.items():
        members.sort(key=refinement)
        color = FAMILY_COLORS[group]
        filled = not group.startswith("reduced") or static == "yes"
        x = [float(r["time_median_s"]) for r in members]
        y = [float(r["tip_error_m"]) for r in members]
        ax.plot(x, y, ls=":" if integ == "erk" else "-", lw=0.7, color=color, alpha=0.6)
        ax.plot(x, y, ls="none", marker=INTEGRATOR_MARKERS.get(integ, "x"), ms=7, color=color,
                mfc=color if filled else "white", mew=1.3)
        for row in members:
            ax.annotate(labels.get(row["name"], ""), (float(row["time_median_s"]),
                        float(row["tip_error_m"])), textcoords="offset points", xytext=(4, 3),
                        fontsize=6.5, color=color)
    handles = [Line2D([], [], color=c, marker="o", ls="-", label=g) for g, c in
               FAMILY_COLORS.items()]
    handles += [Line2D([], [], color="0.3", marker=m, ls="none", label=lab) for m, lab in
                (("o", "BDF"), ("s", "generalized-alpha"), ("^", "explicit RK (erk, dotted)"))]
    handles += [Line2D([], [], color="0.3", marker="o", mfc="0.3", ls="none",
                       label="reduced, static correction on"),
                Line2D([], [], color="0.3", marker="o", mfc="white", ls="none",
                       label="reduced, static correction off")]
    ax.legend(handles=handles, fontsize=7.5, loc="best")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("solve time, median wall_time_s [s]")
    ax.set_ylabel("tip error, max over time [m]")
    ax.set_title(title + "\nlabels: full BDF rtol, galpha dt [s], reduced k (modes)", fontsize=9)
    ax.grid(True, which="both", lw=0.3)
    fig.tight_layout()
    try:
        fig.savefig(path, dpi=150)
    finally:
        plt.close(fig)


# --- main -------------------------------------------------------------------------------------


def parse_args(argv: Sequence[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        prog=PROG, description="Speed/accuracy trade-off of full and reduced models on the "
                               "two-link benchmark (input/two_link.nml).")
    parser.add_argument("--bin", type=Path, default=DEFAULT_BIN,
                        help=f"flexmor executable (default: {DEFAULT_BIN.relative_to(ROOT)} in "
                             "the repository)")
    parser.add_argument("--repeats", type=int, default=None,
                        help="runs per case, the median time is reported (default 3; 1 with "
                             "--quick)")
    parser.add_argument("--out-dir", type=Path, default=Path("bench_out"),
                        help="folder for tradeoff.csv/.md/.png (default: bench_out)")
    parser.add_argument("--quick", action="store_true",
                        help="small subset (full BDF rtol 1e-3, reduced k = 1, 2 fixed BDF, "
                             "reference rtol 1e-8, t_end 0.2 s, one repeat), for tests")
    parser.add_argument("--update-interval", type=float, default=0.01,
                        help="update_interval [s] of the updated-basis cases (default 0.01)")
    parser.add_argument("--mac-threshold", type=float, default=0.999,
                        help="mac_threshold of the updated-basis cases (default 0.999)")
    parser.add_argument("--timeout", type=float, default=900.0,
                        help="limit per run in seconds; a run past it counts as failed "
                             "(default 900)")
    return parser.parse_args(argv)


def check_args(args: argparse.Namespace) -> None:
    if args.repeats is None:
        args.repeats = 1 if args.quick else 3
    if args.repeats < 1:
        raise UserError("--repeats must be at least 1")
    if not args.update_interval > 0.0:
        raise UserError("--update-interval must be positive")
    if not 0.0 < args.mac_threshold <= 1.0:
        raise UserError("--mac-threshold must be in (0, 1]")
    if not args.timeout > 0.0:
        raise UserError("--timeout must be positive")
    if not args.bin.is_file() or not os.access(args.bin, os.X_OK):
        raise UserError(f"{args.bin}: no flexmor executable there; build it first "
                        "(bash scripts/example.sh, or cmake -S . -B build && cmake --build "
                        "build) or give --bin")
    # The runs start in a scratch folder: a relative --bin must not depend on it.
    args.bin = args.bin.resolve()
    if not BASE_SCENE.is_file():
        raise UserError(f"{BASE_SCENE}: base scene missing")
    if args.out_dir.exists() and not args.out_dir.is_dir():
        raise UserError(f"{args.out_dir}: exists and is not a folder")


def run_all(cases: list[Case], reference: Case, base: str, args: argparse.Namespace,
            work: Path, t_end: float | None) -> list[Outcome]:
    """Reference first, then every case, one at a time; errors against the reference."""
    n = len(cases) + 1
    ref = run_case(reference, base, args.bin, work, args.timeout, t_end)
    ref_path = None
    if ref.status == "ok":
        ref_path = load_node_path(ref.path, TIP)  # type: ignore[arg-type]
        ref.tip_error = 0.0
    print(progress(1, n, ref), flush=True)
    outcomes = [ref]
    for i, case in enumerate(cases, start=2):
        outcome = run_case(case, base, args.bin, work, args.timeout, t_end)
        add_error(outcome, ref_path)
        if outcome.status == "ok" and ref_path is None:
            outcome.message = "no reference: tip error unknown"
        print(progress(i, n, outcome), flush=True)
        outcomes.append(outcome)
    return outcomes


def header_block(command: str, args: argparse.Namespace, outcomes: list[Outcome],
                 t_end: float, elapsed: float) -> dict[str, str]:
    version = next((o.attrs.get("flexmor_version") for o in outcomes if o.attrs), None)
    ref, check = outcomes[0], outcomes[1]
    conv = (f"{check.tip_error:.2e} m (`{check.case.name}` against `{ref.case.name}`)"
            if math.isfinite(check.tip_error) else "unknown (a run failed)")
    return {
        "Command": f"`{command}` (in `{os.getcwd()}`)",
        "Date": datetime.now().astimezone().isoformat(timespec="seconds"),
        "Machine": f"{cpu_model()}, {core_count()} cores, {platform.system()} "
                   f"{platform.release()}; 1-min load average {args.load_start:.2f} at the "
                   f"start, {os.getloadavg()[0]:.2f} at the end (other processes skew times)",
        "flexmor": f"version {version or 'unknown'}, binary `{args.bin}`, git commit "
                   f"{git_commit(ROOT)}",
        "Repeats": f"{args.repeats} per case (cases run one at a time)",
        "Scene": f"input/two_link.nml, t_end {t_end:g} s, output_dt {OUTPUT_DT:g} s"
                 + (" (--quick)" if args.quick else ""),
        "Reference": f"full model, `{ref.case.name}`; convergence check: {conv}",
        "Updated basis": f"update = 'mac', update_interval {args.update_interval:g} s, "
                         f"mac_threshold {args.mac_threshold:g}",
        "Whole benchmark": f"{elapsed:.0f} s",
    }


def main(argv: Sequence[str] | None = None) -> int:
    args = parse_args(argv)
    try:
        check_args(args)
    except UserError as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return 2
    start = time.perf_counter()
    args.load_start = os.getloadavg()[0]
    base = BASE_SCENE.read_text()
    base_t_end = float(parse_group(base, "dynamic")["t_end"].lower().replace("d", "e"))
    t_end = 0.2 if args.quick else None
    reference, check = reference_cases(args.quick)
    cases = [check, *build_cases(args.quick, args.repeats, args.update_interval,
                                 args.mac_threshold)]
    print(f"{PROG}: {len(cases) + 1} cases, {args.repeats} repeat(s) each, binary {args.bin}",
          flush=True)
    with tempfile.TemporaryDirectory(prefix="bench_tradeoff_") as tmp:
        outcomes = run_all(cases, reference, base, args, Path(tmp), t_end)
    elapsed = time.perf_counter() - start
    t_used = t_end if t_end is not None else base_t_end
    rows = [csv_row(o, t_used) for o in outcomes]
    labels = {o.case.name: o.case.label for o in outcomes}
    try:
        args.out_dir.mkdir(parents=True, exist_ok=True)
        write_csv(rows, CSV_COLUMNS, args.out_dir / "tradeoff.csv")
        write_markdown(rows, args.out_dir / "tradeoff.md",
                       header_block(command_line(PROG, argv), args, outcomes, t_used, elapsed))
        plot(rows, labels, args.out_dir / "tradeoff.png",
             f"two-link benchmark, t_end {t_used:g} s: tip error against solve time")
    except OSError as exc:
        print(f"{PROG}: error: cannot write into {args.out_dir}: {exc}", file=sys.stderr)
        return 2
    failed = [o.case.name for o in outcomes if o.status != "ok"]
    ref, check = outcomes[0], outcomes[1]
    if math.isfinite(check.tip_error):
        print(f"reference check: {check.case.name} differs from {ref.case.name} by "
              f"{check.tip_error:.2e} m")
    print(f"wrote {args.out_dir / 'tradeoff.csv'}, tradeoff.md, tradeoff.png "
          f"({elapsed:.0f} s in all)")
    if failed:
        print(f"{PROG}: {len(failed)} case(s) failed: {', '.join(failed)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
