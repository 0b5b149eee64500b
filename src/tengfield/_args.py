"""Arguments of the Python API, checked at its entry points (issue #43.19).

One :class:`TypeError` (wrong kind of value) or :class:`ValueError` (a
:class:`~tengfield.errors.SceneError`: right kind, out of range) naming the function, the
argument and what it takes, instead of a raw ``AttributeError`` deep inside, or a run
that ignores the value. The messages name the Python argument (``jobs``), not the CLI
option (``--jobs``): the CLI checks its own options first.
"""
from __future__ import annotations

import math
import os
from numbers import Integral, Real

from .errors import SceneError


def _shown(value) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def check_jobs_argument(function: str, jobs, comm=None) -> int | None:
    """``jobs`` of ``function``: None (all cores) or a whole number in the allowed range
    (:func:`tengfield._mpi.check_jobs`); returns it as an int."""
    from ._mpi import check_jobs

    if jobs is None:
        return None
    if isinstance(jobs, bool) or not isinstance(jobs, Integral):
        raise TypeError(f"{function}(jobs={_shown(jobs)}): expected a whole number of worker "
                        "processes, or None for all cores")
    check_jobs(int(jobs), comm, option=f"{function}(jobs=...): jobs")
    return int(jobs)


def check_instance(function: str, value, name: str, kind: type, what: str,
                   allow_none: bool = False):
    """``value`` is a ``kind`` (``what`` says how to get one), or None if allowed."""
    if value is None and allow_none:
        return value
    if not isinstance(value, kind):
        raise TypeError(f"{function}({name}={_shown(value)}): expected {what}, got "
                        f"{type(value).__name__}")
    return value


def check_fraction(function: str, value, name: str, *, low: float = 0.0, high: float = 1.0,
                   low_open: bool = True, high_open: bool = False) -> float:
    """``value`` a finite real number inside the interval (``low``, ``high``] (ends open
    or closed as given)."""
    if isinstance(value, bool) or not isinstance(value, Real):
        raise TypeError(f"{function}({name}={_shown(value)}): expected a number")
    x = float(value)
    inside = (math.isfinite(x) and (x > low if low_open else x >= low)
              and (x < high if high_open else x <= high))
    if not inside:
        interval = f"{'(' if low_open else '['}{low:g}, {high:g}{')' if high_open else ']'}"
        raise SceneError(f"{function}({name}={_shown(value)}) is out of range: allowed "
                         f"{interval}")
    return x


def check_count(function: str, value, name: str, least: int = 1) -> int:
    """``value`` a whole number >= ``least``."""
    if isinstance(value, bool) or not isinstance(value, Integral):
        raise TypeError(f"{function}({name}={_shown(value)}): expected a whole number")
    if value < least:
        raise SceneError(f"{function}({name}={value}) is out of range: allowed >= {least}")
    return int(value)


def check_path_argument(function: str, path, name: str = "path"):
    """``path`` names a file: a non-empty ``str`` or ``os.PathLike`` (bytes are not
    accepted: a scene's relative file names are resolved as text)."""
    if isinstance(path, (bytes, bytearray)) or not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"{function}({name}={_shown(path)}): expected a file name (str or "
                        f"pathlib.Path), got {type(path).__name__}")
    if not os.fspath(path).strip():
        raise SceneError(f"{function}({name}={_shown(path)}): an empty file name; give a "
                         ".toml file")
    return path
