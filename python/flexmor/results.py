"""Reading flexmor result files (HDF5): the layout of docs/output.md.

:func:`read_result` reads a whole file into a :class:`Result`; :func:`load_node_path`,
:func:`node_labels` and :func:`run_attributes` read single pieces (and accept any HDF5 file with
those datasets, e.g. synthetic test files).

Every failure (missing file, not an HDF5 file, not a flexmor result file, missing node or
dataset, wrong shape) raises :class:`ResultFileError` with a one-line message naming the file,
so a command can print it and exit without a traceback.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import h5py
import numpy as np

from flexmor.model import Model, read_model

if TYPE_CHECKING:
    from flexmor.control import Linear

__all__ = ["Modal", "NodePath", "Result", "ResultFileError", "Static", "load_node_path",
           "node_labels", "read_result", "run_attributes", "to_python"]


class ResultFileError(Exception):
    """A result file is missing, unreadable or lacks what was asked for."""


def open_h5(path: str | os.PathLike, error: type[Exception] = ResultFileError,
            what: str = "result file") -> h5py.File:
    """Open ``path`` read-only; ``error`` with a one-line message when that is impossible."""
    path = os.fspath(path)
    if not os.path.exists(path):
        raise error(f"{path}: no such file")
    if os.path.isdir(path):
        raise error(f"{path}: is a folder, not a {what}")
    try:
        return h5py.File(path, "r")
    except OSError as exc:
        raise error(f"{path}: not a readable HDF5 file ({exc})") from None


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


def _attrs(obj: h5py.HLObject) -> dict[str, Any]:
    return {name: to_python(value) for name, value in obj.attrs.items()}


def _node_labels(group: h5py.Group | None) -> list[str]:
    if not isinstance(group, h5py.Group):
        return []
    return sorted(name for name, obj in group.items()
                  if isinstance(obj, h5py.Group) and isinstance(obj.get("position"), h5py.Dataset))


def node_labels(path: str | os.PathLike) -> list[str]:
    """Sorted labels of the nodes whose position is stored (``/nodes/<label>/position``)."""
    with open_h5(path) as f:
        return _node_labels(f.get("nodes"))


def load_node_path(path: str | os.PathLike, label: str = "tip") -> tuple[np.ndarray, np.ndarray]:
    """Return ``(t, xyz)``: times (nt,) in seconds and positions (nt, 3) in metres of node
    ``label``. Raises :class:`ResultFileError` naming the file and, for a missing label, the
    labels that are available."""
    path = os.fspath(path)
    with open_h5(path) as f:
        labels = _node_labels(f.get("nodes"))
        if not labels and not isinstance(f.get("time"), h5py.Dataset):
            # A static, modal or buckling result: no time histories at all.
            raise ResultFileError(f"{path}: no dynamic run (no /time and no /nodes: the scene "
                                  f"had no &dynamic group; a static run's nodes are under "
                                  f"/static/nodes)")
        if label not in labels:
            available = ", ".join(labels) if labels else "none"
            raise ResultFileError(
                f"{path}: no node '{label}' (no dataset /nodes/{label}/position); "
                f"available: {available}")
        if not isinstance(f.get("time"), h5py.Dataset):
            raise ResultFileError(f"{path}: no dataset /time")
        t = np.asarray(f["time"][...], dtype=float)
        xyz = np.asarray(f[f"nodes/{label}/position"][...], dtype=float)
    if t.ndim != 1:
        raise ResultFileError(f"{path}: /time has shape {t.shape}, expected (nt,)")
    _check_rows(path, f"/nodes/{label}/position", xyz, t.shape[0], (3,), "/time")
    return t, xyz


def run_attributes(path: str | os.PathLike) -> dict[str, Any]:
    """Root attributes of a result file as plain Python values (str, int, float; arrays stay
    numpy arrays)."""
    with open_h5(path) as f:
        return _attrs(f)


def _check_rows(path: str, name: str, data: np.ndarray, n: int, tail: tuple[int, ...],
                against: str) -> None:
    expected = (n, *tail)
    if data.shape != expected:
        hint = " (stored transposed?)" if data.shape == expected[::-1] and len(tail) else ""
        shown = ", ".join(["n" if i == 0 else str(d) for i, d in enumerate(expected)])
        raise ResultFileError(f"{path}: {name} has shape {data.shape}, expected {expected} "
                              f"(({shown}) with n from {against}){hint}")


@dataclass
class NodePath:
    """Positions (n, 3) [m] and, for nodes that have one, rotations (n,) [rad] of one node at
    each output time (or load step); in a spatial result the node's ``orientation`` (n, 4)
    instead: Euler parameters (scalar first) of its rotation from the reference orientation.
    Static paths also carry the node's ``reaction`` (n, 3): fx, fy [N], mz [N m] from supports
    and prescribed inputs, and, for ``&output compliance_nodes``, its tangent ``compliance``
    (n, 3, 3): d(x, y, phi)/d(fx, fy, mz); in a spatial result (n, 6) and (n, 6, 6) with
    components x, y, z and the rotations (moments) about x, y, z."""

    position: np.ndarray
    rotation: np.ndarray | None = None
    reaction: np.ndarray | None = None
    compliance: np.ndarray | None = None
    orientation: np.ndarray | None = None


@dataclass
class Modal:
    """``&modal`` results: frequencies (n_modes,) [Hz], shapes (n_modes, n_dy) in the dynamic
    coordinates and per output node the (n_modes, 3) nodal displacement of each mode."""

    frequency_hz: np.ndarray
    shapes: np.ndarray
    nodes: dict[str, np.ndarray] = field(default_factory=dict)
    time: float | None = None


@dataclass
class Buckling:
    """``&buckling`` results: load multipliers (n,) lowest first, shapes (n, n_dy) and per
    output node the (n, 3) shape (largest nodal translation 1); ``attrs`` holds
    ``reference_load_factor`` and ``n_negative`` (-1: not counted, the matrix-free solver)."""

    load_factor: np.ndarray
    shapes: np.ndarray
    nodes: dict[str, np.ndarray] = field(default_factory=dict)
    attrs: dict[str, Any] = field(default_factory=dict)


@dataclass
class Static:
    """``&static`` results: per load step the load factor (arc-length: as traced), node paths
    (with reactions and compliances), all coordinates ``x`` (n_steps, n_x), the ``stable``
    flag and the lowest natural frequencies ``frequency_hz`` (n_steps, n) [Hz] (None where the
    file does not have them), and ``q`` (n_dy,) at the last step."""

    load_factor: np.ndarray
    q: np.ndarray | None
    nodes: dict[str, NodePath] = field(default_factory=dict)
    x: np.ndarray | None = None
    stable: np.ndarray | None = None
    frequency_hz: np.ndarray | None = None


@dataclass
class Result:
    """The contents of one flexmor result file (docs/output.md). Absent parts are None (or
    empty dicts): ``time``, ``nodes``, ``q``, ``qd``, ``energy`` and ``x`` come from
    ``&dynamic``, ``static`` from ``&static``, ``modal`` from ``&modal``, ``buckling`` from
    ``&buckling``, ``linear`` (:class:`flexmor.control.Linear`) from ``&linear``, ``reduction``
    from ``&reduction``, ``error_check`` from ``&dynamic error_check``, ``model`` from files
    that store the ``/model`` group, ``controllers``
    (label -> {"error": (n_t,), "input": ..., "measure": ...}) from ``&controller`` in a
    dynamic run."""

    path: str
    attrs: dict[str, Any]
    time: np.ndarray | None = None
    nodes: dict[str, NodePath] = field(default_factory=dict)
    q: np.ndarray | None = None
    qd: np.ndarray | None = None
    energy: dict[str, np.ndarray] = field(default_factory=dict)
    x: np.ndarray | None = None
    static: Static | None = None
    modal: Modal | None = None
    buckling: Buckling | None = None
    reduction: dict[str, Any] | None = None
    error_check: dict[str, Any] | None = None
    model: Model | None = None
    linear: Linear | None = None
    controllers: dict[str, dict[str, np.ndarray]] = field(default_factory=dict)

    @property
    def node_labels(self) -> list[str]:
        """Labels of the output nodes with a dynamic path."""
        return list(self.nodes)

    def node_path(self, label: str = "tip") -> tuple[np.ndarray, np.ndarray]:
        """``(t, xyz)`` of node ``label`` (as :func:`load_node_path`)."""
        if self.time is None:
            raise ResultFileError(f"{self.path}: no dynamic results (no dataset /time)")
        if label not in self.nodes:
            available = ", ".join(self.nodes) if self.nodes else "none"
            raise ResultFileError(f"{self.path}: no node '{label}'; available: {available}")
        return self.time, self.nodes[label].position

    def motion(self) -> tuple[np.ndarray, np.ndarray, str]:
        """``(values, x, what)``: all coordinates x (n, n_x) with their times (``what`` 'time')
        from the dynamic analysis, else at the static load steps with their load factors
        (``what`` 'load factor'); :class:`ResultFileError` when the file has neither."""
        if self.x is not None and self.time is not None:
            return self.time, self.x, "time"
        if self.static is not None and self.static.x is not None:
            return self.static.load_factor, self.static.x, "load factor"
        raise ResultFileError(f"{self.path}: no coordinate history (no dataset /x with /time "
                              f"nor /static/x): the scene needs &dynamic or &static")

    def require_model(self) -> Model:
        """The model, or :class:`ResultFileError` for files written without ``/model``."""
        if self.model is None:
            raise ResultFileError(f"{self.path}: no group /model (written by an older flexmor; "
                                  f"rerun the scene with a current one)")
        return self.model


def _float(path: str, f: h5py.File, name: str) -> np.ndarray | None:
    obj = f.get(name)
    if obj is None:
        return None
    if not isinstance(obj, h5py.Dataset):
        raise ResultFileError(f"{path}: /{name} is not a dataset")
    return np.asarray(obj[...], dtype=float)


def _paths(path: str, group: h5py.Group | None, prefix: str, n: int, against: str,
           spatial: bool = False) -> dict[str, NodePath]:
    out: dict[str, NodePath] = {}
    if not isinstance(group, h5py.Group):
        return out
    for label in sorted(group):  # HDF5 keeps no creation order here: sorted labels
        node = group[label]
        if not isinstance(node, h5py.Group) or not isinstance(node.get("position"), h5py.Dataset):
            continue
        position = np.asarray(node["position"][...], dtype=float)
        _check_rows(path, f"/{prefix}/{label}/position", position, n, (3,), against)
        extra: dict[str, np.ndarray | None] = {}
        # Per node 3 components in a planar result (x, y, phi), 6 in a spatial one.
        k = 6 if spatial else 3
        for name, shape in (("rotation", ()), ("reaction", (k,)), ("compliance", (k, k)),
                            ("orientation", (4,))):
            extra[name] = None
            if isinstance(node.get(name), h5py.Dataset):
                extra[name] = np.asarray(node[name][...], dtype=float)
                _check_rows(path, f"/{prefix}/{label}/{name}", extra[name], n, shape, against)
        out[label] = NodePath(position, **extra)
    return out


def _coordinates(path: str, x: np.ndarray | None, name: str, n: int, against: str,
                 model: Model | None) -> np.ndarray | None:
    if x is None:
        return None
    if x.ndim != 2 or x.shape[0] != n:
        raise ResultFileError(f"{path}: /{name} has shape {x.shape}, expected ({n}, n_x) to "
                              f"match {against}")
    if model is not None and x.shape[1] != model.n_coordinates:
        raise ResultFileError(f"{path}: /{name} has {x.shape[1]} columns, /model has "
                              f"{model.n_coordinates} coordinates")
    return x


def _read_static(path: str, f: h5py.File, model: Model | None) -> Static | None:
    if not isinstance(f.get("static"), h5py.Group):
        return None
    load = _float(path, f, "static/load_factor")
    if load is None or load.ndim != 1:
        raise ResultFileError(f"{path}: /static has no 1-D dataset load_factor")
    n = load.shape[0]
    against = "/static/load_factor"
    stable = f.get("static/stable")
    if stable is not None:
        stable = np.asarray(stable[...]).astype(bool)
        _check_rows(path, "/static/stable", stable, n, (), against)
    x = _coordinates(path, _float(path, f, "static/x"), "static/x", n, against, model)
    freq = _float(path, f, "static/frequency_hz")
    if freq is not None and (freq.ndim != 2 or freq.shape[0] != n):
        raise ResultFileError(f"{path}: /static/frequency_hz has shape {freq.shape}, expected "
                              f"({n}, n) to match {against}")
    spatial = isinstance(f.get("model"), h5py.Group) and \
        int(f["model"].attrs.get("dimension", 2)) == 3
    return Static(load, _float(path, f, "static/q"), _paths(path, f.get("static/nodes"),
                  "static/nodes", n, against, spatial), x, stable, freq)


def _read_shapes(path: str, f: h5py.File, name: str, values: str
                 ) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]] | None:
    """Values (n,), shapes (n, n_dy) and per node the (n, 3) shape of /<name> (modal or
    buckling), or None when the file has no such group."""
    group = f.get(name)
    if not isinstance(group, h5py.Group):
        return None
    vals = _float(path, f, f"{name}/{values}")
    shapes = _float(path, f, f"{name}/shapes")
    if vals is None or shapes is None:
        raise ResultFileError(f"{path}: /{name} lacks {values} or shapes")
    if shapes.ndim != 2 or shapes.shape[0] != vals.shape[0]:
        raise ResultFileError(f"{path}: /{name}/shapes has shape {shapes.shape}, expected "
                              f"({vals.shape[0]}, n_dy) to match /{name}/{values}")
    nodes = {}
    if isinstance(group.get("nodes"), h5py.Group):
        for label, node in group["nodes"].items():
            if isinstance(node, h5py.Group) and isinstance(node.get("shape"), h5py.Dataset):
                shape = np.asarray(node["shape"][...], dtype=float)
                _check_rows(path, f"/{name}/nodes/{label}/shape", shape, vals.shape[0], (3,),
                            f"/{name}/{values}")
                nodes[label] = shape
    return vals, shapes, nodes


def _read_modal(path: str, f: h5py.File) -> Modal | None:
    read = _read_shapes(path, f, "modal", "frequency_hz")
    if read is None:
        return None
    time = f["modal"].attrs.get("time")
    return Modal(*read, None if time is None else float(time))


def _read_buckling(path: str, f: h5py.File) -> Buckling | None:
    read = _read_shapes(path, f, "buckling", "load_factor")
    return None if read is None else Buckling(*read, _attrs(f["buckling"]))


def _read_group(group: h5py.Group) -> dict[str, Any]:
    """Datasets of a group (recursively, keys 'a/b') and its attributes under 'attrs'."""
    out: dict[str, Any] = {"attrs": _attrs(group)}
    for name, obj in group.items():
        if isinstance(obj, h5py.Dataset):
            out[name] = obj[...]
        elif isinstance(obj, h5py.Group):
            for key, value in _read_group(obj).items():
                if key != "attrs":
                    out[f"{name}/{key}"] = value
    return out


def _read_controllers(path: str, group: Any, nt: int) -> dict[str, dict[str, np.ndarray]]:
    """/controllers/<label>/{error,input,measure}: (nt,) like /time, or (n, nt) for a user
    law's several actuators or measured outputs (a user law has no error)."""
    out: dict[str, dict[str, np.ndarray]] = {}
    if not isinstance(group, h5py.Group):
        return out
    for label, sub in group.items():
        out[label] = {}
        for name, value in sub.items():
            value = np.asarray(value[...], dtype=float)
            if value.ndim not in (1, 2) or value.shape[-1] != nt:
                raise ResultFileError(f"{path}: /controllers/{label}/{name} has shape "
                                      f"{value.shape}, expected (..., {nt}) like /time")
            out[label][name] = value
    return out


