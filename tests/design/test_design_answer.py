"""tengfield design answers the question (issue 31), with the analytic plate model: the
best.toml that runs to the design's value (never at a resting band point), the warnings
(a band point where nothing moves, an optimum on a bound, a tie, chaos in the best),
error bars with the dynamics' spread, and the stated answer in design.json."""
from __future__ import annotations

import json
import math
import re
import warnings

import numpy as np
import pytest

import plate_model as fx
import tengfield as tf
from tengfield.design_study import design, evaluate, parse_design_section, write_design_outputs
from tengfield.design_study.answer import (answer_lines, chosen_band_point, design_warnings,
                                     readable_unit)

#: 25 Hz / 0.3 mm: Γ = Aω²/g = 0.75, below lift-off for every ball (first in the band)
RESTING_BAND = {"frequency_hz": [25.0, 33.0], "amplitude_mm": [0.3, 1.0]}


def design_scene(**design_keys):
    section = {"objective": "power", "candidates": 4, "seed": 1, "settle_periods": 10,
               "window_periods": 10, "samples_per_period": 120,
               "vary": {"stroke_mm": [1.0, 3.0]}, "excitation": RESTING_BAND}
    section.update(design_keys)
    return fx.scene_with(design=section)


@pytest.fixture
def cache(tmp_path):
    return tmp_path / "cache"


@pytest.mark.slow   # a small design search (plate model)
def test_best_toml_never_rests_and_runs_to_the_value_it_names(tmp_path, cache):
    """The band's first point (25 Hz / 0.3 mm) rests: best.toml was written there and
    `tengfield run` gave 0 W. Now it runs at the non-zero point nearest the band's centre,
    its header lists the band table, and the run gives that point's value within 1 %."""
    scene = design_scene(field="scene")
    result = design(scene, cache_dir=cache, solve=fx.plate_model_solve, jobs=1)
    best = result.best
    assert best["band_values"]["power"][0] == 0.0 and best["regimes"][0] == "rest"
    k = chosen_band_point(result, best)
    assert k != 0 and best["band_values"]["power"][k] > 0
    write_design_outputs(result, tmp_path, plots=False)
    text = (tmp_path / "best.toml").read_text()
    f, a = result.spec.band[k]
    assert f"{f:g} Hz / {a * 1e3:g} mm (the band point nearest the band's centre" in text
    for g, amp in result.spec.band:                       # the band table in the header
        assert f"{g:g} Hz" in text and f"{amp * 1e3:g} mm" in text
    assert "rest" in text
    again = tf.load_scene(tmp_path / "best.toml")
    assert again.excitation.frequency == f and again.excitation.amplitude == pytest.approx(a)
    run = tf.run(again, cache_dir=cache, solve=fx.plate_model_solve)
    assert run.summary["regime"]["regime"] != "rest"
    assert run.summary["load"]["mean_power_W"] == pytest.approx(
        best["band_values"]["power"][k], rel=0.01)
    summary = json.loads((tmp_path / "design.json").read_text())
    assert summary["best_toml_band_point"]["index"] == k


@pytest.mark.slow   # a small design search (plate model)
def test_a_band_point_where_nothing_moves_is_named(cache):
    result = design(design_scene(), cache_dir=cache, solve=fx.plate_model_solve, jobs=1)
    lines = design_warnings(result)
    moves = [w for w in lines if "no candidate moves" in w]
    assert len(moves) == 1 and moves[0].startswith("25 Hz / 0.3 mm: no candidate moves")
    assert "Γ = Aω²/g = 0.75 < 1" in moves[0]


def test_an_optimum_on_a_bound_is_named_with_the_key_and_the_bound(cache):
    """The stroke objective grows with stroke_mm: its best sits on the upper bound."""
    result = design(design_scene(objective="stroke", candidates=12, batch=4), cache_dir=cache,
                    jobs=1)
    assert result.best["values"]["stroke_mm"] == 3.0
    bound = [w for w in design_warnings(result) if "bound" in w]
    assert bound == ["the best stroke_mm = 3 is on the upper bound of its range [design.vary] "
                     "stroke_mm = [1, 3]: the optimum may lie beyond it; widen the range"]
    # an interior optimum is not named
    inner = design(design_scene(objective="stroke", vary={"stroke_mm": [1.0, 3.0]},
                                require="upper-contact",
                                excitation={"frequency_hz": [33.0], "amplitude_mm": [0.5]}),
                   cache_dir=cache, jobs=1)
    if inner.best is not None and 1.0 < inner.best["values"]["stroke_mm"] < 3.0:
        assert not [w for w in design_warnings(inner) if "bound" in w]


