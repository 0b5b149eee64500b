"""Every CSV and text file tengfield reads as input, through one reader: the recorded
excitation (its z column and the 3D model's lateral columns), the PSD table of a random
excitation, and fit's measured trace (:func:`tengfield.fit.read_trace`).

:func:`read_table` resolves the name, refuses a missing, oversized, UTF-16 or binary
file before parsing, drops a UTF-8 byte-order mark, skips blank lines and ``#``
comments, and refuses a row whose field count differs from the header's (naming its
line) and more than ``max_rows`` data rows (while reading). :meth:`CsvTable.column`
turns one column into floats, naming the line and data row of a cell that is not a
number. Each message starts with ``what``, the name the user gave.
"""
from __future__ import annotations

import csv
import math
import os
import re
import stat
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..files import file_kind, note_input
from ..errors import SceneError, header_described, same_name_in_file
from .constants import G
from .limits import (MAX_PSD_ROWS, MAX_RECORDED_ACCELERATION, MAX_RECORDED_BYTES,
                     MAX_RECORDED_DISPLACEMENT, MAX_RECORDED_ROWS, MAX_RECORDED_TIME,
                     MAX_STEP_FACTOR, MIN_RECORDED_ROWS, MIN_STEP_FRACTION)


def decode_utf8(blob: bytes, what: str) -> str:
    """UTF-8 text (a leading byte-order mark is dropped), or one-line SceneError naming
    ``what`` (every text file tengfield reads: scenes, recorded excitations, measured
    traces)."""
    if blob.startswith((b"\xff\xfe", b"\xfe\xff")):
        raise SceneError(f"{what} is UTF-16 text: save it as UTF-8")
    try:
        return blob.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        kind = "binary data" if b"\x00" in blob[:4096] else "not UTF-8 text"
        raise SceneError(f"{what} is {kind} (byte 0x{blob[exc.start]:02x} at offset "
                         f"{exc.start}): save it as UTF-8") from None


def check_file_size(path: Path, what: str, limit: int) -> None:
    """SceneError before reading when ``path`` has more than ``limit`` bytes."""
    size = path.stat().st_size
    if size > limit:
        raise SceneError(f"{what} has {size:,} bytes: allowed at most {limit:,} "
                         f"({limit / 1e6:g} MB, checked before reading; decimate or split it)")


def resolve_input(name: str, base_dir: Path | None, what: str) -> Path:
    """The path of input file ``name``: relative to ``base_dir`` (the scene's folder) and
    then confined to it (``..`` or a symlink leading out of it is refused: a scene cannot
    make tengfield read, and print parts of, a file elsewhere by a relative name); an
    absolute name is read as given. It must be a regular file: a directory, a FIFO or a
    device is named as such. One-line SceneError starting with ``what``."""
    path = Path(name)
    if not path.is_absolute() and base_dir is not None:
        path = Path(base_dir) / path
        try:
            inside = path.resolve().is_relative_to(Path(base_dir).resolve())
        except (OSError, RuntimeError):   # a symlink loop
            inside = False
        if not inside:
            raise SceneError(f"{what} leads outside the scene's folder ({str(base_dir)!r}): "
                             "a relative name must stay inside it; give an absolute path "
                             "to read a file elsewhere")
    shown = f" ({path})" if str(path) != name else ""
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise SceneError(f"{what}: no such file{shown}") from None
    except OSError as exc:
        raise SceneError(f"{what} could not be read: {exc.strerror or exc}{shown}") from None
    if not stat.S_ISREG(st.st_mode):
        raise SceneError(f"{what} is {file_kind(st.st_mode)}, not a regular file{shown}")
    return path


def read_text(name: str, base_dir: Path | None, what: str, max_bytes: int) -> str:
    """The UTF-8 text of file ``name`` (:func:`resolve_input`): a missing file, one of
    more than ``max_bytes`` bytes or one that cannot be read or decoded is a one-line
    SceneError starting with ``what``. The file is noted as an input of the command
    (:func:`tengfield.files.note_input`: never replaced by its outputs)."""
    path = resolve_input(name, base_dir, what)
    note_input(path)
    try:
        check_file_size(path, what, max_bytes)
        blob = path.read_bytes()
    except OSError as exc_:
        raise SceneError(f"{what} could not be read: {exc_.strerror or exc_}") from None
    return decode_utf8(blob, what)   # BOM dropped here