def read_result(path: str | os.PathLike) -> Result:
    """Read a flexmor result file. Raises :class:`ResultFileError` naming the file when it is
    missing, not HDF5, not a flexmor result file (no root attribute ``flexmor_version``, or a
    sweep file) or inconsistent (shapes that do not match ``/time``, ``/model``)."""
    path = os.fspath(path)
    with open_h5(path) as f:
        if isinstance(f.get("cases"), h5py.Group):
            raise ResultFileError(f"{path}: a flexmor-sweep file, not a result file "
                                  f"(read it with flexmor.read_sweep)")
        if "flexmor_version" not in f.attrs:
            raise ResultFileError(f"{path}: not a flexmor result file (no root attribute "
                                  f"flexmor_version)")
        try:
            model = read_model(f) if "model" in f else None
        except ValueError as exc:
            raise ResultFileError(f"{path}: {exc}") from None
        result = Result(path, _attrs(f), model=model)
        time = _float(path, f, "time")
        if time is not None:
            if time.ndim != 1:
                raise ResultFileError(f"{path}: /time has shape {time.shape}, expected (nt,)")
            nt = time.shape[0]
            result.time = time
            result.nodes = _paths(path, f.get("nodes"), "nodes", nt, "/time")
            for name in ("q", "qd"):
                value = _float(path, f, name)
                if value is not None and (value.ndim != 2 or value.shape[0] != nt):
                    raise ResultFileError(f"{path}: /{name} has shape {value.shape}, expected "
                                          f"({nt}, n_dy) to match /time")
                setattr(result, name, value)
            if isinstance(f.get("energy"), h5py.Group):
                result.energy = {k: np.asarray(v[...], dtype=float)
                                 for k, v in f["energy"].items() if isinstance(v, h5py.Dataset)}
            result.x = _coordinates(path, _float(path, f, "x"), "x", nt, "/time", model)
            result.controllers = _read_controllers(path, f.get("controllers"), nt)
        elif "x" in f:
            raise ResultFileError(f"{path}: dataset /x without /time")
        result.static = _read_static(path, f, model)
        result.modal = _read_modal(path, f)
        result.buckling = _read_buckling(path, f)
        # Imported here: flexmor.control builds on this module (open_h5, ResultFileError).
        from flexmor.control import _read_linear
        result.linear = _read_linear(path, f)
        if isinstance(f.get("reduction"), h5py.Group):
            result.reduction = _read_group(f["reduction"])
        if isinstance(f.get("error_check"), h5py.Group):
            result.error_check = _read_group(f["error_check"])
    return result


