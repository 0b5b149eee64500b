"""A long `tengfield run` never builds a whole dynamics column (issue #28 last item,
#30.11): with the dynamics sampled on request and the electrical stage streamed (both
forced on a short run), ``SampledColumn.__array__`` (the one way to build a whole
column) raises, and the run, its summary, run.h5 or waveforms.csv, impacts.csv and
every figure still come out, for each circuit kind."""
from __future__ import annotations

import pytest

import tengfield as tf
from tengfield import io as tio
from tengfield.files import hdf5 as io_hdf5
from tengfield.dynamics import columns
from tengfield.electrical import stream

import plate_model as fx

KINDS = [{"kind": "open"}, {"kind": "short"},
         {"kind": "load", "load_ohm": 1e8, "parallel_capacitance_pF": 338.0},
         {"kind": "series-rc", "load_ohm": 1e8, "series_capacitance_pF": 100.0},
         {"kind": "rectifier"},
         {"kind": "rectifier", "pmic": "uvlo", "storage_capacitance_uF": 1e-4,
          "pmic_quiescent_current_A": 0.0, "uvlo_rising_V": 20.0, "uvlo_falling_V": 10.0,
          "pmic_output_V": 3.3, "pmic_load_ohm": 1e7, "pmic_shunt_V": 100.0}]


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("surrogates")


@pytest.mark.slow
@pytest.mark.parametrize("circuit", KINDS, ids=lambda c: c["kind"] + ("-uvlo" if "pmic" in c
                                                                       else ""))
def test_a_long_run_reads_its_dynamics_a_range_at_a_time(cache, tmp_path, monkeypatch,
                                                         circuit):
    """Each circuit kind twice, both runs with the trap set: run.h5 with every figure, and
    waveforms.csv + impacts.csv (the figures do not depend on the tables' format: drawn
    once per kind, from the same sampled run, is drawing them for either)."""
    monkeypatch.setattr(columns, "LAZY_ROWS", 100)
    monkeypatch.setattr(stream, "STREAM_ROWS", 100)
    monkeypatch.setattr(stream, "CHUNK_ROWS", 2000)
    monkeypatch.setattr(io_hdf5, "CHUNK_ROWS", 1000)

    def whole(self, dtype=None, copy=None):
        raise AssertionError(f"the whole column {self.name!r} was built")

    monkeypatch.setattr(columns.SampledColumn, "__array__", whole)
    for output_format, plots in (("hdf5", True), ("csv", False)):
        scene = fx.scene_with(run={"duration_s": 0.6, "settle_periods": 2,
                                   "output_format": output_format}, circuit=circuit)
        r = tf.run(scene, cache_dir=cache, solve=fx.plate_model_solve)
        assert isinstance(r.dynamics.gap, columns.SampledColumn)
        assert isinstance(r.waveforms, stream.StreamedWaveforms)
        out = tmp_path / output_format
        written = tio.write_run_outputs(r, out, plots=plots)
        written += tio.write_dynamics_outputs(r, out, plots=plots)
        names = {p.name for p in written}
        assert "summary.json" in names
        if plots:
            assert {"waveforms.png", "record.png", "trajectory.png"} <= names
        assert ("run.h5" if output_format == "hdf5" else "waveforms.csv") in names
        assert output_format == "hdf5" or "impacts.csv" in names
        with pytest.raises(AssertionError, match="whole column"):
            r.dynamics.gap.max()                # what building one does here


@pytest.mark.slow
def test_an_array_run_keeps_whole_arrays_and_the_same_waveforms(cache, monkeypatch):
    """`[array]` runs hold whole arrays (tengfield.array): the nominal cell's sampled
    columns are built first (dynamics.columns.with_arrays), the waveforms unchanged."""
    import numpy as np

    scene = fx.scene_with(run={"duration_s": 0.4, "settle_periods": 2},
                          circuit={"kind": "load", "load_ohm": 3e9},
                          array={"cells": 4, "initial_phase_spread_deg": 90.0, "seed": 3})
    plain = tf.run(scene, cache_dir=cache, solve=fx.plate_model_solve)
    monkeypatch.setattr(columns, "LAZY_ROWS", 100)
    sampled = tf.run(scene, cache_dir=cache, solve=fx.plate_model_solve)
    assert type(sampled.dynamics.gap) is np.ndarray
    assert list(sampled.waveforms) == list(plain.waveforms)
    for name, values in plain.waveforms.items():
        np.testing.assert_array_equal(sampled.waveforms[name], values, err_msg=name)
    assert sampled.summary["array"]["array_value"] == plain.summary["array"]["array_value"]
