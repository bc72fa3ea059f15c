"""The Python package on spatial results (&scene dimension = 3): flexmor.model reads the
spatial /model and draws spatial beams along cubic Hermite curves with end tangents
l0 R(lambda) ex0, checked against closed forms (a cantilever under a tip force in z, the
roll-up of input/roll_up.nml), a rigid rotation, malformed files; flexmor-vtk and
flexmor-animate on spatial results. Needs the flexmor binary (FLEXMOR_BIN)."""
import math
import shutil
import xml.etree.ElementTree as ET

import h5py
import meshio
import numpy as np
import pytest
from PIL import Image

import flexmor
from flexmor import animate, to_vtk
from flexmor.model import ELEMENT_TYPE_IDS, rotate

from helpers import BIN, ROOT, run_scene

pytestmark = pytest.mark.skipif(not BIN.is_file(), reason=f"no flexmor binary at {BIN}")

# A straight cantilever of ONE spatial beam along (0.6, 0.8, 0) in the x-y plane (so its chord
# direction ex0 is not a coordinate axis), loaded at the tip by F in z. The section y axis
# defaults to z x chord, so z is the section z axis and the load bends about y: EI_y. I (about
# z) differs from Iy so that the wrong one would show.
L, E, A, I_Z, I_Y, J, G, RHO, K = 1.0, 7.0e10, 1.0e-3, 3.0e-9, 1.0e-9, 1.0e-9, 2.6e10, 2700.0, 5 / 6
CHORD = np.array([0.6, 0.8, 0.0])
# F for a tip deflection of 1e-3 L: F L^3 / (3 E I_y) = 1e-3 L.
F = 3 * E * I_Y * 1.0e-3 / L**2
SEGMENTS = 8


def cantilever(analysis, n=1, scene_extra="", loads=f"&force node = 'tip', fz = {F} /\n"):
    tip = L * CHORD
    return (f"&scene title = 'spatial cantilever', dimension = 3{scene_extra} /\n"
            "&node label = 'root', x = 0, y = 0, z = 0, fixed = .true. /\n"
            f"&node label = 'tip', x = {tip[0]}, y = {tip[1]}, z = {tip[2]} /\n"
            f"&link label = 'beam', from = 'root', to = 'tip', n_elements = {n},\n"
            f"      E = {E}, A = {A}, I = {I_Z}, Iy = {I_Y}, J = {J}, G = {G}, rho = {RHO} /\n"
            + loads + analysis + "&output nodes = 'tip' /\n")


@pytest.fixture(scope="module")
def static_result(tmp_path_factory):
    proc, out = run_scene(tmp_path_factory.mktemp("cantilever"),
                          cantilever("&static n_steps = 2 /\n"), name="cantilever")
    assert proc.returncode == 0, proc.stderr
    return out


@pytest.fixture(scope="module")
def dynamic_result(tmp_path_factory):
    """Two elements released from rest under gravity in -z: 5 output times over 0.02 s."""
    text = cantilever("&dynamic t_end = 0.02, output_dt = 0.005 /\n", n=2,
                      scene_extra=", gravity = 0, 0, -9.81", loads="")
    proc, out = run_scene(tmp_path_factory.mktemp("falling"), text, name="falling")
    assert proc.returncode == 0, proc.stderr
    return out


@pytest.fixture(scope="module")
def roll_up_result(tmp_path_factory):
    text = (ROOT / "input" / "roll_up.nml").read_text()
    proc, out = run_scene(tmp_path_factory.mktemp("roll_up"), text, name="roll_up")
    assert proc.returncode == 0, proc.stderr
    return out


