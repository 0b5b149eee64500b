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
    return number(function, value, name, low=low, high=high, low_open=low_open,
                  high_open=high_open)


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


# -- the general checks of a public entry point's arguments (issue #54.17) -------------
def names(function: str, value, name: str, *, allow_none: bool = True) -> list[str] | None:
    """``value`` a list of names: a ``str`` is ONE name (never its characters), else an
    iterable of ``str``; None where allowed. TypeError naming ``function`` and ``name``."""
    if value is None and allow_none:
        return None
    if isinstance(value, str):
        return [value]
    if isinstance(value, (bytes, bytearray, dict)) or not hasattr(value, "__iter__"):
        raise TypeError(f"{function}({name}={_shown(value)}): expected a name or a list of "
                        f"names (str), got {type(value).__name__}")
    items = list(value)
    for item in items:
        if not isinstance(item, str):
            raise TypeError(f"{function}({name}={_shown(value)}): expected names (str), got "
                            f"{_shown(item)} ({type(item).__name__})")
    return items


def path(function: str, value, name: str, *, allow_none: bool = False, what: str = "a path"):
    """``value`` a file or folder name: a non-empty ``str`` or ``os.PathLike`` (None where
    allowed); returns it as a :class:`pathlib.Path` (or None)."""
    from pathlib import Path

    if value is None and allow_none:
        return None
    if isinstance(value, (bytes, bytearray)) or not isinstance(value, (str, os.PathLike)):
        raise TypeError(f"{function}({name}={_shown(value)}): expected {what} (str or "
                        f"pathlib.Path){' or None' if allow_none else ''}, got "
                        f"{type(value).__name__}")
    if not os.fspath(value).strip():
        raise SceneError(f"{function}({name}={_shown(value)}): an empty name; expected {what}")
    return Path(value)


def flag(function: str, value, name: str) -> bool:
    """``value`` True or False (numpy's bool too); a string such as ``"no"`` is refused,
    never taken as true."""
    if isinstance(value, bool) or type(value).__name__ == "bool_":
        return bool(value)
    raise TypeError(f"{function}({name}={_shown(value)}): expected True or False, got "
                    f"{type(value).__name__}")


def number(function: str, value, name: str, *, low: float = -math.inf, high: float = math.inf,
           low_open: bool = False, high_open: bool = False, allow_none: bool = False):
    """``value`` a finite real number (not a bool, not a string) in the interval, ends open
    or closed as given; None where allowed. Returns a float."""
    if value is None and allow_none:
        return None
    if isinstance(value, bool) or not isinstance(value, Real):
        raise TypeError(f"{function}({name}={_shown(value)}): expected a number"
                        f"{' or None' if allow_none else ''}, got {type(value).__name__}")
    x = float(value)
    inside = (math.isfinite(x) and (x > low if low_open else x >= low)
              and (x < high if high_open else x <= high))
    if not inside:
        interval = f"{'(' if low_open else '['}{low:g}, {high:g}{')' if high_open else ']'}"
        raise SceneError(f"{function}({name}={_shown(value)}) is out of range: allowed "
                         f"{interval}")
    return x


def checked_write(method):
    """The one check of every result's ``write(out_dir, plots=True, ...)``: ``out_dir`` a
    folder name, ``plots`` True or False (a string such as ``"no"`` is refused, nothing
    drawn), TypeError naming ``tengfield.<Result>.write`` and the argument; the method
    gets a :class:`pathlib.Path` and a bool. Marks the method (``checks_arguments``) so a
    test can find a result whose ``write`` lacks it."""
    import functools

    @functools.wraps(method)
    def write(self, out_dir, plots=True, *args, **kwargs):
        where = f"tengfield.{type(self).__name__}.write"
        out_dir = path(where, out_dir, "out_dir", what="a folder name")
        plots = flag(where, plots, "plots")
        return method(self, out_dir, plots, *args, **kwargs)

    write.checks_arguments = True
    return write
