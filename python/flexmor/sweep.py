"""Reading flexmor-sweep result files (HDF5), shared by the sweep commands.

Layout read here (see docs/sweep.md, "Result file"), every dataset of shape (n_cases,):

- ``/cases/parameters/<name>``: float64, the value of each swept parameter per case
- ``/cases/status``: int32, -1 not run yet, 0 ok, else the flexmor exit code of the failure
- ``/cases/message``: fixed-length bytes (1024; 256 from flexmor 0.6), error text of a failed case
- ``/cases/wall_time_s``: float64, solve time (NaN while not run)
- ``/cases/rank``: int32, MPI rank that ran the case (-1 while not run)
- ``/cases/metrics/<name>``: float64 scalar results (NaN where not run, failed or not applicable)
- root attributes: ``mode``, ``n_cases``, ``node``, ``title``, ``base_scene``, ...

Usage::

    import flexmor
    sweep = flexmor.read_sweep("sweep.h5")
    sweep.parameters["reduction.n_modes"], sweep.metric("max_tip_deflection"), sweep.ok

Case numbers: the arrays are indexed from 0; the commands print case *numbers* from 1
(:func:`case_number`, index + 1), as flexmor-sweep's own progress lines ('sweep: case 3
failed: ...') do, so a number on the terminal and in a summary name the same case.

Every failure (missing file, not an HDF5 file, not a sweep file, inconsistent shapes, a
parameter or metric the file does not have) raises :class:`SweepFileError` with a one-line
message naming the file, so a command can print it and exit without a traceback.
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable

import h5py
import numpy as np

from flexmor.results import open_h5, to_python

__all__ = [
    "METRIC_UNITS", "STATUS_NAMES", "Sweep", "SweepFileError", "case_number", "fmt_param",
    "fmt_value", "load_sweep", "matches", "parse_where", "read_sweep", "skip_note", "status_text",
    "value_list", "varying", "where_mask",
]

#: flexmor exit codes recorded in /cases/status (docs/sweep.md).
STATUS_NAMES = {-1: "not run", 0: "ok", 1: "input", 2: "model", 3: "numerical",
                4: "file system", 5: "internal"}

#: Units of the metrics that have one (axis and colour bar labels).
METRIC_UNITS = {"max_tip_deflection": "m", "residual_vibration": "m", "error_estimate": "m",
                "wall_time_s": "s"}

WALL_TIME = "wall_time_s"


class SweepFileError(Exception):
    """A sweep file is missing, unreadable, not a sweep file, or lacks what was asked for."""


@dataclass
class Sweep:
    """The contents of a sweep result file. Arrays have shape (n_cases,)."""

    path: str
    parameters: dict[str, np.ndarray]
    status: np.ndarray
    messages: list[str]
    wall_time_s: np.ndarray
    rank: np.ndarray
    metrics: dict[str, np.ndarray]
    attrs: dict[str, Any] = field(default_factory=dict)

    @property
    def n_cases(self) -> int:
        return int(self.status.shape[0])

    @property
    def parameter_names(self) -> list[str]:
        return list(self.parameters)

    @property
    def metric_names(self) -> list[str]:
        return list(self.metrics)

    @property
    def ok(self) -> np.ndarray:
        """Cases that ran without error."""
        return self.status == 0

    @property
    def failed(self) -> np.ndarray:
        """Cases that ran and failed (status = flexmor exit code > 0)."""
        return self.status > 0

    @property
    def not_run(self) -> np.ndarray:
        """Cases not run yet (status -1; any negative status counts as not run)."""
        return self.status < 0

    def parameter(self, name: str) -> np.ndarray:
        """Values of parameter ``name``; :class:`SweepFileError` listing the available names."""
        if name not in self.parameters:
            raise SweepFileError(
                f"{self.path}: no parameter '{name}'; available: {_names(self.parameters)}")
        return self.parameters[name]

    def metric(self, name: str) -> np.ndarray:
        """Values of metric ``name`` (also ``wall_time_s``); :class:`SweepFileError` listing the
        available names."""
        if name in self.metrics:
            return self.metrics[name]
        if name == WALL_TIME:
            return self.wall_time_s
        raise SweepFileError(
            f"{self.path}: no metric '{name}'; available: "
            f"{_names([*self.metrics, WALL_TIME])}")

    def case_file(self, index: int) -> Path:
        """The result file of the case at array index ``index`` (from 0), written with
        ``&sweep case_files = .true.`` into the folder beside the sweep file (read it with
        :func:`flexmor.read_result`). :class:`SweepFileError` when the sweep wrote none, the
        index is out of range, or that case has not run or failed (it has no file)."""
        folder = self.attrs.get("case_files", "")
        if not folder:
            raise SweepFileError(f"{self.path}: the sweep wrote no result file per case "
                                 f"(&sweep case_files = .true. does)")
        if not 0 <= index < self.n_cases:
            raise SweepFileError(f"{self.path}: no case at index {index} (0 to "
                                 f"{self.n_cases - 1})")
        if self.status[index] != 0:
            raise SweepFileError(f"{self.path}: case {case_number(index)} has no result file "
                                 f"(status: {status_text(int(self.status[index]))})")
        width = len(str(self.n_cases))
        return Path(self.path).parent / folder / f"case_{case_number(index):0{width}d}.h5"


def _names(names: Iterable[str]) -> str:
    listed = ", ".join(names)
    return listed if listed else "none"


def case_number(index: int) -> int:
    """The printed number of the case at array index ``index`` (from 1, as flexmor-sweep)."""
    return int(index) + 1


def status_text(code: int) -> str:
    """'ok', 'not run', or the failure kind with its code: 'numerical (3)'."""
    code = int(code)
    if code == 0:
        return "ok"
    if code < 0:
        return "not run"
    return f"{STATUS_NAMES.get(code, 'error')} ({code})"


def fmt_value(value: float) -> str:
    """Compact form of a parameter or metric value: integers as integers, else 6 digits."""
    value = float(value)
    if math.isnan(value):
        return "nan"
    if value.is_integer() and abs(value) < 1e15:
        return str(int(value))
    return f"{value:.6g}"


def fmt_param(name: str, value: float) -> str:
    """:func:`fmt_value`, except that ``n_modes`` 0 (a full, unreduced run) reads 'full'."""
    if name.rsplit(".", 1)[-1] == "n_modes" and value == 0:
        return "full"
    return fmt_value(value)


def value_list(values: np.ndarray, limit: int = 8) -> str:
    """The distinct values, sorted, as text for --where: '0.1, 0.2, 0.5'; past ``limit`` the
    first and last few and the count."""
    distinct = np.unique(values[np.isfinite(values)])
    texts = [fmt_value(v) for v in distinct]
    if len(texts) <= limit:
        return ", ".join(texts)
    return f"{', '.join(texts[:3])}, ..., {', '.join(texts[-2:])} ({len(texts)} values)"


def _decode(value: Any) -> str:
    if isinstance(value, bytes):
        value = value.decode("utf-8", errors="replace")
    return str(value).rstrip("\x00 ")


def _dataset(path: str, f: h5py.File, name: str, n: int | None) -> np.ndarray:
    obj = f.get(name)
    if not isinstance(obj, h5py.Dataset):
        raise SweepFileError(f"{path}: not a sweep file (no dataset /{name})")
    data = obj[...]
    if data.ndim != 1 or (n is not None and data.shape[0] != n):
        expected = "(n_cases,)" if n is None else f"({n},) like /cases/status"
        raise SweepFileError(f"{path}: /{name} has shape {data.shape}, expected {expected}")
    return data


def _float_group(path: str, f: h5py.File, name: str, n: int) -> dict[str, np.ndarray]:
    group = f.get(name)
    if not isinstance(group, h5py.Group):
        return {}
    return {key: np.asarray(_dataset(path, f, f"{name}/{key}", n), dtype=float)
            for key, obj in group.items() if isinstance(obj, h5py.Dataset)}


def load_sweep(path: str | os.PathLike) -> Sweep:
    """Read a sweep result file. Raises :class:`SweepFileError` naming the file when it is
    missing, not HDF5, not a sweep file (no ``/cases`` with ``status`` and parameters) or its
    datasets disagree in length."""
    path = os.fspath(path)
    with open_h5(path, SweepFileError, "sweep file") as f:
        if not isinstance(f.get("cases"), h5py.Group):
            hint = " (a single-run result file?)" if "time" in f else ""
            raise SweepFileError(f"{path}: not a sweep file (no group /cases){hint}")
        status = np.asarray(_dataset(path, f, "cases/status", None), dtype=np.int64)
        n = status.shape[0]
        parameters = _float_group(path, f, "cases/parameters", n)
        if not parameters:
            raise SweepFileError(f"{path}: not a sweep file (no datasets in /cases/parameters)")
        messages = [_decode(m) for m in _dataset(path, f, "cases/message", n).tolist()]
        wall = np.asarray(_dataset(path, f, "cases/wall_time_s", n), dtype=float)
        rank = np.asarray(_dataset(path, f, "cases/rank", n), dtype=np.int64)
        metrics = _float_group(path, f, "cases/metrics", n)
        attrs = {name: to_python(value) for name, value in f.attrs.items()}
    return Sweep(path, parameters, status, messages, wall, rank, metrics, attrs)


#: The package-level name (``flexmor.read_sweep``), as ``flexmor.read_result``.
read_sweep = load_sweep


def parse_where(text: str) -> tuple[str, float]:
    """``'PARAM=VALUE'`` -> ``(PARAM, VALUE)``; ValueError with a one-line message otherwise."""
    name, sep, value = text.partition("=")
    name, value = name.strip(), value.strip()
    if not sep or not name or not value:
        raise ValueError(f"--where '{text}': expected PARAM=VALUE")
    try:
        return name, float(value)
    except ValueError:
        raise ValueError(f"--where '{text}': '{value}' is not a number") from None


def matches(values: np.ndarray, value: float) -> np.ndarray:
    """Cases whose value is ``value``: equal up to rtol 1e-9, or, where none is, equal in the
    printed 6-digit form (so that 1.5708, as the scripts print pi/2, selects pi/2)."""
    hit = np.isclose(values, value, rtol=1e-9, atol=1e-300)
    if not hit.any():
        printed = fmt_value(value)
        hit = np.array([fmt_value(v) == printed for v in values], dtype=bool)
    return hit


def where_mask(sweep: Sweep, where: Iterable[tuple[str, float]]) -> np.ndarray:
    """Cases matching every ``(name, value)`` filter. A value no case has is an error that
    lists the parameter's values, as is one that matches several distinct values."""
    mask = np.ones(sweep.n_cases, dtype=bool)
    for name, value in where:
        values = sweep.parameter(name)
        hit = matches(values, value)
        if not hit.any():
            listed = value_list(values)
            raise SweepFileError(
                f"{sweep.path}: no case has {name} = {fmt_value(value)}; values: {listed}")
        if np.unique(values[hit]).size > 1:
            raise SweepFileError(
                f"{sweep.path}: {name} = {fmt_value(value)} matches several values "
                f"({', '.join(repr(float(v)) for v in np.unique(values[hit]))}); give more digits")
        mask &= hit
    return mask


def varying(sweep: Sweep, mask: np.ndarray, exclude: Iterable[str] = ()) -> list[str]:
    """Parameters (except ``exclude``) that take more than one value among the cases in
    ``mask``."""
    skip = set(exclude)
    return [name for name, values in sweep.parameters.items()
            if name not in skip and np.unique(values[mask]).size > 1]


def _case_list(indices: np.ndarray, limit: int = 8) -> str:
    shown = ", ".join(str(case_number(i)) for i in indices[:limit])
    return shown + (", ..." if indices.size > limit else "")


def skip_note(sweep: Sweep, mask: np.ndarray, values: np.ndarray, what: str) -> str:
    """'' or a one-line note on the cases in ``mask`` left out because they failed, have not run
    or have no finite ``values`` (``what`` names those values), with their indices."""
    parts = []
    for label, cases in (("failed", mask & sweep.failed), ("not run", mask & sweep.not_run),
                         (f"ok but no finite {what}", mask & sweep.ok & ~np.isfinite(values))):
        idx = np.flatnonzero(cases)
        if idx.size:
            parts.append(f"{idx.size} {label} (case{'s' if idx.size > 1 else ''} "
                         f"{_case_list(idx)})")
    return "skipped " + "; ".join(parts) if parts else ""
