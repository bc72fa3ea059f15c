"""Every bad input gets a one-line error naming the file (and group/variable where there is
one), a non-zero exit status, no backtrace, no NaN, and no result file left behind."""
import subprocess

import numpy as np
import pytest

from helpers import ARM, BIN, assert_clean_error


GOOD = "\n" + ARM + """&motion label = 'm1', law = 'cubic', start = 0, end = 0.5, duration = 0.05 /
&mass node = 'tip', m = 0.1 /
&modal /
&dynamic t_end = 0.02, output_dt = 1e-3 /
"""


def run(tmp_path, text, args=None):
    nml = tmp_path / "scene.nml"
    nml.write_text(text)
    out = tmp_path / "out.h5"
    cmd = [BIN, str(nml), "-o", str(out)] if args is None else [BIN] + args
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120, cwd=tmp_path)
    return proc, out


def test_good_scene_runs(tmp_path):
    proc, out = run(tmp_path, GOOD)
    assert proc.returncode == 0, proc.stderr
    assert out.exists()


def test_missing_file(tmp_path):
    proc, out = run(tmp_path, GOOD, [str(tmp_path / "nope.nml"), "-o", str(tmp_path / "out.h5")])
    assert_clean_error(proc, tmp_path / "out.h5", "nope.nml")


def test_unreadable_file(tmp_path):
    (tmp_path / "dir.nml").mkdir()
    proc, _ = run(tmp_path, GOOD, [str(tmp_path / "dir.nml"), "-o", str(tmp_path / "out.h5")])
    assert_clean_error(proc, tmp_path / "out.h5", "dir.nml")


def test_no_arguments(tmp_path):
    proc, out = run(tmp_path, GOOD, [])
    assert_clean_error(proc, out, "usage")


def test_output_onto_the_input_keeps_the_scene(tmp_path):
    """`-o scene.nml` (however spelled, or through a link) replaced the scene by the result."""
    nml = tmp_path / "scene.nml"
    nml.write_text(GOOD)
    (tmp_path / "link.nml").symlink_to("scene.nml")
    for args in (["scene.nml", "-o", "scene.nml"], ["scene.nml", "-o", "./scene.nml"],
                 ["link.nml", "-o", "scene.nml"]):
        proc = subprocess.run([BIN, *args], capture_output=True, text=True, timeout=120,
                              cwd=tmp_path)
        assert proc.returncode == 4, proc.stderr
        assert_clean_error(proc, tmp_path / "out.h5", "is the input file")
        assert nml.read_text() == GOOD


def test_output_onto_a_special_file_is_refused(tmp_path):
    """The result is renamed onto its name: a pipe or device there (-o /dev/null as root) was
    replaced by a regular file."""
    import os
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    proc, _ = run(tmp_path, GOOD, [str(tmp_path / "scene.nml"), "-o", str(fifo)])
    assert proc.returncode == 4, proc.stderr
    assert_clean_error(proc, tmp_path / "out.h5", "not a regular file")
    assert fifo.is_fifo()


def test_output_option_twice(tmp_path):
    proc, out = run(tmp_path, GOOD, ["scene.nml", "-o", "a.h5", "-o", "out.h5"])
    assert proc.returncode == 1
    assert_clean_error(proc, out, "-o given twice")


