"""Figure files: ``--figure-format`` and ``--dpi`` (one setting for every figure a
command writes: :func:`figure_file` names a figure, :func:`figure_dpi` its resolution)
and :func:`write_figure`, a figure drawn atomically or sent to the figure process."""
from __future__ import annotations

import math
from pathlib import Path

from .atomic import atomic_path, writable_target


#: the figure formats ``--figure-format`` offers (matplotlib writes each by its suffix)
FIGURE_FORMATS = ("png", "pdf", "svg")
#: pixels of one figure file, the bound of every figure a command or a result's
#: ``write`` saves (:func:`check_figure_pixels`): 50 megapixels is a 600-dpi print of
#: field.png (38.5 MP), ~0.6 GB for matplotlib's canvas and ~2.3 GB for pyvista's
#: field.png (``field --dpi 1200``: 14000 x 11000 px, 154 MP, 7 GB, before the bound)
MAX_FIGURE_PIXELS = 50e6
#: the largest figure drawn at its own size [inches]: field.png, 1400 x 1100 px at its
#: 120 dpi (the matplotlib figures are at most 16 x 3.6 and 11 x 8.2 in)
LARGEST_FIGURE_INCHES = (1400 / 120, 1100 / 120)
#: the range ``--dpi`` accepts [dots per inch]: up to the resolution at which the
#: largest figure stays within :data:`MAX_FIGURE_PIXELS` (683 dpi)
DPI_RANGE = (20.0, float(math.floor(math.sqrt(
    MAX_FIGURE_PIXELS / (LARGEST_FIGURE_INCHES[0] * LARGEST_FIGURE_INCHES[1])))))
#: how the command's figures are written: ``--figure-format`` and ``--dpi`` (None: each
#: figure's own resolution)
_FIGURE_OUTPUT = {"format": "png", "dpi": None}


def _pixels(inches, dpi: float) -> tuple[int, int]:
    return round(inches[0] * dpi), round(inches[1] * dpi)


def set_figure_dpi(dpi: float | None) -> None:
    """Every figure saved from now on at ``dpi`` dots per inch (None: each figure's own,
    110-150 for the CLI's PNGs). Raises ValueError outside :data:`DPI_RANGE`, whose top
    keeps the largest figure within :data:`MAX_FIGURE_PIXELS` (checked by every command
    that takes ``--dpi`` before its work)."""
    if dpi is not None:
        dpi = float(dpi)
        if not DPI_RANGE[0] <= dpi <= DPI_RANGE[1]:
            why = ""
            if dpi > DPI_RANGE[1]:
                w, h = _pixels(LARGEST_FIGURE_INCHES, dpi)
                why = (f" (a figure is at most {MAX_FIGURE_PIXELS / 1e6:g} megapixels; the "
                       f"largest, field.png, would be {w} x {h} px here)")
            raise ValueError(f"--dpi {dpi:g} is out of range: allowed "
                             f"[{DPI_RANGE[0]:g}, {DPI_RANGE[1]:g}] dots per inch{why}")
    _FIGURE_OUTPUT["dpi"] = dpi


def check_figure_pixels(name: str, inches, dpi: float) -> float:
    """The resolution to save a figure of ``inches`` (width, height) at, asked ``dpi``:
    ``dpi`` itself within :data:`MAX_FIGURE_PIXELS`, else the highest that fits, with one
    warning line naming the figure, the size and the resolution used (a figure whose size
    grows with its data past the largest :data:`DPI_RANGE` assumes; a notebook's
    ``dpi=``). The one bound of every figure's pixels (matplotlib's and field.png's)."""
    w, h = float(inches[0]), float(inches[1])
    if w * h * dpi * dpi <= MAX_FIGURE_PIXELS:
        return dpi
    fits = math.floor(math.sqrt(MAX_FIGURE_PIXELS / (w * h)))
    pw, ph = _pixels((w, h), dpi)
    import warnings
    warnings.warn(f"{name}: {w:.3g} x {h:.3g} in at {dpi:g} dpi would be {pw} x {ph} px "
                  f"({pw * ph / 1e6:.3g} megapixels): drawn at {fits} dpi (allowed <= "
                  f"{MAX_FIGURE_PIXELS / 1e6:g} megapixels per figure)", RuntimeWarning,
                  stacklevel=3)
    return float(fits)


def figure_dpi(default: float) -> float:
    """The resolution a figure is saved at: ``--dpi`` if given, else ``default``."""
    return default if _FIGURE_OUTPUT["dpi"] is None else _FIGURE_OUTPUT["dpi"]


def set_figure_format(fmt: str) -> None:
    """The format of every figure written from now on (``--figure-format``): one of
    :data:`FIGURE_FORMATS`; raises ValueError naming the allowed ones."""
    fmt = str(fmt).lower().lstrip(".")
    if fmt not in FIGURE_FORMATS:
        raise ValueError(f"--figure-format {fmt!r} is not offered: allowed "
                         f"{', '.join(FIGURE_FORMATS)}")
    _FIGURE_OUTPUT["format"] = fmt


def figure_file(stem: str) -> str:
    """A figure's file name: ``stem`` with the format's suffix (``waveforms.png``, or
    ``waveforms.pdf`` under ``--figure-format pdf``)."""
    return f"{stem}.{_FIGURE_OUTPUT['format']}"


def write_figure(function, *data, path: str | Path, figures=None, **kwargs) -> Path:
    """Draw ``function(*data, path, **kwargs)`` (a ``plot_*`` saver) here, atomically (a
    full disk leaves no 0-byte figure behind), or send it to ``figures`` (a
    :class:`tengfield.plotting.process.FigureProcess`: complete after its ``finish()``);
    returns ``path``."""
    writable_target(path)
    if figures is None:
        with atomic_path(path) as tmp:
            function(*data, tmp, **kwargs)
    else:
        figures.draw(function, *data, path, **kwargs)
    return Path(path)
