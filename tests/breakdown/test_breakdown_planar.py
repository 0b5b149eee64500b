"""The breakdown arithmetic (tengfield.air_breakdown) on a planar contact-separation device,
whose limits are known in closed form (Zi et al., Adv. Funct. Mater. 27:1700049, 2017):
open circuit sigma_max = eps0 V_b(x_max) / x_max, short circuit
sigma_max = min_x eps0 V_b(x) (d0 + x) / (d0 x), d0 = thickness / eps_r."""
import math

import numpy as np
import pytest

from tengfield import air_breakdown
from tengfield.paschen import ATMOSPHERE, Paschen
from tengfield.scene import EPS0
from planar_lines import planar_lines


@pytest.mark.parametrize("x_max", [1e-3, 3e-3])
def test_open_circuit_limit_is_the_parallel_plate_one(x_max):
    paschen = Paschen()
    res = air_breakdown.evaluate(planar_lines(x_max, 1e-3), paschen, ("open",), "grounded-lower")
    expected = EPS0 * paschen.voltage(x_max) / x_max
    assert res.sigma_max == pytest.approx(expected, rel=1e-9)
    assert res.binding.position == pytest.approx(x_max)
    assert res.binding.state == "open" and res.binding.side == "lower"
    # DESIGN §8: 44.6 uC/m^2 at 1 mm, 37.2 at 3 mm
    assert res.sigma_max * 1e6 == pytest.approx({1e-3: 44.6, 3e-3: 37.2}[x_max], rel=0.01)


@pytest.mark.parametrize("d0, design", [(1e-3, 74.0), (0.1e-3, 146.0)])
def test_short_circuit_limit_is_the_parallel_plate_one(d0, design):
    paschen = Paschen()
    x_max = 3e-3
    res = air_breakdown.evaluate(planar_lines(x_max, d0), paschen, ("short",), "grounded-lower")
    x = np.geomspace(1e-7, x_max, 400001)
    closed_form = np.min(EPS0 * paschen.voltage(x) * (d0 + x) / (d0 * x))
    assert res.sigma_max == pytest.approx(closed_form, rel=1e-3)
    assert res.sigma_max * 1e6 == pytest.approx(design, rel=0.02)


def test_both_states_bind_at_the_smaller_and_rows_are_consistent():
    res = air_breakdown.evaluate(planar_lines(3e-3, 1e-3), Paschen(), air_breakdown.STATES[::2],
                             "grounded-lower", sigma=-10e-6)
    assert res.sigma_max == min(b.sigma for b in res.per_state.values())
    assert res.binding.state == "open"
    row = [r for r in res.rows if r["state"] == "open" and r["position_m"] == 3e-3][0]
    assert row["gap_voltage_at_scene_sigma_V"] == pytest.approx(-10e-6 * 3e-3 / EPS0, rel=1e-9)
    assert row["margin"] == pytest.approx(res.sigma_max / 10e-6, rel=1e-9)
    assert res.margin(-10e-6) == pytest.approx(10e-6 / res.sigma_max)


def test_lower_pressure_lowers_the_limit_at_mm_gaps():
    lines = planar_lines(3e-3, 1e-3)
    one = air_breakdown.evaluate(lines, Paschen(), ("open",), "grounded-lower").sigma_max
    half = air_breakdown.evaluate(lines, Paschen(pressure=0.5 * ATMOSPHERE), ("open",),
                              "grounded-lower").sigma_max
    assert half < 0.6 * one
    assert math.isfinite(half) and half > 0


@pytest.mark.slow
@pytest.mark.parametrize("pressure", [ATMOSPHERE, 50.0])
def test_figure_marks_only_landmarks_it_shows(tmp_path, pressure, monkeypatch):
    """breakdown.png at 1 atm and at 50 Pa (where Paschen's minimum lies at 22 mm and the
    streamer regime at metres): every landmark label is inside the plotted gap range."""
    import matplotlib.axes

    from tengfield.plotting.breakdown import plot_breakdown
    texts = []
    original = matplotlib.axes.Axes.text

    def spy(self, x, y, s, *args, **kwargs):
        texts.append((self, x, s))
        return original(self, x, y, s, *args, **kwargs)
    monkeypatch.setattr(matplotlib.axes.Axes, "text", spy)
    lines = planar_lines(3e-3, 1e-3)
    res = air_breakdown.evaluate(lines, Paschen(pressure=pressure, longest_path=12.8e-3),
                             ("open",), "grounded-lower")
    plot_breakdown(res, -10e-6, tmp_path / "b.png")
    assert (tmp_path / "b.png").stat().st_size > 10_000
    assert texts and all(ax.get_xlim()[0] < x < ax.get_xlim()[1] for ax, x, _ in texts)
    labels = {s.strip() for _, _, s in texts}
    assert ("minimum" in labels) == (pressure == ATMOSPHERE)