def check_header(fields: list[str], what: str) -> list[str]:
    """The stripped column names of a header line: a file separated by ';' or tabs and a
    name given twice are refused."""
    header = [f.strip() for f in fields]
    if len(header) == 1:   # a European spreadsheet's (;) or a scope's (tab) export
        for sep, called in ((";", "';'"), ("\t", "tabs")):
            if sep in header[0]:
                raise SceneError(f"{what} is separated by {called}, not by commas: "
                                 "save it as comma-separated with '.' decimals")
    seen = set()
    for i, col in enumerate(header):
        if col in seen:
            raise SceneError(f"{what}: the header names one column twice (columns "
                             f"{header.index(col) + 1} and {i + 1}): give each column its own name")
        seen.add(col)
    return header


def read_csv_rows(text: str, what: str, max_rows: int) -> tuple[list[str], list[tuple]]:
    """(header, [(line number, fields), ...]) of a comma-separated text: blank lines and
    ``#`` comments skipped; a row whose field count differs from the header's is refused
    naming its line; more than ``max_rows`` data rows are refused as soon as seen."""
    header: list[str] | None = None
    rows: list[tuple] = []
    for number, line in enumerate(text.splitlines(), start=1):
        line = line.split("#", 1)[0]
        if not line.strip():
            continue
        try:
            fields = next(csv.reader([line]))
        except csv.Error as exc:     # a cell over the module's 131,072-character limit
            raise SceneError(f"{what}: line {number} cannot be read as CSV ({exc}; "
                             f"{len(line):,} characters): a number takes a few") from None
        if header is None:
            header = check_header(fields, what)
            continue
        if len(fields) != len(header):
            raise SceneError(f"{what}: line {number} (data row {len(rows) + 1}) has "
                             f"{len(fields)} field(s): expected {len(header)}, as the header")
        rows.append((number, fields))
        if len(rows) > max_rows:
            raise SceneError(f"{what} has more than {max_rows:,} data rows: allowed at most "
                             f"{max_rows:,} (checked while reading; decimate or split it)")
    return header or [], rows


#: a number as a CSV cell may hold it: ASCII digits, '.', an exponent, nan or inf
_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|[+-]?(?:nan|inf|infinity)",
                     re.ASCII | re.IGNORECASE)


@dataclass(frozen=True)
class CsvTable:
    """A CSV file as read: ``header`` (stripped names; empty for an empty file) and
    ``rows`` ((line number, fields) per data row); ``what`` names it in messages."""
    what: str
    header: list
    rows: list

    def column(self, col: str, *, allow_blank: bool = False) -> np.ndarray:
        """Column ``col`` as floats; a cell that is not a number is refused naming its
        line, data row and text (blank: NaN with ``allow_blank``)."""
        j = self.header.index(col)
        out = np.empty(len(self.rows))
        for i, (number, fields) in enumerate(self.rows):
            cell = fields[j].strip()
            if not cell and allow_blank:
                out[i] = math.nan
                continue
            try:
                if not _NUMBER.fullmatch(cell):   # float() takes 1_5e-4 and non-ASCII digits
                    raise ValueError(cell)
                out[i] = float(cell)
            except ValueError:
                raise SceneError(f"{self.what}: column {col!r} holds a cell that is not a "
                                 f"number at line {number} (data row {i + 1}): expected a "
                                 "number (digits, '.', an exponent)") from None
        return out


def read_table(name: str, base_dir: Path | None, what: str, *, max_bytes: int,
               max_rows: int) -> CsvTable:
    """Read CSV file ``name`` (:func:`read_text`, :func:`read_csv_rows`)."""
    text = read_text(name, base_dir, what, max_bytes)
    header, rows = read_csv_rows(text, what, max_rows)
    return CsvTable(what, header, rows)


