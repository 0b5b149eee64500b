"""``tengfield fit`` end to end on a small scene (plate-model surrogate pre-cached: no dolfinx)."""
from __future__ import annotations

import json

import numpy as np
import pytest

import plate_model as fx
from fit_synthetic import SHIFT, TRUE, synthetic, trace_scene, write_csv

from tengfield import cli
from tengfield.fit import reference_surrogate
from tengfield.fit._model import ForwardModel
from tengfield.scene import load_scene

SCENE = trace_scene("surface_charge_uC_per_m2 = {min = -100.0, max = 0.0}\n"
                    "parallel_capacitance_pF = {start = 250.0, min = 0.0, max = 1000.0}\n"
                    "time_shift_s = {}\n")


@pytest.fixture
def main(monkeypatch):
    """``tengfield.cli.main`` with the fit command registered (the lead adds it for good)."""
    if "fit" not in cli.COMMAND_MODULES:
        monkeypatch.setattr(cli, "COMMAND_MODULES", [*cli.COMMAND_MODULES, "fit"])
    return cli.main


@pytest.fixture
def setup(tmp_path):
    """(scene path, cache dir, scene) with the plate-model surrogate of the scene cached."""
    path = tmp_path / "scene.toml"
    path.write_text(SCENE)
    scene = load_scene(path)
    cache = tmp_path / "cache"
    surrogate = reference_surrogate(scene, cache_dir=cache, solve=fx.plate_model_solve)[:2]
    return path, cache, scene, surrogate


def test_fit_trace_end_to_end(setup, main, tmp_path, capsys):
    path, cache, scene, surrogate = setup
    trace, _ = synthetic(scene, surrogate, 21, ("V", "Q"), true={**TRUE, "restitution": 0.1})
    csv = write_csv(tmp_path / "measured.csv", trace)
    out = tmp_path / "out"
    code = main(["fit", str(path), "--measured", str(csv), "-o", str(out), "--cache-dir",
                 str(cache)])
    assert code == 0
    summary = json.loads((out / "fit.json").read_text())
    params = summary["parameters"]
    for name in ("surface_charge_uC_per_m2", "parallel_capacitance_pF"):
        assert abs(params[name]["value"] - TRUE[name]) < 3.5 * params[name]["standard_error"]
        assert params[name]["identifiable"]
    period = scene.excitation.period
    err = (params["time_shift_s"]["value"] - SHIFT + period / 2) % period - period / 2
    assert abs(err) < 3.5 * params["time_shift_s"]["standard_error"]
    assert set(summary["residual_rms"]) == {"V", "Q"}
    assert summary["iterations"]["function_evaluations"] > 0 and summary["wall_time_s"] > 0
    assert len(summary["correlation"]["matrix"]) == 3
    assert (out / "fit.png").stat().st_size > 1000
    fitted = load_scene(out / "fitted.toml")           # ready for `tengfield run`
    assert fitted.raw["fit"] == scene.raw["fit"]        # every section whole (#43.1)
    assert fitted.device.surface_charge * 1e6 == pytest.approx(
        params["surface_charge_uC_per_m2"]["value"], rel=1e-5)
    assert fitted.circuit.parallel_capacitance * 1e12 == pytest.approx(
        params["parallel_capacitance_pF"]["value"], rel=1e-5)
    assert fitted.run == scene.run and fitted.excitation == scene.excitation
    assert "surface_charge_uC_per_m2" in capsys.readouterr().out


