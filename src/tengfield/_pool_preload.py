"""Imported by the worker pools' fork server only (:data:`tengfield._pool.PRELOAD`):
the modules of the pools' tasks, and the impact map's compiled kernels loaded once
from numba's cache, so that every worker forked from the server starts with them (as
it did when the pools forked the calling process itself)."""
from __future__ import annotations

from . import array, lumped, sweeps  # noqa: F401 - the tasks' modules
from .dynamics import impact, mapping, table  # noqa: F401


def _load_kernels() -> None:
    """One regime point of the default scene: numba loads (or compiles) the kernels."""
    from .dynamics.impact import Restitution
    from .scene import default_scene

    scene = default_scene()
    setup = mapping.PointSetup(scene.device.stroke, Restitution.from_contact(scene.contact),
                               scene.excitation.phase, scene.initial.time,
                               scene.initial.gap, scene.initial.velocity, 8, 0)
    mapping._chunk((setup, [(0, 0, 20.0, 1.5e-3)]))      # noqa: SLF001


try:
    _load_kernels()
except Exception:  # noqa: BLE001 - a speed-up only: the workers load them if this failed
    pass
