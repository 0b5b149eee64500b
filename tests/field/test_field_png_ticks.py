"""field.png's axes (issue #42, Figures): tick values are round numbers in mm (steps of
1, 2 or 5 x 10^k) over bounds that hold the drawn cell."""
from __future__ import annotations

import math

import numpy as np
import pytest

from tengfield.field.plot import COLOUR_BAR, nice_ticks


@pytest.mark.parametrize("lo, hi", [(-7.35, 7.35), (-0.57, 12.43), (0.0, 3.0), (-2.1, 9.9),
                                    (-0.0123, 0.0456), (-35.0, 112.7)])
def test_ticks_are_round_and_cover_the_range(lo, hi):
    start, stop, count, fmt = nice_ticks(lo, hi)
    assert start <= lo + 1e-12 and stop >= hi - 1e-12
    assert 3 <= count <= 10
    values = np.linspace(start, stop, count)
    step = values[1] - values[0]
    mantissa = step / 10 ** math.floor(math.log10(step))
    assert min(abs(mantissa - m) for m in (1.0, 2.0, 5.0, 10.0)) < 1e-9
    assert np.allclose(values / step, np.round(values / step), atol=1e-9)  # on the step's grid
    labels = [fmt % v for v in values]
    assert len(set(labels)) == count                        # distinct
    assert all(float(text) == pytest.approx(v, abs=step * 1e-6) for text, v in zip(labels, values))
    # the bounds are not much wider than the data: at most one step on each side
    assert lo - start < step + 1e-12 and stop - hi < step + 1e-12


def test_colour_bar_title_sits_clear_of_the_plot():
    # the bar (and its title above it) right of the plot's frame and below the top title
    assert COLOUR_BAR["position_x"] >= 0.86
    assert COLOUR_BAR["position_y"] + COLOUR_BAR["height"] <= 0.78
