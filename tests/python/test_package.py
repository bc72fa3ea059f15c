"""The flexmor Python package: version, console commands, read_result on a real run and on
files that are not flexmor results, and `pip install` of the repository into a fresh venv."""
import importlib
import importlib.metadata
import importlib.util
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest

import flexmor

from helpers import BIN, ROOT

VERSION = (ROOT / "VERSION").read_text().strip()

# A cantilever with a tip mass: &static (3 load steps), &modal and a short &dynamic run.
SCENE = """&scene title = 'cantilever, all analyses' /
&node label = 'root', x = 0.0, y = 0.0, fixed = .true. /
&node label = 'tip', x = 1.0, y = 0.0 /
&link label = 'beam', from = 'root', to = 'tip', n_elements = 2, E = 7.0e10, A = 1.0e-4,
      I = 1.0e-8, rho = 2700 /
&mass node = 'tip', m = 1.0 /
&force node = 'tip', fy = -1.0 /
&static n_steps = 3 /
&modal n_modes = 2 /
&dynamic t_end = 0.02, output_dt = 0.005 /
&output nodes = 'tip', 'beam.1' /
"""


def test_version_is_the_repository_version():
    assert flexmor.__version__ == VERSION
    # The tests must exercise the repository's copy (CTest sets PYTHONPATH to python/).
    assert Path(flexmor.__file__).resolve().parent == ROOT / "python" / "flexmor"


def test_console_commands_resolve():
    tomllib = pytest.importorskip("tomllib")
    with open(ROOT / "pyproject.toml", "rb") as f:
        scripts = tomllib.load(f)["project"]["scripts"]
    assert {"flexmor-vtk", "flexmor-animate", "flexmor-seed-fig2"} <= set(scripts)
    assert not {"flexmor", "flexmor-sweep"} & set(scripts)  # the Fortran executables
    for name, target in scripts.items():
        module, func = target.split(":")
        assert callable(getattr(importlib.import_module(module), func)), name
        proc = subprocess.run([sys.executable, "-m", module, "--help"], capture_output=True,
                              text=True, timeout=120)
        assert proc.returncode == 0 and f"usage: {name}" in proc.stdout, (name, proc.stderr)


def test_no_sys_path_edits():
    # The package is imported as a package: nothing may put folders on sys.path by hand.
    pattern = re.compile(r"sys\.path\.(insert|append|extend)|sys\.path\s*[+]?=")
    files = [*(ROOT / "python").rglob("*.py"), *(ROOT / "scripts").glob("*.py"),
             *(ROOT / "tests" / "python").glob("*.py")]
    offenders = [str(p.relative_to(ROOT)) for p in files
                 if p.name != Path(__file__).name and pattern.search(p.read_text())]
    assert offenders == []