def test_spatial_model_tables(static_result):
    model = flexmor.read_result(static_result).require_model()
    assert model.dimension == 3 and model.spatial
    assert model.node_coordinates.shape == (2, 5) and model.element_coordinates.shape[1] == 14
    assert sorted(model.element_types) == ["beam3d", "euler"]  # the tip's |lambda| = 1
    root, tip = (model.node_labels.index(n) for n in ("root", "tip"))
    np.testing.assert_array_equal(model.node_position[tip], L * CHORD)
    # x, y, no planar rotation, z, then four Euler parameters from (1, 0, 0, 0).
    ix, iy, iphi, iz, il = model.node_coordinates[tip]
    assert iphi == -1 and model.kind[[ix, iy, iz]].tolist() == [1, 2, 4]
    assert model.kind[il:il + 4].tolist() == [5] * 4
    assert model.reference[il:il + 4].tolist() == [1, 0, 0, 0]
    euler = model.element_types.index("euler")
    assert model.element_coordinates[euler, :4].tolist() == list(range(il, il + 4))
    assert model.element_nodes[euler].tolist() == [-1, -1]  # no position: no node
    beam = model.element_types.index("beam3d")
    assert model.element_nodes[beam].tolist() == [root, tip]
    mesh = model.mesh(SEGMENTS)
    lines, vertices = mesh.cell_element_types()
    assert lines.tolist() == [ELEMENT_TYPE_IDS["beam3d"]] * SEGMENTS and vertices.size == 0


def test_cantilever_curve_follows_euler_bernoulli(static_result):
    """Cubic Hermite interpolation reproduces the Euler-Bernoulli cubic
    w(x) = F x^2 (3L - x) / (6 E I_y) exactly from exact end values and slopes, so what is left
    is the beam's physics beyond E-B. Shear (G given: the spatial beam is shear-flexible)
    moves the tip by F L / (k G A) with the section rotations unchanged, so the drawn curve is
    w_EB + H01(s) F L / (k G A): relative to w_tip at most 3 E I_y / (k G A L^2) = 9.7e-6, at
    the midpoint (H01 = 1/2, w = 5/16 w_tip) 1.55e-5 of w(L/2). The geometric non-linearity is
    of order theta_tip^2 = (F L^2 / (2 E I_y))^2 = 2.3e-6. Bounds: 10 x their sum."""
    result = flexmor.read_result(static_result)
    model = result.require_model()
    mesh = model.mesh(SEGMENTS)
    n = model.n_nodes
    tip = model.node_labels.index("tip")
    ref = mesh.reference_points()
    # The reference curve: the straight chord, points evenly along it.
    s = np.arange(1, SEGMENTS) / SEGMENTS
    # Both sides are two or three roundings of numbers up to L (ends, differences, s times
    # them): they differ by up to ~4 eps L; bound 10x, 40 eps L = 8.9e-15 L (1e-15 was 4.5 eps,
    # within 9x of the observed 1.1e-16). A misplaced point is off by O(L / SEGMENTS).
    np.testing.assert_allclose(ref[n:], s[:, None] * L * CHORD, rtol=0,
                               atol=40 * np.finfo(float).eps * L)
    pts = mesh.points(result.static.x[-1])
    # The drawn tip is the node's output position.
    np.testing.assert_array_equal(pts[tip], result.static.nodes["tip"].position[-1])

    w_tip = F * L**3 / (3 * E * I_Y)
    shear = 3 * E * I_Y / (K * G * A * L**2)
    nonlinear = (F * L**2 / (2 * E * I_Y))**2
    assert shear < 1e-4 and nonlinear < 1e-4
    x = s * L
    w = F * x**2 * (3 * L - x) / (6 * E * I_Y)
    h01 = 3 * s**2 - 2 * s**3
    dev = pts[n:, 2] - w
    assert np.all(np.abs(dev) <= 10 * (h01 * shear + nonlinear) * w_tip), dev / w_tip
    mid = SEGMENTS // 2 - 1  # s = 1/2
    rel_mid = abs(dev[mid]) / w[mid]
    assert rel_mid <= 10 * (0.5 * shear * w_tip / w[mid] + nonlinear), rel_mid  # 1.45e-5 seen
    # The deflection is in z only: the curve stays over its chord (in-plane bending would need
    # EI_z and a wrong rotation convention would tilt the tangents out of the x-z plane).
    lateral = pts[n:, :2] @ np.array([-CHORD[1], CHORD[0]])
    assert np.abs(lateral).max() <= 1e-12 * L
    # The tip's section turns by F L^2 / (2 E I_y) (shear leaves section rotations alone),
    # upward for fz > 0: R(lambda_tip) ex0 rises in z (observed 1.2e-6 relative).
    lam = result.static.nodes["tip"].orientation[-1]
    tangent = rotate(lam, CHORD)
    assert tangent[2] == pytest.approx(F * L**2 / (2 * E * I_Y), rel=10 * nonlinear)


