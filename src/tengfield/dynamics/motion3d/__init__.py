"""The ball in 3D (issue #13): a rigid sphere in the tube between the plates.

``simulate_3d(scene) -> Motion3DResult`` integrates position, velocity and
spin relative to the table with compliant contacts at the lower plate, the
upper plate and the tube wall (Hertz from the materials, or the multibody
power law), Coulomb friction with a capped history spring (stick/slip,
rolling), gravity in any direction (``[device] tilt_deg``) and table motion
on three axes. Compiled with numba; see docs/motion3d.md. Its files and figure are
written at the edges (:mod:`tengfield.io`, :mod:`tengfield.plotting.dynamics`).
"""
from __future__ import annotations

from .simulate import Motion3DResult, gravity_vector, integrate_3d, simulate_3d

__all__ = ["simulate_3d", "Motion3DResult", "integrate_3d", "gravity_vector"]
