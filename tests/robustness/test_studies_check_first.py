"""Issue 54 items 12 and 15: every study checks its combination before its first solve,
with the check ``run`` makes (one function: ``air_breakdown.check_gap_lines``), and the
study messages say what is true (series-rc is linear in σ; a band draw takes no
parameters; the γ range holds the scene's γ; design.json has ``best_breakdown_band``)."""
from __future__ import annotations

import pytest

from tengfield.errors import SceneError
from tengfield.scene import parse_scene

BASE = ("[run]\nduration_s = 0.3\nsettle_periods = 2\nsample_rate_hz = 5000\n"
        "[field]\ndegree = 1\nmesh_size_mm = 1.5\ntolerance = 1e-2\n")
BAND = '"device.surface_charge_uC_per_m2" = { distribution = "breakdown-band" }'
STUDY = ('[uncertainty]\nsamples = 20\nmethod = "monte-carlo"\nseed = 3\n'
         "[uncertainty.vary]\n" + BAND + "\n")


def no_solve(*args, **kwargs):
    raise AssertionError("a field solve ran before the combination was checked")


def test_uncertainty_band_draws_with_3d_solves_are_refused_before_any_solve(tmp_path):
    from tengfield.uncertainty_study import run_study

    scene = parse_scene(BASE.replace("[field]\n", '[field]\nmethod = "3d"\n') + STUDY)
    with pytest.raises(SceneError) as err:
        run_study(scene, cache_dir=tmp_path, jobs=1, solve=no_solve)
    text = str(err.value)
    assert "\n" not in text and 'distribution = "breakdown-band"' in text
    assert "method = '3d'" in text and 'use [field] method = "axisymmetric"' in text
    assert not any(tmp_path.iterdir())


def test_design_at_the_breakdown_charge_with_3d_solves_is_refused_before_any_solve(tmp_path):
    from tengfield.design_study import design

    scene = parse_scene('[device]\nsurface_charge_uC_per_m2 = "breakdown"\n'
                        + BASE.replace("[field]\n", '[field]\nmethod = "3d"\n')
                        + "[design]\ncandidates = 4\n[design.vary]\nstroke_mm = [1.0, 3.0]\n")
    with pytest.raises(SceneError) as err:
        design(scene, cache_dir=tmp_path, jobs=1, solve=no_solve)
    text = str(err.value)
    assert "\n" not in text and '"breakdown"' in text and "method = '3d'" in text
    assert not any(tmp_path.iterdir())


def test_the_cli_design_refuses_in_one_line_and_writes_nothing(tmp_path, run_cli):
    (tmp_path / "s.toml").write_text('[device]\nsurface_charge_uC_per_m2 = "breakdown"\n'
                                     + BASE + "[design]\ncandidates = 4\n"
                                     "[design.vary]\nstroke_mm = [1.0, 3.0]\n")
    proc = run_cli("design", "s.toml", "--set", 'field.method="3d"', "-o", "out",
                   cwd=tmp_path, timeout=300)
    assert proc.returncode == 2, proc.stderr
    ours = [ln for ln in proc.stderr.splitlines() if ln.startswith("tengfield: error")]
    assert len(ours) == 1 and "method = '3d'" in ours[0], proc.stderr
    assert "Traceback" not in proc.stderr and not (tmp_path / "out").exists()


def test_the_honeycomb_has_no_gap_lines_and_says_so_before_any_solve(tmp_path):
    """"auto" resolves through the shape: the honeycomb's only method is 3D, so σ =
    "breakdown" and the breakdown check are refused, and its surrogate asks no lines."""
    from tengfield import air_breakdown

    honeycomb = parse_scene('[device]\nshape = "hexagonal"\n' + BASE)
    assert not honeycomb.has_gap_lines and parse_scene(BASE).has_gap_lines
    with pytest.raises(SceneError, match="shape = 'hexagonal' has 3D solves only"):
        air_breakdown.obtain_breakdown_table(honeycomb, cache_dir=tmp_path)
    breakdown = parse_scene('[device]\nshape = "hexagonal"\n'
                            'surface_charge_uC_per_m2 = "breakdown"\n' + BASE)
    assert any("has 3D solves only" in p for p in breakdown.field_problems)
    assert not any(tmp_path.iterdir())
