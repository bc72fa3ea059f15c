"""flexmor-plot-tip-path (flexmor.plot_tip_path) and flexmor.results on small synthetic result
files."""
import subprocess
import sys

import h5py
import numpy as np
import pytest

import flexmor.results as flexmor_results
from flexmor import plot_tip_path


def write_result(path, amplitude=0.0, labels=("tip", "elbow"), nt=141, t_end=0.7):
    """A two-link-like result: the tip swings over an arc and vibrates a little at the end."""
    t = np.linspace(0.0, t_end, nt)
    angle = np.pi / 2 * np.clip(t / 0.5, 0.0, 1.0) ** 2 * (3 - 2 * np.clip(t / 0.5, 0.0, 1.0))
    r = 1.0 + amplitude * np.sin(2 * np.pi * 3.0 * t)
    with h5py.File(path, "w") as f:
        f["time"] = t
        f["time"].attrs["units"] = "s"
        for k, label in enumerate(labels):
            scale = 1.0 / (k + 1)
            pos = np.column_stack([scale * r * np.cos(angle + 0.3), scale * r * np.sin(angle + 0.3),
                                   np.zeros_like(t)])
            f[f"nodes/{label}/position"] = pos
            f[f"nodes/{label}/position"].attrs["units"] = "m"
        f.attrs["flexmor_version"] = "0.1.0"
        f.attrs["status"] = "ok"
        f.attrs["n_steps"] = np.int64(nt)
        f.attrs["wall_time_s"] = 1.25
        f.attrs["fixed"] = np.bytes_(b"fixed-length")
    return t


def run_script(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "flexmor.plot_tip_path", *map(str, args)],
                          capture_output=True, text=True, timeout=120, cwd=cwd)


# --- flexmor_results ------------------------------------------------------------------------


def test_load_node_path_shapes(tmp_path):
    f = tmp_path / "run.h5"
    t_written = write_result(f)
    t, xyz = flexmor_results.load_node_path(f, "tip")
    assert t.shape == t_written.shape and xyz.shape == (t.size, 3)
    np.testing.assert_allclose(t, t_written)
    assert np.all(xyz[:, 2] == 0.0)


def test_node_labels_and_attributes(tmp_path):
    f = tmp_path / "run.h5"
    write_result(f, labels=("tip", "elbow", "base"))
    assert flexmor_results.node_labels(f) == ["base", "elbow", "tip"]
    attrs = flexmor_results.run_attributes(f)
    assert attrs["status"] == "ok" and isinstance(attrs["status"], str)
    assert attrs["fixed"] == "fixed-length"
    assert attrs["n_steps"] == 141 and isinstance(attrs["n_steps"], int)
    assert attrs["wall_time_s"] == pytest.approx(1.25)


def test_missing_label_lists_available(tmp_path):
    f = tmp_path / "run.h5"
    write_result(f)
    with pytest.raises(flexmor_results.ResultFileError) as info:
        flexmor_results.load_node_path(f, "hand")
    message = str(info.value)
    assert "hand" in message and "elbow, tip" in message and str(f) in message


def test_result_without_a_dynamic_run(tmp_path):
    """A static (or modal) result has no /time and no /nodes: said so, not 'available: none'."""
    f = tmp_path / "static.h5"
    with h5py.File(f, "w") as h5:
        h5.attrs["flexmor_version"] = "0.1.0"
        h5["static/nodes/tip/position"] = np.zeros((3, 3))
    with pytest.raises(flexmor_results.ResultFileError, match="no dynamic run .*&dynamic"):
        flexmor_results.load_node_path(f, "tip")


def test_missing_file_and_not_hdf5(tmp_path):
    with pytest.raises(flexmor_results.ResultFileError, match="no such file"):
        flexmor_results.load_node_path(tmp_path / "nope.h5", "tip")
    junk = tmp_path / "junk.h5"
    junk.write_text("not hdf5")
    with pytest.raises(flexmor_results.ResultFileError, match="not a readable HDF5 file"):
        flexmor_results.node_labels(junk)


