"""Progress lines on stderr during long runs: well-formed, one per line, advancing; none with -q
and none from a short run. The interval is shortened through FLEXMOR_PROGRESS_INTERVAL so that
runs of a tenth of a second give several lines on any machine (the default is 2 s)."""
import os
import re
import subprocess

import pytest

from helpers import ARM, BIN, TWO_LINK


# 1 ms: the scenes below take 0.08 to 0.5 s in a Release build here (49 to 289 lines), so a
# machine 20 times faster still prints two or more. At 20 ms the generalized-alpha scene gave
# one line in a Release build once its steps had become cheap.
INTERVAL = "0.001"

# BDF has a single output interval (output_dt = t_end), so its lines can only come from polling
# inside the one long CVODE call.
SCENES = {
    "bdf": ("dynamic", 1.0e-3, """
&node label = 'base', x = 0, y = 0, fixed = .true. /
&node label = 'tip', x = 1, y = 0 /
&link label = 'arm', from = 'base', to = 'tip', n_elements = 32,
      E = 7.0e10, A = 1.0e-4, I = 1.0e-9, rho = 2700 /
&hinge label = 'j1', node = 'base', link = 'arm', mode = 'prescribed', motion = 'm1' /
&motion label = 'm1', law = 'cubic', start = 0, end = 0.5, duration = 0.05 /
&mass node = 'tip', m = 0.1 /
&dynamic t_end = 1.0e-3, output_dt = 1.0e-3, integrator = 'bdf' /
"""),
    "galpha": ("dynamic", 0.2, TWO_LINK.format(n=8) + """
&dynamic t_end = 0.2, output_dt = 0.01, integrator = 'galpha', dt = 1.0e-4 /
"""),
    "reduced": ("reduced", 0.35, TWO_LINK.format(n=6) + """
&reduction n_modes = 3, update = 'interval', update_interval = 0.05 /
&dynamic t_end = 0.35, output_dt = 0.01, integrator = 'erk', rtol = 1e-9, atol = 1e-11 /
"""),
    "static": ("static", 40, """
&node label = 'root', x = 0.0, y = 0.0, fixed = .true. /
&node label = 'tip', x = 1.5, y = 0.0 /
&link label = 'beam', from = 'root', to = 'tip', n_elements = 16,
      E = 7.0e10, A = 1.0e-4, I = 1.0e-9, rho = 2700 /
&force node = 'tip', fy = 300.0 /
&static n_steps = 40 /
"""),
}

SHORT = "\n" + ARM + """&motion label = 'm1', law = 'cubic', start = 0, end = 0.5, duration = 0.05 /
&mass node = 'tip', m = 0.1 /
&static n_steps = 2 /
&dynamic t_end = 0.02, output_dt = 1e-3 /
"""

DURATION = r"(\d+\.\d) (s|min|h)"
# The ETA goes by the rate since the previous line; where nothing has advanced since (lines 1 ms
# apart here) it says so instead.
# A line whose fraction has hardly moved (a reduced run's first line after a basis update) may
# promise 'more than 10000 h'; steps too small to finish would be named before the ETA.
ETA = (r"(?:, steps of about \S+ s \(under 1e-7 of the run: too small to finish; a singular "
       r"configuration, or t_end too long\?\))?"
       r"(?:, ETA " + DURATION + r"|, ETA more than 10000 h"
       r"|, ETA unknown: no progress since the last line)?$")
TIME_LINE = re.compile(
    r"^flexmor: (dynamic|reduced|check) +t = (\d+\.\d+) of (\d+\.\d+) s \((\d+\.\d) %\), (\d+) steps, "
    r"(?:(\d+) basis updates, )?" + DURATION + r" elapsed" + ETA)
LOAD_LINE = re.compile(
    r"^flexmor: static   load step (\d+) of (\d+) \(load factor (\d\.\d{4})\), " + DURATION +
    r" elapsed" + ETA)


def seconds(value, unit):
    return float(value) * {"s": 1, "min": 60, "h": 3600}[unit]


