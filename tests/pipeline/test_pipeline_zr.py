"""`tengfield run` with the 3D ball: the (z, r) surrogate is used exactly when the
ball leaves the axis (analytic (z, r) stand-in for the field solver)."""
import numpy as np

import plate_model as fx
import zr_model as tz
from tengfield import pipeline
from tengfield.surrogate import AnchoredTerminalCurves, radial_motion

BASE = dict(contact={"model": "3d"}, run={"duration_s": 0.3, "settle_periods": 2})


def run(scene, tmp_path):
    return pipeline.run(scene, cache_dir=tmp_path, solve=tz.zr_model_solve)


def test_ball_on_the_axis_keeps_the_one_dimensional_surrogate(tmp_path):
    axial = run(fx.scene_with(**BASE, excitation={"frequency_hz": 30.0, "amplitude_mm": 1.0}),
                tmp_path)
    assert "field_zr" not in axial.stages
    assert not isinstance(axial.curves, AnchoredTerminalCurves)


def test_lateral_shaking_uses_the_zr_surrogate_consistently(tmp_path):
    shaken = fx.scene_with(**BASE, excitation={"frequency_hz": 30.0, "amplitude_mm": 1.0,
                                               "amplitude_x_mm": 0.5, "phase_x_deg": 30.0},
                           circuit={"kind": "load", "load_ohm": 1e8})
    out = run(shaken, tmp_path)
    assert out.stages["field_zr"].status == "ran"
    assert isinstance(out.curves, AnchoredTerminalCurves)
    r, _ = radial_motion(out.dynamics)
    assert r.max() > 1e-4                                   # the ball did leave the axis
    # I_SC = dQ_SC/dz z' + dQ_SC/dr r' is the time derivative of the sampled Q_SC
    t, q, i = (out.waveforms[k] for k in ("time_s", "Q_sc_C", "I_sc_A"))
    assert np.median(np.abs(np.gradient(q, t) - i)) < 1e-3 * np.abs(i).max()
    residual = out.stages["circuit"].details["energy_balance_relative_residual"]
    assert residual < 1e-3
    again = run(shaken, tmp_path)
    assert again.stages["field_zr"].status == "cached"
    np.testing.assert_array_equal(again.waveforms["Q_sc_C"], q)
