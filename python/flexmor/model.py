"""The model stored in a result file (``/model``, docs/output.md) and its drawn geometry.

Indices are 0-based here (the file stores 1-based ones, 0 for "none"): ``-1`` marks a missing
coordinate. :class:`Mesh` turns coordinate vectors x (the rows of ``/x`` or ``/static/x``) into
drawable points: the nodes, and along each beam the element's cubic Hermite interpolation.
Planar models (``/model`` attribute ``dimension`` 2) and spatial ones (3: nodes with z and
Euler parameters, ``beam3d`` and ``euler`` elements) are both read.
"""
from __future__ import annotations

from dataclasses import dataclass

import h5py
import numpy as np

__all__ = ["ELEMENT_TYPE_IDS", "Mesh", "Model", "read_model", "rotate"]

#: Cell data ``element_type`` of the VTK files and the colour key of the animation.
ELEMENT_TYPE_IDS = {"beam": 1, "truss": 2, "hinge": 3, "slider": 4, "beam3d": 5}
#: Coordinate kinds of ``/model/coordinates/kind``.
KIND_X, KIND_Y, KIND_ROTATION, KIND_Z, KIND_EULER = 1, 2, 3, 4, 5
#: Element types drawn as cubic Hermite curves (planar and spatial beams).
BEAM_TYPES = ("beam", "beam3d")
#: Columns of /model/nodes/coordinates: (x, y, phi) planar, (x, y, 0, z, lambda0) spatial.
NODE_COLUMNS = {2: 3, 3: 5}


@dataclass
class Model:
    """Coordinates, nodes and elements of a model, 0-based indices (-1: none).

    ``coordinate_names`` (n_x,), ``reference`` (n_x,) x0 [m or rad], ``kind`` (n_x,) 1 x, 2 y,
    3 rotation, 4 z, 5 Euler parameter; ``node_labels`` (n_nodes,), ``node_position``
    (n_nodes, 3) reference [m], ``node_coordinates`` (n_nodes, 3) indices into x of x, y,
    rotation (spatial: (n_nodes, 5) of x, y, -1, z and the first of the node's four Euler
    parameters); ``element_labels``, ``element_types`` ('beam', 'truss', 'hinge', 'slider';
    spatial 'beam3d', 'euler', 'body3d') (n_el,), ``element_coordinates`` (n_el, 6) (spatial
    (n_el, w), w >= 14 when there are beams: xp, yp, zp, lambda_p (4), xq, yq, zq, lambda_q
    (4)), ``element_nodes`` (n_el, 2) indices into the nodes (an ``euler`` element has none:
    -1); ``dimension`` 2 or 3."""

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
    dimension: int = 2

    @property
    def spatial(self) -> bool:
        """True for a spatial model (dimension 3)."""
        return self.dimension == 3

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
        """Indices of the elements of type ``kind`` ('beam', 'truss', 'beam3d', ...)."""
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


def _width(f: h5py.File, name: str, rows: int, planar: bool) -> int:
    """Columns of the table /name: 6 in a planar file; in a spatial one as stored (the writer
    pads to the widest element, 14 with beams), at least 6."""
    if planar:
        return 6
    obj = f.get(name)
    if not isinstance(obj, h5py.Dataset):
        raise ValueError(f"no dataset /{name}")
    if obj.ndim != 2 or obj.shape[0] != rows or obj.shape[1] < 6:
        raise ValueError(f"/{name} has shape {obj.shape}, expected ({rows}, 6 or more)")
    return int(obj.shape[1])


def _indices(f: h5py.File, name: str, shape: tuple[int, ...], upper: int) -> np.ndarray:
    data = np.asarray(_dataset(f, name, shape), dtype=np.int64)
    if data.size and (data.min() < 0 or data.max() > upper):
        raise ValueError(f"/{name} has indices outside 0..{upper}")
    return data - 1


