"""Real instruments' exports (issue #39): metadata lines before the header (found, or
given by header_row), ';' and tab separators, decimal commas, units in the header. The
three example exports of examples/ (examples/make_bench_exports.py: one trace saved three
ways) read to the same SI numbers; an export that still cannot be read names its line and
what was expected, and never echoes the file's text."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import tengfield as tf
from tengfield.errors import SceneError
from tengfield.fit.spec import parse_fit_section, read_trace

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def _trace(path, **fit):
    scene = tf.default_scene().with_values(fit=fit)
    return read_trace(path, parse_fit_section(scene))


def test_the_three_example_exports_read_to_the_same_trace():
    tek = _trace(EXAMPLES / "tek_scope.csv", time_column="TIME",
                 columns={"V": {"column": "CH1"}})
    log = _trace(EXAMPLES / "electrometer_log.tsv", time_column="Time",
                 columns={"Q": {"column": "Charge"}})
    semi = _trace(EXAMPLES / "scope_semicolon.csv", time_column="TIME",
                  columns={"V": {"column": "CH1"}, "Q": {"column": "CH2"}})
    n = 1000                                      # 0.2 s at 5 kHz, after 12 metadata lines
    for trace in (tek, log, semi):
        assert trace.time.size == n
        np.testing.assert_allclose(np.diff(trace.time), 2e-4, rtol=1e-6)   # ms -> s too
    np.testing.assert_allclose(semi.time, tek.time, atol=1e-9)
    v_pp = np.ptp(tek.values["V"])
    assert 0.3 < v_pp < 3.0                       # volts through 338 pF, not kilovolts
    np.testing.assert_allclose(semi.values["V"], tek.values["V"], atol=1e-6 * 1.01)
    q_pp = np.ptp(log.values["Q"])
    assert 0.1e-9 < q_pp < 1e-9                   # nC in the header -> coulombs
    np.testing.assert_allclose(semi.values["Q"], log.values["Q"], atol=1e-15 * 1.01)


def test_a_units_header_names_the_column_with_or_without_its_unit():
    with_unit = _trace(EXAMPLES / "scope_semicolon.csv", time_column="TIME [s]",
                       columns={"V": {"column": "CH1 [V]"}})
    bare = _trace(EXAMPLES / "scope_semicolon.csv", time_column="TIME",
                  columns={"V": {"column": "CH1"}})
    np.testing.assert_array_equal(with_unit.values["V"], bare.values["V"])


def test_header_row_can_be_given(tmp_path):
    path = tmp_path / "given.csv"
    lines = ["Instrument,X", "time,signal"] + [f"{i * 1e-3},{np.sin(i)}" for i in range(40)]
    path.write_text("\n".join(lines) + "\n")
    trace = _trace(path, time_column="time", header_row=2, columns={"V": {"column": "signal"}})
    assert trace.time.size == 40
    with pytest.raises(SceneError, match="line 1"):   # the header is not on line 1
        _trace(path, time_column="time", header_row=1, columns={"V": {"column": "signal"}})


SECRET = "s3cr3t-cell"


@pytest.mark.parametrize("case, expected", [
    ("short-row", "line 16 (data row 3) has 1 field(s): expected 2 (separated by ';'"),
    ("missing-column", "expected it on the header line 13"),
    ("bad-time-unit", "expected one of s, sec, ms"),
])
def test_an_unreadable_export_names_the_line_and_not_the_text(tmp_path, case, expected):
    meta = [f"{SECRET} {i};{SECRET}" for i in range(12)]
    header = "TIME [fortnights];CH1 [V]" if case == "bad-time-unit" else "TIME [s];CH1 [V]"
    if case == "missing-column":
        header = "TIME [s];CH9 [V]"
    rows = [f"{i * 1e-3:.4f};{np.sin(i):.4f}".replace(".", ",") for i in range(30)]
    if case == "short-row":
        rows[2] = SECRET
    path = tmp_path / "bad.csv"
    path.write_text("\n".join(meta + [header] + rows) + "\n")
    with pytest.raises(SceneError) as info:
        _trace(path, time_column="TIME", columns={"V": {"column": "CH1"}})
    message = str(info.value)
    assert expected in message and SECRET not in message and "fortnights" not in message
    assert "\n" not in message


def test_a_recorded_excitation_reads_an_export(tmp_path):
    """[excitation] kind = "recorded" through the same reader: metadata, ';', decimal
    commas and a unit (mm) in the header give the record of the plain CSV in SI."""
    t = np.arange(0, 0.5, 1e-3)
    z = 1.5e-3 * np.sin(2 * np.pi * 20 * t)
    plain = tmp_path / "plain.csv"
    plain.write_text("time_s,displacement_m\n"
                     + "".join(f"{a!r},{b!r}\n" for a, b in zip(t, z)))
    export = tmp_path / "export.csv"
    export.write_text("Logger;ACC-3\nDate;2026-11-28\n\ntime_s [ms];displacement_m [mm]\n"
                      + "".join(f"{a * 1e3:.3f};{b * 1e3:.9f}\n".replace(".", ",")
                                for a, b in zip(t, z)))
    scenes = [tf.Scene.from_dict({"excitation": {"kind": "recorded", "file": p.name,
                                                 "frequency_hz": 20.0},
                                  "run": {"duration_s": 0.4, "settle_periods": 2}},
                                 base_dir=tmp_path)
              for p in (plain, export)]
    a, b = scenes[0].excitation, scenes[1].excitation
    np.testing.assert_allclose(b.times, a.times, atol=1e-12)
    np.testing.assert_allclose(b.values, a.values, atol=1e-12)
