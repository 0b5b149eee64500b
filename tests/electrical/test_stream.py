"""The streamed electrical stage of a long run (issue #28 last item, #30.11) equals the
whole-record one: a short run with tiny chunks (many of them, impacts on their
boundaries) against the same run computed whole, for each streamed circuit kind, with
and without the instrument's C_p. Columns and peaks bit-identical, energy sums to
1e-12 relative. The field is the analytic plate model (no dolfinx)."""
from __future__ import annotations

import math

import numpy as np
import pytest

import tengfield as tf
from tengfield.electrical import stream
from tengfield.electrical.stream import StreamedWaveforms

import plate_model as fx

RUN = {"duration_s": 0.6, "settle_periods": 3, "sample_rate_hz": 5000.0}


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("surrogates")


def _both(cache, monkeypatch, chunk_rows, **sections):
    scene = fx.scene_with(run=RUN, **sections)
    whole = tf.run(scene, cache_dir=cache, solve=fx.plate_model_solve)
    monkeypatch.setattr(stream, "STREAM_ROWS", 10)
    monkeypatch.setattr(stream, "CHUNK_ROWS", chunk_rows)
    streamed = tf.run(scene, cache_dir=cache, solve=fx.plate_model_solve)
    monkeypatch.undo()
    return whole, streamed


def _same_numbers(a, b, path="", rel=1e-12):
    """Equal JSON-like trees: floats to ``rel`` relative (of the larger), the rest exactly."""
    if isinstance(a, dict):
        assert set(a) == set(b), path
        for k in a:
            _same_numbers(a[k], b[k], f"{path}.{k}", rel)
    elif isinstance(a, (list, tuple)):
        assert len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b)):
            _same_numbers(x, y, f"{path}[{i}]", rel)
    elif isinstance(a, float) and isinstance(b, float):
        if math.isnan(a):
            assert math.isnan(b), path
        else:
            assert abs(a - b) <= rel * max(abs(a), abs(b)), (path, a, b)
    else:
        assert a == b, (path, a, b)


def _summary_without_timing(summary):
    """The summary without its stages and without the matched load: a streamed run does
    not scan loads (it would hold the whole run; it says so in ``matched_load_reason``,
    checked in :func:`_streamed_has_no_matched_load`), the whole run does."""
    out = dict(summary)
    stages = {k: dict(v) for k, v in out.pop("stages").items()}
    out.pop("matched_load", None)
    out.pop("matched_load_reason", None)
    return out, stages


def _streamed_has_no_matched_load(whole, streamed):
    assert streamed.summary["matched_load"] is None
    assert "streamed" in streamed.summary["matched_load_reason"]
    if whole.curves is not None and whole.scene.array.cells == 0:
        assert whole.summary["matched_load"]["load_ohm"] > 0


@pytest.mark.parametrize("sections", [
    {"circuit": {"kind": "open"}},
    {"circuit": {"kind": "open", "parallel_capacitance_pF": 338.0}},
    {"circuit": {"kind": "short"}},
    {"circuit": {"kind": "load", "load_ohm": 1e8}},
    {"circuit": {"kind": "load", "load_ohm": 3e9, "parallel_capacitance_pF": 338.0}},
    {"circuit": {"kind": "load", "load_ohm": 1e5}},       # τ far below the output step
    {"circuit": {"kind": "series-rc", "load_ohm": 1e8}},  # C_s large: the deficit form
    {"circuit": {"kind": "series-rc", "load_ohm": 1e8, "series_capacitance_pF": 1.0,
                 "parallel_capacitance_pF": 338.0}},      # C_s small: the charge form
], ids=["open", "open-Cp", "short", "load", "load-Cp", "load-fast", "series-rc",
        "series-rc-small"])