def run(tmp_path, text, args=(), interval=INTERVAL):
    nml = tmp_path / "scene.nml"
    nml.write_text(text)
    env = dict(os.environ)
    env.pop("FLEXMOR_PROGRESS_INTERVAL", None)
    if interval is not None:
        env["FLEXMOR_PROGRESS_INTERVAL"] = interval
    proc = subprocess.run([BIN, str(nml), "-o", str(tmp_path / "out.h5"), *args],
                          capture_output=True, text=True, timeout=600, cwd=tmp_path, env=env)
    assert proc.returncode == 0, proc.stderr
    return proc


@pytest.mark.parametrize("name", SCENES)
def test_progress_lines(tmp_path, name):
    kind, end, text = SCENES[name]
    proc = run(tmp_path, text)
    lines = proc.stderr.splitlines()
    assert proc.stderr.endswith("\n") and len(lines) >= 2, proc.stderr
    assert "flexmor: " + kind not in proc.stdout
    previous = None
    for line in lines:
        if kind == "static":
            m = LOAD_LINE.match(line)
            assert m, line
            k, n, factor = int(m[1]), int(m[2]), float(m[3])
            assert n == end and 1 <= k <= n and factor == pytest.approx(k / n, abs=6e-5), line
            now = (k, seconds(m[4], m[5]))
        else:
            m = TIME_LINE.match(line)
            assert m and m[1] == kind, line
            t, t_end, pct, steps = float(m[2]), float(m[3]), float(m[4]), int(m[5])
            assert t_end == pytest.approx(end) and 0 <= t <= t_end, line
            # pct comes from the unrounded t: within the rounding of both.
            assert pct == pytest.approx(100 * t / t_end, abs=0.06 + 100 * 5e-4), line
            assert (m[6] is not None) == (kind == "reduced"), line
            updates = int(m[6]) if m[6] else 0
            now = (t, steps, updates, seconds(m[7], m[8]))
        if previous is not None:
            assert all(a <= b for a, b in zip(previous, now)), (previous, line)
        previous = now
    first = (LOAD_LINE if kind == "static" else TIME_LINE).match(lines[0])
    last = (LOAD_LINE if kind == "static" else TIME_LINE).match(lines[-1])
    key = 1 if kind == "static" else 2
    assert float(last[key]) > float(first[key]), "progress does not advance: " + proc.stderr


def test_error_check_reports_its_second_run(tmp_path):
    """&dynamic error_check: the second run reports as 'check', after the run's own lines,
    from t = 0 again; -q silences both."""
    text = SCENES["galpha"][2].replace("dt = 1.0e-4 /", "dt = 1.0e-4, error_check = 'tolerance' /")
    assert "error_check" in text
    proc = run(tmp_path, text)
    kinds = [TIME_LINE.match(line) for line in proc.stderr.splitlines()]
    assert all(kinds), proc.stderr
    names = [m[1] for m in kinds]
    assert "dynamic" in names and "check" in names, names
    first_check = names.index("check")
    assert set(names[:first_check]) == {"dynamic"} and set(names[first_check:]) == {"check"}
    assert float(kinds[first_check][2]) <= float(kinds[-1][2])
    assert "error check: a second run with dt 1.00E-05" in proc.stdout
    quiet = run(tmp_path, text, args=["-q"])
    assert quiet.stderr == "" and quiet.stdout == ""


def test_quiet_prints_no_progress(tmp_path):
    proc = run(tmp_path, SCENES["bdf"][2], args=["-q"])
    assert proc.stderr == "" and proc.stdout == ""


def test_short_run_is_silent(tmp_path):
    # The default interval (2 s): a run of a fraction of a second prints nothing on stderr.
    proc = run(tmp_path, SHORT, interval=None)
    assert proc.stderr == ""
    assert "dynamic:" in proc.stdout


@pytest.mark.parametrize("bad", ["abc", "-1", "0"])
def test_bad_interval_is_ignored(tmp_path, bad):
    proc = run(tmp_path, SHORT, interval=bad)
    assert proc.stderr == ""
