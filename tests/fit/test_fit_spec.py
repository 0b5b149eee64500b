"""The [fit] section, measured CSVs and targets: defaults and validation."""
from __future__ import annotations

import numpy as np
import pytest

from tengfield.errors import SceneError
from tengfield.fit import parse_fit_section, parse_targets, read_trace
from tengfield.scene import parse_scene


def test_scene_passes_the_fit_table_through():
    scene = parse_scene('[fit]\nloss = "huber"\n[fit.parameters]\nrestitution = {max = 0.4}\n')
    assert scene.raw["fit"]["parameters"]["restitution"] == {"max": 0.4}
    assert scene.with_values(circuit={"load_ohm": 1e6}).raw["fit"]["loss"] == "huber"
    with pytest.raises(SceneError, match=r"\[fit\] must be a table"):
        parse_scene("fit = 3\n")


def test_defaults_free_sigma_and_the_shift_over_two_periods():
    scene = parse_scene("[excitation]\nfrequency_hz = 25.0\n")
    spec = parse_fit_section(scene)
    assert [p.name for p in spec.parameters] == ["surface_charge_uC_per_m2", "time_shift_s"]
    sigma, shift = spec.parameters
    assert sigma.start == pytest.approx(-8.0) and not sigma.start_given
    assert (shift.lo, shift.hi) == (0.0, pytest.approx(0.08))
    assert spec.loss == "linear" and spec.columns is None


def test_a_run_waveforms_csv_is_read_without_a_columns_table(tmp_path):
    """The columns of `tengfield run`'s waveforms.csv are found by name, SI units."""
    t = np.linspace(0.0, 0.1, 50)
    path = tmp_path / "waveforms.csv"
    np.savetxt(path, np.column_stack([t, t, 2 * t, 3 * t, 4 * t]), delimiter=",",
               header="time_s,gap_m,V_oc_V,Q_sc_C,I_sc_A", comments="")
    trace = read_trace(path, parse_fit_section(parse_scene("")))
    assert sorted(trace.values) == ["I", "Q", "V"]
    np.testing.assert_allclose(trace.values["Q"], 3 * t)
    assert trace.span == pytest.approx(0.1)


def test_a_utf8_byte_order_mark_is_dropped(tmp_path):
    """Spreadsheet exports often start with a BOM: the first column is still 'time_s'."""
    t = np.linspace(0.0, 0.1, 50)
    path = tmp_path / "bom.csv"
    lines = ["time_s,V_oc_V"] + [f"{float(x)!r},{float(2 * x)!r}" for x in t]
    path.write_bytes(b"\xef\xbb\xbf" + "\n".join(lines).encode())
    trace = read_trace(path, parse_fit_section(parse_scene("")))
    np.testing.assert_array_equal(trace.time, t)
    np.testing.assert_array_equal(trace.values["V"], 2 * t)


def test_columns_units_and_noise_are_converted_to_si(tmp_path):
    scene = parse_scene('[fit]\ntime_column = "t"\ntime_unit = "us"\n'
                        '[fit.columns.I]\ncolumn = "i"\nunit = "nA"\nnoise = 0.5\n')
    spec = parse_fit_section(scene)
    path = tmp_path / "m.csv"
    np.savetxt(path, np.column_stack([np.arange(10.0), np.ones(10)]), delimiter=",",
               header="t,i", comments="")
    trace = read_trace(path, spec)
    assert trace.time[1] == pytest.approx(1e-6)
    assert trace.values["I"][0] == pytest.approx(1e-9)
    assert spec.columns[0].noise == pytest.approx(0.5e-9)


def test_targets_parse_units_and_uncertainty():
    v, q = parse_targets(["V_pp_V=4.2", "Q_pp_nC=1.42+-0.1"])
    assert (v.key, v.value, v.uncertainty) == ("V_pp", 4.2, pytest.approx(0.21))
    assert (q.value, q.uncertainty) == (pytest.approx(1.42e-9), pytest.approx(0.1e-9))
    with pytest.raises(SceneError, match="given twice"):
        parse_targets(["V_pp_V=1", "V_pp_mV=1000"])
