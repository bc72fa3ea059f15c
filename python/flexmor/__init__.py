"""flexmor's Python side: readers of result and sweep files, plots and mechanism views.

    import flexmor
    result = flexmor.read_result("two_link.h5")
    t, xyz = result.node_path("tip")
    sweep = flexmor.read_sweep("sweep.h5")
    linear = flexmor.read_linear("cantilever.h5")     # &linear: flexmor.control

See docs/python.md for the API and the console commands.
"""
from __future__ import annotations

from pathlib import Path


def _version() -> str:
    # The repository's VERSION when this is the source tree (PYTHONPATH=python), else the
    # version the installed distribution was built with (read from VERSION at build time).
    source = Path(__file__).resolve().parents[2]
    if (source / "pyproject.toml").is_file() and (source / "VERSION").is_file():
        return (source / "VERSION").read_text().strip()
    from importlib.metadata import PackageNotFoundError, version
    try:
        return version("flexmor")
    except PackageNotFoundError:
        return "unknown"


__version__ = _version()

from flexmor.model import Mesh, Model  # noqa: E402
from flexmor.results import (Buckling, Modal, NodePath, Result, ResultFileError, Static,  # noqa: E402
                             distance_from, load_node_path, node_labels, read_result,
                             relative_angle, rotation_from, run_attributes)
from flexmor.sweep import Sweep, SweepFileError, read_sweep  # noqa: E402
from flexmor.control import Linear, LinearModelError, read_linear  # noqa: E402

__all__ = ["Buckling", "Linear", "LinearModelError", "Mesh", "Modal", "Model", "NodePath",
           "Result", "ResultFileError", "Static", "Sweep", "SweepFileError", "__version__",
           "distance_from", "load_node_path", "node_labels", "read_linear", "read_result",
           "read_sweep", "relative_angle", "rotation_from", "run_attributes"]
