"""The surrogates on disk, on the axis and over (z, r): the HDF5 format, with checksums
and structure checks.

:func:`write_table` (:mod:`.output`) writes atomically (temporary file + ``os.replace``);
every data array is stored with HDF5's Fletcher-32 filter and the SHA-256
of its bytes, and the scalars with a SHA-256 of their own. :func:`read_table`
trusts a file only if it is complete, of this format, for the expected
scene and solver, every checksum matches and the data make sense
(:func:`check_table`: positions sorted from 0 to the stroke, consistent
shapes, finite values, each C symmetric positive definite with C_lu < 0,
induced fractions in [-1, 0]). A file of the layout before the per-unit one (1-D
format 3, (z, r) format 1: charges in C and the ball charge they were solved at) is
read and converted (:func:`per_unit_charge`). Where the files live and when one
is reused: :mod:`tengfield.surrogate.cache`. The (z, r) file (``kind = "zr"``) has
the same rules (:func:`write_radial_table`, :func:`read_radial_table`,
:func:`check_radial_table`: every offset's column passes :func:`check_table`).
"""
from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from ..files.hdf5 import array_digest, scalars_digest, write_checked_file  # noqa: F401
from .layout import (ARRAYS, ARRAYS_ZR, LINE_CHECK_INDEX, OLD_BALL_CHARGE,  # noqa: F401
                     OLD_CHARGE_ARRAY, OPTIONAL_ARRAYS, OPTIONAL_SCALARS_ZR, SCALAR_TYPES,
                     SCALAR_TYPES_ZR, SCALARS, SCALARS_ZR, _SHAPES, old_layout, typed_scalars)
from .output import write_table  # noqa: F401 - written beside the figure, read here
from .provenance import (FORMAT_VERSION, FORMAT_VERSION_ZR, OLD_FORMAT_VERSIONS,
                         OLD_FORMAT_VERSIONS_ZR)
from .table import GRID_TAILS, RadialTable, SurrogateError, SurrogateTable, grid_tails

# ---------------------------------------------------------------------------
# checksums and structure
def check_shapes(arrays: dict) -> None:
    """Raise :class:`SurrogateError` unless the per-position ``arrays`` (table attribute
    -> array) have one length and the shapes of :data:`ARRAYS`."""
    positions = np.asarray(arrays["positions"])
    n = positions.shape[0] if positions.ndim == 1 else -1
    induced = np.shape(arrays["induced_fraction"])
    electrodes = induced[1] if len(induced) == 2 and induced[1] in (1, 2) else 2
    for attr, tail in _SHAPES.items():
        if attr == "capacitance":            # the pair's (2, 2), one electrode's (1, 1)
            tail = (electrodes, electrodes)
        elif attr == "induced_fraction":
            tail = (electrodes,)
        shape = np.shape(arrays[attr])
        if n < 0 or shape != (n, *tail):
            raise SurrogateError(f"array {ARRAYS[attr]!r} has shape {shape}, expected "
                                 f"{(max(n, 0), *tail)}")


def check_axis(values: np.ndarray, end: float, name: str, end_name: str) -> None:
    """Raise :class:`SurrogateError` unless the sample coordinates ``values`` [m], at
    least two, ascend strictly from 0 to ``end`` [m] > 0 (``name``: what one value is,
    ``end_name``: what ``end`` is, for the message)."""
    n = np.size(values)
    if n < 2:
        raise SurrogateError(f"{n} {name}(s): at least 2 are needed")
    # float(): numpy 2 would print np.float64(...) in the message
    if not (np.isfinite(end) and end > 0.0):
        raise SurrogateError(f"{end_name} {float(end)!r} m is not positive")
    if not np.all(np.isfinite(values)) or not np.all(np.diff(values) > 0.0):
        raise SurrogateError(f"{name}s are not strictly ascending")
    if values[0] != 0.0 or abs(values[-1] - end) > 1e-12 * end:
        raise SurrogateError(f"{name}s run from {float(values[0])!r} to {float(values[-1])!r} "
                             f"m, not from 0 to the {end_name} {float(end)!r} m")


