"""Issue #21 items 7, 8, 17 (scene side): extreme values that used to pass validation and
give nonsense, malformed recorded CSVs, oversized inputs. Through the CLI where the bug
was seen there: exit code 2, one line, no traceback."""
from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tengfield.dynamics.table import sine_table
from tengfield.errors import SceneError
from tengfield.scene import load_scene, parse_scene
from tengfield.scene.limits import auto_domain_radius
from tengfield.scene.schema import SCHEMA

SHORT = "[run]\nduration_s = 0.3\nsettle_periods = 2\nsample_rate_hz = 2000\n"


def one_line_error(proc, *needles):
    assert proc.returncode == 2, (proc.returncode, proc.stdout, proc.stderr)
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("tengfield: error: "), proc.stderr
    assert "Traceback" not in proc.stderr
    for n in needles:
        assert n in lines[0], (n, lines[0])
    return lines[0]


# -- item 7: extreme values --------------------------------------------------------------
@pytest.mark.parametrize("body,needles", [
    ("[excitation]\namplitude_mm = 1e308\n", ["amplitude_mm", "1e+308", "allowed [0, 1e+06]"]),
    ("[excitation]\namplitude_mm = 1e308\n[contact]\nmodel = '3d'\n", ["amplitude_mm"]),
    ("[circuit]\nkind = 'load'\nload_ohm = 1e-300\n", ["load_ohm", "1e-300", "allowed [0.001"]),
    ("[device]\nplate_thickness_mm = 1e308\n", ["plate_thickness_mm", "10000]"]),
    ("[run]\nsettle_periods = " + "1" * 5000 + "\n", ["line 2", "settle_periods",
                                                      "5000 digits", "out of range"]),
    ("[run]\nduration_s = " + "1" * 400 + "\n", ["duration_s", "400 digits", "out of range"]),
    ("[fit]\nx = " + "[" * 3000 + "]" * 3000 + "\n", ["nested too deeply", "allowed 8"]),
    ("[run]\nduration_s = 1979-05-27\n", ["[run] duration_s", "1979-05-27", "date"]),
    ("[field]\ndomain_radius_mm = 1979-05-27\n", ["domain_radius_mm", "1979-05-27", "date"]),
    ("[run]\nduration_s = 1e-300\nsettle_periods = 0\n", ["samples", "allowed >= 2"]),
    ("[initial]\ntime_s = 1e300\n", ["time_s", "allowed [-1e+12, 1e+12]"]),
])
def test_extreme_scene_values_are_one_line_errors(run_cli, tmp_path, body, needles):
    scene = tmp_path / "x.toml"
    scene.write_text(body + SHORT if "[run]" not in body else body)
    one_line_error(run_cli("scene", scene), *needles)


def test_huge_amplitude_is_refused_before_the_dynamics(run_cli, tmp_path):
    """It ran: 'regime rest' (impact) or a NaN trajectory (3D), both with exit code 0."""
    scene = tmp_path / "x.toml"
    scene.write_text("[excitation]\namplitude_mm = 1e308\n" + SHORT)
    one_line_error(run_cli("dynamics", scene, "-o", tmp_path / "out", "--no-plots"),
                   "amplitude_mm")
    assert not (tmp_path / "out" / "summary.json").exists()


def test_a_big_scene_file_is_refused_before_reading(run_cli, tmp_path):
    scene = tmp_path / "big.toml"
    scene.write_text("# padding\n" * 200_000 + SHORT)
    one_line_error(run_cli("scene", scene), "bytes: allowed at most 1,000,000")


def _numeric_keys():
    return [(sec, key) for sec, keys in SCHEMA.items() for key, spec in keys.items()
            if spec[1] in (int, float)]


EXTREMES = [1e308, -1e308, 1e-300, -1e-300, 5e-324, 1e300, 1e30, 1e-30, 0.0, 2**63, 10**400]


@pytest.mark.parametrize("sec,key", _numeric_keys())
@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(value=st.sampled_from(EXTREMES) | st.floats(allow_nan=False, allow_infinity=False))
def test_every_numeric_key_is_refused_or_gives_finite_numbers(sec, key, value):
    """Each numeric key with an extreme value: a SceneError naming the key, or a scene whose
    derived numbers (masses, volumes, the table's derivative bounds, the auto domain) are
    finite."""
    spec = SCHEMA[sec][key]
    if spec[1] is int and isinstance(value, float):
        value = int(value)
    text = f"[{sec}]\n{key} = {value!r}\n"
    if isinstance(value, int) and abs(value) > 10**300:
        text = f"[{sec}]\n{key} = {value}\n"
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            scene = parse_scene(text)
        except SceneError as exc:
            msg = str(exc)
            assert "\n" not in msg
            assert key in msg or "samples" in msg or "periods" in msg or "[" in msg, msg
            scene = None
    # a key the default scene does not use (another shape's, another contact law's) or a
    # renamed one is read with one warning naming it, and a reader below Nyquist says it
    # aliases: nothing else warns
    for warning in caught:
        text_ = str(warning.message)
        assert f"[{sec}] {key}" in text_ and "\n" not in text_, text_
        assert ("left out" in text_ and warning.category is RuntimeWarning) or (
            "is now" in text_ and warning.category is FutureWarning) or (
            "meant in metres" in text_ and warning.category is UserWarning
            and key.endswith("_mm") and 0 < abs(value) < 0.05) or (
            "(Nyquist)" in text_ and warning.category is RuntimeWarning
            and (sec, key) == ("instrument", "sample_rate_hz")
            and 0 < value < 2 * scene.excitation.frequency), text_
    if scene is None:
        return
    dev, exc_ = scene.device, scene.excitation
    numbers = [dev.ball_mass, dev.ball_charge, dev.bounding_radius, dev.cell_volume,
               dev.plate_spacing, exc_.omega, exc_.period, exc_.gamma,
               auto_domain_radius(dev), scene.run.duration * scene.run.sample_rate,
               scene.initial.time + scene.run.duration, scene.circuit.load,
               1.0 / scene.circuit.load, scene.circuit.storage_capacitance]
    table = sine_table(exc_.amplitude, exc_.omega, exc_.phase)
    numbers += [table.acc_bound, table.jerk_bound, table.snap_bound]
    assert all(math.isfinite(x) for x in numbers), (sec, key, value, numbers)


