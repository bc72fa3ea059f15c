"""scripts/bench_modal.py: the scene it builds, bad arguments, and a small run with the real
flexmor whose dense and Krylov frequencies must agree."""
import csv
import subprocess
import sys

from helpers import BIN, ROOT, load_driver

SCRIPT = ROOT / "scripts" / "bench_modal.py"
bmo = load_driver(SCRIPT)


def run_script(*args, timeout=600):
    return subprocess.run([sys.executable, str(SCRIPT), *map(str, args)], capture_output=True,
                          text=True, timeout=timeout)


def test_scene_is_the_two_link_with_modes_only():
    text = bmo.scene(16, "krylov", bmo.CASES["gravity"])
    assert text.count("n_elements = 16") == 2 and "&dynamic" not in text
    assert text.count("&modal") == 1 and "&modal n_modes = 4, solver = 'krylov' /" in text
    assert "&scene gravity = 0.0, -9.81, title" in text and text.count("&scene") == 1


def test_bad_arguments_exit_2(tmp_path):
    for args in (["--meshes", "4,x"], ["--meshes", "1"], ["--repeat", "0"],
                 ["--bin", tmp_path / "none"]):
        proc = run_script(*args, "--out-dir", tmp_path)
        assert proc.returncode == 2 and "bench_modal.py" in proc.stderr, proc.stderr


def test_small_run_writes_tables(tmp_path):
    proc = run_script("--bin", BIN, "--out-dir", tmp_path, "--meshes", "4,30", "--dense-max", "4",
                      "--repeat", "1")
    assert proc.returncode == 0, proc.stderr
    with open(tmp_path / "modal.csv") as f:
        rows = list(csv.DictReader(f))
    assert [(r["case"], r["elements_per_link"]) for r in rows] == [
        ("unloaded", "4"), ("unloaded", "30"), ("gravity", "4"), ("gravity", "30")]
    # 4 beams: every solver; 30: above --dense-max, the Krylov path alone.
    assert all(float(rows[i][f"{s}_s"]) > 0 for i in (0, 2) for s in bmo.SOLVERS)
    assert rows[1]["lapack_s"] == "" and float(rows[1]["krylov_s"]) > 0
    # Unloaded, the paths agree to round-off (1e-14 observed); under gravity to the dense
    # differences' truncation error (1e-9 observed).
    assert float(rows[0]["lapack_freq_diff"]) < 1e-10
    assert float(rows[2]["lapack_freq_diff"]) < 1e-7
    md = (tmp_path / "modal.md").read_text()
    assert "| gravity | 30 | 120 | – | – |" in md and "commit" in md
