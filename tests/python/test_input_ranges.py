"""The physical inputs' ranges of the scene schema (magnitudes 0 or within 1e-30 .. 1e30):
values beyond them are refused naming the file, group and variable (and the list entry), and
scenes with every input at an extreme of its range run without a NaN, an Inf or a
floating-point trap (Debug builds trap on overflow, invalid and division by zero). Also lists
whose entries must differ, times that must increase, and control characters in messages."""
import h5py
import numpy as np
import pytest

from helpers import ARM, assert_clean_error, run_scene

GOOD = ARM + """&motion label = 'm1', law = 'cubic', start = 0, end = 0.5, duration = 0.05 /
&mass node = 'tip', m = 0.1 /
&dynamic t_end = 0.02, output_dt = 1e-3 /
"""

REFUSED = {
    "E above the range": (GOOD.replace("E = 7.0e10", "E = 2e30"),
                          ["scene.nml:", "&link #1", "'E'", "must be in [1e-30, 1e30]", "got 2e30"]),
    "I below the range": (GOOD.replace("I = 1.0e-9", "I = 1e-31"), ["&link #1", "'I'", "1e-30"]),
    # 0 means Euler-Bernoulli; a tiny G made the shear parameter 12 EI / (k G A l^2) overflow.
    "G tiny but not 0": (GOOD.replace("rho = 2700", "rho = 2700, G = 1e-300"),
                         ["&link #1", "'G'", "must be 0 or in [1e-30, 1e30]"]),
    "coordinate tiny but not 0": (GOOD.replace("x = 1, y = 0", "x = 1, y = 1e-40"),
                                  ["&node #2", "'y'", "0 or of magnitude in [1e-30, 1e30]"]),
    "force above the range": (GOOD + "&force node = 'tip', fy = -1e31 /\n",
                              ["&force #1", "'fy'", "1e30"]),
    "mass above the range": (GOOD.replace("m = 0.1", "m = 1e40"), ["&mass #1", "'m'", "1e30"]),
    "gravity entry": (GOOD + "&scene gravity = 0, -1e35 /\n",
                      ["&scene #1", "'gravity'", "value 2", "1e30"]),
    "table value entry": (GOOD.replace(
        "law = 'cubic', start = 0, end = 0.5, duration = 0.05",
        "law = 'table', times = 0, 0.01, 0.02, values = 0, 5e30, 0"),
        ["&motion #1", "'values'", "value 2", "1e30"]),
    "t_end above the range": (GOOD.replace("t_end = 0.02", "t_end = 1e50"),
                              ["&dynamic #1", "'t_end'", "[1e-30, 1e30]"]),
    # Duplicates that make no sense.
    "terms twice": (GOOD.replace(
        "law = 'cubic', start = 0, end = 0.5, duration = 0.05", "law = 'sum', terms = 'a', 'a'")
        + "&motion label = 'a', law = 'ramp', rate = 1 /\n",
        ["&motion #1", "'terms'", "'a' is given twice (entries 1 and 2)"]),
    "output node twice": (GOOD + "&output nodes = 'tip', 'base', 'tip' /\n",
                          ["&output #1", "'nodes'", "'tip' is given twice (entries 1 and 3)"]),
    "compliance node twice": (GOOD + "&output compliance_nodes = 'tip', 'tip' /\n",
                              ["&output #1", "'compliance_nodes'", "twice"]),
    "linear input twice": (GOOD + "&linear inputs = 'tip.fy', 'tip.fy', outputs = 'tip.y' /\n",
                           ["&linear #1", "'inputs'", "twice"]),
    "linear output twice": (GOOD + "&linear inputs = 'tip.fy', outputs = 'tip.y', 'tip.y' /\n",
                            ["&linear #1", "'outputs'", "twice"]),
    "node dynamic coordinate twice": (GOOD.replace("x = 1, y = 0 /", "x = 1, y = 0, "
                                                   "dynamic = 'x', 'X' /"),
                                      ["&node #2", "'dynamic'", "'x' is given twice"]),
    "controller actuator twice": (
        GOOD.replace("mode = 'prescribed', motion = 'm1'", "mode = 'dynamic'") +
        "&controller label = 'c', law = 'user', actuator = 'j1.torque', 'j1.torque', "
        "measure = 'j1.angle' /\n", ["&controller #1", "'actuator'", "twice"]),
    # Times that must increase.
    "linear times unsorted": (GOOD + "&linear inputs = 'tip.fy', outputs = 'tip.y', "
                              "times = 0.01, 0.005 /\n",
                              ["&linear #1", "'times'", "strictly increasing", "entry 2"]),
    # Two times nearest to one output sample gave the same model twice.
    "linear times on one output sample": (GOOD + "&linear inputs = 'tip.fy', outputs = 'tip.y', "
                                          "times = 0.0101, 0.0102 /\n",
                                          ["scene.nml:", "group &linear", "'times'",
                                           "entries 1 and 2", "both pick the output sample"]),
    # Accepted up to 1e9 steps while the integrators stop at 1e7: this one ran for minutes
    # into 'max_steps reached'.
    "fixed steps beyond the step limit": (GOOD.replace("t_end = 0.02, output_dt = 1e-3",
                                                       "t_end = 20, output_dt = 1, "
                                                       "integrator = 'galpha', dt = 1e-6"),
                                          ["&dynamic", "'dt'", "2.00E+07 fixed steps",
                                           "10000000 a run may take"]),
    "fixed steps of the error check beyond the step limit": (
        GOOD.replace("t_end = 0.02, output_dt = 1e-3", "t_end = 2, output_dt = 1, "
                     "integrator = 'galpha', dt = 1e-6, error_check = 'tolerance'"),
        ["&dynamic", "'dt'", "2.00E+07 fixed steps (with the error check)"]),
    "linear times repeated": (GOOD + "&linear inputs = 'tip.fy', outputs = 'tip.y', "
                              "times = 0.01, 0.01 /\n",
                              ["&linear #1", "'times'", "strictly increasing"]),
}