def test_fit_targets_end_to_end(setup, main, tmp_path):
    """Peak-to-peak V and Q made at σ = -30, C_p = 100 pF come back from --targets."""
    path, cache, scene, (curves, sigma_ref) = setup
    model = ForwardModel(scene, curves, sigma_ref, span=0.5)
    peaks = model.scalars(TRUE)
    out = tmp_path / "out"
    code = main(["fit", str(path), "--targets", f"V_pp_V={peaks['V_pp']:.6g}",
                 f"Q_pp_nC={peaks['Q_pp'] * 1e9:.6g}+-0.01", "--free",
                 "surface_charge_uC_per_m2,parallel_capacitance_pF", "-o", str(out),
                 "--cache-dir", str(cache)])
    assert code == 0
    params = json.loads((out / "fit.json").read_text())["parameters"]
    assert params["surface_charge_uC_per_m2"]["value"] == pytest.approx(-30.0, rel=1e-3)
    assert params["parallel_capacitance_pF"]["value"] == pytest.approx(100.0, rel=1e-3)
    assert (out / "fit.png").exists() and (out / "fitted.toml").exists()


def _error(main, capsys, argv):
    code = main(argv)
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith("tengfield: error: ") and err.count("\n") == 1, err
    assert "Traceback" not in err
    return err