CASES = {
    "unknown group": (GOOD + "&solver tol = 1 /\n", ["scene.nml", "&solver"]),
    "unknown variable": (GOOD.replace("t_end = 0.02", "t_end = 0.02, dtt = 1"),
                         ["&dynamic", "dtt"]),
    "wrong type": (GOOD.replace("E = 7.0e10", "E = 'steel'"), ["&link", "'e'"]),
    "wrong type logical": (GOOD.replace("fixed = .true.", "fixed = 3"), ["&node", "fixed"]),
    "missing required": (GOOD.replace("E = 7.0e10,", ""), ["&link", "'e'", "missing"]),
    "zero area": (GOOD.replace("A = 1.0e-4", "A = 0"), ["&link", "'A'", "positive"]),
    "negative inertia": (GOOD.replace("I = 1.0e-9", "I = -1e-9"), ["&link", "'I'"]),
    "zero density": (GOOD.replace("rho = 2700", "rho = 0"), ["&link", "'rho'"]),
    "negative length": (GOOD.replace("x = 1, y = 0", "x = 0, y = 0"),
                        ["arm", "same place"]),
    "undefined node": (GOOD.replace("to = 'tip'", "to = 'tp'"), ["&link", "'to'", "'tp'"]),
    "undefined mass node": (GOOD.replace("&mass node = 'tip'", "&mass node = 'top'"),
                            ["&mass", "'top'"]),
    "undefined motion": (GOOD.replace("motion = 'm1'", "motion = 'm2'"), ["&hinge", "'m2'"]),
    "undefined output node": (GOOD + "&output nodes = 'tip', 'elbow' /\n", ["&output", "elbow"]),
    "mechanism (too few conditions)": (
        GOOD.replace("mode = 'prescribed', motion = 'm1'", "mode = 'released'"),
        ["do not solve", "mechanism"]),
    "over-constrained (too many dynamic)": (
        GOOD.replace("&node label = 'tip', x = 1, y = 0 /",
                     "&node label = 'tip', x = 1, y = 0, fixed = .true. /"),
        ["do not solve", "over-constrained"]),
    "singular mass": (
        GOOD + "&node label = 'b', x = 1, y = 1 /\n"
               "&link label = 'arm2', from = 'tip', to = 'b', E = 7e10, A = 1e-4, I = 1e-9, "
               "rho = 2700 /\n"
               "&hinge label = 'j3', node = 'b', link = 'arm2', mode = 'dynamic', "
               "stiffness = 10 /\n",
        ["mass matrix is singular"]),
    "zero time step": (GOOD.replace("t_end = 0.02", "t_end = 0.02, integrator = 'galpha', dt = 0"),
                       ["&dynamic", "'dt'"]),
    "negative end time": (GOOD.replace("t_end = 0.02", "t_end = -1"), ["&dynamic", "'t_end'"]),
    # Below what double precision meets (galpha_adaptive shrank its steps without end), and
    # error weights that overflow when squared (a floating-point trap in CVODE).
    "rtol below 1e-14": (GOOD.replace("t_end = 0.02", "t_end = 0.02, rtol = 1e-20"),
                         ["&dynamic", "'rtol'", "at least"]),
    "atol below 1e-100": (GOOD.replace("t_end = 0.02", "t_end = 0.02, integrator = 'bdf', "
                                       "atol = 1e-200"), ["&dynamic", "'atol'", "at least"]),
    "zero output step": (GOOD.replace("output_dt = 1e-3", "output_dt = 0"), ["'output_dt'"]),
    "unknown integrator": (GOOD.replace("t_end = 0.02", "t_end = 0.02, integrator = 'rk4'"),
                           ["'integrator'", "rk4"]),
    "unknown law": (GOOD.replace("law = 'cubic'", "law = 'cubik'"), ["&motion", "'law'", "cubik"]),
    "output node twice": (GOOD + "&output nodes = 'tip', 'tip' /\n", ["&output", "twice"]),
    "internal jacobian with galpha": (
        GOOD.replace("t_end = 0.02", "t_end = 0.02, integrator = 'galpha', jacobian = 'internal'"),
        ["'jacobian'", "bdf"]),
    "truss mass keyword": (GOOD + "&node label = 'c', x = 1, y = 1, fixed = .true. /\n"
                           "&truss label = 't', from = 'tip', to = 'c', E = 1e9, A = 1e-6, "
                           "mass = 'lumpd' /\n", ["&truss", "lumpd"]),
    "damping on a free hinge": (GOOD.replace("mode = 'prescribed', motion = 'm1'",
                                             "mode = 'dynamic', damping = 0.1"),
                                ["&hinge", "'damping'"]),
    "unknown mode class": (GOOD.replace("mode = 'prescribed'", "mode = 'rigidd'"),
                           ["&hinge", "rigidd"]),
    "unterminated string": (GOOD.replace("label = 'arm'", "label = 'arm"), ["scene.nml"]),
    "group not closed": (GOOD.replace("&modal /", "&modal"), ["scene.nml"]),
    "no nodes": ("&modal /\n", ["&node"]),
    "twice defined node": (GOOD + "&node label = 'tip', x = 2, y = 0 /\n", ["tip", "twice"]),
    # Expanded in memory: 16 GB (and, with two such items, an integer overflow) before.
    "huge repeat count": (GOOD.replace("&modal /", "&scene gravity = 2000000000*0.0 /\n&modal /"),
                          ["scene.nml:", "&scene #1", "'gravity'", "more than 10000000 values"]),
    "huge repeat count of a string": (GOOD + "&output nodes = 1500000000*'tip', 1500000000*'tip' /\n",
                                      ["&output #1", "'nodes'", "more than 10000000 values"]),
    # The static size check must leave too many frequencies to their own message.
    "static n_frequencies huge": (GOOD.replace("&modal /", "&static n_frequencies = 2000000000 /"),
                                  ["&static", "'n_frequencies'", "dynamic coordinates"]),
    # A controller or &linear naming 'j1' took whichever element came first.
    "hinge label twice": (GOOD + "&hinge label = 'j1', node = 'tip', link = 'arm', "
                          "mode = 'dynamic' /\n", ["&hinge #2", "'j1'", "twice"]),
    "truss with a hinge's label": (GOOD + "&node label = 'c', x = 1, y = 1, fixed = .true. /\n"
                                   "&truss label = 'j1', from = 'tip', to = 'c', E = 1e9, "
                                   "A = 1e-6 /\n", ["&truss #1", "'j1'", "&hinge #1"]),
    # Products of such inputs overflowed deep in the model (a floating-point trap in Debug).
    "node coordinate beyond 1e100": (GOOD.replace("x = 1, y = 0", "x = 1e300, y = 0"),
                                     ["&node #2", "'x'", "out of range", "1e100"]),
    "gravity beyond 1e100": (GOOD.replace("&modal /", "&scene gravity = 0, -1e300 /\n&modal /"),
                             ["&scene #1", "'gravity'", "1e100"]),
    # A floating-point trap (the sample count overflowed an integer) and a hang allocating the
    # states (16 GB), before.
    "controller period far too small": (
        GOOD.replace("mode = 'prescribed', motion = 'm1'", "mode = 'dynamic'") +
        "&controller label = 'c', actuator = 'j1.torque', measure = 'j1.angle', kp = 1, "
        "period = 1e-12 /\n", ["&controller 'c'", "'period'", "1e7"]),
    "controller n_states far too large": (
        GOOD.replace("mode = 'prescribed', motion = 'm1'", "mode = 'dynamic'") +
        "&controller label = 'c', law = 'user', actuator = 'j1.torque', measure = 'j1.angle', "
        "n_states = 2000000000 /\n", ["&controller #1", "'n_states'", "10000"]),
    "static newton": (GOOD.replace("&modal /", "&force node = 'tip', fy = -50 /\n"
                                   "&static n_steps = 1, max_iter = 1, tol = 1e-14 /"),
                      ["static", "did not converge"]),
    # The results of 2e9 load steps (880 GB) were allocated: a Fortran runtime error.
    "static steps beyond memory": (GOOD.replace("&modal /", "&force node = 'tip', fy = -50 /\n"
                                                "&static n_steps = 2000000000 /"),
                                   ["&static", "'n_steps'", "GB (limit 4 GB)"]),
    "arc-length steps beyond memory": (GOOD.replace(
        "&modal /", "&force node = 'tip', fy = -50 /\n"
        "&static method = 'arc_length', n_steps = 2000000000 /"),
        ["&static", "'n_steps'", "GB (limit 4 GB)"]),
}