def check_magnitude(x: np.ndarray, limit: float, what: str, label: str, unit: str) -> None:
    """Refuse |x| > ``limit`` naming the first such data row and its value."""
    bad = np.flatnonzero(np.abs(x) > limit)
    if bad.size:
        raise SceneError(f"{what}: {label} holds {x[bad[0]]:g} {unit} at data row {bad[0] + 1}: "
                         f"allowed |x| <= {limit:g} {unit} (beyond it the numerics overflow; "
                         "check the column's unit)")


def check_time_steps(t: np.ndarray, what: str, *, row_offset: int = 0) -> None:
    """Times must increase, by steps of at least MIN_STEP_FRACTION x the median step (and
    more than 4 ulp of the times): the message names the data row and both values."""
    step = np.diff(t)
    if np.any(step <= 0):
        i = int(np.flatnonzero(step <= 0)[0])
        raise SceneError(f"{what}: time is not strictly increasing at data row "
                         f"{i + 2 + row_offset} ({float(t[i])!r} s then {float(t[i + 1])!r} s)")
    if step.size == 0:
        return
    median = float(np.median(step))
    ulp = 4.0 * np.spacing(np.maximum(np.abs(t[:-1]), np.abs(t[1:])))
    small = np.flatnonzero((step < MIN_STEP_FRACTION * median) | (step <= ulp))
    if small.size:
        i = int(small[0])
        raise SceneError(f"{what}: time step at data row {i + 2 + row_offset} is {step[i]:.3g} s "
                         f"({float(t[i])!r} s then {float(t[i + 1])!r} s), far below the data's resolution: "
                         f"allowed >= {MIN_STEP_FRACTION:g} x the median step "
                         f"{median:.3g} s (a duplicated or mistyped stamp?)")


def check_no_gaps(t: np.ndarray, what: str) -> None:
    """Refuse a time step above MAX_STEP_FACTOR x the median step (rows missing: the
    spline through the record would invent the table's motion there), naming the data
    rows on both sides, their times and the number of such gaps."""
    step = np.diff(t)
    if step.size == 0:
        return
    median = float(np.median(step))
    gaps = np.flatnonzero(step > MAX_STEP_FACTOR * median)
    if gaps.size:
        i = int(gaps[0])
        more = f" (and {gaps.size - 1} more)" if gaps.size > 1 else ""
        raise SceneError(f"{what}: a gap between data rows {i + 1} and {i + 2} ({t[i]:.9g} s "
                         f"then {t[i + 1]:.9g} s: {step[i] / median:.3g} x the median step "
                         f"{median:.3g} s){more}: allowed at most {MAX_STEP_FACTOR:g} x the "
                         "median step (the motion inside would be invented): fill the gap or "
                         "cut the record there")


# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class Record:
    """A recorded excitation as read: ``times`` [s], ``values`` (the signal column, [m]
    or [m/s^2]) and the lateral columns ``values_x``, ``values_y`` (None when not named)."""
    times: np.ndarray
    values: np.ndarray
    values_x: np.ndarray | None = None
    values_y: np.ndarray | None = None


#: the columns of a recorded excitation by [excitation] key, and how a message names
#: them (None: by the column's name)
RECORDED_COLUMNS = {"time_column": "time", "signal_column": "signal",
                    "signal_x_column": None, "signal_y_column": None}