@pytest.mark.skipif(not BIN.is_file(), reason=f"no flexmor binary at {BIN}")
def test_read_result_of_a_real_run(tmp_path):
    scene = tmp_path / "cantilever.nml"
    scene.write_text(SCENE)
    out = tmp_path / "cantilever.h5"
    proc = subprocess.run([str(BIN), str(scene), "-o", str(out), "-q"], capture_output=True,
                          text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    r = flexmor.read_result(out)
    assert re.fullmatch(r"\d+\.\d+\.\d+", r.attrs["flexmor_version"])
    assert r.attrs["status"] == "ok"
    assert r.attrs["title"] == "cantilever, all analyses"
    # Dynamic: the output nodes (sorted by label), shapes consistent with /time.
    np.testing.assert_allclose(r.time, [0.0, 0.005, 0.01, 0.015, 0.02], rtol=0, atol=1e-15)
    assert r.node_labels == ["beam.1", "tip"]
    assert r.nodes["tip"].position.shape == (5, 3) and r.nodes["tip"].rotation.shape == (5,)
    t, xyz = r.node_path("tip")
    assert t is r.time and xyz is r.nodes["tip"].position
    n_dy = r.attrs["n_dynamic_coordinates"]
    assert r.q.shape == r.qd.shape == (5, n_dy) and set(r.energy) == {"kinetic", "potential"}
    # The model and the coordinate history agree with the node datasets.
    m = r.require_model()
    assert m.n_nodes == 3 and m.element_types == ["beam", "beam"]
    assert r.x.shape == (5, m.n_coordinates)
    tip = m.node_labels.index("tip")
    np.testing.assert_array_equal(m.node_position[tip], [1.0, 0.0, 0.0])
    ix, iy, iphi = m.node_coordinates[tip]
    np.testing.assert_allclose(r.x[:, [ix, iy]], xyz[:, :2], rtol=0, atol=1e-12)
    np.testing.assert_allclose(r.x[:, iphi], r.nodes["tip"].rotation, rtol=0, atol=1e-12)
    # Static: load factors k/3, tip going down, and /static/x at each step.
    st = r.static
    np.testing.assert_allclose(st.load_factor, [1 / 3, 2 / 3, 1.0], rtol=1e-15)
    assert st.q.shape == (n_dy,) and st.x.shape == (3, m.n_coordinates)
    y_tip = st.nodes["tip"].position[:, 1]
    assert np.all(np.diff(y_tip) < 0) and y_tip[0] < 0
    np.testing.assert_allclose(st.x[:, iy], y_tip, rtol=0, atol=1e-12)
    assert st.stable is None or (st.stable.shape == (3,) and st.stable.all())
    # Modal: two positive, increasing frequencies with their shapes.
    assert r.modal.frequency_hz.shape == (2,) and 0 < r.modal.frequency_hz[0] < \
        r.modal.frequency_hz[1]
    assert r.modal.shapes.shape == (2, n_dy) and r.modal.nodes["tip"].shape == (2, 3)
    assert r.reduction is None
    assert r.motion()[2] == "time"


def test_read_result_errors_name_the_file(tmp_path):
    def error(path):
        with pytest.raises(flexmor.ResultFileError) as info:
            flexmor.read_result(path)
        message = str(info.value)
        assert "\n" not in message and str(path) in message
        return message

    assert "no such file" in error(tmp_path / "missing.h5")
    junk = tmp_path / "junk.h5"
    junk.write_text("not hdf5")
    assert "not a readable HDF5 file" in error(junk)
    plain = tmp_path / "plain.h5"
    with h5py.File(plain, "w") as f:
        f["time"] = np.arange(3.0)
    assert "not a flexmor result file" in error(plain)
    sweep = tmp_path / "sweep.h5"
    with h5py.File(sweep, "w") as f:
        f.attrs["flexmor_version"] = VERSION
        f["cases/status"] = np.zeros(2, dtype=np.int32)
    assert "read_sweep" in error(sweep)
    bad = tmp_path / "bad.h5"
    with h5py.File(bad, "w") as f:
        f.attrs["flexmor_version"] = VERSION
        f["time"] = np.arange(3.0)
        f["nodes/tip/position"] = np.zeros((3, 4))
    assert "/nodes/tip/position has shape (3, 4)" in error(bad)
    no_model = flexmor.read_result(_minimal(tmp_path / "old.h5"))
    with pytest.raises(flexmor.ResultFileError, match="no group /model"):
        no_model.require_model()
    with pytest.raises(flexmor.ResultFileError, match="no coordinate history"):
        no_model.motion()


def _minimal(path):
    with h5py.File(path, "w") as f:
        f.attrs["flexmor_version"] = "0.2.0"
        f["time"] = np.arange(3.0)
        f["nodes/tip/position"] = np.zeros((3, 3))
    return path


def _build_tools_missing():
    """Why `pip install --no-build-isolation` cannot work here, or ''."""
    if importlib.util.find_spec("venv") is None:
        return "the venv module is missing"
    try:
        setuptools = importlib.metadata.version("setuptools")
    except importlib.metadata.PackageNotFoundError:
        return "setuptools is not installed"
    major_minor = tuple(int(p) for p in re.findall(r"\d+", setuptools)[:2])
    if major_minor < (62, 0):
        return f"setuptools {setuptools} is older than 62 (no [tool.setuptools.dynamic] file)"
    if major_minor < (70, 1):
        try:
            importlib.metadata.version("wheel")
        except importlib.metadata.PackageNotFoundError:
            return f"setuptools {setuptools} needs wheel to build (scripts/setup.sh installs it)"
    return ""


def test_pip_install_into_a_venv(tmp_path):
    reason = _build_tools_missing()
    if reason:
        pytest.skip(reason)
    # Build from a copy of what the package needs, so that setuptools' build/ and egg-info
    # folders land there and not in the repository.
    src = tmp_path / "src"
    src.mkdir()
    for name in ("pyproject.toml", "VERSION"):
        shutil.copy(ROOT / name, src / name)
    (src / "docs").mkdir()
    shutil.copy(ROOT / "docs" / "python.md", src / "docs" / "python.md")
    shutil.copytree(ROOT / "python", src / "python",
                    ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    env.update(PIP_DISABLE_PIP_VERSION_CHECK="1", PIP_NO_INPUT="1", PIP_ROOT_USER_ACTION="ignore")
    venv = tmp_path / "venv"
    proc = subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", "--without-pip",
                           str(venv)], capture_output=True, text=True, timeout=300, env=env)
    if proc.returncode != 0:
        pytest.skip(f"python3 -m venv failed: {proc.stderr.strip()[-200:]}")
    python = venv / "bin" / "python"
    if subprocess.run([str(python), "-m", "pip", "--version"], capture_output=True,
                      timeout=120, env=env).returncode != 0:
        pytest.skip("pip is not importable in the venv")
    proc = subprocess.run([str(python), "-m", "pip", "install", "--no-deps", "--no-build-isolation",
                           "--no-index", "--quiet", str(src)], capture_output=True, text=True,
                          timeout=600, env=env, cwd=tmp_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    proc = subprocess.run([str(python), "-c", "import flexmor; print(flexmor.__version__); "
                           "print(flexmor.__file__)"], capture_output=True, text=True,
                          timeout=120, env=env, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    version, location = proc.stdout.split()
    assert version == VERSION
    assert Path(location).resolve().is_relative_to(venv.resolve())  # not the repository's copy
    proc = subprocess.run([str(venv / "bin" / "flexmor-vtk"), "--help"], capture_output=True,
                          text=True, timeout=120, env=env, cwd=tmp_path)
    assert proc.returncode == 0 and "usage: flexmor-vtk" in proc.stdout, proc.stderr


COLUMN = """&node label = 'base', x = 0, y = 0, fixed = .true. /
&node label = 'top', x = 0, y = 1 /
&link label = 'col', from = 'base', to = 'top', n_elements = 4,
      E = 7.0e10, A = 1.0e-4, I = 1.0e-9, rho = 2700 /
&force node = 'top', fy = -70.0 /
&buckling n_modes = 2 /
&output nodes = 'top' /
"""


def test_read_result_buckling(tmp_path):
    """A fixed-free column under EI/L^2 (70 N): the first multiplier is pi^2/4 (Euler); four
    elements are within 1e-4 of it (docs: mesh convergence of the buckling analysis)."""
    scene = tmp_path / "column.nml"
    scene.write_text(COLUMN)
    out = tmp_path / "column.h5"
    proc = subprocess.run([str(BIN), str(scene), "-o", str(out), "-q"], capture_output=True,
                          text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    b = flexmor.read_result(out).buckling
    assert b is not None and b.load_factor.shape == (2,) and b.shapes.shape[0] == 2
    assert abs(b.load_factor[0] / (np.pi ** 2 / 4) - 1) < 1e-3, b.load_factor
    assert b.load_factor[1] > b.load_factor[0]
    assert b.nodes["top"].shape == (2, 3)
    np.testing.assert_allclose(np.abs(b.nodes["top"][0, 0]), 1.0, rtol=1e-12)
