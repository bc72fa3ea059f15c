"""`&modal solver` end to end: the Krylov path (no dense matrices, docs/theory.md 8.1) gives
the dense solvers' modes, 'auto' takes it on large models, and it is refused with the reason
where it does not apply."""
import h5py
import numpy as np
import pytest

from helpers import ARM, BIN, ROOT, assert_clean_error, run_scene

pytestmark = pytest.mark.skipif(not BIN.is_file(), reason="flexmor binary not built")


def arm(n_elements, modal, extra=""):
    return (ARM.replace("n_elements = 2", f"n_elements = {n_elements}")
            + "&motion label = 'm1', law = 'cubic', start = 0, end = 0.5, duration = 0.05 /\n"
            + "&mass node = 'tip', m = 0.1 /\n&output nodes = 'tip' /\n" + extra
            + f"&modal {modal} /\n")


def modes(tmp_path, name, text):
    proc, out = run_scene(tmp_path, text, name=name)
    assert proc.returncode == 0, proc.stderr
    with h5py.File(out) as f:
        return (f["modal/frequency_hz"][:], f["modal/shapes"][:],
                f["modal/nodes/tip/shape"][:], f["modal"].attrs["eigensolver"])


def test_krylov_matches_dense(tmp_path):
    # 40 beams: 80 dynamic coordinates. Both paths normalise to Mbar and make the largest
    # entry positive, so shapes compare entry by entry; observed 1e-14 (frequencies) and
    # 1e-12 (shapes) relative.
    f_d, v_d, tip_d, used_d = modes(tmp_path, "dense", arm(40, "n_modes = 5, solver = 'lapack'"))
    f_k, v_k, tip_k, used_k = modes(tmp_path, "krylov", arm(40, "n_modes = 5, solver = 'krylov'"))
    assert (used_d, used_k) == ("lapack", "krylov")
    assert np.max(np.abs(f_k - f_d) / f_d) < 1e-10
    assert np.max(np.abs(v_k - v_d)) < 1e-8 * np.max(np.abs(v_d))
    assert np.max(np.abs(tip_k - tip_d)) < 1e-8 * np.max(np.abs(tip_d))


def test_auto_takes_krylov_on_large_models(tmp_path):
    # 60 beams: 120 dynamic coordinates, above the Krylov path's threshold of 100.
    *_, used = modes(tmp_path, "auto", arm(60, "n_modes = 4"))
    assert used == "krylov"
    # All modes: LAPACK whatever the size.
    *_, used = modes(tmp_path, "all", arm(60, "n_modes = 0"))
    assert used == "lapack"


def test_krylov_with_loads(tmp_path):
    # Gravity and a tip pull: the loads' stiffness is differenced on both paths (along unit
    # vectors on the dense one, along the Lanczos vectors on the other). The dense path's
    # central differences (h = 6e-6 m on 25 mm beams) are off by about (h / l)^2 / 6 = 1e-8
    # of the load stiffness: observed 1.3e-8 in the frequencies, 5e-10 in the shapes.
    loads = "&scene gravity = 0, -9.81 /\n&force node = 'tip', fx = 50 /\n"
    f_d, v_d, _, _ = modes(tmp_path, "dense", arm(40, "n_modes = 4, solver = 'lapack'", loads))
    f_k, v_k, _, used = modes(tmp_path, "krylov", arm(40, "n_modes = 4, solver = 'krylov'", loads))
    f_0, *_ = modes(tmp_path, "unloaded", arm(40, "n_modes = 4, solver = 'krylov'"))
    assert used == "krylov" and f_k[0] > 1.05 * f_0[0]   # the pull stiffens the arm
    assert np.max(np.abs(f_k - f_d) / f_d) < 1e-6
    assert np.max(np.abs(v_k - v_d)) < 1e-6 * np.max(np.abs(v_d))


@pytest.mark.parametrize("modal, extra, reason", [
    ("n_modes = 2, solver = 'krylov', along_motion = .true.", "", "along a motion"),
    ("n_modes = 2, solver = 'krylov'", "&scene linear_solver = 'dense' /\n", "dense path"),
])
def test_krylov_refused_with_reason(tmp_path, modal, extra, reason):
    proc, out = run_scene(tmp_path, arm(8, modal, extra))
    assert_clean_error(proc, out, "eigensolver 'krylov'", reason)


def test_unknown_solver(tmp_path):
    proc, out = run_scene(tmp_path, arm(8, "n_modes = 2, solver = 'qr'"))
    assert_clean_error(proc, out, "&modal", "solver", "krylov")


BLADE = (ROOT / "input" / "rotating_blade.nml").read_text()


def blade(modal, linear=""):
    """input/rotating_blade.nml (spun at 10 rad/s) with its &modal replaced."""
    old = "&modal n_modes = 4, time = 1.0, along_motion = .true. /"
    assert old in BLADE
    return BLADE.replace(old, modal + "\n" + linear)


def test_modes_far_along_a_steady_spin(tmp_path):
    """At 10 rad/s the spin is steady: the modes along it are the same at 1 s and at 999 s
    (the shaft 1.6e3 turns on, reached in kinematic steps). Both are the same difference
    tangent at the same relative state, 1e-9 relative apart at most (observed 1e-12); bound
    1e-7."""
    near, _, _, _ = modes(tmp_path, "near", blade(
        "&modal n_modes = 4, time = 1.0, along_motion = .true. /"))
    far, _, _, _ = modes(tmp_path, "far", blade(
        "&modal n_modes = 4, time = 999.0, along_motion = .true. /"))
    assert np.max(np.abs(far / near - 1)) < 1e-7, (far, near)


@pytest.mark.parametrize("time", ["1.0e4", "1.0e5", "1.0e300"])
@pytest.mark.parametrize("group", ["modal", "linear"])
def test_time_too_far_along_the_motion(tmp_path, time, group):
    """A time at which the shaft has turned 1e5 rad or more: the kinematic continuation
    gave a wrong model error ('the kinematic Jacobian is singular: ... not determined'),
    a floating-point trap in Debug, or a NaN residual; now one error naming the variable."""
    if group == "modal":
        text = blade(f"&modal n_modes = 4, time = {time}, along_motion = .true. /")
    else:
        text = blade("", f"&linear inputs = 'tip.fz', outputs = 'tip.z', time = {time}, "
                         "along_motion = .true. /")
    proc, out = run_scene(tmp_path, text)
    if time == "1.0e300":     # beyond what the reader takes (1e100)
        assert_clean_error(proc, out, f"group &{group} #1: variable 'time'", "out of range")
    else:
        assert_clean_error(proc, out, f"group &{group}: variable 'time'",
                           "more than the continuation follows")
