"""surrogate.png's (z, r) map of a table whose offsets are scaled to the admissible radius
at each height (the spherical shell): drawn inside r <= r_max(z), solves at their real
offsets, the cavity wall as a line; a tube's (radial) map keeps its rectangle."""
import numpy as np
import pytest

from tengfield.plotting import new_figure
from tengfield.plotting.waveforms import _plot_radial_change


class Curves:
    """A stand-in (z, r) surrogate: Q_SC = z + r² over a 12 mm stroke, R = 6 mm."""

    def __init__(self, scaled: bool):
        self.scaled, self.stroke, self.max_offset = scaled, 12e-3, 6e-3
        self.positions = np.linspace(0.0, 12e-3, 5)
        self.offsets = np.linspace(0.0, 6e-3, 3)

    def charge(self, z, r):
        return np.asarray(z) * 1e-9 + np.asarray(r) ** 2 * 1e-6


@pytest.mark.parametrize("scaled", [True, False])
def test_the_map_stays_where_the_ball_can_be(scaled):
    fig = new_figure((5, 4))
    ax = fig.add_subplot()
    _plot_radial_change(ax, Curves(scaled), 1, None)
    lines = {line.get_label(): line for line in ax.get_lines()}
    z, r = (np.asarray(v) / 1e3 for v in lines["3D solves"].get_data())
    wall = np.sqrt(np.maximum(6e-3**2 - (z - 6e-3) ** 2, 0.0))
    if scaled:
        assert np.all(r <= wall + 1e-12)              # solves at their real offsets
        assert np.any(r < r.max()) and r[z == 0].max() == 0.0   # the stroke's ends: r = 0
        assert "cavity wall r_max(z)" in lines
        filled = [c for c in ax.collections if hasattr(c, "get_array")]
        assert filled                                   # the contours are drawn
    else:
        assert "cavity wall r_max(z)" not in lines
        assert r.max() == pytest.approx(6.0e-3) and r[z == 0].max() == pytest.approx(6e-3)
