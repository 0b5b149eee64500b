"""Plots (matplotlib, Agg). Each stage has its own module; each figure has a core that
returns the matplotlib Figure (``*_figure``, used by the results' ``plot()``) and a
``plot_*`` that saves it (:func:`save_figure`, used by the CLI)."""


def new_figure(figsize, **kwargs):
    """A matplotlib Figure drawn by Agg without pyplot: saving it needs no backend, so
    the caller's (a notebook's) backend is never switched. ``figsize`` in inches."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize, **kwargs)
    FigureCanvasAgg(fig)
    return fig


#: the command line's ``--dpi`` (None: each figure's own resolution)
_DPI = {"dpi": None}

#: the range ``--dpi`` accepts [dots per inch]
DPI_RANGE = (20.0, 1200.0)


def set_figure_dpi(dpi: float | None) -> None:
    """Every figure saved from now on at ``dpi`` dots per inch (None: each figure's own,
    110-120 for the CLI's PNGs). Raises ValueError outside :data:`DPI_RANGE`."""
    if dpi is not None:
        dpi = float(dpi)
        if not DPI_RANGE[0] <= dpi <= DPI_RANGE[1]:
            raise ValueError(f"--dpi {dpi:g} is out of range: allowed "
                             f"[{DPI_RANGE[0]:g}, {DPI_RANGE[1]:g}] dots per inch")
    _DPI["dpi"] = dpi


def figure_dpi(default: float) -> float:
    """The resolution a figure is saved at: ``--dpi`` if given, else ``default``."""
    return default if _DPI["dpi"] is None else _DPI["dpi"]


def save_figure(fig, path, dpi: float):
    """Write ``fig`` (from a ``*_figure`` function of this package: what the results'
    ``plot()`` return in a notebook) to the PNG ``path`` at ``dpi`` (or the command
    line's ``--dpi``); returns ``path``. Every ``plot_*(..., path)`` is its
    ``*_figure`` core saved here, so the CLI's PNG and ``plot()`` are one figure."""
    fig.savefig(path, dpi=figure_dpi(dpi))
    return path