def read_model(f: h5py.File) -> Model:
    """The ``/model`` group of an open result file, planar or spatial; ValueError (one line,
    naming the dataset) for a missing dataset, a wrong shape or an index out of range."""
    group = f.get("model")
    if not isinstance(group, h5py.Group):
        raise ValueError("no group /model")
    try:
        n_x, n_nodes, n_el = (int(group.attrs[k]) for k in
                              ("n_coordinates", "n_nodes", "n_elements"))
    except KeyError as exc:
        raise ValueError(f"/model has no attribute {exc.args[0]}") from None
    # Files from before spatial scenes have no attribute: they are planar.
    dimension = int(group.attrs.get("dimension", 2))
    if dimension not in NODE_COLUMNS:
        raise ValueError(f"/model has attribute dimension = {dimension}, expected 2 or 3")
    names = _strings(_dataset(f, "model/coordinates/name", (n_x,)))
    reference = np.asarray(_dataset(f, "model/coordinates/reference", (n_x,)), dtype=float)
    kind = np.asarray(_dataset(f, "model/coordinates/kind", (n_x,)), dtype=np.int64)
    labels = _strings(_dataset(f, "model/nodes/label", (n_nodes,)))
    position = np.asarray(_dataset(f, "model/nodes/position", (n_nodes, 3)), dtype=float)
    node_coords = _indices(f, "model/nodes/coordinates", (n_nodes, NODE_COLUMNS[dimension]), n_x)
    el_labels = _strings(_dataset(f, "model/elements/label", (n_el,)))
    el_types = [t.strip().lower() for t in _strings(_dataset(f, "model/elements/type", (n_el,)))]
    width = _width(f, "model/elements/coordinates", n_el, dimension == 2)
    el_coords = _indices(f, "model/elements/coordinates", (n_el, width), n_x)
    el_nodes = _indices(f, "model/elements/nodes", (n_el, 2), n_nodes)
    model = Model(names, reference, kind, labels, position, node_coords, el_labels, el_types,
                  el_coords, el_nodes, dimension)
    if dimension == 2:
        _check(model)
    else:
        _check_spatial(model)
    return model


def _check(model: Model) -> None:
    """Consistency that the drawing of a planar model relies on; ValueError naming the element
    or node."""
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


#: Coordinate kinds of the used columns of each spatial element type, and which columns are
#: the (x, y, z, lambda0) of its end nodes.
_SPATIAL_KINDS = {
    "beam3d": [KIND_X, KIND_Y, KIND_Z] + [KIND_EULER] * 4 + [KIND_X, KIND_Y, KIND_Z]
    + [KIND_EULER] * 4,
    "euler": [KIND_EULER] * 4,
    "body3d": [KIND_X, KIND_Y, KIND_Z] + [KIND_EULER] * 4,
    # A free node rotation's rotation vector, and a hinge between two sets of Euler parameters
    # (a driven node rotation's, from its clamped frame).
    "rotvec": [KIND_EULER] * 4,
    "hinge3d": [KIND_EULER] * 8,
}
_SPATIAL_ENDS = {"beam3d": ([0, 1, 2, 3], [7, 8, 9, 10]), "body3d": ([0, 1, 2, 3],) * 2,
                 "euler": (), "rotvec": (), "hinge3d": ()}
#: Spatial element types on Euler parameters only (blocks of four, no translations).
_EULER_ONLY = ("euler", "rotvec", "hinge3d")


