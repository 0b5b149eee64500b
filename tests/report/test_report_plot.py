"""The report's names and figures (issues #28, #29): report.md's error table and the
stage figures name their quantities from the one table of output quantities
(``tengfield.quantities``), and ``Report.stage_figures()`` returns the figures ``tengfield
report`` saves (one matplotlib Figure per stage), drawn from the rows alone."""
from __future__ import annotations

import math

import pytest
from matplotlib.figure import Figure

from tengfield.quantities import describe, quantity
from tengfield.accuracy_report import Report, Row, make_plan, markdown, write_report
from tengfield.accuracy_report.plan import ERROR_KEYS, QUANTITIES
from tengfield.scene import default_scene


def _report(stages=("field", "surrogate", "dynamics", "circuit")) -> Report:
    rows = []
    for stage in stages:
        for i, wall in enumerate((0.1, 0.4, 1.6)):
            err = 10.0 ** (-1 - i)
            if stage == "circuit":
                rows.append(Row(stage, f"R=1e+08 ohm, {i}", {"load_ohm": 1e8, "sample_rate_hz":
                                2500.0 * 2 ** i, "time_constant_s": 1e-3}, wall,
                                {"P_load": err, "V_load": err / 2}, "finer step"))
            else:
                knobs = {"method": "axisymmetric", "degree": 2, "far_field": "kelvin"} \
                    if stage == "field" else {"model": "impact"}
                rows.append(Row(stage, f"{stage} {i}", knobs, wall,
                                {"V_oc": err, "Q_sc": err / 3, "I_sc": err * 2}, "ref",
                                error_position=err if stage == "field" else math.nan))
    return Report(default_scene(), make_plan(fast=True), rows, [], {"field": "p2"},
                  {"regime": "period-1"}, 3.0, True)


def test_the_error_table_names_its_quantities_from_the_table():
    text = markdown(_report(), {})
    symbols = [quantity(ERROR_KEYS[q].rpartition(".")[2]).symbol for q in QUANTITIES]
    assert symbols == ["V_OC", "Q_SC", "I_SC"]
    assert "| error V_OC | error Q_SC | error I_SC | max" in text
    assert "| error P_mean | error V_load |" in text
    for key in ("peak_to_peak.V_oc_V", "peak_to_peak.Q_sc_C", "peak_to_peak.I_sc_A",
                "load.mean_power_W", "peak_to_peak.V_load_V"):
        assert describe(key, unit=False) in text
    assert "| 0.05 |" in text     # the circuit row's V_load error, its own column


@pytest.mark.slow
def test_report_plot_returns_one_figure_per_stage_and_the_cli_saves_them(tmp_path):
    report = _report(("field", "dynamics", "circuit"))
    figures = report.stage_figures()
    assert list(figures) == ["field", "dynamics", "circuit"]
    for stage, fig in figures.items():
        assert isinstance(fig, Figure)
        ax = fig.axes[0]
        assert ax.get_xlabel() == "wall time [s]" and ax.get_xscale() == "log"
        assert ax.get_title().lower().startswith(stage)
    assert figures["field"].axes[0].get_ylabel() == \
        "relative error (max of V_OC, Q_SC, I_SC peak-to-peak)"
    assert figures["circuit"].axes[0].get_ylabel() == "relative error (P_mean, V_load)"
    # the field row's largest error (I_SC: 2 x) is what is drawn
    line = figures["field"].axes[0].get_lines()[0]
    assert list(line.get_ydata()) == pytest.approx([0.2, 0.02, 0.002])
    written = write_report(report, tmp_path)
    pngs = sorted(p.name for p in written if p.suffix == ".png")
    assert pngs == ["circuit.png", "dynamics.png", "field.png"]
    figures["field"].savefig(tmp_path / "notebook.png", dpi=100)
    assert (tmp_path / "notebook.png").read_bytes() == (tmp_path / "field.png").read_bytes()
