"""The pinned outputs of a representative set of runs (issue #51: "every number kept").

Each case runs one ``tengfield`` command in a subprocess, exactly as a user does, and
reads back the numbers it wrote: every number of its JSON summary (wall times, paths and
versions left out) and, of every numeric CSV column, its sum, sum of squares, first and
last values and extremes. ``tests/pins/pinned-<dolfinx>.json`` keeps them; the test
(``test_pins.py``) holds every pinned number within a relative 1e-9 on the release that
pinned it (CSV cells carry 10 significant digits, 5e-10 of rounding).

Re-pin after a change that moves a number on purpose, and say which and why in the
commit::

    PYTHONPATH=src .venv/bin/python tests/pins/pinning.py --write [--only NAME ...]
"""
from __future__ import annotations

import argparse
import csv
import json
import math
import os
import re
import subprocess
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]

#: a small, fast scene on the default device (the probes' base scene of issue #54)
BASE = """\
[run]
duration_s = 0.3
settle_periods = 2
sample_rate_hz = 5000.0
[field]
degree = 1
mesh_size_mm = 1.5
tolerance = 1e-2
"""

#: summary keys that are not results: wall times, paths, text, versions, hashes, the
#: least-squares solver's iteration counts (its path: round-off of the machine moves it,
#: seen 6 -> 5 Jacobians with every fitted value the same to 1e-9)
SKIP = re.compile(r"(wall_time|_wall_|elapsed|seconds_per|\bpath\b|field_hash|version|"
                  r"^iterations\.|"
                  r"cache|_bytes$|memory|rss|\.reason$|^stages\..*time|field_solves|solves_run|meshings|_wall_s|cost_per_candidate)")

#: numbers whose size is round-off: the relative energy residuals when the books close
#: (1e-16 .. 1e-15, moved by the order of a sum) and a fit's correlations near 0 (seen
#: 1.8e-6 moved by 1e-13 on another machine); held to an absolute
#: :data:`ROUNDOFF_TOLERANCE` as well as to ``rtol``
ROUNDOFF = re.compile(r"(energy_residuals\.|_relative_residual$|correlation\.matrix\.)")
ROUNDOFF_TOLERANCE = 1e-12


@dataclass(frozen=True)
class Case:
    """One pinned command: ``argv`` after ``tengfield``, run in a work folder holding
    ``base.toml`` (and the files of ``setup``); ``reads`` the outputs it pins."""
    name: str
    argv: tuple[str, ...]
    reads: tuple[str, ...]
    setup: str = ""          # name of a function below that writes extra input files
    extra_scene: str = ""    # appended to base.toml
    env: dict = field(default_factory=dict)


def _recorded_table(work: Path) -> None:
    """A recorded table displacement: 20 Hz, 1.5 mm and its second harmonic, 1 s."""
    import numpy as np

    t = np.arange(0.0, 1.0 + 1e-12, 1e-4)
    y = 1.5e-3 * np.sin(2 * np.pi * 20 * t) + 0.1e-3 * np.sin(2 * np.pi * 40 * t + 0.3)
    lines = ["time_s,displacement_m"] + [f"{a:.6f},{b:.9e}" for a, b in zip(t, y)]
    (work / "table.csv").write_text("\n".join(lines) + "\n")


SETUPS = {"recorded": _recorded_table}

