"""fit.png (issue #42, Figures): paper-sized, symbols with units in the title, a labelled
residual axis, and targets drawn as measured ± uncertainty against fitted per target."""
from types import SimpleNamespace

import numpy as np

from tengfield.plotting.fit import fit_figure


def _common(mode):
    return dict(mode=mode, names=["surface_charge_uC_per_m2", "restitution"],
                values={"surface_charge_uC_per_m2": -35.78, "restitution": 0.62},
                standard_errors={"surface_charge_uC_per_m2": 0.41, "restitution": 0.013},
                identifiable={"surface_charge_uC_per_m2": True, "restitution": True})


def _trace():
    t = np.linspace(0.0, 0.1, 200)
    v = 50 * np.sin(2 * np.pi * 20 * t)
    return SimpleNamespace(**_common("trace"), measured={"time": t, "V": v},
                           fitted={"V": 0.98 * v},
                           residuals={"V": {"tool_key": "V_oc_V"}}, noise={})


def _targets():
    residuals = {
        "V_pp_V": {"unit": "V", "measured": 120.0, "fitted": 115.0, "uncertainty": 6.0},
        "Q_pp_nC": {"unit": "nC", "measured": 1.4, "fitted": 1.45, "uncertainty": 0.07}}
    return SimpleNamespace(**_common("targets"),
                           measured={k: r["measured"] for k, r in residuals.items()},
                           fitted={k: r["fitted"] for k, r in residuals.items()},
                           noise={k: {"relative": r["uncertainty"] / r["measured"]}
                                  for k, r in residuals.items()},
                           residuals=residuals)


def test_trace_fit_is_paper_sized_with_symbols_and_a_labelled_residual_axis():
    fig = fit_figure(_trace())
    width, height = fig.get_size_inches()
    assert width >= 7.0 and height >= 5.0
    title = fig.axes[0].get_title()
    assert "σ = −35.78 ± 0.41 µC/m²" in title and "restitution e = 0.620 ± 0.013" in title
    assert "surface_charge_uC_per_m2" not in title
    assert fig.axes[1].get_ylabel() == "residual [V]"


def test_targets_draw_measured_with_error_bars_against_fitted_per_target():
    fig = fit_figure(_targets())
    width, height = fig.get_size_inches()
    assert width >= 7.0 and height >= 5.0
    panels = [ax for ax in fig.axes if ax.get_ylabel()]
    assert [ax.get_ylabel() for ax in panels] == ["V_pp [V]", "Q_pp [nC]"]
    for ax, (measured, fitted, sigma) in zip(panels, [(120.0, 115.0, 6.0), (1.4, 1.45, 0.07)]):
        ticks = [t.get_text() for t in ax.get_xticklabels()]
        assert ticks == ["measured", "fitted"]
        bars = ax.containers[0]                   # the measured value's error bar
        (segments,) = bars.lines[2]
        (low, high) = segments.get_segments()[0][:, 1]
        assert np.isclose(low, measured - sigma) and np.isclose(high, measured + sigma)
        fitted_y = [ln.get_ydata()[0] for ln in ax.get_lines() if ln.get_label() == "fitted"]
        assert np.allclose(fitted_y, [fitted])
    assert "σ = −35.78 ± 0.41 µC/m²" in fig._suptitle.get_text()


def test_fitted_values_are_rounded_to_their_errors_a_zero_shown_as_0():
    """Issue #53: "t_0 = 2.51e−19 ± 2.6e-06 s" and "σ = −8 ± 0.002" (the fitted −7.9971,
    read as the start value) in fit.png's title."""
    from tengfield.plotting.fit import value_with_error

    assert value_with_error(2.51e-19, 2.62e-6, "s") == "0 ± 2.6 µs"
    assert value_with_error(-7.9971, 0.00202, "µC/m²") == "−7.9971 ± 0.0020 µC/m²"
    assert value_with_error(-8.0, 1.1e-6, "µC/m²") == "−8 ± 1.1×10⁻⁶ µC/m²"
    assert value_with_error(3e-3, 2e-4, "s") == "3.00 ± 0.20 ms"
    assert value_with_error(-35.8, 12.0) == "−36 ± 12"
    result = _trace()
    result.names = ["surface_charge_uC_per_m2", "time_shift_s"]
    result.values = {"surface_charge_uC_per_m2": -7.9971, "time_shift_s": 2.51206e-19}
    result.standard_errors = {"surface_charge_uC_per_m2": 0.00202, "time_shift_s": 2.62e-6}
    result.identifiable = {"surface_charge_uC_per_m2": True, "time_shift_s": True}
    title = fit_figure(result).axes[0].get_title()
    assert title == "σ = −7.9971 ± 0.0020 µC/m²; t_0 = 0 ± 2.6 µs"
    assert "e-0" not in title and "e−" not in title
