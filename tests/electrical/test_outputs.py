"""Outputs a bench can be compared with (issue #28) and the rectifier's lines (#29).

``peak`` (max |x|) beside ``peak_to_peak``; ``V_oc_V`` always the ideal open-circuit
voltage and ``V_read_V`` what an instrument of capacitance C_p reads; FOM_S and the
CMEO the device's own; ``[reference]`` / ``--reference`` against the tool's values; the
one table of output quantities; a rectifier run without chip or load says and draws
only what it has. The field is the analytic plate model of ``plate_model`` (no
dolfinx); the dynamics are the real impact map on short runs.
"""
from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest

import tengfield as tf
from tengfield import electrical, quantities
from tengfield.commands.run import print_summary
from tengfield.errors import SceneError

import plate_model as fx

SHORT_RUN = {"duration_s": 0.3, "settle_periods": 2, "sample_rate_hz": 5000.0}
#: the paper's electrometer: C_p = 338 pF
INSTRUMENT = {"parallel_capacitance_pF": 338.0}


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("surrogates")


def model_run(cache, **sections):
    scene = fx.scene_with(run=SHORT_RUN, **sections)
    return tf.run(scene, cache_dir=cache, solve=fx.plate_model_solve)


# ---------------------------------------------------------------------------
# peak beside peak-to-peak
def test_peak_beside_peak_to_peak(cache):
    r = model_run(cache)
    s = r.summary
    assert set(s["peak"]) == set(s["peak_to_peak"]) == {"V_oc_V", "Q_sc_C", "I_sc_A"}
    assert r.peak_to_peak is r.peaks
    mask, _ = electrical.steady_window(r.t, r.scene)
    for short, column in electrical.PEAK_QUANTITIES.items():
        peak, p2p = s["peak"][column], s["peak_to_peak"][column]
        assert r.peak[short] == peak and r.peaks[short] == p2p
        # max |x| lies between half the swing and the whole swing, and is at least the
        # largest sampled |x| (the rule adds the impact instants to the samples)
        assert 0.5 * p2p <= peak <= p2p, column
        assert peak >= np.max(np.abs(r.waveforms[column][mask])), column
    # Q_SC is 0 in the reference state (ball on the lower electrode) and one-signed:
    # its peak is its peak-to-peak
    assert s["peak"]["Q_sc_C"] == pytest.approx(s["peak_to_peak"]["Q_sc_C"], rel=1e-3)
    # I_SC swings both ways: its peak is strictly below its peak-to-peak
    assert s["peak"]["I_sc_A"] < s["peak_to_peak"]["I_sc_A"]
    assert "max |x|" in s["peak_rule"]


def test_terminal_prints_peak_and_peak_to_peak(cache, capsys):
    r = model_run(cache)
    print_summary(r.summary)
    out = capsys.readouterr().out
    peak_line = next(line for line in out.splitlines() if line.startswith("peak (max |x|)"))
    p2p_line = next(line for line in out.splitlines() if line.startswith("peak-to-peak"))
    i_peak = r.summary["peak"]["I_sc_A"] * 1e9
    assert f"I_SC = {i_peak:.4g} nA" in peak_line
    assert f"Q_SC = {r.summary['peak_to_peak']['Q_sc_C'] * 1e9:.4g} nC" in p2p_line


