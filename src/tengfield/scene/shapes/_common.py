"""Helpers the shape modules share (file units in messages, design ranges)."""
from __future__ import annotations

from ...errors import SceneError


def mm(x: float) -> str:
    """``x`` [m] in mm, as messages write it."""
    return f"{x * 1e3:g}"


def around(x: float, factors) -> list[float]:
    """[x f_lo, x f_hi] in mm, 3 significant digits."""
    return [float(f"{x * 1e3 * f:.3g}") for f in factors]


def ball_fits(ball: float, cavity: float) -> None:
    if ball >= cavity:
        raise SceneError(f"[device] ball_diameter_mm = {mm(ball)} is out of range: allowed "
                         f"(0, {mm(cavity)}) mm (smaller than cavity_diameter_mm: the ball "
                         "must fit the cavity)")