def read_recorded(exc: dict, base_dir: Path | None) -> Record:
    """The CSV of ``[excitation] kind = "recorded"`` (``exc``: the section's SI values by
    attribute): the time and signal columns, and the lateral columns the 3D model drives
    the table with (signal_x_column, signal_y_column, when named), each checked as the
    signal is."""
    name = exc["file"]
    if not name:
        raise SceneError("[excitation] kind = 'recorded' needs file = 'name.csv'")
    what = f"[excitation] file = {name!r}"
    wanted = ["time_column", "signal_column"] + [
        key for key in ("signal_x_column", "signal_y_column") if exc[key]]
    path = resolve_input(name, base_dir, what)
    note_input(path)
    try:
        check_file_size(path, what, MAX_RECORDED_BYTES)
        blob = path.read_bytes()
    except OSError as exc_:
        raise SceneError(f"{what} could not be read: {exc_.strerror or exc_}") from None
    if not decode_utf8(blob, what).strip():     # checks the encoding (the text is dropped)
        raise SceneError(f"{what} is empty: expected a header line "
                         f"({exc['time_column']},{exc['signal_column']}) and at least "
                         f"{MIN_RECORDED_ROWS} data rows")
    head = decode_utf8(blob[:1 << 16], what) if len(blob) > 1 << 16 else None
    layout = _recorded_layout(head if head is not None else decode_utf8(blob, what), exc, what)
    if not layout.plain or layout.header_line > 1:     # an instrument's export
        del blob
        columns = _export_columns(exc, wanted, what, base_dir)
    else:
        columns = _fast_columns(blob, exc, wanted, what) if b"#" not in blob else None
        if columns is None:     # comments, or a row Arrow refuses: Python's reader names it
            columns = _python_columns(decode_utf8(blob, what), exc, wanted, what)
        del blob
    rows = len(columns["time_column"])
    if rows < MIN_RECORDED_ROWS:
        raise SceneError(f"{what} has {rows} data rows: at least "
                         f"{MIN_RECORDED_ROWS} are needed (the quintic spline of the table motion)")
    for key, arr in columns.items():
        bad = np.flatnonzero(~np.isfinite(arr))
        if bad.size:
            label = RECORDED_COLUMNS[key]
            raise SceneError(f"{what}: {label} column holds NaN or inf at data row {bad[0] + 1}"
                             if label else f"{what}: column {exc[key]!r} holds NaN or inf at "
                             f"data row {bad[0] + 1}")
    limit, unit = ((MAX_RECORDED_DISPLACEMENT, "m") if exc["signal"] == "displacement"
                   else (MAX_RECORDED_ACCELERATION, "m/s^2"))
    for key in wanted[1:]:
        check_magnitude(columns[key], limit, what, f"{exc['signal']} column {exc[key]!r}", unit)
    t = columns["time_column"]
    check_magnitude(t, MAX_RECORDED_TIME, what, f"time column {exc['time_column']!r}", "s")
    check_time_steps(t, what)
    check_no_gaps(t, what)
    return Record(t, columns["signal_column"], columns.get("signal_x_column"),
                  columns.get("signal_y_column"))


def _check_columns(header: list[str], exc: dict, wanted: list[str]) -> None:
    for col_key in wanted:
        col = exc[col_key]
        if col not in header:
            raise SceneError(f"[excitation] {col_key} = {col!r} is not a column of "
                             f"{exc['file']!r}; {header_described(header)}"
                             + same_name_in_file(col, header))


def _python_columns(text: str, exc: dict, wanted: list[str], what: str) -> dict:
    """The wanted columns by Python's csv module (comments; the messages naming a line)."""
    header, rows = read_csv_rows(text, what, MAX_RECORDED_ROWS)
    del text
    _check_columns(header, exc, wanted)
    table = CsvTable(what, header, rows)
    return {key: table.column(exc[key], allow_blank=True) for key in wanted}


#: bytes Arrow parses at a time when reading a recorded excitation
ARROW_BLOCK_BYTES = 1 << 22


