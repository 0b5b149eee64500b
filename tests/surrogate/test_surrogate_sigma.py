"""The ball's surface charge σ is neither in the surrogate's cache key (issue #28) nor in
its table (issue #51: per unit ball charge): a σ-only change (value, sign, "breakdown", 0)
is a cache hit, and every charge scales exactly."""
from __future__ import annotations

import json

import numpy as np
import pytest

from tengfield import surrogate
from tengfield.pipeline import run

import plate_model as fx


def _sigma(scene, uc):
    return scene.with_values(device={"surface_charge_uC_per_m2": uc})


def test_a_sigma_only_change_is_a_cache_hit_with_charges_scaled(tmp_path):
    scene = _sigma(fx.scene_with(), -8.0)
    solver = fx.CountingSolver()
    first, outcome = surrogate.obtain_table(scene, cache_dir=tmp_path, solve=solver)
    assert outcome.status == "computed" and solver.calls > 0
    calls = solver.calls
    q_first = first.induced_charges(scene.device.ball_charge)
    for uc, factor in ((-20.0, 2.5), (8.0, -1.0), (-8.0, 1.0)):
        at = _sigma(scene, uc)
        table, outcome = surrogate.obtain_table(at, cache_dir=tmp_path, solve=solver)
        assert outcome.status == "cached" and solver.calls == calls, uc
        np.testing.assert_array_equal(table.induced_fraction, first.induced_fraction)
        np.testing.assert_allclose(table.induced_charges(at.device.ball_charge),
                                   factor * q_first, rtol=1e-12, atol=0)
        np.testing.assert_array_equal(table.capacitance, first.capacitance)
        np.testing.assert_array_equal(table.field_error, first.field_error)
        assert table.interpolation_error == first.interpolation_error
    assert len(list(tmp_path.glob("surrogate-*.h5"))) == 1


def test_an_uncharged_ball_is_solved_at_the_stand_in_and_charges_nothing(tmp_path):
    uncharged = _sigma(fx.scene_with(), 0.0)
    solver = fx.CountingSolver()
    table, outcome = surrogate.obtain_table(uncharged, cache_dir=tmp_path, solve=solver)
    assert outcome.status == "computed"
    assert np.all(np.isfinite(table.induced_fraction)) and np.all(table.induced_fraction < 0)
    assert not np.any(table.induced_charges(uncharged.device.ball_charge))
    curves = surrogate.TerminalCurves(table, "floating", uncharged.device.ball_charge)
    assert not np.any(curves.charge_samples) and np.all(curves.capacitance_samples > 0)
    stored = surrogate.read_table(surrogate.cache_path(fx.scene_with(), tmp_path))
    np.testing.assert_array_equal(stored.induced_fraction, table.induced_fraction)
    calls = solver.calls
    charged, outcome = surrogate.obtain_table(_sigma(fx.scene_with(), -8.0), cache_dir=tmp_path,
                                              solve=solver)
    assert outcome.status == "cached" and solver.calls == calls
    np.testing.assert_array_equal(charged.induced_fraction, table.induced_fraction)


def test_a_run_at_another_sigma_scales_every_charge_output(tmp_path):
    scene = _sigma(fx.scene_with(), -8.0).with_values(run={"duration_s": 0.8})
    solver = fx.CountingSolver()
    simulate = (lambda s: fx.FakeDynamics(s, "bounce"))
    first = run(scene, cache_dir=tmp_path, solve=solver, simulate=simulate)
    calls = solver.calls
    second = run(_sigma(scene, -20.0), cache_dir=tmp_path, solve=solver, simulate=simulate)
    assert solver.calls == calls and second.stages["field"].status == "cached"
    for key in ("V_oc_V", "Q_sc_C", "I_sc_A"):
        assert second.summary["peak_to_peak"][key] == pytest.approx(
            2.5 * first.summary["peak_to_peak"][key], rel=1e-9), key
    flipped = run(_sigma(scene, 8.0), cache_dir=tmp_path, solve=solver, simulate=simulate)
    assert solver.calls == calls and flipped.stages["field"].status == "cached"
    np.testing.assert_allclose(flipped.waveforms["Q_sc_C"], -first.waveforms["Q_sc_C"],
                               rtol=1e-9, atol=1e-9 * np.ptp(first.waveforms["Q_sc_C"]))


