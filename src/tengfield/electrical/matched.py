"""The matched resistive load of a run: the resistor that takes the most mean power.

A scan over loads of one run's own Q_SC(t), C_T(t) and motion (no field solve, no new
dynamics): a log grid of :data:`LOAD_GRID` loads over +- :data:`LOAD_DECADES` around
1 / (2 pi f C_T), then Brent's bounded search (scipy) between the best grid point's
neighbours, each load through the load circuit's own integrator
(:func:`~tengfield.electrical.circuits.load.steady_load`, over the steady window; the
load-independent part of its grid built once, :class:`LoadGrid`). ``tengfield run``'s
``matched_load`` and ``tengfield design``'s matched load are this one function.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np

from .circuits.load import LoadGrid, steady_load

#: matched-load scan: decades either side of 1 / (2 pi f C_T), grid points, Brent's tolerance
LOAD_DECADES = 1.5
LOAD_GRID = 7
LOAD_XATOL_DECADES = 0.01


def loaded_scene(point, load: float):
    """``point`` with ``[circuit] kind = "load"``, ``load_ohm = load`` [ohm]: what
    ``point.with_values(circuit=...)`` gives, without parsing the whole scene again (the
    load scan asks ~40 loads per candidate): the section replaced (its own checks run),
    and the values as given (``raw``) with it."""
    from ..scene.schema import update_section

    raw = dict(point.raw)
    raw["circuit"] = dict(raw.get("circuit", {}))
    update_section(raw, "circuit", {"kind": "load", "load_ohm": float(load)})
    return dataclasses.replace(point, circuit=dataclasses.replace(
        point.circuit, kind="load", load=float(load)), raw=raw)


def load_power(point, dynamics, curves, load: float, grid=None) -> float:
    """The mean power [W] into ``load`` [ohm] over the steady window (:func:`steady_load`)."""
    loaded = loaded_scene(point, load)
    return float(steady_load(loaded, dynamics, curves, grid=grid)["mean_power_W"])


def matched_load(points, dynamics, curves, aggregate: str,
                 bounds: tuple | None = None) -> tuple[float, list[float]]:
    """(R [ohm], powers [W] per point) maximising the aggregate mean power of ``points``
    (band scenes with their ``dynamics``) into one resistor: a log grid of LOAD_GRID
    loads over +- LOAD_DECADES around 1 / (2 pi f C_T) (f, C_T: means over the points),
    then Brent's bounded search (scipy) between the best grid point's neighbours.
    ``bounds`` ([design] load_ohm, [ohm]): every load searched lies in [lo, hi].
    ``curves``: the terminal curves of every point, or a list of each point's own."""
    from scipy.optimize import minimize_scalar

    # one curves object for every point, or each point's own (a charge that differs by
    # point: the contacts' steady charge of each band point of a design)
    per_point = list(curves) if isinstance(curves, (list, tuple)) else [curves] * len(points)
    n_cells = points[0].device.cells
    c_t = float(np.mean(per_point[0].capacitance_samples)) * n_cells \
        + points[0].circuit.parallel_capacitance
    f = float(np.mean([p.excitation.frequency for p in points]))
    centre = math.log10(1.0 / (2 * math.pi * f * c_t))
    cache: dict[float, list[float]] = {}
    # each point's load-independent grid, built once for the scan (the same numbers)
    grids = [LoadGrid(p, d, c) for p, d, c in zip(points, dynamics, per_point)]

    def powers(log_r: float) -> list[float]:
        key = round(float(log_r), 12)
        if key not in cache:
            cache[key] = [load_power(p, d, c, 10.0**key, g)
                          for p, d, c, g in zip(points, dynamics, per_point, grids)]
        return cache[key]

    def score(log_r: float) -> float:
        p = powers(log_r)
        return float(np.mean(p) if aggregate == "mean" else np.min(p))

    floor, ceiling = (math.log10(bounds[0]), math.log10(bounds[1])) if bounds else \
        (-math.inf, math.inf)
    start, stop = max(centre - LOAD_DECADES, floor), min(centre + LOAD_DECADES, ceiling)
    if start >= stop:   # the range lies wholly on one side of 1 / (2 pi f C_T): all of it
        start, stop = floor, ceiling
    grid = np.linspace(start, stop, LOAD_GRID)
    scores = [score(x) for x in grid]
    k = int(np.argmax(scores))
    lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, LOAD_GRID - 1)]
    if k in (0, LOAD_GRID - 1):   # the optimum at the grid's edge: widen once
        lo, hi = (grid[0] - 2 * LOAD_DECADES, grid[1]) if k == 0 else \
            (grid[-2], grid[-1] + 2 * LOAD_DECADES)
        lo, hi = max(lo, floor), min(hi, ceiling)
    if all(s == 0 for s in scores):
        x = min(max(centre, floor), ceiling)
        return 10.0**x, powers(x)
    best = minimize_scalar(lambda x: -score(x), bounds=(lo, hi), method="bounded",
                           options={"xatol": LOAD_XATOL_DECADES})
    x = float(best.x) if -best.fun >= scores[k] else float(grid[k])
    return 10.0**x, powers(x)