def _fast_columns(blob: bytes, exc: dict, wanted: list[str], what: str) -> dict | None:
    """The wanted columns of a comment-free CSV by Apache Arrow, only those columns (a
    190 MB file of 30 columns: 2 s and ~0.6 GB instead of 300 s and 3.7 GB); None when
    Arrow refuses something (a short row, a cell that is not a number, ...): Python's
    reader then names it by its line.

    Arrow's serial reader (``read_csv``, ``use_threads=False``) joins its read-ahead thread
    before it returns or raises; the streaming reader (``open_csv``) left a read-ahead task
    on Arrow's I/O pool when it refused a block, and a process ending right after it
    aborted in about 1 of 7 runs on a loaded machine ("terminate called without an active
    exception", exit 134; apache/arrow#34314)."""
    import pyarrow as pa
    import pyarrow.csv as pa_csv

    pos, line = 0, b""
    while pos < len(blob) and not line.strip():       # the header: the first non-blank line
        end = blob.find(b"\n", pos)
        end = len(blob) if end < 0 else end
        line, pos = blob[pos:end], end + 1
    try:
        fields = next(csv.reader([line.decode("utf-8-sig")]))
    except csv.Error:
        return None        # Python's reader names the line
    header = check_header(fields, what)
    _check_columns(header, exc, wanted)
    names = list(dict.fromkeys(exc[key] for key in wanted))
    body = pa.py_buffer(memoryview(blob)[min(pos, len(blob)):])
    convert = pa_csv.ConvertOptions(include_columns=names, null_values=[""],
                                    column_types={n: pa.float64() for n in names},
                                    strings_can_be_null=False, quoted_strings_can_be_null=True)
    try:
        table = pa_csv.read_csv(pa.BufferReader(body), read_options=pa_csv.ReadOptions(
            column_names=header, block_size=ARROW_BLOCK_BYTES, use_threads=False),
            convert_options=convert)
    except (pa.ArrowInvalid, pa.ArrowNotImplementedError):
        return None
    if table.num_rows > MAX_RECORDED_ROWS:
        raise SceneError(f"{what} has more than {MAX_RECORDED_ROWS:,} data rows: allowed "
                         f"at most {MAX_RECORDED_ROWS:,} (decimate or split it)")
    return {key: table.column(exc[key]).to_numpy().astype(np.float64) for key in wanted}


def read_psd(name: str, base_dir: Path | None) -> tuple[np.ndarray, np.ndarray]:
    """A PSD table (``[excitation] psd_file``): header ``frequency_hz`` and one of
    ``psd_g2_per_hz`` or ``psd_m2_per_s4_per_hz``; returns (frequencies [Hz], values
    [(m/s^2)^2/Hz]), refusing a table that holds no power."""
    where = f"[excitation] psd_file = {name!r}"
    table = read_table(name, base_dir, where, max_bytes=MAX_RECORDED_BYTES, max_rows=MAX_PSD_ROWS)
    header = table.header
    units = {"psd_g2_per_hz": G**2, "psd_m2_per_s4_per_hz": 1.0}
    value_cols = [h for h in header if h in units]
    if len(value_cols) > 1:
        raise SceneError(f"{where}: the header has both psd_g2_per_hz and "
                         "psd_m2_per_s4_per_hz: keep exactly one of them")
    if "frequency_hz" not in header or len(value_cols) != 1:
        raise SceneError(f"{where}: the header needs the columns frequency_hz "
                         "and one of psd_g2_per_hz, psd_m2_per_s4_per_hz")
    freqs = table.column("frequency_hz")
    vals = table.column(value_cols[0])
    if freqs.size < 2:
        raise SceneError(f"{where} has {freqs.size} data rows: at least 2 are needed")
    for i, (f, v) in enumerate(zip(freqs, vals)):
        if not (math.isfinite(f) and math.isfinite(v)) or not 0.0 < f <= 1e6 or not 0.0 <= v <= 1e12:
            raise SceneError(f"{where}: data row {i + 1}: frequency_hz = {f:g}, "
                             f"{value_cols[0]} = {v:g}; allowed frequency in (0, 1e6] Hz, "
                             "PSD in [0, 1e12]")
        if i and f <= freqs[i - 1]:
            raise SceneError(f"{where}: data row {i + 1}: frequency {f:g} Hz is not above the "
                             f"previous row's {freqs[i - 1]:g} Hz")
    if not np.any(vals > 0.0):
        raise SceneError(f"[excitation] psd_file = {name!r} holds no power (every "
                         "PSD value is 0)")
    if not np.any((vals[1:] > 0.0) & (vals[:-1] > 0.0)):
        raise SceneError(f"[excitation] psd_file = {name!r} holds no power: between its rows "
                         "the PSD is interpolated log-log, so a segment with a zero end is zero "
                         "everywhere; give two neighbouring rows > 0")
    return freqs, vals * units[value_cols[0]]


