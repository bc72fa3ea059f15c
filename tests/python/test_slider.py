"""The &slider group: a node on a straight guide (docs/input.md, &slider).

A block of mass m on a guide inclined at 30 degrees, held by a truss spring along the guide:
its static sag under gravity, its two frequencies (along the guide from the truss, across it
from a dynamic slider's guide spring) against the closed forms, the result file's model; then
every input error of the group, each a one-line message naming the group and variable."""
import math

import numpy as np
import pytest

from helpers import assert_clean_error, run_scene

h5py = pytest.importorskip("h5py")

ALPHA = math.radians(30.0)
M, EA, L0, K_GUIDE, G = 2.0, 1.0e4, 0.5, 3.0e3, 9.81
C, S = math.cos(ALPHA), math.sin(ALPHA)

#: The truss runs from a fixed anchor to the block along the guide.
BLOCK = f"""&scene gravity = 0.0, {-G} /
&node label = 'anchor', x = 0.0, y = 0.0, fixed = .true. /
&node label = 'block', x = {L0 * C!r}, y = {L0 * S!r} /
&truss label = 'spring', from = 'anchor', to = 'block', E = {EA}, A = 1.0, mode = 'dynamic' /
&slider label = 'guide', node = 'block', direction = {2 * C!r}, {2 * S!r} /
&mass node = 'block', m = {M} /
"""


def test_block_static_sag(tmp_path):
    """Gravity's component along the guide, m g sin(alpha), stretches the truss by
    m g sin(alpha) L0 / EA (compresses: the block slides down): 4.9e-4 m. The truss is
    geometrically exact and linear in its elongation, so only the Newton tolerance remains
    (1e-11 max(1e-3, max |x0|) = 4e-12 m); allowed 1e-10 m. The block stays on the guide."""
    proc, out = run_scene(tmp_path, BLOCK + "&static n_steps = 1 /\n")
    assert proc.returncode == 0, proc.stderr
    with h5py.File(out) as f:
        pos = f["static/nodes/block/position"][-1, :2]
    along = pos @ np.array([C, S]) - L0
    across = pos @ np.array([-S, C])
    assert abs(along + M * G * S * L0 / EA) <= 1e-10, along
    assert abs(across) <= 1e-10, across


def test_dynamic_guide_spring_frequencies(tmp_path):
    """A dynamic slider is a spring of K_GUIDE across the guide: with the truss along it the
    block has two modes, sqrt(EA/L0/m) along and sqrt(K_GUIDE/m) across (no gravity, no
    preload: the truss adds no transverse stiffness). Eigenvalues of a 2x2 problem: 1e-9
    relative allowed. The mode shapes point along and across the guide."""
    text = BLOCK.replace(f"gravity = 0.0, {-G}", "gravity = 0.0, 0.0").replace(
        "direction =", f"mode = 'dynamic', stiffness = {K_GUIDE}, direction =") + "&modal /\n"
    proc, out = run_scene(tmp_path, text)
    assert proc.returncode == 0, proc.stderr
    with h5py.File(out) as f:
        f_hz = f["modal/frequency_hz"][:]
        shapes = f["modal/nodes/block/shape"][:, :2]
        types = [t.decode().strip() if isinstance(t, bytes) else t.strip()
                 for t in f["model/elements/type"][:]]
    expected = sorted([math.sqrt(EA / L0 / M), math.sqrt(K_GUIDE / M)])
    assert np.allclose(f_hz * 2 * math.pi, expected, rtol=1e-9, atol=0), (f_hz, expected)
    directions = {round(abs(math.atan2(y, x)), 6) for x, y in shapes}
    assert directions == {round(ALPHA, 6), round(ALPHA + math.pi / 2, 6)}, shapes
    assert types == ["truss", "slider"]


def test_python_package_reads_sliders(tmp_path):
    """flexmor.read_result reads a model with a slider: the element names its node twice."""
    flexmor = pytest.importorskip("flexmor")
    proc, out = run_scene(tmp_path, BLOCK + "&static n_steps = 1 /\n")
    assert proc.returncode == 0, proc.stderr
    model = flexmor.read_result(out).model
    e = model.element_labels.index("guide")
    assert model.element_types[e] == "slider"
    block = model.node_labels.index("block")
    assert list(model.element_nodes[e]) == [block, block]