@pytest.mark.slow   # a small design search (plate model)
def test_a_worst_case_aggregate_that_ties_is_named_not_an_infinite_margin(tmp_path, cache):
    """aggregate = "min" over a band with a resting point: every candidate scores 0; it
    printed 'margin 0 W = inf x the error bars' and ranked them anyway."""
    result = design(design_scene(aggregate="min"), cache_dir=cache,
                    solve=fx.plate_model_solve, jobs=1)
    assert all(result.rows[i]["objective"] == 0 for i in result.ranking)
    conf = result.confidence()
    assert conf["tie"] and conf["margin_over_error_bars"] is None
    ties = [w for w in design_warnings(result) if "ties" in w]
    assert len(ties) == 1 and ties[0].startswith("aggregate = 'min' ties: all 4 candidates")
    assert "inf x" not in "\n".join(answer_lines(result))
    write_design_outputs(result, tmp_path)
    assert (tmp_path / "design.png").stat().st_size > 10_000


def _chaotic_scene(**keys):
    """20 Hz / 5 mm at gap 3.9-4.1 mm, restitution 0.5: chaotic (aperiodic over every
    run of the settling check; 33 Hz / 0.75 mm at restitution 0.1, chaotic in one
    window, settles: issue #42)."""
    section = {"objective": "charge", "vary": {"stroke_mm": [3.5, 4.5]},
               "excitation": {"frequency_hz": [20.0], "amplitude_mm": [5.0]}}
    return design_scene(**{**section, **keys}).with_values(contact={"restitution": 0.5})


def test_a_chaotic_band_point_carries_its_spread_over_windows_in_the_error_bar(cache):
    scene = _chaotic_scene()
    spec = parse_design_section(scene)
    row = evaluate(scene, spec, {"stroke_mm": 4.0}, cache_dir=cache, solve=fx.plate_model_solve)
    assert row["regimes"] == ["chaos"] and row["windows"] == [3]
    spread = row["band_spread"]["charge"][0]
    assert spread > 0
    # the spread is the standard deviation of the value over three consecutive windows
    from tengfield.design_study.candidate import band_scene, candidate_scene, window_values
    from tengfield.surrogate import TerminalCurves, precompute
    cand = candidate_scene(scene, spec, {"stroke_mm": 4.0})
    point = band_scene(cand, spec, 20.0, 5.0e-3)
    curves = TerminalCurves(precompute(cand, solve=fx.plate_model_solve),
                            cand.circuit.reference, cand.device.ball_charge)
    more = window_values("charge", spec, point, curves, 1.0, None, tf.simulate)
    assert spread == pytest.approx(np.std([row["objective"], *more], ddof=1), rel=1e-12)
    # it enters the ± beside the field and surrogate estimate
    field_part = row["objective"] * (row["field_error"] + row["interpolation_error"])
    assert row["objective_error"] == pytest.approx(field_part + spread, rel=1e-12)
    assert row["dynamics_error"]["charge"] == spread
    # a regular band point is scored on one window: no spread
    regular = evaluate(scene, spec, {"stroke_mm": 1.0}, cache_dir=cache,
                       solve=fx.plate_model_solve)
    assert regular["windows"] == [1] and regular["band_spread"]["charge"] == [0.0]


def test_chaos_in_the_best_design_is_a_warning(cache):
    result = design(_chaotic_scene(vary={"stroke_mm": [3.9, 4.1]}), cache_dir=cache,
                    solve=fx.plate_model_solve, jobs=1)
    assert result.best["regimes"] == ["chaos"]
    chaos = [w for w in design_warnings(result) if "chaotic" in w]
    assert len(chaos) == 1 and "20 Hz / 5 mm (±" in chaos[0]
    assert "its ± includes that spread" in chaos[0]


