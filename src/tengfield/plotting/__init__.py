"""Plots (matplotlib, Agg). Each stage has its own module; each figure has a core that
returns the matplotlib Figure (``*_figure``, used by the results' ``plot()``) and a
``plot_*`` that saves it (:func:`save_figure`, used by the CLI)."""

# --dpi lives beside --figure-format, with the file names it shapes (tengfield.files.figures)
from ..files import DPI_RANGE, figure_dpi, set_figure_dpi  # noqa: F401



#: a quantity whose values span less than this fraction of their size is constant to
#: rounding: drawn flat, with plain tick labels (no "1e−6+1.2556572e3" offset)
CONSTANT_SPAN = 1e-6


def new_figure(figsize, **kwargs):
    """A matplotlib Figure drawn by Agg without pyplot: saving it needs no backend, so
    the caller's (a notebook's) backend is never switched. ``figsize`` in inches.
    Every draw first tidies it (:func:`tidy_figure`): the one place the rules of every
    figure (constant axes drawn flat, legends off the data) are applied."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    class TidyFigure(Figure):
        def draw(self, renderer):
            tidy_figure(self, renderer)
            super().draw(renderer)

    fig = TidyFigure(figsize=figsize, **kwargs)
    FigureCanvasAgg(fig)
    _shown_in_notebooks(Figure)
    return fig


def _data_values(ax, axis: str):
    """The finite data values an axes draws along ``axis`` ("x" or "y"): its lines in
    data coordinates, its scatter/errorbar collections and its bars."""
    import numpy as np

    values = []
    for line in ax.get_lines():
        if line.get_transform() is not ax.transData:   # axhline, axvline: references
            continue
        values.append(np.asarray(line.get_xdata() if axis == "x" else line.get_ydata(),
                                 dtype=float).ravel())
    for coll in ax.collections:
        if coll.get_transform() is ax.transData:
            for path in coll.get_paths():
                v = path.vertices
                values.append(v[:, 0 if axis == "x" else 1])
        offsets = np.asarray(coll.get_offsets(), dtype=float)
        if offsets.size and coll.get_offset_transform() is ax.transData:
            values.append(offsets[:, 0 if axis == "x" else 1])
    for patch in ax.patches:     # bars and histogram bins (not an axvspan's band)
        if patch.get_data_transform() is ax.transData:
            corners = patch.get_patch_transform().transform(patch.get_path().vertices)
            values.append(corners[:, 0 if axis == "x" else 1])
    if not values:
        return np.empty(0)
    v = np.concatenate(values)
    return v[np.isfinite(v)]


def flatten_constant_axes(ax) -> None:
    """A linear axis whose data are constant to rounding (span ≤ :data:`CONSTANT_SPAN` of
    their size: a 1e-9 wiggle on 1255.66) is drawn as the constant it is: limits ±5 %
    around the value (±1 at 0), plain tick labels, no offset."""
    import numpy as np
    from matplotlib.ticker import ScalarFormatter

    for axis in "xy":
        scale = ax.get_xscale() if axis == "x" else ax.get_yscale()
        if scale != "linear":
            continue
        v = _data_values(ax, axis)
        if v.size < 2:
            continue
        size = float(np.max(np.abs(v)))
        if float(np.ptp(v)) > CONSTANT_SPAN * size:
            continue
        centre = float(np.mean(v))
        half = 0.05 * abs(centre) if size > 0 else 1.0
        which = ax.xaxis if axis == "x" else ax.yaxis
        (ax.set_xlim if axis == "x" else ax.set_ylim)(centre - half, centre + half)
        formatter = which.get_major_formatter()
        if isinstance(formatter, ScalarFormatter):
            formatter.set_useOffset(False)


#: legend places tried inside the axes, in order, before one beside it
_INSIDE = ("upper right", "upper left", "lower right", "lower left", "center right",
           "center left", "upper center", "lower center", "center")


def _covers_data(ax, box) -> bool:
    """Whether the display box ``box`` covers any drawn data of ``ax`` (a line's path,
    a marker, a bar or filled area): reference lines and bands (axhline, axvspan) do
    not count."""
    import numpy as np

    for line in ax.get_lines():
        if line.get_transform() is not ax.transData or not line.get_visible():
            continue
        xy = ax.transData.transform(np.column_stack([line.get_xdata(), line.get_ydata()])
                                    .astype(float))
        xy = xy[np.all(np.isfinite(xy), axis=1)]
        if xy.size == 0:
            continue
        inside = ((xy[:, 0] >= box.x0) & (xy[:, 0] <= box.x1)
                  & (xy[:, 1] >= box.y0) & (xy[:, 1] <= box.y1))
        if np.any(inside):
            return True
        if line.get_linestyle() not in ("None", "", " ") and len(xy) > 1:
            from matplotlib.path import Path
            if Path(xy).intersects_bbox(box, filled=False):
                return True
    for coll in ax.collections:
        if not coll.get_visible():
            continue
        offsets = np.asarray(coll.get_offsets(), dtype=float)
        if offsets.size and coll.get_offset_transform() is ax.transData and len(offsets) > 1:
            xy = ax.transData.transform(offsets)
            if np.any((xy[:, 0] >= box.x0) & (xy[:, 0] <= box.x1)
                      & (xy[:, 1] >= box.y0) & (xy[:, 1] <= box.y1)):
                return True
        if coll.get_transform() is ax.transData:
            for path in coll.get_paths():
                if ax.transData.transform_path(path).intersects_bbox(box, filled=True):
                    return True
    for patch in ax.patches:      # bars (an axvspan's band is a background: it does not count)
        if patch.get_data_transform() is not ax.transData:
            continue
        if patch.get_visible() and patch.get_window_extent().overlaps(box):
            return True
    return False


def place_legend(ax, renderer) -> bool:
    """Move ``ax``'s legend to the first corner where it covers no data, else beside the
    axes (right of it); returns whether it moved outside."""
    legend = ax.get_legend()
    if legend is None or getattr(legend, "_tidy_outside", False):
        return False
    for loc in _INSIDE:
        legend.set_loc(loc)
        if not _covers_data(ax, legend.get_window_extent(renderer)):
            return False
    if ax.get_yscale() == "linear" and not getattr(legend, "_tidy_headroom", False):
        # headroom: raise the top so the data end below the legend's height
        legend._tidy_headroom = True
        (y0, y1), axes_box = ax.get_ylim(), ax.get_window_extent(renderer)
        share = legend.get_window_extent(renderer).height / max(axes_box.height, 1.0)
        if share < 0.45:
            ax.set_ylim(y0, y0 + (y1 - y0) / (1.0 - share - 0.04))
            for loc in ("upper right", "upper left", "upper center"):
                legend.set_loc(loc)
                if not _covers_data(ax, legend.get_window_extent(renderer)):
                    return False
            ax.set_ylim(y0, y1)
    legend._ncols = 1
    legend.set_loc("upper left")
    legend.set_bbox_to_anchor((1.01, 1.0), transform=ax.transAxes)
    legend._tidy_outside = True
    return True


def wrap_wide_titles(fig, renderer) -> None:
    """A title wider than its figure is broken after a comma (as many lines as needed)."""
    titles = [fig._suptitle] if getattr(fig, "_suptitle", None) is not None else []
    titles += [ax.title for ax in fig.axes]
    room = fig.bbox.width * 0.96
    for text in titles:
        words = text.get_text()
        if not words or "\n" in words:
            continue
        width = text.get_window_extent(renderer).width
        if width <= room:
            continue
        parts, lines, line = words.split(", "), [], ""
        per_char = width / max(len(words), 1)
        for part in parts:
            candidate = f"{line}, {part}" if line else part
            if line and len(candidate) * per_char > room:
                lines.append(line + ",")
                line = part
            else:
                line = candidate
        lines.append(line)
        text.set_text("\n".join(lines))


def tidy_figure(fig, renderer) -> None:
    """The rules every figure keeps, applied at draw time (data and limits final):
    constant axes flat (:func:`flatten_constant_axes`), titles within the figure
    (:func:`wrap_wide_titles`), legends off the data
    (:func:`place_legend`, the layout redone when one moved beside its axes)."""
    if getattr(fig, "_tidying", False):
        return
    fig._tidying = True
    try:
        for ax in fig.axes:
            ax.get_xlim(), ax.get_ylim()       # autoscale now: transData as drawn
            flatten_constant_axes(ax)
        wrapped = [t.get_text() for t in ([fig._suptitle] if fig._suptitle else [])]
        wrap_wide_titles(fig, renderer)
        moved = wrapped != [t.get_text() for t in ([fig._suptitle] if fig._suptitle else [])]
        for ax in fig.axes:
            moved |= place_legend(ax, renderer)
        if moved:
            from matplotlib.layout_engine import ConstrainedLayoutEngine
            if not isinstance(fig.get_layout_engine(), ConstrainedLayoutEngine):
                import warnings
                with warnings.catch_warnings():       # an axes tight_layout cannot fit
                    warnings.simplefilter("ignore", UserWarning)
                    fig.tight_layout()
    finally:
        fig._tidying = False

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
    from ..files.atomic import target_name
    from ..files.figures import check_figure_pixels
    fig.savefig(path, dpi=check_figure_pixels(target_name(path), fig.get_size_inches(),
                                              figure_dpi(dpi)))
    return path
