"""One HDF5 file of tables (``run.h5`` of ``tengfield run``, ``[run] output_format =
"hdf5"``): a group per table, a dataset per column (the CSV header names), each with
its ``units`` attribute, chunked and compressed (deflate + shuffle, which h5py, HDF5's
own tools, MATLAB and Origin's HDF5 import all read), written a chunk at a time.

Layout (docs/stability.md, "long runs"):

* ``/waveforms/<column>``: the columns of waveforms.csv;
* ``/trajectory/<column>``: the dynamics' columns; a column equal to one of
  ``/waveforms`` (``time_s``, ``gap_m``... of a 1-D run) is an HDF5 hard link to it,
  stored once, read as any other dataset;
* ``/impacts/<column>`` (``plate`` as the strings ``lower``/``upper``), and for a 3D run
  ``/contacts/<column>``;
* file attributes ``summary_json`` (summary.json's text), ``scene_text``,
  ``tengfield_version``, ``layout``.

In pandas (no PyTables needed)::

    import h5py, pandas as pd
    with h5py.File("out/run.h5", "r") as f:
        waveforms = pd.DataFrame({name: f["waveforms"][name][()] for name in f["waveforms"]})

``h5py`` is Debian's build (:func:`import_h5py`); it is
imported only when a file is written.
"""
from __future__ import annotations

import hashlib
import io
import json
import os
from pathlib import Path

import numpy as np

from .atomic import write_bytes

#: The largest table written as CSV (rows): what tengfield reads back as a recorded
#: excitation or a measured trace (tengfield.scene.limits.MAX_RECORDED_ROWS,
#: tengfield.fit.spec.MAX_TRACE_ROWS: 100 s at 20 kHz). A run with more samples writes
#: its tables to run.h5 instead (one warning), as ``[run] output_format = "hdf5"`` does.
MAX_CSV_ROWS = 2_000_000
#: rows per HDF5 chunk and per write (2 MB of doubles): memory stays one chunk per column
CHUNK_ROWS = 1 << 18
#: deflate level: 1 is ~4x faster than 4 for <2 % more bytes (doubles compress little)
DEFLATE_LEVEL = 1
FILE_NAME = "run.h5"

#: unit of a column from its name's suffix (longest first)
_UNITS = (("_m_per_s2", "m/s^2"), ("_m_per_s", "m/s"), ("_rad_per_s", "rad/s"),
          ("_W_per_m3", "W/m^3"), ("_ohm", "ohm"), ("_Hz", "Hz"), ("_V", "V"), ("_C", "C"),
          ("_A", "A"), ("_W", "W"), ("_J", "J"), ("_F", "F"), ("_s", "s"), ("_m", "m"))


def unit_of(column: str) -> str:
    """The SI unit of a column named with its unit suffix (``gap_velocity_m_per_s`` ->
    ``m/s``); ``1`` for a count or a name without one (``plate``, ``steps``)."""
    for suffix, unit in _UNITS:
        if column.endswith(suffix):
            return unit
    return "1"


def import_h5py(error=RuntimeError):
    """``h5py``, which must be the distribution's build (Debian's python3-h5py): raises
    ``error`` (one line) for a pip wheel imported beside dolfinx.

    A pip wheel of h5py bundles its own HDF5; imported after dolfinx has loaded
    the system HDF5 it fails ("Not a datatype") or corrupts files. ``make setup``
    removes such a wheel from the venv; this names the problem if one is back.
    """
    import sys

    import h5py

    bundled = Path(h5py.__file__).resolve().parents[1] / "h5py.libs"
    if bundled.exists() and any(name.startswith("dolfinx") for name in sys.modules):
        raise error(
            f"the h5py at {Path(h5py.__file__).parent} is a pip wheel with its own HDF5, "
            "which clashes with the HDF5 dolfinx loads: `pip uninstall h5py` in the venv "
            "(Debian's python3-h5py is used), e.g. by running `make setup`")
    return h5py


def _h5py():
    return import_h5py()


def _sampled(column) -> bool:
    """A column sampled on request (:class:`tengfield.dynamics.columns.SampledColumn`):
    not an array, but sliceable."""
    return not isinstance(column, np.ndarray) and hasattr(column, "chunks") \
        and hasattr(column, "__len__")


