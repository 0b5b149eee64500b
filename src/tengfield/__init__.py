"""tengfield: predict what a bouncing-ball triboelectric nanogenerator delivers.

Pipeline: scene -> impact dynamics -> field surrogate (dolfinx) -> circuit ->
V_OC, Q_SC, I_SC. In a notebook::

    import tengfield as tf
    scene = tf.default_scene()            # or tf.load_scene("my.toml")
    r = tf.run(scene)                     # r.t, r.V_oc, r.Q_sc, r.I_sc, r.peaks, r.stages
    dyn = tf.simulate(scene)              # the ball's motion alone
    res = tf.solve_position(scene, 1e-3)  # electrostatics at one gap z [m]
    table, outcome = tf.build_surrogate(scene)   # the cached field surrogate
    ball = tf.simulate_3d(scene)          # the rigid ball in 3D (wall, friction, spin)
    fit = tf.calibrate(scene, measured=trace)    # sigma, C_p, ... fitted to a trace
    best = tf.design(scene)               # the geometry that serves [design]'s band best
    study = tf.uncertainty(scene)         # bands and Sobol indices over [uncertainty.vary]
    limit = tf.breakdown(scene)           # the air-breakdown limit on sigma (Paschen)
    rep = tf.report(scene, fast=True)     # error against run time, cheapest settings
    rows = tf.sweep(scene, vary={"device.stroke_mm": "1:5:9"}, frequency_hz=[20, 30])
    grid = tf.map(scene, frequency_hz="5:70:40", amplitude_mm="0.1:5:40")   # regime map
    tf.harvest.harvest(t, q_sc, c_t, storage_capacitance=10e-6)   # bridges into a store

Importing tengfield loads neither dolfinx, gmsh nor numba: ``run``,
``simulate``, ``solve_position``, ``build_surrogate``, ``simulate_3d``,
``calibrate``, the study verbs ``design``, ``uncertainty``, ``breakdown``, ``report``
(their packages: ``design_study``, ``uncertainty_study``, ``air_breakdown``,
``accuracy_report``) and the submodules are imported on first use.
"""
from __future__ import annotations

from . import _early_interrupt  # noqa: F401 - first: Ctrl-C during the CLI's imports
import importlib

__version__ = "0.1.0"

from .errors import DynamicsError, FieldError, SceneError, TengfieldError  # noqa: E402
from ._console import headless_vtk as _headless_vtk  # noqa: E402

_headless_vtk()   # a script's or notebook's field.png: no X-server warning on stderr
from .scene import Scene, default_scene, load_scene, parse_scene  # noqa: E402

#: public name -> (module, attribute), imported on first access
_LAZY = {
    "run": ("tengfield.pipeline", "run"),
    "simulate": ("tengfield.dynamics", "simulate"),
    "RunResult": ("tengfield.pipeline", "RunResult"),
    "solve_position": ("tengfield.field", "solve_position"),
    "build_surrogate": ("tengfield.surrogate", "obtain_table"),
    "simulate_3d": ("tengfield.dynamics.motion3d", "simulate_3d"),
    "calibrate": ("tengfield.fit", "calibrate"),
    "map": ("tengfield.dynamics.mapping", "map_study"),
    "design": ("tengfield.design_study", "design"),
    "uncertainty": ("tengfield.uncertainty_study", "run_study"),
    "breakdown": ("tengfield.air_breakdown", "study"),
    "report": ("tengfield.accuracy_report", "build_report"),
    "sweep": ("tengfield.sweeps", "study"),
}

__all__ = ["Scene", "default_scene", "load_scene", "parse_scene", "SceneError",
           "TengfieldError", "DynamicsError", "FieldError", "__version__",
           *(name for name in _LAZY if name != "map")]   # tf.map: never shadow the builtin on *


def __getattr__(name: str):
    """Import the heavy entry points (and submodules) only when first used."""
    if name in _LAZY:
        module, attribute = _LAZY[name]
        value = getattr(importlib.import_module(module), attribute)
        globals()[name] = value
        return value
    try:
        return importlib.import_module(f"{__name__}.{name}")
    except ModuleNotFoundError as exc:
        if exc.name != f"{__name__}.{name}":
            raise
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None


def __dir__():
    return sorted(set(globals()) | set(_LAZY))
