"""The one electrical loop (tengfield.electrical.loop, issue #51): a circuit kind is a small
contract (start: its state; the state's chunk: a step; finish: its record) that the loop
drives over the Source's chunks, a whole run being one chunk. A kind written here, outside
the package, runs whole and in chunks of any size with the same numbers; the loop's own
peaks are those of its columns; the registered kinds give the same columns whole and in
chunks. The field is the analytic plate model (no dolfinx)."""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import tengfield as tf
from tengfield.electrical import loop as loop_module
from tengfield.electrical.circuits import Circuit, CircuitRun, circuit_for
from tengfield.electrical.loop import Loop
from tengfield.source import Source

import plate_model as fx

RUN = {"duration_s": 0.3, "settle_periods": 2, "sample_rate_hz": 10000.0}


class _Counted:
    """The state of :class:`ChargeMeter`: the charge the short circuit has carried since
    the run's first sample, and how many chunks it saw."""

    def __init__(self, source):
        self.source, self.first, self.chunks = source, None, 0

    def chunk(self, i0, i1):
        q = self.source.rows(i0, i1)["Q_sc"]
        if self.first is None:
            self.first = float(q[0])
        self.chunks += 1
        return {"Q_moved_C": q - self.first}


class ChargeMeter(Circuit):
    """A circuit kind written outside the package: an ideal charge meter in the short
    circuit (the charge moved since the start)."""
    name = "charge-meter"
    columns = ("Q_moved_C",)

    def start(self, scene, source, window_start, chunk_rows):
        return _Counted(source) if source.charged else None

    def finish(self, scene, source, state, record, note):
        return CircuitRun({}, f"charge meter{note}", {"chunks": state.chunks},
                          data={"moved_peak_to_peak": record["column_peak_to_peak"]})


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    scene = fx.scene_with(run=RUN)
    return tf.run(scene, cache_dir=tmp_path_factory.mktemp("surrogates"),
                  solve=fx.plate_model_solve)


def _loop(result, monkeypatch, entry, chunk_rows=None):
    monkeypatch.setattr(loop_module, "circuit_for", lambda scene: entry)
    source = Source.of_scene(result.scene, result.curves, result.dynamics)
    return Loop(result.scene, source, chunk_rows)


@settings(max_examples=12, deadline=None)
@given(size=st.integers(min_value=1, max_value=3000))   # the run's 3001 rows: 2 chunks at least
def test_a_new_kind_is_one_object_and_runs_in_chunks_of_any_size(result, size):
    with pytest.MonkeyPatch.context() as monkeypatch:
        whole = _loop(result, monkeypatch, ChargeMeter())
        one = whole.reduce()
        chunked = _loop(result, monkeypatch, ChargeMeter(), size)
        many = chunked.reduce()
        ran_one, ran_many = whole.finish(one), chunked.finish(many, " (chunked)")
    assert chunked.rows == 3001 and not chunked.whole
    moved = one["columns"]["Q_moved_C"]
    # the meter's column is Q_SC - Q_SC(0), whole and in chunks alike
    np.testing.assert_array_equal(moved, one["columns"]["Q_sc_C"] - one["columns"]["Q_sc_C"][0])
    assert many["columns"] is None and one["columns"] is not None
    assert ran_one.details["chunks"] == 1
    assert ran_many.details["chunks"] == chunked.chunk_count == -(-chunked.rows // size)
    assert ran_many.reason == "charge meter (chunked)"
    for name in ("peak_to_peak", "peak"):
        assert many["extremes"][name] == one["extremes"][name]
    assert ran_many.data == ran_one.data
    w = whole.window
    assert ran_one.data["moved_peak_to_peak"]["Q_moved_C"] == np.ptp(moved[w:])
    assert many["max_gap"] == one["max_gap"] == float(np.max(result.dynamics.gap[w:]))


def test_the_loops_peaks_are_its_columns_and_the_impacts(result, monkeypatch):
    """Peak-to-peak over the steady window: the samples' extremes, widened by the
    instants just before and after every impact (where I_SC jumps), never narrower."""
    loop = _loop(result, monkeypatch, circuit_for(result.scene))
    reduced = loop.reduce()
    cols, w = reduced["columns"], loop.window
    for name, column in (("V_oc", "V_oc_V"), ("Q_sc", "Q_sc_C"), ("I_sc", "I_sc_A")):
        assert reduced["extremes"]["peak_to_peak"][name] >= np.ptp(cols[column][w:])
        assert reduced["extremes"]["peak"][name] >= np.max(np.abs(cols[column][w:]))
    # I_SC takes its extremes at the impacts: there the loop's exceed the samples'
    assert reduced["extremes"]["peak"]["I_sc"] > np.max(np.abs(cols["I_sc_A"][w:]))
    assert reduced["extremes"] == {"peak_to_peak": result.peaks, "peak": result.peak}


@pytest.mark.parametrize("circuit", [{"kind": "open"}, {"kind": "load", "load_ohm": 1e8},
                                     {"kind": "series-rc", "load_ohm": 1e8,
                                      "series_capacitance_pF": 100.0},
                                     {"kind": "rectifier"}])
def test_every_registered_kind_gives_its_columns_whole_and_in_chunks(tmp_path, circuit):
    scene = fx.scene_with(run=RUN, circuit=circuit)
    result = tf.run(scene, cache_dir=tmp_path, solve=fx.plate_model_solve)
    source = Source.of_scene(result.scene, result.curves, result.dynamics)
    one = Loop(result.scene, source).reduce()
    many = Loop(result.scene, source, 777)
    parts = {c: [] for c in many.columns}
    for _, _, cols in many.chunks():
        for c in parts:
            parts[c].append(cols[c])
    for c in many.columns:
        np.testing.assert_array_equal(np.concatenate(parts[c]), one["columns"][c], err_msg=c)
        np.testing.assert_array_equal(one["columns"][c], np.asarray(result.waveforms[c]),
                                      err_msg=c)
