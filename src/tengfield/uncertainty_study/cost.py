"""The work of a study, counted and said before it starts (issue #43.6, #43.3).

:func:`study_cost` counts what a study of the drawn values will do without doing any of
it: the evaluations, the field solves (at most: one per distinct geometry, fewer when the
cache holds some), the dynamics runs (one per group of equal dynamics inputs and the
nominal run), the surrogate cache it may add and the memory it holds (the evaluations'
outputs until the files are written, the Sobol bootstrap). :func:`check_cost` refuses a
study past its limits in one line naming the key that sets the limit, before any work;
:meth:`WorkCost.line` is the line printed before the work starts.

Neutral on purpose: :class:`WorkCost`, :func:`available_memory` and
:func:`check_cost` take plain numbers, so ``tengfield design`` can announce and bound its
candidates the same way.
"""
from __future__ import annotations

import os
from dataclasses import dataclass

from ..errors import SceneError

#: bytes one cached surrogate takes on disk (the default cell's table: 60 kB; 76 kB on
#: average over the geometries of a probe, issue #43.6)
SURROGATE_BYTES = 80_000
#: bytes one evaluation holds until the files are written: its outputs and its row of
#: uncertainty.csv as text (measured with tracemalloc on a σ study of the default scene:
#: 15 outputs, 1.9 kB + 1.3 kB; a load or rectifier circuit has about twice the outputs)
EVALUATION_BYTES = 5_000
#: the part of the available memory a study may plan to hold (the rest: Python, numpy,
#: the dynamics of the group at hand, the other processes)
MEMORY_FRACTION = 0.5


@dataclass(frozen=True)
class WorkCost:
    """What a piece of work will do: ``evaluations``, ``field_solves`` (at most),
    ``dynamics_runs``, ``cache_bytes`` (at most, the surrogates it may add) and
    ``memory_bytes`` (its peak, estimated)."""
    evaluations: int
    field_solves: int
    dynamics_runs: int
    cache_bytes: int
    memory_bytes: int

    def line(self, what: str = "uncertainty") -> str:
        """``tengfield: uncertainty: 1,280 evaluations: at most 512 field solves, ...``"""
        return (f"tengfield: {what}: {self.evaluations:,} evaluations: at most "
                f"{self.field_solves:,} field solve{'s' * (self.field_solves != 1)} "
                f"(~{show_bytes(self.cache_bytes)} of surrogate cache), "
                f"{self.dynamics_runs:,} dynamics run{'s' * (self.dynamics_runs != 1)}, "
                f"~{show_bytes(self.memory_bytes)} of memory")


def show_bytes(n: float) -> str:
    """``1.5 GB``, ``80 kB``, ``0 B`` (decimal units)."""
    for unit, size in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= size:
            return f"{n / size:.3g} {unit}"
    return f"{int(n)} B"


def available_memory() -> int | None:
    """Bytes of memory available to a new allocation (``MemAvailable`` of /proc/meminfo,
    else the free physical pages), None when unknown."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return None


def check_cost(cost: WorkCost, *, field_limit: int, field_key: str, size_key: str,
               memory: int | None = None, what: str = "study") -> None:
    """Refuse ``cost`` in one line (SceneError) when its field solves exceed
    ``field_limit`` (set by the scene key ``field_key``) or its memory exceeds
    :data:`MEMORY_FRACTION` of ``memory`` (default: :func:`available_memory`; the key
    ``size_key`` is what to lower)."""
    if cost.field_solves > field_limit:
        raise SceneError(
            f"{field_key} = {field_limit}: the {what} needs up to {cost.field_solves:,} field "
            f"solves (~{show_bytes(cost.cache_bytes)} of surrogate cache, each solve seconds to "
            f"minutes): allowed <= {field_limit} (raise {field_key} to run it, or lower "
            f"{size_key} or vary fewer geometry keys)")
    memory = available_memory() if memory is None else memory
    if memory is not None and cost.memory_bytes > MEMORY_FRACTION * memory:
        raise SceneError(
            f"{size_key}: the {what} would hold ~{show_bytes(cost.memory_bytes)} "
            f"({cost.evaluations:,} evaluations x ~{show_bytes(EVALUATION_BYTES)} and the "
            f"bootstrap): allowed up to {MEMORY_FRACTION:.0%} of the "
            f"{show_bytes(memory)} available; lower {size_key}")


def study_cost(scene, spec, values) -> WorkCost:
    """The cost of the study ``spec`` of ``scene`` at the drawn ``values``
    (``(evaluations, D)``, file units): counted from the values alone, nothing built or
    solved."""
    import numpy as np

    from ..scene.schema import SURFACE_CHARGE_SETTING
    from .evaluation import is_electrical, is_field_key
    from .statistics import bootstrap_bytes

    keys = spec.keys
    values = np.asarray(values, dtype=float).reshape(len(values), len(keys))
    dynamic = [j for j, k in enumerate(keys) if not is_electrical(k)]
    groups = len({tuple(row) for row in values[:, dynamic]}) if dynamic else (1 if len(values)
                                                                            else 0)
    geometry = [j for j, k in enumerate(keys) if is_field_key(k, scene.device.shape)]
    charged = scene.device.ball_charge != 0.0 or SURFACE_CHARGE_SETTING in keys
    if not charged:
        solves = 0
    elif geometry:
        nominal = tuple(float(scene.to_dict()[keys[j].split(".", 1)[0]][keys[j].split(".", 1)[1]])
                        for j in geometry)
        solves = len({tuple(row) for row in values[:, geometry]} | {nominal})
    else:
        solves = 1
    memory = values.nbytes + len(values) * EVALUATION_BYTES
    if spec.method == "sobol":
        memory += bootstrap_bytes(spec.samples)
    return WorkCost(evaluations=len(values), field_solves=solves, dynamics_runs=groups + 1,
                    cache_bytes=solves * SURROGATE_BYTES, memory_bytes=int(memory))
