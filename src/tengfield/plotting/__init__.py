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
    _shown_in_notebooks(Figure)
    return fig


def _shown_in_notebooks(figure_class) -> None:
    """In an IPython kernel (Jupyter) where pyplot was never imported, a Figure made
    without pyplot would show as ``<Figure size ...>``: register the PNG display that
    ``%matplotlib inline`` registers (only if none is; nothing outside IPython)."""
    import sys

    ipython = sys.modules.get("IPython")
    shell = ipython.get_ipython() if ipython is not None else None
    if shell is None or not hasattr(shell, "display_formatter"):
        return
    png = shell.display_formatter.formatters.get("image/png")
    if png is None or _has(png, figure_class):
        return
    from IPython.core.pylabtools import print_figure

    png.for_type(figure_class, lambda fig: print_figure(fig, "png", bbox_inches="tight"))


def _has(formatter, figure_class) -> bool:
    try:
        formatter.lookup_by_type(figure_class)
        return True
    except KeyError:
        return False


def save_figure(fig, path, dpi: float):
    """Write ``fig`` (from a ``*_figure`` function of this package: what the results'
    ``plot()`` return in a notebook) to the PNG ``path`` at ``dpi`` (or the command
    line's ``--dpi``); returns ``path``. Every ``plot_*(..., path)`` is its
    ``*_figure`` core saved here, so the CLI's PNG and ``plot()`` are one figure."""
    fig.savefig(path, dpi=figure_dpi(dpi))
    return path