def check_table(table: SurrogateTable) -> None:
    """Raise :class:`SurrogateError` (reason only) unless ``table`` makes sense.

    Positions strictly ascending from 0 to the stroke, arrays of one length
    and the right shapes, finite values, each C symmetric positive definite
    with C_lu < 0, each induced fraction (charge per unit ball charge) in [-1, 0] (to 1 %).
    """
    check_shapes({attr: getattr(table, attr) for attr in ARRAYS})
    z = table.positions
    check_axis(z, float(table.stroke), "position", "stroke")
    C, fractions = table.capacitance, table.induced_fraction
    if not (np.all(np.isfinite(C)) and np.all(np.isfinite(fractions))):
        raise SurrogateError("non-finite capacitance or induced fraction")
    if C.shape[1] == 1:                 # the single-electrode cell: C_ll > 0
        bad = ~(C[:, 0, 0] > 0)
    else:
        c_ll, c_lu, c_ul, c_uu = C[:, 0, 0], C[:, 0, 1], C[:, 1, 0], C[:, 1, 1]
        scale = np.maximum(np.abs(c_ll), np.abs(c_uu))
        bad = ~((np.abs(c_lu - c_ul) <= 1e-12 * scale) & (c_ll > 0) & (c_uu > 0) & (c_lu < 0)
                & (c_ll * c_uu - c_lu * c_ul > 0))
    if np.any(bad):
        i = int(np.argmax(bad))
        raise SurrogateError(f"the capacitance matrix at z = {z[i]:.6g} m is not symmetric "
                             "positive definite with C_lu < 0")
    slack = 1e-2
    bad = np.any((fractions > slack) | (fractions < -1.0 - slack), axis=1)
    if np.any(bad):
        i = int(np.argmax(bad))
        raise SurrogateError(f"the induced fractions at z = {z[i]:.6g} m are not between -1 "
                             "and 0 (the induced charges not between 0 and minus the ball "
                             "charge)")


def per_unit_charge(arrays: dict, scalars: dict, version: int) -> dict:
    """Convert, in place, what a file of the old layout (``version``: 1-D format 3, (z, r)
    format 1) holds to today's: ``induced_fraction = induced_charge / ball_charge``
    (the field is linear in the ball's charge), the ball charge dropped from the
    scalars. Returns ``{"format": version, "ball_charge_C": Q}`` for the provenance.
    :class:`SurrogateError` for a ball charge of 0 (the charges then say nothing per
    unit charge) or a non-finite one."""
    (charge_attr,) = OLD_CHARGE_ARRAY
    (ball_attr,) = OLD_BALL_CHARGE
    ball_charge = float(scalars.pop(ball_attr))
    if ball_charge == 0.0 or not np.isfinite(ball_charge):
        raise SurrogateError(
            f"was written by an older tengfield (format {version}: charges in C) for a ball "
            f"charge of {ball_charge!r} C, so it holds no charge per unit ball charge: solve "
            "it again (tengfield precompute --force, or delete the file)")
    arrays["induced_fraction"] = np.asarray(arrays.pop(charge_attr), dtype=float) / ball_charge
    return {"format": int(version), "ball_charge_C": ball_charge}


# ---------------------------------------------------------------------------
# HDF5 file
def _import_h5py():
    """``h5py``, Debian's build (:func:`tengfield.files.hdf5.import_h5py`; a pip wheel
    beside dolfinx is a :class:`SurrogateError`)."""
    from ..files.hdf5 import import_h5py

    return import_h5py(SurrogateError)


def _read_checked(f, name: str) -> np.ndarray:
    """Dataset ``name`` of open file ``f``, its SHA-256 checked (Fletcher-32 by HDF5).

    Before any byte is read, what its header claims is checked against what the file
    holds (a bit flip in a dimension claimed 9 GB of a 76 kB file, and reading it took
    24 GB): a numeric dtype of at most 8 bytes, chunked as written (one chunk of the
    dataset's shape), and no more bytes than are stored (no compression is written:
    the stored size is the data plus Fletcher-32's 4 bytes) nor than the file has."""
    if name not in f:
        raise SurrogateError(f"array {name!r} is missing")
    try:    # newer HDF5 (Debian 13) refuses a dimension beyond its maximum when opening
        dataset = f[name]
        shape, dtype = dataset.shape, dataset.dtype
    except (KeyError, OSError, ValueError) as exc:
        raise SurrogateError(f"array {name!r}: its header is damaged (not read): "
                             f"{str(exc).splitlines()[0] if str(exc) else type(exc).__name__}"
                             ) from None
    if shape is None or dtype.kind not in "biuf" or dtype.itemsize > 8:
        raise SurrogateError(f"array {name!r} has dtype {dtype} and shape {shape}: not a "
                             "numeric array as written")
    nbytes = int(np.prod(shape, dtype=np.float64)) * dtype.itemsize
    stored = dataset.id.get_storage_size()
    file_size = os.fstat(f.id.get_vfd_handle()).st_size if f.driver == "sec2" else None
    if (nbytes and dataset.chunks != shape) or nbytes > stored \
            or (file_size is not None and nbytes > file_size):
        raise SurrogateError(f"array {name!r} claims shape {shape} ({nbytes:.3g} bytes) but "
                             f"{stored} bytes are stored (chunks {dataset.chunks}): its header "
                             "is damaged (not read)")
    data = dataset[()]
    stored = dataset.attrs.get("sha256")
    if stored is None or str(stored) != array_digest(data):
        raise SurrogateError(f"array {name!r} does not match its checksum")
    return data


