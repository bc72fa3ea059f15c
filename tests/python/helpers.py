"""What the Python tests share: where the executables are (FLEXMOR_BIN and FLEXMOR_SWEEP_BIN,
set by CTest; a Debug build by default) and the control law library, small scenes, the closed
form of the examples' PD, and loading a benchmark driver."""
import importlib.util
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
BIN = Path(os.environ.get("FLEXMOR_BIN", ROOT / "build-debug" / "bin" / "flexmor"))
SWEEP_BIN = Path(os.environ.get("FLEXMOR_SWEEP_BIN",
                                ROOT / "build-debug" / "bin" / "flexmor-sweep"))
#: examples/c/pid_law.c built as a shared library by CTest (FLEXMOR_PID_LAW), a user control law
#: for &controller library.
PID_LAW = Path(os.environ.get("FLEXMOR_PID_LAW", ROOT / "build-debug" / "tests" / "pid_law.so"))

#: A 1 m arm of two beam elements, hinged at a fixed base and driven by motion 'm1': the
#: tests add the motion, masses and analyses they need.
ARM = """&node label = 'base', x = 0, y = 0, fixed = .true. /
&node label = 'tip', x = 1, y = 0 /
&link label = 'arm', from = 'base', to = 'tip', n_elements = 2,
      E = 7.0e10, A = 1.0e-4, I = 1.0e-9, rho = 2700 /
&hinge label = 'j1', node = 'base', link = 'arm', mode = 'prescribed', motion = 'm1' /
"""


#: The two-link benchmark arm (input/two_link.nml without its analyses) with {n} beam elements
#: per link: format(n=...) and add the analyses.
TWO_LINK = """
&node label = 'base',  x = 0.0,   y = 0.0, fixed = .true. /
&node label = 'elbow', x = 0.545, y = 0.0 /
&node label = 'tip',   x = 1.220, y = 0.0 /
&link label = 'link1', from = 'base', to = 'elbow', n_elements = {n},
      E = 7.3e10, A = 9.0e-4, I = 1.69e-8, rho = 2700 /
&link label = 'link2', from = 'elbow', to = 'tip', n_elements = {n},
      E = 7.3e10, A = 4.0e-4, I = 3.33e-9, rho = 2700 /
&hinge label = 'joint1', node = 'base',  link = 'link1', mode = 'prescribed', motion = 'phi1' /
&hinge label = 'joint2', node = 'elbow', link = 'link2', mode = 'prescribed', motion = 'phi2' /
&motion label = 'phi1', law = 'cubic', start = 0.0, end = 1.5707963267948966, duration = 0.5 /
&motion label = 'phi2', law = 'cubic', start = 0.0, end = 1.5707963267948966, duration = 0.5 /
&mass node = 'elbow', m = 1.0 /
&mass node = 'tip',   m = 3.0 /
"""

def rigid_link_pd(t, tau=0.05, kp=2.0, kd=0.5):
    """The angle of the rigid 1 m link of examples/c (J = rho A L^3 / 3) under a PD and a
    constant torque tau from rest: J y'' + kd y' + kp y = tau, underdamped."""
    j = 2700 * 1.0e-4 / 3
    w, z = math.sqrt(kp / j), kd / (2 * math.sqrt(kp * j))
    wd = w * math.sqrt(1 - z * z)
    return tau / kp * (1 - np.exp(-z * w * t) * (np.cos(wd * t) + z * w / wd * np.sin(wd * t)))


def load_driver(path):
    """A benchmark driver of scripts/ as a module (the drivers are scripts, not part of the
    flexmor package; they import it)."""
    spec = importlib.util.spec_from_file_location(path.stem, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[path.stem] = module  # dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


def run_scene(folder, text, name="scene", quiet=True, timeout=600):
    """Write `text` to folder/<name>.nml and run flexmor on it (in `folder`); returns the
    completed process and the result path (which exists only on success)."""
    nml = Path(folder) / f"{name}.nml"
    nml.write_text(text)
    out = Path(folder) / f"{name}.h5"
    cmd = [str(BIN), str(nml), "-o", str(out)] + (["-q"] if quiet else [])
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, cwd=folder)
    return proc, out


def assert_clean_error(proc, out, *fragments):
    """A failed run: non-zero status, exactly one line 'flexmor: error: ...' holding every
    fragment, no backtrace or NaN, and no result file (nor a temporary) left behind."""
    assert proc.returncode != 0, proc.stdout + proc.stderr
    err = proc.stderr.strip()
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("flexmor: error: "), err
    for fragment in fragments:
        assert fragment in err, f"{fragment!r} not in {err!r}"
    for bad in ("Backtrace", "Error termination", "NaN", " nan", "Infinity"):
        assert bad not in proc.stdout + proc.stderr
    assert not out.exists()
    assert not list(out.parent.glob("*.h5*")), list(out.parent.glob("*"))