CASES = (
    Case("default_run", ("run", "-o", "out"), ("out/summary.json", "out/waveforms.csv")),
    Case("load_instrument",
         ("run", "base.toml", "--set", "circuit.kind=load", "--set", "circuit.load_ohm=1e8",
          "--set", "instrument.capacitance_pF=338", "-o", "out"),
         ("out/summary.json", "out/waveforms.csv")),
    Case("rectifier_store",
         ("run", "base.toml", "--set", "circuit.kind=rectifier",
          "--set", "circuit.storage_capacitance_uF=0.01", "-o", "out"),
         ("out/summary.json", "out/waveforms.csv")),
    Case("rectifier_uvlo",
         ("run", "base.toml", "--set", "circuit.kind=rectifier",
          "--set", "circuit.storage_capacitance_uF=0.002", "--set", "circuit.pmic=uvlo",
          "--set", "run.duration_s=1.5", "--set", "run.sample_rate_hz=20000", "-o", "out"),
         ("out/summary.json", "out/waveforms.csv")),
    Case("array",
         ("run", "base.toml", "--set", "array.cells=3", "--set", "array.initial_phase_spread_deg=90",
          "--set", "array.restitution_spread=0.05", "-o", "out"),
         ("out/summary.json", "out/waveforms.csv")),
    Case("breakdown_band", ("breakdown", "base.toml", "-o", "out"), ("out/breakdown.json",)),
    Case("design", ("design", "base.toml", "--candidates", "4", "--seed", "1", "-o", "out"),
         ("out/design.json", "out/design.csv")),
    Case("uncertainty",
         ("uncertainty", "base.toml", "-o", "out"), ("out/uncertainty.json",),
         extra_scene='[uncertainty]\nsamples = 16\n[uncertainty.vary]\n'
                     '"contact.restitution" = { distribution = "uniform", low = 0.05, high = 0.3 }\n'
                     '"excitation.amplitude_mm" = { distribution = "uniform", low = 1.2, high = 1.8 }\n'),
    Case("shell", ("run", "base.toml", "--set", "device.shape=spherical-shell", "-o", "out"),
         ("out/summary.json", "out/waveforms.csv")),
    Case("honeycomb",
         ("run", "base.toml", "--set", "device.shape=hexagonal", "--set", "field.mesh_size_mm=100",
          "--set", "field.tolerance=0.5", "-o", "out"),
         ("out/summary.json", "out/waveforms.csv")),
    Case("recorded",
         ("run", "base.toml", "--set", "excitation.kind=recorded",
          "--set", "excitation.file=table.csv", "-o", "out"),
         ("out/summary.json", "out/waveforms.csv"), setup="recorded"),
    Case("random",
         ("run", "base.toml", "--set", "excitation.kind=random",
          "--set", "excitation.band_hz=[10.0, 200.0]",
          "--set", "excitation.rms_acceleration_m_per_s2=15.0",
          "--set", "excitation.seed=3", "-o", "out"),
         ("out/summary.json", "out/waveforms.csv")),
    Case("fit", ("fit", "--measured", str(ROOT / "examples" / "scope.csv"), "-o", "out"),
         ("out/fit.json",)),
    Case("spice", ("run", "base.toml", "--spice", "-o", "out"), ("out/teng.lib",)),
)


def numbers_of_json(data, prefix: str = "") -> dict[str, float]:
    """Every finite number of a JSON document by its dotted path (lists by index),
    leaving out :data:`SKIP`'s keys."""
    out: dict[str, float] = {}
    if isinstance(data, dict):
        items = data.items()
    elif isinstance(data, list):
        items = ((str(i), v) for i, v in enumerate(data))
    else:
        items = ()
    for key, value in items:
        path = f"{prefix}.{key}" if prefix else str(key)
        if SKIP.search(path):
            continue
        if isinstance(value, bool):
            out[path] = float(value)
        elif isinstance(value, (int, float)):
            if math.isfinite(value):
                out[path] = float(value)
        elif isinstance(value, (dict, list)):
            out.update(numbers_of_json(value, path))
    return out


def numbers_of_csv(path: Path) -> dict[str, float]:
    """Per numeric column: sum, sum of squares, first, last, min, max."""
    with open(path, newline="") as handle:
        rows = [r for r in csv.reader(line for line in handle if not line.startswith("#"))]
    header, body = rows[0], rows[1:]
    out: dict[str, float] = {"rows": float(len(body))}
    for j, name in enumerate(header):
        if SKIP.search(name):
            continue
        try:
            column = [float(r[j]) for r in body if j < len(r) and r[j] != ""]
        except ValueError:
            continue
        column = [c for c in column if math.isfinite(c)]
        if not column:
            continue
        out[f"{name}.sum"] = math.fsum(column)
        out[f"{name}.sumsq"] = math.fsum(c * c for c in column)
        out[f"{name}.first"] = column[0]
        out[f"{name}.last"] = column[-1]
        out[f"{name}.min"] = min(column)
        out[f"{name}.max"] = max(column)
    return out


_FLOAT = re.compile(r"(?<![\w.])[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?")


def numbers_of_text(path: Path) -> dict[str, float]:
    """A text file's numbers (a netlist's PWL tables) outside its comment lines:
    their count, sum, sum of squares and a checksum weighted by position."""
    values = []
    for line in path.read_text().splitlines():
        if line.lstrip().startswith("*"):
            continue
        values.extend(float(m) for m in _FLOAT.findall(line))
    return {"count": float(len(values)), "sum": math.fsum(values),
            "sumsq": math.fsum(v * v for v in values),
            "weighted": math.fsum((i % 97 + 1) * v for i, v in enumerate(values))}


