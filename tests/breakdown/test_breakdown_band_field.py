"""The band (issue #38) from real field solves (coarse meshes): its edges ordered for
every shipped cell with gap lines (the tube, the spherical shell), and a run's
``breakdown_band`` equal to the runs at each edge's σ."""
import math

import pytest
from shell_model import SHELL

from tengfield import air_breakdown
from tengfield.pipeline import run
from tengfield.quantities import summary_value
from tengfield.scene import Scene, default_scene

pytestmark = [pytest.mark.slow, pytest.mark.field,
              # coarse meshes (field error above tolerance) and runs above the static limit
              pytest.mark.filterwarnings("ignore::RuntimeWarning")]

COARSE = {"degree": 1, "mesh_size_mm": 1.0, "tolerance": 0.03}
SHORT = {"duration_s": 0.4, "settle_periods": 4, "sample_rate_hz": 5000.0}


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("cache")


def tube(**sections):
    return default_scene().with_values(field=COARSE, run=SHORT, **sections)


def shell():
    return Scene.from_dict({"device": SHELL, "field": {"mesh_size_mm": 2.0, "tolerance": 0.01},
                            "excitation": {"frequency_hz": 20.0, "amplitude_mm": 3.0},
                            "run": SHORT})


@pytest.mark.parametrize("make", [tube, shell], ids=["tube", "spherical-shell"])
def test_edges_are_ordered_for_every_cell(make, cache):
    scene = make()
    table, _ = air_breakdown.obtain_breakdown_table(scene, cache_dir=cache)
    result = air_breakdown.scene_breakdown(scene, table)
    band = air_breakdown.scene_band(scene, result)
    assert 0.0 < band.lower <= band.static_at_gamma <= band.estimate <= band.upper < math.inf
    assert band.static_at_gamma == pytest.approx(result.sigma_max, rel=1e-12)
    # the upper edge binds where the smaller gap is widest along the trajectory
    assert band.upper_gap == pytest.approx(max(band.track.smaller_gap), rel=1e-12)
    assert band.upper_gap > band.lower_gap
    # more ions: the estimate cannot rise; none at all: it is clamped to the upper edge
    more = air_breakdown.scene_band(scene.with_values(breakdown={"ion_density_per_cm3": 5e4}),
                                result)
    assert band.lower <= more.estimate <= band.estimate
    none = air_breakdown.scene_band(scene.with_values(breakdown={
        "ion_density_per_cm3": 0.0, "seed_rate_per_cm3_s": 0.0}), result)
    assert none.estimate == none.upper


@pytest.mark.parametrize("circuit", [{"parallel_capacitance_pF": 338.0},
                                     {"kind": "load", "load_ohm": 1e8},
                                     {"kind": "series-rc", "load_ohm": 1e8,
                                      "series_capacitance_pF": 100.0}],
                         ids=["C_p", "load", "series-rc"])
def test_breakdown_band_equals_the_runs_at_each_edge(circuit, cache):
    scene = tube(circuit=circuit).with_values(device={"surface_charge_uC_per_m2": "breakdown"})
    summary = run(scene, cache_dir=cache).summary
    outputs = summary["breakdown_band"]
    assert "peak_to_peak.Q_sc_C" in outputs and "peak.I_sc_A" in outputs
    if circuit.get("kind") in ("load", "series-rc"):     # the load's power, ∝ sigma^2
        assert "load.mean_power_W" in outputs
    edges = summary["breakdown"]["band"]
    assert edges["lower_uC_per_m2"] <= edges["estimate_uC_per_m2"] <= edges["upper_uC_per_m2"]
    path = summary["breakdown"]["trajectory"]
    # at sigma = -sigma_max the trajectory just reaches breakdown (the dense grid's minimum)
    assert path["peak_gap_voltage_over_breakdown"] == pytest.approx(1.0, abs=0.02)
    for edge in ("lower", "estimate", "upper"):
        sigma = -edges[f"{edge}_uC_per_m2"]
        at = run(tube(circuit=circuit, device={"surface_charge_uC_per_m2": sigma}),
                 cache_dir=cache).summary
        for key, values in outputs.items():
            assert values[edge] == pytest.approx(summary_value(at, key), rel=1e-9), (edge, key)
