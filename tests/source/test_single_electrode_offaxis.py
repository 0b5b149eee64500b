"""The single-electrode cell with the ball off the axis ([contact] model = "3d", issue
#51): the (z, r) surrogate of one electrode (C_ll, q_l over the grid) and the contact
charge's bookkeeping through the topology's hooks (``contact_share``,
``contact_transfer``), with a one-electrode version of the analytic (z, r) stand-in
(tests/zr_model.py) for the field solver."""
from __future__ import annotations

import numpy as np
import pytest

import plate_model as fx
import zr_model as tz
from tengfield import pipeline, terminals
from tengfield.field.result import PositionResult
from tengfield.surrogate import AnchoredTerminalCurves, radial_motion

SHAKEN = dict(contact={"model": "3d"}, run={"duration_s": 0.3, "settle_periods": 2},
              excitation={"frequency_hz": 30.0, "amplitude_mm": 1.0, "amplitude_x_mm": 0.5,
                          "phase_x_deg": 30.0})
SINGLE = {"electrodes": "lower"}
CHARGE = {"model": "contact", "equilibrium_uC_per_m2": -20.0, "efficiency": 0.3,
          "discharge": "none"}


def single_solve(scene, position, *, comm=None, offset=0.0, method="3d", **_):
    """The stand-in's lower electrode alone (C_ll, q_l): the bare upper plate is gone."""
    c_ll, _, _, q_l, _ = (float(v) for v in tz.zr_model(scene, position, offset))
    assert scene.device.electrode_names == ("lower",)
    return PositionResult(position=float(position), offset=float(offset),
                          capacitance=[[c_ll]], induced_charge=[q_l],
                          ball_charge=scene.device.ball_charge, dofs=1000, cells=2000,
                          method=method, degree=2, wall_time=0.01,
                          relative_error_estimate=1e-6, solve_time=0.005)


def _run(tmp_path, device=None, **sections):
    scene = fx.scene_with(**SHAKEN, device={**SINGLE, **(device or {})}, **sections)
    return pipeline.run(scene, cache_dir=tmp_path, solve=single_solve)


def test_the_single_electrodes_zr_table_holds_one_electrode(tmp_path):
    """The run leaves the axis through the (z, r) surrogate of one electrode: its table is
    (n_z, n_r, 1, 1) and (n_z, n_r, 1), its C_T the electrode's C_ll, and the cached table
    is read back as it was written."""
    out = _run(tmp_path, circuit={"kind": "load", "load_ohm": 1e8})
    assert out.stages["field_zr"].status == "ran"
    assert isinstance(out.curves, AnchoredTerminalCurves)
    assert radial_motion(out.dynamics)[0].max() > 1e-4
    table = out.curves.zr.table
    assert table.electrodes == 1 and table.capacitance.shape[2:] == (1, 1)
    np.testing.assert_array_equal(out.curves.zr.capacitance_grid, table.capacitance[..., 0, 0])
    assert out.summary["reference"] == "lower-to-ground"
    t, q, i = (out.waveforms[k] for k in ("time_s", "Q_sc_C", "I_sc_A"))
    assert np.median(np.abs(np.gradient(q, t) - i)) < 1e-3 * np.abs(i).max()
    again = _run(tmp_path, circuit={"kind": "load", "load_ohm": 1e8})
    assert again.stages["field_zr"].status == "cached"
    np.testing.assert_array_equal(again.waveforms["Q_sc_C"], q)


def test_a_ball_at_equilibrium_off_the_axis_is_the_constant_charge_run(tmp_path):
    """Starting at σ_eq with no leakage the contacts change nothing: the single electrode's
    off-axis contact run is its constant run at σ_eq (1e-12)."""
    constant = _run(tmp_path, device={"surface_charge_uC_per_m2": -20.0})
    contact = _run(tmp_path, charge={**CHARGE, "initial_uC_per_m2": -20.0})
    assert contact.stages["field_zr"].status == "cached"
    assert contact.summary["charge"]["contacts"] > 5
    for key in ("Q_sc_C", "I_sc_A", "V_oc_V", "C_T_F"):
        ours, theirs = contact.waveforms[key], constant.waveforms[key]
        assert np.max(np.abs(ours - theirs)) <= 1e-12 * np.max(np.abs(theirs)), key


def test_the_wire_carries_what_the_electrode_gives_up_off_the_axis(tmp_path):
    """A charging ball (σ_eq away from its start, leakage on): at r = 0 the off-axis
    terminal is the on-axis one (1e-12), and the current is dQ_SC/dt away from the
    contacts, with the ż and ṙ terms; the contacts' gains are drawn from the electrode:
    the topology's transfer is −D, its share 0."""
    from tengfield.contact_run import field_scene
    from tengfield.source.contacts import run_history
    from tengfield.source.offaxis import OffAxisContactTerminal
    from tengfield.source.terminal import ContactTerminal
    from tengfield.surrogate import obtain_table

    out = _run(tmp_path, charge={**CHARGE, "leakage_time_s": 0.05})
    t, q, i = (out.waveforms[k] for k in ("time_s", "Q_sc_C", "I_sc_A"))
    contacts = np.asarray(out.dynamics.impacts.time) - float(out.dynamics.t[0]) + float(t[0])
    near = np.zeros_like(t, dtype=bool)
    for c in contacts:
        near |= np.abs(t - c) < 1.5 * (t[1] - t[0])
    assert np.median(np.abs(np.gradient(q, t) - i)[~near]) < 1e-4 * np.abs(i).max()

    scene = fx.scene_with(**SHAKEN, device=SINGLE, charge={**CHARGE, "leakage_time_s": 0.05})
    table, _ = obtain_table(field_scene(scene), cache_dir=tmp_path, solve=single_solve)
    curves = out.curves.terminal.offaxis
    history, upper, _, _ = run_history(
        scene, out.dynamics.impacts,
        np.asarray(out.dynamics.impacts.time) - float(out.dynamics.t[0]))
    assert not np.any(upper)          # the bare upper plate is no electrode
    off = OffAxisContactTerminal(table, curves.zr.table, history, upper)
    on = ContactTerminal(table, history, upper)
    assert off.wiring is terminals.SINGLE_ELECTRODE
    k, dk_dz, dk_dr = off.share(np.full(5, 1e-3), np.linspace(0.0, 4e-4, 5))
    assert not np.any(k) and not np.any(dk_dz) and not np.any(dk_dr)
    ts = np.linspace(0.0, 0.3, 301)
    z = np.linspace(0.0, table.stroke, ts.size)
    rate = np.cos(40 * ts) * 0.1
    for a, b in zip(off.evaluate(ts, z, rate, np.zeros_like(z)), on.evaluate(ts, z, rate)):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12 * np.max(np.abs(b)))
    gained = np.cumsum(history.gains)[-1]
    assert on.short_circuit_charge(np.array([1.0]), history.at(np.array([1.0])), 0.0, 0.0,
                                   0.0, 0.0)[0] == pytest.approx(
        (history.at(1.0) - history.start) * on.b0 - gained, rel=1e-12)
