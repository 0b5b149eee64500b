"""Recorded excitation: C^4 interpolation, same guarantees as the sine."""
import math

import numpy as np
import pytest

from tengfield.dynamics import simulate
from tengfield.dynamics.impact import Restitution, integrate
from tengfield.dynamics.table import recorded_table, sine_table
from tengfield.errors import DynamicsError


def _sine_record(signal, f=30.0, amplitude=3e-3, rate=4000.0, duration=0.5):
    t = np.arange(0.0, duration + 1e-12, 1.0 / rate)
    w = 2 * math.pi * f
    values = amplitude * np.sin(w * t) if signal == "displacement" else -amplitude * w**2 * np.sin(w * t)
    return t, values


@pytest.mark.parametrize("signal", ["displacement", "acceleration"])
def test_recorded_sine_matches_analytic_sine(signal):
    t, values = _sine_record(signal)
    rec = recorded_table(t, values, signal)
    exact = sine_table(3e-3, 2 * math.pi * 30.0, 0.0)
    tt = np.linspace(0.05, 0.45, 500)
    assert np.max(np.abs(rec.evaluate(tt)[2] - exact.evaluate(tt)[2])) < 1e-3 * 3e-3 * (60 * math.pi) ** 2
    kw = dict(t_start=0.05, t_end=0.45, period=1 / 30.0)
    _, imp_rec, _ = integrate(rec, 3e-3, Restitution(0.6), **kw)
    _, imp_sin, _ = integrate(exact, 3e-3, Restitution(0.6), **kw)
    n = min(len(imp_rec[0]), len(imp_sin[0]), 6)
    assert n >= 4
    np.testing.assert_allclose(imp_rec[0][:n], imp_sin[0][:n], atol=2e-5)


def test_recorded_scene_end_to_end_and_out_of_record(tmp_path):
    t, values = _sine_record("displacement")
    np.savetxt(tmp_path / "table.csv", np.column_stack([t, values]), delimiter=",",
               header="time_s,displacement_m", comments="")
    text = ('[excitation]\nkind = "recorded"\nfile = "table.csv"\nfrequency_hz = 30.0\n'
            '[run]\nduration_s = 0.4\nsettle_periods = 3\n')
    (tmp_path / "s.toml").write_text(text)
    from tengfield.scene import load_scene
    scene = load_scene(tmp_path / "s.toml")
    res = simulate(scene)
    assert np.all((res.gap >= 0) & (res.gap <= scene.device.stroke))
    assert len(res.impacts) > 5
    with pytest.raises(DynamicsError, match="outside the recorded excitation"):
        simulate(scene, duration=2.0)
