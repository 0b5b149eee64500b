"""design's band, budget and cost checks (issues #43 items 2, 5, 13, 20, 21; #40; #42):
near-duplicate band points refused, candidate de-duplication linear, a run too large
refused naming [design] keys before any work, no infinite margin on the terminal, a
candidate whose ball rests at every band point decided without a field solve, and a
[design] load_ohm range a bench can build (a matched load past it flagged)."""
from __future__ import annotations

import csv

import numpy as np
import pytest

import plate_model as fx
from tengfield.design_study import design, evaluate, parse_design_section, write_design_outputs
from tengfield.design_study.answer import answer_lines, design_warnings
from tengfield.design_study.search import _Space, fresh_candidates
from tengfield.errors import SceneError


def design_scene(**design_keys):
    section = {"objective": "power_density", "candidates": 8, "seed": 1,
               "settle_periods": 10, "window_periods": 10, "samples_per_period": 120,
               "vary": {"stroke_mm": [1.0, 5.0]},
               "excitation": {"frequency_hz": [33.0], "amplitude_mm": [1.0]}}
    section.update(design_keys)
    return fx.scene_with(design=section)


# ---------------------------------------------------------------------------
# item 2: a band point given twice
@pytest.mark.parametrize("band, expected", [
    ({"frequency_hz": [33.0], "amplitude_mm": [1.0, 1.0000001, 3.0]},
     "[design.excitation] amplitude_mm = [1.0, 1.0000001, 3.0]: 1 and 1.0000001 are one band "
     "point (within a relative 1e-05): give each value once"),
    ({"frequency_hz": [20.0, 30.0, 20.0], "amplitude_mm": [1.0]},
     "[design.excitation] frequency_hz = [20.0, 30.0, 20.0]: 20 and 20 are one band point"),
])
def test_near_duplicate_band_points_are_refused_in_one_line(band, expected):
    with pytest.raises(SceneError) as err:
        parse_design_section(design_scene(excitation=band))
    assert expected in str(err.value) and "\n" not in str(err.value)
    # values apart by more than the tolerance are two points
    spec = parse_design_section(design_scene(excitation={"frequency_hz": [33.0],
                                                         "amplitude_mm": [1.0, 1.001]}))
    assert len(spec.band) == 2


# ---------------------------------------------------------------------------
# item 5: de-duplication is a dict lookup, not a scan of the round so far
class _CountingSpace(_Space):
    def __init__(self, spec):
        super().__init__(spec)
        self.key_calls = 0

    def key(self, values):
        self.key_calls += 1
        return super().key(values)


def test_candidate_deduplication_calls_key_once_per_unit():
    """2000 units, each given twice, two of them seen in an earlier round: 1998 fresh
    candidates with one key call per unit (a scan of the fresh list costs ~n^2 / 2)."""
    spec = parse_design_section(design_scene(resolution=0.0))
    space = _CountingSpace(spec)
    units = np.random.default_rng(3).random((2000, 1))
    seen = {space.key(space.values(space.snap(units[0]))): 0,
            space.key(space.values(space.snap(units[1]))): 1}
    space.key_calls = 0
    fresh = fresh_candidates(space, np.vstack([units, units]), seen, room=10_000)
    assert len(fresh) == 1998
    assert len({space.key(v) for v in fresh}) == 1998
    assert space.key_calls <= 4000 + 1998


@pytest.mark.slow
def test_a_hundred_thousand_candidates_deduplicate_in_linear_work():
    spec = parse_design_section(design_scene(resolution=0.0, candidates=100_000,
                                             vary={"stroke_mm": [1.0, 5.0],
                                                   "ball_diameter_mm": [5.0, 9.0]}))
    space = _CountingSpace(spec)
    units = np.random.default_rng(5).random((100_000, 2))
    fresh = fresh_candidates(space, units, {}, room=spec.candidates)
    assert len(fresh) == len({space.key(v) for v in fresh}) > 99_000
    assert space.key_calls <= 3 * 100_000
    # the budget still caps a round
    assert len(fresh_candidates(space, units, {}, room=10)) == 10


# ---------------------------------------------------------------------------
# item 13: a band run past the scene's limits, named in [design] keys, before any work
def test_a_band_run_too_large_is_refused_naming_the_design_keys():
    scene = design_scene(window_periods=100_000, samples_per_period=100_000)
    with pytest.raises(SceneError) as err:
        parse_design_section(scene)
    text = str(err.value)
    assert text.startswith("[design] settle_periods = 10, window_periods = 100000, "
                           "samples_per_period = 100000: the run of band point 33 Hz / 1 mm")
    assert "allowed" in text and "\n" not in text


@pytest.mark.slow
def test_cli_design_too_large_exits_2_before_any_work(tmp_path, run_cli):
    (tmp_path / "big.toml").write_text(
        "[design]\nwindow_periods = 100000\nsamples_per_period = 100000\n"
        "[design.vary]\nstroke_mm = [1.0, 5.0]\n")
    proc = run_cli("design", "big.toml", "-o", "out", cwd=tmp_path, timeout=300)
    assert proc.returncode == 2, proc.stderr
    ours = [ln for ln in proc.stderr.splitlines() if ln.startswith("tengfield")]
    assert len(ours) == 1 and ours[0].startswith("tengfield: error: [design] settle_periods")
    assert not (tmp_path / "out").exists()