def read_outputs(work: Path, reads) -> dict[str, float]:
    out: dict[str, float] = {}
    for name in reads:
        path = work / name
        if path.suffix == ".json":
            numbers = numbers_of_json(json.loads(path.read_text()))
        elif path.suffix == ".csv":
            numbers = numbers_of_csv(path)
        else:
            numbers = numbers_of_text(path)
        out.update({f"{path.name}:{k}": v for k, v in numbers.items()})
    return out


def environment(cache: Path) -> dict:
    env = {k: v for k, v in os.environ.items() if not k.startswith("TENGFIELD_")}
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT / "src"), env.get("PYTHONPATH")) if p)
    env["TENGFIELD_CACHE_DIR"] = str(cache)
    env.setdefault("MPLBACKEND", "Agg")
    return env


def run_case(case: Case, work: Path, cache: Path, python: str = sys.executable) -> dict[str, float]:
    """Run ``case`` in the fresh folder ``work`` and return its numbers."""
    work.mkdir(parents=True, exist_ok=True)
    (work / "base.toml").write_text(BASE + case.extra_scene)
    if case.setup:
        SETUPS[case.setup](work)
    env = environment(cache)
    env.update(case.env)
    proc = subprocess.run([python, "-m", "tengfield.cli", *case.argv], cwd=work, env=env,
                          stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=1800)
    if proc.returncode != 0:
        raise RuntimeError(f"{case.name}: tengfield {' '.join(case.argv)} exited "
                           f"{proc.returncode}:\n{proc.stderr[-3000:]}")
    return read_outputs(work, case.reads)


def release() -> str:
    """The dolfinx version the field numbers depend on (``0.5.2`` on Debian 12)."""
    try:
        from importlib.metadata import version

        return version("fenics-dolfinx")
    except Exception:  # noqa: BLE001
        import dolfinx

        return dolfinx.__version__


def pinned_file(version: str | None = None) -> Path:
    return HERE / f"pinned-dolfinx-{version or release()}.json"


def compare(pinned: dict[str, float], now: dict[str, float], rtol: float) -> list[str]:
    """Lines naming each pinned number that moved past ``rtol`` (relative to the larger
    of the number and a floor of 1e-9 of its output's largest magnitude) or disappeared."""
    scale: dict[str, float] = {}
    for key, value in pinned.items():
        stem = key.split(":")[0]
        scale[stem] = max(scale.get(stem, 0.0), abs(value))
    moved = []
    for key, value in sorted(pinned.items()):
        if SKIP.search(key.split(":", 1)[-1]):     # pinned before it was left out
            continue
        if key not in now:
            moved.append(f"{key}: pinned {value!r}, now absent")
            continue
        floor = 1e-9 * scale[key.split(':')[0]] * 1e-6
        allowed = rtol * max(abs(value), floor)
        if ROUNDOFF.search(key):
            allowed = max(allowed, ROUNDOFF_TOLERANCE)
        if abs(now[key] - value) > allowed:
            moved.append(f"{key}: pinned {value!r}, now {now[key]!r} "
                         f"(relative {abs(now[key] - value) / max(abs(value), 1e-300):.2e})")
    return moved


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", action="store_true", help="write the pinned file")
    parser.add_argument("--only", nargs="*", default=None, help="cases to run")
    args = parser.parse_args(argv)
    cases = [c for c in CASES if args.only is None or c.name in args.only]
    target = pinned_file()
    pinned = json.loads(target.read_text()) if target.exists() else {"cases": {}}
    with tempfile.TemporaryDirectory(prefix="tengfield-pins-") as scratch:
        cache = Path(scratch) / "cache"
        for case in cases:
            numbers = run_case(case, Path(scratch) / case.name, cache)
            old = pinned["cases"].get(case.name)
            moved = compare(old, numbers, 1e-9) if old else ["(not pinned before)"]
            print(f"{case.name}: {len(numbers)} numbers; "
                  f"{'unchanged' if not moved else str(len(moved)) + ' moved'}", flush=True)
            for line in moved[:20]:
                print("   ", line)
            pinned["cases"][case.name] = numbers
    pinned["cases"] = {c.name: pinned["cases"][c.name] for c in CASES if c.name in pinned["cases"]}
    if args.write:
        pinned["dolfinx"] = release()
        target.write_text(json.dumps(pinned, indent=1, sort_keys=True) + "\n")
        print(f"wrote {target}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
