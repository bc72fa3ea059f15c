"""scripts/compliant_examples.py (the tables and plots of docs/examples.md) runs, on coarse
meshes, and writes its tables and plots."""
import re
import subprocess
import sys

from helpers import BIN, ROOT


def test_script_quick(tmp_path):
    proc = subprocess.run([sys.executable, str(ROOT / "scripts" / "compliant_examples.py"),
                           "--bin", str(BIN), "--meshes", "2", "4", "--out-dir", str(tmp_path)],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    table = (tmp_path / "bench" / "compliant_examples.md").read_text()
    assert "## Parallel leaf-spring guide (2 elements per leaf)" in table
    assert "| 2.2 |" in table and "| 0.30 |" in table
    for name in ("leaf_spring_guide.png", "cross_spring_pivot.png"):
        assert (tmp_path / "img" / name).stat().st_size > 10000


def test_spin_up_plot(tmp_path):
    """scripts/spin_up.py (the spin-up plots of docs/examples.md) runs and draws both: the
    motion, and the reduced run's error estimate against its true distance from the full
    model (2.29e-4 and 2.31e-4 m). Both images go to tmp_path, none into docs/img."""
    out, reduction = tmp_path / "spin_up.png", tmp_path / "spin_up_reduction.png"
    proc = subprocess.run([sys.executable, str(ROOT / "scripts" / "spin_up.py"), "--bin",
                           str(BIN), "--out", str(out), "--reduction-out", str(reduction)],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert out.stat().st_size > 10000 and reduction.stat().st_size > 10000
    # The peak of a 0.4 m swing (galpha, 2 ms): a model quantity, not a round-off one.
    peak = float(proc.stdout.split("largest deflection")[1].split()[0])
    assert 0.3 < peak < 0.5
    found = re.search(r"estimate up to (\S+) m, the tip up to (\S+) m", proc.stdout)
    assert found, proc.stdout
    estimate, true = float(found.group(1)), float(found.group(2))
    assert estimate > 0 and 0.1 < true / estimate < 10, proc.stdout
