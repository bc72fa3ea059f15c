"""The model stored in a result file (``/model``, docs/output.md) and its drawn geometry.

Indices are 0-based here (the file stores 1-based ones, 0 for "none"): ``-1`` marks a missing
coordinate. :class:`Mesh` turns coordinate vectors x (the rows of ``/x`` or ``/static/x``) into
drawable points: the nodes, and along each beam the element's cubic Hermite interpolation.
"""
from __future__ import annotations

from dataclasses import dataclass

import h5py
import numpy as np

__all__ = ["ELEMENT_TYPE_IDS", "Mesh", "Model", "read_model"]

#: Cell data ``element_type`` of the VTK files and the colour key of the animation.
ELEMENT_TYPE_IDS = {"beam": 1, "truss": 2, "hinge": 3, "slider": 4}
#: Coordinate kinds of ``/model/coordinates/kind``.
KIND_X, KIND_Y, KIND_ROTATION = 1, 2, 3


@dataclass
class Model:
    """Coordinates, nodes and elements of a model, 0-based indices (-1: none).

    ``coordinate_names`` (n_x,), ``reference`` (n_x,) x0 [m or rad], ``kind`` (n_x,) 1 x, 2 y,
    3 rotation; ``node_labels`` (n_nodes,), ``node_position`` (n_nodes, 3) reference [m],
    ``node_coordinates`` (n_nodes, 3) indices into x of x, y, rotation; ``element_labels``,
    ``element_types`` ('beam', 'truss', 'hinge') (n_el,), ``element_coordinates`` (n_el, 6),
    ``element_nodes`` (n_el, 2) indices into the nodes."""

    coordinate_names: list[str]
    reference: np.ndarray
    kind: np.ndarray
    node_labels: list[str]
    node_position: np.ndarray
    node_coordinates: np.ndarray
    element_labels: list[str]
    element_types: list[str]
    element_coordinates: np.ndarray
    element_nodes: np.ndarray

    @property
    def n_coordinates(self) -> int:
        return int(self.reference.shape[0])

    @property
    def n_nodes(self) -> int:
        return len(self.node_labels)

    @property
    def n_elements(self) -> int:
        return len(self.element_labels)

    def elements_of_type(self, kind: str) -> np.ndarray:
        """Indices of the elements of type ``kind`` ('beam', 'truss' or 'hinge')."""
        return np.array([i for i, t in enumerate(self.element_types) if t == kind], dtype=int)

    def mesh(self, segments: int = 8) -> "Mesh":
        """The drawing of this model with ``segments`` straight pieces per beam."""
        return Mesh(self, segments)


def _strings(data: np.ndarray) -> list[str]:
    return [v.decode("utf-8", errors="replace") if isinstance(v, bytes) else str(v)
            for v in data.tolist()]


def _dataset(f: h5py.File, name: str, shape: tuple[int, ...]) -> np.ndarray:
    obj = f.get(name)
    if not isinstance(obj, h5py.Dataset):
        raise ValueError(f"no dataset /{name}")
    data = obj[...]
    if data.shape != shape and not (data.size == 0 and np.prod(shape) == 0):
        raise ValueError(f"/{name} has shape {data.shape}, expected {shape}")
    return data.reshape(shape)


def _indices(f: h5py.File, name: str, shape: tuple[int, ...], upper: int) -> np.ndarray:
    data = np.asarray(_dataset(f, name, shape), dtype=np.int64)
    if data.size and (data.min() < 0 or data.max() > upper):
        raise ValueError(f"/{name} has indices outside 0..{upper}")
    return data - 1