def _column(group, name: str, values) -> None:
    """Dataset ``name`` of ``group`` from a 1-D array, written ``CHUNK_ROWS`` at a time
    (a view per write: no copy of the column; a long run's column sampled on request
    is sampled a write at a time)."""
    if _sampled(values):
        n = len(values)
        options = dict(chunks=(min(n, CHUNK_ROWS),), compression="gzip",
                       compression_opts=DEFLATE_LEVEL, shuffle=True) if n else {}
        dataset = group.create_dataset(name, shape=(n,), dtype=np.float64, **options)
        for start in range(0, n, CHUNK_ROWS):
            dataset[start:start + CHUNK_ROWS] = values[start:start + CHUNK_ROWS]
        dataset.attrs["units"] = unit_of(name)
        return
    values = np.asarray(values)
    if values.dtype.kind in "UO":                  # text cells (impacts' plate)
        values = np.asarray(values, dtype=bytes)
    if values.dtype == bool:
        values = values.astype(np.int8)
    n = values.shape[0]
    options = {}
    if n:
        options = dict(chunks=(min(n, CHUNK_ROWS),), compression="gzip",
                       compression_opts=DEFLATE_LEVEL, shuffle=values.dtype.kind in "fiu")
    dataset = group.create_dataset(name, shape=(n,), dtype=values.dtype, **options)
    for start in range(0, n, CHUNK_ROWS):
        dataset[start:start + CHUNK_ROWS] = values[start:start + CHUNK_ROWS]
    dataset.attrs["units"] = unit_of(name)


def _same(a, b) -> bool:
    """Equal 1-D columns (compared a chunk at a time: no n-sized temporary)."""
    if a is b:                   # e.g. a long run's column sampled on request, not built
        return True
    if _sampled(a) or _sampled(b):
        return len(a) == len(b) and all(
            np.array_equal(np.asarray(a[i:i + CHUNK_ROWS]), np.asarray(b[i:i + CHUNK_ROWS]))
            for i in range(0, len(a), CHUNK_ROWS))
    a, b = np.asarray(a), np.asarray(b)
    if a is b:
        return True
    if a.shape != b.shape or a.dtype != b.dtype:
        return False
    return all(np.array_equal(a[i:i + CHUNK_ROWS], b[i:i + CHUNK_ROWS])
               for i in range(0, a.shape[0], CHUNK_ROWS))


def _chunked(columns) -> bool:
    """A table given a chunk at a time (``columns``, ``rows``, ``chunks()``: e.g. a
    streamed run's :class:`tengfield.electrical.stream.StreamedWaveforms`)."""
    return hasattr(columns, "chunks") and hasattr(columns, "rows")


def _table_bytes(columns) -> int:
    if _chunked(columns):
        return 8 * columns.rows * len(list(columns))
    return sum(v.nbytes if _sampled(v) else np.asarray(v).nbytes for v in columns.values())


def _chunked_columns(group, columns) -> None:
    """Datasets of a chunked table (float64 columns of ``columns.rows`` rows), filled a
    chunk at a time as ``columns.chunks()`` yields them: memory is one chunk."""
    n = columns.rows
    options = {}
    if n:
        options = dict(chunks=(min(n, CHUNK_ROWS),), compression="gzip",
                       compression_opts=DEFLATE_LEVEL, shuffle=True)
    datasets = {}
    for name in columns:
        datasets[name] = group.create_dataset(name, shape=(n,), dtype=np.float64, **options)
        datasets[name].attrs["units"] = unit_of(name)
    start = 0
    for chunk in columns.chunks():
        rows = len(next(iter(chunk.values())))
        for name, dataset in datasets.items():
            dataset[start:start + rows] = chunk[name]
        start += rows
    if start != n:
        raise RuntimeError(f"chunked table wrote {start} rows of {n}")


def _link_source(shared, column):
    """The array ``shared[column]`` stands for, without computing a chunked table's."""
    if _chunked(shared):
        source_of = getattr(shared, "source_of", None)
        return None if source_of is None else source_of(column)
    return shared.get(column)


