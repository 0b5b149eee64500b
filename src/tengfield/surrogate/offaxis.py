"""Whether the ball is off the axis, and its radial motion: what the (z, r) surrogate
needs of a 3D trajectory.

These belong to the 3D motion (:mod:`tengfield.dynamics.motion3d`) and stay here until that
package takes them; they read a trajectory and never import it.
"""
from __future__ import annotations

import numpy as np

from .sampling import max_offset

#: the ball "leaves the axis" when its largest radial offset exceeds this fraction of
#: r_max; below it the change of Q_SC is O((r / r_max)²) x 2e-3 < 1e-8 (docs/surrogate.md)
AXIS_FRACTION = 1e-3


def _radial_rate(x, y, vx, vy) -> tuple[np.ndarray, np.ndarray]:
    r = np.hypot(x, y)
    with np.errstate(invalid="ignore", divide="ignore"):
        rate = np.where(r > 0.0, (x * vx + y * vy) / np.where(r > 0.0, r, 1.0), 0.0)
    return r, rate


def radial_motion(motion, times=None) -> tuple[np.ndarray, np.ndarray]:
    """``(r, dr/dt)`` [m], [m/s] of a :class:`tengfield.dynamics.motion3d.Motion3DResult` at its
    output samples, or exactly at ``times`` [s] (``motion.sample3d``); dr/dt = 0 on
    the axis. Anything without lateral motion (a 1-D DynamicsResult) gives zeros."""
    if times is not None:
        t = np.atleast_1d(np.asarray(times, dtype=float))
        if not hasattr(motion, "sample3d"):
            return np.zeros_like(t), np.zeros_like(t)
        state = np.asarray(motion.sample3d(t), dtype=float).reshape(-1, 9)
        return _radial_rate(state[:, 0], state[:, 1], state[:, 3], state[:, 4])
    if not hasattr(motion, "x"):
        n = np.asarray(motion.gap).size
        return np.zeros(n), np.zeros(n)
    velocity = np.asarray(motion.velocity, dtype=float).reshape(-1, 3)
    return _radial_rate(np.asarray(motion.x, dtype=float), np.asarray(motion.y, dtype=float),
                        velocity[:, 0], velocity[:, 1])


def leaves_axis(scene, motion) -> bool:
    """True when ``motion`` takes the ball off the axis by more than ``AXIS_FRACTION``
    of r_max (then the (z, r) surrogate is needed; otherwise the 1-D one is exact
    to far below its own error)."""
    radial = getattr(motion, "radial", None)
    if radial is None or np.asarray(radial).size == 0:
        return False
    return bool(np.max(np.asarray(radial, dtype=float)) > AXIS_FRACTION * max_offset(scene.device))