def test_transposed_position_is_reported(tmp_path):
    f = tmp_path / "bad.h5"
    with h5py.File(f, "w") as h:
        h["time"] = np.arange(5.0)
        h["nodes/tip/position"] = np.zeros((3, 5))
    with pytest.raises(flexmor_results.ResultFileError, match="transposed"):
        flexmor_results.load_node_path(f, "tip")


# --- plot_tip_path ---------------------------------------------------------------------------


def test_zoom_window_contains_peaks(tmp_path):
    paths = []
    for amplitude in (0.0, 0.01, 0.02):
        f = tmp_path / f"a{amplitude}.h5"
        write_result(f, amplitude)
        paths.append(flexmor_results.load_node_path(f, "tip")[1])
    xmin, xmax, ymin, ymax = plot_tip_path.zoom_window(paths, 0.05)
    full_x = max(np.ptp(p[:, 0]) for p in paths)
    assert xmax - xmin < 0.5 * full_x, "the detail window is a zoom, not the full view"
    for xyz in paths:
        k = np.argmax(xyz[:, 1])
        assert xmin <= xyz[k, 0] <= xmax and ymin <= xyz[k, 1] <= ymax


def test_zoom_window_of_a_still_point():
    xyz = np.tile([0.5, 2.0, 0.0], (10, 1))
    xmin, xmax, ymin, ymax = plot_tip_path.zoom_window([xyz])
    assert xmin < 0.5 < xmax and ymin < 2.0 < ymax


def test_plot_writes_png_and_window_has_peak(tmp_path):
    full, reduced = tmp_path / "full.h5", tmp_path / "reduced_1mode.h5"
    write_result(full, 0.01)
    write_result(reduced, 0.015)
    out = tmp_path / "tip_path.png"
    assert plot_tip_path.main([str(full), str(reduced), "-o", str(out)]) == 0
    assert out.stat().st_size > 1000
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    series = [(p.stem, *flexmor_results.load_node_path(p, "tip")) for p in (full, reduced)]
    window = plot_tip_path.plot_paths(series, str(tmp_path / "again.png"))
    xmin, xmax, ymin, ymax = window
    for _, _, xyz in series:
        k = np.argmax(xyz[:, 1])
        assert xmin <= xyz[k, 0] <= xmax and ymin <= xyz[k, 1] <= ymax


def test_cli_with_labels_and_node(tmp_path):
    a, b = tmp_path / "a.h5", tmp_path / "b.h5"
    write_result(a)
    write_result(b, 0.02)
    out = tmp_path / "elbow.png"
    proc = run_script(a, b, "-o", out, "--node", "elbow", "--label", "full", "--label", "2 modes")
    assert proc.returncode == 0, proc.stderr
    assert out.stat().st_size > 1000


def test_cli_default_output_name(tmp_path):
    a = tmp_path / "a.h5"
    write_result(a)
    proc = run_script(a, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "tip_path.png").stat().st_size > 1000


def test_cli_missing_file(tmp_path):
    out = tmp_path / "x.png"
    proc = run_script(tmp_path / "missing.h5", "-o", out)
    assert proc.returncode == 2
    assert "missing.h5" in proc.stderr and "no such file" in proc.stderr
    assert "Traceback" not in proc.stderr
    assert not out.exists()


def test_cli_missing_label(tmp_path):
    a = tmp_path / "a.h5"
    write_result(a)
    proc = run_script(a, "-o", tmp_path / "x.png", "--node", "hand")
    assert proc.returncode == 2
    assert "'hand'" in proc.stderr and "available: elbow, tip" in proc.stderr
    assert "Traceback" not in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1


def test_cli_label_count_mismatch(tmp_path):
    a = tmp_path / "a.h5"
    write_result(a)
    proc = run_script(a, "-o", tmp_path / "x.png", "--label", "one", "--label", "two")
    assert proc.returncode == 2 and "Traceback" not in proc.stderr


def test_cli_missing_output_folder(tmp_path):
    a = tmp_path / "a.h5"
    write_result(a)
    proc = run_script(a, "-o", tmp_path / "no" / "x.png")
    assert proc.returncode == 2 and "does not exist" in proc.stderr
    assert "Traceback" not in proc.stderr
