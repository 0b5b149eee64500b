"""A fit with an ``[instrument]`` (issue #39) compares a measured trace with what that
instrument records: a current read through a 100 Hz front end with a 1 ms aperture,
written by ``tf.run`` (the pipeline's reader, not the fit's model), gives σ back, and
fit.json's tool quantity is ``I_read_A``; the same trace fitted as the ideal I_SC does
not. The field is the analytic plate model."""
from __future__ import annotations

import numpy as np
import pytest

import tengfield as tf
from tengfield.fit.solve import fit_trace
from tengfield.fit.spec import Column, Trace, parse_fit_section

import plate_model as fx

INSTRUMENT = {"capacitance_pF": 100.0, "bandwidth_hz": 100.0, "aperture_s": 1e-3}
RUN = {"duration_s": 1.0, "settle_periods": 10, "sample_rate_hz": 5000.0}


def _measured(surrogate_cache):
    """The read current of the steady part of a run with σ = -8 (the plate scene's)."""
    r = tf.run(fx.scene_with(run=RUN, instrument=INSTRUMENT), cache_dir=surrogate_cache,
               solve=fx.plate_model_solve)
    t = np.asarray(r.t)
    keep = t >= 0.6
    trace = Trace("read", t[keep], {"I": np.asarray(r.waveforms["I_read_A"])[keep]},
                  [Column("I", "I", "A", None)])
    return trace, r


def _fit(scene, plate_surrogate, trace):
    spec = parse_fit_section(scene.with_values(fit={"parameters": {
        "surface_charge_uC_per_m2": {"start": -20.0}, "time_shift_s": {}}}))
    return fit_trace(scene, plate_surrogate[0], plate_surrogate[1], trace, spec)


@pytest.mark.slow
def test_a_filtered_current_fits_back_sigma_through_the_instrument(plate_surrogate,
                                                                  surrogate_cache):
    trace, run = _measured(surrogate_cache)
    assert np.max(np.abs(trace.values["I"])) < 0.9 * run.peak["I_sc"]   # filtered
    read = _fit(fx.scene_with(run=RUN, instrument=INSTRUMENT), plate_surrogate, trace)
    assert read.values["surface_charge_uC_per_m2"] == pytest.approx(-8.0, rel=1e-2)
    assert read.residuals["I"]["tool_key"] == "I_read_A"
    ideal = _fit(fx.scene_with(run=RUN, circuit={"parallel_capacitance_pF": 100.0}),
                 plate_surrogate, trace)
    assert ideal.residuals["I"]["tool_key"] == "I_sc_A"
    # the ideal I_SC cannot take the filter's shape: σ comes out too small and the
    # residual is far larger
    assert abs(ideal.values["surface_charge_uC_per_m2"]) < 7.5           # -7.10
    assert ideal.residuals["I"]["percent_of_signal_rms"] > 10.0           # 23 %
    assert read.residuals["I"]["percent_of_signal_rms"] < 1.0


@pytest.mark.parametrize("given", [{"circuit": {"parallel_capacitance_pF": 100.0}},
                                   {"instrument": {"capacitance_pF": 100.0,
                                                   "bandwidth_hz": 100.0}}],
                         ids=["old-key", "instrument"])
def test_a_fitted_capacitance_is_written_as_the_instruments(given, tmp_path):
    """fitted.toml holds the fitted C_p once, as [instrument] capacitance_pF: a scene with
    an [instrument] and the old [circuit] key both given was refused on reading."""
    import types
    import warnings

    from tengfield.fit.output import fitted_scene_dict
    from tengfield.files import scene_toml

    scene = tf.default_scene().with_values(**given)
    result = types.SimpleNamespace(values={"parallel_capacitance_pF": 250.0})
    path = tmp_path / "fitted.toml"
    path.write_text(scene_toml(fitted_scene_dict(scene, result), "test", base_dir=None))
    with warnings.catch_warnings():
        warnings.simplefilter("error")                 # no deprecation warning either
        fitted = tf.load_scene(path)
    assert fitted.circuit.parallel_capacitance == pytest.approx(250e-12)
    assert fitted.instrument.capacitance == pytest.approx(250e-12)
    assert fitted.instrument.bandwidth == scene.instrument.bandwidth
