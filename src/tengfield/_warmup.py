"""Compile tengfield's numba kernels once, into numba's on-disk cache.

    python -m tengfield._warmup          # `make setup` and the Dockerfile call this

Every kernel is ``@njit(cache=True)``: the first process that calls one
compiles it (about 10 s for the impact map alone on a 2-core machine) and
writes the machine code to numba's cache, which later processes load in a
fraction of a second. Without this step the first ``tengfield run`` after an
install pays that compile time. Here a few tiny workloads (no dolfinx, no
gmsh, about a second of simulated time in all) go through the same code paths
as ``tengfield run``, ``dynamics``, ``map`` and the harvesting and array
circuits, so every kernel is compiled with the argument types those use.

Where the cache goes is numba's choice: ``NUMBA_CACHE_DIR`` when set (the
container image sets it to a directory inside the image), else a
``__pycache__`` next to each kernel's source (the editable install of
``make setup``: ``src/tengfield/*/__pycache__``). An entry is keyed on the
source file's path, size and modification time and on the CPU: editing a
kernel, or running on another CPU model, compiles again (once).

Prints one line: how many kernels have a cache entry, where, and how long it
took (one kernel, ``dynamics._kernel._flight``, is called by none of them).
Exit status 0; 1 if a workload fails (the install is then broken anyway).
"""
from __future__ import annotations

import sys
import time

#: the modules holding ``@njit(cache=True)`` kernels
KERNEL_MODULES = ("tengfield.dynamics._kernel", "tengfield.dynamics.motion3d._kernel",
                  "tengfield.harvest._kernel", "tengfield._lumped_kernel",
                  "tengfield.source._kernel")

_SHORT_3D = """
[contact]
model = "3d"
[run]
duration_s = 0.1
settle_periods = 1
"""


def _workloads() -> None:
    import numpy as np

    from . import array, harvest, lumped
    from .dynamics import regime_map, simulate
    from .scene import default_scene, parse_scene

    scene = default_scene()
    # the impact map, its sampling and the regime classification (run, dynamics)
    simulate(scene)
    # the regime map's points (map, sweep): one process, no pool
    regime_map(scene, [20.0], [1.5e-3], jobs=1, progress=False, periods=4, settle_periods=1)
    # the rigid ball in 3D ([contact] model = "3d")
    simulate(parse_scene(_SHORT_3D, source="<warm-up>"))
    # the bridge rectifier into a store, with and without the power chip
    t = np.linspace(0.0, 0.05, 200)
    q = 1e-9 * np.sin(2 * np.pi * 20.0 * t)
    c = 4e-13 + 1e-14 * np.cos(2 * np.pi * 20.0 * t)
    harvest.harvest(t, q, c, storage_capacitance=1e-6)
    harvest.harvest(t, np.column_stack([q, q]), np.column_stack([c, c]),
                    storage_capacitance=1e-6, chip=harvest.PowerChip(),
                    diode=harvest.Diode(model="shockley"))
    harvest.Diode().path_current(np.array([0.0, 1.0]))
    # the load ODE (a [circuit] kind = "load" or "series-rc")
    lumped.load_response(t, q, 2e-9 * np.pi * 20.0 * np.cos(2 * np.pi * 20.0 * t), c, 1e9)
    # the ball's contact charging ([charge] model = "contact")
    from .source._kernel import contact_recurrence
    contact_recurrence(np.ones(3), np.full(3, 1e-3), -1e-9, 1.0, 0.0)
    # an array's cells: many trajectories sampled in one call, then the splines
    from .dynamics.impact import TrajectoryBundle
    cell, _ = array.cell_trajectory(scene, (0.0, 0.9, 0.0))
    TrajectoryBundle([cell, cell])(np.linspace(0.1, 0.2, 50))
    from .source._kernel import spline_terminal
    knots = np.linspace(0.0, 3e-3, 5)
    coeffs = np.zeros((4, knots.size - 1))
    spline_terminal(np.zeros(3), np.zeros(3), knots, coeffs, coeffs, 3e-3)


def kernels() -> list:
    """Every numba dispatcher of :data:`KERNEL_MODULES` (imports them)."""
    import importlib

    from numba.core.registry import CPUDispatcher

    found = {}
    for name in KERNEL_MODULES:
        module = importlib.import_module(name)
        # each once, in the module that defines it (one module imports another's)
        found.update({id(v): v for v in vars(module).values()
                      if isinstance(v, CPUDispatcher) and v.py_func.__module__ == name})
    return list(found.values())


def index_file(dispatcher) -> str | None:
    """The path of ``dispatcher``'s numba cache index (``*.nbi``), or None when
    it has no on-disk cache (not ``cache=True``, or no writable place for it)."""
    cache = getattr(dispatcher, "_cache", None)
    cache_file = getattr(cache, "_cache_file", None)
    return getattr(cache_file, "_index_path", None)


def cache_dirs(dispatchers) -> list[str]:
    """The directories numba keeps these dispatchers' cache files in."""
    import os

    return sorted({os.path.dirname(p) for p in map(index_file, dispatchers) if p})


def main() -> int:
    t0 = time.perf_counter()
    try:
        _workloads()
    except Exception as exc:  # noqa: BLE001 - one line, then fail
        print(f"tengfield warm-up: failed: {type(exc).__name__}: {exc}", file=sys.stderr)
        return 1
    import os

    found = kernels()
    cached = sum(bool(p) and os.path.exists(p) for p in map(index_file, found))
    where = ", ".join(cache_dirs(found)) or "nowhere"
    print(f"tengfield warm-up: {cached} of {len(found)} numba kernels in the cache after "
          f"{time.perf_counter() - t0:.1f} s; cache in {where}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