FOUR_BAR = """
&node label = 'o1', x = 0, y = 0, fixed = .true. /
&node label = 'a', x = 0.5, y = 0 /
&node label = 'b', x = 1.0, y = 0.6 /
&node label = 'o2', x = 1.0, y = 0, fixed = .true. /
&link label = 'crank', from = 'o1', to = 'a', E = 7e10, A = 1e-4, I = 1e-9, rho = 2700 /
&link label = 'coupler', from = 'a', to = 'b', E = 7e10, A = 1e-4, I = 1e-9, rho = 2700 /
&link label = 'rocker', from = 'b', to = 'o2', E = 7e10, A = 1e-4, I = 1e-9, rho = 2700 /
&hinge label = 'drive', node = 'o1', link = 'crank', mode = 'prescribed', motion = 'm' /
&hinge label = 'ha', node = 'a', link = 'coupler', mode = 'released' /
&hinge label = 'hb', node = 'b', link = 'rocker', mode = 'released' /
&hinge label = 'ho2', node = 'o2', link = 'rocker', mode = 'released' /
&motion label = 'm', law = 'cubic', end = 3.14159, duration = 1.0 /
&dynamic t_end = 0.01, output_dt = 1e-3 /
"""

RED = GOOD + "&reduction {} /\n"
CASES.update({
    "reduction k too large": (RED.format("n_modes = 5"), ["&reduction", "n_modes = 5",
                                                          "number of dynamic coordinates (4)"]),
    "reduction k zero": (RED.format("n_modes = 0"), ["&reduction", "'n_modes'", "at least 1"]),
    "reduction two selections": (RED.format("n_modes = 1, cutoff_hz = 100"),
                                 ["&reduction", "exactly one"]),
    "reduction no selection": (RED.format(""), ["&reduction", "exactly one"]),
    "reduction without dynamic": (RED.format("n_modes = 1").replace(
        "&dynamic t_end = 0.02, output_dt = 1e-3 /", ""), ["&reduction", "&dynamic"]),
    "reduction basis does not solve": (FOUR_BAR + "&reduction n_modes = 1, basis_time = 1.0 /\n",
                                       ["&reduction", "basis_time", "did not converge"]),
    "reduction basis_prescribed count": (RED.format("n_modes = 1, basis_prescribed = 0.1, 0.2"),
                                         ["'basis_prescribed'", "1 values", "got 2"]),
    "reduction update without interval": (RED.format("n_modes = 1, update = 'mac'"),
                                          ["&reduction", "'update_interval'"]),
    # Never ended: the basis check times did not move past t.
    "reduction update interval far too small": (
        RED.format("n_modes = 1, update = 'interval', update_interval = 1e-12"),
        ["&reduction", "'update_interval'", "1e7"]),
    "reduction unknown update": (RED.format("n_modes = 1, update = 'often'"),
                                 ["'update'", "often"]),
    "reduction unknown eigensolver": (RED.format("n_modes = 1, eigensolver = 'magma'"),
                                      ["'eigensolver'", "magma"]),
    "reduction cutoff below lowest mode": (RED.format("cutoff_hz = 1e-3"),
                                           ["no mode below", "cutoff_hz"]),
    "reduction bad mac threshold": (RED.format("n_modes = 1, mac_threshold = 1.5"),
                                    ["'mac_threshold'"]),
    "reduction auto without motion": (RED.format("auto_factor = 2").replace(
        "law = 'cubic'", "law = 'constant'"), ["auto_factor", "constant"]),
    "reduction static correction without stiffness": (
        RED.format("n_modes = 1, static_correction = .true.").replace(
            "mode = 'prescribed', motion = 'm1'", "mode = 'dynamic'"),
        ["static_correction", "positive definite"]),
    "empty label": (GOOD.replace("label = 'arm'", "label = ''"), ["&link", "'label'", "empty"]),
    "label with a trailing blank": (GOOD.replace("label = 'tip', x", "label = 'tip ', x"),
                                    ["&node #2", "'label'", "'tip '", "blank"]),
    # Cut to 64 characters in the model: '&output nodes' then called such a node undefined.
    "label too long": (GOOD.replace("'tip'", "'" + "t" * 70 + "'"),
                       ["&node #2", "'label'", "70 characters long", "48"]),
    # '&output nodes = 'arm.1'' took whichever of the two came first.
    "node label of a link's interior node": (GOOD.replace("'tip'", "'arm.1'"),
                                             ["&node #2", "'arm.1'", "interior node 1"]),
    # A NUL cut the title short in the result file; in a label it made two HDF5 names one
    # and the run failed only when writing its results.
    "NUL in a label": (GOOD.replace("label = 'tip'", "label = 'ti\x00p'"),
                       ["&node #2", "'label'", "control characters (byte 0)"]),
    "NUL in the title": (GOOD.replace("&modal /", "&scene title = 'a\x00b' /\n&modal /"),
                         ["&scene #1", "'title'", "control characters"]),
    "label with a slash": (GOOD.replace("label = 'tip', x", "label = 'a/b', x"),
                           ["&node", "'label'", "'/'"]),
    "motion on a dynamic hinge": (GOOD.replace("mode = 'prescribed'", "mode = 'dynamic'"),
                                  ["&hinge", "'motion'", "prescribed"]),
    "stiffness on a prescribed hinge": (GOOD.replace("motion = 'm1'", "motion = 'm1', stiffness = 5"),
                                        ["&hinge", "'stiffness'", "dynamic"]),
    "dt with bdf": (GOOD.replace("t_end = 0.02",
                                 "t_end = 0.02, integrator = 'bdf', dt = 1e-4"),
                    ["&dynamic", "'dt'", "galpha"]),
    "max_order with erk": (GOOD.replace("t_end = 0.02", "t_end = 0.02, integrator = 'erk', "
                                        "max_order = 3"), ["'max_order'", "bdf"]),
    "max_step with galpha": (GOOD.replace("t_end = 0.02", "t_end = 0.02, integrator = 'galpha', "
                                          "max_step = 1e-3"), ["'max_step'"]),
    "mac_threshold without mac": (RED.format("n_modes = 1, mac_threshold = 0.5"),
                                  ["'mac_threshold'", "update = 'mac'"]),
    "update_interval without update": (RED.format("n_modes = 1, update_interval = 0.1"),
                                       ["'update_interval'", "interval"]),
    # Was exit status 5, 'CVODE: CVodeSetMinStep returned -22' (an internal error).
    "max_step far too small": (GOOD.replace("t_end = 0.02", "t_end = 0.02, integrator = 'bdf', "
                                            "max_step = 1e-12"),
                               ["scene.nml:", "&dynamic #1", "'max_step'", "1e7"]),
    "max_step below the round-off of the time": (
        GOOD.replace("t_end = 0.02, output_dt = 1e-3", "t_end = 1e-10, output_dt = 1e-11, "
                     "integrator = 'bdf', max_step = 1e-17"), ["'max_step'", "round-off"]),
    "erk order": (GOOD.replace("t_end = 0.02", "t_end = 0.02, integrator = 'erk', erk_order = 7"),
                  ["'erk_order'"]),
})