GOOD = BLOCK + "&static n_steps = 1 /\n"
CASES = {
    "unknown node": (GOOD.replace("node = 'block', direction", "node = 'blok', direction"),
                     ["&slider 'guide'", "'node'", "'blok'"]),
    "zero direction": (GOOD.replace(f"direction = {2 * C!r}, {2 * S!r}", "direction = 0.0, 0.0"),
                       ["&slider #1", "'direction'", "zero vector"]),
    "one direction value": (GOOD.replace(f"direction = {2 * C!r}, {2 * S!r}", "direction = 1.0"),
                            ["&slider #1", "'direction'", "2 values"]),
    "missing direction": (GOOD.replace(f", direction = {2 * C!r}, {2 * S!r}", ""),
                          ["&slider #1", "'direction'"]),
    "missing node": (GOOD.replace("node = 'block', direction", "direction"),
                     ["&slider #1", "'node'", "missing"]),
    "bad mode": (GOOD.replace("direction =", "mode = 'prescribed', direction ="),
                 ["&slider #1", "'mode'", "'prescribed'"]),
    "stiffness with rigid mode": (GOOD.replace("direction =", "stiffness = 1.0, direction ="),
                                  ["&slider #1", "'stiffness'", "dynamic"]),
    "damping with released mode": (
        GOOD.replace("direction =", "mode = 'released', damping = 0.1, direction ="),
        ["&slider #1", "'damping'", "dynamic"]),
    "negative stiffness": (
        GOOD.replace("direction =", "mode = 'dynamic', stiffness = -1.0, direction ="),
        ["&slider #1", "'stiffness'", "negative"]),
    "damping without stiffness": (
        GOOD.replace("direction =", "mode = 'dynamic', damping = 0.1, direction ="),
        ["&slider 'guide'", "'damping'", "stiffness > 0"]),
    "on a clamped node (over-constrained)": (
        GOOD.replace("x = " + repr(L0 * C), "fixed = .true., x = " + repr(L0 * C)),
        ["do not solve", "over-constrained"]),
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_bad_slider(tmp_path, name):
    text, fragments = CASES[name]
    assert text != GOOD, "the case did not change the scene"
    proc, out = run_scene(tmp_path, text)
    assert_clean_error(proc, out, *fragments)



#: A carriage on a guide along x (prismatic joint of a body: slider plus fix_phi) carrying a
#: rigid upright beam, held by a truss spring from a fixed anchor.
CARRIAGE = """&node label = 'anchor', x = -0.5, y = 0.0, fixed = .true. /
&node label = 'cart', x = 0.0, y = 0.0, fix_phi = .true. /
&node label = 'top', x = 0.0, y = 0.4 /
&link label = 'post', from = 'cart', to = 'top', E = 7.0e10, A = 1.0e-4, I = 1.0e-9,
      rho = 2700, bending = 'rigid' /
&truss label = 'spring', from = 'anchor', to = 'cart', E = 2.0e4, A = 1.0, mode = 'dynamic' /
&slider label = 'rail', node = 'cart', direction = 1.0, 0.0 /
&mass node = 'cart', m = 1.5 /
&modal /
"""


def test_prismatic_joint_of_a_body(tmp_path):
    """Slider plus fix_phi: the carriage and its rigid post only translate along x, so the one
    frequency is sqrt(k / (m_cart + rhoA l)) (the post's consistent mass, translated rigidly,
    is its whole mass), k = EA/l0 of the truss; a 1x1 eigenproblem, 1e-9 relative allowed.
    Without fix_phi the post could turn about the cart: a mechanism."""
    proc, out = run_scene(tmp_path, CARRIAGE)
    assert proc.returncode == 0, proc.stderr
    with h5py.File(out) as f:
        f_hz = f["modal/frequency_hz"][:]
    k, mass = 2.0e4 / 0.5, 1.5 + 2700 * 1.0e-4 * 0.4
    assert f_hz.shape == (1,)
    assert abs(f_hz[0] * 2 * math.pi / math.sqrt(k / mass) - 1) <= 1e-9, f_hz
    (tmp_path / "free").mkdir()
    proc, out = run_scene(tmp_path / "free", CARRIAGE.replace(", fix_phi = .true.", ""))
    assert proc.returncode == 2 and "mechanism" in proc.stderr, proc.stderr
    assert not out.exists()
