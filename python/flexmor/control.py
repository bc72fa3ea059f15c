"""The linearised state-space models of ``&linear`` (``/linear`` of a result file) for control
design: frequency response, poles, transmission zeros, SciPy and python-control systems, Bode
and pole-zero plots.

    lin = flexmor.read_linear("cantilever.h5")      # or flexmor.read_result(...).linear
    w = 2 * np.pi * np.logspace(0, 3, 500)
    g = lin.frequency_response(w, input="tip.fy", output="tip.y")   # (500,) complex, m/N
    lin.poles(), lin.zeros("tip.fy", "tip.y")
    sys = lin.to_control()                           # python-control StateSpace

The state is z = (dq, dq') of the dynamic coordinates (docs/input.md, &linear), SI units:
inputs in N or N m, outputs in m or rad. Reading problems raise
:class:`~flexmor.results.ResultFileError`; an unknown input or output name or a model index out
of range raises :class:`LinearModelError`; both carry one line for a command to print.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any, Sequence

import h5py
import numpy as np

from flexmor.results import ResultFileError, open_h5, to_python

__all__ = ["Linear", "LinearModelError", "frequency_response", "plot_bode", "plot_pole_zero",
           "pole_table", "read_linear", "transmission_zeros", "unit_of"]


class LinearModelError(LookupError):
    """An input or output name, or a linearisation index, that the models do not have."""


# Components of &linear inputs and outputs (docs/input.md) and their SI units.
_UNITS = {"fx": "N", "fy": "N", "fz": "N", "moment": "N m", "mx": "N m", "my": "N m",
          "mz": "N m", "torque": "N m", "x": "m", "y": "m", "z": "m", "phi": "rad",
          "rx": "rad", "ry": "rad", "rz": "rad", "angle": "rad"}


def unit_of(name: str) -> str:
    """SI unit of an input or output 'node.component' (the part after the last dot), or ''."""
    return _UNITS.get(name.rsplit(".", 1)[-1], "")


def frequency_response(a: np.ndarray, b: np.ndarray, c: np.ndarray, d: np.ndarray,
                       w: np.ndarray | Sequence[float]) -> np.ndarray:
    """G(i w) = C (i w I - A)^-1 B + D at the angular frequencies ``w`` [rad/s]: (n_w, n_y, n_u).

    Solves (i w I - A) X = B for each w rather than inverting: the inverse of a matrix with
    eigenvalues near i w loses the digits the solve keeps. The solves are batched in chunks
    that keep the stacked matrices to about 64 MB. ``ValueError`` at a ``w`` where i w I - A is
    singular: i w is a pole (w = 0 with rigid-body modes), where G is infinite."""
    a, b, c, d = (np.asarray(m, dtype=float) for m in (a, b, c, d))
    w = np.atleast_1d(np.asarray(w, dtype=float))
    n = a.shape[0]
    out = np.empty((w.size, c.shape[0], b.shape[1]), dtype=complex)
    chunk = max(1, int(4e6 // max(n * n, 1)))
    eye = np.eye(n)
    for start in range(0, w.size, chunk):
        ws = w[start:start + chunk]
        m = 1j * ws[:, None, None] * eye - a
        try:
            x = np.linalg.solve(m, np.broadcast_to(b, (ws.size, *b.shape)))
        except np.linalg.LinAlgError:
            # numpy names no matrix of the batch: find the first singular one for the message.
            bad = next((wk for wk, mk in zip(ws, m) if _singular(mk)), ws[0])
            raise ValueError(f"the frequency response is infinite at w = {bad:g} rad/s: i w "
                             f"is an eigenvalue of A (a pole on the imaginary axis; rigid-body "
                             f"modes have their poles at 0)") from None
        out[start:start + chunk] = c @ x + d
    return out


def _singular(m: np.ndarray) -> bool:
    try:
        np.linalg.solve(m, np.ones(m.shape[0]))
    except np.linalg.LinAlgError:
        return True
    return False


def transmission_zeros(a: np.ndarray, b: np.ndarray, c: np.ndarray, d: float = 0.0
                       ) -> np.ndarray:
    """Finite zeros of the single-input single-output system (A, b, c, d): the finite generalised
    eigenvalues s of the Rosenbrock pencil [[A - s I, b], [c, d]], sorted by magnitude.

    These are the invariant zeros: they include modes that b cannot excite or c cannot see
    (those cancel against poles in G). b and c are scaled to unit norm first (the zeros do not
    change) so that the pencil's blocks are of comparable size. An infinite eigenvalue comes out
    as alpha/beta with beta at round-off, i.e. |s| ~ ||pencil|| / eps ~ 1e16 ||A||, while the
    finite zeros of a structure lie within its pole magnitudes (at most ~||A||): anything beyond
    1e8 ||A|| (the geometric middle) counts as infinite. Raises ``ValueError`` when G is zero
    (b = 0 or c = 0, and d = 0): its pencil is singular and has no zeros to speak of."""
    from scipy.linalg import eig

    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float).reshape(-1)
    c = np.asarray(c, dtype=float).reshape(-1)
    nb, nc = np.linalg.norm(b), np.linalg.norm(c)
    if nb == 0.0 or nc == 0.0:
        if d == 0.0:
            raise ValueError("the transfer function is identically zero (B or C has no "
                             "entries for this channel): its zeros are undefined")
        return np.empty(0, dtype=complex)
    n = a.shape[0]
    pencil = np.zeros((n + 1, n + 1))
    pencil[:n, :n] = a
    pencil[:n, n] = b / nb
    pencil[n, :n] = c / nc
    pencil[n, n] = d / (nb * nc)
    mass = np.zeros((n + 1, n + 1))
    mass[:n, :n] = np.eye(n)
    (alpha, beta) = eig(pencil, mass, right=False, homogeneous_eigvals=True)
    limit = 1e8 * max(np.linalg.norm(a, 2), 1.0)
    finite = np.abs(alpha) < limit * np.abs(beta)
    zeros = alpha[finite] / beta[finite]
    return zeros[np.argsort(np.abs(zeros), kind="stable")]


def pole_table(poles: np.ndarray) -> list[tuple[float, float | None, float, complex]]:
    """One row per real pole and per complex pair (the member with Im >= 0), sorted by
    magnitude: ``(f_n [Hz], zeta or None, f_d [Hz], pole)`` with the natural frequency
    f_n = |s|/2 pi, the damping ratio zeta = -Re s/|s| (None for s = 0: a rigid-body mode) and
    the damped frequency f_d = Im s/2 pi."""
    poles = np.asarray(poles, dtype=complex)
    scale = max(float(np.max(np.abs(poles))), 1.0) if poles.size else 1.0
    # A pair's partner is its conjugate; keep the upper one and the real ones (Im at round-off).
    keep = poles[poles.imag >= -1e-12 * scale]
    keep = keep[np.argsort(np.abs(keep), kind="stable")]
    rows = []
    for s in keep:
        mag = abs(s)
        zeta = None if mag == 0.0 else -s.real / mag
        rows.append((mag / (2 * np.pi), zeta, max(s.imag, 0.0) / (2 * np.pi), complex(s)))
    return rows


@dataclass
class Linear:
    """``&linear`` results: n_lin linearisations at ``time`` (n_lin,) [s] with ``A``
    (n_lin, n_z, n_z), ``B`` (n_lin, n_z, n_u), ``C`` (n_lin, n_y, n_z), ``D`` (n_lin, n_y, n_u)
    and the names of the ``inputs`` (n_u) and ``outputs`` (n_y), 'node.component' as in the
    scene. ``k`` selects a linearisation (0-based); ``input``/``output`` take a name or an
    index."""

    path: str
    time: np.ndarray
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    inputs: list[str]
    outputs: list[str]
    attrs: dict[str, Any] = field(default_factory=dict)

    @property
    def n_models(self) -> int:
        return int(self.time.shape[0])

    @property
    def n_states(self) -> int:
        return int(self.A.shape[1])

    def index(self, k: int) -> int:
        """``k`` checked against the number of linearisations."""
        if not 0 <= k < self.n_models:
            times = ", ".join(f"{t:g}" for t in self.time)
            raise LinearModelError(f"{self.path}: linearisation index {k} out of range: the "
                                   f"file has {self.n_models} (0 to {self.n_models - 1}, at "
                                   f"t = {times} s)")
        return int(k)

    def _channel(self, name: str | int, names: list[str], what: str) -> int:
        if isinstance(name, (int, np.integer)):
            if 0 <= name < len(names):
                return int(name)
            raise LinearModelError(f"{self.path}: {what} index {name} out of range: "
                                   f"{len(names)} {what}s")
        if name in names:
            return names.index(name)
        raise LinearModelError(f"{self.path}: no {what} '{name}'; the {what}s are "
                               f"{', '.join(names)}")

    def input_index(self, name: str | int) -> int:
        return self._channel(name, self.inputs, "input")

    def output_index(self, name: str | int) -> int:
        return self._channel(name, self.outputs, "output")

    def matrices(self, k: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(A, B, C, D)`` of linearisation ``k``."""
        k = self.index(k)
        return self.A[k], self.B[k], self.C[k], self.D[k]

    def frequency_response(self, w: np.ndarray | Sequence[float], k: int = 0,
                           input: str | int | None = None,
                           output: str | int | None = None) -> np.ndarray:
        """G(i w) at angular frequencies ``w`` [rad/s] (see :func:`frequency_response`):
        (n_w, n_y, n_u), or (n_w,) for one ``input`` and ``output`` (give both or neither).
        ``ValueError`` naming the file at a pole on the imaginary axis (G infinite)."""
        a, b, c, d = self.matrices(k)
        if (input is None) != (output is None):
            raise ValueError("give both input and output, or neither")
        try:
            if input is None:
                return frequency_response(a, b, c, d, w)
            i, j = self.input_index(input), self.output_index(output)
            return frequency_response(a, b[:, [i]], c[[j], :], d[[j]][:, [i]], w)[:, 0, 0]
        except ValueError as e:
            raise ValueError(f"{self.path}: linearisation {k}: {e}") from None

    def dc_gain(self, k: int = 0) -> np.ndarray:
        """-C A^-1 B + D (n_y, n_u). ``ValueError`` when A is singular: a model with
        rigid-body modes (poles at 0) has no finite static gain."""
        a, b, c, d = self.matrices(k)
        try:
            return d - c @ np.linalg.solve(a, b)
        except np.linalg.LinAlgError:
            raise ValueError(f"{self.path}: A of linearisation {k} is singular (rigid-body "
                             f"modes, poles at 0): no finite DC gain") from None

    def poles(self, k: int = 0) -> np.ndarray:
        """Eigenvalues of A [1/s], sorted by magnitude."""
        ev = np.linalg.eigvals(self.matrices(k)[0])
        return ev[np.argsort(np.abs(ev), kind="stable")]

    def zeros(self, input: str | int, output: str | int, k: int = 0) -> np.ndarray:
        """Transmission zeros [1/s] of one input-output channel (:func:`transmission_zeros`)."""
        a, b, c, d = self.matrices(k)
        i, j = self.input_index(input), self.output_index(output)
        return transmission_zeros(a, b[:, i], c[j, :], float(d[j, i]))

    def to_scipy(self, k: int = 0):
        """``scipy.signal.StateSpace`` of linearisation ``k`` (continuous time)."""
        from scipy.signal import StateSpace

        return StateSpace(*self.matrices(k))

    def to_control(self, k: int = 0):
        """python-control ``StateSpace`` of linearisation ``k`` with the input and output
        names. python-control reserves '.' in signal names (it separates subsystem and
        signal), so 'tip.fy' becomes 'tip_fy'; the states are dq[i] and dqd[i]."""
        import control

        a, b, c, d = self.matrices(k)
        n = a.shape[0] // 2
        names = {}
        for kind, labels in (("input", self.inputs), ("output", self.outputs)):
            safe = [label.replace(".", "_") for label in labels]
            if len(set(safe)) != len(safe):
                raise LinearModelError(f"{self.path}: {kind} names {labels} are not unique "
                                       f"once '.' becomes '_' (python-control forbids '.')")
            names[kind + "s"] = safe
        states = [f"dq[{i}]" for i in range(n)] + [f"dqd[{i}]" for i in range(n)]
        return control.ss(a, b, c, d, states=states, name=f"linear{k}", **names)