# ---------------------------------------------------------------------------
# V_OC and what the instrument reads
def test_instrument_reads_v_read_and_leaves_v_oc_and_fom_alone(cache):
    bare = model_run(cache)
    meter = model_run(cache, circuit=INSTRUMENT)
    # V_OC is the ideal open-circuit voltage whatever the meter
    np.testing.assert_array_equal(meter.V_oc, bare.V_oc)
    assert meter.summary["peak_to_peak"]["V_oc_V"] == bare.summary["peak_to_peak"]["V_oc_V"]
    assert "V_read_V" not in bare.waveforms and "V_read_V" not in bare.summary["peak"]
    # V_read = Q_SC / (C_T + C_p): from the ideal V_OC = Q_SC / C_T and the surrogate's C_T
    c_t = np.asarray(meter.curves.capacitance(meter.waveforms["gap_m"]))
    q = meter.Q_sc
    np.testing.assert_allclose(meter.V_read, q / (c_t + 338e-12), rtol=1e-12, atol=0)
    np.testing.assert_allclose(meter.V_oc[q != 0], (q / c_t)[q != 0], rtol=1e-12)
    for stat in ("peak", "peak_to_peak"):
        read = meter.summary[stat]["V_read_V"]
        assert 0 < read < meter.summary[stat]["V_oc_V"]
    assert meter.peak["V_read"] == meter.summary["peak"]["V_read_V"]
    # the structural figure of merit and the CMEO are the device's own
    e_bare, e_meter = bare.summary["energy_per_cycle"], meter.summary["energy_per_cycle"]
    assert e_meter["figure_of_merit_structural"] == e_bare["figure_of_merit_structural"]
    assert e_meter["max_energy_per_cycle_J"] == e_bare["max_energy_per_cycle_J"]
    assert "max_energy_per_cycle_with_instrument_J" not in e_bare
    q_max, c_max, c_0 = e_meter["Q_sc_max_C"], e_meter["C_at_max_gap_F"], e_meter["C_at_zero_F"]
    assert e_meter["max_energy_per_cycle_with_instrument_J"] == pytest.approx(
        0.5 * q_max**2 * (1 / (c_max + 338e-12) + 1 / (c_0 + 338e-12)), rel=1e-12)
    assert e_meter["max_energy_per_cycle_with_instrument_J"] < e_meter["max_energy_per_cycle_J"]


def test_instrument_across_a_load_reads_the_load_voltage(cache):
    r = model_run(cache, circuit={"kind": "load", "load_ohm": 3e9, **INSTRUMENT})
    assert r.V_read is r.waveforms["V_load_V"]
    mask, _ = electrical.steady_window(r.t, r.scene)
    assert r.summary["peak"]["V_read_V"] == pytest.approx(
        np.max(np.abs(r.waveforms["V_load_V"][mask])), rel=1e-12)
    assert "load" in r.summary["V_read_rule"] or "V_load_V" in r.summary["V_read_rule"]
    assert r.summary["circuit"]["load_ohm"] == 3e9


# ---------------------------------------------------------------------------
# [reference]: measured values beside the tool's
def test_reference_table_gives_the_percent_differences(cache):
    measured = {"V_pp_V": 4.2, "Q_pp_nC": 1.42, "I_peak_uA": 0.16}
    r = model_run(cache, circuit=INSTRUMENT, reference=measured)
    block = r.summary["measured_comparison"]["quantities"]
    assert set(block) == set(measured)
    tool = {"V_pp_V": r.summary["peak_to_peak"]["V_read_V"],                # the reading
            "Q_pp_nC": r.summary["peak_to_peak"]["Q_sc_C"] * 1e9,
            "I_peak_uA": r.summary["peak"]["I_sc_A"] * 1e6}
    for key, value in measured.items():
        row = block[key]
        assert row["measured_value"] == pytest.approx(value, rel=1e-12)
        assert row["tool_value"] == pytest.approx(tool[key], rel=1e-12)
        assert row["difference_percent"] == pytest.approx(
            100.0 * (tool[key] - value) / value, rel=1e-9)
    assert block["V_pp_V"]["tool_key"] == "peak_to_peak.V_read_V"
    assert block["Q_pp_nC"]["unit"] == "nC" and block["I_peak_uA"]["tool_key"] == "peak.I_sc_A"
    # without an instrument a measured voltage is compared with nothing (issue #42: the
    # ideal V_OC is kilovolts, no bench reads it), and the row says why
    bare = model_run(cache, reference={"V_pp_V": 4.2})
    row = bare.summary["measured_comparison"]["quantities"]["V_pp_V"]
    assert row["tool_key"] is None and row["difference_percent"] is None
    assert "capacitance" in row["compared_with"]
    assert "measured_comparison" not in model_run(cache).summary


