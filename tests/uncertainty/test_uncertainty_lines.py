"""uncertainty's terminal lines (issue #42 item 6): each output named by its symbol and
statistic (never `peak_to_peak.I_sc_A ... µA`, an SI key beside a display unit), and a
nominal value outside every draw said and warned of."""
from __future__ import annotations

from types import SimpleNamespace

from tengfield.uncertainty_study.output import nominal_outside_warnings, summary_lines


def study(nominal, draws):
    p = sorted(draws)
    block = {"nominal": nominal, "percentiles": {"5": p[0], "50": p[len(p) // 2],
                                                 "95": p[-1]}, "sobol": None}
    summary = {"evaluations": len(draws), "method": "monte-carlo", "samples": len(draws),
               "seed": 1, "dynamics_runs": 0, "field_solves": 0,
               "outputs": {"peak_to_peak.I_sc_A": block}, "output_keys": ["peak_to_peak.I_sc_A"],
               "regimes": {"bounce": {"fraction": 0.5}, "not-settled": {"fraction": 0.5}}}
    rows = [{"peak_to_peak.I_sc_A": d} for d in draws]
    return SimpleNamespace(summary=summary, main=["peak_to_peak.I_sc_A"],
                           evaluations=SimpleNamespace(rows=rows))


def test_the_label_agrees_with_the_unit():
    lines = summary_lines(study(7.396e-8, [7.0e-8, 7.5e-8, 8.0e-8]))
    line = [ln for ln in lines if "nominal" in ln][0]
    assert "I_sc_A" not in line and "peak_to_peak." not in line
    # nA, as tengfield run prints I_SC (issue #53: the uncertainty said µA, the figure nA)
    assert line.strip().startswith("I_SC peak-to-peak [nA]: nominal 73.96, median")
    assert "not-settled 50%" in lines[-1]


def test_a_nominal_outside_every_draw_is_said():
    s = study(1.0e-7, [7.0e-8, 7.5e-8, 8.0e-8])
    line = [ln for ln in summary_lines(s) if "nominal" in ln][0]
    assert "outside every draw" in line
    said = nominal_outside_warnings(s)
    assert len(said) == 1 and "above every one of the 3 draws" in said[0]
    assert not nominal_outside_warnings(study(7.4e-8, [7.0e-8, 7.5e-8, 8.0e-8]))
