"""flexmor-vtk (flexmor.to_vtk) and flexmor-animate (flexmor.animate): the drawn geometry on a
synthetic model, then ParaView series and animations of real runs (FLEXMOR_BIN, set by CTest;
those tests are skipped where the binary does not exist)."""
import re
import subprocess
import sys
import xml.etree.ElementTree as ET

import h5py
import meshio
import numpy as np
import pytest
from PIL import Image

import flexmor
from flexmor import animate, to_vtk
from flexmor.model import ELEMENT_TYPE_IDS

from helpers import BIN, ROOT

needs_bin = pytest.mark.skipif(not BIN.is_file(), reason=f"no flexmor binary at {BIN}")

# The two-link benchmark, cut to 0.05 s with 6 output times: it starts at rest in its reference
# configuration (joint motions start at 0 with zero speed).
DYNAMIC_SCENE = re.sub(r"&dynamic[^/]*/", "&dynamic t_end = 0.05, output_dt = 0.01, "
                       "integrator = 'bdf', rtol = 1.0e-6, atol = 1.0e-8 /",
                       (ROOT / "input" / "two_link.nml").read_text())

# Statics only: a cantilever (2 beams, tip load giving a 1 mm deflection, 1e-3 of its length)
# and, apart from it, a truss pulled along its axis.
L, EI, P = 1.0, 7.0e10 * 1.0e-8, -2.1
EA_TRUSS, F_TRUSS, L_TRUSS = 7.0e10 * 1.0e-4, 7.0e3, 0.5
STATIC_SCENE = f"""&scene title = 'cantilever and truss' /
&node label = 'root', x = 0.0, y = 0.0, fixed = .true. /
&node label = 'tip', x = {L}, y = 0.0 /
&node label = 'anchor', x = 0.0, y = -1.0, fixed = .true. /
&node label = 'end', x = {L_TRUSS}, y = -1.0, fix_y = .true. /
&link label = 'beam', from = 'root', to = 'tip', n_elements = 2, E = 7.0e10, A = 1.0e-4,
      I = 1.0e-8, rho = 2700 /
&truss label = 'bar', from = 'anchor', to = 'end', E = 7.0e10, A = 1.0e-4, rho = 2700 /
&force node = 'tip', fy = {P} /
&force node = 'end', fx = {F_TRUSS} /
&static n_steps = 4 /
"""


