"""&dynamic integrator = 'auto' (the default) takes generalized-alpha with error control for
rtol >= 1e-6 and BDF below (docs/input.md), and options are checked against the integrator
taken: dt applies to the first, max_order to the second."""
import h5py
import pytest

from helpers import ARM, assert_clean_error, run_scene

MOTION = "&motion label = 'm1', law = 'cubic', start = 0, end = 0.5, duration = 0.01 /\n"


@pytest.mark.parametrize("given,taken", [
    ("", "galpha_adaptive"),                                 # rtol 1e-6 by default
    ("rtol = 1e-4", "galpha_adaptive"),
    ("rtol = 1e-6", "galpha_adaptive"),
    ("rtol = 1e-7", "bdf"),
    ("integrator = 'auto', rtol = 1e-9", "bdf"),
    ("integrator = 'bdf', rtol = 1e-3", "bdf"),              # an explicit choice stands
    ("rtol = 1e-5, dt = 1e-5", "galpha_adaptive"),
    ("rtol = 1e-8, max_order = 3", "bdf"),
])
def test_choice_by_rtol(tmp_path, given, taken):
    extra = f", {given}" if given else ""
    proc, out = run_scene(tmp_path, ARM + MOTION +
                          f"&dynamic t_end = 0.01, output_dt = 1e-3{extra} /\n")
    assert proc.returncode == 0, proc.stderr
    with h5py.File(out) as f:
        assert f.attrs["integrator"] == taken


@pytest.mark.parametrize("given,fragments", [
    ("rtol = 1e-8, dt = 1e-5", ["'dt'", "galpha"]),
    ("rtol = 1e-4, max_order = 2", ["'max_order'", "bdf"]),
    ("integrator = 'automatic'", ["'integrator'", "'automatic'"]),
])
def test_options_of_the_other_integrator(tmp_path, given, fragments):
    proc, out = run_scene(tmp_path, ARM + MOTION +
                          f"&dynamic t_end = 0.01, output_dt = 1e-3, {given} /\n")
    assert_clean_error(proc, out, "&dynamic", *fragments)