def _check_room(path: Path, tables: dict) -> None:
    """``OSError(ENOSPC)`` naming ``path`` if its filesystem has less room than the
    uncompressed columns need: HDF5 meeting a full disk mid-write can crash the
    interpreter (a full cache disk: "Slist already enabled?", then a segfault)."""
    import errno
    import shutil

    need = sum(_table_bytes(columns) for columns in tables.values())
    need += 1 << 20                                  # metadata, chunk index
    free = shutil.disk_usage(path.parent).free
    if free < need:
        raise OSError(errno.ENOSPC, f"No space left on device ({free / 1e6:.3g} MB free, "
                      f"up to {need / 1e6:.3g} MB needed)", str(path))


def write_tables(path: str | Path, tables: dict, *, attrs: dict | None = None,
                 link_to: str | None = "waveforms") -> Path:
    """Write ``tables`` (group name -> {column name -> 1-D array}, in order; or a chunked
    table of float64 columns: a mapping with ``rows`` and ``chunks()`` yielding
    ``{column: array}`` for consecutive rows, written as they come) to the HDF5
    file ``path``, through a temporary file replaced at the end (a reader never sees
    half a file; an error leaves none). A column of another group equal to the column of
    the same name in group ``link_to`` is a hard link to it (stored once). ``attrs``:
    file attributes (strings, numbers). Raises ``OSError`` naming ``path``."""
    h5py = _h5py()
    path = Path(path)
    tmp = path.with_name(f".{path.stem}.tmp-{os.getpid()}{path.suffix}")
    _check_room(path, tables)
    try:
        with h5py.File(tmp, "w", track_order=True) as f:
            for name, value in (attrs or {}).items():
                f.attrs[name] = value
            for group_name, columns in tables.items():
                group = f.create_group(group_name, track_order=True)
                if _chunked(columns):
                    group.attrs["rows"] = columns.rows
                    _chunked_columns(group, columns)
                    continue
                group.attrs["rows"] = len(next(iter(columns.values()))) if columns else 0
                shared = tables.get(link_to, {}) if group_name != link_to else {}
                for column, values in columns.items():
                    source = _link_source(shared, column) if column in shared else None
                    if source is not None and _same(values, source):
                        group[column] = f[f"{link_to}/{column}"]     # hard link
                    else:
                        _column(group, column, values)
        os.replace(tmp, path)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        raise OSError(exc.errno, exc.strerror or str(exc), str(path)) from None
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return path


def read_tables(path: str | Path) -> dict:
    """``{group: {column: array}}`` of a file written by :func:`write_tables` (strings
    decoded), for tests and notebooks; the file's attributes under ``"attrs"``."""
    h5py = _h5py()
    out: dict = {}
    with h5py.File(path, "r") as f:
        out["attrs"] = {k: (v.decode() if isinstance(v, bytes) else v) for k, v in f.attrs.items()}
        for group_name, group in f.items():
            out[group_name] = {}
            for column, dataset in group.items():
                values = dataset[()]
                if values.dtype.kind == "S":
                    values = values.astype(str)
                out[group_name][column] = values
    return out


#: the first bytes of an HDF5 file (its superblock's signature)
HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"


def is_hdf5(path: str | Path) -> bool:
    """Whether ``path`` is a regular file that starts as an HDF5 file does (False for
    anything that cannot be read: the caller's reader names the problem)."""
    try:
        if not Path(path).is_file():
            return False
        with open(path, "rb") as fh:
            return fh.read(len(HDF5_SIGNATURE)) == HDF5_SIGNATURE
    except OSError:
        return False


class WaveformTable:
    """The ``/waveforms`` table of a run.h5 read as a measured trace is read from a CSV:
    ``header`` (its column names), ``rows`` (one entry per sample: only its length is
    used) and ``column(name)`` as floats (fit's ``--measured out/run.h5``)."""

    def __init__(self, what: str, columns: dict):
        self.what = what
        self._columns = columns
        self.header = list(columns)
        self.rows = range(len(next(iter(columns.values()))) if columns else 0)

    def column(self, col: str, *, allow_blank: bool = False) -> np.ndarray:
        return np.asarray(self._columns[col], dtype=float)