def read_model(f: h5py.File) -> Model:
    """The ``/model`` group of an open result file; ValueError (one line, naming the dataset)
    for a missing dataset, a wrong shape or an index out of range."""
    group = f.get("model")
    if not isinstance(group, h5py.Group):
        raise ValueError("no group /model")
    try:
        n_x, n_nodes, n_el = (int(group.attrs[k]) for k in
                              ("n_coordinates", "n_nodes", "n_elements"))
    except KeyError as exc:
        raise ValueError(f"/model has no attribute {exc.args[0]}") from None
    if int(group.attrs.get("dimension", 2)) != 2:
        raise ValueError("/model is a spatial model (dimension 3): flexmor.model reads planar "
                         "models only so far (node paths are in /nodes/<label>/position)")
    names = _strings(_dataset(f, "model/coordinates/name", (n_x,)))
    reference = np.asarray(_dataset(f, "model/coordinates/reference", (n_x,)), dtype=float)
    kind = np.asarray(_dataset(f, "model/coordinates/kind", (n_x,)), dtype=np.int64)
    labels = _strings(_dataset(f, "model/nodes/label", (n_nodes,)))
    position = np.asarray(_dataset(f, "model/nodes/position", (n_nodes, 3)), dtype=float)
    node_coords = _indices(f, "model/nodes/coordinates", (n_nodes, 3), n_x)
    el_labels = _strings(_dataset(f, "model/elements/label", (n_el,)))
    el_types = [t.strip().lower() for t in _strings(_dataset(f, "model/elements/type", (n_el,)))]
    el_coords = _indices(f, "model/elements/coordinates", (n_el, 6), n_x)
    el_nodes = _indices(f, "model/elements/nodes", (n_el, 2), n_nodes)
    model = Model(names, reference, kind, labels, position, node_coords, el_labels, el_types,
                  el_coords, el_nodes)
    _check(model)
    return model


def _check(model: Model) -> None:
    """Consistency that the drawing relies on; ValueError naming the element or node."""
    if model.kind.size and not np.isin(model.kind, (KIND_X, KIND_Y, KIND_ROTATION)).all():
        raise ValueError("/model/coordinates/kind has values other than 1, 2, 3")
    for i, label in enumerate(model.node_labels):
        ix, iy, _ = model.node_coordinates[i]
        if ix < 0 or iy < 0 or model.kind[ix] != KIND_X or model.kind[iy] != KIND_Y:
            raise ValueError(f"/model/nodes/coordinates: node '{label}' has no x and y "
                             f"coordinates")
    used = {"beam": 6, "truss": 4, "hinge": 2, "slider": 2}
    for e, (label, kind) in enumerate(zip(model.element_labels, model.element_types)):
        if kind not in used:
            raise ValueError(f"/model/elements/type: element '{label}' has unknown type "
                             f"'{kind}' (beam, truss, hinge or slider)")
        coords = model.element_coordinates[e]
        if (coords[:used[kind]] < 0).any():
            raise ValueError(f"/model/elements/coordinates: {kind} '{label}' lacks coordinates")
        if (model.element_nodes[e] < 0).any():
            raise ValueError(f"/model/elements/nodes: element '{label}' lacks nodes")
        if kind != "hinge":
            ends = (coords[[0, 1]], coords[[3, 4]] if kind == "beam" else coords[[2, 3]])
            if kind == "slider":  # one node, named twice
                ends = (coords[[0, 1]],) * 2
            for end, node in zip(ends, model.element_nodes[e]):
                if not np.array_equal(end, model.node_coordinates[node, :2]):
                    raise ValueError(f"/model/elements/coordinates: {kind} '{label}' does not "
                                     f"use the x, y of its node '{model.node_labels[node]}'")