def distance_from(run: Result, reference: Result,
                  nodes: list[str] | None = None) -> tuple[np.ndarray, list[str]]:
    """The largest distance [m] of ``nodes`` (default: every output node both files have)
    from the reference's at each of ``run``'s output times (the reference interpolated
    linearly), and the nodes. Raises :class:`ResultFileError` for a run or reference without
    /time, nodes not in both files, or a reference that does not cover the run's times."""
    for result in (run, reference):
        if result.time is None:
            raise ResultFileError(f"{result.path}: no dataset /time (a dynamic run, &dynamic)")
    shared = [label for label in run.node_labels if label in reference.nodes]
    if nodes:
        missing = [label for label in nodes if label not in shared]
        if missing:
            raise ResultFileError(f"node(s) {', '.join(missing)} not in both files; shared: "
                                  f"{', '.join(shared) if shared else 'none'}")
        shared = list(nodes)
    if not shared:
        raise ResultFileError(f"{run.path} and {reference.path} share no output node "
                              f"(&output nodes)")
    t, t_ref = run.time, reference.time
    slack = 1e-9 * max(1.0, abs(float(t[-1])))
    if t[0] < t_ref[0] - slack or t[-1] > t_ref[-1] + slack:
        raise ResultFileError(f"{reference.path}: its times {t_ref[0]:g} to {t_ref[-1]:g} s do "
                              f"not cover the run's {t[0]:g} to {t[-1]:g} s")
    distance = np.zeros_like(t)
    for label in shared:
        xyz, xyz_ref = run.nodes[label].position, reference.nodes[label].position
        distance = np.maximum(distance, np.linalg.norm(xyz - _interp(t, t_ref, xyz_ref), axis=1))
    return distance, shared