def _check_spatial(model: Model) -> None:
    """Consistency that the drawing of a spatial model relies on: x, y, z of every node, four
    consecutive Euler parameters where a node has them, elements on their nodes' positions;
    ValueError naming the element or node."""
    kind = model.kind
    if kind.size and not np.isin(kind, (KIND_X, KIND_Y, KIND_Z, KIND_EULER)).all():
        raise ValueError("/model/coordinates/kind has values other than 1, 2, 4, 5 in a "
                         "spatial model")
    n_x = model.n_coordinates
    for i, label in enumerate(model.node_labels):
        ix, iy, _, iz, il = model.node_coordinates[i]
        if min(ix, iy, iz) < 0 or [kind[ix], kind[iy], kind[iz]] != [KIND_X, KIND_Y, KIND_Z]:
            raise ValueError(f"/model/nodes/coordinates: node '{label}' has no x, y and z "
                             f"coordinates")
        if il >= 0 and (il + 4 > n_x or (kind[il:il + 4] != KIND_EULER).any()):
            raise ValueError(f"/model/nodes/coordinates: node '{label}' does not start four "
                             f"Euler parameters at coordinate {il + 1}")
    nodes = model.node_coordinates[:, [0, 1, 3, 4]]
    for e, (label, etype) in enumerate(zip(model.element_labels, model.element_types)):
        if etype not in _SPATIAL_KINDS:
            raise ValueError(f"/model/elements/type: element '{label}' has type '{etype}', "
                             f"not one of a spatial model ({', '.join(_SPATIAL_KINDS)})")
        pattern = _SPATIAL_KINDS[etype]
        coords = model.element_coordinates[e]
        if len(coords) < len(pattern) or (coords[:len(pattern)] < 0).any():
            raise ValueError(f"/model/elements/coordinates: {etype} '{label}' lacks coordinates")
        if (kind[coords[:len(pattern)]] != pattern).any():
            raise ValueError(f"/model/elements/coordinates: {etype} '{label}' has coordinates "
                             f"of the wrong kinds (expected kinds {pattern})")
        euler_only = etype in _EULER_ONLY
        for block in range(0, len(pattern), 4 if euler_only else 7):
            first = block + (0 if euler_only else 3)
            if not np.array_equal(coords[first:first + 4], coords[first] + np.arange(4)):
                raise ValueError(f"/model/elements/coordinates: {etype} '{label}' has Euler "
                                 f"parameters that are not four consecutive coordinates")
        ends = _SPATIAL_ENDS[etype]
        if ends and (model.element_nodes[e] < 0).any():
            raise ValueError(f"/model/elements/nodes: element '{label}' lacks nodes")
        # An end hinged at its node has Euler parameters of its own: only x, y, z are shared.
        for end, node in zip(ends, model.element_nodes[e]):
            if not np.array_equal(coords[end[:3]], nodes[node][:3]):
                raise ValueError(f"/model/elements/coordinates: {etype} '{label}' does not "
                                 f"use the x, y and z of its node "
                                 f"'{model.node_labels[node]}'")


def rotate(lam: np.ndarray, a: np.ndarray) -> np.ndarray:
    """R(lambda) a for Euler parameters ``lam`` (..., 4), scalar first, and vectors ``a``
    (..., 3) (broadcast). lambda is normalised first: the solver keeps |lambda| = 1 only to its
    tolerance, and the homogeneous R of elements_rotation is |lambda|^2 times the rotation.
    ValueError for a zero or non-finite lambda, which is no rotation."""
    lam = np.asarray(lam, dtype=float)
    norm = np.linalg.norm(lam, axis=-1, keepdims=True)
    if not (np.isfinite(norm).all() and (norm > 0).all()):
        raise ValueError("Euler parameters of zero or non-finite length: not a rotation")
    lam = lam / norm
    w, v = lam[..., :1], lam[..., 1:]
    a = np.asarray(a, dtype=float)
    return ((w**2 - np.sum(v * v, axis=-1, keepdims=True)) * a
            + 2 * np.sum(v * a, axis=-1, keepdims=True) * v + 2 * w * np.cross(v, a))