def read_checked_file(path: str | Path, *, check_format, array_names: dict, scalar_names: dict,
                      scalar_types: dict, build, expected_hash: str | None = None,
                      expected_solver: str | None = None, hash_label: str = "field hash",
                      optional_names: dict | None = None, optional_scalars: dict | None = None):
    """Read a file written by :func:`write_checked_file`; raise :class:`SurrogateError`
    (naming ``path``) unless it is complete, of the format ``check_format(attrs)``
    accepts (it raises :class:`SurrogateError` otherwise; it returns the format version
    when that is an old one, read by :func:`old_layout` and converted by
    :func:`per_unit_charge`, else None), unchanged since written
    (checksums), sensible (``build(arrays, history, scalars, provenance)`` returns the
    table or raises) and (if given) for ``expected_hash`` (called ``hash_label`` in the
    message) made by the solver with fingerprint ``expected_solver``."""
    h5py = _import_h5py()
    path = Path(path)

    def fail(reason: str):
        return SurrogateError(f"surrogate file {str(path)!r} {reason}", path=path, reason=reason)

    if not path.is_file():
        raise fail("is a directory" if path.is_dir() else "does not exist")
    try:
        with h5py.File(path, "r") as f:
            if not bool(f.attrs.get("complete", False)):
                raise SurrogateError("is partial (complete flag unset)")
            old = check_format(f.attrs)
            if old is not None:     # charges in C and their ball charge: converted below
                array_names, scalar_names, scalar_types = old_layout(
                    array_names, scalar_names, scalar_types)
            stored_hash = str(f.attrs["field_hash"])
            if expected_hash is not None and stored_hash != expected_hash:
                raise SurrogateError(f"was made for {hash_label} {stored_hash[:12]}..., the "
                                     f"scene has {expected_hash[:12]}...")
            arrays = {attr: _read_checked(f, name) for attr, name in array_names.items()}
            arrays.update({attr: _read_checked(f, name)
                           for attr, name in (optional_names or {}).items() if name in f})
            history = _read_checked(f, "error_history")
            scalars = typed_scalars({attr: f.attrs[name] for attr, name in scalar_names.items()},
                                    scalar_types)
            scalars.update({attr: kind(f.attrs[name])
                            for attr, (name, kind, _) in (optional_scalars or {}).items()
                            if name in f.attrs})
            if str(f.attrs.get("scalars_sha256", "")) != scalars_digest(scalars):
                raise SurrogateError("scalar attributes do not match their checksum")
            provenance_text = str(f.attrs["provenance"])
            converted = None if old is None else per_unit_charge(arrays, scalars, old)
    except SurrogateError as exc:
        raise fail(exc.reason) from None
    except Exception as exc:  # noqa: BLE001 - any read failure means "corrupt"
        raise fail(f"is corrupt or unreadable: {type(exc).__name__}: {exc}") from None
    try:
        provenance_data = json.loads(provenance_text)
        if converted is not None:   # where the fractions came from (not a table field)
            provenance_data["converted_from"] = converted
        table = build(arrays, history, scalars, provenance_data)
    except SurrogateError as exc:
        raise fail(f"holds inconsistent data: {exc.reason}") from None
    except Exception as exc:  # noqa: BLE001 - shapes that do not even build a table
        raise fail(f"holds inconsistent data: {type(exc).__name__}: {exc}") from None
    stored_solver = table.provenance.get("solver_fingerprint")
    if expected_solver is not None and stored_solver != expected_solver:
        raise fail(f"was made by another version of the field solver (fingerprint "
                   f"{stored_solver}, now {expected_solver})")
    return table


def _plain(value):
    """An HDF5 attribute as a Python value (numpy 2 prints ``np.int64(2)`` for its repr)."""
    return value.item() if isinstance(value, np.generic) else value