# ---------------------------------------------------------------------------
# instruments' exports (issue #39): metadata lines before the header, ';' or tab
# separators, decimal commas, units in the header
#: separators an export may use, in the order they are tried
DELIMITERS = (",", ";", "\t")
#: a header cell with its unit: ``TIME [s]``, ``CH1(V)``, ``Current (nA)``
_UNIT = re.compile(r"^(?P<name>.*?\S)\s*[\[(]\s*(?P<unit>[^\[\]()]+?)\s*[\])]\s*$")
#: a number written with a decimal comma: ``-1,25``, ``3,0E-4``
_DECIMAL_COMMA = re.compile(r"[+-]?\d*,\d+(?:[eE][+-]?\d+)?|[+-]?\d+,(?:[eE][+-]?\d+)?")
#: lines looked at for the header when it is not given
MAX_HEADER_SEARCH = 200


def split_unit(cell: str) -> tuple[str, str]:
    """``"TIME [s]"`` -> ``("TIME", "s")``; a name without a unit -> ``(name, "")``."""
    cell = cell.strip()
    m = _UNIT.match(cell)
    return (m["name"], m["unit"].strip()) if m else (cell, "")


def _split(line: str, delimiter: str) -> list[str]:
    try:
        return next(csv.reader([line], delimiter=delimiter))
    except (csv.Error, StopIteration):
        return []


@dataclass(frozen=True)
class Export:
    """How an instrument's export is laid out: ``header_line`` (1-based), ``delimiter``,
    ``decimal_comma``, ``units`` (column name -> the unit its header gives, "" none)."""
    header_line: int
    delimiter: str
    decimal_comma: bool
    units: dict

    @property
    def plain(self) -> bool:
        """A comma-separated file with its header on the first line and no units: the
        fast reader's."""
        return (self.delimiter == "," and not self.decimal_comma
                and not any(self.units.values()))


def _names_time(cells: list[str], time_column: str) -> bool:
    wanted = split_unit(time_column)[0].casefold()
    return any(split_unit(c)[0].casefold() == wanted for c in cells)


def find_export(lines: list[str], what: str, time_column: str, header_row: int = 0) -> Export:
    """The layout of an export whose lines are ``lines``: the header is line
    ``header_row`` (1-based) when given, else the first line naming ``time_column`` (with
    or without its unit), else the first non-blank line (the plain CSV's rule). The
    separator is the one that splits the header into cells naming the time column (else
    the one giving the most cells); with ';' or tabs, numbers may use a decimal comma.
    Messages name the line and what was expected, never the file's text."""
    if header_row:
        if header_row > len(lines):
            raise SceneError(f"{what}: header_row = {header_row}, but the file has "
                             f"{len(lines)} line(s): expected a line number in [1, {len(lines)}]")
        number = header_row
    else:
        number = 0
        first = 0
        for i, line in enumerate(lines[:MAX_HEADER_SEARCH], start=1):
            text = line.split("#", 1)[0] if line.lstrip().startswith("#") else line
            if not text.strip():
                continue
            first = first or i
            if any(_names_time(_split(text, d), time_column) for d in DELIMITERS):
                number = i
                break
        number = number or first or 1
    line = lines[number - 1] if lines else ""
    if not line.strip():
        raise SceneError(f"{what}: line {number} is blank: expected the header line "
                         "(the column names)")
    splits = {d: _split(line, d) for d in DELIMITERS}
    named = [d for d in DELIMITERS if _names_time(splits[d], time_column)]
    delimiter = named[0] if named else max(DELIMITERS, key=lambda d: len(splits[d]))
    if not named and len(splits[delimiter]) == 1:
        delimiter = ","
    units = {}
    for cell in splits[delimiter]:
        name, unit = split_unit(cell)
        units[name] = unit
    decimal_comma = delimiter != "," and any(
        _DECIMAL_COMMA.fullmatch(c.strip())
        for ln in lines[number:number + 50] for c in _split(ln, delimiter))
    return Export(number, delimiter, decimal_comma, units)


