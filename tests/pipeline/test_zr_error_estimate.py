"""Issue #42: a run whose ball leaves the axis (a (z, r) table joined to the axis table)
reports the (z, r) table's error estimate, the one that governs off the axis, as
summary.json's ``surrogate_error_estimate``; the (z, r) table's settings come from
``[field] radial_mesh_size_mm``, ``radial_degree``, ``radial_tolerance`` (issue #40).
The surrogates are the analytic stand-ins of ``test_run_3d_figures.py`` (no field solve)."""
from __future__ import annotations

import numpy as np
import pytest

from zr_model import LATERAL, seed_cache
from tengfield import pipeline
from tengfield.scene import load_scene


@pytest.mark.slow
def test_the_zr_tables_estimate_governs_the_runs_surrogate_error(tmp_path):
    path = tmp_path / "lateral.toml"
    path.write_text(LATERAL)
    scene = load_scene(path)
    cache = tmp_path / "cache"
    table, zr_table = seed_cache(scene, cache)
    result = pipeline.run(scene, cache_dir=cache)
    summary = result.summary
    zr = summary["stages"]["field_zr"]
    assert zr["status"] == "cached"
    expected = max(table.interpolation_error, zr_table.interpolation_error,
                   float(np.nanmax(zr_table.field_error)))
    assert expected > table.interpolation_error   # the axis table's alone was reported
    assert summary["surrogate_error_estimate"] == expected
    assert summary["surrogate_error_estimate"] >= zr_table.interpolation_error
    assert "(z, r)" in summary["surrogate_error_rule"]


@pytest.mark.slow
def test_the_zr_table_settings_are_scene_keys(tmp_path):
    """Another (z, r) mesh size in the scene is another (z, r) cache file: the run then
    solves (here: refuses to, no solver given) instead of reading the seeded one."""
    path = tmp_path / "lateral.toml"
    path.write_text(LATERAL)
    scene = load_scene(path)
    cache = tmp_path / "cache"
    seed_cache(scene, cache)
    other = scene.with_values(field={"radial_mesh_size_mm": 3.0})
    calls = []

    def solve(scene, z, **kwargs):
        calls.append(kwargs.get("mesh_size_mm"))
        raise RuntimeError("stop")
    try:
        pipeline.run(other, cache_dir=cache, solve=solve)
    except RuntimeError:
        pass
    assert calls and calls[0] == 3.0
