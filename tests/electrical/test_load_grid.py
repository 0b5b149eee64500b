"""The load scan's kept grid (``electrical.LoadGrid``, issue #40's design speed): a scan
over loads that builds the load-independent part of the integration grid once gives the
numbers of building it per load, bit for bit, for loads whose relaxation points add to
the grid and loads that add none, on the axis and off it (the (z, r) surrogate). The
field is the analytic plate model (no dolfinx)."""
from __future__ import annotations

import numpy as np
import pytest

import plate_model as fx
import zr_model as zx
from tengfield import electrical, pipeline
from tengfield.dynamics import simulate
from tengfield.scene import load_scene

SHORT_RUN = {"duration_s": 0.4, "settle_periods": 2, "sample_rate_hz": 4000.0}
#: 10 kohm .. 100 Gohm: tau from ~1e-8 s (relaxation points after every impact) to
#: ~1e-1 s (none: longer than 4 output steps), in a scan's order: far apart, then close
LOADS = np.logspace(4, 11, 8)[[7, 0, 6, 1, 5, 2, 4, 3]]


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("surrogates")


def _scan_both_ways(scene, dynamics, curves):
    grid = electrical.LoadGrid(scene, dynamics, curves)
    added = []
    for load in LOADS:
        loaded = scene.with_values(circuit={"kind": "load", "load_ohm": float(load)})
        alone = electrical.steady_load(loaded, dynamics, curves)
        kept = electrical.steady_load(loaded, dynamics, curves, grid=grid)
        assert set(alone) == set(kept)
        for key, value in alone.items():
            if isinstance(value, np.ndarray):
                assert np.array_equal(value, kept[key]), (load, key)
            else:
                assert value == kept[key], (load, key, value, kept[key])
        added.append(alone["integration_points"])
    return added


def test_a_kept_grid_gives_each_loads_numbers_bit_for_bit(cache):
    scene = fx.scene_with(run=SHORT_RUN, circuit={"parallel_capacitance_pF": 10.0})
    result = pipeline.run(scene, cache_dir=cache, solve=fx.plate_model_solve)
    dynamics = simulate(result.scene)
    points = _scan_both_ways(result.scene, dynamics, result.curves)
    # both kinds of load met: some add relaxation points to the grid, the largest none
    assert points[1] > points[0] and points[0] == points[2]


def test_a_kept_grid_of_an_off_axis_run_gives_the_same_numbers(cache, tmp_path):
    path = tmp_path / "lateral.toml"
    path.write_text(zx.LATERAL)
    scene = load_scene(path).with_values(run=SHORT_RUN)
    _, zr_table = zx.seed_cache(scene, cache)
    curves = zr_table.curves(scene.circuit.reference, scene.device.ball_charge)
    assert curves.radial
    dynamics = simulate(scene)
    assert np.ptp(np.asarray(dynamics.gap)) > 0
    _scan_both_ways(scene, dynamics, curves)


def _grid_built_whole(scene, dynamics, curves, time_constant):
    """The integration grid as it was built before the kept grid: every point sorted
    first, the terminal waveforms evaluated on the sorted arrays."""
    from tengfield.electrical.waveforms import (_impact_states, elapsed_times, impact_elapsed,
                                                sample_elapsed)
    from tengfield.source import Source

    t = elapsed_times(dynamics)
    impacts = impact_elapsed(dynamics, t[0], t[-1])
    step = float(np.median(np.diff(t)))
    extra = electrical.relaxation_times(np.concatenate([[t[0]], impacts]), time_constant,
                                        step, t[-1])
    gap_pre, vel_pre, gap_post, vel_post = _impact_states(scene, dynamics, impacts)
    gap_extra, vel_extra, _ = sample_elapsed(dynamics, extra)
    grid = np.concatenate([t, impacts, impacts, extra])
    gap = np.concatenate([dynamics.gap, gap_pre, gap_post, gap_extra])
    vel = np.concatenate([dynamics.gap_velocity, vel_pre, vel_post, vel_extra])
    tag = np.concatenate([np.ones(t.size), np.zeros(impacts.size), np.full(impacts.size, 2.0),
                          np.full(extra.size, 3.0)])
    order = np.lexsort((tag, grid))
    grid, gap, vel = grid[order], gap[order], vel[order]
    fine = Source.of_scene(scene, curves, dynamics).terminal(grid, gap, vel)
    return grid, fine, np.flatnonzero(order < t.size)


def test_the_kept_grid_is_the_grid_built_whole(cache):
    """The kept part's waveforms are evaluated before the sort: pointwise in time, so
    the same doubles as on the sorted grid."""
    scene = fx.scene_with(run=SHORT_RUN)
    result = pipeline.run(scene, cache_dir=cache, solve=fx.plate_model_solve)
    dynamics = simulate(result.scene)
    kept = electrical.LoadGrid(result.scene, dynamics, result.curves)
    for tau in (1e-7, 3e-5, 1.0):
        grid, fine, index = kept.fine(tau)
        want_grid, want_fine, want_index = _grid_built_whole(result.scene, dynamics,
                                                             result.curves, tau)
        assert np.array_equal(grid, want_grid) and np.array_equal(index, want_index)
        assert set(fine) == set(want_fine)
        for key in fine:
            assert np.array_equal(fine[key], want_fine[key], equal_nan=True), (tau, key)
