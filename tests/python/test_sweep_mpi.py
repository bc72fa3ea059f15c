"""flexmor-sweep end to end: serial and under mpirun with 2 and 3 ranks (uneven split), resume
after an interruption (also kill -9 of mpirun), failed cases recorded, bad sweep input."""
import os
import shutil
import signal
import subprocess
import time

import h5py
import numpy as np
import pytest

from helpers import BIN as FLEXMOR_BIN
from helpers import PID_LAW, ROOT, SWEEP_BIN, rigid_link_pd

BIN = SWEEP_BIN
MPIEXEC = os.environ.get("MPIEXEC") or shutil.which("mpiexec") or "mpiexec"
ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
           OMPI_MCA_rmaps_base_oversubscribe="1", OPENBLAS_NUM_THREADS="1")
pytestmark = pytest.mark.skipif(not BIN.is_file(), reason="flexmor-sweep not built")

BASE = """
&node label = 'base', x = 0, y = 0, fixed = .true. /
&node label = 'tip', x = 1, y = 0 /
&link label = 'arm', from = 'base', to = 'tip', n_elements = 2,
      E = 7.0e10, A = 1.0e-4, I = 1.0e-9, rho = 2700 /
&hinge label = 'j1', node = 'base', link = 'arm', mode = 'prescribed', motion = 'm1' /
&motion label = 'm1', law = 'cubic', start = 0, end = 0.5, duration = 0.02 /
&mass node = 'tip', m = 0.1 /
&dynamic t_end = 0.03, output_dt = 1e-3 /
"""

SWEEP = """
&sweep base = 'base.nml', mode = 'product' /
&parameter name = 'motion.m1.end', values = 0.3, 0.6, 0.9 /
&parameter name = 'link.arm.n_elements', values = 2, 5000 /
"""


def write_inputs(folder, sweep=SWEEP, base=BASE):
    (folder / "base.nml").write_text(base)
    (folder / "sweep.nml").write_text(sweep)
    return folder / "sweep.nml"


def run_sweep(folder, ranks=None, out="out.h5", timeout=900):   # hang guard: 20 s here
    cmd = [str(BIN), "sweep.nml", "-o", out]
    if ranks is not None:
        cmd = [MPIEXEC, "-n", str(ranks)] + cmd
    return subprocess.run(cmd, cwd=folder, env=ENV, capture_output=True, text=True,
                          timeout=timeout)


def read(path):
    with h5py.File(path, "r") as f:
        cases = f["cases"]
        return {
            "status": cases["status"][:],
            "message": [m.decode().rstrip("\x00 ") for m in cases["message"][:]],
            "wall": cases["wall_time_s"][:],
            "rank": cases["rank"][:],
            "metrics": {k: v[:] for k, v in cases["metrics"].items()},
            "parameters": {k: v[:] for k, v in cases["parameters"].items()},
        }


@pytest.fixture(scope="module")
def serial(tmp_path_factory):
    folder = tmp_path_factory.mktemp("serial")
    write_inputs(folder)
    proc = run_sweep(folder)
    assert proc.returncode == 0, proc.stderr
    return folder, read(folder / "out.h5"), proc


def test_serial_sweep_records_every_case(serial):
    _, res, proc = serial
    assert list(res["status"][::2]) == [0, 0, 0]          # n_elements = 2
    # n_elements = 5000: an input error of the case (too large), recorded. A value beyond
    # the schema's range (E = -1) is refused before any case runs: test_out_of_range_value.
    assert all(s == 1 for s in res["status"][1::2])
    assert all("too large" in m for m in res["message"][1::2])
    assert all(m == "" for m in res["message"][::2])
    ok = res["status"] == 0
    for name in ("max_tip_deflection", "residual_vibration", "n_steps", "n_model_evals"):
        assert np.all(np.isfinite(res["metrics"][name][ok])), name
        assert np.all(np.isnan(res["metrics"][name][~ok])), name
    assert np.all(res["metrics"]["n_modes"][ok] == 0)
    assert np.all(np.isnan(res["metrics"]["max_control_error"]))   # no &controller
    # A larger swing deflects the arm more.
    d = res["metrics"]["max_tip_deflection"][ok]
    assert d[0] < d[1] < d[2] and d[0] > 0
    assert list(res["parameters"]["motion.m1.end"]) == [0.3, 0.3, 0.6, 0.6, 0.9, 0.9]
    assert "6/6 done, 3 failed" in proc.stdout