def _check_format(attrs) -> int | None:
    """None for today's format, the version for an old one still read; else raise."""
    version = attrs.get("format_version")
    if version is not None and int(version) in OLD_FORMAT_VERSIONS:
        return int(version)
    if version is None or int(version) != FORMAT_VERSION:
        readable = ", ".join(str(v) for v in (*OLD_FORMAT_VERSIONS, FORMAT_VERSION))
        raise SurrogateError(f"has format version {_plain(version)!r}, written by another "
                             f"tengfield version (this one reads formats {readable})")
    return None


def _build_table(arrays: dict, history, scalars: dict, provenance_data: dict) -> SurrogateTable:
    if history.ndim != 2 or history.shape[1] != 2:
        raise SurrogateError(f"error history has shape {history.shape}")
    check_shapes(arrays)
    n = np.shape(arrays["positions"])[0]
    if "line_check" in arrays:
        arrays["line_check"] = _expand_line_check(arrays["line_check"],
                                                  arrays.pop("line_check_index", None), n)
    basis = 1 + np.shape(arrays["induced_fraction"])[1]   # [φ_1, ψ_k per electrode]
    for attr in OPTIONAL_ARRAYS:
        if attr in arrays:
            shape = np.shape(arrays[attr])
            if len(shape) != 4 or shape[0] != n or shape[1] != 2 or shape[3] != basis:
                raise SurrogateError(f"array {OPTIONAL_ARRAYS[attr]!r} has shape {shape}, "
                                     f"expected ({n}, 2, lines, {basis})")
    if "line_potential" in arrays and not np.all(np.isfinite(arrays["line_potential"])):
        raise SurrogateError("non-finite breakdown line potentials")
    table = SurrogateTable(**arrays, **scalars, provenance=provenance_data,
                           error_history=[(int(n), float(e)) for n, e in history.tolist()])
    # __post_init__ sorts: check the order as stored, then the rest
    z = np.asarray(arrays["positions"], dtype=float)
    if z.ndim != 1 or not np.all(np.diff(z) > 0.0):
        raise SurrogateError("positions are not strictly ascending")
    check_table(table)
    return table


def _expand_line_check(rows, index, n: int) -> np.ndarray:
    """The lines' mesh check at all ``n`` positions (NaN where it was not solved) from
    the stored ``rows`` at the positions ``index``; raise :class:`SurrogateError`
    unless the two agree and the rows are finite."""
    rows = np.asarray(rows, dtype=float)
    if index is None:
        raise SurrogateError(f"array {LINE_CHECK_INDEX!r} is missing")
    index = np.asarray(index)
    if (index.ndim != 1 or index.dtype.kind not in "iu" or rows.ndim != 4
            or rows.shape[0] != index.size or np.any(np.diff(index) <= 0)
            or (index.size and (index[0] < 0 or index[-1] >= n))):
        raise SurrogateError(f"arrays {OPTIONAL_ARRAYS['line_check']!r} (shape {rows.shape}) "
                             f"and {LINE_CHECK_INDEX!r} (shape {index.shape}) do not match "
                             f"{n} positions")
    if not np.all(np.isfinite(rows)):
        raise SurrogateError("non-finite breakdown line check potentials")
    full = np.full((n, *rows.shape[1:]), np.nan)
    full[index] = rows
    return full


def read_table(path: str | Path, expected_hash: str | None = None,
               expected_solver: str | None = None) -> SurrogateTable:
    """Read a surrogate file; raise :class:`SurrogateError` unless it is complete,
    readable, unchanged since written (checksums), sensible (:func:`check_table`)
    and (if given) made for ``expected_hash`` by the solver with fingerprint
    ``expected_solver`` (:func:`solver_fingerprint`)."""
    return read_checked_file(path, check_format=_check_format, array_names=ARRAYS,
                             scalar_names=SCALARS, scalar_types=SCALAR_TYPES,
                             build=_build_table, expected_hash=expected_hash,
                             expected_solver=expected_solver,
                             optional_names={**OPTIONAL_ARRAYS, "line_check_index": LINE_CHECK_INDEX})


# ---------------------------------------------------------------------------
# the (z, r) file
def _check_grid_shapes(arrays: dict, nz: int, nr: int) -> None:
    """Raise :class:`SurrogateError` unless each per-point array of ``arrays`` (table
    attribute -> array) has the shape ``(nz, nr, *tail)`` of :func:`grid_tails` (the
    electrode count read from the induced fractions: 2, or 1 for the single electrode)."""
    q = np.shape(arrays["induced_fraction"])
    electrodes = q[2] if len(q) == 3 and q[2] in (1, 2) else 2   # else refused as the pair's
    for attr, tail in grid_tails(electrodes).items():
        shape = np.shape(arrays[attr])
        if shape != (nz, nr, *tail):
            raise SurrogateError(f"array {ARRAYS_ZR[attr]!r} has shape {shape}, expected "
                                 f"{(nz, nr, *tail)}")