def test_rigid_rotation_moves_the_drawing_rigidly(static_result):
    """Positions rotated by Q and every node's Euler parameters set to those of Q (scaled by
    1.3: the drawing normalises lambda) rotate every drawn point by Q: the Hermite tangents
    turn with R(lambda) ex0, in the convention of elements_rotation (R(p) rotates by p)."""
    model = flexmor.read_result(static_result).require_model()
    mesh = model.mesh(SEGMENTS)
    ref = mesh.reference_points()
    axis = np.array([1.0, -2.0, 0.5]) / np.linalg.norm([1.0, -2.0, 0.5])
    angle = 2.2
    q = np.concatenate([[math.cos(angle / 2)], math.sin(angle / 2) * axis])
    # Rodrigues' formula: Q independently of the quaternion form under test.
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    rot = np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k
    x = model.reference.copy()
    xyz = model.node_coordinates[:, [0, 1, 3]]
    x[xyz] = model.node_position @ rot.T
    for il in model.node_coordinates[:, 4]:
        if il >= 0:
            x[il:il + 4] = 1.3 * q
    np.testing.assert_allclose(mesh.points(x), ref @ rot.T, rtol=0, atol=1e-14)
    # Zero Euler parameters are no rotation: a clear error, not a collapsed drawing.
    x[model.node_coordinates[model.node_labels.index("tip"), 4]:][:4] = 0.0
    with pytest.raises(ValueError, match="Euler parameters"):
        mesh.points(x)


def test_roll_up_draws_a_circle(roll_up_result):
    """mz = 2 pi E I / L rolls the strip of n equal elements into a circle of radius
    R = L / (2 pi) about (0, R, 0). Two effects separate the drawing from it:
    - the nodes: with no axial force the elongation mode of elements_beam3d vanishes,
      l = l0 - (2 e5^2 + e5 e6 + 2 e6^2) / (30 l0) with e5 = e6 = l0 a (angle form, a = pi / n
      the half-angle per element), so the chord is l = l0 (1 - a^2 / 6) and the closed polygon
      has circumradius R_n = l / (2 sin a) = R a (1 - a^2/6) / sin a (= R (1 - a^4/120 + ...),
      -2.0e-4 here); centre (0, R_n, 0);
    - the Hermite curve between nodes on a circle of radius R_n, end tangents of length
      l0 = 2 a R tangent to it: at s = 1/2 its radius is R_n (cos a + (k/4) sin a), k = l0/R_n
      (1 - a^4/24 + ..., -9.7e-4 here); every interior point follows the same closed form.
    So every drawn point is within R_n |rho(s) - 1| of the circle about (0, R_n) (checked to
    the solver's 1e-6 R), and within R_n max|rho - 1| + 2 |R_n - R| (1.37e-3 R) of the exact
    circle (observed 1.355e-3 R)."""
    result = flexmor.read_result(roll_up_result)
    model = result.require_model()
    mesh = model.mesh(SEGMENTS)
    root, tip = (model.node_labels.index(n) for n in ("root", "tip"))
    length = float(np.linalg.norm(model.node_position[tip] - model.node_position[root]))
    n = len(mesh.beams)
    assert (length, n) == (1.5, 8)
    r_exact = length / (2 * math.pi)
    a = math.pi / n
    r_nodes = r_exact * a * (1 - a**2 / 6) / math.sin(a)
    k = 2 * a * r_exact / r_nodes
    # Radius rho(s) of the Hermite curve through (cos a, -+ sin a) with tangents
    # k (sin a, cos a), k (-sin a, cos a) on the unit circle.
    s = np.arange(1, SEGMENTS) / SEGMENTS
    h = np.stack([2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s, -2 * s**3 + 3 * s**2,
                  s**3 - s**2])
    p1, p2 = np.array([math.cos(a), -math.sin(a)]), np.array([math.cos(a), math.sin(a)])
    t1, t2 = k * np.array([math.sin(a), math.cos(a)]), k * np.array([-math.sin(a), math.cos(a)])
    rho = np.linalg.norm(np.outer(h[0], p1) + np.outer(h[1], t1) + np.outer(h[2], p2)
                         + np.outer(h[3], t2), axis=1)
    assert rho.min() == pytest.approx(math.cos(a) + k / 4 * math.sin(a), rel=1e-15)

    pts = mesh.points(result.static.x[-1])
    # Bending about z: the strip stays in z = 0, to round-off of the Newton solution.
    assert np.abs(pts[:, 2]).max() < 1e-12 * length
    np.testing.assert_array_equal(pts[tip], result.static.nodes["tip"].position[-1])
    about_nodes = np.linalg.norm(pts - [0.0, r_nodes, 0.0], axis=1)
    np.testing.assert_allclose(about_nodes[:model.n_nodes], r_nodes, rtol=0, atol=1e-6 * r_exact)
    np.testing.assert_allclose(about_nodes[model.n_nodes:].reshape(n, -1), np.tile(r_nodes * rho, (n, 1)),
                               rtol=0, atol=1e-6 * r_exact)
    about_exact = np.abs(np.linalg.norm(pts - [0.0, r_exact, 0.0], axis=1) - r_exact)
    bound = r_nodes * (1 - rho.min()) + 2 * abs(r_nodes - r_exact) + 1e-6 * r_exact
    assert about_exact.max() <= bound, (about_exact.max() / r_exact, bound / r_exact)
    assert about_exact.max() > 0.5 * bound  # the derivation, not a loose bound, explains it
    # The reference strip is straight along x.
    ref = mesh.reference_points()
    assert np.abs(ref[:, 1:]).max() == 0.0