@pytest.mark.parametrize("ranks", [2, 3])
def test_mpi_matches_serial(serial, tmp_path, ranks):
    _, ref, _ = serial
    write_inputs(tmp_path)
    proc = run_sweep(tmp_path, ranks)
    assert proc.returncode == 0, proc.stderr
    res = read(tmp_path / "out.h5")
    assert list(res["status"]) == list(ref["status"])
    assert res["message"] == ref["message"]
    for name, values in ref["metrics"].items():
        np.testing.assert_allclose(res["metrics"][name], values, rtol=1e-12, atol=0,
                                   equal_nan=True, err_msg=name)
    assert set(res["rank"]) <= set(range(1, ranks)) and -1 not in res["rank"]


def test_rerun_on_finished_file_does_nothing(serial, tmp_path):
    folder, _, _ = serial
    shutil.copy(folder / "out.h5", tmp_path / "done.h5")
    write_inputs(tmp_path)
    before = read(tmp_path / "done.h5")
    proc = run_sweep(tmp_path, out="done.h5")
    assert proc.returncode == 0, proc.stderr
    assert "6 already in" in proc.stdout
    after = read(tmp_path / "done.h5")
    np.testing.assert_array_equal(after["wall"], before["wall"])


def test_resume_runs_only_missing_cases(serial, tmp_path):
    folder, ref, _ = serial
    shutil.copy(folder / "out.h5", tmp_path / "part.h5")
    with h5py.File(tmp_path / "part.h5", "r+") as f:   # as if cases 2 and 5 never ran
        for i in (2, 5):
            f["cases/status"][i - 1] = -1
            f["cases/wall_time_s"][i - 1] = np.nan
    write_inputs(tmp_path)
    proc = run_sweep(tmp_path, 2, out="part.h5")
    assert proc.returncode == 0, proc.stderr
    assert "4 already in" in proc.stdout
    res = read(tmp_path / "part.h5")
    assert list(res["status"]) == list(ref["status"])
    assert [r for r in res["rank"]] == [0, 1, 0, 0, 1, 0]


def test_killed_sweep_stays_readable_and_resumes(tmp_path):
    """kill -9 of mpirun mid-way: the file opens, finished cases are kept, a rerun completes."""
    sweep = ("&sweep base = 'base.nml', mode = 'product' /\n"
             "&parameter name = 'motion.m1.end', start = 0.1, stop = 1.0, n = 16 /\n"
             "&parameter name = 'dynamic.rtol', values = 1e-8 /\n"
             "&parameter name = 'dynamic.t_end', values = 2.0 /\n")
    write_inputs(tmp_path, sweep=sweep)
    proc = subprocess.Popen([MPIEXEC, "-n", "2", str(BIN), "sweep.nml", "-o", "k.h5"],
                            cwd=tmp_path, env=ENV, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, start_new_session=True)
    deadline = time.time() + 900          # hang guard: 3 cases take a few seconds here
    done = 0

    while time.time() < deadline and proc.poll() is None and done < 3:
        time.sleep(0.2)
        try:
            # The writer holds HDF5's file lock; reading alongside it needs the lock off.
            with h5py.File(tmp_path / "k.h5", "r", locking=False) as f:
                done = int(np.sum(f["cases/status"][:] >= 0))
        except (OSError, KeyError):
            pass

    assert proc.poll() is None, "the sweep ended before it could be interrupted"
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait(timeout=300)
    wait_for_orphans(tmp_path / "k.h5")
    partial = read(tmp_path / "k.h5")
    assert 1 <= np.sum(partial["status"] == 0) <= 16
    rerun = run_sweep(tmp_path, 2, out="k.h5")
    assert rerun.returncode == 0, rerun.stderr
    final = read(tmp_path / "k.h5")
    assert np.all(final["status"] == 0)
    kept = partial["status"] == 0
    np.testing.assert_array_equal(final["wall"][kept], partial["wall"][kept])


