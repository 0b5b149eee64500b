"""``design`` with σ = "breakdown" reports the band of its objective for the best design
(issue #38): the objective at each band point scaled to the band's edges."""
import pytest

from tengfield.air_breakdown import obtain_breakdown_table, scene_breakdown
from tengfield.design_study import DesignResult, candidate_scene, evaluate, parse_design_section
from tengfield.design_study.answer import best_breakdown_band, breakdown_band_lines
from tengfield.scene import default_scene


@pytest.mark.slow
@pytest.mark.field
@pytest.mark.filterwarnings("ignore::RuntimeWarning")   # the coarse mesh's field error
def test_the_best_design_reports_its_objective_over_the_band(tmp_path):
    scene = default_scene().with_values(
        device={"surface_charge_uC_per_m2": "breakdown"},
        design={"objective": "charge", "candidates": 4, "seed": 1, "settle_periods": 4,
                "window_periods": 4, "vary": {"stroke_mm": [2.0, 4.0]},
                "excitation": {"frequency_hz": [20.0], "amplitude_mm": [1.5]}})
    spec = parse_design_section(scene)
    row = evaluate(scene, spec, {"stroke_mm": 3.0}, cache_dir=tmp_path)
    assert row["status"] == "ok", row["reason"]
    result = DesignResult(scene=scene, spec=spec, rows=[{"index": 0, "phase": "test", **row}],
                          ranking=[0])
    band = best_breakdown_band(result, cache_dir=tmp_path)
    cand = candidate_scene(scene, spec, {"stroke_mm": 3.0})
    table, _ = obtain_breakdown_table(cand, cache_dir=tmp_path)
    limit = scene_breakdown(cand, table)
    assert row["surface_charge_uC_per_m2"] == pytest.approx(-limit.sigma_max * 1e6, rel=1e-12)
    edges = band["sigma_edges_uC_per_m2"][0]
    assert edges["lower"] <= edges["estimate"] <= edges["upper"]
    for edge in ("lower", "estimate", "upper"):
        assert band[edge] == pytest.approx(
            row["objective"] * edges[edge] / (limit.sigma_max * 1e6), rel=1e-9)
    assert band["lower"] <= row["objective"] <= band["upper"]
    # design.json holds what the terminal prints (docs/design.md)
    result.cache_dir = tmp_path
    assert result.summary["best_breakdown_band"] == band
    line = breakdown_band_lines(result, band)[0]
    assert line.startswith("  charge over the breakdown band (lower / estimate / upper): ")
    # not asked for: another sigma
    plain = DesignResult(scene=default_scene().with_values(design=scene.raw["design"]),
                         spec=spec, rows=result.rows, ranking=[0])
    assert best_breakdown_band(plain, cache_dir=tmp_path) is None
    assert plain.summary["best_breakdown_band"] is None
