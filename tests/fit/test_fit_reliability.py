"""Issue #21 items 6 and 8 (fit side): a trace with no signal, a residual as large as the
signal, and the measured trace reader's holes (near-duplicate times, malformed lines,
values near 1e300). Through ``tengfield fit`` (plate-model surrogate pre-cached)."""
from __future__ import annotations

import json

import numpy as np
import pytest

import plate_model as fx
from fit_synthetic import TRUE, synthetic, write_csv

from tengfield import cli
from tengfield.fit import reference_surrogate
from tengfield.scene import load_scene

SCENE = """
[run]
duration_s = 1.0
settle_periods = 10

[instrument]
capacitance_pF = 100.0

[fit]
time_column = "time_ms"
time_unit = "ms"

[fit.columns.V]
column = "V_meas"
unit = "V"
"""


@pytest.fixture
def setup(tmp_path):
    path = tmp_path / "scene.toml"
    path.write_text(SCENE)
    scene = load_scene(path)
    cache = tmp_path / "cache"
    surrogate = reference_surrogate(scene, cache_dir=cache, solve=fx.plate_model_solve)[:2]
    trace, _ = synthetic(scene, surrogate, 5, ("V",), true={**TRUE, "restitution": 0.1},
                         duration=0.2)
    return path, cache, trace


def _fit(path, cache, csv, out, capsys):
    code = cli.main(["fit", str(path), "--measured", str(csv), "-o", str(out), "--cache-dir",
                     str(cache), "--no-plots"])
    return code, capsys.readouterr()


def _one_line(code, captured, *needles):
    assert code == 2
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("tengfield: error: "), captured.err
    for n in needles:
        assert n in lines[0], (n, lines[0])


def test_a_flat_trace_is_refused_as_carrying_no_signal(setup, tmp_path, capsys):
    """It fitted σ as identifiable with χ²/ν ≈ 0.9 and no note."""
    path, cache, trace = setup
    trace.values["V"] = np.full(trace.time.size, 0.7)
    csv = write_csv(tmp_path / "flat.csv", trace)
    code, captured = _fit(path, cache, csv, tmp_path / "out", capsys)
    _one_line(code, captured, "carries no signal", "'V_meas'", "constant")


def test_a_trace_times_1e300_is_refused_naming_the_row(setup, tmp_path, capsys):
    """It blamed the model ('the model gives no signal at the start values')."""
    path, cache, trace = setup
    trace.values["V"] = trace.values["V"] * 1e300
    csv = write_csv(tmp_path / "huge.csv", trace)
    code, captured = _fit(path, cache, csv, tmp_path / "out", capsys)
    _one_line(code, captured, "'V_meas'", "data row 1", "allowed |x| <= 1e+06 V")


def test_a_residual_as_large_as_the_signal_warns_and_notes(setup, tmp_path, capsys):
    """A trace 1e4 x too large (a unit slip) used to be fitted without a word."""
    path, cache, trace = setup
    trace.values["V"] = trace.values["V"] * 1e4
    csv = write_csv(tmp_path / "scaled.csv", trace)
    out = tmp_path / "out"
    code, captured = _fit(path, cache, csv, out, capsys)
    assert code == 0
    assert "tengfield: warning: fit: the residual is as large as the signal" in captured.err
    summary = json.loads((out / "fit.json").read_text())
    assert any("residual is as large as the signal" in n
               for n in summary["identifiability_notes"])
    assert not any(p["identifiable"] for p in summary["parameters"].values())


def test_pure_noise_is_not_reported_as_identified(setup, tmp_path, capsys):
    path, cache, trace = setup
    trace.values["V"] = np.random.default_rng(3).standard_normal(trace.time.size)
    csv = write_csv(tmp_path / "noise.csv", trace)
    out = tmp_path / "out"
    code, captured = _fit(path, cache, csv, out, capsys)
    assert code == 0 and "residual is as large as the signal" in captured.err
    summary = json.loads((out / "fit.json").read_text())
    assert not summary["parameters"]["surface_charge_uC_per_m2"]["identifiable"]


def test_a_near_duplicate_time_is_refused(setup, tmp_path, capsys):
    path, cache, trace = setup
    csv = write_csv(tmp_path / "m.csv", trace)
    lines = csv.read_text().splitlines()
    t, v = lines[51].split(",")
    lines.insert(52, f"{float(t) + 1e-12!r},{v}")
    csv.write_text("\n".join(lines) + "\n")
    code, captured = _fit(path, cache, csv, tmp_path / "out", capsys)
    _one_line(code, captured, "m.csv", "data row 52", "far below the data's resolution")


def test_a_row_with_a_missing_column_names_its_line(setup, tmp_path, capsys):
    path, cache, trace = setup
    csv = write_csv(tmp_path / "m.csv", trace)
    lines = csv.read_text().splitlines()
    lines[30] = lines[30].split(",")[0] + ",1.0,2.0"
    csv.write_text("\n".join(lines) + "\n")
    code, captured = _fit(path, cache, csv, tmp_path / "out", capsys)
    _one_line(code, captured, "m.csv", "line 31", "data row 30", "3 field(s): expected 2")


def test_a_constant_column_next_to_a_signal_is_refused_naming_it(tmp_path, capsys):
    """A flat V column (a probe not connected) beside a good Q: the fit pulled sigma to
    -0.05 +- 0.001 (truth -30), weighted the Q column out as 'noise', reported chi2/nu = 1
    and no note (the flat column's zero spread kept the residual check quiet)."""
    path = tmp_path / "scene.toml"
    path.write_text(SCENE + '\n[fit.columns.Q]\ncolumn = "Q_meas"\nunit = "nC"\n')
    scene = load_scene(path)
    cache = tmp_path / "cache"
    surrogate = reference_surrogate(scene, cache_dir=cache, solve=fx.plate_model_solve)[:2]
    trace, _ = synthetic(scene, surrogate, 5, ("V", "Q"), duration=0.2)
    trace.values["V"] = np.full(trace.time.size, 5.0)
    csv = write_csv(tmp_path / "flat_v.csv", trace)
    code, captured = _fit(path, cache, csv, tmp_path / "out", capsys)
    _one_line(code, captured, "'V_meas'", "constant (5 V)", "[fit.columns]")
    assert not (tmp_path / "out" / "fit.json").exists()