# Motion laws (docs/input.md, &motion): each bad input names the group and the variable.
M1 = "&motion label = 'm1', law = 'cubic', start = 0, end = 0.5, duration = 0.05 /"
RAMP_A = "\n&motion label = 'a', law = 'ramp', rate = 1 /"
CASES.update({
    "motion sum unknown term": (GOOD.replace(M1, "&motion label = 'm1', law = 'sum', "
                                "terms = 'a', 'zz' /" + RAMP_A), ["&motion 'm1'", "'terms'", "'zz'"]),
    "motion sum of itself": (GOOD.replace(M1, "&motion label = 'm1', law = 'sum', terms = 'm1' /"),
                             ["&motion 'm1'", "'terms'", "itself"]),
    "motion sum cycle": (GOOD.replace(M1, "&motion label = 'm1', law = 'sum', terms = 'a' /\n"
                                      "&motion label = 'a', law = 'sum', terms = 'b' /\n"
                                      "&motion label = 'b', law = 'sum', terms = 'a' /"),
                         ["&motion", "'terms'", "'a' -> 'b' -> 'a'"]),
    "motion sum without terms": (GOOD.replace(M1, "&motion label = 'm1', law = 'sum' /"),
                                 ["&motion", "'terms'"]),
    "motion table not increasing": (GOOD.replace(M1, "&motion label = 'm1', law = 'table', "
                                                 "times = 0, 0.01, 0.01, values = 0, 1, 2 /"),
                                    ["&motion", "'times'", "strictly increasing"]),
    "motion table unequal lengths": (GOOD.replace(M1, "&motion label = 'm1', law = 'table', "
                                                  "times = 0, 0.01, 0.02, values = 0, 1 /"),
                                     ["&motion", "'values'", "3 times but 2 values"]),
    "motion table one point": (GOOD.replace(M1, "&motion label = 'm1', law = 'table', "
                                            "times = 0, values = 0 /"), ["&motion", "at least 2"]),
    "motion table missing file": (GOOD.replace(M1, "&motion label = 'm1', law = 'table', "
                                               "file = 'nope.csv' /"),
                                  ["&motion", "'file'", "nope.csv", "No such file"]),
    "motion table file and times": (GOOD.replace(M1, "&motion label = 'm1', law = 'table', "
                                                 "file = 'a.csv', times = 0, 1 /"),
                                    ["&motion", "'file'", "not both"]),
    "motion harmonic zero frequency": (GOOD.replace(M1, "&motion label = 'm1', law = 'harmonic', "
                                                    "amplitude = 0.1, frequency = 0 /"),
                                       ["&motion", "'frequency'", "positive"]),
    "motion spin_up zero duration": (GOOD.replace(M1, "&motion label = 'm1', law = 'spin_up', "
                                                  "rate = 1, duration = 0 /"),
                                     ["&motion", "'duration'", "positive"]),
    "motion rate with cubic": (GOOD.replace("duration = 0.05", "duration = 0.05, rate = 2"),
                               ["&motion", "'rate'", "'ramp' or 'spin_up'"]),
    "motion end with ramp": (GOOD.replace(M1, "&motion label = 'm1', law = 'ramp', rate = 1, "
                                          "end = 2 /"), ["&motion", "'end'", "'cubic'"]),
    "motion start with sum": (GOOD.replace(M1, "&motion label = 'm1', law = 'sum', terms = 'a', "
                                           "start = 1 /" + RAMP_A), ["&motion", "'start'", "'sum'"]),
    # Each of these ended in a floating-point trap (Debug) inside the motion law, its table's
    # spline or the kinematics, instead of a message.
    "motion duration far too short": (GOOD.replace("duration = 0.05", "duration = 1e-300"),
                                      ["&motion #1", "'duration'", "[1e-30, 1e30]"]),
    "motion duration far too long": (GOOD.replace("duration = 0.05", "duration = 1e300"),
                                     ["&motion #1", "'duration'", "out of range", "1e100"]),
    # Beyond the schema's ranges (1e-30 to 1e30), which keep accelerations within 1e90: the
    # motions' own 1e100 checks (accelerations) are a second line now.
    "motion duration below the range": (GOOD.replace("duration = 0.05", "duration = 1e-60"),
                                        ["&motion #1", "'duration'", "[1e-30, 1e30]", "1e-60"]),
    "motion end far too large": (GOOD.replace("end = 0.5", "end = 1e99"),
                                 ["&motion #1", "'end'", "magnitude in [1e-30, 1e30]"]),
    "motion harmonic frequency far too high": (GOOD.replace(M1, "&motion label = 'm1', law = "
                                               "'harmonic', amplitude = 0.1, frequency = 1e60 /"),
                                               ["&motion #1", "'frequency'", "[1e-30, 1e30]"]),
    "motion ramp rate far too high": (GOOD.replace(M1, "&motion label = 'm1', law = 'ramp', "
                                                   "rate = 1e300 /"), ["&motion #1", "'rate'"]),
    "motion table times far too close": (GOOD.replace(M1, "&motion label = 'm1', law = 'table', "
                                                      "times = 0, 1e-300, 2e-300, values = 0, "
                                                      "0.1, 0.2 /"),
                                         ["&motion #1", "'times'", "value 2", "1e-30"]),
    "motion table value far too large": (GOOD.replace(M1, "&motion label = 'm1', law = 'table', "
                                                      "times = 0, 0.01, 0.02, values = 0, 1e99, "
                                                      "0 /"), ["&motion #1", "'values'", "value 2"]),
    "motion ramp with auto_factor": (RED.format("auto_factor = 2").replace(
        M1, "&motion label = 'm1', law = 'sum', terms = 'a' /" + RAMP_A),
        ["&motion 'm1'", "ramp", "auto_factor"]),
})


