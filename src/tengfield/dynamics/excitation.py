"""Kinds of ``[excitation]``: how each moves the table, one entry each.

:data:`EXCITATIONS` maps ``[excitation] kind`` to an :class:`ExcitationKind`
(as SciPy's ``solve_ivp`` maps a method name to its solver): the vertical table
motion that every model integrates, and the lateral ones of the 3D model. A new
kind is one entry here (plus its keys in the scene schema); the pieces it is made
of stay where they are: :mod:`.table` (sine, recorded splines) and
:mod:`.vibration` (random and multi-harmonic records).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from .._registry import lookup
from ..errors import DynamicsError
from .table import TableMotion, recorded_table, sine_phase_at, sine_table
from .vibration import scene_vibration_table


@dataclass(frozen=True)
class ExcitationKind:
    """One kind of ``[excitation]``.

    ``vertical(scene, origin, phase) -> TableMotion``: y(t) [m] on the time axis
    ``t - origin`` [s] (runs integrate relative to their start, so the precision does
    not depend on the absolute time); ``phase`` [rad] is the drive's phase
    (``[excitation] phase_deg``, or an ``[array]`` cell's own), used by a kind that
    has one (``phased``).

    ``lateral(scene) -> (x, y)``: the table motion along x and y on the absolute time
    axis (the 3D model).

    Capabilities (what callers ask instead of comparing the kind's name):
    ``periodic``: one frequency and amplitude describe it (``frequency_hz``,
    ``amplitude_mm``), so sweeps, regime maps, design bands and fit's amplitude scale
    can vary them; ``phased``: it takes another phase (an ``[array]`` cell's own);
    ``random``: it has a noise seed (``[run] realisations`` draw new ones);
    ``recorded``: it is a measured record of fixed length (runs must lie inside it).
    """
    vertical: Callable[..., TableMotion]
    lateral: Callable[..., tuple[TableMotion, TableMotion]]
    phased: bool = False
    periodic: bool = False
    random: bool = False
    recorded: bool = False


def _still(scene) -> TableMotion:
    """No motion along an axis (a sine of amplitude 0 at the drive's frequency)."""
    return sine_table(0.0, scene.excitation.omega, 0.0)


def _sine_vertical(scene, origin: float, phase: float) -> TableMotion:
    exc = scene.excitation
    return sine_table(exc.amplitude, exc.omega, sine_phase_at(exc.frequency, phase, origin))


def _sine_lateral(scene) -> tuple[TableMotion, TableMotion]:
    """A sine per axis: ``amplitude_x_mm``/``phase_x_deg``, ``amplitude_y_mm``/``phase_y_deg``."""
    exc = scene.excitation
    return (sine_table(exc.amplitude_x, exc.omega, exc.phase_x),
            sine_table(exc.amplitude_y, exc.omega, exc.phase_y))


def _recorded_vertical(scene, origin: float, phase: float) -> TableMotion:
    exc = scene.excitation
    return recorded_table(exc.times, exc.values, exc.signal, origin=origin,
                          smoothing_hz=exc.smoothing)


def _recorded_lateral(scene) -> tuple[TableMotion, TableMotion]:
    """The columns ``signal_x_column``, ``signal_y_column`` of the same file, read with the
    scene (``Excitation.values_x``/``values_y``; none: still)."""
    exc = scene.excitation
    return tuple(_still(scene) if values is None
                 else recorded_table(exc.times, values, exc.signal)
                 for values in (exc.values_x, exc.values_y))


def _vibration_vertical(scene, origin: float, phase: float) -> TableMotion:
    return scene_vibration_table(scene, origin)


def _vibration_lateral(scene) -> tuple[TableMotion, TableMotion]:
    """Per axis: the fundamental's sine plus noise (:func:`.vibration.scene_vibration_table`)."""
    return scene_vibration_table(scene, axis="x"), scene_vibration_table(scene, axis="y")


#: ``[excitation] kind`` -> how it moves the table
EXCITATIONS: dict[str, ExcitationKind] = {
    "sine": ExcitationKind(_sine_vertical, _sine_lateral, phased=True, periodic=True),
    "recorded": ExcitationKind(_recorded_vertical, _recorded_lateral, recorded=True),
    "random": ExcitationKind(_vibration_vertical, _vibration_lateral, random=True),
    "harmonics": ExcitationKind(_vibration_vertical, _vibration_lateral, random=True),
}


def excitation_kind(scene) -> ExcitationKind:
    """The :class:`ExcitationKind` of ``scene.excitation.kind``."""
    return lookup(EXCITATIONS, scene.excitation.kind, "[excitation] kind")


def repeats_each_period(scene) -> bool:
    """The table motion repeats with the drive's period ``1 / frequency_hz``: a periodic
    kind (the sine), or a harmonics drive with no noise whose components are all whole
    multiples of its fundamental (to 1e-9). Such a run can be continued to check that
    its regime settled (:func:`tengfield.dynamics._settled`)."""
    kind = excitation_kind(scene)
    if kind.periodic:
        return True
    exc = scene.excitation
    if kind.recorded or exc.has_noise or not exc.harmonics:
        return False
    ratios = [f / exc.frequency for f, _, _ in exc.harmonics]
    return all(round(r) >= 1 and abs(r - round(r)) <= 1e-9 * r for r in ratios)


def table_from_scene(scene, origin: float = 0.0, *, phase: float | None = None) -> TableMotion:
    """The vertical table motion of ``scene.excitation`` on the time axis ``t - origin`` [s].

    ``phase`` [rad] replaces ``[excitation] phase_deg`` (an ``[array]`` cell's own
    phase); only a kind with a phase of its own (the sine) can take another one.
    """
    kind = excitation_kind(scene)
    own = scene.excitation.phase
    if phase is None:
        phase = own
    elif phase != own and not kind.phased:
        raise DynamicsError(f"[excitation] kind = {scene.excitation.kind!r} cannot be shifted "
                            f"to phase {phase:g} rad (only a sine can)")
    return kind.vertical(scene, origin, phase)

