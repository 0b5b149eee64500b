"""``tengfield design`` over a spherical shell (issue #32): the varied cavity and ball
through the shape's rules (scene/shapes/), the one-line refusals, impossible
candidates skipped with their reason, and the CLI end to end (small mesh, figures on)."""
from __future__ import annotations

import csv
import json

import pytest
from shell_model import SHELL, shell_device_toml  # noqa: F401

from tengfield.design_study import candidate_scene, evaluate, followed_geometry, parse_design_section
from tengfield.design_study.spec import default_design_section
from tengfield.errors import SceneError
from tengfield.scene import Scene, default_scene

SHELL = {"shape": "spherical-shell", "cavity_diameter_mm": 20.0, "shell_thickness_mm": 2.0,
         "electrode_band_mm": 2.0, "ball_diameter_mm": 8.0, "wall_permittivity": 3.0,
         "surface_charge_uC_per_m2": -50.0}
BAND = {"frequency_hz": [20.0], "amplitude_mm": [3.0]}


def shell_design(device=None, **design):
    section = {"objective": "charge", "candidates": 4, "settle_periods": 3,
               "window_periods": 3, "samples_per_period": 100, "excitation": BAND,
               "vary": {"cavity_diameter_mm": [14.0, 22.0], "ball_diameter_mm": [6.0, 10.0]}}
    section.update(design)
    return Scene.from_dict({"device": {**SHELL, **(device or {})}, "design": section})


def test_a_varied_ball_takes_the_cavity_along_keeping_the_stroke():
    scene = shell_design(vary={"ball_diameter_mm": [6.0, 10.0]})
    spec = parse_design_section(scene)
    base = scene.to_dict()["device"]
    assert followed_geometry(base, {"ball_diameter_mm": 10.0}) == {"cavity_diameter_mm": 22.0}
    assert followed_geometry(base, {"ball_diameter_mm": 10.0, "cavity_diameter_mm": 15.0}) == {}
    cand = candidate_scene(scene, spec, {"ball_diameter_mm": 10.0})
    assert cand.device.cavity_diameter == pytest.approx(22e-3, rel=1e-12)
    assert cand.device.stroke == pytest.approx(scene.device.stroke, rel=1e-12)   # 12 mm kept
    assert cand.device.electrode_band == scene.device.electrode_band
    fixed = shell_design(vary={"ball_diameter_mm": [6.0, 10.0]}, geometry="fixed")
    cand = candidate_scene(fixed, parse_design_section(fixed), {"ball_diameter_mm": 10.0})
    assert cand.device.cavity_diameter == pytest.approx(20e-3) and \
        cand.device.stroke == pytest.approx(10e-3, rel=1e-12)
    # a base scene that writes the (derived) stroke: a varied cavity is not refused
    written = shell_design(device={"stroke_mm": 12.0})
    cand = candidate_scene(written, parse_design_section(written),
                           {"cavity_diameter_mm": 16.0, "ball_diameter_mm": 7.0})
    assert cand.device.stroke == pytest.approx(9e-3, rel=1e-12)
    # the band and the shell's thickness vary as any key (their own field hash)
    varied = shell_design(vary={"electrode_band_mm": [1.0, 4.0], "shell_thickness_mm": [1.0, 3.0]})
    spec = parse_design_section(varied)
    one = candidate_scene(varied, spec, {"electrode_band_mm": 3.0, "shell_thickness_mm": 1.0})
    two = candidate_scene(varied, spec, {"electrode_band_mm": 1.5, "shell_thickness_mm": 1.0})
    assert (one.device.electrode_band, one.device.shell_thickness) == (3e-3, 1e-3)
    assert one.device.cell_volume == pytest.approx(4 / 3 * __import__("math").pi * 11e-3**3)
    assert one.field_hash() != two.field_hash() != varied.field_hash()


@pytest.mark.parametrize("values, message", [
    ({"cavity_diameter_mm": 14.0, "ball_diameter_mm": 14.5},
     r"\[device\] ball_diameter_mm = 14.5 is out of range: allowed \(0, 14\) mm \(smaller than "
     r"cavity_diameter_mm: the ball must fit the cavity\)"),
    ({"cavity_diameter_mm": 14.0, "electrode_band_mm": 15.0},
     r"\[device\] electrode_band_mm = 15 is out of range: allowed \(0, 14\) mm \(narrower than "
     r"cavity_diameter_mm\)"),
])
def test_an_impossible_shell_is_a_skipped_candidate_with_its_one_line_reason(values, message):
    vary = {k: [1.0, 30.0] for k in values}
    scene = shell_design(vary=vary, geometry="fixed")
    row = evaluate(scene, parse_design_section(scene), values)
    assert row["status"] == "skipped"
    assert __import__("re").search(message, row["reason"]) and "\n" not in row["reason"]


