"""How tengfield writes one file: every output goes through here.

* :func:`atomic_path`: a temporary file next to the target, moved over it
  (``os.replace``) only when complete: a reader never sees half a file;
  :func:`writable_target` refuses to write into a pipe or a device, or through a
  symlink;
* :func:`write_text`, :func:`write_json` (strict JSON, NaN -> null) and
  :func:`scene_toml` (a scene dict as TOML: fitted, recommended and best scenes),
  written atomically;
* CSV: :func:`write_csv` for tables of numbers (Apache Arrow's compiled writer:
  every double as its shortest round-trip decimal, or a printf format per column),
  and :func:`write_rows` for small tables of text cells (Python's ``csv`` module:
  a cell holding a comma, a quote or a line break is quoted, which Arrow refuses
  to write unquoted and quotes every text cell to allow). Both write a plain
  comma-separated header.

The output sets (``waveforms.csv`` with ``summary.json``, the dynamics files, ...)
are put together in :mod:`tengfield.io` and in the ``output`` module of each
command's package; the output directories in :mod:`tengfield.outputs`.
"""
from __future__ import annotations

import csv
import json
import os
import re
import stat
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from ._json import jsonable
from .errors import OutputError

_KINDS = {stat.S_IFIFO: "a named pipe (FIFO)", stat.S_IFCHR: "a character device",
          stat.S_IFBLK: "a block device", stat.S_IFSOCK: "a socket", stat.S_IFLNK: "a symlink",
          stat.S_IFDIR: "a directory", stat.S_IFREG: "a file"}


#: the files this process read as input (scene files, recorded excitations, PSD tables,
#: measured traces) as (st_dev, st_ino): an output directory never removes or replaces
#: one of them (:class:`tengfield.outputs.StagedOutput`)
_INPUTS: dict[tuple[int, int], str] = {}


def note_input(path: str | Path) -> None:
    """Record that this process reads ``path`` as an input (every reader of an input
    file calls it before reading)."""
    try:
        st = os.stat(path)
    except OSError:
        return
    _INPUTS[(st.st_dev, st.st_ino)] = str(path)


def input_named(path: str | Path) -> str | None:
    """The name an input was read under when ``path`` is the same file, else None."""
    try:
        st = os.stat(path)
    except OSError:
        return None
    return _INPUTS.get((st.st_dev, st.st_ino))


def forget_inputs() -> None:
    """Start a new command's list of inputs."""
    _INPUTS.clear()


def file_kind(mode: int) -> str:
    """``a named pipe (FIFO)``, ``a character device``, ... of an ``st_mode``."""
    return _KINDS.get(stat.S_IFMT(mode), "a special file")


def writable_target(path: str | Path) -> Path:
    """``path``, made safe to write a file at: a symlink there is removed (a file is
    written in its place, never through it to its target); a directory, FIFO or device
    node is refused (:class:`tengfield.errors.OutputError`: nothing is written into a
    pipe or a device). The staging directory of ``-o DIR`` (under mpirun too) holds none
    of these; the Python API writes where it is told. :func:`write_csv` writes where it is
    told (``/dev/full`` included); :func:`atomic_path` and the writers of an output
    set check."""
    path = Path(path)
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        return path
    if stat.S_ISLNK(st.st_mode):
        path.unlink()
    elif not stat.S_ISREG(st.st_mode):
        raise OutputError(f"{str(path)!r} is {file_kind(st.st_mode)}, not a regular file: "
                          "nothing was written there")
    return path


@contextmanager
def atomic_path(path: str | Path):
    """Yield a temporary path next to ``path`` (same suffix, so plotting libraries
    pick the format); it replaces ``path`` (``os.replace``) when the block ends
    without an exception, else it is removed: a reader never sees half a file."""
    path = writable_target(path)
    tmp = path.with_name(f".{path.stem}.tmp-{os.getpid()}{path.suffix}")
    try:
        yield tmp
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


def write_text(path: str | Path, text: str) -> Path:
    """``text`` to ``path``, atomically."""
    path = Path(path)
    with atomic_path(path) as tmp:
        tmp.write_text(text)
    return path


def write_json(path: str | Path, data) -> Path:
    """``data`` as indented strict JSON (NaN -> null, see :func:`tengfield._json.jsonable`)."""
    return write_text(path, json.dumps(jsonable(data), indent=2) + "\n")