@pytest.mark.slow
@pytest.mark.field
def test_cli_run_at_another_sigma_is_a_cache_hit(tmp_path, run_cli, cli_env):
    """The real field solver, figures on: -8 (solves), then -20 and +8 uC/m^2 (cached)."""
    env = cli_env(TENGFIELD_CACHE_DIR=tmp_path / "cache", MPLBACKEND="Agg")
    summaries = {}
    for uc in (-8.0, -20.0, 8.0):
        scene = tmp_path / f"s{uc:g}.toml"
        scene.write_text(f"[device]\nsurface_charge_uC_per_m2 = {uc}\n"
                         "[run]\nduration_s = 0.8\n")
        out = tmp_path / f"out{uc:g}"
        done = run_cli("run", scene, "-o", out, env=env)
        assert done.returncode == 0, done.stderr
        assert (out / "waveforms.png").exists()
        summaries[uc] = json.loads((out / "summary.json").read_text())
    assert summaries[-8.0]["stages"]["field"]["status"] == "ran"
    for uc, factor in ((-20.0, 2.5), (8.0, 1.0)):
        assert summaries[uc]["stages"]["field"]["status"] == "cached", uc
        assert summaries[uc]["field_hash"] == summaries[-8.0]["field_hash"]
        for key in ("V_oc_V", "Q_sc_C", "I_sc_A"):
            assert summaries[uc]["peak_to_peak"][key] == pytest.approx(
                factor * summaries[-8.0]["peak_to_peak"][key], rel=1e-9), (uc, key)


def test_a_surrogate_cached_by_an_older_tengfield_is_read_and_copied(tmp_path):
    """A cache written under the old key (sigma in it, FIELD_SCHEMA 1) is read (and
    scaled), never solved again; it is copied under today's key."""
    import dataclasses

    from tengfield.surrogate.provenance import legacy_field_hash

    scene = _sigma(fx.scene_with(), -8.0)
    solver = fx.CountingSolver()
    table, _ = surrogate.obtain_table(scene, cache_dir=tmp_path / "made", solve=solver)
    legacy = legacy_field_hash(scene)
    assert legacy != scene.field_hash()
    old = tmp_path / "cache" / f"surrogate-{legacy[:24]}.h5"
    old.parent.mkdir()
    surrogate.write_table(old, dataclasses.replace(table, field_hash=legacy))
    calls = solver.calls
    # the old key holds sigma: the scene at -8 finds it
    got, outcome = surrogate.obtain_table(scene, cache_dir=tmp_path / "cache", solve=solver)
    assert solver.calls == calls
    assert outcome.status == "cached" and "older tengfield" in outcome.reason
    np.testing.assert_array_equal(got.induced_fraction, table.induced_fraction)
    assert surrogate.cache_path(scene, tmp_path / "cache").is_file()
    # ... and its copy under today's key serves every sigma
    got, outcome = surrogate.obtain_table(_sigma(scene, -20.0), cache_dir=tmp_path / "cache",
                                          solve=solver)
    assert solver.calls == calls and outcome.status == "cached"
    assert "older" not in outcome.reason
    np.testing.assert_array_equal(got.induced_fraction, table.induced_fraction)


def test_the_default_scenes_legacy_key_is_the_old_field_hash():
    """FIELD_SCHEMA 1's hash of the default scene (tests/scene/test_scene_schema.py before #28)."""
    from tengfield.scene import default_scene
    from tengfield.surrogate.provenance import legacy_field_hash

    assert legacy_field_hash(default_scene()) == (
        "56dec865f925b863506de432f346f81a03924f24ee0d70bc7fb742ff937ee99c")