@pytest.mark.parametrize("shape_device, vary, message", [
    (SHELL, {"stroke_mm": [5.0, 10.0]},
     r"\[design.vary\] stroke_mm does not apply to shape = 'spherical-shell': its stroke is "
     r"cavity_diameter_mm - ball_diameter_mm; vary cavity_diameter_mm"),
    (SHELL, {"gap_mm": [5.0, 10.0]}, r"\[design.vary\] gap_mm does not apply to shape"),
    (SHELL, {"tube_inner_radius_mm": [4.0, 6.0]},
     r"\[design.vary\] tube_inner_radius_mm does not apply to shape = 'spherical-shell' \(a key "
     r"of shape = 'tube'\); allowed for it: cavity_diameter_mm, shell_thickness_mm, "
     r"electrode_band_mm"),
    ({}, {"cavity_diameter_mm": [10.0, 20.0]},
     r"\[design.vary\] cavity_diameter_mm does not apply to shape = 'tube' \(a key of shape = "
     r"'spherical-shell'\)"),
])
def test_a_key_of_another_shape_in_design_vary_is_one_line(shape_device, vary, message):
    scene = Scene.from_dict({"device": dict(shape_device),
                             "design": {"vary": vary, "excitation": BAND}})
    with pytest.raises(SceneError, match=message) as info:
        parse_design_section(scene)
    assert "\n" not in str(info.value)


def test_the_default_study_of_a_shell_varies_its_cavity_and_ball():
    section, said = default_design_section(Scene.from_dict({"device": SHELL}))
    assert section["vary"] == {"cavity_diameter_mm": [16.0, 24.0],
                               "ball_diameter_mm": [5.6, 10.4]}
    assert "cavity_diameter_mm = [16.0, 24.0]" in said and "tube" not in said
    tube, said = default_design_section(default_scene())     # the tube's study unchanged
    assert tube["vary"] == {"stroke_mm": [1.5, 4.5], "ball_diameter_mm": [4.9, 9.1]}
    assert "(tube and electrodes follow the ball)" in said


SHELL_TOML = shell_device_toml() + """\
[excitation]
frequency_hz = 20
amplitude_mm = 3

[field]
mesh_size_mm = 2.5
tolerance = 0.05

[design]
objective = "charge"
candidates = 4
batch = 2
field = "scene"
settle_periods = 3
window_periods = 3
samples_per_period = 100

[design.vary]
cavity_diameter_mm = [14.0, 22.0]
ball_diameter_mm = [6.0, 10.0]
"""


@pytest.mark.slow    # 4 shell geometries (axisymmetric solves at 2.5 mm), then best.toml's run
@pytest.mark.field
def test_tengfield_design_on_a_shell_end_to_end(tmp_path, run_cli, cli_env):
    """``tengfield design`` over a shell's cavity and ball (figures on): design.csv names
    the varied keys, every candidate's stroke and volume are its own shell's, the answer
    states the stroke (cavity - ball), and ``tengfield run best.toml`` gives the design's
    Q_SC peak-to-peak (the same surrogate, the same band point); with σ = "breakdown"
    each shell is scored at its own limit."""
    import math

    path = tmp_path / "shell.toml"
    path.write_text(SHELL_TOML)
    env = cli_env(TENGFIELD_CACHE_DIR=tmp_path / "cache")
    out = tmp_path / "design"
    proc = run_cli("design", path, "-o", out, "--jobs", "1", env=env)
    assert proc.returncode == 0, proc.stderr
    assert (out / "design.png").stat().st_size > 10_000
    rows = list(csv.DictReader((out / "design.csv").open()))
    assert len(rows) == 4 and {r["status"] for r in rows} == {"ok"}
    for r in rows:
        cavity, ball = float(r["cavity_diameter_mm"]), float(r["ball_diameter_mm"])
        assert 0 < ball < cavity
        outer = 0.5e-3 * cavity + 2e-3
        assert float(r["device_volume_m3"]) == pytest.approx(4 / 3 * math.pi * outer**3,
                                                             rel=1e-12)
        assert 0 < float(r["charge_C"])
    assert len({r["field_hash"] for r in rows}) == 4        # four shells, four surrogates
    summary = json.loads((out / "design.json").read_text())
    best = summary["best"]
    assert best["stroke_mm"] == pytest.approx(best["cavity_diameter_mm"]
                                              - best["ball_diameter_mm"], rel=1e-12)
    assert "plate_spacing_mm" not in best
    assert "stroke = cavity - ball diameter" in proc.stdout
    run = tmp_path / "best"
    proc = run_cli("run", out / "best.toml", "-o", run, env=env)
    assert proc.returncode == 0, proc.stderr
    got = json.loads((run / "summary.json").read_text())
    assert got["stages"]["field"]["status"] == "cached"      # the design's own surrogate
    assert got["peak_to_peak"]["Q_sc_C"] == pytest.approx(best["objective"], rel=1e-6)

    # σ = "breakdown": each shell at its own air-breakdown limit (its gap lines); the
    # same candidates (same seed), the charge scales with σ exactly
    path.write_text(SHELL_TOML.replace("-50", '"breakdown"'))
    proc = run_cli("design", path, "-o", tmp_path / "bd", "--jobs", "1", "--no-plots", env=env)
    assert proc.returncode == 0, proc.stderr
    limited = list(csv.DictReader((tmp_path / "bd" / "design.csv").open()))
    sigmas = set()
    for r, at50 in zip(limited, rows):
        assert r["cavity_diameter_mm"] == at50["cavity_diameter_mm"]
        sigma = float(r["surface_charge_uC_per_m2"])
        sigmas.add(round(sigma, 6))
        assert -1e3 < sigma < 0
        assert float(r["charge_C"]) == pytest.approx(float(at50["charge_C"]) * sigma / -50.0,
                                                     rel=1e-12)
    assert len(sigmas) == 4                                # each geometry its own limit
