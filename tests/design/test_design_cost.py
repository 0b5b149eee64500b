"""design says its work before it starts and refuses past its stated limit (issue #43.6,
design half): candidates x band points evaluations, one field solve per candidate when a
geometry key is varied (one otherwise, none for an uncharged ball), counted from the
[design] section alone; past [design] max_field_solves it is one line, before any solve."""
from __future__ import annotations

import io
import sys

import pytest

import plate_model as fx
from tengfield.design_study import design, parse_design_section
from tengfield.design_study.spec import design_cost
from tengfield.errors import SceneError


def design_scene(sigma=-8.0, **design_keys):
    section = {"objective": "power_density", "candidates": 8, "seed": 1,
               "settle_periods": 10, "window_periods": 10, "samples_per_period": 120,
               "vary": {"stroke_mm": [1.0, 5.0]},
               "excitation": {"frequency_hz": [20.0, 33.0], "amplitude_mm": [1.0, 2.0, 3.0]}}
    section.update(design_keys)
    return fx.scene_with(design=section, device={"surface_charge_uC_per_m2": sigma})


@pytest.mark.parametrize("vary, sigma, solves", [
    ({"stroke_mm": [1.0, 5.0]}, -8.0, 40),                     # a geometry key: one each
    ({"load_ohm": [1e6, 1e9]}, -8.0, 1),                       # the load only: one geometry
    ({"stroke_mm": [1.0, 5.0]}, 0.0, 0),                       # an uncharged ball: none
])
def test_the_count_follows_the_section(vary, sigma, solves):
    scene = design_scene(sigma=sigma, candidates=40, vary=vary)
    cost = design_cost(scene, parse_design_section(scene))
    assert cost.evaluations == cost.dynamics_runs == 40 * 6      # 2 frequencies x 3 amplitudes
    assert cost.field_solves == solves
    assert cost.cache_bytes == 80_000 * solves


def test_past_the_limit_is_one_line_before_any_solve(tmp_path):
    scene = design_scene(candidates=2000)
    solver = fx.CountingSolver()
    with pytest.raises(SceneError) as err:
        design(scene, cache_dir=tmp_path, solve=solver)
    text = str(err.value)
    assert text.startswith("[design] max_field_solves = 1000: the design needs up to 2,000 "
                           "field solves")
    assert "[design] candidates = 2000" in text and "\n" not in text
    assert solver.calls == 0
    # the limit is the user's to raise
    raised = design_scene(candidates=2000, max_field_solves=5000)
    assert parse_design_section(raised).max_field_solves == 5000


@pytest.mark.parametrize("value", [0, -1, 2.5, True, "many"])
def test_a_bad_limit_names_the_key(value):
    with pytest.raises(SceneError, match=r"^\[design\] max_field_solves = .* out of range: "
                                         r"allowed whole numbers \[1, 10000000\]"):
        parse_design_section(design_scene(max_field_solves=value))


class _Terminal(io.StringIO):
    def isatty(self):
        return True


def test_the_count_is_said_before_the_work_on_a_terminal(tmp_path, monkeypatch):
    """Said where the progress bar shows (a terminal, rank 0, not --quiet); a piped
    stderr stays silent."""
    scene = design_scene(candidates=4, excitation={"frequency_hz": [33.0],
                                                   "amplitude_mm": [1.0]})
    solver = fx.CountingSolver()
    piped = io.StringIO()
    monkeypatch.setattr(sys, "stderr", piped)
    design(scene, cache_dir=tmp_path, solve=solver, progress=True)
    assert "tengfield: design:" not in piped.getvalue()
    screen = _Terminal()
    monkeypatch.setattr(sys, "stderr", screen)
    design(scene, cache_dir=tmp_path, solve=solver, progress=True)
    err = screen.getvalue()
    said = [ln for ln in err.splitlines() if ln.startswith("tengfield: design:")]
    assert said == ["tengfield: design: 4 evaluations: at most 4 field solves (~320 kB of "
                    "surrogate cache), 4 dynamics runs, ~20 kB of memory"]
    assert solver.calls <= 4
