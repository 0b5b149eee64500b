"""uncertainty.png (issue #42, Figures): inputs and outputs labelled with symbols and
units, tick labels inside the figure."""
from __future__ import annotations

import numpy as np

from tengfield.scene import default_scene
from tengfield.uncertainty_study import uncertainty_spec
from tengfield.uncertainty_study.evaluation import Evaluations
from tengfield.uncertainty_study.sampling import study_values
from tengfield.uncertainty_study.study import Study, summarise

SIGMA = "device.surface_charge_uC_per_m2"
REST = "contact.restitution"
C_P = "circuit.load_ohm"
Q = "peak_to_peak.Q_sc_C"


def _study() -> Study:
    scene = default_scene().with_values(uncertainty={"samples": 16, "method": "sobol", "seed": 1,
                                                     "vary": {
        SIGMA: {"distribution": "normal", "mean": -20.0, "std": 2.0},
        REST: {"distribution": "uniform", "low": 0.05, "high": 0.5},
        C_P: {"distribution": "uniform", "low": 1e6, "high": 1e8}}})
    spec = uncertainty_spec(scene)
    values = study_values(spec)
    rows = [{Q: 0.04e-9 * abs(s) * (1.0 - e / 2.0) * (1 + c / 1e9)} for s, e, c in values]
    ev = Evaluations(rows, ["period-1"] * len(rows), {Q: 0.04e-9 * 8.0}, "period-1", 0, 1,
                     1, [])
    return Study(spec, values, ev, summarise(scene, spec, values, ev))


def test_inputs_and_outputs_are_labelled_with_symbols_and_units_and_fit_the_figure():
    fig = _study().plot()
    hist, bars = fig.axes[:2]
    assert hist.get_xlabel() == "Q_SC peak-to-peak [nC]"
    ticks = [t.get_text() for t in bars.get_xticklabels()]
    assert ticks == ["σ [µC/m²]", "e (restitution)", "R [Ω]"]
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    frame = fig.bbox
    for ax in fig.axes:       # every drawn tick label and axis label inside the figure
        box = ax.get_tightbbox(renderer)
        assert box.x0 >= frame.x0 - 0.5 and box.x1 <= frame.x1 + 0.5, ax.get_xlabel()
        assert box.y0 >= frame.y0 - 0.5 and box.y1 <= frame.y1 + 0.5, ax.get_xlabel()


I = "peak.I_sc_A"
E = "energy_per_cycle.max_energy_per_cycle_J"


def _units_study() -> Study:
    """A current in nA and an energy in µJ: outputs the figure once drew in µA and in J
    with a 1e−6 offset, while the terminal said nA (the run's) and µJ."""
    scene = default_scene().with_values(uncertainty={"samples": 16, "method": "sobol", "seed": 1,
                                                     "vary": {
        SIGMA: {"distribution": "normal", "mean": -20.0, "std": 2.0},
        REST: {"distribution": "uniform", "low": 0.05, "high": 0.5}}})
    spec = uncertainty_spec(scene)
    values = study_values(spec)
    rows = [{I: 7e-9 * abs(s) * (1 - e / 3), E: 1.2e-7 * s * s * (1 - e / 3)} for s, e in values]
    ev = Evaluations(rows, ["period-1"] * len(rows), {I: 7e-9 * 8, E: 1.2e-7 * 64},
                     "period-1", 0, 1, 1, [])
    return Study(spec, values, ev, summarise(scene, spec, values, ev))


def test_units_are_the_terminals_no_offsets_and_sobol_bars_within_0_and_1():
    from helpers import assert_labelled, assert_units_as_terminal
    from tengfield.uncertainty_study.output import summary_lines

    study = _units_study()
    fig = study.plot()
    labels = [ax.get_xlabel() for ax in fig.axes]
    assert "I_SC peak [nA]" in labels and "E_CMEO [µJ]" in labels
    lines = summary_lines(study)
    assert any(line.startswith("  I_SC peak [nA]: ") for line in lines), lines
    assert_units_as_terminal(fig, lines)
    assert_labelled(fig)             # no offset text ("1e−6"), legends off the data
    for ax in fig.axes:
        if ax.get_ylabel() != "share of variance":
            continue
        assert ax.get_ylim() == (0.0, 1.05)
        for coll in ax.collections:  # the error bars' segments
            for seg in coll.get_segments():
                assert np.all(seg[:, 1] >= -1e-12) and np.all(seg[:, 1] <= 1 + 1e-12)