@pytest.mark.parametrize("name", sorted(REFUSED))
def test_refused(tmp_path, name):
    text, fragments = REFUSED[name]
    proc, out = run_scene(tmp_path, text)
    assert proc.returncode == 1, proc.stderr
    assert_clean_error(proc, out, *fragments)


def test_table_file_entry(tmp_path):
    (tmp_path / "m.csv").write_text("0, 0\n0.01, 1e31\n0.02, 0\n")
    text = GOOD.replace("law = 'cubic', start = 0, end = 0.5, duration = 0.05",
                        "law = 'table', file = 'm.csv'")
    proc, out = run_scene(tmp_path, text)
    assert_clean_error(proc, out, "&motion #1", "'values'", "value 2 of file 'm.csv' (column 2)",
                       "1e30")


def test_control_characters_are_escaped(tmp_path):
    """A form feed in a value and before a group: the message shows \\f, never the byte."""
    proc, out = run_scene(tmp_path, GOOD.replace("m = 0.1", "m = 0.1\f2"))
    assert_clean_error(proc, out, "&mass #1", "0.1\\f2")
    assert "\f" not in proc.stderr
    proc, out = run_scene(tmp_path, "\f\x1b" + GOOD)
    assert_clean_error(proc, out, "text outside a group", "\\f<0x1B>")
    assert "\f" not in proc.stderr and "\x1b" not in proc.stderr


