"""Reading flexmor result files (HDF5), shared by the plotting and comparison scripts.

Layout read here (h5py's view, C order; see the README):

- ``/time``: (nt,) seconds
- ``/nodes/<label>/position``: (nt, 3) metres (z = 0 for planar models)
- root attributes: ``flexmor_version``, ``input``, ``status``, ``wall_time_s``, ...

Every failure (missing file, not an HDF5 file, missing node or dataset, wrong shape) raises
:class:`ResultFileError` with a one-line message naming the file, so a script can print it and
exit without a traceback.
"""
from __future__ import annotations

import os
from typing import Any

import h5py
import numpy as np

__all__ = ["ResultFileError", "load_node_path", "node_labels", "run_attributes", "to_python"]


class ResultFileError(Exception):
    """A result file is missing, unreadable or lacks what was asked for."""


def _open(path: str | os.PathLike) -> h5py.File:
    path = os.fspath(path)
    if not os.path.exists(path):
        raise ResultFileError(f"{path}: no such file")
    if os.path.isdir(path):
        raise ResultFileError(f"{path}: is a folder, not a result file")
    try:
        return h5py.File(path, "r")
    except OSError as exc:
        raise ResultFileError(f"{path}: not a readable HDF5 file ({exc})") from None


def _node_labels(f: h5py.File) -> list[str]:
    nodes = f.get("nodes")
    if not isinstance(nodes, h5py.Group):
        return []
    return sorted(
        name
        for name, obj in nodes.items()
        if isinstance(obj, h5py.Group) and isinstance(obj.get("position"), h5py.Dataset)
    )


def node_labels(path: str | os.PathLike) -> list[str]:
    """Sorted labels of the nodes whose position is stored (``/nodes/<label>/position``)."""
    with _open(path) as f:
        return _node_labels(f)


def load_node_path(path: str | os.PathLike, label: str = "tip") -> tuple[np.ndarray, np.ndarray]:
    """Return ``(t, xyz)``: times (nt,) in seconds and positions (nt, 3) in metres of node
    ``label``. Raises :class:`ResultFileError` naming the file and, for a missing label, the
    labels that are available."""
    path = os.fspath(path)
    with _open(path) as f:
        labels = _node_labels(f)
        if label not in labels:
            available = ", ".join(labels) if labels else "none"
            raise ResultFileError(
                f"{path}: no node '{label}' (no dataset /nodes/{label}/position); "
                f"available: {available}"
            )
        if not isinstance(f.get("time"), h5py.Dataset):
            raise ResultFileError(f"{path}: no dataset /time")
        t = np.asarray(f["time"][...], dtype=float)
        xyz = np.asarray(f[f"nodes/{label}/position"][...], dtype=float)
    if t.ndim != 1:
        raise ResultFileError(f"{path}: /time has shape {t.shape}, expected (nt,)")
    nt = t.shape[0]
    if xyz.shape != (nt, 3):
        hint = ""
        if xyz.shape == (3, nt):
            hint = " (stored transposed?)"
        raise ResultFileError(
            f"{path}: /nodes/{label}/position has shape {xyz.shape}, expected ({nt}, 3) "
            f"to match /time{hint}"
        )
    return t, xyz


def to_python(value: Any) -> Any:
    """An HDF5 attribute value as plain Python (bytes decoded, numpy scalars unwrapped)."""
    if isinstance(value, bytes):
        return value.decode("utf-8", errors="replace")
    if isinstance(value, np.ndarray):
        if value.dtype.kind in "SO":
            return [to_python(v) for v in value.tolist()]
        return value
    if isinstance(value, np.generic):
        return to_python(value.item())
    return value


def run_attributes(path: str | os.PathLike) -> dict[str, Any]:
    """Root attributes of a result file as plain Python values (str, int, float; arrays stay
    numpy arrays)."""
    with _open(path) as f:
        return {name: to_python(value) for name, value in f.attrs.items()}