@pytest.mark.parametrize("case, expected", [
    ("wrong-column", "[fit.columns.Q] column = 'Q_meas' is not a column"),
    ("nan", "column 'V_meas' holds NaN"),
    ("empty", "has 0 data rows"),
    ("no-file", "no such file"),
    ("not-increasing", "time is not strictly increasing"),
    ("utf-16", "is UTF-16 text: save it as UTF-8"),
    ("binary", "is binary data (byte 0x"),
    # ';'- and tab-separated exports are read since issue #39 (tests/fit/test_fit_exports.py)
])
def test_bad_traces_are_one_line_errors(setup, main, tmp_path, capsys, case, expected):
    path, cache, _, _ = setup
    csv = tmp_path / "bad.csv"
    t = np.arange(20) * 0.1
    rows = np.column_stack([t, np.sin(t), np.cos(t)])
    header = "time_ms,V_meas,Q_meas"
    if case == "wrong-column":
        header = "time_ms,V_meas,Q_nC"
    if case == "nan":
        rows[5, 1] = np.nan
    if case == "not-increasing":
        rows[7, 0] = rows[6, 0]
    if case == "empty":
        rows = rows[:0]
    if case != "no-file":
        np.savetxt(csv, rows, delimiter=",", header=header, comments="")
    if case == "utf-16":
        csv.write_bytes(csv.read_text().encode("utf-16"))
    if case == "binary":
        csv.write_bytes(b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR\xff")
    if case in ("semicolon", "tab"):
        csv.write_text(csv.read_text().replace(",", ";" if case == "semicolon" else "\t"))
    err = _error(main, capsys, ["fit", str(path), "--measured", str(csv), "-o",
                                str(tmp_path / "out"), "--cache-dir", str(cache)])
    assert expected in err


@pytest.mark.parametrize("fit_text, expected", [
    ('[fit]\nlos = "huber"', "unknown key [fit] los (did you mean 'loss'?)"),
    ('[fit]\nloss = "l3"', "[fit] loss = 'l3' is not allowed"),
    ("[fit.parameters]\nrestitution = {min = 0.5, max = 1.5}", "allowed [0, 1]"),
    ("[fit.parameters]\nsigma = {}", "unknown fit parameter 'sigma'"),
    ("[fit.parameters]\nload_ohm = {}", "the scene has no load"),
    ("[fit.parameters]\nparallel_capacitance_pF = {start = 5.0, min = 10.0, max = 20.0}",
     "[fit.parameters] parallel_capacitance_pF.start = 5.0 is out of range: allowed [10, 20]"),
    ('[fit.columns.V]\nunit = "volt"', "[fit.columns.V] unit = 'volt' is not allowed"),
    ("[fit.columns.P]\n", "unknown quantity [fit.columns.P]"),
    # a 146 TiB start-scan grid (a MemoryError traceback); the default scene runs at 20 Hz
    ("[fit.parameters]\ntime_shift_s = {max = 1e9}",
     "[fit.parameters] time_shift_s: bounds [0, 1e+09] s span 2e+10 periods: allowed at most "
     "100 periods (5 s;"),
])
def test_bad_fit_sections_are_one_line_errors(main, tmp_path, capsys, fit_text, expected):
    path = tmp_path / "scene.toml"
    path.write_text(fit_text + "\n")
    csv = tmp_path / "m.csv"
    csv.write_text("time_s,V_oc_V\n" + "".join(f"{i},{i}\n" for i in range(10)))
    err = _error(main, capsys, ["fit", str(path), "--measured", str(csv), "-o",
                                str(tmp_path / "out")])
    assert expected in err, err


@pytest.mark.parametrize("target, expected", [
    ("V_pp=4.2", "expected NAME=VALUE"),
    ("Q_pp_mC=1.4", "unit 'mC' is not allowed"),
    ("I_peak_uA=-0.16", "out of range"),
    # a unit slip, as a trace beyond 1 MV / 1 C / 1 kA is refused: it was fitted and said
    # "surface_charge_uC_per_m2 has no effect on these data"
    ("V_pp_V=1e30", "V_pp = 1e+30 V is out of range: allowed (0, 1e+06] V"),
    ("Q_pp_nC=2e9", "Q_pp = 2e+09 nC is out of range: allowed (0, 1e+09] nC"),
    ("I_peak_mA=5e6", "I_peak = 5e+06 mA is out of range: allowed (0, 1e+06] mA"),
])
def test_bad_targets_are_one_line_errors(main, tmp_path, capsys, target, expected):
    err = _error(main, capsys, ["fit", "--targets", target, "-o", str(tmp_path / "out")])
    assert expected in err, err


LOAD_SCENE = """
[run]
duration_s = 1.0
settle_periods = 10

[circuit]
kind = "load"
load_ohm = 1e8

[fit.parameters]
surface_charge_uC_per_m2 = {}
load_ohm = {min = 1e6, max = 1e11}
time_shift_s = {}
"""


def test_a_load_runs_waveforms_csv_is_read_by_its_load_columns(main, tmp_path):
    """[circuit] kind = "load" compares V and I with the load's voltage and current: without
    [fit.columns] a `tengfield run` waveforms.csv of a load gives V_load_V and I_load_A
    (it took V_oc_V and I_sc_A: the fit pushed R to ~1e5 ohm, truth 1e9, chi2/nu < 1 and
    no note, the open-circuit voltage weighted out as noise)."""
    path = tmp_path / "scene.toml"
    path.write_text(LOAD_SCENE)
    scene = load_scene(path)
    cache = tmp_path / "cache"
    surrogate = reference_surrogate(scene, cache_dir=cache, solve=fx.plate_model_solve)[:2]
    true = {"surface_charge_uC_per_m2": -30.0, "load_ohm": 1e9}
    kw = dict(true=true, white=0.005, hum=0.0, duration=0.3)
    loaded, _ = synthetic(scene, surrogate, 4, ("V", "Q", "I"), **kw)
    opened, _ = synthetic(scene.with_values(circuit={"kind": "open"}), surrogate, 4,
                          ("V", "I"), **kw)
    csv = tmp_path / "waveforms.csv"     # the columns `tengfield run` writes for a load
    np.savetxt(csv, np.column_stack([loaded.time, opened.values["V"], loaded.values["Q"],
                                     opened.values["I"], loaded.values["V"],
                                     loaded.values["I"]]),
               delimiter=",", header="time_s,V_oc_V,Q_sc_C,I_sc_A,V_load_V,I_load_A",
               comments="", fmt="%.12g")
    out = tmp_path / "out"
    assert main(["fit", str(path), "--measured", str(csv), "-o", str(out), "--cache-dir",
                 str(cache), "--no-plots"]) == 0
    summary = json.loads((out / "fit.json").read_text())
    assert set(summary["residual_rms"]) == {"V", "Q", "I"}
    params = summary["parameters"]
    for name, value in true.items():
        assert abs(params[name]["value"] - value) < 3.5 * params[name]["standard_error"], params
    assert params["load_ohm"]["value"] == pytest.approx(1e9, rel=0.05)
