"""fit states what its statistics rest on (issue #42 item 5): a reduced chi^2 that is 1
by construction (noise estimated from the residuals) is said to be so, with the noise
levels; targets say their assumed 1-sigma uncertainty (5 % by default, or NAME=V+-S);
a time shift on a bound that is a whole number of periods away wraps: no alarm."""
from __future__ import annotations

from types import SimpleNamespace

import pytest

import plate_model as fx
from fit_synthetic import synthetic, trace_scene, write_csv

from tengfield import cli
from tengfield.fit import reference_surrogate
from tengfield.fit._residuals import bound_notes
from tengfield.scene import load_scene

SCENE = trace_scene("surface_charge_uC_per_m2 = {min = -100.0, max = 0.0}\n"
                    "time_shift_s = {}\n")


@pytest.fixture
def setup(tmp_path):
    path = tmp_path / "scene.toml"
    path.write_text(SCENE)
    scene = load_scene(path)
    cache = tmp_path / "cache"
    surrogate = reference_surrogate(scene, cache_dir=cache, solve=fx.plate_model_solve)[:2]
    return path, cache, scene, surrogate


def test_chi2_of_estimated_noise_is_said_to_be_1_by_construction(setup, tmp_path, capsys):
    path, cache, scene, surrogate = setup
    trace, _ = synthetic(scene, surrogate, 6, ("V", "Q"), white=0.005, hum=0.0)
    csv = write_csv(tmp_path / "measured.csv", trace)
    assert cli.main(["fit", str(path), "--measured", str(csv), "-o", str(tmp_path / "out"),
                     "--cache-dir", str(cache), "--no-plots"]) == 0
    out = capsys.readouterr().out
    line = [ln for ln in out.splitlines() if "chi^2" in ln][0]
    assert "1 by construction" in line and "estimated from the residuals" in line
    assert "V " in line and "Q " in line and " nC" in line   # the levels, in the data's units


def test_targets_state_their_assumed_uncertainty(setup, tmp_path, capsys):
    path, cache, scene, surrogate = setup
    assert cli.main(["fit", str(path), "--targets", "V_pp_V=300", "Q_pp_nC=0.5+-0.05",
                     "--free", "surface_charge_uC_per_m2", "-o", str(tmp_path / "out"),
                     "--cache-dir", str(cache), "--no-plots"]) == 0
    out = capsys.readouterr().out
    line = [ln for ln in out.splitlines() if "1-sigma uncertainty" in ln][0]
    assert "V_pp_V +- 15 V (5 %, the default: write NAME=VALUE+-SIGMA)" in line
    assert "Q_pp_nC +- 0.05 nC (given)" in line


def result_on(shift, lo, hi):
    return SimpleNamespace(bounds={"time_shift_s": (lo, hi)}, values={"time_shift_s": shift},
                           notes=[], mode="trace", residuals={})


def test_a_shift_on_a_bound_a_whole_number_of_periods_wide_wraps():
    period = 0.05
    result = result_on(0.1, 0.0, 0.1)            # the default bounds: [0, 2 periods]
    bound_notes(result, {"time_shift_s": 0.1}, period=period)
    assert not [n for n in result.notes if "sits on its bound" in n]
    assert any("wraps" in n and "periodic" in n for n in result.notes)


def test_a_shift_on_a_bound_narrower_than_a_period_is_noted():
    result = result_on(0.02, 0.0, 0.02)
    bound_notes(result, {"time_shift_s": 0.02}, period=0.05)
    assert [n for n in result.notes if "sits on its bound" in n]
