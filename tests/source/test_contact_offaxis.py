"""[charge] model = "contact" with the 3D ball off the axis ([contact] model = "3d",
issue #52): the contact bookkeeping over the (z, r) curves (tengfield.source.offaxis),
with the analytic (z, r) stand-in for the field solver (tests/zr_model.py)."""
from __future__ import annotations

import numpy as np
import pytest

import plate_model as fx
import zr_model as tz
from tengfield import pipeline
from tengfield.surrogate import AnchoredTerminalCurves, radial_motion

SHAKEN = dict(contact={"model": "3d"}, run={"duration_s": 0.3, "settle_periods": 2},
              excitation={"frequency_hz": 30.0, "amplitude_mm": 1.0, "amplitude_x_mm": 0.5,
                          "phase_x_deg": 30.0})
CHARGE = {"model": "contact", "equilibrium_uC_per_m2": -20.0, "efficiency": 0.3,
          "discharge": "none"}


def _run(tmp_path, **sections):
    return pipeline.run(fx.scene_with(**SHAKEN, **sections), cache_dir=tmp_path,
                        solve=tz.zr_model_solve)


def test_a_ball_at_equilibrium_off_the_axis_is_the_constant_charge_run(tmp_path):
    """Starting at σ_eq with no leakage and no cap the contacts change nothing: the
    off-axis run is the constant model's at σ_eq, the (z, r) curves included (1e-12)."""
    constant = _run(tmp_path, device={"surface_charge_uC_per_m2": -20.0})
    contact = _run(tmp_path, charge={**CHARGE, "initial_uC_per_m2": -20.0})
    assert isinstance(constant.curves, AnchoredTerminalCurves)
    assert contact.stages["field_zr"].status == "cached"     # the same (z, r) table
    assert radial_motion(contact.dynamics)[0].max() > 1e-4      # the ball left the axis
    assert contact.summary["charge"]["contacts"] > 5
    for key in ("Q_sc_C", "I_sc_A", "V_oc_V", "C_T_F"):
        ours, theirs = contact.waveforms[key], constant.waveforms[key]
        assert np.max(np.abs(ours - theirs)) <= 1e-12 * np.max(np.abs(theirs)), key


def test_the_current_is_the_derivative_of_the_charge_off_the_axis(tmp_path):
    """With leakage the charge the ball lost to the air is redistributed by the share
    k(z, r): I_SC = dQ_SC/dt with both ż and ṙ terms of Q_SC and of k (a missing term
    of dk/dr, dQ/dr or q' shows here)."""
    out = _run(tmp_path, charge={**CHARGE, "leakage_time_s": 0.05,
                                 "initial_uC_per_m2": -20.0})
    t, q, i = (out.waveforms[k] for k in ("time_s", "Q_sc_C", "I_sc_A"))
    contacts = np.asarray(out.dynamics.impacts.time) - float(out.dynamics.t[0]) \
        + float(t[0])
    near = np.zeros_like(t, dtype=bool)
    for c in contacts:   # Q_SC jumps at a contact: leave its two neighbouring samples out
        near |= np.abs(t - c) < 1.5 * (t[1] - t[0])
    slope = np.gradient(q, t)
    assert np.median(np.abs(slope - i)[~near]) < 1e-4 * np.abs(i).max()
    assert np.max(np.abs(q - q[0])) > 0.0


def test_on_the_axis_the_off_axis_terminal_is_the_on_axis_one(tmp_path):
    """At r = 0 the anchored share and curves are the axis table's: the off-axis
    terminal gives the on-axis ContactTerminal's numbers (1e-12)."""
    from tengfield.contact_run import field_scene
    from tengfield.source.contacts import run_history
    from tengfield.source.offaxis import OffAxisContactTerminal
    from tengfield.source.terminal import ContactTerminal
    from tengfield.surrogate import obtain_table

    scene = fx.scene_with(**SHAKEN, charge={**CHARGE, "leakage_time_s": 0.05})
    out = pipeline.run(scene, cache_dir=tmp_path, solve=tz.zr_model_solve)
    table, _ = obtain_table(field_scene(scene), cache_dir=tmp_path, solve=tz.zr_model_solve)
    curves = out.curves.terminal.offaxis
    history, upper, _, _ = run_history(
        scene, out.dynamics.impacts,
        np.asarray(out.dynamics.impacts.time) - float(out.dynamics.t[0]))
    off = OffAxisContactTerminal(table, curves.zr.table, history, upper)
    on = ContactTerminal(table, history, upper)
    t = np.linspace(0.0, 0.3, 301)
    z = np.linspace(0.0, table.stroke, t.size)
    rate = np.cos(40 * t) * 0.1
    for a, b in zip(off.evaluate(t, z, rate, np.zeros_like(z)), on.evaluate(t, z, rate)):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12 * np.max(np.abs(b)))


def test_the_off_axis_run_writes_its_files_with_figures(tmp_path):
    out = _run(tmp_path / "cache", charge={**CHARGE, "efficiency": 0.5})
    written = {p.name for p in out.write(tmp_path / "out", plots=True)}
    assert {"waveforms.csv", "summary.json", "ball_charge.png", "waveforms.png",
            "trajectory3d.png"} <= written
    assert "q_ball_C" in out.waveforms


def test_the_studies_still_refuse_the_ball_off_the_axis():
    from tengfield.contact_run import check_contact_charge
    from tengfield.errors import SceneError

    scene = fx.scene_with(contact={"model": "3d"}, charge=CHARGE)
    check_contact_charge(scene, off_axis=True)           # run: the (z, r) curves
    with pytest.raises(SceneError, match=r'^\[charge\] model = "contact" with \[contact\] '
                                         r'model = "3d": not supported yet'):
        check_contact_charge(scene)


@pytest.mark.parametrize("charge", [None, CHARGE])
def test_the_rectifier_takes_the_charge_off_the_axis(charge, tmp_path):
    """The rectifier's bridge sees Q_SC(z, r) and C_T(z, r) at the ball's offset (it
    crashed with a TypeError for the 3D ball off the axis, constant charge too): its input
    at the output samples is the run's own Q_sc_C and C_T_F columns, the energy books
    close, and a contact-charged ball at σ_eq stores what the constant one stores."""
    from tengfield.electrical.waveforms import elapsed_times, sample_elapsed
    from tengfield.source import Source

    extra = {"charge": {**charge, "initial_uC_per_m2": -20.0}} if charge else \
        {"device": {"surface_charge_uC_per_m2": -20.0}}
    out = _run(tmp_path, circuit={"kind": "rectifier"}, **extra)
    t = elapsed_times(out.dynamics)
    gap, _, _ = sample_elapsed(out.dynamics, t)
    q, c = Source.of_scene(out.scene, out.curves, out.dynamics).state(t, gap)
    np.testing.assert_allclose(q, out.waveforms["Q_sc_C"], rtol=1e-9,
                               atol=1e-9 * np.max(np.abs(q)))
    np.testing.assert_allclose(c, out.waveforms["C_T_F"], rtol=1e-9)
    assert np.ptp(radial_motion(out.dynamics)[0]) > 1e-4
    residuals = out.summary["rectifier"]["energy_residuals"]
    assert max(abs(v) for v in residuals.values()) < 1e-6, residuals
    if charge:
        constant = _run(tmp_path, circuit={"kind": "rectifier"},
                        device={"surface_charge_uC_per_m2": -20.0})
        np.testing.assert_allclose(out.waveforms["V_store_V"], constant.waveforms["V_store_V"],
                                   rtol=1e-12, atol=1e-12 * np.max(np.abs(
                                       constant.waveforms["V_store_V"])))