#: The arm with every physical input at one end of its range (or the product of two at
#: opposite ends): the element matrices then span up to about 1e150 (E I / l^3 with l of a
#: few 1e-16 over a link of 1e-12 in 2 elements is about 1e60 / 1e-46) and the solver must
#: either run or stop with a clear message, never on a NaN or an overflow.
EXTREMES = {
    "stiff and light": {"E = 7.0e10": "E = 1e30", "I = 1.0e-9": "I = 1e30",
                        "A = 1.0e-4": "A = 1e-30", "rho = 2700": "rho = 1e-30",
                        "m = 0.1": "m = 1e-30"},
    "soft and heavy": {"E = 7.0e10": "E = 1e-30", "I = 1.0e-9": "I = 1e-30",
                       "A = 1.0e-4": "A = 1e30", "rho = 2700": "rho = 1e30", "m = 0.1": "m = 1e30"},
    "huge arm": {"x = 1, y = 0": "x = 1e30, y = 1e30"},
    "tiny arm": {"x = 1, y = 0": "x = 1e-11, y = 0", "end = 0.5": "end = 1e-30"},
    "huge loads": {"&dynamic": "&scene gravity = 1e30, -1e30 /\n&force node = 'tip', "
                   "fx = 1e30, fy = -1e30, moment = 1e30 /\n&dynamic"},
    "huge motion": {"end = 0.5": "end = 1e30", "duration = 0.05": "duration = 1e-30"},
    "shear and damping": {"rho = 2700": "rho = 2700, G = 1e-30, shear_factor = 1e30, "
                          "damping = 1e30"},
}


@pytest.mark.parametrize("name", sorted(EXTREMES))
@pytest.mark.parametrize("analyses", ["&static /\n&modal /\n", ""])
def test_extreme_inputs_run_or_fail_cleanly(tmp_path, name, analyses):
    text = GOOD
    for a, b in EXTREMES[name].items():
        assert a in text
        text = text.replace(a, b)
    text += analyses
    proc, out = run_scene(tmp_path, text, timeout=900)
    for bad in ("Floating-point exception", "SIGFPE", "Backtrace", "Error termination"):
        assert bad not in proc.stderr, proc.stderr
    if proc.returncode != 0:
        assert proc.returncode in (1, 2, 3), proc.stderr
        assert_clean_error(proc, out)
        return
    with h5py.File(out) as f:
        def finite(name, obj):
            if isinstance(obj, h5py.Dataset) and obj.dtype.kind == "f":
                assert np.all(np.isfinite(obj[()])), name
        f.visititems(finite)


def test_link_too_long_for_its_units(tmp_path):
    """A link of 1e13 length units: rotations (rad) and lengths 13 decades apart make the
    kinematic Jacobian's pivots look singular, which blamed the mode classes ('coordinate
    ... is not determined'); scaled to unit rows and columns it is regular, and the message
    says to take a larger unit. A link of 1e3 units runs."""
    proc, out = run_scene(tmp_path, GOOD.replace("x = 1, y = 0", "x = 1e13, y = 0"))
    assert proc.returncode == 2, proc.stderr
    assert_clean_error(proc, out, "singular only in the units of the scene", "larger unit")
    assert "not determined" not in proc.stderr
    proc, out = run_scene(tmp_path, GOOD.replace("x = 1, y = 0", "x = 1e3, y = 0"))
    assert proc.returncode == 0, proc.stderr


@pytest.mark.parametrize("scene,edits", [
    # A torque pulse of 1e30 N m on the free body, and loads of 1e30 on the spatial pivot:
    # the kinematic Newton's iterates ran away (Euler parameters of 1e25 and more) and the
    # spatial beam's twist overflowed, a floating-point trap in Debug builds.
    ("torque_free_body", {"values = 0.0, 1.0, 0.0": "values = 0.0, 1e30, 0.0",
                          "t_end = 10.0": "t_end = 0.005"}),
    ("cross_spring_pivot_spatial", {}),
])
def test_runaway_spatial_kinematics_fail_cleanly(tmp_path, scene, edits):
    from helpers import ROOT
    text = (ROOT / "input" / f"{scene}.nml").read_text()
    if not edits:   # every load at 1e30 in magnitude, statics only
        import re
        text = re.sub(r"\b(f[xyz]|m[xyz])\s*=\s*(-?)[0-9.eE+-]+",
                      lambda m: f"{m.group(1)} = {m.group(2)}1e30", text)
        text = re.sub(r"&dynamic[^/]*/", "", text)
    for a, b in edits.items():
        assert a in text
        text = text.replace(a, b)
    proc, out = run_scene(tmp_path, text, timeout=900)
    assert proc.returncode == 3, proc.stderr
    assert_clean_error(proc, out)
