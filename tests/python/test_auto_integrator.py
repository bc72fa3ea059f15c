"""&dynamic integrator = 'auto' (the default) takes generalized-alpha with error control for
rtol >= 1e-6; below, the run takes BDF unless the model is stiff: its fastest natural frequency
(joints locked; of the basis for a reduced model) turns through more than 1000 rad over the
run (docs/input.md). Options are checked against the integrator taken: dt applies to the
first, max_order to the second (and selects it)."""
import re
from pathlib import Path

import h5py
import pytest

from helpers import ARM, assert_clean_error, run_scene

MOTION = "&motion label = 'm1', law = 'cubic', start = 0, end = 0.5, duration = 0.01 /\n"
TWO_LINK = (Path(__file__).resolve().parents[2] / "input" / "two_link.nml").read_text()


@pytest.mark.parametrize("given,taken", [
    ("", "galpha_adaptive"),                                 # rtol 1e-6 by default
    ("rtol = 1e-4", "galpha_adaptive"),
    ("rtol = 1e-6", "galpha_adaptive"),
    ("rtol = 1e-7", "bdf"),                                  # not stiff over 0.01 s
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


def two_link(n_per_link, t_end, rtol, extra=""):
    text = TWO_LINK.replace("n_elements = 3", f"n_elements = {n_per_link}")
    text = re.sub(r"&modal[^/]*/", "", text)
    text = re.sub(r"&dynamic[^/]*/", f"&dynamic t_end = {t_end}, output_dt = {t_end / 2}, "
                  f"rtol = {rtol}, atol = {rtol * 1e-2} /", text)
    return text + extra


@pytest.mark.parametrize("text,taken,reason", [
    # The arm's fastest mode over 0.01 s: well under 1000 rad.
    (ARM + MOTION + "&dynamic t_end = 0.01, output_dt = 1e-3, rtol = 1e-7 /\n", "bdf",
     "not stiff"),
    # The two-link's fastest bending mode (4234 Hz at 3 elements per link) over 0.05 s:
    # 1330 rad. BDF would be held to that mode's period (8 per link, 0.7 s, rtol 1e-7:
    # 276,000 steps against galpha_adaptive's 7,000).
    (two_link(3, 0.05, 1e-7), "galpha_adaptive", ", stiff ("),
    # Its reduced model keeps modes up to 23 Hz: 7 rad over the same 0.05 s.
    (two_link(3, 0.05, 1e-7, "&reduction n_modes = 2 /\n"), "bdf", "not stiff"),
    # Too large for all modes (404 dynamic coordinates): taken as stiff without computing.
    (two_link(101, 2e-4, 1e-7), "galpha_adaptive", "taken as stiff"),
])
def test_choice_by_stiffness(tmp_path, text, taken, reason):
    proc, out = run_scene(tmp_path, text, quiet=False)
    assert proc.returncode == 0, proc.stderr
    assert f"integrator: {taken} (auto: " in proc.stdout
    with h5py.File(out) as f:
        assert f.attrs["integrator"] == taken
        assert reason in f.attrs["integrator_choice"]


@pytest.mark.parametrize("given,fragments", [
    ("rtol = 1e-8, dt = 1e-5", ["'dt'", "galpha", "chooses by the model's stiffness"]),
    ("rtol = 1e-4, max_order = 2", ["'max_order'", "bdf"]),
    ("rtol = 1e-8, erk_order = 5", ["'erk_order'", "name the integrator"]),
    ("rtol = 1e-8, jacobian = 'internal'", ["'jacobian'", "'bdf'", "name the integrator"]),
    ("integrator = 'automatic'", ["'integrator'", "'automatic'"]),
])
def test_options_of_the_other_integrator(tmp_path, given, fragments):
    proc, out = run_scene(tmp_path, ARM + MOTION +
                          f"&dynamic t_end = 0.01, output_dt = 1e-3, {given} /\n")
    assert_clean_error(proc, out, "&dynamic", *fragments)


@pytest.mark.parametrize("reduction, warned", [("", True), ("&reduction n_modes = 2 /\n", False)])
def test_erk_on_a_stiff_model_is_warned(tmp_path, reduction, warned):
    """integrator = 'erk' where 'auto' would find the model stiff (the full two-link: its
    fastest mode, 4.2 kHz, turns through 1300 rad in 0.05 s; stability holds an explicit step
    to about 3 / omega = 1.1e-4 s) gets a warning naming that step; the 2-mode reduced model
    (23 Hz) is not stiff and gets none."""
    text = re.sub(r"&dynamic[^/]*/", "&dynamic t_end = 0.05, integrator = 'erk' /",
                  TWO_LINK) + reduction
    proc, _ = run_scene(tmp_path, text)
    assert proc.returncode == 0, proc.stderr
    assert ("integrator = 'erk' on a stiff model" in proc.stderr) == warned, proc.stderr
    if warned:
        assert "holds an explicit step to about 1.13E-04 s" in proc.stderr, proc.stderr