def read_export(name: str, base_dir: Path | None, what: str, *, time_column: str,
                header_row: int = 0, max_bytes: int, max_rows: int) -> tuple[CsvTable, Export]:
    """An instrument's export as a :class:`CsvTable` (header: the column names without
    their units; cells with '.' decimals) and its :class:`Export` layout (the units).
    Lines before the header (an oscilloscope's metadata) are skipped; blank lines and
    ``#`` comments too. A row with another number of cells than the header is refused
    naming its line and the count expected."""
    text = read_text(name, base_dir, what, max_bytes)
    lines = text.splitlines()
    del text
    layout = find_export(lines, what, time_column, header_row)
    header = [split_unit(c)[0] for c in _split(lines[layout.header_line - 1], layout.delimiter)]
    seen = set()
    for i, col in enumerate(header, start=1):
        if col in seen:
            raise SceneError(f"{what}: line {layout.header_line} (the header) names one "
                             f"column twice (cell {i}): expected distinct column names")
        seen.add(col)
    rows: list[tuple] = []
    for number in range(layout.header_line + 1, len(lines) + 1):
        line = lines[number - 1].split("#", 1)[0]
        if not line.strip():
            continue
        fields = _split(line, layout.delimiter)
        if len(fields) == len(header) + 1 and not fields[-1].strip():
            fields = fields[:-1]                       # a trailing separator
        if len(fields) != len(header):
            sep = {",": "','", ";": "';'", "\t": "tabs"}[layout.delimiter]
            raise SceneError(f"{what}: line {number} (data row {len(rows) + 1}) has "
                             f"{len(fields)} field(s): expected {len(header)} (separated "
                             f"by {sep}, as the header on line {layout.header_line})")
        if layout.decimal_comma:
            fields = [f.strip().replace(",", ".") if _DECIMAL_COMMA.fullmatch(f.strip())
                      else f for f in fields]
        rows.append((number, fields))
        if len(rows) > max_rows:
            raise SceneError(f"{what} has more than {max_rows:,} data rows: allowed at most "
                             f"{max_rows:,} (checked while reading; decimate or split it)")
    return CsvTable(what, header, rows), layout


#: a time unit as an export's header writes it -> seconds
HEADER_TIME_UNITS = {"s": 1.0, "sec": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6, "μs": 1e-6,
                     "ns": 1e-9}


#: a recorded signal's unit as an export's header writes it -> SI, by [excitation] signal
HEADER_SIGNAL_UNITS = {"displacement": {"m": 1.0, "mm": 1e-3, "um": 1e-6, "µm": 1e-6},
                       "acceleration": {"m/s^2": 1.0, "m/s2": 1.0, "m/s²": 1.0, "g": G}}


def _recorded_layout(text: str, exc: dict, what: str) -> Export:
    """:func:`find_export` of a recorded excitation (a truncated head may cut the last
    line: only the header and a few rows after it are looked at)."""
    lines = text.splitlines()[:MAX_HEADER_SEARCH + 60]
    layout = find_export(lines, what, exc["time_column"], exc.get("header_row", 0))
    first = next((i for i, ln in enumerate(lines, start=1)
                  if ln.split("#", 1)[0].strip()), 1)
    return layout if layout.header_line != first or not layout.plain else \
        Export(1, layout.delimiter, layout.decimal_comma, layout.units)


def _export_columns(exc: dict, wanted: list[str], what: str, base_dir) -> dict:
    """The wanted columns of an instrument's export (:func:`read_export`) in SI: a
    header's unit (``TIME [ms]``, ``Z (mm)``) converts its column."""
    table, layout = read_export(exc["file"], base_dir, what, time_column=exc["time_column"],
                                header_row=exc.get("header_row", 0),
                                max_bytes=MAX_RECORDED_BYTES, max_rows=MAX_RECORDED_ROWS)
    names = {key: split_unit(exc[key])[0] for key in wanted}
    for key, col in names.items():
        if col not in table.header:
            raise SceneError(f"[excitation] {key} = {exc[key]!r} is not a column of "
                             f"{exc['file']!r}: expected it on the header line "
                             f"{layout.header_line} (with or without a unit)")
    out = {}
    for key, col in names.items():
        unit = layout.units.get(col, "")
        units = HEADER_TIME_UNITS if key == "time_column" else HEADER_SIGNAL_UNITS[exc["signal"]]
        if unit and unit not in units:
            raise SceneError(f"{what}: the header gives column {col!r} a unit tengfield does "
                             f"not know: expected one of {', '.join(units)}")
        out[key] = table.column(col, allow_blank=True) * (units[unit] if unit else 1.0)
    return out
