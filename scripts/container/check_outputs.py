"""Sanity checks on what `tengfield run` / `tengfield precompute` wrote.

Runs inside the container (it needs h5py and numpy, which the image has):

    python /checks/check_outputs.py run DIR         # summary.json + waveforms.csv
    python /checks/check_outputs.py cached-run DIR  # the same, field stage from the cache
    python /checks/check_outputs.py precompute DIR  # the surrogate HDF5 file(s) in DIR
    python /checks/check_outputs.py png FILE        # a non-blank PNG

Prints one line per fact it checked and exits 1 on the first failure, with a
message that names the file and what is wrong.
"""
from __future__ import annotations

import csv
import json
import math
import sys
from pathlib import Path


class CheckFailed(Exception):
    pass


def _require(condition: bool, message: str) -> None:
    if not condition:
        raise CheckFailed(message)


def _one(directory: Path, pattern: str) -> Path:
    found = sorted(directory.rglob(pattern))
    _require(bool(found), f"no {pattern} under {directory} (found: "
             f"{sorted(str(p.relative_to(directory)) for p in directory.rglob('*'))})")
    return found[0]


def _finite_numbers(value) -> list[float]:
    """Every number inside a JSON value (bools excluded)."""
    if isinstance(value, bool):
        return []
    if isinstance(value, (int, float)):
        return [float(value)]
    if isinstance(value, dict):
        return [x for v in value.values() for x in _finite_numbers(v)]
    if isinstance(value, list):
        return [x for v in value for x in _finite_numbers(v)]
    return []


def check_run(directory: Path) -> None:
    summary_path = _one(directory, "summary.json")
    summary = json.loads(summary_path.read_text())
    _require(isinstance(summary, dict) and summary, f"{summary_path}: empty or not an object")
    numbers = _finite_numbers(summary)
    _require(bool(numbers), f"{summary_path}: holds no numbers")
    _require(all(math.isfinite(x) for x in numbers), f"{summary_path}: NaN or inf inside")
    peaks = summary.get("peak_to_peak", {})
    for key in ("V_oc_V", "Q_sc_C", "I_sc_A"):
        if key in peaks:
            _require(peaks[key] > 0.0, f"{summary_path}: peak_to_peak.{key} = {peaks[key]!r}, "
                     "expected > 0 for a bouncing ball")
    print(f"ok  {summary_path.name}: {len(summary)} top-level keys, {len(numbers)} finite numbers, "
          f"peak-to-peak {peaks}")

    csv_path = _one(directory, "waveforms.csv")
    with csv_path.open(newline="") as handle:
        rows = [r for r in csv.reader(handle) if r and not r[0].startswith("#")]
    _require(len(rows) >= 3, f"{csv_path}: {len(rows) - 1} data rows, expected a waveform")
    header, data = rows[0], rows[1:]
    _require(all(len(r) == len(header) for r in data), f"{csv_path}: ragged rows")
    values = [[float(x) for x in r] for r in data]
    _require(all(math.isfinite(x) for r in values for x in r), f"{csv_path}: NaN or inf inside")
    time_column = [r[0] for r in values]
    _require(all(b > a for a, b in zip(time_column, time_column[1:])),
             f"{csv_path}: first column ({header[0]}) is not increasing")
    _require(any(any(x != 0.0 for x in col) for col in list(zip(*values))[1:]),
             f"{csv_path}: every waveform column is zero")
    print(f"ok  {csv_path.name}: {len(data)} rows x {len(header)} columns {header}")
    for png in sorted(directory.glob("*.png")):
        check_png(png)


def check_cached_run(directory: Path) -> None:
    """A run whose field stage came from the cache (no field solve)."""
    check_run(directory)
    summary = json.loads(_one(directory, "summary.json").read_text())
    field = summary.get("stages", {}).get("field", {})
    _require(field.get("status") == "cached",
             f"{directory}/summary.json: stages.field = {field!r}, expected status 'cached'")
    print(f"ok  field stage cached: {field.get('reason', '')}")


def check_precompute(directory: Path) -> None:
    import h5py
    import numpy as np

    candidates = sorted(list(directory.rglob("*.h5")) + list(directory.rglob("*.hdf5")))
    _require(bool(candidates), f"no .h5/.hdf5 file under {directory}")
    leftovers = [p for p in directory.rglob("*") if p.name.endswith((".tmp", ".part"))]
    _require(not leftovers, f"temporary files left behind: {leftovers}")
    for path in candidates:
        with h5py.File(path, "r") as handle:
            attrs = dict(handle.attrs)
            for flag in ("complete", "completed", "is_complete"):
                if flag in attrs:
                    _require(bool(attrs[flag]), f"{path}: attribute {flag} = {attrs[flag]!r}")
            datasets = []
            handle.visititems(lambda name, obj: datasets.append(name)
                              if isinstance(obj, h5py.Dataset) else None)
            _require(bool(datasets), f"{path}: no datasets")
            for name in datasets:
                data = handle[name][()]
                if isinstance(data, np.ndarray) and data.dtype.kind in "fiu":
                    _require(data.size > 0, f"{path}:{name}: empty")
                    _require(bool(np.all(np.isfinite(data))), f"{path}:{name}: NaN or inf")
        print(f"ok  {path.name}: {len(datasets)} finite datasets, attributes {sorted(attrs)}")
        try:
            from tengfield.surrogate import read_radial_table, read_table
        except ImportError:  # an older tree: the generic checks above must do
            continue
        if str(attrs.get("kind", "")) == "zr":   # the (z, r) surrogate of a 3D run
            table = read_radial_table(path)      # raises unless complete and well formed
            print(f"ok  {path.name}: tengfield reads it back: (z, r) grid {table.shape}, "
                  f"interpolation error {table.interpolation_error:.3g}, converged "
                  f"{table.converged}")
            continue
        table = read_table(path)  # raises unless complete and well formed
        print(f"ok  {path.name}: tengfield reads it back: {table.count} positions, "
              f"interpolation error {table.interpolation_error:.3g}, converged {table.converged}")


def check_png(path: Path) -> None:
    data = path.read_bytes()
    _require(data[:8] == b"\x89PNG\r\n\x1a\n", f"{path}: not a PNG")
    _require(len(data) > 2000, f"{path}: only {len(data)} bytes, probably blank")
    print(f"ok  {path.name}: PNG, {len(data)} bytes")


CHECKS = {"run": check_run, "cached-run": check_cached_run, "precompute": check_precompute,
          "png": check_png}

if __name__ == "__main__":
    if len(sys.argv) != 3 or sys.argv[1] not in CHECKS:
        sys.exit(f"usage: check_outputs.py {{{'|'.join(CHECKS)}}} PATH")
    try:
        CHECKS[sys.argv[1]](Path(sys.argv[2]))
    except Exception as exc:  # noqa: BLE001 - whatever goes wrong, the check failed
        print(f"FAIL {type(exc).__name__}: {exc}", file=sys.stderr)
        sys.exit(1)
