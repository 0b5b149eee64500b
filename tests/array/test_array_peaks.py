"""Issue #21 item 4: one peak rule for every path. An [array] reports the peak-to-peak
V_OC, Q_SC, I_SC over the output samples *and* just before and after every cell's
impacts (electrical.terminal_peaks), as the run without [array] does: I_SC jumps
at an impact and takes its extremes there.

Field: the analytic plate model; dynamics: the real impact map.
"""
from __future__ import annotations

import pytest

import tengfield as tf

import plate_model as fx

SHORT_RUN = {"duration_s": 0.5, "settle_periods": 2, "sample_rate_hz": 4000.0}


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("surrogates")


def run(cache, rate=4000.0, **sections):
    scene = fx.scene_with(run={**SHORT_RUN, "sample_rate_hz": rate}, circuit={"kind": "open"},
                          **sections)
    return tf.run(scene, cache_dir=cache, solve=fx.plate_model_solve)


@pytest.fixture(scope="module")
def single(cache):
    return run(cache)


@pytest.mark.parametrize("sections, cells", [
    ({"array": {"cells": 1}}, 1),
    ({"array": {"cells": 4}}, 4),
    # distinct dynamics (the spread path) whose motion is the nominal one to round-off
    ({"array": {"cells": 4, "restitution_spread": 1e-12}}, 4),
], ids=["one-cell", "identical", "spread-path"])
def test_array_peaks_are_the_single_cell_peaks_scaled_by_the_cells(cache, single, sections,
                                                                   cells):
    """N identical cells in parallel: Q_SC and I_SC add (N x), V_OC does not change."""
    arr = run(cache, **sections)
    expected = {"V_oc": single.peaks["V_oc"], "Q_sc": cells * single.peaks["Q_sc"],
                "I_sc": cells * single.peaks["I_sc"]}
    for name, value in expected.items():
        assert arr.peaks[name] == pytest.approx(value, rel=1e-9), name
        column = {"V_oc": "V_oc_V", "Q_sc": "Q_sc_C", "I_sc": "I_sc_A"}[name]
        assert arr.summary["peak_to_peak"][column] == pytest.approx(value, rel=1e-9)
    assert arr.summary["peak_to_peak_rule"] == single.summary["peak_to_peak_rule"]


def test_spread_array_current_peak_does_not_depend_on_the_sampling(cache):
    """With spread the extremes of the summed I_SC sit at the cells' impacts: the peak
    at 4 kHz equals the one at 20 kHz to 1e-3 (the smooth extremes between impacts are
    sampled; sampled alone the peak is several % low)."""
    spread = {"cells": 3, "restitution_spread": 0.05, "seed": 3}
    coarse = run(cache, 4000.0, array=spread)
    fine = run(cache, 20000.0, array=spread)
    assert coarse.summary["array"]["distinct_dynamics"] == 3
    assert coarse.peaks["I_sc"] == pytest.approx(fine.peaks["I_sc"], rel=1e-3)
