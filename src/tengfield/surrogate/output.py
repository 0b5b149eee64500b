"""The files of a surrogate table: the HDF5 table ``tengfield precompute`` writes
(:func:`write_table`, the layout of :mod:`.layout`; :mod:`.store` reads it back) and surrogate.png, the figure
``tengfield run`` draws of the surrogate it used (:func:`write_surrogate_figure`).
Every file through :mod:`tengfield.files`."""
from __future__ import annotations

from pathlib import Path

import json

import numpy as np

from ..errors import SurrogateError
from ..files import figure_file, write_figure
from ..files.hdf5 import write_checked_file
from .layout import ARRAYS, LINE_CHECK_INDEX, OPTIONAL_ARRAYS, SCALAR_TYPES, SCALARS, typed_scalars
from .provenance import FORMAT_VERSION

#: the table's file name inside an output directory (``SurrogateTable.write``)
SURROGATE_FILE = "surrogate.h5"


def write_table(path: str | Path, table: SurrogateTable) -> Path:
    """Write ``table`` to HDF5 atomically (:func:`tengfield.files.hdf5.write_checked_file`: every array
    with a Fletcher-32 filter and its SHA-256, checksummed scalars). Raises
    ``OSError`` if the file cannot be written (nothing is left behind)."""
    arrays = {name: np.asarray(getattr(table, attr)) for attr, name in ARRAYS.items()}
    arrays["error_history"] = np.asarray(table.error_history, dtype=float).reshape(-1, 2)
    for attr, name in OPTIONAL_ARRAYS.items():
        if getattr(table, attr, None) is not None:
            arrays[name] = np.asarray(getattr(table, attr), dtype=float)
    if OPTIONAL_ARRAYS["line_check"] in arrays:
        check = arrays[OPTIONAL_ARRAYS["line_check"]]
        solved = np.flatnonzero(np.all(np.isfinite(check), axis=tuple(range(1, check.ndim))))
        if solved.size:
            arrays[OPTIONAL_ARRAYS["line_check"]] = check[solved]
            arrays[LINE_CHECK_INDEX] = solved.astype(np.int64)
        else:   # solved nowhere: as if absent (HDF5 filters refuse empty datasets)
            del arrays[OPTIONAL_ARRAYS["line_check"]]
    scalars = typed_scalars(vars(table), SCALAR_TYPES)
    return write_checked_file(path, arrays, scalars, SCALARS, error=SurrogateError, attrs={
        "format_version": FORMAT_VERSION,
        "provenance": json.dumps(table.provenance, default=str),
        "scene_text": table.provenance.get("scene_text", ""),
        "command_line": table.provenance.get("command_line", "")})


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
                          reference: str = "floating",
                          ball_charge: float | None = None) -> list[Path]:
    """surrogate.h5 (the table, as ``tengfield precompute -o`` writes it: per unit ball
    charge) and, with ``plots``, surrogate.png (as ``tengfield run`` draws it: the scene's
    cells and reference when the table knows its scene, at ``ball_charge`` [C], which
    ``plots`` needs: :meth:`SurrogateTable.write` gives its scene's); returns the paths."""
    from ..files import writable_target

    if plots and ball_charge is None:   # refused before anything is written
        raise SurrogateError("surrogate.png needs a ball charge: the table is per unit "
                             "charge; give ball_charge [C]")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written = [write_table(writable_target(out / SURROGATE_FILE), table)]
    if plots:
        scene = getattr(table, "scene", None)
        cells = 1 if scene is None else scene.device.cells
        if scene is not None:
            reference = scene.circuit.reference
        written.append(write_surrogate_figure(table, table.curves(reference, ball_charge), out,
                                              cells=cells))
    return written