# ---------------------------------------------------------------------------
# #40 / item 21: a ball at rest at every band point is decided by the dynamics alone
def test_a_candidate_at_rest_in_the_whole_band_gets_no_field_solve(tmp_path):
    """Γ = Aω²/g = 0.44 < 1 at 33 Hz / 0.1 mm: the ball never lifts off, so Q_SC, V_OC
    and the load power are 0 whatever the field; design.csv says it was not solved."""
    scene = design_scene(objective=["power_density", "charge"],
                         excitation={"frequency_hz": [33.0], "amplitude_mm": [0.1]})
    spec = parse_design_section(scene)
    solver = fx.CountingSolver()
    row = evaluate(scene, spec, {"stroke_mm": 3.0}, cache_dir=tmp_path / "c", solve=solver)
    assert solver.calls == 0
    assert row["regimes"] == ["rest"] and row["status"] == "ok"
    assert row["objectives"]["power_density"] == {"value": 0.0, "error": 0.0}
    assert row["objectives"]["charge"] == {"value": 0.0, "error": 0.0}
    assert row["field_status"] == "not solved (at rest at every band point)"
    # a moving band point still solves the field
    moving = design_scene(excitation={"frequency_hz": [33.0], "amplitude_mm": [0.1, 1.0]})
    row = evaluate(moving, parse_design_section(moving), {"stroke_mm": 3.0},
                   cache_dir=tmp_path / "c", solve=solver)
    assert solver.calls > 0 and row["field_status"] == "computed"


@pytest.mark.slow
def test_design_csv_names_the_candidates_decided_at_rest(tmp_path):
    scene = design_scene(candidates=4, excitation={"frequency_hz": [33.0],
                                                   "amplitude_mm": [0.1]})
    solver = fx.CountingSolver()
    result = design(scene, cache_dir=tmp_path / "c", solve=solver, jobs=1)
    assert solver.calls == 0
    write_design_outputs(result, tmp_path / "out", plots=False)
    with open(tmp_path / "out" / "design.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 4
    assert {r["field_status"] for r in rows} == {"not solved (at rest at every band point)"}


# ---------------------------------------------------------------------------
# item 20: error bars of 0 are not an infinite margin
@pytest.mark.slow
def test_zero_error_bars_print_no_infinite_margin(tmp_path):
    """The stroke objective is exact (no field, no spread): its bars are 0."""
    result = design(design_scene(objective="stroke", candidates=4), cache_dir=tmp_path,
                    solve=fx.plate_model_solve, jobs=1)
    conf = result.confidence()
    assert conf["margin"] > 0 and conf["error"] == 0
    text = "\n".join(answer_lines(result))
    assert "inf" not in text
    assert "the error bars are 0" in text


# ---------------------------------------------------------------------------
# #42: a load a bench can build
def test_a_design_load_range_bounds_the_matched_load(tmp_path):
    free = design_scene()
    spec = parse_design_section(free)
    row = evaluate(free, spec, {"stroke_mm": 3.0}, cache_dir=tmp_path,
                   solve=fx.plate_model_solve)
    assert row["load_ohm"] > 1e9          # the matched load of a pF device: GΩ
    bench = design_scene(load_ohm=[1e6, 1e9])
    spec = parse_design_section(bench)
    assert spec.load_range == (1e6, 1e9)
    bounded = evaluate(bench, spec, {"stroke_mm": 3.0}, cache_dir=tmp_path,
                       solve=fx.plate_model_solve)
    assert 1e6 <= bounded["load_ohm"] <= 1e9
    assert bounded["load_ohm"] == pytest.approx(1e9, rel=0.05)   # the power rises to the edge
    assert 0 < bounded["objective"] < row["objective"]


@pytest.mark.parametrize("value, expected", [
    ([1e9, 1e6], "[design] load_ohm = [1000000000.0, 1000000.0]: expected [min, max] with "
                 "0 < min < max"),
    ([0.0, 1e6], "[design] load_ohm = [0.0, 1000000.0]: expected [min, max] with 0 < min"),
    (1e6, "[design] load_ohm = 1000000.0: expected [min, max]"),
])
def test_a_bad_load_range_is_one_line(value, expected):
    with pytest.raises(SceneError) as err:
        parse_design_section(design_scene(load_ohm=value))
    assert expected in str(err.value)


def test_a_load_range_beside_a_varied_load_is_refused():
    with pytest.raises(SceneError, match=r"\[design\] load_ohm and \[design.vary\] load_ohm"):
        parse_design_section(design_scene(load_ohm=[1e6, 1e9],
                                          vary={"stroke_mm": [1.0, 5.0],
                                                "load_ohm": [1e6, 1e9]}))


@pytest.mark.slow
def test_a_matched_load_past_a_gigaohm_is_flagged(tmp_path):
    result = design(design_scene(candidates=4), cache_dir=tmp_path,
                    solve=fx.plate_model_solve, jobs=1)
    assert result.best["load_ohm"] > 1e9
    flagged = [w for w in design_warnings(result) if "GΩ" in w]
    assert len(flagged) == 1 and "[design] load_ohm = [1e6, 1e9]" in flagged[0]
    bench = design(design_scene(candidates=4, load_ohm=[1e6, 1e9]), cache_dir=tmp_path,
                   solve=fx.plate_model_solve, jobs=1)
    assert not [w for w in design_warnings(bench) if "GΩ" in w]
