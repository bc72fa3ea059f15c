"""User control laws from a shared library (&controller law = 'user', library, symbol, params;
docs/input.md) run by the flexmor program: examples/c/pid_law.c, built by CTest
(FLEXMOR_PID_LAW), gives the built-in PID's motion, the example scene next to its library
matches the closed form, the error check's second run has the law, and every bad input is a
clear error."""
import re
import shutil
import subprocess

import numpy as np
import pytest

from helpers import BIN, PID_LAW, ROOT, assert_clean_error, rigid_link_pd, run_scene

h5py = pytest.importorskip("h5py")
pytestmark = pytest.mark.skipif(not PID_LAW.is_file(), reason="pid_law.so not built")

STAGE = (ROOT / "input" / "stage_pid.nml").read_text().replace(", u_min = -1.0, u_max = 1.0", "")
STAGE_PID = "reference = 'step', kp = 1500.0, ki = 5.0e4, kd = 11.0"
EXAMPLE = ROOT / "examples" / "c" / "rigid_link_library.nml"


def stage_with_library_law():
    """input/stage_pid.nml without its limits (the library's law has no anti-windup) and with
    the same PID (kp, ki, kd, r = the step's 1 mm) as the law pid_law of the library."""
    assert STAGE_PID in STAGE
    return STAGE.replace(STAGE_PID, f"law = 'user', n_states = 1, library = '{PID_LAW}', "
                         "symbol = 'pid_law', params = 1500.0, 5.0e4, 11.0, 1.0e-3")


def run_ok(folder, text, name):
    proc, out = run_scene(folder, text, name=name)
    assert proc.returncode == 0, proc.stderr
    return out


def shuttle(out):
    with h5py.File(out) as f:
        return f["nodes/shuttle/position"][:], f["controllers/position/input"][:]


def test_library_law_moves_the_stage_as_the_builtin_pid(tmp_path):
    """The leaf-spring stage's 1 mm step under the built-in PID and under pid_law.so with the
    same gains: the same ODE, but not the same Newton iterations (the built-in PID's closed-loop
    Jacobian has its analytic part, a user law's is taken by differences of the whole system:
    5295 against 5330 evaluations), so the runs agree to the integrator's global error, not to
    round-off. Each is within 1.3e-8 m (u: 1.5e-4 N) of an rtol 1e-10 run at the scene's rtol
    1e-6; bounds 10 x twice that, 3e-7 m and 3e-3 N. Observed 2.6e-10 m and 3.8e-6 N. A wrong
    gain, sign or reference moves the shuttle by a fraction of its 1.1 mm travel."""
    pos_pid, u_pid = shuttle(run_ok(tmp_path, STAGE, "pid"))
    proc, out = run_scene(tmp_path, stage_with_library_law(), "library")
    assert proc.returncode == 0, proc.stderr
    pos_lib, u_lib = shuttle(out)
    assert np.ptp(pos_pid[:, 0]) > 1e-3                    # the step: a real comparison
    assert np.max(np.abs(pos_lib - pos_pid)) < 3e-7
    assert np.max(np.abs(u_lib - u_pid)) < 3e-3


def example_in(folder):
    """The example scene and its library (as its header says to build it) in `folder`."""
    shutil.copy(EXAMPLE, folder / EXAMPLE.name)
    shutil.copy(PID_LAW, folder / "pid_law.so")
    return folder / EXAMPLE.name


def tip_angle(out):
    with h5py.File(out) as f:
        tip = f["nodes/tip/position"][:]
        return f["time"][:], np.arctan2(tip[:, 1], tip[:, 0])


def test_example_finds_its_library_beside_the_scene(tmp_path):
    """examples/c/rigid_link_library.nml names 'pid_law.so': the file beside the scene, whatever
    the current folder (flexmor runs from another one here). The PD's closed form: observed
    1.8e-10 rad at BDF rtol 1e-9 (as examples/c/pd_rigid_link.c, the same law from C); bound
    1e-8 rad, 10 x the integrator's global error there."""
    (tmp_path / "case").mkdir()
    scene = example_in(tmp_path / "case")
    (tmp_path / "elsewhere").mkdir()
    proc = subprocess.run([str(BIN), str(scene), "-o", "out.h5", "-q"], capture_output=True,
                          text=True, timeout=600, cwd=tmp_path / "elsewhere")
    assert proc.returncode == 0, proc.stderr
    t, angle = tip_angle(tmp_path / "elsewhere" / "out.h5")
    assert len(t) == 1001
    assert np.max(np.abs(angle - rigid_link_pd(t))) < 1e-8