def _strings(values: np.ndarray) -> list[str]:
    return [str(to_python(v)) for v in np.asarray(values).reshape(-1)]


def _read_linear(path: str, f: h5py.File) -> Linear | None:
    """The /linear group of an open result file, or None when there is none."""
    group = f.get("linear")
    if not isinstance(group, h5py.Group):
        return None
    data = {}
    for name in ("time", "A", "B", "C", "D", "inputs", "outputs"):
        obj = group.get(name)
        if not isinstance(obj, h5py.Dataset):
            raise ResultFileError(f"{path}: /linear has no dataset {name}")
        data[name] = obj[...]
    time = np.asarray(data["time"], dtype=float).reshape(-1)
    inputs, outputs = _strings(data["inputs"]), _strings(data["outputs"])
    n, nu, ny = time.shape[0], len(inputs), len(outputs)
    a = np.asarray(data["A"], dtype=float)
    nz = a.shape[1] if a.ndim == 3 else -1
    mats = {"A": a}
    for name, shape in (("A", (n, nz, nz)), ("B", (n, nz, nu)), ("C", (n, ny, nz)),
                        ("D", (n, ny, nu))):
        m = np.asarray(data[name], dtype=float)
        if nz < 0 or m.shape != shape:
            raise ResultFileError(f"{path}: /linear/{name} has shape {m.shape}, expected "
                                  f"(n_lin, ...) = {shape} from /linear/time ({n}), "
                                  f"{nu} inputs and {ny} outputs"
                                  + ("" if nz >= 0 else " (A must be (n_lin, n_z, n_z))"))
        mats[name] = m
    return Linear(path, time, mats["A"], mats["B"], mats["C"], mats["D"], inputs, outputs,
                  {k: to_python(v) for k, v in group.attrs.items()})


