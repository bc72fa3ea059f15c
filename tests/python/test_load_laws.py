"""Nodal loads that follow a time law (&force time_law): a spring-mass oscillator driven by a
harmonic force against the closed-form response from rest."""
import math

import h5py
import numpy as np

from helpers import assert_clean_error, run_scene


# A 1 kg mass on a massless truss spring k = EA/L = 1000 N/m along x (omega = 31.6 rad/s).
OSCILLATOR = """&node label = 'wall', x = 0, y = 0, fixed = .true. /
&node label = 'mass', x = 1, y = 0, fix_y = .true. /
&truss label = 'spring', from = 'wall', to = 'mass', E = 1.0e7, A = 1.0e-4 /
&mass node = 'mass', m = 1.0 /
&force node = 'mass', fx = 2.0, time_law = 'drive' /
&motion label = 'drive', law = 'harmonic', amplitude = 1.0, frequency = 3.0 /
&dynamic t_end = 1.0, output_dt = 0.01, rtol = 1e-10, atol = 1e-12 /
&output nodes = 'mass' /
"""


def test_harmonic_force_on_an_oscillator(tmp_path):
    """F = F0 sin(W t) from rest: x = F0/(k - m W^2) (sin W t - (W/w) sin w t). The truss is
    exactly linear along its axis, so only the integrator error remains (rtol 1e-10: observed
    2.6e-10 m of 5e-3 m); bound 1e-8 m."""
    proc, out = run_scene(tmp_path, OSCILLATOR)
    assert proc.returncode == 0, proc.stderr
    with h5py.File(out) as f:
        t = f["time"][:]
        x = f["nodes/mass/position"][:, 0] - 1.0
    k, m, f0, big_w = 1000.0, 1.0, 2.0, 2 * math.pi * 3.0
    w = math.sqrt(k / m)
    exact = f0 / (k - m * big_w**2) * (np.sin(big_w * t) - big_w / w * np.sin(w * t))
    assert np.max(np.abs(exact)) > 1e-3
    assert np.max(np.abs(x - exact)) < 1e-8


def test_time_law_errors(tmp_path):
    """An undefined law is an error naming the group and variable; a law nobody uses but a
    force is not reported as unused."""
    proc, out = run_scene(tmp_path, OSCILLATOR.replace("time_law = 'drive'", "time_law = 'nope'"))
    assert_clean_error(proc, out, "&force #1", "'time_law'", "'nope'")
    proc, out = run_scene(tmp_path, OSCILLATOR)
    assert proc.returncode == 0 and "warning" not in proc.stderr, proc.stderr