def rotation_from(run: Result, reference: Result,
                  nodes: list[str] | None = None) -> tuple[np.ndarray, list[str]]:
    """The largest angle [rad] between the orientations of ``nodes`` (default: every output
    node both files have, those with a rotation of their own) in ``run`` and in the reference
    at each of ``run``'s output times, and those nodes: the difference of the planar angles, or
    the angle of the relative rotation of spatial Euler parameters (the reference's
    interpolated linearly and normalised, which is exact to second order in its output step).
    Errors as :func:`distance_from`, and for nodes without a rotation."""
    _, shared = distance_from(run, reference, nodes)
    turned = [label for label in shared if _has_rotation(run.nodes[label])
              and _has_rotation(reference.nodes[label])]
    if nodes and len(turned) < len(shared):
        raise ResultFileError(f"node(s) {', '.join(sorted(set(shared) - set(turned)))} have no "
                              f"rotation of their own in both files")
    if not turned:
        raise ResultFileError(f"{run.path} and {reference.path} share no output node with a "
                              f"rotation of its own")
    t, t_ref = run.time, reference.time
    angle = np.zeros_like(t)
    for label in turned:
        node, ref = run.nodes[label], reference.nodes[label]
        if node.orientation is None:
            apart = np.abs(node.rotation - np.interp(t, t_ref, ref.rotation))
        else:
            at = _interp(t, t_ref, ref.orientation)
            apart = relative_angle(node.orientation, at / np.linalg.norm(at, axis=1)[:, None])
        angle = np.maximum(angle, apart)
    return angle, turned


def relative_angle(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """The angle [rad, 0..pi] of the rotation between Euler parameters p and q (rows, scalar
    first), from the vector and scalar parts of their relative rotation (an atan2: accurate for
    small angles, where an arccos of the scalar part is not)."""
    v = p[:, :1] * q[:, 1:] - q[:, :1] * p[:, 1:] - np.cross(p[:, 1:], q[:, 1:])
    return 2.0 * np.arctan2(np.linalg.norm(v, axis=1), np.abs(np.sum(p * q, axis=1)))


def _has_rotation(node: NodePath) -> bool:
    return node.rotation is not None or node.orientation is not None


def _interp(t: np.ndarray, t_ref: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Each column of values (at t_ref) at the times t, linearly."""
    return np.column_stack([np.interp(t, t_ref, values[:, c]) for c in range(values.shape[1])])
