"""trajectory.png (issue #42, Figures): the spherical shell's figure speaks of the cavity
wall, not of plates; a regime without a period is named without "period 0"."""
from types import SimpleNamespace

import numpy as np

from tengfield.plotting.dynamics import trajectory_figure, trajectory_plot


class _Impacts:
    time = np.zeros(0)
    plate = np.zeros(0, dtype=object)

    def __len__(self):
        return 0


def _result(*, cavity_radius, name="bounce", period=0):
    t = np.linspace(0.0, 0.2, 500)

    def sample(times):
        times = np.asarray(times)
        y = 1e-3 * np.sin(2 * np.pi * 20 * times)
        z = 2e-3 * np.abs(np.sin(2 * np.pi * 10 * times))
        return z, np.zeros_like(times), y

    regime = SimpleNamespace(name=name, period=period, max_gap=2e-3,
                             lower_contacts_per_period=1.0, upper_contacts_per_period=0.0)
    return SimpleNamespace(t=t, period=0.05, time_origin=0.0, sample=sample, impacts=_Impacts(),
                           regime=regime, stroke=12e-3, window_start=0.05,
                           cavity_radius=cavity_radius)


def _legend(fig):
    return [t.get_text() for t in fig.axes[0].get_legend().get_texts()]


def test_the_shells_trajectory_speaks_of_the_cavity_wall():
    fig = trajectory_plot(trajectory_figure(_result(cavity_radius=10e-3)))
    labels = _legend(fig)
    assert not any("plate" in label for label in labels), labels
    assert any("cavity wall" in label for label in labels), labels
    tube = trajectory_plot(trajectory_figure(_result(cavity_radius=0.0)))
    assert any("lower plate" in label for label in _legend(tube))


def test_a_regime_with_period_zero_is_named_without_a_period():
    for period in (0, 0.0, np.int64(0), None):
        data = trajectory_figure(_result(cavity_radius=10e-3, name="bounce", period=period))
        assert "period 0" not in data.title and "period None" not in data.title
        assert "regime: bounce," in data.title
    data = trajectory_figure(_result(cavity_radius=0.0, name="bounce", period=2))
    assert "regime: bounce, period 2" in data.title
