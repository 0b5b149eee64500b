"""The surrogate a run uses (issue #41): :func:`tengfield.run_surrogate.surrogate_for_run`,
the one place that decides the charge a run, sweep, field solve, ensemble or uncertainty
study runs with, lives beside the run rather than in the breakdown package. The plate
model stands in for the field (no gap lines: no σ_max)."""
from __future__ import annotations

import numpy as np
import pytest

import plate_model as fx
from tengfield import air_breakdown
from tengfield.errors import TengfieldError
from tengfield.surrogate import obtain_table


def test_a_numeric_charge_runs_with_the_scenes_own_surrogate(tmp_path):
    from tengfield.run_surrogate import surrogate_for_run

    scene = fx.scene_with(device={"surface_charge_uC_per_m2": -30.0})
    resolved, table, outcome, limit = surrogate_for_run(scene, cache_dir=tmp_path,
                                                        solve=fx.plate_model_solve)
    assert resolved is scene and limit is None          # no gap lines: σ_max unknown
    assert outcome.status == "computed"
    cached, again = obtain_table(scene, cache_dir=tmp_path, solve=fx.plate_model_solve)
    assert again.status == "cached"
    np.testing.assert_array_equal(table.positions, cached.positions)
    np.testing.assert_array_equal(table.induced_fraction, cached.induced_fraction)
    assert table.scene is scene      # the σ its curves take: the scene's, not the table's


def test_breakdown_charge_without_gap_lines_is_refused_in_one_line(tmp_path):
    from tengfield.run_surrogate import surrogate_for_run

    scene = fx.scene_with(device={"surface_charge_uC_per_m2": "breakdown"})
    with pytest.raises(TengfieldError, match='surface_charge_uC_per_m2 = "breakdown"') as info:
        surrogate_for_run(scene, cache_dir=tmp_path, solve=fx.plate_model_solve)
    assert "\n" not in str(info.value)


def test_the_breakdown_package_no_longer_hands_out_the_runs_surrogate():
    assert not hasattr(air_breakdown, "obtain_run_table")
    assert "obtain_run_table" not in air_breakdown.__all__
