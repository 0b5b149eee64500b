"""The dynamics' contact models, one entry each (as SciPy's ``solve_ivp`` keeps ``METHODS``).

:data:`MODELS` maps ``[contact] model`` to the function that runs it; every entry
has the interface of :class:`Model`. :func:`tengfield.dynamics.simulate` picks
the entry and calls it; a new model is one entry here (plus its keys in the scene
schema). Importing this module loads the models' modules (numba kernels, compiled
on first call); ``import tengfield.dynamics`` does not, it imports this on the
first run.
"""
from __future__ import annotations

from typing import Protocol

from ..errors import SceneError
from .impact import simulate_impact
from .motion3d import simulate_3d
from .result import DynamicsResult
from .soft import simulate_soft


class Model(Protocol):
    """A contact model: the trajectory of ``scene`` over ``duration`` [s] (None:
    ``[run] duration_s``), from ``[initial] time_s``; raises
    :class:`tengfield.errors.DynamicsError` when the motion cannot be integrated."""

    def __call__(self, scene, *, duration: float | None = None) -> DynamicsResult: ...


#: ``[contact] model`` -> the function that runs it
MODELS: dict[str, Model] = {
    "impact": simulate_impact,   # rigid plates, Newton restitution, exact event map (.impact)
    "soft": simulate_soft,       # spring-dashpot contact, stiff SciPy solver (.soft)
    "3d": simulate_3d,           # rigid ball in the tube, walls, friction, spin (.motion3d)
}


def model_of(scene) -> Model:
    """The :class:`Model` of ``scene.contact.model``."""
    name = scene.contact.model
    try:
        return MODELS[name]
    except KeyError:
        raise SceneError(f"[contact] model = {name!r}: allowed "
                         f"{', '.join(map(repr, MODELS))}") from None
