"""fit names what it compares from the one table of output quantities (issue #28):
fit.json's residuals name per target / column the tool quantity (``peak_to_peak.V_read_V``
with C_p > 0, ``peak_to_peak.V_oc_V`` without, the load's with a load), its words and unit
(``tengfield.quantities.describe``), and the terminal says "V_pp_V (tool: ...)"."""
from __future__ import annotations

import json
import re

import pytest

import plate_model as fx
from fit_synthetic import write_csv, synthetic

from tengfield import cli
from tengfield.fit import reference_surrogate
from tengfield.fit.compared import MEASURED_KEYS, compared, compared_key
from tengfield.quantities import MEASURED, describe, quantity
from tengfield.scene import load_scene

SCENE = """
[run]
duration_s = 1.0
settle_periods = 10

{instrument}
[fit]
time_column = "time_ms"
time_unit = "ms"

[fit.columns.V]
column = "V_meas"
unit = "V"

[fit.columns.Q]
column = "Q_meas"
unit = "nC"
"""


@pytest.fixture
def main(monkeypatch):
    if "fit" not in cli.COMMAND_MODULES:
        monkeypatch.setattr(cli, "COMMAND_MODULES", [*cli.COMMAND_MODULES, "fit"])
    return cli.main


def _setup(tmp_path, cp):
    path = tmp_path / f"scene-{cp}.toml"
    # an instrument of C_p = cp across the terminals (none at 0: the ideal quantities)
    path.write_text(SCENE.format(
        instrument=f"[instrument]\ncapacitance_pF = {cp}\n" if cp > 0 else ""))
    scene = load_scene(path)
    cache = tmp_path / "cache"
    surrogate = reference_surrogate(scene, cache_dir=cache, solve=fx.plate_model_solve)[:2]
    return path, cache, scene, surrogate


@pytest.mark.parametrize("cp, voltage, charge, current", [
    (100.0, "V_read_V", "Q_read_C", "I_read_A"), (0.0, "V_oc_V", "Q_sc_C", "I_sc_A")])
def test_targets_name_the_tool_quantity_they_are_compared_with(tmp_path, main, capsys, cp,
                                                               voltage, charge, current):
    path, cache, scene, _ = _setup(tmp_path, cp)
    out = tmp_path / "out"
    assert main(["fit", str(path), "--targets", "V_pp_V=300", "Q_pp_pC=500",
                 "I_peak_uA=0.02", "--free", "surface_charge_uC_per_m2", "-o", str(out),
                 "--cache-dir", str(cache), "--no-plots"]) == 0
    printed = capsys.readouterr().out
    res = json.loads((out / "fit.json").read_text())["residuals"]
    expected = {"V_pp_V": f"peak_to_peak.{voltage}", "Q_pp_pC": f"peak_to_peak.{charge}",
                "I_peak_uA": f"peak.{current}"}
    for label, key in expected.items():
        r = res[label]
        assert r["tool_key"] == key
        assert r["tool_label"] == describe(key, unit=False)
        assert r["tool_unit"] == quantity(key.rpartition(".")[2]).unit
        line = re.search(rf"^    {label} \(tool: {re.escape(r['tool_label'])}\): measured "
                         rf"(\S+), fitted (\S+) {r['unit']} ", printed, re.M)
        assert line, printed
        assert float(line[2]) == pytest.approx(r["fitted"], rel=1e-3)
    # the words are the table's: an instrument's reading is not called V_OC
    assert ("voltage read through C_p" in res["V_pp_V"]["tool_label"]) == (cp > 0)


def test_a_fitted_instrument_names_v_read(tmp_path):
    """C_p free: the voltage target is compared with the reading through the fitted C_p."""
    from tengfield.fit import calibrate

    path, cache, scene, _ = _setup(tmp_path, 0.0)
    result = calibrate(scene, targets=["V_pp_V=0.5", "Q_pp_nC=0.3"],
                       free=["surface_charge_uC_per_m2", "parallel_capacitance_pF"],
                       cache_dir=cache, solve=fx.plate_model_solve)
    assert result.values["parallel_capacitance_pF"] > 0
    assert result.residuals["V_pp_V"]["tool_key"] == "peak_to_peak.V_read_V"


def test_a_trace_names_the_waveform_each_column_is_compared_with(tmp_path, main, capsys):
    path, cache, scene, surrogate = _setup(tmp_path, 100.0)
    trace, _ = synthetic(scene, surrogate, 2, ("V", "Q"))
    csv = write_csv(tmp_path / "m.csv", trace)
    out = tmp_path / "out"
    assert main(["fit", str(path), "--measured", str(csv), "--free",
                 "surface_charge_uC_per_m2,time_shift_s", "-o", str(out), "--cache-dir",
                 str(cache)]) == 0
    printed = capsys.readouterr().out
    res = json.loads((out / "fit.json").read_text())["residuals"]
    # an instrument is given: each column is compared with what it reads
    assert res["V"]["tool_key"] == "V_read_V" and res["Q"]["tool_key"] == "Q_read_C"
    assert res["Q"]["tool_label"] == quantity("Q_read_C").label
    assert f"V (column 'V_meas'; tool: {quantity('V_read_V').label}): residual RMS" in printed
    assert (out / "fit.png").exists()


def test_the_compared_quantities_come_from_the_table_and_the_circuit():
    scene = fx.scene_with(circuit={"parallel_capacitance_pF": 100.0})
    for (letter, stat), key in MEASURED_KEYS.items():
        assert MEASURED[key][0] == stat
        name = MEASURED[key][1]
        assert compared_key(letter, stat, scene, 1e-10) == f"{stat}.{name}"
        assert compared_key(letter, "", scene, 1e-10) == name
    assert compared_key("V", "peak", scene, 0.0) == "peak.V_oc_V"
    load = fx.scene_with(circuit={"kind": "load", "load_ohm": 1e9})
    assert compared("V", "peak_to_peak", load, 0.0)["tool_key"] == "peak_to_peak.V_load_V"
    assert compared("I", "", load, 1e-10) == {"tool_key": "I_load_A",
                                               "tool_label": quantity("I_load_A").label,
                                               "tool_unit": "A"}
    assert compared("Q", "peak", load, 0.0)["tool_key"] == "peak.Q_sc_C"
