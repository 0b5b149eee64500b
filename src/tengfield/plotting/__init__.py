"""Plots (matplotlib, Agg). Each stage has its own module."""


def new_figure(figsize, **kwargs):
    """A matplotlib Figure drawn by Agg without pyplot: saving it needs no backend, so
    the caller's (a notebook's) backend is never switched. ``figsize`` in inches."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize, **kwargs)
    FigureCanvasAgg(fig)
    return fig