def read_waveform_table(path: str | Path, what: str, *, max_rows: int) -> WaveformTable:
    """The numeric columns of ``path``'s ``/waveforms`` group (a run.h5 of tengfield
    run), as a table of a measured trace; a file without it, more than ``max_rows``
    samples, or one HDF5 cannot read: one-line SceneError starting with ``what``."""
    from ..errors import SceneError
    from .atomic import note_input

    h5py = _h5py()
    note_input(Path(path))
    try:
        with h5py.File(path, "r") as f:
            group = f.get("waveforms")
            if not isinstance(group, h5py.Group):
                raise SceneError(f"{what} is an HDF5 file without a /waveforms table: "
                                 "expected tengfield run's run.h5 (or a CSV with a header)")
            columns = {}
            for name, dataset in group.items():
                if not isinstance(dataset, h5py.Dataset) or dataset.ndim != 1 \
                        or dataset.dtype.kind not in "fiu":
                    continue
                if dataset.shape[0] > max_rows:
                    raise SceneError(f"{what} has {dataset.shape[0]:,} samples in /waveforms: "
                                     f"allowed at most {max_rows:,} (decimate it)")
                columns[str(name)] = dataset[()]
    except OSError as exc:
        raise SceneError(f"{what} could not be read as HDF5: "
                         f"{exc.strerror or type(exc).__name__}") from None
    if len({len(v) for v in columns.values()}) > 1:
        raise SceneError(f"{what}: the /waveforms columns differ in length")
    return WaveformTable(what, columns)


# ---------------------------------------------------------------------------
# checked files (the surrogates: tengfield.surrogate.store reads them)
def array_digest(array) -> str:
    """SHA-256 of an array's dtype, shape and bytes (little-endian, C order)."""
    a = np.ascontiguousarray(array)
    a = a.astype(a.dtype.newbyteorder("<"), copy=False)
    digest = hashlib.sha256(f"{a.dtype.str}{a.shape}".encode())
    digest.update(a.tobytes())
    return digest.hexdigest()


def scalars_digest(values: dict) -> str:
    """SHA-256 of the scalar attributes (canonical JSON; NaN written as ``NaN``)."""
    return hashlib.sha256(json.dumps(values, sort_keys=True).encode()).hexdigest()


def write_checked_file(path: str | Path, arrays: dict, scalars: dict, scalar_names: dict,
                       attrs: dict, *, error=RuntimeError) -> Path:
    """Write a checked HDF5 file (the surrogates') atomically (temporary file + ``os.replace``): ``arrays``
    (dataset name -> array) each with a Fletcher-32 filter and its SHA-256 (attribute
    ``sha256``), ``scalars`` (attribute -> typed value) as
    the file attributes ``scalar_names[attr]`` with their ``scalars_sha256``, the
    further file attributes ``attrs`` and the ``complete`` flag set last. Raises
    ``OSError`` if it cannot be written (nothing is left behind); ``error`` for an h5py
    that cannot be used (:func:`import_h5py`)."""
    h5py = import_h5py(error)
    # HDF5 builds the file in memory; the disk sees only plain writes. A full disk then is
    # an OSError (ENOSPC) like any other; an HDF5 file whose flush failed on a full disk
    # raised "Slist already enabled?" and crashed the interpreter (issue #30.14).
    buffer = io.BytesIO()
    with h5py.File(buffer, "w") as f:
        f.attrs["complete"] = False
        for name, data in arrays.items():
            dataset = f.create_dataset(name, data=data, fletcher32=True,
                                       chunks=data.shape if data.size else None)
            dataset.attrs["sha256"] = array_digest(data)
        for attr, name in scalar_names.items():
            f.attrs[name] = scalars[attr]
        f.attrs["scalars_sha256"] = scalars_digest(scalars)
        for name, value in attrs.items():
            f.attrs[name] = value
        f.attrs["written_with"] = f"h5py {h5py.__version__}, HDF5 {h5py.version.hdf5_version}"
        f.flush()
        f.attrs["complete"] = True
    return write_bytes(path, buffer.getbuffer())