class Mesh:
    """Points and cells of a model's drawing: the nodes (points 0 .. n_nodes-1), then the
    ``segments - 1`` interior points of each beam (planar ``beam`` or spatial ``beam3d``).
    ``lines`` (n_lines, 2) are point pairs (``segments`` per beam, one per truss),
    ``vertices`` the hinge points; ``line_element`` and ``vertex_element`` the element index
    of each cell. ``euler`` and ``body3d`` elements are not drawn (their nodes are)."""

    def __init__(self, model: Model, segments: int = 8) -> None:
        if segments < 1:
            raise ValueError("segments must be at least 1")
        self.model, self.segments = model, int(segments)
        self.beams = np.array([i for i, t in enumerate(model.element_types) if t in BEAM_TYPES],
                              dtype=int)
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
        if model.spatial:
            # beam3d applies R(lambda) to its reference chord direction ex0 (lambda = 1 in
            # the reference state), which the reference end positions give.
            chord = ref[coords[:, 7:10]] - ref[coords[:, 0:3]] if len(self.beams) \
                else np.zeros((0, 3))
            self._l0 = np.linalg.norm(chord, axis=-1)
            if (self._l0 <= 0).any():
                bad = model.element_labels[self.beams[np.argmax(self._l0 <= 0)]]
                raise ValueError(f"/model/coordinates/reference: beam3d '{bad}' has both "
                                 f"ends at the same place")
            self._ex0 = chord / self._l0[:, None]
        else:
            self._chord_angle = np.arctan2(ref[coords[:, 4]] - ref[coords[:, 1]],
                                           ref[coords[:, 3]] - ref[coords[:, 0]]) \
                if len(self.beams) else np.zeros(0)

    def _hermite(self, p1: np.ndarray, t1: np.ndarray, p2: np.ndarray, t2: np.ndarray
                 ) -> np.ndarray:
        """Interior points (..., nb * (segments - 1), d) of the cubic Hermite curves with ends
        p1, p2 and end tangents t1, t2 (each (..., nb, d), tangents d curve / d s)."""
        h = self._basis  # curve(s) = h00 p1 + h10 t1 + h01 p2 + h11 t2
        inner = (p1[..., None, :] * h[0][:, None] + t1[..., None, :] * h[1][:, None]
                 + p2[..., None, :] * h[2][:, None] + t2[..., None, :] * h[3][:, None])
        return inner.reshape(*p1.shape[:-2], -1, p1.shape[-1])

    def points(self, x: np.ndarray) -> np.ndarray:
        """Point positions (..., n_points, 3) [m] for coordinates ``x`` (..., n_x); z = 0 in a
        planar model. ValueError for a wrong length of x or (spatial) zero Euler parameters."""
        x = np.asarray(x, dtype=float)
        model = self.model
        if x.shape[-1] != model.n_coordinates:
            raise ValueError(f"x has {x.shape[-1]} coordinates, the model {model.n_coordinates}")
        out = np.zeros((*x.shape[:-1], self.n_points, 3))
        out[..., :model.n_nodes, 0] = x[..., model.node_coordinates[:, 0]]
        out[..., :model.n_nodes, 1] = x[..., model.node_coordinates[:, 1]]
        if model.spatial:
            out[..., :model.n_nodes, 2] = x[..., model.node_coordinates[:, 3]]
        if not len(self.beams) or self.segments == 1:
            return out
        if model.spatial:
            out[..., model.n_nodes:, :] = self._spatial_inner(x)
            return out
        c, ref = self._beam_coords, model.reference
        p1 = np.stack([x[..., c[:, 0]], x[..., c[:, 1]]], axis=-1)  # (..., nb, 2)
        p2 = np.stack([x[..., c[:, 3]], x[..., c[:, 4]]], axis=-1)
        length = np.linalg.norm(p2 - p1, axis=-1)[..., None]  # (..., nb, 1)
        a1 = self._chord_angle + x[..., c[:, 2]] - ref[c[:, 2]]
        a2 = self._chord_angle + x[..., c[:, 5]] - ref[c[:, 5]]
        t1 = length * np.stack([np.cos(a1), np.sin(a1)], axis=-1)
        t2 = length * np.stack([np.cos(a2), np.sin(a2)], axis=-1)
        out[..., model.n_nodes:, :2] = self._hermite(p1, t1, p2, t2)
        return out

    def _spatial_inner(self, x: np.ndarray) -> np.ndarray:
        """Interior points of the beam3d elements: end tangents l0 R(lambda) ex0, the section
        axis through each end node at its undeformed length (the element's own measure of
        length; the chord shortens as the beam bends, l0 does not)."""
        c = self._beam_coords
        p1, p2 = x[..., c[:, 0:3]], x[..., c[:, 7:10]]  # (..., nb, 3)
        try:
            t1 = self._l0[:, None] * rotate(x[..., c[:, 3:7]], self._ex0)
            t2 = self._l0[:, None] * rotate(x[..., c[:, 10:14]], self._ex0)
        except ValueError as exc:
            raise ValueError(f"x: a beam3d end node has {exc}") from None
        return self._hermite(p1, t1, p2, t2)

    def reference_points(self) -> np.ndarray:
        """:meth:`points` of the reference coordinates x0."""
        return self.points(self.model.reference)

    def cell_element_types(self) -> tuple[np.ndarray, np.ndarray]:
        """``ELEMENT_TYPE_IDS`` of the line cells and of the vertex cells."""
        types = self.model.element_types
        line = [ELEMENT_TYPE_IDS[types[e]] for e in self.line_element]
        vertex = [ELEMENT_TYPE_IDS[types[e]] for e in self.vertex_element]
        return np.array(line, dtype=np.int64), np.array(vertex, dtype=np.int64)
