"""Issue #21 item 1: ``tengfield run`` of a 3D scene with a lateral drive, figures on.

The figure of the surrogate used to call ``voltage(z)`` of the (z, r) curves without
r and crash the figure process. The surrogates are pre-cached from the analytic
(z, r) stand-in of ``tests/zr_model.py`` (the CLI finds them by the scene's
hash and imports no dolfinx), so the test costs a dynamics run, not 3D field solves.
"""
from __future__ import annotations

import json

import numpy as np
import pytest

from helpers import assert_png
from zr_model import LATERAL, seed_cache
from tengfield.scene import load_scene
from tengfield.surrogate import AnchoredTerminalCurves, TerminalCurves

@pytest.mark.slow
def test_surrogate_figure_of_zr_curves_shows_the_visited_offsets(tmp_path):
    from tengfield.plotting.waveforms import plot_surrogate, surrogate_lines

    path = tmp_path / "lateral.toml"
    path.write_text(LATERAL)
    scene = load_scene(path)
    table, zr_table = seed_cache(scene, tmp_path / "cache")
    axis = TerminalCurves(table, "floating", scene.device.ball_charge)
    curves = AnchoredTerminalCurves(zr_table.curves("floating", scene.device.ball_charge), axis)
    r_seen = 0.4 * curves.max_offset
    gap = np.linspace(0.0, curves.stroke, 50)
    visited = (gap, np.linspace(0.0, r_seen, 50))

    lines = surrogate_lines(curves, cells=2, visited=visited)
    offsets = [r for r, _ in lines]
    assert offsets[0] == 0.0 and offsets[-1] == pytest.approx(r_seen)
    z = np.linspace(0.0, curves.stroke, 400)
    on_axis = lines[0][1]
    # on the axis the figure shows the 1-D surrogate, scaled to the cells
    np.testing.assert_allclose(on_axis["Q_SC"], 2 * axis.charge(z), rtol=1e-12, atol=1e-24)
    np.testing.assert_allclose(on_axis["C_T"], 2 * axis.capacitance(z), rtol=1e-12)
    # at the largest offset visited, the (z, r) curves there (V_OC does not scale)
    far = lines[-1][1]
    np.testing.assert_allclose(far["V_OC"], curves.voltage(z, r_seen), rtol=1e-12, atol=1e-15)
    assert np.max(np.abs(far["Q_SC"] - on_axis["Q_SC"])) > 0.0   # r does change Q_SC

    plot_surrogate(table, curves, tmp_path / "zr.png", cells=2, visited=visited)
    plot_surrogate(table, curves, tmp_path / "zr-all.png")          # no trajectory: r_max
    plot_surrogate(table, axis, tmp_path / "axis.png")              # the 1-D surrogate
    for name in ("zr.png", "zr-all.png", "axis.png"):
        assert_png(tmp_path / name)


@pytest.mark.slow
def test_cli_run_3d_lateral_with_figures(tmp_path, run_cli, cli_env):
    path = tmp_path / "lateral.toml"
    path.write_text(LATERAL)
    cache = tmp_path / "cache"
    seed_cache(load_scene(path), cache)
    proc = run_cli("run", "lateral.toml", "-o", "out", cwd=tmp_path,
                   env=cli_env(TENGFIELD_CACHE_DIR=cache))
    assert proc.returncode == 0, proc.stderr
    assert "Traceback" not in proc.stderr
    out = tmp_path / "out"
    for name in ("waveforms.png", "surrogate.png", "trajectory.png", "trajectory3d.png"):
        assert_png(out / name)
    for name in ("waveforms.csv", "trajectory.csv", "contacts.csv", "impacts.csv"):
        assert (out / name).stat().st_size > 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["stages"]["field_zr"]["status"] == "cached"
    assert summary["stages"]["field"]["status"] == "cached"
