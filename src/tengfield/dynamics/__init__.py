"""Non-smooth dynamics of the ball between the two plates (DESIGN.md section 5).

``simulate(scene)`` integrates the motion relative to the table with the
contact model of ``scene.contact.model``, taken from ``MODELS``
(:mod:`tengfield.dynamics.models`: one entry per model):

* ``"impact"``: rigid plates, Newton restitution, exact free flight between
  events, sticking/lift-off and chatter handled exactly
  (:mod:`tengfield.dynamics.impact`, compiled with numba);
* ``"soft"``: the spring-dashpot contact of the paper's Eq. (1) integrated
  by a stiff SciPy solver (:mod:`tengfield.dynamics.soft`);
* ``"3d"``: the rigid ball in the tube, with wall contacts, friction and spin
  (:mod:`tengfield.dynamics.motion3d`, compiled with numba).

The table motion of each ``[excitation] kind`` is one entry of
:data:`tengfield.dynamics.excitation.EXCITATIONS`.

``regime_map(scene, frequencies_hz, amplitudes_m)`` classifies the motion on
a grid of excitations. Importing this package never imports dolfinx or gmsh.
"""
from __future__ import annotations

from .result import REGIMES, DynamicsResult, Impacts, Regime

__all__ = ["simulate", "regime_map", "DynamicsResult", "Impacts", "Regime", "REGIMES",
           "MapResult", "MODELS"]


def simulate(scene, *, duration: float | None = None) -> DynamicsResult:
    """Trajectory of the ball for ``scene`` over ``duration`` [s] (default scene.run.duration).

    Starts at ``scene.initial`` (time, gap, velocity relative to the table),
    samples at ``scene.run.sample_rate_hz``; ``[contact] model`` picks the impact map,
    soft contact or the 3D rigid ball from ``MODELS`` (:mod:`tengfield.dynamics.models`);
    the regime is taken from the window after ``scene.run.settle_periods`` excitation
    periods.
    Raises :class:`tengfield.errors.DynamicsError` if the motion cannot be
    integrated (e.g. the bound on events per period is exceeded). ``scene``: a
    :class:`~tengfield.Scene` or a dict of sections (as :func:`tengfield.run`);
    ``duration``: a positive finite number of seconds.
    """
    import math
    import numbers

    from ..scene import as_scene
    from .models import model_of
    if duration is not None:
        if isinstance(duration, bool) or not isinstance(duration, numbers.Real):
            raise TypeError(f"tengfield.simulate: duration = {duration!r:.40} must be a "
                            f"number of seconds (a float), got {type(duration).__name__}")
        duration = float(duration)
        if not (math.isfinite(duration) and duration > 0.0):
            raise ValueError(f"tengfield.simulate: duration = {duration!r} s is out of range: "
                             "allowed (0, inf)")
    scene = as_scene(scene, "simulate")
    _warn_lateral_left_out(scene)
    model = model_of(scene)
    result = model(scene, duration=duration)
    result = _settled(scene, model, result, scene.run.duration if duration is None else duration)
    result.scene = scene
    return result


def _settled(scene, model, result, duration: float):
    """``result`` with its regime checked for settling
    (:func:`tengfield.dynamics.regime.settled_regime`: the run continued to twice, four
    times, ... its length) when the table motion repeats each period (a sine, or
    harmonics of it without noise) and the model is the exact
    impact map (fast); other runs keep the regime of their own window (an aperiodic
    window of a random drive is chaos (aperiodic), never "not-settled")."""
    import dataclasses

    from ..errors import TengfieldError
    from .excitation import excitation_kind, repeats_each_period
    from .regime import settled_regime

    if not repeats_each_period(scene):
        # a random or noisy drive never settles: aperiodic motion is the drive's, and is
        # called chaos (aperiodic) whatever the window's length, as before issue #42
        if result.regime.name == "not-settled":
            return dataclasses.replace(result, regime=dataclasses.replace(result.regime,
                                                                          name="chaos"))
        return result
    if not model.event_map:
        return result
    # the longer runs sampled sparsely: only their regime is used (the exact event map's
    # trajectory and regime do not depend on the sample rate)
    sparse = []

    def regime_of(span):
        if span <= duration * (1 + 1e-12):
            return result.regime
        try:
            if not sparse:
                rate = min(scene.run.sample_rate,
                           CHECK_SAMPLES_PER_PERIOD * scene.excitation.frequency)
                sparse.append(scene.with_values(run={"sample_rate_hz": rate}))
            longer = sparse[0]
            if not excitation_kind(scene).periodic:   # harmonics: a table built per run
                longer = longer.with_values(run={"duration_s": span})
            return model(longer, duration=span).regime
        except TengfieldError:     # too many samples or events: the check stops here
            raise _Unchecked from None

    try:
        regime = settled_regime(regime_of, duration, scene.excitation.period)
    except _Unchecked:
        return result
    return dataclasses.replace(result, regime=regime)


#: samples per excitation period of the settling check's longer runs (their sampled
#: columns are not used)
CHECK_SAMPLES_PER_PERIOD = 16


class _Unchecked(Exception):
    """A longer run of the settling check could not be simulated."""


def _warn_lateral_left_out(scene) -> None:
    """One warning when the scene drives the table sideways and its contact model
    moves the ball along the axis only (the lateral keys would be left out silently)."""
    from .models import model_of
    exc = scene.excitation
    if model_of(scene).lateral:
        return
    given = [f"{key} = {value:g}" for key, value in (
        ("amplitude_x_mm", exc.amplitude_x * 1e3), ("amplitude_y_mm", exc.amplitude_y * 1e3),
        ("rms_acceleration_x_m_per_s2", exc.rms_acceleration_x),
        ("rms_acceleration_y_m_per_s2", exc.rms_acceleration_y)) if value != 0.0]
    given += [f"{key} = {value!r}" for key, value in (
        ("signal_x_column", exc.signal_x_column), ("signal_y_column", exc.signal_y_column))
        if value]
    if given:
        import warnings
        warnings.warn(f"[excitation] {', '.join(given)} left out: [contact] model = "
                      f"{scene.contact.model!r} moves the ball along the axis only (a lateral "
                      f"drive needs model = \"3d\")", RuntimeWarning, stacklevel=3)


def regime_map(scene, frequencies_hz, amplitudes_m, *, jobs: int | None = None,
               progress: bool = True, periods: int = 200, settle_periods: int | None = None,
               comm=None):
    """Regime at every (frequency [Hz], amplitude [m]) pair of a grid -> ``MapResult``.

    Arrays are indexed [amplitude, frequency]; ``records()`` gives one dict per
    point. Runs ``periods`` excitation periods per point on ``jobs`` processes
    (default all cores) or over the ranks of ``comm`` (MPI task farm); see
    :func:`tengfield.dynamics.mapping.regime_map`.
    """
    from .mapping import regime_map as _regime_map
    return _regime_map(scene, frequencies_hz, amplitudes_m, jobs=jobs, progress=progress,
                       periods=periods, settle_periods=settle_periods, comm=comm)


def __getattr__(name):
    if name == "MapResult":
        from .mapping import MapResult
        return MapResult
    if name == "MODELS":
        from .models import MODELS
        return MODELS
    raise AttributeError(name)