def check_radial_table(table: RadialTable) -> None:
    """Raise :class:`SurrogateError` (reason only) unless ``table`` makes sense:
    shapes, offsets strictly ascending from 0 to ``max_offset``, and every
    offset's column passing :func:`tengfield.surrogate.check_table`."""
    nz, nr = table.shape
    _check_grid_shapes({attr: getattr(table, attr) for attr in GRID_TAILS}, nz, nr)
    r = table.offsets
    check_axis(r, float(table.max_offset), "offset", "max offset")
    z = table.positions
    if z.ndim != 1 or not np.all(np.diff(z) > 0.0):
        raise SurrogateError("positions are not strictly ascending")
    for j in range(nr):
        try:
            check_table(table.column(j))
        except SurrogateError as exc:
            raise SurrogateError(f"at offset r = {r[j]:.6g} m: {exc.reason}") from None


def write_radial_table(path, table: RadialTable) -> Path:
    """Write ``table`` to HDF5 atomically with the 1-D surrogate's checksums
    (:func:`tengfield.files.hdf5.write_checked_file`). Raises ``OSError`` if it
    cannot (nothing is left behind)."""
    arrays = {name: np.asarray(getattr(table, attr)) for attr, name in ARRAYS_ZR.items()}
    arrays["error_history"] = np.asarray(table.error_history, dtype=float).reshape(-1, 3)
    scalars = typed_scalars(vars(table), SCALAR_TYPES_ZR)
    names = dict(SCALARS_ZR)
    for attr, (name, kind, default) in OPTIONAL_SCALARS_ZR.items():
        if getattr(table, attr) != default:
            scalars[attr], names[attr] = kind(getattr(table, attr)), name
    return write_checked_file(path, arrays, scalars, names, {
        "format_version": FORMAT_VERSION_ZR, "kind": "zr",
        "provenance": json.dumps(table.provenance, default=str)}, error=SurrogateError)


def _check_format_zr(attrs) -> int | None:
    """None for today's (z, r) format, the version for an old one still read; else raise."""
    version = attrs.get("format_version")
    zr = str(attrs.get("kind", "")) == "zr" and version is not None
    if zr and int(version) in OLD_FORMAT_VERSIONS_ZR:
        return int(version)
    if not zr or int(version) != FORMAT_VERSION_ZR:
        readable = " or ".join(str(v) for v in (*OLD_FORMAT_VERSIONS_ZR, FORMAT_VERSION_ZR))
        raise SurrogateError(f"is not a (z, r) surrogate of format {readable} "
                             f"(kind {_plain(attrs.get('kind'))!r}, format {_plain(version)!r})")
    return None


def _build_radial_table(arrays: dict, history, scalars: dict,
                        provenance_data: dict) -> RadialTable:
    _check_grid_shapes(arrays, np.shape(arrays["positions"])[0], np.shape(arrays["offsets"])[0])
    if history.ndim != 2 or history.shape[1] != 3:
        raise SurrogateError(f"error history has shape {history.shape}")
    table = RadialTable(**arrays, **scalars, provenance=provenance_data,
                        error_history=[(int(a), int(b), float(e))
                                       for a, b, e in history.tolist()])
    check_radial_table(table)
    return table


def read_radial_table(path, expected_hash: str | None = None,
                      expected_solver: str | None = None) -> RadialTable:
    """Read a (z, r) surrogate file; raise :class:`SurrogateError` unless it is
    complete, of this format, unchanged (checksums), sensible
    (:func:`check_radial_table`) and (if given) for ``expected_hash``
    (:func:`tengfield.surrogate.provenance.radial_hash`) and the solver ``expected_solver``
    (:func:`read_checked_file`)."""
    return read_checked_file(path, check_format=_check_format_zr, array_names=ARRAYS_ZR,
                             scalar_names=SCALARS_ZR, scalar_types=SCALAR_TYPES_ZR,
                             build=_build_radial_table, expected_hash=expected_hash,
                             expected_solver=expected_solver, hash_label="hash",
                             optional_scalars=OPTIONAL_SCALARS_ZR)
