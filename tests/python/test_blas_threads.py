"""The executables put OpenBLAS on one thread and shut its pool down at start
(src/core/core_threads.c), whatever OPENBLAS_NUM_THREADS says: a run gives the same numbers
with the variable unset, at 1 and at 2, and does not hang on the pool's shutdown. (What the
shutdown saves, 0.1 s of processor time per run, is a benchmark matter: docs/theory.md 9.)"""
import os
import subprocess

import h5py
import numpy as np
import pytest

from helpers import BIN, ROOT

pytestmark = pytest.mark.skipif(not BIN.is_file(), reason="flexmor binary not built")


def run(tmp_path, name, threads):
    """The two-link, k = 4 with the expanded evaluation (BLAS at every evaluation), to 0.1 s."""
    text = (ROOT / "input" / "two_link.nml").read_text().replace("&modal n_modes = 12 /", "")
    text = text.replace("t_end = 0.7", "t_end = 0.1")
    text += "&reduction n_modes = 4, evaluation = 'expanded' /\n"
    nml = tmp_path / f"{name}.nml"
    nml.write_text(text)
    out = tmp_path / f"{name}.h5"
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    if threads is not None:
        env["OPENBLAS_NUM_THREADS"] = threads
    proc = subprocess.run([str(BIN), str(nml), "-o", str(out), "-q"], env=env,
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    with h5py.File(out) as f:
        return f["nodes/tip/position"][:], int(f.attrs["n_steps"])


def test_same_run_whatever_the_thread_setting(tmp_path):
    tip_1, steps_1 = run(tmp_path, "one", "1")
    for name, threads in (("unset", None), ("two", "2")):
        tip, steps = run(tmp_path, name, threads)
        assert steps == steps_1
        # One thread in every case, so the same operations in the same order: bit for bit.
        np.testing.assert_array_equal(tip, tip_1)
