"""Figure files: ``--figure-format`` and ``--dpi`` (one setting for every figure a
command writes: :func:`figure_file` names a figure, :func:`figure_dpi` its resolution)
and :func:`write_figure`, a figure drawn atomically or sent to the figure process."""
from __future__ import annotations

from pathlib import Path

from .atomic import atomic_path, writable_target


#: the figure formats ``--figure-format`` offers (matplotlib writes each by its suffix)
FIGURE_FORMATS = ("png", "pdf", "svg")
#: the range ``--dpi`` accepts [dots per inch]
DPI_RANGE = (20.0, 1200.0)
#: how the command's figures are written: ``--figure-format`` and ``--dpi`` (None: each
#: figure's own resolution)
_FIGURE_OUTPUT = {"format": "png", "dpi": None}


def set_figure_dpi(dpi: float | None) -> None:
    """Every figure saved from now on at ``dpi`` dots per inch (None: each figure's own,
    110-150 for the CLI's PNGs). Raises ValueError outside :data:`DPI_RANGE`."""
    if dpi is not None:
        dpi = float(dpi)
        if not DPI_RANGE[0] <= dpi <= DPI_RANGE[1]:
            raise ValueError(f"--dpi {dpi:g} is out of range: allowed "
                             f"[{DPI_RANGE[0]:g}, {DPI_RANGE[1]:g}] dots per inch")
    _FIGURE_OUTPUT["dpi"] = dpi


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