def test_reference_table_is_printed(cache, capsys):
    r = model_run(cache, reference={"Q_pp_nC": 1.42})
    print_summary(r.summary)
    out = capsys.readouterr().out
    row = r.summary["measured_comparison"]["quantities"]["Q_pp_nC"]
    line = next(line for line in out.splitlines() if line.strip().startswith("Q_pp_nC"))
    assert f"{row['difference_percent']:+.1f} %" in line
    assert "peak_to_peak.Q_sc_C" in line and "measured 1.42 nC" in line


@pytest.mark.parametrize("section, expected", [
    ({"V_pp": 4.2}, "unknown key [reference] V_pp (did you mean 'V_pp_V'?)"),
    ({"Q_pp_nC": -1.0}, "[reference] Q_pp_nC = -1.0 is out of range"),
    ({"I_peak_uA": "0.16"}, "[reference] I_peak_uA = '0.16': expected a number"),
])
def test_reference_section_is_checked(section, expected):
    with pytest.raises(SceneError) as err:
        fx.scene_with(reference=section)
    assert expected in str(err.value) and "\n" not in str(err.value)


def test_reference_items_of_the_command_line():
    assert quantities.parse_measured(["V_pp_V=4.2", "Q_pp_nC=1.42"]) == {
        "V_pp_V": 4.2, "Q_pp_nC": 1.42}
    for items, expected in ((["V_pp_V"], "expected KEY=VALUE"),
                            (["I_peak_nA=3"], "did you mean 'I_peak_uA'?"),
                            (["Q_pp_nC=a lot"], "expected a number")):
        with pytest.raises(ValueError, match=expected.replace("?", r"\?")):
            quantities.parse_measured(items)
    # every measured key is a [reference] key of the scene and the other way round
    from tengfield.scene.schema import SCHEMA
    assert set(quantities.MEASURED) == set(SCHEMA["reference"])


# ---------------------------------------------------------------------------
# the one table
def test_the_table_names_every_output(cache):
    keys = quantities.summary_keys(instrument=True)
    for key in ("peak_to_peak.Q_sc_C", "peak.I_sc_A", "peak.V_read_V", "load.mean_power_W",
                "energy_per_cycle.figure_of_merit_structural"):
        assert key in keys
    assert "peak.V_read_V" not in quantities.summary_keys()
    r = model_run(cache, circuit={"kind": "load", "load_ohm": 3e9})
    assert quantities.summary_value(r.summary, "peak.I_sc_A") == r.summary["peak"]["I_sc_A"]
    assert quantities.summary_value(r.summary, "load.mean_power_W") == \
        r.summary["load"]["mean_power_W"]
    assert quantities.summary_value(r.summary, "peak.V_read_V") is None
    assert quantities.summary_value(model_run(cache).summary, "load.mean_power_W") is None
    # every waveform column a run writes is an entry of the table
    for column in r.waveforms:
        assert quantities.QUANTITIES[column].waveform, column
    assert quantities.QUANTITIES["V_oc_V"].unit == "V"
    assert quantities.QUANTITIES["Q_sc_C"].label == "short-circuit charge Q_SC"
    assert quantities.column_name("V_oc_V", "peak_to_peak") == "V_oc_pp_V"
    assert quantities.column_name("I_sc_A", "peak") == "I_sc_peak_A"
    assert quantities.axis_label("Q_sc_C") == "Q_SC [nC]"
    from tengfield.ensemble import ENSEMBLE_COLUMNS, realisation_row
    from tengfield.sweeps import SWEEP_COLUMNS
    for table in (ENSEMBLE_COLUMNS, SWEEP_COLUMNS):
        assert {"V_oc_pp_V", "Q_sc_pp_C", "I_sc_pp_A", "I_sc_peak_A", "V_read_pp_V"} <= set(table)
    row = realisation_row(0, 0, r.summary)
    assert row["I_sc_peak_A"] == r.summary["peak"]["I_sc_A"] and row["V_read_pp_V"] is None