def run_scene(tmp_path, name, text):
    scene = tmp_path / f"{name}.nml"
    scene.write_text(text)
    out = tmp_path / f"{name}.h5"
    proc = subprocess.run([str(BIN), str(scene), "-o", str(out), "-q"], capture_output=True,
                          text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    return out


@pytest.fixture(scope="module")
def dynamic_result(tmp_path_factory):
    return run_scene(tmp_path_factory.mktemp("dynamic"), "two_link_short", DYNAMIC_SCENE)


@pytest.fixture(scope="module")
def static_result(tmp_path_factory):
    return run_scene(tmp_path_factory.mktemp("static"), "cantilever", STATIC_SCENE)


def run_command(module, *args):
    return subprocess.run([sys.executable, "-m", f"flexmor.{module}", *map(str, args)],
                          capture_output=True, text=True, timeout=600)


def pvd_entries(path):
    return [(float(d.get("timestep")), d.get("file")) for d in ET.parse(path).iter("DataSet")]


def counts(model, segments):
    """Expected (points, line cells, vertex cells) of a model drawn with ``segments``."""
    n_beam, n_truss, n_hinge = (model.element_types.count(t) for t in ("beam", "truss", "hinge"))
    return model.n_nodes + n_beam * (segments - 1), n_beam * segments + n_truss, n_hinge


# --- a synthetic model (the /model layout of docs/output.md) ----------------------------------


def write_synthetic(path, angle):
    """Beams A-M-B (link 'arm'), a truss B-C and a hinge at A, rotated rigidly about the origin
    by ``angle`` (n_t,) rad: node rotations equal the angle, the hinge's own one too."""
    ref = np.array([0, 0, 0, 0.5, 0, 0, 1, 0, 0, 1, -0.5, 0.0])
    x = np.zeros((angle.size, ref.size))
    for k, a in enumerate(angle):
        rot = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
        for i in (0, 3, 6, 9):
            x[k, i:i + 2] = rot @ ref[i:i + 2]
        x[k, [2, 5, 8, 11]] = a
    s = h5py.string_dtype()
    with h5py.File(path, "w") as f:
        f.attrs["flexmor_version"] = flexmor.__version__
        f["time"] = np.linspace(0.0, 1.0, angle.size)
        f["x"] = x
        f["nodes/B/position"] = np.column_stack([x[:, 6], x[:, 7], np.zeros(angle.size)])
        m = f.create_group("model")
        m.attrs.update(n_nodes=4, n_elements=4, n_coordinates=12)
        m.create_dataset("coordinates/name", data=[f"c{i}" for i in range(12)], dtype=s)
        m["coordinates/reference"] = ref
        m["coordinates/kind"] = np.array([1, 2, 3, 1, 2, 3, 1, 2, 3, 1, 2, 3], dtype=np.int32)
        m.create_dataset("nodes/label", data=["A", "arm.1", "B", "C"], dtype=s)
        m["nodes/position"] = np.array([[0, 0, 0], [0.5, 0, 0], [1, 0, 0], [1, -0.5, 0.0]])
        m["nodes/coordinates"] = np.array([[1, 2, 3], [4, 5, 6], [7, 8, 9], [10, 11, 0]],
                                          dtype=np.int32)
        m.create_dataset("elements/label", data=["arm#1", "arm#2", "bar", "joint"], dtype=s)
        m.create_dataset("elements/type", data=["beam", "beam", "truss", "hinge"], dtype=s)
        m["elements/coordinates"] = np.array([[1, 2, 3, 4, 5, 6], [4, 5, 6, 7, 8, 9],
                                              [7, 8, 10, 11, 0, 0], [12, 3, 0, 0, 0, 0]],
                                             dtype=np.int32)
        m["elements/nodes"] = np.array([[1, 2], [2, 3], [3, 4], [1, 1]], dtype=np.int32)


def test_mesh_of_a_rigid_rotation_is_the_rotated_reference(tmp_path):
    path = tmp_path / "synthetic.h5"
    angle = np.array([0.0, 0.3, 2.5])
    write_synthetic(path, angle)
    result = flexmor.read_result(path)
    mesh = result.require_model().mesh(segments=4)
    assert (mesh.n_points, len(mesh.lines), len(mesh.vertices)) == counts(result.model, 4)
    ref = mesh.reference_points()
    # Reference: nodes where /model/nodes/position says, beam points evenly along the chords.
    np.testing.assert_array_equal(ref[:4], result.model.node_position)
    np.testing.assert_allclose(ref[4:7, 0], [0.125, 0.25, 0.375], atol=1e-15)
    np.testing.assert_allclose(ref[7:10, 0], [0.625, 0.75, 0.875], atol=1e-15)
    # A rigid rotation moves every point of the drawing (nodes and Hermite points) rigidly.
    for k, a in enumerate(angle):
        rot = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
        np.testing.assert_allclose(mesh.points(result.x[k])[:, :2], ref[:, :2] @ rot.T,
                                   atol=1e-14)
    lines, vertices = mesh.cell_element_types()
    assert lines.tolist() == [ELEMENT_TYPE_IDS["beam"]] * 8 + [ELEMENT_TYPE_IDS["truss"]]
    assert vertices.tolist() == [ELEMENT_TYPE_IDS["hinge"]] and mesh.vertices.tolist() == [0]


def test_hermite_end_tangents_follow_the_end_rotations(tmp_path):
    path = tmp_path / "synthetic.h5"
    write_synthetic(path, np.zeros(2))
    result = flexmor.read_result(path)
    x = result.model.reference.copy()
    x[[2, 5]] = 0.2, -0.1  # beam arm#1 (A to arm.1) bent: end rotations 0.2 and -0.1 rad
    pts = result.model.mesh(segments=400).points(x)[:, :2]
    first = pts[[0, 4]]          # A and the first interior point
    last = pts[[4 + 398, 1]]     # the last interior point of arm#1 and arm.1
    for (p, q), phi in ((first, 0.2), (last, -0.1)):
        d = q - p
        # Chord of a segment vs tangent: differs by O(h) of the curvature, h = 1/400.
        assert abs(np.arctan2(d[1], d[0]) - phi) < 2e-3


def test_vtk_refuses_a_file_without_model(tmp_path):
    old = tmp_path / "old.h5"
    with h5py.File(old, "w") as f:
        f.attrs["flexmor_version"] = "0.2.0"
        f["time"] = np.arange(3.0)
        f["nodes/tip/position"] = np.zeros((3, 3))
    for module, out in (("to_vtk", tmp_path / "vtk"), ("animate", tmp_path / "a.gif")):
        proc = run_command(module, old, "-o", out)
        assert proc.returncode == 2, proc.stderr
        lines = proc.stderr.strip().splitlines()
        assert len(lines) == 1 and "old.h5" in lines[0] and "/model" in lines[0], proc.stderr
        assert "Traceback" not in proc.stderr
    assert not (tmp_path / "a.gif").exists()


# --- real runs ----------------------------------------------------------------------------------


@needs_bin
def test_vtk_series_of_a_dynamic_run(dynamic_result, tmp_path):
    segments = 5
    proc = run_command("to_vtk", dynamic_result, "-o", tmp_path / "vtk", "--segments", segments)
    assert proc.returncode == 0, proc.stderr
    result = flexmor.read_result(dynamic_result)
    model = result.require_model()
    nt = result.time.size
    assert nt == 6 and result.x.shape == (nt, model.n_coordinates)

    pvd = tmp_path / "vtk" / "two_link_short.pvd"
    entries = pvd_entries(pvd)
    assert [t for t, _ in entries] == result.time.tolist()  # every output time, exactly
    n_points, n_lines, n_vertices = counts(model, segments)
    assert (n_lines, n_vertices) == (6 * segments, 2)  # 3 beams per link, 2 hinges

    beams = model.elements_of_type("beam")
    for k, (_, name) in enumerate(entries):
        mesh = meshio.read(pvd.parent / name)
        assert mesh.points.shape == (n_points, 3)
        cells = {block.type: block.data for block in mesh.cells}
        assert cells["line"].shape == (n_lines, 2) and cells["vertex"].shape == (n_vertices, 1)
        # The nodes are the first points: the output nodes where /nodes/<label>/position has them.
        for label, path in result.nodes.items():
            i = model.node_labels.index(label)
            np.testing.assert_allclose(mesh.points[i], path.position[k], rtol=0, atol=1e-12)
        if k == 0:
            first = mesh
    # First output time = the initial, undeformed state: the reference geometry, built here
    # from /model/nodes/position alone (beam points evenly along the straight chords).
    pos = model.node_position
    np.testing.assert_allclose(first.points[:model.n_nodes], pos, rtol=0, atol=1e-12)
    s = np.arange(1, segments) / segments
    for b, e in enumerate(beams):
        a, c = pos[model.element_nodes[e]]
        inner = first.points[model.n_nodes + b * (segments - 1):][:segments - 1]
        np.testing.assert_allclose(inner, a + s[:, None] * (c - a), rtol=0, atol=1e-12)
    assert np.abs(first.point_data["displacement"]).max() <= 1e-12
    types = np.concatenate(first.cell_data["element_type"])
    assert sorted(set(types.tolist())) == [ELEMENT_TYPE_IDS["beam"], ELEMENT_TYPE_IDS["hinge"]]
    # Later frames: displacement = position - reference, and the tip has moved.
    last = meshio.read(pvd.parent / entries[-1][1])
    np.testing.assert_allclose(last.point_data["displacement"], last.points - first.points,
                               rtol=0, atol=1e-12)
    assert np.linalg.norm(last.point_data["displacement"][model.node_labels.index("tip")]) > 1e-3


@needs_bin
def test_vtk_series_of_a_static_run_follows_the_beam_deflection(static_result, tmp_path):
    result = flexmor.read_result(static_result)
    assert result.time is None and result.static is not None
    pvd, n = to_vtk.write_series(result, tmp_path / "vtk", segments=8)
    entries = pvd_entries(pvd)
    assert n == 4 and [t for t, _ in entries] == [0.25, 0.5, 0.75, 1.0]
    mesh = meshio.read(pvd.parent / entries[-1][1])
    model = result.model
    assert mesh.points.shape[0] == counts(model, 8)[0]
    # Along the cantilever (linear range: w/L = 1e-3) the drawn points follow the exact cubic
    # w(x) = P x^2 (3L - x) / (6 EI); the nonlinear terms are ~(w/L)^2 = 1e-6 of w.
    beam = [model.node_labels.index(n) for n in ("root", "beam.1", "tip")]
    beam_points = np.concatenate([beam, model.n_nodes + np.arange(2 * 7)])
    xr = (mesh.points - mesh.point_data["displacement"])[beam_points, 0]  # reference x
    w_exact = P * xr**2 * (3 * L - xr) / (6 * EI)
    w_tip = P * L**3 / (3 * EI)
    assert abs(w_tip) > 0.9e-3
    np.testing.assert_allclose(mesh.point_data["displacement"][beam_points, 1], w_exact,
                               rtol=0, atol=1e-3 * abs(w_tip))
    # The truss: a straight line from the anchor to its end, stretched by F L / (EA).
    end = model.node_labels.index("end")
    stretch = F_TRUSS * L_TRUSS / EA_TRUSS
    np.testing.assert_allclose(mesh.point_data["displacement"][end], [stretch, 0, 0],
                               rtol=1e-6, atol=1e-6 * stretch)
    types = np.concatenate(mesh.cell_data["element_type"])
    assert (types == ELEMENT_TYPE_IDS["truss"]).sum() == 1


@needs_bin
def test_animation_gif_has_one_frame_per_output_time(dynamic_result, tmp_path):
    out = tmp_path / "anim.gif"
    proc = run_command("animate", dynamic_result, "-o", out, "--every", 2, "--scale", 20,
                       "--fps", 5, "--dpi", 40)
    assert proc.returncode == 0, proc.stderr
    result = flexmor.read_result(dynamic_result)
    expected = len(to_vtk.frame_indices(result.time.size, 2))
    assert expected == 4  # output times 0, 2, 4 and the last (5)
    with Image.open(out) as im:
        assert im.format == "GIF" and im.n_frames == expected
    # Drawn = reference + S x displacement at every point, within the fixed axes.
    values, drawn, ref, what, mesh = animate.drawn_points(result, 8, 20.0, 2)
    true = mesh.points(result.x[[0, 2, 4, 5]])
    np.testing.assert_allclose(drawn, ref + 20.0 * (true - ref), rtol=0, atol=1e-12)
    xmin, xmax, ymin, ymax = animate.limits(drawn, ref)
    assert what == "time" and values.tolist() == result.time[[0, 2, 4, 5]].tolist()
    assert xmin < drawn[..., 0].min() and drawn[..., 0].max() < xmax
    assert ymin < drawn[..., 1].min() and drawn[..., 1].max() < ymax


def test_animation_output_errors(tmp_path, monkeypatch, capsys):
    path = tmp_path / "synthetic.h5"
    write_synthetic(path, np.linspace(0.0, 0.5, 3))
    from matplotlib import animation as mpl_animation

    monkeypatch.setattr(mpl_animation.writers, "is_available", lambda name: False)
    assert animate.main([str(path), "-o", str(tmp_path / "a.mp4")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "ffmpeg" in err[0] and err[0].startswith("flexmor-animate: error:")
    assert animate.main([str(path), "-o", str(tmp_path / "a.avi")]) == 2
    assert "use .gif or .mp4" in capsys.readouterr().err
    assert animate.main([str(path), "-o", str(tmp_path / "no" / "a.gif")]) == 2
    assert "does not exist" in capsys.readouterr().err
    assert not any(tmp_path.glob("a.*"))


EXAMPLES = sorted(p for p in (ROOT / "input").glob("*.nml") if "&sweep" not in p.read_text())


@pytest.mark.parametrize("example", EXAMPLES, ids=lambda p: p.stem)
def test_every_example_is_read_converted_and_drawn(example, tmp_path):
    """Every scene of input/ (a dynamic run cut to 3 output steps) gives a result that the
    reader takes, flexmor-vtk converts and flexmor-animate draws, or, without a coordinate
    history (modal or buckling only), the one-line refusal. The reader refused the spatial
    scenes with joints at link ends, and both commands failed with a traceback on a model of
    bodies on nodes only (input/free_body.nml), before this test."""
    text = example.read_text()
    step = re.search(r"output_dt\s*=\s*([0-9.eE+-]+)", text)
    text = re.sub(r"t_end\s*=\s*[0-9.eE+-]+",
                  f"t_end = {3 * float(step.group(1) if step else 1e-3)!r}", text)
    nml = tmp_path / example.name
    nml.write_text(text)
    out = tmp_path / f"{example.stem}.h5"
    proc = subprocess.run([str(BIN), "-q", str(nml), "-o", str(out)], capture_output=True,
                          text=True, timeout=600, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    result = flexmor.read_result(out)
    history = result.x is not None or result.static is not None
    # --every: a static run's load steps are many frames; the first and the last suffice.
    for module, args in ((to_vtk, ["-o", str(tmp_path / "vtk"), "--every", "1000"]),
                         (animate, ["-o", str(tmp_path / "anim.gif"), "--dpi", "30",
                                    "--every", "1000"])):
        status = module.main([str(out), *args])
        assert status == (0 if history else 2), (module.__name__, status)
    if history:
        assert (tmp_path / "vtk" / f"{example.stem}.pvd").is_file()
        assert (tmp_path / "anim.gif").stat().st_size > 1000