@pytest.mark.slow   # a small design search (plate model)
def test_the_answer_is_stated_in_design_json_and_on_the_terminal(tmp_path, cache):
    """Every varied key, the plate spacing h = stroke + d, the tube and electrode sizes
    that followed a bigger ball (named as changed), σ, the load, the band table; the same
    for the runner-up."""
    scene = design_scene(vary={"stroke_mm": [1.0, 3.0], "ball_diameter_mm": [6.0, 9.0]},
                         candidates=5)
    result = design(scene, cache_dir=cache, solve=fx.plate_model_solve, jobs=1)
    write_design_outputs(result, tmp_path, plots=False)
    summary = json.loads((tmp_path / "design.json").read_text())
    best = summary["best"]
    assert best["plate_spacing_mm"] == pytest.approx(best["stroke_mm"] + best["ball_diameter_mm"])
    assert [p["frequency_hz"] for p in best["band_points"]] == [25.0, 25.0, 33.0, 33.0]
    assert [p["amplitude_mm"] for p in best["band_points"]] == [0.3, 1.0, 0.3, 1.0]
    assert [p["regime"] for p in best["band_points"]] == result.best["regimes"]
    assert [p["value"] for p in best["band_points"]] == result.best["band_values"]["power"]
    assert best["surface_charge_uC_per_m2"] == pytest.approx(-8.0) and not best["breakdown"]
    assert best["load"]["rule"].startswith("matched, one resistor for the band")
    assert best["load"]["ohm"] == result.best["load_ohm"]
    if best["ball_diameter_mm"] != 7.0:   # the base scene's ball: d 7 mm, bore 4 mm
        assert best["changed"]["tube_inner_radius_mm"] == {
            "from": 4.0, "to": pytest.approx(best["ball_diameter_mm"] / 2 + 0.5)}
    second = summary["runner_up"]
    assert second is not None and {"plate_spacing_mm", "band_points", "load",
                                   "within_error_bars"} <= set(second)
    text = "\n".join(answer_lines(result))
    assert f"plate spacing h = stroke + ball diameter = {best['plate_spacing_mm']:g} mm" in text
    assert "σ = -8 µC/m^2 (the scene's)" in text and "load: matched" in text
    assert re.search(r"25 Hz +0\.3 mm +rest +0\n", text)
    assert "runner-up #" in text
    if best["changed"]:
        assert "changed to follow: tube_inner_radius_mm 4 ->" in text


def test_readable_units():
    assert readable_unit("W", 2.67e-6) == ("µW", 1e6)
    assert readable_unit("W", 0.0) == ("µW", 1e6)
    assert readable_unit("W/m^3", 2.15) == ("µW/cm^3", 1.0)
    assert readable_unit("W/m^3", 2150.0) == ("mW/cm^3", 1e-3)
    assert readable_unit("C", 4.6e-10) == ("pC", 1e12)
    assert readable_unit("m", 2e-3) == ("mm", 1e3)


@pytest.mark.slow   # a small design search (plate model)
def test_design_png_is_readable_with_error_bars_and_the_bound_optimum_marked(cache):
    """Readable units and axis labels, error bars, the bound optimum marked, no Pareto panel
    for one objective (it drew W with a 1e-6 offset, raw key names, no error bars)."""
    from tengfield.design_study.output import plot_scales
    from tengfield.design_study.spec import OBJECTIVES, objective_label
    from tengfield.plotting.design import plot_design

    result = design(design_scene(candidates=6, batch=2, vary={"stroke_mm": [1.0, 3.0]}),
                    cache_dir=cache, solve=fx.plate_model_solve, jobs=1)
    units = {k: v[0] for k, v in OBJECTIVES.items()}
    bound = [("stroke_mm", "upper", 3.0)]      # as if the best sat on it: drawn and named
    fig = plot_design(result, "/dev/null", units=units, scales=plot_scales(result),
                      names={k: objective_label(k) for k in OBJECTIVES}, on_bound=bound)
    axes = [a for a in fig.axes if a.get_label() != "<colorbar>"]
    assert len(axes) == 1 and "Pareto" not in axes[0].get_title()
    ax = axes[0]
    assert ax.get_xlabel() == "stroke Δh [mm]" and ax.get_ylabel() == "mean load power [µW]"   # the quantity table's words
    assert ax.containers, "error bars"
    labels = ax.get_legend_handles_labels()[1]
    assert "best on a bound" in labels and "feasible (± error bar)" in labels
    assert "best on the upper bound of stroke_mm (3): widen the range" in ax.get_title()
    assert re.search(r"best \d[\d.]* ± [\d.e-]+ µW", ax.get_title())
    assert not ax.yaxis.get_major_formatter().get_offset()