def test_error_check_second_run_has_the_library_law(tmp_path):
    """&dynamic error_check: the second run (rtol / 10) has the law too; the two runs differ by
    about the first one's global error, ~1e-10 rad at rtol 1e-9 (the closed form above); bound
    1e-7 m at the 1 m tip, and above 0 (a second run that did not run the law would stop
    with 'needs a control law', one without the disturbance's response would be 1e-2 m away)."""
    scene = example_in(tmp_path)
    scene.write_text(scene.read_text().replace("atol = 1e-12 /",
                                               "atol = 1e-12, error_check = 'tolerance' /"))
    proc = subprocess.run([str(BIN), str(scene), "-o", "out.h5", "-q"], capture_output=True,
                          text=True, timeout=600, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    with h5py.File(tmp_path / "out.h5") as f:
        distance = f["error_check/distance"][:]
    assert 0 < np.max(distance) < 1e-7


#: The example's controller without its law (each bad input below adds one).
CONTROLLER = "&controller label = 'ext', actuator = 'j1.torque', measure = 'j1.angle', {} /"
LAW = "law = 'user', library = 'pid_law.so', symbol = 'pid_law'"


@pytest.mark.parametrize("law,fragments", [
    # Read from the scene: the group by its place in the file, the variable by name.
    ("kp = 1.0, library = 'pid_law.so', symbol = 'pid_law'",
     ["group &controller #1", "'library'", "law = 'user'"]),
    ("kp = 1.0, symbol = 'pid_law'", ["group &controller #1", "'symbol'", "law = 'user'"]),
    ("kp = 1.0, params = 1.0", ["group &controller #1", "'params'", "law = 'user'"]),
    ("law = 'user', library = 'pid_law.so'", ["group &controller #1", "'library' needs 'symbol'"]),
    ("law = 'user', symbol = 'pid_law'", ["group &controller #1", "'symbol' needs 'library'"]),
    ("law = 'user', params = 1.0", ["group &controller #1", "'params'", "'library'"]),
    ("law = 'user', library = '', symbol = 'pid_law'",
     ["group &controller #1", "'library'", "empty"]),
    ("law = 'user', library = 'pid_law.so', symbol = ''",
     ["group &controller #1", "'symbol'", "empty"]),
    (LAW + ", params = 2.0, 'x'", ["group &controller #1", "'params'", "'x'"]),
    # Loaded with the model: the group by its label; the loader's messages end with dlerror()'s.
    (LAW.replace("pid_law.so", "missing.so") + ", params = 2.0, 0.0, 0.5, 0.0",
     ["&controller 'ext'", "'library'", "cannot open", "missing.so", "No such file"]),
    (LAW.replace("pid_law.so", "scene.nml") + ", params = 2.0, 0.0, 0.5, 0.0",
     ["&controller 'ext'", "'library'", "cannot open", "scene.nml"]),
    (LAW.replace("'pid_law'", "'pd_law'") + ", params = 2.0, 0.0, 0.5, 0.0",
     ["&controller 'ext'", "'symbol'", "has no function 'pd_law'", "pd_law)"]),
    (LAW + ", params = 2.0, 0.5",
     ["&controller 'ext'", "'params'", "reads 4 values", "pid_law_n_params", "2 are given"]),
    (LAW, ["&controller 'ext'", "'params'", "0 are given"]),
    # At run time: the law refuses a controller it is not for (two states) with status -1.
    (LAW + ", params = 2.0, 0.0, 0.5, 0.0, n_states = 2",
     ["&controller 'ext'", "user control law failed (status -1) at t = 0"]),
])
def test_bad_library_input(tmp_path, law, fragments):
    """Each bad input is one line naming the scene file, the &controller and the variable."""
    text = example_in(tmp_path).read_text()
    text = re.sub(r"&controller.*?/\n", CONTROLLER.format(law) + "\n", text, flags=re.S)
    proc, out = run_scene(tmp_path, text)
    assert_clean_error(proc, out, "scene.nml", *fragments)
