"""``START:STOP:N`` command-line ranges, shared by ``map`` and ``sweep``."""
from __future__ import annotations

import math

from ..errors import SceneError

MAX_POINTS = 100_000


def number_text(value) -> str:
    """A command-line number for a message: ``:g`` when that is the number itself (``3.5``,
    ``1e-06``), else the shortest text that is (``repr``: ``3.0000000001``), so a value
    just beyond a bound never reads as the bound (``3 is out of range: allowed [0, 3]``);
    the rule of the scene's values (``scene.schema.show``: the value as written)."""
    try:
        value = float(value)
    except (TypeError, ValueError):
        return repr(value)
    text = f"{value:g}"
    return text if not math.isfinite(value) or float(text) == value else repr(value)


def parse_range(text: str, option: str, *, positive: bool = True, log: bool = False):
    """``START:STOP:N`` -> N values, both ends included (linear, or logarithmic with
    ``log``); a single number ``X`` -> [X]. Values must be finite and > 0
    (``positive``) or >= 0; N in [1, 100000]. Bad input raises :class:`SceneError`
    naming the option, the text and what is allowed."""
    import numpy as np

    parts = text.split(":")
    if len(parts) not in (1, 3):
        raise SceneError(f"{option} = {text!r}: expected START:STOP:N (e.g. 5:70:66) or one number")
    try:
        ends = [float(p) for p in parts[:2]]
        count = int(parts[2]) if len(parts) == 3 else 1
    except ValueError:
        raise SceneError(f"{option} = {text!r}: START and STOP must be numbers and N a whole "
                         "number, e.g. 5:70:66") from None
    if not all(math.isfinite(v) for v in ends):
        raise SceneError(f"{option} = {text!r}: START and STOP must be finite")
    if not 1 <= count <= MAX_POINTS:
        raise SceneError(f"{option} = {text!r}: N = {count} is out of range: "
                         f"allowed [1, {MAX_POINTS}]")
    low = min(ends)
    if (positive or log) and low <= 0:
        raise SceneError(f"{option} = {text!r} is out of range: every value must be > 0")
    if low < 0:
        raise SceneError(f"{option} = {text!r} is out of range: every value must be >= 0")
    if len(ends) == 1:
        return np.array(ends)
    if log:
        return np.logspace(math.log10(ends[0]), math.log10(ends[1]), count)
    return np.linspace(ends[0], ends[1], count)