@pytest.mark.parametrize("chunk_rows", [97, 1024])
def test_streamed_equals_whole(cache, monkeypatch, sections, chunk_rows):
    whole, streamed = _both(cache, monkeypatch, chunk_rows, **sections)
    assert not isinstance(whole.waveforms, StreamedWaveforms)
    assert isinstance(streamed.waveforms, StreamedWaveforms)
    rows = len(whole.t)
    assert rows > 2 * chunk_rows                      # many chunks
    assert streamed.stages["circuit"].details["streamed_chunks"] == -(-rows // chunk_rows)
    # every column bit-identical, also read chunk by chunk
    assert list(streamed.waveforms) == [c for c in list(streamed.waveforms)
                                        if c in whole.waveforms]
    assert set(streamed.waveforms) == set(whole.waveforms)
    chunks = list(streamed.waveforms.chunks())
    for column, values in whole.waveforms.items():
        np.testing.assert_array_equal(streamed.waveforms[column], values, err_msg=column)
        np.testing.assert_array_equal(np.concatenate([c[column] for c in chunks]), values,
                                      err_msg=column)
    assert streamed.peaks == whole.peaks              # the same extremes, bit for bit
    assert streamed.peak == whole.peak
    a, sa = _summary_without_timing(whole.summary)
    b, sb = _summary_without_timing(streamed.summary)
    _streamed_has_no_matched_load(whole, streamed)
    _same_numbers(a, b)
    assert sa["circuit"]["status"] == sb["circuit"]["status"]
    # the last 5 periods kept whole: the rows waveforms.png draws
    t = np.asarray(whole.t)
    last = t >= t[-1] - 5.0 * whole.scene.excitation.period
    for column, values in streamed.waveforms.tail.items():
        np.testing.assert_array_equal(values, np.asarray(whole.waveforms[column])[last])


def test_the_load_books_are_the_whole_runs(cache, monkeypatch):
    """The load's mean power and energy balance from sums over chunks (1e-12), and the
    V-Q loop of the last period (vq.png) from the kept tail, bit for bit."""
    whole, streamed = _both(cache, monkeypatch, 64, circuit={"kind": "load", "load_ohm": 1e8})
    wl, sl = whole.summary["load"], streamed.summary["load"]
    assert sl["mean_power_W"] > 0
    assert sl["integration_points"] == wl["integration_points"]
    for key in ("mean_power_W", "V_load_peak_to_peak_V", "I_load_peak_to_peak_A"):
        assert sl[key] == pytest.approx(wl[key], rel=1e-12, abs=0)
    for key, value in wl["energy_balance_J"].items():
        assert sl["energy_balance_J"][key] == pytest.approx(value, rel=1e-12, abs=0)
    (qa, va, area_a), (qb, vb, area_b) = whole.extras["_vq"]["load"], \
        streamed.extras["_vq"]["load"]
    np.testing.assert_array_equal(qa, qb)
    np.testing.assert_array_equal(va, vb)
    assert area_a == area_b


def test_envelope_brackets_every_sample(cache, monkeypatch):
    """The min/max envelope built while streaming holds every sample of its bin."""
    whole, streamed = _both(cache, monkeypatch, 200, circuit={"kind": "load", "load_ohm": 1e8})
    env = streamed.extras["_envelope"]
    lo, hi = env["V_load_V"]
    v = np.asarray(whole.waveforms["V_load_V"])
    assert np.min(lo) == np.min(v) and np.max(hi) == np.max(v)
    assert np.all(lo <= hi) and len(env["time_s"]) == len(lo)


def test_short_runs_keep_whole_arrays(cache):
    """Below STREAM_ROWS nothing changes: RunResult.waveforms is a dict of arrays."""
    r = tf.run(fx.scene_with(run=RUN), cache_dir=cache, solve=fx.plate_model_solve)
    assert isinstance(r.waveforms, dict)


#: a small store and chip levels the plate model's cell reaches in 0.6 s (the chip
#: switches on and off several times; tests/harvest/test_harvest_run.py)
SMALL_CHIP = {"kind": "rectifier", "storage_capacitance_uF": 1e-4, "pmic": "uvlo",
              "pmic_quiescent_current_A": 0.0, "uvlo_rising_V": 20.0, "uvlo_falling_V": 10.0,
              "pmic_output_V": 3.3, "pmic_load_ohm": 1e7, "pmic_shunt_V": 100.0}


def _close(a, b, err_msg=""):
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    scale = float(np.max(np.abs(a))) if a.size else 0.0
    np.testing.assert_allclose(b, a, rtol=1e-12, atol=1e-12 * scale, err_msg=err_msg)


@pytest.mark.parametrize("circuit", [
    {"kind": "rectifier"},
    SMALL_CHIP,
    {**SMALL_CHIP, "parallel_capacitance_pF": 338.0, "pmic_quiescent_current_A": 1e-9},
], ids=["rectifier", "rectifier-uvlo", "rectifier-uvlo-Cp-quiescent"])
@pytest.mark.parametrize("chunk_rows", [97, 1024])
@pytest.mark.filterwarnings("ignore:rectifier. numerical_dissipation_J")
def test_streamed_rectifier_equals_whole(cache, monkeypatch, circuit, chunk_rows):
    """The rectifier (and its UVLO chip) streamed: the harvester's state carried from
    chunk to chunk; columns, the rectifier block (switch counts, crossings, books) and
    the V-Q loop equal the whole record's (1e-12: the bridge charge is summed per chunk);
    charging.png's envelope holds the record's extremes."""
    whole, streamed = _both(cache, monkeypatch, chunk_rows, circuit=circuit)
    assert isinstance(streamed.waveforms, StreamedWaveforms)
    for column, values in whole.waveforms.items():
        _close(values, streamed.waveforms[column], err_msg=column)
    np.testing.assert_array_equal(streamed.waveforms["pmic_on"], whole.waveforms["pmic_on"])
    assert streamed.peaks == whole.peaks
    a, _ = _summary_without_timing(whole.summary)
    b, _ = _summary_without_timing(streamed.summary)
    _streamed_has_no_matched_load(whole, streamed)
    _same_numbers(a, b)
    rect = streamed.summary["rectifier"]
    if circuit is SMALL_CHIP:
        assert rect["chip_switch_on_count"] >= 2           # the chip did switch
        assert math.isfinite(rect["time_to_uvlo_rising_V_s"])
    (qa, va, area_a), (qb, vb, area_b) = whole.extras["_vq"]["rectifier"], \
        streamed.extras["_vq"]["rectifier"]
    _close(qa, qb)
    _close(va, vb)
    assert area_b == pytest.approx(area_a, rel=1e-12)
    fine, env = whole.extras["_fine"], streamed.extras["_fine"]
    assert np.max(env.store_voltage) == np.max(fine.store_voltage)
    assert np.min(env.store_voltage) == np.min(fine.store_voltage)
    assert np.all(np.diff(env.time) >= 0) and env.chip_on.any() == fine.chip_on.any()