# ---------------------------------------------------------------------------
# TOML
def toml_value(value) -> str:
    """A TOML literal for a bool, int, float (``inf``, ``-inf``, ``nan`` included), string
    or list of them; ``TypeError`` for anything else."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return repr(value)                # always has ".", "e", "inf" or "nan": a TOML float
    if isinstance(value, str):
        return json.dumps(value)          # a TOML basic string is a JSON string
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    if isinstance(value, dict):           # an inline table (a table inside a list)
        return "{ " + ", ".join(f"{toml_key(k)} = {toml_value(v)}" for k, v in value.items()
                                if v is not None) + " }"
    raise TypeError(f"cannot write {value!r} to TOML")


_BARE_KEY = re.compile(r"^[A-Za-z0-9_-]+$")


def toml_key(key) -> str:
    """A TOML key: bare when it can be (``samples``), else quoted
    (``"contact.restitution"``: a dotted name inside ``[uncertainty.vary]`` is one key)."""
    key = str(key)
    return key if _BARE_KEY.match(key) else json.dumps(key)


def scene_dir(source: str) -> Path:
    """The folder a scene's relative file names resolve from: its file's folder, or the
    working directory for a scene without a file (``"<default>"``, ``"<dict>"``), as
    :meth:`tengfield.scene.Scene.with_values` reads them."""
    if source in ("<default>", "<dict>", "") or source.startswith("<"):
        return Path.cwd()
    return Path(source).parent


def _is_file_key(key: str) -> bool:
    """A key naming a file (``file``, ``psd_file``, ...)."""
    return key == "file" or key.endswith("_file")


def _file_value(key: str, value, base_dir: Path | None):
    """``value`` of a file key as an absolute path (resolved from ``base_dir``), so that
    the written scene runs from wherever it lives (issue #30.6: a fitted.toml in ``-o``
    kept ``file = "rec.csv"`` relative to the original scene and did not run)."""
    if base_dir is None or not _is_file_key(key) or not isinstance(value, str) or not value:
        return value
    if os.path.isabs(value):
        return value
    return os.path.abspath(os.path.join(os.fspath(base_dir), value))


def scene_toml(data: dict, header: str = "", *, base_dir: str | Path | None = None) -> str:
    """TOML text of a scene dict (``{section: {key: value}}``): ``header`` as comment
    lines, then one table per section, each written whole: its scalars, then each
    sub-table under its own header (``[uncertainty.vary]``, ``[design.excitation]``,
    nested as deep as given), so that reading the text back gives ``data`` (issue #43.1:
    sub-tables were dropped while their parent's scalars stayed). Left out: an entry at
    the top level that is no section, a None. ``base_dir``: the folder the original
    scene's relative file names (``file``, ``psd_file``) resolve from
    (:func:`scene_dir`); they are written as absolute paths, since the written scene
    lives elsewhere (in ``-o``)."""
    lines = [f"# {line}" for line in header.splitlines()]
    base = None if base_dir is None else Path(base_dir)

    def table(path: list[str], values: dict) -> None:
        lines.extend(["", "[" + ".".join(toml_key(p) for p in path) + "]"])
        lines.extend(f"{toml_key(key)} = {toml_value(_file_value(key, v, base))}"
                     for key, v in values.items() if v is not None and not isinstance(v, dict))
        for key, v in values.items():
            if isinstance(v, dict):
                table([*path, key], v)

    for sec, values in data.items():
        if isinstance(values, dict):
            table([sec], values)
    return "\n".join(lines).lstrip("\n") + "\n"


# ---------------------------------------------------------------------------
# CSV
#: rows formatted and written at a time by :func:`write_csv` with ``formats`` (bounds
#: the memory of the text of a long run)
FORMAT_BLOCK_ROWS = 1 << 16


def write_csv(path: str | Path, header: list[str], columns: list, *,
              formats: dict[str, str] | None = None, append: bool = False) -> Path:
    """CSV of equal-length columns: floats as their shortest round-trip decimal (full
    double precision: ``float(text)`` gives the double back; ``1e-05`` is written
    ``0.00001``, ``2.5e-07`` as ``2.5e-7``), integers as integers, booleans as 0/1,
    strings as they are (no quoting: they must not contain commas, quotes or line
    breaks; a table of text cells goes through :func:`write_rows`). A NaN (a value that
    does not exist, e.g. the exit time of a contact still open when the run ends) is an
    empty cell, the missing value of spreadsheets, Origin and pandas; ±inf is written
    ``inf``/``-inf``. The header is the plain comma-separated names. ``formats`` gives a column (by name) a printf format
    instead (``"%.10g"``: what ``numpy.savetxt`` writes with it).

    Formatted and written by Apache Arrow's CSV writer (compiled, 75 ns per number:
    600k impacts in 0.2 s, 6x faster than Python's ``repr``). Written where it is
    told: in place (after :func:`writable_target`) or inside :func:`atomic_path`.
    ``append``: the rows go at the end of ``path``, without a header (a table written a
    chunk at a time)."""
    import pyarrow as pa
    import pyarrow.csv as pa_csv

    formats = formats or {}
    arrays = []
    for name, col in zip(header, columns, strict=True):
        if name in formats:                 # formatted block by block, below
            arrays.append(np.asarray(col))
        elif isinstance(col, pa.Array):     # e.g. a dictionary (categorical) column
            arrays.append(col)
        else:
            arrays.append(_arrow_array(col))
        if len(arrays[-1]) != len(arrays[0]):
            raise ValueError(f"write_csv: column {name!r} has {len(arrays[-1])} rows, "
                             f"the first one {len(arrays[0])}")
    options = pa_csv.WriteOptions(include_header=False, quoting_style="none")
    rows = len(arrays[0]) if arrays else 0
    if formats and rows:
        blocks = [[pa.array([formats[name] % v if v == v else ""   # NaN: an empty cell
                             for v in a[start:start + FORMAT_BLOCK_ROWS].tolist()],
                            type=pa.string()) if name in formats
                   else a.slice(start, FORMAT_BLOCK_ROWS) for name, a in zip(header, arrays)]
                  for start in range(0, rows, FORMAT_BLOCK_ROWS)]
    else:
        blocks = [[pa.array([], type=pa.string()) if name in formats else a
                   for name, a in zip(header, arrays)]]
    try:
        with pa.OSFile(str(path), "ab" if append else "wb") as sink:
            if not append:
                sink.write((",".join(header) + "\n").encode())
            for block in blocks:
                table = pa.Table.from_arrays(block, names=list(header))
                pa_csv.write_csv(table, sink, write_options=options)
    except OSError as exc:   # Arrow's: "Error writing bytes to file. Detail: [errno 28] ..."
        if exc.errno:
            raise OSError(exc.errno, os.strerror(exc.errno), str(path)) from None
        raise
    return Path(path)


def _arrow_array(col):
    import pyarrow as pa

    values = np.asarray(col)
    if values.dtype == bool:
        values = values.astype(np.int8)
    if values.dtype.kind == "U":
        return pa.array(values, type=pa.string())
    if values.dtype.kind == "O":
        return pa.array([str(v) for v in values.tolist()], type=pa.string())
    return pa.array(values, from_pandas=True)   # float NaN -> null: an empty cell


def write_rows(path: str | Path, header: list[str], rows) -> Path:
    """A table of text cells (``rows``: sequences in the order of ``header``; a number
    is written as ``str`` gives it), atomically, by Python's ``csv`` module: a cell with
    a comma, a quote or a line break is quoted."""
    with atomic_path(path) as tmp, open(tmp, "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(header)
        writer.writerows(rows)
    return Path(path)


# ---------------------------------------------------------------------------
# whose files an output directory holds (issue #42)
#: in -o DIR: the name of the tengfield command whose files DIR holds (written with them)
COMMAND_RECORD = ".tengfield-command"


def record_command(staging: str | Path, command: str) -> None:
    """Note in the staging directory of ``-o DIR`` which command writes its files (moved
    into DIR with them, listed in its manifest)."""
    Path(staging, COMMAND_RECORD).write_text(command + "\n")


def refuse_another_commands_directory(target: str | Path, command: str,
                                      option: str = "-o") -> None:
    """Raise :class:`~tengfield.errors.OutputError` (one line) when ``-o DIR`` holds the
    files of a different tengfield command: writing there would remove them (a
    directory keeps one command's complete set). Nothing is checked for a DIR with no
    record (new, or not written by tengfield)."""
    from .errors import OutputError

    record = Path(target, COMMAND_RECORD)
    try:
        owner = record.read_text().strip() if record.is_file() else ""
    except OSError:
        return
    if not owner or owner == command:
        return
    manifest = Path(target, ".tengfield-manifest.json")
    try:
        names = [n for n in json.loads(manifest.read_text()).get("files", [])
                 if n != COMMAND_RECORD and Path(target, n).is_file()]
    except (OSError, ValueError, AttributeError):
        names = []
    shown = ", ".join(names[:3]) + (", ..." if len(names) > 3 else "")
    raise OutputError(f"{option} {str(target)!r} holds the files of `tengfield {owner}`"
                      + (f" ({shown})" if shown else "")
                      + f"; `tengfield {command}` would replace them: nothing was written; "
                        f"choose another {option} directory")


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
