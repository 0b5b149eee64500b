"""The ball's charge made by its contacts along one trajectory, for every command that
runs a scene with ``[charge] model = "contact"`` (issue #52): ``run``, ``sweep`` (its
points and ``--vary charge.*``) and ``uncertainty`` (``[uncertainty.vary]`` draws of
``charge.*``) call :func:`contact_source` after their own field stage, so a study's row
is the run's numbers.

Given a scene, its trajectory and the surrogate table of its geometry (per unit ball
charge: Q_SC and the electrode charges are linear in the ball's charge), it
returns the charge history along the impacts (:mod:`tengfield.source.contacts`), the
summary's ``charge`` block, the scene at its steady charge (what the σ-dependent blocks
use), the table and the :class:`~tengfield.source.terminal.ContactCurves`
the circuits read. No field solve: the air-breakdown cap of ``[charge] discharge`` comes
from the table's gap lines and the trajectory.
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from .scene.schema import SURFACE_CHARGE_KEY


def reference_sigma(scene) -> float:
    """The σ [C/m²] a contact scene's field is solved at: σ_eq, or the initial σ when
    σ_eq = 0 (a ball that only leaks); 0 when both are 0 (no charge ever: no field)."""
    charge = scene.charge
    return float(charge.equilibrium if charge.equilibrium != 0.0 else charge.initial)


def field_scene(scene):
    """``scene`` at its :func:`reference_sigma` (the scene whose surrogate a contact run
    uses; its field hash is the geometry's, σ is not in it)."""
    return scene.with_values(device={SURFACE_CHARGE_KEY: reference_sigma(scene) * 1e6})


@dataclass
class ContactRun:
    """What :func:`contact_source` gives: ``scene`` at the steady charge, ``table`` (per
    unit ball charge; None: no field), ``curves`` (:class:`ContactCurves`, None without a
    field), the ``history`` (:class:`~tengfield.source.contacts.ChargeHistory`) and the
    summary's ``block``, ``limit`` (the breakdown limit of the geometry or None), the
    ``wall_time_s`` of the history, the ``whole`` run's trajectory and the first sample
    of its ``window`` (:func:`electrical_window`); :attr:`dynamics` is the trajectory the
    electrical stage runs along."""
    scene: object
    table: object
    curves: object
    history: object
    block: dict
    limit: object
    wall_time_s: float
    whole: object = None
    window: int = 0

    @functools.cached_property
    def dynamics(self):
        """The trajectory the electrical stage runs along: the run's last periods, or the
        whole run (:func:`tengfield.dynamics.columns.tail`; the impacts always the whole
        run's)."""
        if not self.window:
            return self.whole
        from . import electrical
        from .dynamics.columns import tail
        return tail(self.whole, self.window, window_start=self.block["waveforms"]["start_s"]
                    + electrical.steady_start(self.scene))

    @property
    def charged(self):
        """``(history, block)``: what the run's outputs add (the q_ball_C column, the
        ``charge`` block, ball_charge.png)."""
        return self.history, self.block


def discharge_cap(scene, limit, dynamics) -> float:
    """The air-breakdown cap [C/m²] of ``[charge] discharge`` (inf for "none" or without
    a limit): σ_max of the static states ("static"), else that edge of the breakdown band
    of the trajectory (:func:`tengfield.air_breakdown.scene_band`)."""
    charge = scene.charge
    if charge.discharge == "none" or limit is None:
        return math.inf
    if charge.discharge == "static":
        return float(limit.sigma_max)
    from .air_breakdown import scene_band
    return float(scene_band(scene, limit, dynamics).edges()[charge.discharge])


def electrical_window(scene, dynamics) -> tuple[int, dict]:
    """``(index, block)``: the first sample of ``dynamics`` the electrical stage of a
    contact run covers, and summary.json's ``charge.waveforms`` block.

    The charge follows every impact of the run (cheap: the impact map), the circuit only
    the samples it reports. ``[charge] waveforms`` = "steady": the run's last
    ``[run] settle_periods`` + ``[charge] window_periods`` excitation periods (the
    circuit's own settling, left out of the peaks as in any run, then the steady window),
    the whole run when it is no longer; "start-up": the whole run, from the ball's
    initial charge; "auto": "start-up" where the circuit fills a store from empty (a
    rectifier: its charging is the run), "steady" otherwise."""
    import bisect

    from . import electrical

    charge = scene.charge
    mode = charge.waveforms
    if mode == "auto":
        mode = "start-up" if electrical.circuit_for(scene).fills_store else "steady"
    elapsed = electrical.elapsed_times(dynamics)
    n = len(elapsed)
    first, end = float(elapsed[0]), float(elapsed[n - 1])
    period = float(scene.excitation.period)
    span = (scene.run.settle_periods + charge.window_periods) * period
    index = 0
    if mode == "steady" and end - first > span:
        index = min(bisect.bisect_left(elapsed, end - span), n - 2)   # the first >= start
    origin = electrical.time_origin(dynamics)
    start = float(elapsed[index])
    if index == 0:
        rule = ("the whole run" + ("" if mode == "start-up" else
                f": not longer than settle_periods + window_periods = "
                f"{scene.run.settle_periods + charge.window_periods} periods"))
    else:
        rule = (f"the run's last settle_periods + window_periods = "
                f"{scene.run.settle_periods} + {charge.window_periods} periods; the charge "
                "follows every impact from the start ([charge] waveforms = \"start-up\" "
                "for the whole run)")
    block = {"mode": mode, "requested": charge.waveforms, "start_s": origin + start,
             "end_s": origin + end, "whole_run": index == 0, "rule": rule}
    return index, block


def waveform_line(block: dict) -> str:
    """The terminal's line of a contact run whose waveforms leave out the start-up
    ('' when they cover the whole run)."""
    window = block.get("waveforms") or {}
    if not window or window.get("whole_run", True):
        return ""
    return (f"waveforms, peaks and figures: t = {window['start_s']:.6g} to "
            f"{window['end_s']:.6g} s (the steady window; the start-up: [charge] "
            'waveforms = "start-up")')


def breakdown_limit(scene, table):
    """The breakdown limit of ``table``'s geometry (None: the table has no gap lines)."""
    if table is None or table.line_potential is None:
        return None
    from .air_breakdown.charge import scene_breakdown
    return scene_breakdown(scene, table)


def contact_source(scene, dynamics, table, limit=None, *, period: float | None = None,
                   curves=None) -> ContactRun:
    """The contact run of ``scene`` along ``dynamics`` with ``table`` (its geometry's
    surrogate, per unit ball charge; None: no field needed, Q_SC = 0) and the
    geometry's breakdown ``limit`` (None: taken from the table's gap lines when it has
    them). ``period`` [s]: the period the contacts repeat with (default: the drive's
    where it repeats each period, else 0). ``curves``: the run's curves where the ball
    leaves the axis (the (z, r) ones,
    :class:`~tengfield.surrogate.table.AnchoredTerminalCurves`, at any charge: their
    (z, r) table is read); None: on the axis."""
    import time

    from . import electrical
    from .errors import TengfieldError
    from .source.contacts import charge_summary, run_history
    from .source.terminal import ContactCurves, ContactTerminal

    start = time.perf_counter()
    charge = scene.charge
    reference = field_scene(scene)
    if limit is None:
        limit = breakdown_limit(reference, table)
    if charge.discharge != "none" and limit is None and table is not None:
        raise TengfieldError(
            f'[charge] discharge = {charge.discharge!r} needs the air-breakdown lines of '
            'the surrogate (the axisymmetric solver makes them; this one has none): set '
            '[charge] discharge = "none" or [field] method = "axisymmetric"')
    cap = discharge_cap(reference, limit, dynamics) if table is not None else math.inf
    impacts = dynamics.impacts
    history, upper, law, areas = run_history(
        scene, impacts, np.asarray(impacts.time, dtype=float) - electrical.time_origin(dynamics),
        cap)
    elapsed = electrical.elapsed_times(dynamics)
    window_start = float(elapsed[electrical.steady_window_index(elapsed, scene)[0]])
    if period is None:
        from .dynamics.excitation import repeats_each_period
        period = float(scene.excitation.period) if repeats_each_period(scene) else 0.0
    block = charge_summary(history, law, cap_level=charge.discharge,
                           duration=float(elapsed[-1]), areas=areas,
                           window_start=window_start, period=period)
    block["relative_humidity_percent"] = charge.relative_humidity * 100.0
    if charge.relative_humidity > 0.0:   # sigma_eq, tau above are the humid ones
        from .humidity import LAW, breakdown_factor
        block["humidity_law"] = LAW
        block["breakdown_voltage_factor"] = breakdown_factor(charge.relative_humidity)
    steady = block["steady_uC_per_m2"] * 1e-6 * law.ball_area
    run_scene = scene.with_values(device={SURFACE_CHARGE_KEY: steady / law.ball_area * 1e6})
    index, block["waveforms"] = electrical_window(scene, dynamics)
    wall = time.perf_counter() - start
    if table is None or steady == 0.0 and history.start == 0.0 and not history.contacts:
        return ContactRun(run_scene, None, None, history, block, limit, wall, dynamics, index)
    if curves is not None and curves.radial:     # [contact] model = "3d", off the axis
        from .source.offaxis import OffAxisContactCurves, OffAxisContactTerminal
        terminal = OffAxisContactTerminal(table, curves.zr.table, history, upper,
                                          scene.circuit.reference)
        curves = OffAxisContactCurves(terminal, steady)
    else:
        terminal = ContactTerminal(table, history, upper, scene.circuit.reference)
        curves = ContactCurves(terminal, steady)
    return ContactRun(run_scene, table, curves, history, block, limit, wall, dynamics, index)


def check_contact_charge(scene, off_axis: bool = False) -> None:
    """Refuse, before the work and in one line, what ``[charge] model = "contact"`` does
    not run yet: unless ``off_axis`` (``run``: its (z, r) curves), a ball that leaves the
    axis. An ``[array]`` runs (each cell's ball charged by its own impacts,
    tengfield.array)."""
    from .errors import SceneError
    from .dynamics.models import MODELS, model_of

    if model_of(scene).lateral and not off_axis:
        on_axis = ", ".join(repr(name) for name, entry in MODELS.items() if not entry.lateral)
        raise SceneError('[charge] model = "contact" with [contact] model = '
                         f'"{scene.contact.model}": not supported yet (the ball off the '
                         f"axis); allowed: [contact] model = {on_axis}")


#: a study row's charge columns (sweep.csv, uncertainty's outputs), from the ``charge``
#: block: the steady σ [µC/m²], the time to 90 % of it [s], what binds
CHARGE_COLUMNS = ("sigma_steady_uC_per_m2", "rise_time_90_s", "charge_binds")


def charge_columns(block: dict) -> dict:
    """The :data:`CHARGE_COLUMNS` of a ``charge`` block."""
    return {"sigma_steady_uC_per_m2": block.get("steady_uC_per_m2"),
            "rise_time_90_s": block.get("rise_time_90_s"),
            "charge_binds": block.get("binds")}