def wait_for_orphans(path, timeout=600.0):
    """Ranks of a killed mpirun notice it and abort; until then they hold the file's lock."""
    deadline = time.time() + timeout
    pattern = f"flexmor-sweep sweep.nml -o {path.name}"
    while time.time() < deadline:
        found = subprocess.run(["pgrep", "-f", pattern], capture_output=True, text=True)
        if not found.stdout.strip():
            return
        time.sleep(0.5)
    subprocess.run(["pkill", "-9", "-f", pattern])
    pytest.fail(f"ranks of the killed mpirun were still running after {timeout:.0f} s")


BAD = {
    "unknown parameter": ("&parameter name = 'dynamic.rtoll', values = 1e-6 /",
                          ["rtoll"]),
    "unknown group": ("&parameter name = 'solver.tol', values = 1 /", ["solver"]),
    "unknown label": ("&parameter name = 'motion.m9.end', values = 1 /", ["m9"]),
    "empty range": ("&parameter name = 'motion.m1.end', start = 0, stop = 1, n = 0 /",
                    ["motion.m1.end"]),
}


@pytest.mark.parametrize("name", sorted(BAD))
def test_bad_sweep_input(tmp_path, name):
    extra, fragments = BAD[name]
    write_inputs(tmp_path, sweep="&sweep base = 'base.nml' /\n" + extra + "\n")
    proc = run_sweep(tmp_path, 2)
    assert proc.returncode == 1, proc.stdout + proc.stderr
    # One line from flexmor-sweep (rank 0); mpiexec adds its own banner after it.
    err = proc.stderr.strip().splitlines()[0]
    assert err.startswith("flexmor-sweep: error: "), proc.stderr
    assert proc.stderr.count("flexmor-sweep:") == 1, proc.stderr
    for fragment in fragments:
        assert fragment in err
    assert not (tmp_path / "out.h5").exists()


def test_out_of_range_value(tmp_path):
    """A value the scene schema refuses (E = -1, rho = 1e-40 below its 1e-30) stops the sweep
    before any case runs, naming the parameter and the first case that has it."""
    for extra, fragments in [
            ("&parameter name = 'link.arm.E', values = 7.0e10, -1.0 /",
             ["link.arm.E", "case 2", "'E' of &link", "must be positive, in [1e-30, 1e30]",
              "-1"]),
            ("&parameter name = 'link.arm.rho', min = 1e-40, max = 1e-35 /",
             ["link.arm.rho", "case 1", "'rho' of &link", "1e-30"])]:
        mode = "random', n_samples = 3" if "min" in extra else "product'"
        write_inputs(tmp_path, sweep=f"&sweep base = 'base.nml', mode = '{mode} /\n{extra}\n")
        proc = run_sweep(tmp_path)
        assert proc.returncode == 1, proc.stdout + proc.stderr
        for fragment in fragments:
            assert fragment in proc.stderr
        assert not (tmp_path / "out.h5").exists()


def test_zero_samples(tmp_path):
    write_inputs(tmp_path, sweep="&sweep base = 'base.nml', mode = 'random', n_samples = 0 /\n"
                 "&parameter name = 'motion.m1.end', min = 0, max = 1 /\n")
    proc = run_sweep(tmp_path)
    assert proc.returncode == 1 and "n_samples" in proc.stderr


def test_missing_base_scene(tmp_path):
    (tmp_path / "sweep.nml").write_text("&sweep base = 'nope.nml' /\n"
                                        "&parameter name = 'motion.m1.end', values = 1 /\n")
    proc = run_sweep(tmp_path)
    assert proc.returncode != 0 and "nope.nml" in proc.stderr


