"""The /reduction group of a reduced run's result file (docs/output.md), end to end."""
import subprocess

import h5py
import numpy as np
import pytest

from test_cli_errors import GOOD

from helpers import BIN


def run(tmp_path, text):
    nml = tmp_path / "scene.nml"
    nml.write_text(text)
    out = tmp_path / "out.h5"
    proc = subprocess.run([str(BIN), str(nml), "-o", str(out)], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0, proc.stderr
    return proc, out


@pytest.mark.skipif(not BIN.is_file(), reason="flexmor binary not built")
def test_reduced_run_layout(tmp_path):
    proc, out = run(tmp_path, GOOD + "&reduction n_modes = 2, update = 'interval', "
                    "update_interval = 0.005, static_correction = .true. /\n")
    assert "reduction: 2 modes (n_modes = 2 given)" in proc.stdout
    with h5py.File(out) as f:
        nt, n_dy = f["q"].shape
        red = f["reduction"]
        assert red["eta"].shape == (nt, 2) and red["eta_dot"].shape == (nt, 2)
        assert red["basis"].shape == (2, n_dy) and red["frequency_hz"].shape == (2,)
        assert red["residual"].shape == (nt,) and red["error_estimate"].shape == (nt,)
        assert np.all(np.isfinite(red["residual"][:])) and np.all(red["error_estimate"][:] >= 0)
        assert red["checks/time"].shape == (3,) and list(red["checks/updated"][:]) == [1, 1, 1]
        assert red["checks/frequency_hz"].shape == (3, 2)
        attrs = dict(red.attrs)
        assert attrs["n_modes"] == 2 and attrs["selection"] == "count"
        assert attrs["eigensolver"] == "lapack" and attrs["static_correction"] == "yes"
        assert attrs["update"] == "interval" and attrs["n_updates"] == 3
        assert attrs["error_estimate_max"] == pytest.approx(red["error_estimate"][:].max())
        # The summary line repeats it, so that the trade shows without opening the file.
        line = next(s for s in proc.stdout.splitlines()
                    if s.startswith("reduction: error estimate up to "))
        shown = float(line.split("up to ")[1].split()[0])
        assert shown == pytest.approx(attrs["error_estimate_max"], rel=0.01)
        # The basis is M0-normalised in the modal sense: the same as the modal shapes.
        shapes = f["modal/shapes"][:2]
        assert np.allclose(np.abs(red["basis"][:]), np.abs(shapes), atol=1e-12)


@pytest.mark.skipif(not BIN.is_file(), reason="flexmor binary not built")
def test_auto_selection_reports_why(tmp_path):
    proc, out = run(tmp_path, GOOD + "&reduction auto_factor = 1.0 /\n")
    with h5py.File(out) as f:
        attrs = dict(f["reduction"].attrs)
    assert attrs["selection"] == "auto" and attrs["motion_bandwidth_hz"] > 0
    assert "x motion bandwidth" in attrs["reason"] and attrs["reason"] in proc.stdout


def test_n_modes_out_of_range_names_its_group_once(tmp_path):
    """n_modes above the number of dynamic coordinates: one 'group &reduction' and the
    variable, not the basis configuration's prefix on a message that has its own group."""
    nml = tmp_path / "scene.nml"
    nml.write_text(GOOD + "&reduction n_modes = 5 /\n")
    proc = subprocess.run([str(BIN), str(nml), "-o", str(tmp_path / "out.h5")],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 1, proc.stderr
    assert proc.stderr.count("group &reduction") == 1, proc.stderr
    assert "variable 'n_modes'" in proc.stderr and "basis configuration" not in proc.stderr
