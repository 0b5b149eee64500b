"""Plots (matplotlib, Agg). Each stage has its own module; each figure has a core that
returns the matplotlib Figure (``*_figure``, used by the results' ``plot()``) and a
``plot_*`` that saves it (:func:`save_figure`, used by the CLI)."""

# --dpi lives beside --figure-format, with the file names it shapes (tengfield.files.figures)
from ..files import DPI_RANGE, figure_dpi, set_figure_dpi  # noqa: F401



def new_figure(figsize, **kwargs):
    """A matplotlib Figure drawn by Agg without pyplot: saving it needs no backend, so
    the caller's (a notebook's) backend is never switched. ``figsize`` in inches."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize, **kwargs)
    FigureCanvasAgg(fig)
    return fig


def save_figure(fig, path, dpi: float):
    """Write ``fig`` (from a ``*_figure`` function of this package: what the results'
    ``plot()`` return in a notebook) to the PNG ``path`` at ``dpi`` (or the command
    line's ``--dpi``); returns ``path``. Every ``plot_*(..., path)`` is its
    ``*_figure`` core saved here, so the CLI's PNG and ``plot()`` are one figure."""
    fig.savefig(path, dpi=figure_dpi(dpi))
    return path
