"""What the Python tests share: where the executables are (FLEXMOR_BIN and FLEXMOR_SWEEP_BIN,
set by CTest; a Debug build by default), a small scene, and loading a benchmark driver."""
import importlib.util
import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
BIN = Path(os.environ.get("FLEXMOR_BIN", ROOT / "build-debug" / "bin" / "flexmor"))
SWEEP_BIN = Path(os.environ.get("FLEXMOR_SWEEP_BIN",
                                ROOT / "build-debug" / "bin" / "flexmor-sweep"))

#: A 1 m arm of two beam elements, hinged at a fixed base and driven by motion 'm1': the
#: tests add the motion, masses and analyses they need.
ARM = """&node label = 'base', x = 0, y = 0, fixed = .true. /
&node label = 'tip', x = 1, y = 0 /
&link label = 'arm', from = 'base', to = 'tip', n_elements = 2,
      E = 7.0e10, A = 1.0e-4, I = 1.0e-9, rho = 2700 /
&hinge label = 'j1', node = 'base', link = 'arm', mode = 'prescribed', motion = 'm1' /
"""


def load_driver(path):
    """A benchmark driver of scripts/ as a module (the drivers are scripts, not part of the
    flexmor package; they import it)."""
    spec = importlib.util.spec_from_file_location(path.stem, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[path.stem] = module  # dataclasses look their module up there
    spec.loader.exec_module(module)
    return module