def test_vtk_of_a_spatial_result_has_z(dynamic_result, tmp_path):
    result = flexmor.read_result(dynamic_result)
    model = result.require_model()
    pvd, count = to_vtk.write_series(result, tmp_path / "vtk", segments=4)
    assert count == result.time.size == 5
    entries = [(float(d.get("timestep")), d.get("file")) for d in ET.parse(pvd).iter("DataSet")]
    assert [t for t, _ in entries] == result.time.tolist()
    mesh = model.mesh(4)
    tip = model.node_labels.index("tip")
    for k, (_, name) in enumerate(entries):
        vtu = meshio.read(pvd.parent / name)
        np.testing.assert_allclose(vtu.points, mesh.points(result.x[k]), rtol=0, atol=1e-15)
        np.testing.assert_allclose(vtu.points[tip], result.nodes["tip"].position[k], rtol=0,
                                   atol=1e-15)
        types = np.concatenate(vtu.cell_data["element_type"])
        assert set(types.tolist()) == {ELEMENT_TYPE_IDS["beam3d"]}
    last = meshio.read(pvd.parent / entries[-1][1])
    # Falling under gravity in -z: every point but the clamped root has moved down.
    assert last.points[:, 2].max() == 0.0 and last.points[:, 2].min() < -1e-3
    assert (last.point_data["displacement"][:, 2] < 0).sum() == mesh.n_points - 1


def test_animation_of_a_spatial_result(dynamic_result, roll_up_result, tmp_path):
    out = tmp_path / "falling.gif"
    proc_status = animate.main([str(dynamic_result), "-o", str(out), "--scale", "50",
                                "--dpi", "40", "--view", "20", "-120"])
    assert proc_status == 0
    with Image.open(out) as im:
        assert im.format == "GIF" and im.n_frames == 5
    # Drawn = reference + S x displacement in all three components, inside the cube.
    result = flexmor.read_result(dynamic_result)
    values, drawn, ref, what, mesh = animate.drawn_points(result, 8, 50.0, 1)
    np.testing.assert_allclose(drawn, ref + 50.0 * (mesh.points(result.x) - ref), rtol=0,
                               atol=1e-12)
    assert np.abs(drawn[..., 2]).max() > 0.05
    lo, hi = animate.limits_3d(drawn, ref)
    assert np.all(lo < drawn.min(axis=(0, 1))) and np.all(drawn.max(axis=(0, 1)) < hi)
    assert np.ptp(hi - lo) == pytest.approx(0.0, abs=1e-15)  # a cube: equal scales
    # The static roll-up: one frame per load step, every 8th of 16 and the last: 3.
    out = tmp_path / "roll_up.gif"
    assert animate.main([str(roll_up_result), "-o", str(out), "--every", "8", "--dpi", "40"]) == 0
    with Image.open(out) as im:
        assert im.n_frames == 3