# -- item 7/8: recorded excitation CSV ------------------------------------------------------
def _recorded_scene(tmp_path, body):
    (tmp_path / "table.csv").write_text(body)
    scene = tmp_path / "rec.toml"
    scene.write_text("[excitation]\nkind = 'recorded'\nfile = 'table.csv'\nfrequency_hz = 20\n"
                     "[run]\nduration_s = 0.2\nsettle_periods = 1\nsample_rate_hz = 2000\n")
    return scene


def _record(n=400, rate=1000.0, amp=1e-3):
    """(times, values) as lists of Python floats: their repr is the number on numpy 1 and 2
    (numpy 2's np.float64 repr reads 'np.float64(0.0)')."""
    t = np.arange(n) / rate
    return t.tolist(), (amp * np.sin(2 * np.pi * 20 * t)).tolist()


def test_recorded_values_near_1e300_are_one_line(run_cli, tmp_path):
    t, y = _record()
    y[10] = 3e300
    body = "time_s,displacement_m\n" + "".join(f"{a!r},{b!r}\n" for a, b in zip(t, y))
    one_line_error(run_cli("scene", _recorded_scene(tmp_path, body)),
                   "table.csv", "data row 11", "3e+300", "allowed |x| <= 1000 m")


def test_recorded_near_duplicate_time_is_refused_naming_the_row(run_cli, tmp_path):
    """A stamp 1e-15 s after its neighbour was accepted and changed the motion."""
    t, y = _record()
    rows = [f"{a!r},{b!r}\n" for a, b in zip(t, y)]
    rows.insert(101, f"{t[100] + 1e-15!r},{y[100]!r}\n")
    body = "time_s,displacement_m\n" + "".join(rows)
    one_line_error(run_cli("scene", _recorded_scene(tmp_path, body)),
                   "table.csv", "data row 102", "far below the data's resolution", "0.1 s")


def test_recorded_row_with_a_missing_column_names_the_line(run_cli, tmp_path):
    """numpy said 'Some errors were detected !' with no row number."""
    t, y = _record()
    rows = [f"{a!r},{b!r}\n" for a, b in zip(t, y)]
    rows[40] = f"{t[40]!r}\n"
    body = "time_s,displacement_m\n" + "".join(rows)
    one_line_error(run_cli("scene", _recorded_scene(tmp_path, body)),
                   "table.csv", "line 42", "data row 41", "1 field(s): expected 2")


@pytest.mark.slow
def test_a_record_arrow_refuses_never_aborts_the_process(cli_command, cli_env, tmp_path):
    """Arrow's streaming reader left a read-ahead task behind when it refused a block: a
    process ending right after it aborted ("terminate called without an active
    exception", exit 134) in ~15 % of runs with four at once. Every run is one line, exit 2."""
    import subprocess

    t, y = _record()
    rows = [f"{a!r},{b!r}\n" for a, b in zip(t, y)]
    rows[40] = f"{t[40]!r}\n"
    scene = _recorded_scene(tmp_path, "time_s,displacement_m\n" + "".join(rows))
    codes = []
    for _ in range(6):
        procs = [subprocess.Popen(cli_command("scene", scene), env=cli_env(),
                                  stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
                 for _ in range(4)]
        for proc in procs:
            _out, err = proc.communicate(timeout=300)
            codes.append((proc.returncode, err.strip().splitlines()[-1:]))
    assert all(code == 2 for code, _ in codes), codes


def test_recorded_file_too_large_is_refused_before_reading(tmp_path, monkeypatch):
    import tengfield.scene.recorded as recorded

    monkeypatch.setattr(recorded, "MAX_RECORDED_BYTES", 1000)
    t, y = _record()
    body = "time_s,displacement_m\n" + "".join(f"{a!r},{b!r}\n" for a, b in zip(t, y))
    with pytest.raises(SceneError, match=r"table.csv' has [0-9,]+ bytes: allowed at most 1,000"):
        load_scene(_recorded_scene(tmp_path, body))


def test_recorded_rows_beyond_the_limit_are_refused_while_reading(tmp_path, monkeypatch):
    import tengfield.scene.recorded as recorded

    monkeypatch.setattr(recorded, "MAX_RECORDED_ROWS", 100)
    t, y = _record()
    body = "time_s,displacement_m\n" + "".join(f"{a!r},{b!r}\n" for a, b in zip(t, y))
    with pytest.raises(SceneError, match="more than 100 data rows"):
        load_scene(_recorded_scene(tmp_path, body))


@pytest.mark.parametrize("sep", [";", "\t"], ids=["semicolon", "tab"])
def test_recorded_file_with_another_separator_is_read(tmp_path, sep):
    """A ';' or tab separated export (refused before issue #39) reads to the record of the
    comma-separated file."""
    t, y = _record()
    body = f"time_s{sep}displacement_m\n" + "".join(
        f"{float(a)!r}{sep}{float(b)!r}\n" for a, b in zip(t, y))
    exc = load_scene(_recorded_scene(tmp_path, body)).excitation
    np.testing.assert_array_equal(exc.times, t)
    np.testing.assert_array_equal(exc.values, y)
