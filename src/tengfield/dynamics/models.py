"""The dynamics' contact models, one entry each (as SciPy's ``solve_ivp`` keeps ``METHODS``).

:data:`MODELS` maps ``[contact] model`` to the function that runs it; every entry
has the interface of :class:`Model`. :func:`tengfield.dynamics.simulate` picks
the entry and calls it; a new model is one entry here (plus its keys in the scene
schema). Importing this module loads the models' modules (numba kernels, compiled
on first call); ``import tengfield.dynamics`` does not, it imports this on the
first run.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

from .._registry import lookup
from .impact import simulate_impact
from .motion3d import simulate_3d
from .result import DynamicsResult
from .soft import simulate_soft


class Model(Protocol):
    """A contact model: the trajectory of ``scene`` over ``duration`` [s] (None:
    ``[run] duration_s``), from ``[initial] time_s``; raises
    :class:`tengfield.errors.DynamicsError` when the motion cannot be integrated."""

    def __call__(self, scene, *, duration: float | None = None) -> DynamicsResult: ...


@dataclass(frozen=True)
class ContactModel:
    """One ``[contact] model``: ``run`` (a :class:`Model`; the entry is called as it is)
    and its capabilities, what callers ask instead of comparing the model's name:
    ``lateral``: the ball moves off the axis (the table's x and y drive it; its run
    writes trajectory3d and contacts); ``event_map``: the exact impact map that
    ``[array]`` cells with their own dynamics need."""
    run: Model
    lateral: bool = False
    event_map: bool = False

    def __call__(self, scene, *, duration: float | None = None) -> DynamicsResult:
        return self.run(scene, duration=duration)


#: ``[contact] model`` -> its :class:`ContactModel`
MODELS: dict[str, ContactModel] = {
    # rigid plates, Newton restitution, exact event map (.impact)
    "impact": ContactModel(simulate_impact, event_map=True),
    # spring-dashpot contact, stiff SciPy solver (.soft)
    "soft": ContactModel(simulate_soft),
    # rigid ball in the tube, walls, friction, spin (.motion3d)
    "3d": ContactModel(simulate_3d, lateral=True),
}


def model_of(scene) -> ContactModel:
    """The :class:`ContactModel` of ``scene.contact.model``."""
    return lookup(MODELS, scene.contact.model, "[contact] model")