def test_example_sweep_checks_and_lists_its_cases():
    proc = subprocess.run([str(BIN), str(ROOT / "input" / "sweep_two_link.nml"), "--check"],
                          env=ENV, capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    assert "12 cases" in lines[0] and "valid" in lines[0]
    assert len(lines) == 14 and lines[-1].split()[0] == "12"


def test_no_arguments_is_a_usage_error(tmp_path):
    proc = subprocess.run([str(BIN)], cwd=tmp_path, env=ENV, capture_output=True, text=True,
                          timeout=60)
    assert proc.returncode == 1 and "usage" in proc.stderr


def test_spatial_scene_sweep(tmp_path):
    """A sweep over a spatial scene (serial): a cantilever's out-of-plane stiffness swept by
    its Iy under a tip force raised by a cubic law over 1 s, 13 times the first period, so
    the response is quasi-static: the largest tip deflection is F L^3 / (3 E Iy) to the
    quasi-static error ((1/(omega T))^2 ~ 2e-4) and the small residual vibration (observed
    1.7e-3; bound 2e-2), and a spatial variable of the wrong kind (a list) is refused by
    name."""
    base = """&scene title = 'spatial cantilever', dimension = 3 /
&node label = 'root', x = 0, y = 0, z = 0, fixed = .true. /
&node label = 'tip', x = 1, y = 0, z = 0 /
&link label = 'arm', from = 'root', to = 'tip', n_elements = 2, E = 7.0e10, A = 1.0e-4,
      I = 1.0e-9, Iy = 2.0e-9, J = 1.5e-9, G = 2.6e10, shear_factor = 1.0e8, rho = 2700 /
&motion label = 'up', law = 'cubic', start = 0, end = 1, duration = 1.0 /
&force node = 'tip', fz = 1.0e-3, time_law = 'up' /
&dynamic t_end = 1.2, output_dt = 0.01 /
"""
    sweep = """&sweep base = 'base.nml', mode = 'product', node = 'tip' /
&parameter name = 'link.arm.Iy', values = 2.0e-9, 4.0e-9 /
"""
    write_inputs(tmp_path, sweep, base)
    proc = run_sweep(tmp_path)
    assert proc.returncode == 0, proc.stderr
    res = read(tmp_path / "out.h5")
    assert list(res["status"]) == [0, 0]
    expected = 1.0e-3 / (3 * 7.0e10 * np.array([2.0e-9, 4.0e-9]))
    assert np.allclose(res["metrics"]["max_tip_deflection"], expected, rtol=2e-2)
    write_inputs(tmp_path, sweep.replace("'link.arm.Iy', values = 2.0e-9, 4.0e-9",
                                         "'link.arm.orientation', values = 0.0, 1.0"), base)
    proc = run_sweep(tmp_path, out="bad.h5")
    assert proc.returncode != 0
    assert "'orientation'" in proc.stderr and "list" in proc.stderr, proc.stderr


def test_sweep_of_controller_gains(tmp_path):
    """A sweep over a PID's integral gain on input/stage_pid.nml (serial): the control-error
    metrics are the largest |r - y| over the run (the 1 mm step itself at t = 0) and at its
    end, where the integral action has brought the error down (observed 4.6e-8 m at
    ki = 5e4 and 8e4; bound 1e-6 m); a scene without controllers gives NaN for them (the serial
    fixture's metrics)."""
    base = (ROOT / "input" / "stage_pid.nml").read_text()
    sweep = """&sweep base = 'base.nml', mode = 'product', node = 'shuttle' /
&parameter name = 'controller.position.ki', values = 5.0e4, 8.0e4 /
"""
    write_inputs(tmp_path, sweep, base)
    proc = run_sweep(tmp_path)
    assert proc.returncode == 0, proc.stderr
    res = read(tmp_path / "out.h5")
    assert list(res["status"]) == [0, 0]
    assert np.allclose(res["metrics"]["max_control_error"], 1.0e-3, rtol=1e-12)
    assert np.all(res["metrics"]["final_control_error"] < 1e-6)


def test_sweep_metric_error_check(tmp_path):
    """A base scene with &dynamic error_check = 'tolerance' swept over rtol (serial): each
    case's error_check metric is its own check (positive, and smaller at the tighter rtol:
    the global error of galpha_adaptive falls like rtol^(2/3), 4.6 times per decade; required
    more than 2 times), and NaN without the check (the metric of the base scene's cases)."""
    base = (ROOT / "input" / "two_link.nml").read_text().replace("&modal n_modes = 12 /", "")
    base = base.replace("rtol = 1.0e-6, atol = 1.0e-8 /",
                        "rtol = 1.0e-6, atol = 1.0e-8, error_check = 'tolerance' /")
    assert "error_check = 'tolerance'" in base
    sweep = """&sweep base = 'base.nml', mode = 'product', node = 'tip' /
&parameter name = 'dynamic.rtol', values = 1.0e-3, 1.0e-4 /
"""
    write_inputs(tmp_path, sweep, base)
    proc = run_sweep(tmp_path)
    assert proc.returncode == 0, proc.stderr
    res = read(tmp_path / "out.h5")
    assert list(res["status"]) == [0, 0]
    check = res["metrics"]["error_check"]
    assert np.all(check > 0) and check[0] > 2 * check[1], check
    turned = res["metrics"]["error_check_rotation"]
    assert np.all(turned > 0) and turned[0] > 2 * turned[1], turned
    write_inputs(tmp_path, sweep, base.replace(", error_check = 'tolerance'", ""))
    proc = run_sweep(tmp_path, out="plain.h5")
    assert proc.returncode == 0, proc.stderr
    plain = read(tmp_path / "plain.h5")["metrics"]
    assert np.all(np.isnan(plain["error_check"])) and np.all(np.isnan(plain["error_check_rotation"]))


@pytest.mark.parametrize("ranks", [None, 2])
def test_case_files(tmp_path, ranks):
    """&sweep case_files = .true.: every case that ran ok has the result file a flexmor run of
    it writes, beside the sweep file (out_cases/case_k.h5, k from 1); its steps are the case's
    metric and its attribute input_overrides names the case's parameters (the input attribute
    is the base scene's text); failed cases have none; flexmor.Sweep.case_file finds them, and
    says why not."""
    import flexmor
    write_inputs(tmp_path, SWEEP.replace("mode = 'product' /",
                                         "mode = 'product', case_files = .true. /"))
    proc = run_sweep(tmp_path, ranks)
    assert proc.returncode == 0, proc.stderr
    sweep = flexmor.read_sweep(tmp_path / "out.h5")
    assert sweep.attrs["case_files"] == "out_cases"
    ok = np.flatnonzero(sweep.ok)
    assert len(ok) == 3 and np.all(sweep.failed[np.flatnonzero(~sweep.ok)])
    files = sorted(p.name for p in (tmp_path / "out_cases").iterdir())
    assert files == sorted(f"case_{i + 1}.h5" for i in ok)
    for i in ok:
        result = flexmor.read_result(sweep.case_file(i))
        assert result.attrs["n_steps"] == sweep.metric("n_steps")[i]
        overrides = result.attrs["input_overrides"]
        assert overrides.startswith("motion.m1.end = ") and ", link.arm.n_elements = " in overrides
        assert float(overrides.split(",")[0].split("=")[1]) == pytest.approx(
            sweep.parameter("motion.m1.end")[i], rel=1e-9)
    with pytest.raises(flexmor.SweepFileError, match="has no result file"):
        sweep.case_file(int(np.flatnonzero(~sweep.ok)[0]))
    write_inputs(tmp_path)
    assert run_sweep(tmp_path, out="plain.h5").returncode == 0
    with pytest.raises(flexmor.SweepFileError, match="case_files = .true."):
        flexmor.read_sweep(tmp_path / "plain.h5").case_file(0)


def test_refused_output_leaves_no_case_folder(tmp_path):
    """-o naming a file that is no sweep result, with case_files: refused, and no
    'notes_cases' folder left behind (it was made before the file was looked at)."""
    write_inputs(tmp_path, SWEEP.replace("mode = 'product' /",
                                         "mode = 'product', case_files = .true. /"))
    (tmp_path / "notes.h5").write_text("not HDF5")
    proc = run_sweep(tmp_path, out="notes.h5")
    assert proc.returncode != 0 and "notes.h5" in proc.stderr, proc.stderr
    assert not (tmp_path / "notes_cases").exists()
    assert (tmp_path / "notes.h5").read_text() == "not HDF5"


@pytest.mark.skipif(not PID_LAW.is_file(), reason="pid_law.so not built")
def test_library_law_sweep(tmp_path):
    """examples/c/rigid_link_library.nml as the base scene, its law from the shared library
    beside it (&controller library = 'pid_law.so', examples/c/pid_law.c), swept over the
    disturbance torque under mpirun with 2 ranks: the worker rank loads the library itself.
    Each case's tip follows the PD's closed form with its torque (observed 1.8e-10 rad at BDF
    rtol 1e-9; bound 1e-8 rad), the control-error metrics are NaN (a user law's error is its
    own) and the cases are those of a serial sweep, bit for bit. The law's params are a
    list: a name without an entry is refused with a message."""
    import flexmor
    base = (ROOT / "examples" / "c" / "rigid_link_library.nml").read_text()
    base = base.replace("t_end = 10.0", "t_end = 2.0")
    shutil.copy(PID_LAW, tmp_path / "pid_law.so")
    write_inputs(tmp_path, """&sweep base = 'base.nml', node = 'tip', case_files = .true. /
&parameter name = 'hinge.j1.torque', values = 0.02, 0.05, 0.08 /
""", base)
    proc = run_sweep(tmp_path, 2)
    assert proc.returncode == 0, proc.stderr
    res = read(tmp_path / "out.h5")
    assert list(res["status"]) == [0, 0, 0] and list(res["rank"]) == [1, 1, 1], res["message"]
    assert np.all(np.isnan(res["metrics"]["final_control_error"]))
    sweep = flexmor.read_sweep(tmp_path / "out.h5")
    for i, tau in enumerate([0.02, 0.05, 0.08]):
        result = flexmor.read_result(sweep.case_file(i))
        t, tip = result.time, result.nodes["tip"].position
        assert len(t) == 201
        angle = np.arctan2(tip[:, 1], tip[:, 0])
        assert np.max(np.abs(angle - rigid_link_pd(t, tau=tau))) < 1e-8
    proc = run_sweep(tmp_path, out="serial.h5")
    assert proc.returncode == 0, proc.stderr
    serial = read(tmp_path / "serial.h5")
    for name, values in serial["metrics"].items():
        assert np.array_equal(values, res["metrics"][name], equal_nan=True), name
    (tmp_path / "sweep.nml").write_text("""&sweep base = 'base.nml', node = 'tip' /
&parameter name = 'controller.ext.params', values = 1.0, 2.0 /
""")
    proc = run_sweep(tmp_path, out="params.h5")
    assert proc.returncode == 1 and "'params'" in proc.stderr and "list" in proc.stderr
    assert "'controller.ext.params(1)'" in proc.stderr


@pytest.mark.skipif(not PID_LAW.is_file(), reason="pid_law.so not built")
def test_sweep_of_library_law_params(tmp_path):
    """Entries of a library law's params swept under mpirun with 2 ranks: kp = params(1) and
    kd = params(3) of examples/c/rigid_link_library.nml's PD (two entries of one list, each
    its own &parameter), the other entries as the base scene has them. Each case's tip follows
    the PD's closed form with its own kp and kd (observed 2.5e-10 rad at BDF rtol 1e-9; bound
    1e-8 rad), so the larger kp settles nearer zero (tau / kp); the sweep file keeps the names
    as given, and summary and plot take them. An entry beyond the four params, or the same
    entry twice, is refused before any case runs."""
    import flexmor
    from flexmor import sweep_plot, sweep_summary
    base = (ROOT / "examples" / "c" / "rigid_link_library.nml").read_text()
    base = base.replace("t_end = 10.0", "t_end = 2.0")
    shutil.copy(PID_LAW, tmp_path / "pid_law.so")
    kp, kd = "controller.ext.params(1)", "controller.ext.params(3)"
    write_inputs(tmp_path, f"""&sweep base = 'base.nml', node = 'tip', case_files = .true. /
&parameter name = '{kp}', values = 2.0, 8.0 /
&parameter name = '{kd}', values = 0.5, 0.25 /
""", base)
    proc = run_sweep(tmp_path, 2)
    assert proc.returncode == 0, proc.stderr
    sweep = flexmor.read_sweep(tmp_path / "out.h5")
    assert sweep.parameter_names == [kp, kd] and list(sweep.status) == [0, 0, 0, 0]
    final = []
    for i in range(4):
        gain, damping = sweep.parameter(kp)[i], sweep.parameter(kd)[i]
        assert (gain, damping) == ([2.0, 8.0][i // 2], [0.5, 0.25][i % 2])
        result = flexmor.read_result(sweep.case_file(i))
        tip = result.nodes["tip"].position
        angle = np.arctan2(tip[:, 1], tip[:, 0])
        assert np.max(np.abs(angle - rigid_link_pd(result.time, kp=gain, kd=damping))) < 1e-8
        assert result.attrs["input_overrides"].startswith(f"{kp} = ")
        final.append(abs(angle[-1]))
    assert max(final[2:]) < min(final[:2])
    assert sweep_summary.main([str(tmp_path / "out.h5"), "--csv", str(tmp_path / "s.csv")]) == 0
    assert (tmp_path / "s.csv").read_text().splitlines()[0].count("controller.ext.params(") == 2
    png = tmp_path / "kp.png"
    assert sweep_plot.main([str(tmp_path / "out.h5"), "--metric", "max_tip_deflection", "--x",
                            kp, "--where", f"{kd}=0.5", "-o", str(png)]) == 0
    assert png.read_bytes()[:4] == b"\x89PNG"
    for extra, fragments in [
            (f"&parameter name = 'controller.ext.params(5)', values = 1 /",
             ["'controller.ext.params(5)'", "entry 5", "has 4 entries", "base.nml"]),
            (f"&parameter name = '{kp}', values = 1 /\n&parameter name = '{kp}', values = 2 /",
             ["&parameter #2", f"'{kp}'", "the same scene variable"])]:
        (tmp_path / "sweep.nml").write_text("&sweep base = 'base.nml', node = 'tip' /\n" + extra
                                            + "\n")
        proc = run_sweep(tmp_path, out="bad.h5")
        assert proc.returncode == 1, proc.stderr
        assert all(f in proc.stderr for f in fragments), proc.stderr
        assert not (tmp_path / "bad.h5").exists()


def test_sweep_of_gravity_entry_matches_direct_runs(tmp_path):
    """scene.gravity(2) swept on the flexible arm of BASE with &scene gravity = 0.5, -9.81
    (gx stays 0.5): each case's result file holds the tip path a flexmor run of the scene
    with that gravity written by hand gives (the same scene: observed identical, bound
    1e-12 m), and the stronger gravity deflects the tip more (observed 0.4900 and 0.4954 m)."""
    base = "&scene gravity = 0.5, -9.81 /\n" + BASE
    write_inputs(tmp_path, """&sweep base = 'base.nml', node = 'tip', case_files = .true. /
&parameter name = 'scene.gravity(2)', values = -3.0, -30.0 /
""", base)
    proc = run_sweep(tmp_path, 2)
    assert proc.returncode == 0, proc.stderr
    import flexmor
    sweep = flexmor.read_sweep(tmp_path / "out.h5")
    assert list(sweep.status) == [0, 0]
    assert np.array_equal(sweep.parameter("scene.gravity(2)"), [-3.0, -30.0])
    for i, gy in enumerate(["-3.0", "-30.0"]):
        (tmp_path / f"direct{i}.nml").write_text(base.replace("-9.81", gy))
        direct = subprocess.run([str(FLEXMOR_BIN), f"direct{i}.nml", "-o", f"direct{i}.h5",
                                 "-q"], cwd=tmp_path, env=ENV, capture_output=True, text=True,
                                timeout=600)
        assert direct.returncode == 0, direct.stderr
        want = flexmor.read_result(tmp_path / f"direct{i}.h5").nodes["tip"].position
        got = flexmor.read_result(sweep.case_file(i)).nodes["tip"].position
        assert got.shape == want.shape and np.max(np.abs(got - want)) < 1e-12
    deflection = sweep.metric("max_tip_deflection")
    assert deflection[1] > deflection[0] > 0


def test_example_sweep_every_case_runs(tmp_path):
    """input/sweep_two_link.nml, serially: all 12 cases succeed. The last one (joints turned by
    3 pi / 4 and pi / 2) failed in its metrics: the rigid-link reference's kinematic Newton
    started from the run's end configuration. Its max_tip_deflection is the largest distance
    of the tip from the rigid-link tip along the cubic laws, computed here from the same case
    run by flexmor and the closed-form rigid kinematics: equal within the rigid solve's
    tolerance (kinematic Newton ~1e-10 m; observed 2e-14 m; bound 1e-8 m)."""
    for name in ("sweep_two_link.nml", "two_link.nml"):
        (tmp_path / name).write_text((ROOT / "input" / name).read_text())
    (tmp_path / "sweep.nml").write_text((tmp_path / "sweep_two_link.nml").read_text())
    proc = run_sweep(tmp_path)
    assert proc.returncode == 0, proc.stderr
    res = read(tmp_path / "out.h5")
    assert list(res["status"]) == [0] * 12, res["message"]
    phi1, phi2, duration = (float(res["parameters"][f"motion.{name}"][-1])
                            for name in ("phi1.end", "phi2.end", "phi1.duration"))
    text = (ROOT / "input" / "two_link.nml").read_text()
    law = "law = 'cubic', start = 0.0, end = 1.5707963267948966, duration = 0.5 /"
    assert text.count(law) == 2
    text = text.replace(f"'phi1', {law}", f"'phi1', law = 'cubic', start = 0.0, end = {phi1!r}, "
                        f"duration = {duration!r} /")
    text = text.replace(f"'phi2', {law}", f"'phi2', law = 'cubic', start = 0.0, end = {phi2!r}, "
                        f"duration = {duration!r} /")
    assert repr(phi1) in text and repr(phi2) in text
    (tmp_path / "case.nml").write_text(text)
    run = subprocess.run([str(FLEXMOR_BIN), "-q", "case.nml", "-o", "case.h5"], cwd=tmp_path,
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    with h5py.File(tmp_path / "case.h5") as f:
        t, tip = f["time"][:], f["nodes/tip/position"][:, :2]
    s = np.clip(t / duration, 0, 1)
    cubic = 3 * s**2 - 2 * s**3
    a1, a2 = phi1 * cubic, phi1 * cubic + phi2 * cubic
    rigid = np.stack([0.545 * np.cos(a1) + 0.675 * np.cos(a2),
                      0.545 * np.sin(a1) + 0.675 * np.sin(a2)], axis=1)
    expected = np.max(np.linalg.norm(tip - rigid, axis=1))
    assert abs(res["metrics"]["max_tip_deflection"][-1] - expected) < 1e-8, \
        (res["metrics"]["max_tip_deflection"][-1] - expected)


def test_failed_case_keeps_its_whole_message(tmp_path):
    """A failed case's message with its cause: the four-bar with its rocker pin moved to a
    dead point fails with a CVODE error and the kinematics' explanation after it (about 400
    bytes), which the 256 bytes of /cases/message used to cut off. Files of flexmor 0.6 (256
    bytes) still resume: the message is cut to their length."""
    base = (ROOT / "input" / "four_bar.nml").read_text().replace("t_end = 0.0838",
                                                                  "t_end = 0.002")
    sweep = ("&sweep base = 'base.nml', mode = 'product', node = 'B' /\n"
             "&parameter name = 'node.B.y', values = 0.25, 2.5e-5 /\n")
    write_inputs(tmp_path, sweep=sweep, base=base)
    proc = run_sweep(tmp_path, 2)
    assert proc.returncode == 0, proc.stderr
    res = read(tmp_path / "out.h5")
    assert list(res["status"]) == [0, 3], res
    message = res["message"][1]
    assert len(message.encode()) > 256 and message.endswith("aligned at a dead point)"), message
    assert "CVODE failed at t = 0.154" in message
    with h5py.File(tmp_path / "out.h5", "r+") as f:     # as written by flexmor 0.6
        del f["cases/message"]
        f["cases/message"] = np.array([b"", b""], dtype="S256")
        f["cases/status"][1] = -1
    proc = run_sweep(tmp_path, 2)
    assert proc.returncode == 0, proc.stderr
    assert "1 already in" in proc.stdout
    res = read(tmp_path / "out.h5")
    assert list(res["status"]) == [0, 3] and res["message"][1] == message.encode()[:256].decode()