class Mesh:
    """Points and cells of a model's drawing: the nodes (points 0 .. n_nodes-1), then the
    ``segments - 1`` interior points of each beam. ``lines`` (n_lines, 2) are point pairs
    (``segments`` per beam, one per truss), ``vertices`` the hinge points; ``line_element`` and
    ``vertex_element`` the element index of each cell."""

    def __init__(self, model: Model, segments: int = 8) -> None:
        if segments < 1:
            raise ValueError("segments must be at least 1")
        self.model, self.segments = model, int(segments)
        self.beams = model.elements_of_type("beam")
        trusses = model.elements_of_type("truss")
        hinges = model.elements_of_type("hinge")
        n_inner = self.segments - 1
        self.n_points = model.n_nodes + len(self.beams) * n_inner
        lines, line_element = [], []
        for b, e in enumerate(self.beams):
            first, last = model.element_nodes[e]
            inner = model.n_nodes + b * n_inner + np.arange(n_inner)
            chain = np.concatenate(([first], inner, [last]))
            lines += list(zip(chain[:-1], chain[1:]))
            line_element += [e] * self.segments
        for e in trusses:
            lines.append(tuple(model.element_nodes[e]))
            line_element.append(e)
        self.lines = np.array(lines, dtype=np.int64).reshape(-1, 2)
        self.line_element = np.array(line_element, dtype=np.int64)
        self.vertices = model.element_nodes[hinges, 0].astype(np.int64)
        self.vertex_element = hinges.astype(np.int64)
        # Hermite basis at the interior parameters s = k / segments.
        s = np.arange(1, self.segments) / self.segments
        self._basis = np.stack([2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s,
                                -2 * s**3 + 3 * s**2, s**3 - s**2])  # (4, n_inner)
        coords = model.element_coordinates[self.beams]
        self._beam_coords = coords
        ref = model.reference
        self._chord_angle = np.arctan2(ref[coords[:, 4]] - ref[coords[:, 1]],
                                       ref[coords[:, 3]] - ref[coords[:, 0]]) \
            if len(self.beams) else np.zeros(0)

    def points(self, x: np.ndarray) -> np.ndarray:
        """Point positions (..., n_points, 3) [m] for coordinates ``x`` (..., n_x); z = 0."""
        x = np.asarray(x, dtype=float)
        model = self.model
        if x.shape[-1] != model.n_coordinates:
            raise ValueError(f"x has {x.shape[-1]} coordinates, the model {model.n_coordinates}")
        out = np.zeros((*x.shape[:-1], self.n_points, 3))
        out[..., :model.n_nodes, 0] = x[..., model.node_coordinates[:, 0]]
        out[..., :model.n_nodes, 1] = x[..., model.node_coordinates[:, 1]]
        if len(self.beams) and self.segments > 1:
            c, ref = self._beam_coords, model.reference
            p1 = np.stack([x[..., c[:, 0]], x[..., c[:, 1]]], axis=-1)  # (..., nb, 2)
            p2 = np.stack([x[..., c[:, 3]], x[..., c[:, 4]]], axis=-1)
            length = np.linalg.norm(p2 - p1, axis=-1)[..., None]  # (..., nb, 1)
            a1 = self._chord_angle + x[..., c[:, 2]] - ref[c[:, 2]]
            a2 = self._chord_angle + x[..., c[:, 5]] - ref[c[:, 5]]
            t1 = length * np.stack([np.cos(a1), np.sin(a1)], axis=-1)
            t2 = length * np.stack([np.cos(a2), np.sin(a2)], axis=-1)
            h = self._basis  # curve(s) = h00 p1 + h10 t1 + h01 p2 + h11 t2
            inner = (p1[..., None, :] * h[0][:, None] + t1[..., None, :] * h[1][:, None]
                     + p2[..., None, :] * h[2][:, None] + t2[..., None, :] * h[3][:, None])
            out[..., model.n_nodes:, :2] = inner.reshape(*x.shape[:-1], -1, 2)
        return out

    def reference_points(self) -> np.ndarray:
        """:meth:`points` of the reference coordinates x0."""
        return self.points(self.model.reference)

    def cell_element_types(self) -> tuple[np.ndarray, np.ndarray]:
        """``ELEMENT_TYPE_IDS`` of the line cells and of the vertex cells."""
        types = np.array([ELEMENT_TYPE_IDS[t] for t in self.model.element_types], dtype=np.int64)
        return types[self.line_element], types[self.vertex_element]
