"""The files of a surrogate table: the HDF5 table ``tengfield precompute`` writes
(:func:`tengfield.surrogate.store.write_table`) and surrogate.png, the figure
``tengfield run`` draws of the surrogate it used (:func:`write_surrogate_figure`).
Every file through :mod:`tengfield._files`."""
from __future__ import annotations

from pathlib import Path

from .._files import figure_file, write_figure

#: the table's file name inside an output directory (``SurrogateTable.write``)
SURROGATE_FILE = "surrogate.h5"


def write_surrogate_figure(table, curves, out_dir, *, cells: int = 1, visited=None,
                           error_estimate: float | None = None, figures=None) -> Path:
    """surrogate.png: V_OC, Q_SC, C_T of ``cells`` cells against z (``curves`` through
    ``table``; ``visited``, ``error_estimate`` as
    :func:`tengfield.plotting.waveforms.surrogate_figure` takes them)."""
    from ..plotting.waveforms import plot_surrogate

    return write_figure(plot_surrogate, table, curves, path=Path(out_dir) / figure_file("surrogate"),
                        figures=figures, cells=cells, visited=visited,
                        error_estimate=error_estimate)


def write_surrogate_files(table, out_dir, *, plots: bool = True,
                          reference: str = "floating") -> list[Path]:
    """surrogate.h5 (the table, as ``tengfield precompute -o`` writes it) and, with
    ``plots``, surrogate.png (as ``tengfield run`` draws it: the scene's cells and
    reference when the table knows its scene); returns the paths."""
    from .store import write_table
    from .._files import writable_target

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written = [write_table(writable_target(out / SURROGATE_FILE), table)]
    if plots:
        scene = getattr(table, "scene", None)
        cells = 1 if scene is None else scene.device.cells
        if scene is not None:
            reference = scene.circuit.reference
        written.append(write_surrogate_figure(table, table.curves(reference), out, cells=cells))
    return written
