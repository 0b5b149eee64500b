"""#29 notebook use: ``Study.plot()`` returns the figure ``tengfield uncertainty`` saves
as uncertainty.png (a study built from known outputs: no field, no dynamics)."""
from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from tengfield.scene import default_scene
from tengfield.uncertainty_study import uncertainty_spec
from tengfield.uncertainty_study.evaluation import Evaluations
from tengfield.uncertainty_study.output import write_outputs
from tengfield.uncertainty_study.sampling import study_values
from tengfield.uncertainty_study.study import Study, summarise

SIGMA = "device.surface_charge_uC_per_m2"
REST = "contact.restitution"
Q = "peak_to_peak.Q_sc_C"


def _study(method="sobol") -> Study:
    scene = default_scene().with_values(uncertainty={"samples": 32, "method": method, "seed": 1,
                                                     "vary": {
        SIGMA: {"distribution": "normal", "mean": -20.0, "std": 2.0},
        REST: {"distribution": "uniform", "low": 0.05, "high": 0.5}}})
    spec = uncertainty_spec(scene)
    values = study_values(spec)
    # Q_SC pp = 0.04 nC per uC/m^2 of |σ|, times (1 - e / 2): both inputs matter
    rows = [{Q: 0.04e-9 * abs(s) * (1.0 - e / 2.0)} for s, e in values]
    ev = Evaluations(rows, ["period-1"] * len(rows), {Q: 0.04e-9 * 8.0}, "period-1", 0, 1,
                     1, [])
    return Study(spec, values, ev, summarise(scene, spec, values, ev))


def test_study_plot_returns_the_figure_the_cli_saves(tmp_path):
    study = _study()
    fig = study.plot()
    assert isinstance(fig, Figure)
    hist, bars = fig.axes[:2]
    assert hist.get_xlabel() == "Q_SC peak-to-peak [nC]" and hist.get_ylabel() == "evaluations"
    assert bars.get_ylabel() == "share of variance"
    assert [t.get_text() for t in bars.get_xticklabels()] == ["σ [µC/m²]", "e (restitution)"]
    # the histogram holds every evaluation, in nC
    counts = sum(p.get_height() for p in hist.containers[0])
    assert counts == len(study.evaluations.rows)
    nominal = [ln for ln in hist.get_lines() if ln.get_label() == "nominal"][0]
    assert nominal.get_xdata()[0] == np.float64(0.04e-9 * 8.0 * 1e9)
    written = write_outputs(study, tmp_path)
    assert tmp_path / "uncertainty.png" in written
    fig.savefig(tmp_path / "notebook.png", dpi=110)
    assert (tmp_path / "notebook.png").read_bytes() == \
        (tmp_path / "uncertainty.png").read_bytes()


def test_a_monte_carlo_study_plots_one_panel_per_output():
    fig = _study("monte-carlo").plot()
    assert isinstance(fig, Figure) and len(fig.axes) == 1
    assert fig.axes[0].get_xlabel() == "Q_SC peak-to-peak [nC]"
    assert "monte-carlo" in fig.texts[0].get_text()