@pytest.mark.slow   # a small design search (plate model)
def test_progress_shows_done_total_and_the_current_best_on_a_terminal(monkeypatch, cache):
    import io
    import sys

    class Terminal(io.StringIO):
        def isatty(self):
            return True

    scene = design_scene(candidates=4)
    screen = Terminal()
    monkeypatch.setattr(sys, "stderr", screen)
    design(scene, cache_dir=cache, solve=fx.plate_model_solve, jobs=1, progress=True)
    shown = screen.getvalue()
    assert "4/4" in shown and re.search(r"best \d[\d.]* [nµm]?W", shown)
    piped = io.StringIO()                     # not a terminal: nothing
    monkeypatch.setattr(sys, "stderr", piped)
    design(scene, cache_dir=cache, solve=fx.plate_model_solve, jobs=1, progress=True)
    assert piped.getvalue() == ""
    quiet = Terminal()                        # --quiet: progress=False
    monkeypatch.setattr(sys, "stderr", quiet)
    design(scene, cache_dir=cache, solve=fx.plate_model_solve, jobs=1, progress=False)
    assert quiet.getvalue() == ""


def test_design_csv_has_the_spread_and_windows_per_band_point(tmp_path, cache):
    import csv

    result = design(_chaotic_scene(vary={"stroke_mm": [3.9, 4.1]}), cache_dir=cache,
                    solve=fx.plate_model_solve, jobs=1)
    write_design_outputs(result, tmp_path, plots=False)
    rows = list(csv.DictReader(open(tmp_path / "design.csv")))
    chaotic = 0
    for rec, row in zip(rows, result.rows):
        if row["regimes"] != ["chaos"]:      # a candidate whose motion settles
            assert rec["windows"] == "1" and float(rec["charge_spread_per_band_point"]) == 0
            continue
        chaotic += 1
        assert rec["windows"] == "3"
        assert float(rec["charge_spread_per_band_point"]) == row["band_spread"]["charge"][0] > 0
    assert chaotic >= 1


def test_best_toml_band_point_prefers_the_centre_then_regular_motion_then_the_value():
    from types import SimpleNamespace as NS

    spec = NS(objective="power", band=[(25.0, 0.3e-3), (25.0, 1e-3), (33.0, 0.3e-3),
                                      (33.0, 1e-3)])
    result = NS(spec=spec)
    row = {"band_values": {"power": [0.0, 9.0, 0.02, 25.0]},
           "regimes": ["rest", "bounce", "bounce", "chaos"]}
    assert chosen_band_point(result, row) == 1          # equally near: regular before chaos
    row["regimes"][3] = "regular-contact"
    assert chosen_band_point(result, row) == 3          # then the larger value
    spec.band = [(25.0, 0.3e-3), (29.0, 0.65e-3), (33.0, 1e-3)]
    row = {"band_values": {"power": [0.0, 1.0, 25.0]}, "regimes": ["rest", "bounce", "regular-contact"]}
    assert chosen_band_point(result, row) == 1          # the centre first
    row["band_values"]["power"][1] = 0.0
    assert chosen_band_point(result, row) == 2          # never a point that scored zero


@pytest.mark.slow   # a small design search (plate model)
def test_design_result_plot_returns_the_figure_design_png_is(cache, tmp_path):
    """DesignResult.plot() -> a matplotlib Figure (not saved) with the varied keys and the
    objective on its axes; design.png is the same figure saved (same pixel size)."""
    from matplotlib.figure import Figure
    from PIL import Image

    from tengfield.design_study.output import plot_scales
    from tengfield.design_study.spec import objective_label

    result = design(design_scene(objective="charge", candidates=6, batch=3,
                                 vary={"stroke_mm": [1.0, 3.0], "ball_diameter_mm": [6.0, 8.0]}),
                    cache_dir=cache, solve=fx.plate_model_solve, jobs=1)
    fig = result.plot()
    assert isinstance(fig, Figure)
    axes = [a for a in fig.axes if a.get_label() != "<colorbar>"]
    unit = plot_scales(result)["charge"][0]
    assert unit == "pC" or unit == "nC"
    objective = f"{objective_label('charge')} [{unit}]"
    assert [(a.get_xlabel(), a.get_ylabel()) for a in axes] == [
        ("stroke Δh [mm]", "ball diameter d [mm]"), ("stroke Δh [mm]", objective)]
    best = result.best["values"]
    star = [line for line in axes[0].get_lines() if line.get_label() == "best"][0]
    assert (star.get_xdata()[0], star.get_ydata()[0]) == (best["stroke_mm"],
                                                         best["ball_diameter_mm"])
    written = write_design_outputs(result, tmp_path / "out")
    fig.savefig(tmp_path / "plot.png", dpi=110)
    png = tmp_path / "out" / "design.png"
    assert png in written
    assert Image.open(png).size == Image.open(tmp_path / "plot.png").size