def test_waveform_figure_names_the_instrument():
    from tengfield.plotting.waveforms import waveform_panels
    t = np.zeros(3)
    labels = [label for _, label, _ in waveform_panels(
        {"time_s": t, "V_oc_V": t, "V_read_V": t, "Q_sc_C": t, "I_sc_A": t}, 338.0)]
    assert "V_read [V]" in labels       # short; C_p is named in the panel's legend
    assert labels[0] == "V_OC (ideal) [V]"
    plain = [label for _, label, _ in waveform_panels(
        {"time_s": t, "V_oc_V": t, "Q_sc_C": t, "I_sc_A": t})]
    assert plain == ["V_OC [V]", "Q_SC [nC]", "I_SC [nA]"]


# ---------------------------------------------------------------------------
# the rectifier: only what the run has
def test_rectifier_without_chip_or_load(cache, capsys, monkeypatch):
    r = model_run(cache, circuit={"kind": "rectifier", "storage_capacitance_uF": 1e-4})
    s = r.summary
    assert "load_ohm" not in s["circuit"]
    assert "load" not in r.extras["_vq"] and "rectifier" in r.extras["_vq"]
    assert "load_loop_area_J" not in s["energy_per_cycle"]
    assert s["rectifier"]["record_length_s"] == pytest.approx(0.3, rel=1e-9)
    print_summary(s)
    out = capsys.readouterr().out
    assert "never" not in out and "UVLO" not in out and "reaches" not in out
    # with a chip whose levels the store does not reach: "not reached in 0.3 s"
    chip = dict(s, rectifier=dict(s["rectifier"], pmic="uvlo", chip_switch_on_count=0,
                                  chip_duty_cycle=0.0, time_to_uvlo_falling_V_s=None,
                                  time_to_uvlo_rising_V_s=None))
    print_summary(chip)
    out = capsys.readouterr().out
    assert "4.04 V not reached in 0.3 s" in out and "never" not in out
    # charging.png: no UVLO lines without a chip
    from tengfield.plotting import harvest as hp
    figures = []
    original = hp.new_figure
    monkeypatch.setattr(hp, "new_figure", lambda *a, **k: figures.append(original(*a, **k))
                        or figures[-1])
    hp.plot_charging(r.extras["_fine"], r.scene, cache / "charging.png")
    labels = [line.get_label() for line in figures[-1].axes[0].get_lines()]
    assert not any("UVLO" in label for label in labels) and "store U" in labels
    chipped = r.scene.with_values(circuit={"pmic": "uvlo"})
    hp.plot_charging(r.extras["_fine"], chipped, cache / "charging2.png")
    labels = [line.get_label() for line in figures[-1].axes[0].get_lines()]
    assert sum("UVLO" in label for label in labels) == 2


@pytest.mark.parametrize("kind", ["open", "short"])
def test_no_load_ohm_without_a_load(cache, kind):
    assert "load_ohm" not in model_run(cache, circuit={"kind": kind}).summary["circuit"]