def _broken_copy(source, tmp_path, edit):
    path = tmp_path / "broken.h5"
    shutil.copy(source, path)
    with h5py.File(path, "r+") as f:
        edit(f)
    return path


def _replace(f, name, data):
    del f[name]
    f[name] = data


@pytest.mark.parametrize("edit, fragments", [
    (lambda f: f["model"].attrs.modify("dimension", 4), ["/model", "dimension = 4"]),
    (lambda f: _replace(f, "model/nodes/coordinates", f["model/nodes/coordinates"][:, :3]),
     ["/model/nodes/coordinates", "shape"]),
    # The beam's first Euler parameter moved by one: no longer four of its node's.
    (lambda f: _replace(f, "model/elements/coordinates", np.where(
        f["model/elements/coordinates"][...] == f["model/nodes/coordinates"][0, 4],
        f["model/nodes/coordinates"][0, 4] + 1, f["model/elements/coordinates"][...])),
     ["/model/elements/coordinates", "beam3d 'beam#1'"]),
    # The beam named with its nodes swapped: its ends are not those nodes' coordinates.
    (lambda f: _replace(f, "model/elements/nodes", f["model/elements/nodes"][...][:, ::-1]),
     ["/model/elements/coordinates", "beam3d 'beam#1' does not use", "node 'tip'"]),
    (lambda f: _replace(f, "model/elements/type", np.array(
        [b"beam" if t == b"beam3d" else t for t in f["model/elements/type"][...]])),
     ["/model/elements/type", "'beam'", "spatial"]),
    (lambda f: _replace(f, "model/coordinates/kind", np.where(
        f["model/coordinates/kind"][...] == 4, 3, f["model/coordinates/kind"][...])),
     ["/model/coordinates/kind"]),
])
def test_malformed_spatial_model(static_result, tmp_path, edit, fragments):
    path = _broken_copy(static_result, tmp_path, edit)
    with pytest.raises(flexmor.ResultFileError) as info:
        flexmor.read_result(path)
    message = str(info.value)
    assert "\n" not in message and str(path) in message
    for fragment in fragments:
        assert fragment in message, message


def test_hinged_spatial_model_is_read_and_drawn(tmp_path):
    """A link hinged at a node (input/two_link_spatial.nml: revolute joints at the base and the
    elbow) has Euler parameters of its own at that end, not the node's: the reader accepts it
    (it refused every such file before) and the drawing's first points are the nodes, at the
    positions of the result file."""
    text = (ROOT / "input" / "two_link_spatial.nml").read_text()
    text = text.replace("t_end = 0.7", "t_end = 0.05")
    assert "t_end = 0.05" in text
    proc, out = run_scene(tmp_path, text, name="hinged")
    assert proc.returncode == 0, proc.stderr
    result = flexmor.read_result(out)
    model = result.require_model()
    base = model.node_labels.index("base")
    hinged = [e for e in range(len(model.element_labels))
              if model.element_types[e] == "beam3d" and model.element_nodes[e][0] == base]
    assert hinged, "link1's first beam starts at the base"
    own = model.element_coordinates[hinged[0]][3:7]
    assert not np.array_equal(own, model.node_coordinates[base, 4] + np.arange(4))
    points = model.mesh(SEGMENTS).points(result.x)
    tip = model.node_labels.index("tip")
    np.testing.assert_allclose(points[:, tip], result.nodes["tip"].position, rtol=0, atol=1e-14)
