"""scripts/compliant_examples.py (the tables and plots of docs/examples.md) runs, on coarse
meshes, and writes its tables and plots."""
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
    """scripts/spin_up.py (the spin-up plot of docs/examples.md) runs and draws."""
    out = tmp_path / "spin_up.png"
    proc = subprocess.run([sys.executable, str(ROOT / "scripts" / "spin_up.py"), "--bin",
                           str(BIN), "--out", str(out)], capture_output=True, text=True,
                          timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert out.stat().st_size > 10000
    # The peak of a 0.4 m swing (galpha, 2 ms): a model quantity, not a round-off one.
    peak = float(proc.stdout.split("largest deflection")[1].split()[0])
    assert 0.3 < peak < 0.5
