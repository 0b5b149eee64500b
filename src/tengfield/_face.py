"""The plain summary dict every result offers as ``result.summary`` (a property).

A few results used to spell it ``result.summary()``; :class:`Summary` is a plain
``dict`` that still answers that call (with a :class:`DeprecationWarning`), so old
notebooks keep working while new code reads the property.
"""
from __future__ import annotations

import warnings


class Summary(dict):
    """A JSON-ready dict; calling it returns a copy and warns that the call is deprecated."""

    def __call__(self) -> dict:
        warnings.warn("result.summary() is deprecated: read the property result.summary",
                      DeprecationWarning, stacklevel=2)
        return dict(self)


def figure_of_png(draw) -> "object":
    """A matplotlib Figure showing the PNG that ``draw(path)`` writes (for the plotting
    functions that only write a file); the figure is the picture, axes hidden."""
    import tempfile
    from pathlib import Path

    import matplotlib.image as mpimg
    from matplotlib.figure import Figure

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "figure.png"
        draw(path)
        image = mpimg.imread(path)
    height, width = image.shape[:2]
    fig = Figure(figsize=(width / 100, height / 100), dpi=100)
    ax = fig.add_axes((0, 0, 1, 1))
    ax.imshow(image)
    ax.set_axis_off()
    return fig