# ---------------------------------------------------------------------------
# the command, end to end with figures
@pytest.mark.slow
def test_cli_run_with_instrument_and_reference(tmp_path, run_cli, cli_env):
    (tmp_path / "meter.toml").write_text(
        "[run]\nduration_s = 0.3\nsettle_periods = 2\nsample_rate_hz = 5000.0\n"
        "[instrument]\ncapacitance_pF = 338.0\n[reference]\nV_pp_V = 4.2\n")
    scene = tf.load_scene(tmp_path / "meter.toml")
    tf.run(scene, cache_dir=tmp_path / "cache", solve=fx.plate_model_solve)   # fills the cache
    env = cli_env(MPLBACKEND="Agg", TENGFIELD_CACHE_DIR=tmp_path / "cache")
    proc = run_cli("run", "meter.toml", "-o", "out", "--reference", "Q_pp_nC=1.42",
                   "I_peak_uA=0.16", cwd=tmp_path, timeout=600, env=env)
    assert proc.returncode == 0, proc.stderr
    out = tmp_path / "out"
    assert (out / "waveforms.png").stat().st_size > 0
    with open(out / "waveforms.csv") as f:
        header = next(csv.reader(f))
    assert header == electrical.WAVEFORM_COLUMNS + ["V_read_V", "Q_read_C", "I_read_A"]
    summary = json.loads((out / "summary.json").read_text())
    assert set(summary["measured_comparison"]["quantities"]) == {"V_pp_V", "Q_pp_nC",
                                                                 "I_peak_uA"}
    assert summary["peak"]["V_read_V"] < summary["peak"]["V_oc_V"]
    assert "V read through C_p = 338 pF" in proc.stdout
    assert "measured comparison" in proc.stdout and "peak (max |x|)" in proc.stdout
    bad = run_cli("run", "meter.toml", "-o", "out2", "--reference", "Q_pp=1", cwd=tmp_path,
                  timeout=600, env=env)
    assert bad.returncode == 2 and "did you mean 'Q_pp_nC'?" in bad.stderr
    assert len(bad.stderr.strip().splitlines()) == 1
    assert math.isfinite(summary["measured_comparison"]["quantities"]["V_pp_V"][
        "difference_percent"])


def test_array_with_an_instrument_reports_both_voltages(cache):
    """Cells with their own dynamics: V_OC of the array's terminal is Q / C, the reading
    Q / (C + C_p); both statistics of each, peak <= peak-to-peak for I_SC."""
    r = model_run(cache, circuit=INSTRUMENT,
                  array={"cells": 3, "restitution_spread": 0.05})
    s = r.summary
    assert r.summary["array"]["distinct_dynamics"] > 1
    assert set(s["peak"]) == set(s["peak_to_peak"]) == {"V_oc_V", "Q_sc_C", "I_sc_A",
                                                        "V_read_V"}
    assert 0 < s["peak"]["V_read_V"] < s["peak"]["V_oc_V"]
    assert s["peak"]["I_sc_A"] <= s["peak_to_peak"]["I_sc_A"]
    mask, _ = electrical.steady_window(r.t, r.scene)
    for column in ("V_oc_V", "V_read_V", "Q_sc_C", "I_sc_A"):
        assert s["peak"][column] >= np.max(np.abs(r.waveforms[column][mask])), column
    # the reading and the ideal voltage of the same charge: V_read (C + C_p) = V_oc C
    q = r.Q_sc
    c = q[q != 0] / r.V_oc[q != 0]
    np.testing.assert_allclose(r.V_read[q != 0] * (c + 338e-12), q[q != 0], rtol=1e-9)


def test_fit_reads_the_instruments_column_of_a_run(cache, tmp_path):
    """A run read through C_p writes the ideal V_oc_V and the reading V_read_V: fit's
    voltage (what an instrument reads, Q_SC / (C_T + C_p)) is taken from V_read_V."""
    from tengfield import io
    from tengfield.fit.spec import parse_fit_section, read_trace

    r = model_run(cache, circuit=INSTRUMENT)
    io.write_waveforms_csv(tmp_path / "waveforms.csv", r.waveforms)
    trace = read_trace(tmp_path / "waveforms.csv", parse_fit_section(r.scene))
    assert {c.quantity: c.column for c in trace.columns}["V"] == "V_read_V"
    np.testing.assert_allclose(trace.values["V"], r.V_read, rtol=1e-9)