def read_linear(path: str | os.PathLike) -> Linear:
    """The ``&linear`` models of a result file; :class:`ResultFileError` naming the file when it
    is missing, not HDF5, has no ``/linear`` group or inconsistent shapes."""
    path = os.fspath(path)
    with open_h5(path) as f:
        linear = _read_linear(path, f)
    if linear is None:
        raise ResultFileError(f"{path}: no group /linear (the scene needs &linear)")
    return linear


def default_band(poles: np.ndarray) -> tuple[float, float]:
    """A frequency band [Hz] for a Bode plot: a decade below the lowest natural frequency of a
    non-rigid pole to a decade above the highest, but at most five decades in all (fine meshes
    and stiffness-proportional damping put real poles far above what matters)."""
    fn = np.abs(np.asarray(poles)) / (2 * np.pi)
    fn = fn[fn > 1e-9 * max(float(fn.max(initial=0.0)), 1.0)]
    if fn.size == 0:
        return 0.1, 100.0
    low = float(fn.min()) / 10
    return low, min(float(fn.max()) * 10, low * 1e5)


def response_grid(poles: np.ndarray, fmin: float, fmax: float, points: int) -> np.ndarray:
    """Log-spaced frequencies [Hz] with the damped frequencies of the poles inside the band
    added, so that lightly damped peaks are drawn at their height rather than between two
    samples."""
    grid = np.geomspace(fmin, fmax, points)
    fd = np.abs(np.asarray(poles).imag) / (2 * np.pi)
    fd = fd[(fd > fmin) & (fd < fmax)]
    return np.unique(np.concatenate([grid, fd]))


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_bode(f_hz: np.ndarray, g: np.ndarray, output: str, title: str = "",
              unit: str = "", poles: np.ndarray | None = None, dpi: int = 150) -> None:
    """Magnitude (log-log) and unwrapped phase [deg] of ``g`` (n_f,) at ``f_hz`` into the
    image ``output``; the damped frequencies of ``poles`` inside the band as dotted lines."""
    plt = _pyplot()
    fig, (ax_mag, ax_ph) = plt.subplots(2, 1, sharex=True, figsize=(7.0, 6.0))
    mag = np.abs(g)
    # An exact zero (a grid point on a zero without damping) cannot go on a log axis.
    ax_mag.loglog(f_hz, np.where(mag > 0, mag, np.nan), lw=1.3)
    ax_ph.semilogx(f_hz, np.degrees(np.unwrap(np.angle(g))), lw=1.3)
    if poles is not None:
        fd = np.abs(np.asarray(poles).imag) / (2 * np.pi)
        for fp in np.unique(fd[(fd >= f_hz[0]) & (fd <= f_hz[-1])]):
            for ax in (ax_mag, ax_ph):
                ax.axvline(fp, ls=":", lw=0.7, color="0.5")
    ax_mag.set_ylabel(f"|G| ({unit})" if unit else "|G|")
    ax_ph.set_ylabel("phase (deg)")
    ax_ph.set_xlabel("frequency (Hz)")
    ax_mag.set_title(title)
    for ax in (ax_mag, ax_ph):
        ax.grid(True, which="both", lw=0.3)
    fig.tight_layout()
    try:
        fig.savefig(output, dpi=dpi)
    finally:
        plt.close(fig)


