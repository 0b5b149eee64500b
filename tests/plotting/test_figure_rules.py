"""The rules every figure keeps (issue #53, Figures), applied where every figure is drawn
(``plotting.new_figure``): a quantity constant to rounding is drawn flat with plain tick
labels, no legend covers data, titles fit their figure; and the figures that broke them:
the sweep's panels (every setting drawn), the run titles (R and C_p), the trajectory's."""
from types import SimpleNamespace

import numpy as np
import pytest

from helpers import assert_labelled, assert_legends_clear, assert_no_offsets
from tengfield.plotting import new_figure
from tengfield.plotting.sweep_vary import vary_figure
from tengfield.plotting.waveforms import run_title


class _Sweep(list):
    """A sweep result as vary_figure reads it: rows, and the varied keys."""
    def __init__(self, rows, vary):
        super().__init__(rows)
        self.vary = vary


def _rows(settings=10, values=(1e6, 1e7, 1e8), wiggle=0.0):
    rng = np.random.default_rng(1)
    rows = []
    for f in (np.linspace(18.0, 22.0, settings) if settings > 1 else [20.0]):
        for r in values:
            v = 1255.6572 * f / 20 + wiggle * rng.standard_normal()
            rows.append({"circuit.load_ohm": r, "frequency_hz": float(f), "amplitude_mm": 1.5,
                         "load_ohm": None, "V_oc_pp_V": v, "Q_sc_pp_C": 3.25e-10 * f / 20,
                         "I_sc_pp_A": 7.6e-8 * f / 20})
    return _Sweep(rows, ["circuit.load_ohm"])


def test_a_constant_to_rounding_is_drawn_flat_without_an_offset():
    """A 1e-9 V wiggle on 1255.66 V (one setting) was drawn as a trend labelled
    "1e−6+1.2556572e3"."""
    fig = vary_figure(_rows(settings=1, wiggle=1e-9), "circuit.load_ohm")
    assert_no_offsets(fig)
    ax = fig.axes[0]
    low, high = ax.get_ylim()
    assert low < 1255.6572 < high and high - low == pytest.approx(0.1 * 1255.6572, rel=1e-6)


def test_a_real_trend_keeps_its_limits():
    fig = new_figure((4, 3))
    ax = fig.subplots()
    ax.plot([0, 1, 2], [1.0, 2.0, 3.0])
    fig.canvas.draw()
    low, high = ax.get_ylim()
    assert low < 1.0 and 3.0 < high and high - low < 2.5


def test_the_sweep_draws_every_setting_once_in_one_legend():
    """10 frequencies: 10 lines per panel (it drew the first 8), one legend beside the
    panels, not one over each panel's data."""
    fig = vary_figure(_rows(settings=10), "circuit.load_ohm")
    for ax in fig.axes:
        assert len(ax.get_lines()) == 10
        assert ax.get_legend() is None
        assert ax.get_xscale() == "log"              # loads over decades
    (legend,) = fig.legends
    assert [t.get_text() for t in legend.get_texts()][:2] == ["f = 18 Hz", "f = 18.44 Hz"]
    assert "first" not in fig._suptitle.get_text()
    assert_labelled(fig)


def test_a_legend_over_data_moves_to_a_free_corner_or_beside_the_axes():
    for y in (lambda t: np.sin(t), lambda t: 0.5 + 0.5 * np.sign(np.sin(8 * t))):
        fig = new_figure((6, 3))
        ax = fig.subplots()
        t = np.linspace(0, 10, 400)
        ax.plot(t, y(t), label="a curve that fills the axes")
        ax.plot(t, 0.9 * y(t), label="and another")
        ax.set_xlabel("t [s]")
        ax.set_ylabel("y [V]")
        ax.legend(loc="upper right")
        assert_legends_clear(fig)


def test_a_title_wider_than_its_figure_is_wrapped():
    fig = new_figure((4, 3))
    ax = fig.subplots()
    ax.plot([0, 1], [0, 1])
    fig.suptitle(", ".join(["σ = −8 µC/m², Δh = 3 mm"] * 4))
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    assert "\n" in fig._suptitle.get_text()
    assert fig._suptitle.get_window_extent(renderer).width <= fig.bbox.width


def _run(kind="load", load=1e7, instrument_pf=338.0):
    scene = SimpleNamespace(
        excitation=SimpleNamespace(frequency=20.0, amplitude=1.5e-3),
        device=SimpleNamespace(surface_charge=-8e-6, stroke=3e-3, cells=1,
                              electrode_names=("lower", "upper")),
        circuit=SimpleNamespace(kind=kind, load=load, parallel_capacitance=0.0,
                                reference="floating"),
        instrument=SimpleNamespace(capacitance=instrument_pf * 1e-12))
    return SimpleNamespace(scene=scene, summary={"cells": 1})


def test_run_title_names_the_load_and_the_parallel_capacitance():
    title = run_title(_run())
    assert "R = 10 MΩ" in title and "C_p = 338 pF" in title
    bare = run_title(_run(kind="open", instrument_pf=0.0))
    assert "R =" not in bare and "C_p" not in bare


def test_motion_words_spell_the_restitution_and_the_stroke():
    from tengfield.plotting.dynamics import motion_words
    from tengfield.scene import default_scene

    words = motion_words(default_scene(), stroke=True)
    assert "restitution 0.1" in words and "Δh = " in words
    assert "e = " not in words and "dh" not in words


def test_a_histogram_of_a_constant_is_drawn_at_its_value_without_an_offset():
    """FOM_S constant to 1e-12 over an uncertainty study: "1e−12+1.047587481" before."""
    fig = new_figure((4, 3))
    ax = fig.subplots()
    ax.hist(1.047587481 + 1e-12 * np.random.default_rng(0).standard_normal(64), bins=8)
    ax.set_xlabel("FOM_S")
    ax.set_ylabel("evaluations")
    assert_no_offsets(fig)
    low, high = ax.get_xlim()
    assert low < 1.047587481 < high and high - low > 0.05


def test_figure_units_have_superscripts_the_terminal_keeps_carets():
    """design.png's axis read "µW/cm^3" (the terminal's spelling)."""
    from tengfield.design_study.answer import readable_unit
    from tengfield.quantities import axis_label, figure_unit

    label, _ = readable_unit("W/m^3", 1.0)
    assert label == "µW/cm^3" and figure_unit(label) == "µW/cm³"
    assert axis_label("power_density_W_per_m3") == "P/V [W/m³]"
    assert figure_unit("1/cm^3/s") == "1/cm³/s" and figure_unit("m^-1") == "m⁻¹"