def test_motion_table_csv(tmp_path):
    """A table from a CSV file next to the scene (not the working folder), with a header;
    a bad line is named with its file and number."""
    sub = tmp_path / "scene"
    sub.mkdir()
    (sub / "m.csv").write_text("t, angle\n0, 0\n0.005, 0.01\n0.01, 0.03\n0.02, 0.05\n")
    text = GOOD.replace(M1, "&motion label = 'm1', law = 'table', file = 'm.csv' /")
    (sub / "scene.nml").write_text(text)
    out = tmp_path / "out.h5"
    proc = subprocess.run([BIN, str(sub / "scene.nml"), "-o", str(out)], capture_output=True,
                          text=True, timeout=120, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    out.unlink()
    (sub / "m.csv").write_text("t, angle\n0, 0\n\n0.01, x\n")
    proc = subprocess.run([BIN, str(sub / "scene.nml"), "-o", str(out)], capture_output=True,
                          text=True, timeout=120, cwd=tmp_path)
    assert_clean_error(proc, out, "&motion", "'file'", "m.csv' line 4", "0.01, x")

@pytest.mark.parametrize("csv,fragments", [
    # A floating-point trap (overflow) in the list-directed read.
    ("0, 0\n0.01, 1e400\n", ["m.csv' line 2", "out of range"]),
    ("1e400, 0\n1, 0.1\n2, 0.2\n", ["m.csv' line 1", "out of range"]),
])
def test_motion_table_csv_number_out_of_range(tmp_path, csv, fragments):
    (tmp_path / "m.csv").write_text(csv)
    proc, out = run(tmp_path, GOOD.replace(M1, "&motion label = 'm1', law = 'table', "
                                           "file = 'm.csv' /"))
    assert_clean_error(proc, out, "&motion", "'file'", *fragments)


@pytest.mark.parametrize("csv", [
    "0, 0\n" + " " * 5000 + "0.01, 0.03\n0.02, 0.05\n",   # was cut at 4096: a blank line
    "\ufeff0, 0\n0.01, 0.03\n0.02, 0.05\n",                 # the BOM made line 1 a header
    "\n  \nt, angle\n0, 0\n0.01, 0.03\n0.02, 0.05\n",       # the header after blank lines
])
def test_motion_table_csv_keeps_every_point(tmp_path, csv):
    """Each of these tables has the points (0, 0), (0.01, 0.03), (0.02, 0.05): the run's joint
    angle at 0.02 s is the last value, which the loss of a point would change."""
    import h5py
    (tmp_path / "m.csv").write_text(csv)
    (tmp_path / "ref.csv").write_text("0, 0\n0.01, 0.03\n0.02, 0.05\n")
    results = []
    for name in ("m.csv", "ref.csv"):
        out = tmp_path / "out.h5"
        proc, out = run(tmp_path, GOOD.replace(M1, "&motion label = 'm1', law = 'table', "
                                               f"file = '{name}' /"))
        assert proc.returncode == 0, proc.stderr
        with h5py.File(out) as f:
            results.append(f["nodes/tip/position"][()])
        out.unlink()
    np.testing.assert_array_equal(results[0], results[1])


# A column, fixed at the base, for &buckling (docs/input.md); {} takes the &buckling variables.
COLUMN = """&node label = 'base', x = 0, y = 0, fixed = .true. /
&node label = 'top', x = 0, y = 1 /
&link label = 'col', from = 'base', to = 'top', n_elements = 4,
      E = 7.0e10, A = 1.0e-4, I = 1.0e-9, rho = 2700 /
&force node = 'top', fy = -70 /
&buckling {} /
"""

CASES.update({
    "buckling n_modes zero": (COLUMN.format("n_modes = 0"),
                              ["&buckling", "'n_modes'", "at least 1"]),
    "buckling load_factor zero": (COLUMN.format("load_factor = 0"),
                                  ["&buckling", "'load_factor'", "[1e-30, 1e30]", "got 0"]),
    # 1e-300 left the loads in the round-off (a wrong multiplier, 26 % off); 1e300 overflows.
    "buckling load_factor tiny": (COLUMN.format("load_factor = 1e-300"),
                                  ["&buckling", "'load_factor'", "[1e-30, 1e30]"]),
    "buckling load_factor huge": (COLUMN.format("load_factor = 1e50"),
                                  ["&buckling", "'load_factor'", "[1e-30, 1e30]"]),
    "buckling twice": (COLUMN.format("") + "&buckling /\n", ["&buckling", "only once"]),
    "buckling without load": (COLUMN.format("").replace("&force node = 'top', fy = -70 /", ""),
                              ["&buckling", "no load"]),
    "buckling without dynamic mode": (COLUMN.format("").replace("rho = 2700", "rho = 2700, "
                                                                "bending = 'rigid'"),
                                      ["no dynamic deformation mode"]),
    "buckling on a mechanism": (COLUMN.format("") + "&hinge label = 'pin', node = 'base', "
                                "link = 'col', mode = 'dynamic', stiffness = 0 /\n",
                                ["buckling", "not positive definite"]),
})


def test_motion_sum_terms_are_used(tmp_path):
    """The terms of a sum a hinge uses are used (no warning); a sum nobody uses is reported
    with its terms."""
    sums = ("&motion label = 'm1', law = 'sum', terms = 'a', 'b' /" + RAMP_A +
            "\n&motion label = 'b', law = 'harmonic', amplitude = 0.01, frequency = 5 /")
    proc, out = run(tmp_path, GOOD.replace(M1, sums))
    assert proc.returncode == 0 and "warning" not in proc.stderr, proc.stderr
    out.unlink()
    proc, out = run(tmp_path, GOOD + sums.replace("'m1'", "'s'").replace("'a'", "'c'") + "\n")
    assert proc.returncode == 0 and "'s', 'c', 'b'" in proc.stderr, proc.stderr


@pytest.mark.parametrize("name", sorted(CASES))
def test_bad_input(tmp_path, name):
    text, fragments = CASES[name]
    proc, out = run(tmp_path, text)
    assert_clean_error(proc, out, *fragments)


def test_dynamic_failure_reports_time(tmp_path):
    """A motion far too violent for the model: the run stops with the time, not NaN."""
    text = GOOD.replace("end = 0.5, duration = 0.05", "end = 2000, duration = 0.001")
    text = text.replace("t_end = 0.02", "t_end = 0.02, rtol = 1e-3")
    proc, out = run(tmp_path, text)
    assert_clean_error(proc, out, "t =")


def test_output_times_end_exactly_once(tmp_path):
    """t_end that is not a multiple of output_dt is written once, at the end."""
    import h5py
    proc, out = run(tmp_path, GOOD.replace("t_end = 0.02, output_dt = 1e-3",
                                           "t_end = 0.0095, output_dt = 1e-3"))
    assert proc.returncode == 0, proc.stderr
    with h5py.File(out) as f:
        t = f["time"][:]
    assert len(t) == 11 and t[-1] == 0.0095 and all(t[1:] > t[:-1])