def plot_pole_zero(poles: np.ndarray, zeros: np.ndarray, output: str, title: str = "",
                   radius: float | None = None, dpi: int = 150) -> int:
    """Poles (x) and zeros (o) in the s-plane [1/s] into the image ``output``; with ``radius``
    only those with |s| <= radius (the count left out is returned and noted in the title)."""
    plt = _pyplot()
    poles, zeros = np.asarray(poles, dtype=complex), np.asarray(zeros, dtype=complex)
    hidden = 0
    if radius is not None:
        hidden = int(np.sum(np.abs(poles) > radius) + np.sum(np.abs(zeros) > radius))
        poles, zeros = poles[np.abs(poles) <= radius], zeros[np.abs(zeros) <= radius]
    fig, ax = plt.subplots(figsize=(6.0, 6.0))
    ax.plot(poles.real, poles.imag, "x", color="C3", ms=8, mew=1.5, label="poles")
    ax.plot(zeros.real, zeros.imag, "o", color="C0", ms=7, mfc="none", mew=1.5, label="zeros")
    ax.axhline(0, color="0.6", lw=0.6)
    ax.axvline(0, color="0.6", lw=0.6)
    # Lightly damped structures put their poles at Re s ~ round-off of Im s: matplotlib would
    # scale the real axis to that noise, so it spans at least a tenth of the imaginary one.
    shown = np.concatenate([poles, zeros])
    if shown.size:
        span = 0.05 * max(float(np.max(np.abs(shown))), 1e-30)
        lo, hi = float(np.min(shown.real)), float(np.max(shown.real))
        pad = 0.05 * (hi - lo)
        ax.set_xlim(min(lo - pad, -span), max(hi + pad, span))
    ax.set_xlabel("Re s (1/s)")
    ax.set_ylabel("Im s (rad/s)")
    if hidden:
        title = f"{title}\n({hidden} beyond |s| = {radius:.3g} /s not shown)"
    ax.set_title(title)
    ax.grid(True, lw=0.3)
    ax.legend(fontsize=8, loc="best")
    fig.tight_layout()
    try:
        fig.savefig(output, dpi=dpi)
    finally:
        plt.close(fig)
    return hidden
