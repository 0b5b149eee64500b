"""One design candidate: its scene (geometry rule, charge, field settings) and its score.

:func:`candidate_scene` builds the device of one set of varied values; :func:`evaluate`
scores it on every band point: dynamics (impact map), the field surrogate (cached by
the field hash; on this process, ``comm=None``), then the circuit (matched resistive
load, rectifier, Q_SC peaks). An impossible candidate (a ball that does not fit, a
mesh the field cannot take...) comes back ``status = "skipped"`` with the reason; one
that misses ``require`` comes back ``"infeasible"`` without a field solve.
"""
from __future__ import annotations

import dataclasses

import math
import time
import warnings
from typing import Callable

import numpy as np

from .. import electrical
from ..electrical.matched import (LOAD_DECADES, LOAD_GRID, LOAD_XATOL_DECADES,  # noqa: F401
                                  load_power as _load_power, loaded_scene, matched_load)
from ..errors import TengfieldError
from .spec import OBJECTIVES, OTHER_VARY, DesignSpec, band_run, periodic
from ..scene.schema import SURFACE_CHARGE_KEY

#: the design's field settings (``[design] field = "coarse"``): degree 2, base mesh
#: min(DESIGN_MESH_MAX_MM, DESIGN_MESH_BALL_FRACTION x d), surrogate tolerance
#: DESIGN_TOLERANCE (9 -> 17 positions), meshes moved with the ball and mapped from the
#: candidate's canonical geometry (DESIGN_MESH_MOTION; field/moving.py: a function of
#: the candidate alone). Field error estimate measured 1.1e-2 (d = 5 mm) and 1.6e-2
#: (d = 10 mm at 1.43 mm); docs/design.md
DESIGN_DEGREE = 2
DESIGN_MESH_MAX_MM = 1.0
DESIGN_MESH_BALL_FRACTION = 0.2
DESIGN_TOLERANCE = 0.02
DESIGN_MESH_MOTION = "move"
#: windows an irregular (chaotic) band point is scored over: its spread enters the error bar
DYNAMICS_WINDOWS = 3


def design_field_settings(ball_diameter_mm: float) -> dict:
    """``[field]`` keys of the coarse design setting for a ball of this diameter."""
    return {"degree": DESIGN_DEGREE,
            "mesh_size_mm": float(f"{min(DESIGN_MESH_MAX_MM, DESIGN_MESH_BALL_FRACTION * ball_diameter_mm):.6g}"),
            "tolerance": DESIGN_TOLERANCE, "mesh_motion": DESIGN_MESH_MOTION}


def followed_geometry(base_device: dict, values: dict) -> dict:
    """``[device]`` keys that follow the varied ones (``geometry = "follow"``), file units.

    The rule is the shape's (``base_device["shape"]``; ``scene/shapes/``): the tube keeps
    its radial clearance (bore - ball radius), wall and electrode inset, so a bigger ball
    gets a bigger bore; the spherical shell keeps its stroke (cavity - ball), so a bigger
    ball gets a bigger cavity. A key that is itself varied never follows.
    """
    from ..scene.shapes import followed_keys
    return followed_keys(base_device.get("shape", "tube"), base_device, values)


def candidate_charge(scene, table=None):
    """``(scene, table)`` at the ball's surface charge density σ a candidate is scored at.

    THE one place that decides it: the scene's own ``σ``
    (or its varied value); with ``σ = "breakdown"`` each geometry
    at its own air-breakdown limit, σ = −σ_max from its surrogate's gap lines
    (:func:`tengfield.air_breakdown.resolve_for_run`: the table, per unit ball charge,
    serves it: no new field solve), so designs are compared at charges they can hold. Raises
    :class:`~tengfield.errors.TengfieldError` when the limit is asked for and the surrogate
    has no gap lines.
    """
    from ..air_breakdown import resolve_for_run, uses_breakdown_charge

    if table is None or not uses_breakdown_charge(scene):
        return scene, table
    resolved, table, _ = resolve_for_run(scene, table)   # raises without gap lines
    return resolved, table


def candidate_scene(base, spec: DesignSpec, values: dict):
    """The scene of one candidate (``values``: varied keys, file units); raises
    :class:`~tengfield.errors.SceneError` when it is impossible."""
    from ..scene.shapes import derived_stroke

    device = {k: v for k, v in values.items() if k not in OTHER_VARY}
    base_device = base.to_dict()["device"]
    if spec.geometry == "follow":
        device.update(followed_geometry(base_device, device))
    device.update(derived_stroke(base.device.shape, base.raw.get("device", {}),
                                 {**base_device, **device}))
    sections = {"device": device}
    other = {k: v for k, v in values.items() if k in OTHER_VARY}
    for key, value in other.items():
        sections.setdefault(OTHER_VARY[key], {})[key] = value
    if spec.field == "coarse":
        d_mm = device.get("ball_diameter_mm", base.device.ball_diameter * 1e3)
        sections["field"] = design_field_settings(d_mm)
    scene = base.with_values(**{s: v for s, v in sections.items() if s != "field"})
    if "field" in sections:
        scene = scene.with_values(field=sections["field"])   # checks the field values
    return scene


def band_scene(scene, spec: DesignSpec, frequency: float, amplitude: float):
    """``scene`` driven at one band point (``amplitude`` [m]) for settle + window periods.
    A random or harmonics excitation is kept as the scene gives it (its one band point is
    its reference frequency and fundamental): every candidate meets the same realisation
    (the noise follows the run's clock and seed, not its length)."""
    run = band_run(spec, frequency)
    if not periodic(scene.excitation.kind):
        return scene.with_values(run=run)
    return scene.with_values(
        excitation={"frequency_hz": frequency, "amplitude_mm": amplitude * 1e3}, run=run)


def aggregate_values(values, how: str) -> float:
    arr = np.asarray(values, dtype=float)
    return float(np.mean(arr) if how == "mean" else np.min(arr))


def _regime_ok(regime, require: str) -> bool:
    if require == "upper-contact":
        return regime.upper_contacts_per_period > 0
    if require == "regular-contact":
        return regime.name == "regular-contact"
    return True


def evaluate(base, spec: DesignSpec, values: dict, *, cache_dir=None,
             solve: Callable | None = None, simulate: Callable | None = None,
             tables: dict | None = None) -> dict:
    """Score one candidate (``values``: varied keys, file units) -> a row (JSON-ready).

    ``tables``: an in-process memo {field hash: table} (a repeated geometry is free even
    without a disk cache). Never raises for a bad candidate: skipped rows carry ``reason``.
    """
    from .._args import check_instance
    from ..scene.parse import check_scene_argument
    from ..dynamics import simulate as default_simulate
    from ..air_breakdown import obtain_breakdown_table, uses_breakdown_charge

    check_scene_argument("design_study.evaluate", base, "base")
    check_instance("design_study.evaluate", spec, "spec", DesignSpec,
                   "a DesignSpec (tengfield.design_study.parse_design_section(scene))")
    check_instance("design_study.evaluate", values, "values", dict, "a dict of varied keys")
    from ..surrogate import TerminalCurves, obtain_table

    simulate = simulate or default_simulate
    row = {"values": dict(values), "status": "ok", "reason": "", "objectives": {},
           "objective": math.nan, "objective_error": math.nan, "band_values": {},
           "band_spread": {}, "dynamics_error": {}, "windows": [],
           "regimes": [], "upper_contacts_per_period": [], "upper_contact_fraction": math.nan,
           "load_ohm": None, "field_hash": "", "field_error": math.nan,
           "interpolation_error": math.nan, "field_status": "", "mesh_placements": {},
           "positions": 0,
           "device_volume_m3": math.nan, SURFACE_CHARGE_KEY: math.nan,
           "wall_s": {"field": 0.0, "dynamics": 0.0, "circuit": 0.0}}
    try:
        scene = candidate_scene(base, spec, values)
    except TengfieldError as exc:
        return {**row, "status": "skipped", "reason": str(exc)}
    volume = scene.device.cell_volume * scene.device.cells
    row["device_volume_m3"] = volume
    needs_field = any(OBJECTIVES[o][2] for o in spec.objectives)
    if needs_field and scene.field_problems:
        return {**row, "status": "skipped", "reason": "; ".join(scene.field_problems)}
    # dynamics at every band point
    start = time.perf_counter()
    points, dynamics = [], []
    try:
        for f, a in spec.band:
            point = band_scene(scene, spec, f, a)
            points.append(point)
            dynamics.append(simulate(point))
    except TengfieldError as exc:
        return {**row, "status": "skipped", "reason": str(exc),
                "wall_s": {**row["wall_s"], "dynamics": time.perf_counter() - start}}
    row["wall_s"]["dynamics"] = time.perf_counter() - start
    row["regimes"] = [d.regime.name for d in dynamics]
    row["upper_contacts_per_period"] = [float(d.regime.upper_contacts_per_period)
                                        for d in dynamics]
    row["upper_contact_fraction"] = float(np.mean([u > 0 for u in
                                                   row["upper_contacts_per_period"]]))
    missed = [(f, a) for (f, a), d in zip(spec.band, dynamics)
              if not _regime_ok(d.regime, spec.require)]
    if missed:
        f, a = missed[0]
        row.update(status="infeasible",
                   reason=f"require = {spec.require!r} not met at {len(missed)} of "
                          f"{len(spec.band)} band points (first: {f:g} Hz, {a * 1e3:g} mm)")
        return row
    if needs_field and spec.percentile is None and all(d.regime.name == "rest"
                                                       for d in dynamics):
        return _decided_at_rest(row, spec, points)
    # field surrogate (cached by the field hash)
    curves = table = None
    if needs_field:
        start = time.perf_counter()
        try:
            key = scene.field_hash()
            row["field_hash"] = key
            if tables is not None and key in tables:
                # the key and the table leave sigma out (per unit ball charge)
                table, row["field_status"] = tables[key], "memo"
            else:
                with warnings.catch_warnings():   # the coarse field's accuracy is reported
                    warnings.simplefilter("ignore", RuntimeWarning)   # as the error bar
                    obtain = obtain_breakdown_table if uses_breakdown_charge(scene) \
                        else obtain_table        # "breakdown": the surrogate with its lines
                    solved = scene
                    if scene.charge.from_contacts:   # the geometry at a reference charge
                        from ..contact_run import field_scene
                        from ..surrogate.cache import solved_scene
                        solved = solved_scene(field_scene(scene))
                    table, outcome = obtain(solved, cache_dir=cache_dir, comm=None,
                                            solve=solve)
                row["field_status"] = outcome.status
                if outcome.status in ("computed", "recomputed"):   # how its meshes were
                    row["mesh_placements"] = dict(          # placed (moved, meshed, mapped)
                        (table.provenance or {}).get("mesh_placements") or {})
                if tables is not None:
                    tables[key] = table
        except TengfieldError as exc:
            return {**row, "status": "skipped", "reason": f"field: {exc}",
                    "wall_s": {**row["wall_s"], "field": time.perf_counter() - start}}
        row["wall_s"]["field"] = time.perf_counter() - start
        row["field_error"] = float(np.nanmax(table.field_error)) \
            if np.isfinite(table.field_error).any() else 0.0
        row["interpolation_error"] = float(table.interpolation_error)
        row["positions"] = int(table.count)
        try:
            charged, table = candidate_charge(scene, table)
        except TengfieldError as exc:
            return {**row, "status": "skipped", "reason": f"breakdown: {exc}"}
        if charged is not scene:   # the band scenes at the charge the geometry can hold
            scene = charged        # (the motion does not depend on the charge)
            points = [band_scene(scene, spec, f, a) for f, a in spec.band]
        row[SURFACE_CHARGE_KEY] = scene.device.surface_charge * 1e6
        curves = TerminalCurves(table, scene.circuit.reference, scene.device.ball_charge)
        if scene.charge.from_contacts:   # each band point at the charge its contacts make
            try:
                points, curves = _at_contact_charge(points, dynamics, table, row)
            except TengfieldError as exc:
                return {**row, "status": "skipped", "reason": f"charge: {exc}"}
    # circuit
    start = time.perf_counter()
    band_values: dict[str, list[float]] = {}
    for objective in spec.objectives:
        band_values[objective] = _objective_values(objective, spec, scene, points, dynamics,
                                                   curves, volume, row)
    row["band_values"] = band_values
    row["band_spread"] = dynamics_spread(spec, points, dynamics, curves, volume, row, simulate)
    row["windows"] = [DYNAMICS_WINDOWS if irregular(d.regime) else 1 for d in dynamics]
    row["wall_s"]["circuit"] = time.perf_counter() - start
    robust = None
    if spec.percentile is not None:   # the objectives' percentiles over [uncertainty.vary]
        start = time.perf_counter()
        try:
            robust = robust_values(spec, points, row, cache_dir=cache_dir, solve=solve,
                                   simulate=simulate)
        except TengfieldError as exc:
            return {**row, "status": "skipped", "reason": f"uncertainty: {exc}"}
        row["wall_s"]["uncertainty"] = time.perf_counter() - start
        row["robust"] = robust
        row["uncertainty_evaluations"] = robust["evaluations"]
    eps = (0.0 if math.isnan(row["field_error"]) else row["field_error"]) + \
        (0.0 if math.isnan(row["interpolation_error"]) else row["interpolation_error"])
    row["relative_error"] = eps
    how = spec.band_aggregate
    for objective, vals in band_values.items():
        value = aggregate_values(vals, how)
        dyn_part = aggregate_spread(vals, row["band_spread"][objective], how)
        entry, pct_part = {"value": value}, 0.0
        if robust is not None:   # the band's mean of the percentiles; the nominal kept
            r = robust["objectives"][objective]
            pct_part = r["percentile_error"]
            entry = {"value": aggregate_values(r["band_percentiles"], "mean"),
                     "nominal": value, "percentile_error": pct_part}
        field_part = abs(entry["value"]) * OBJECTIVES[objective][1] * eps
        row["objectives"][objective] = {**entry, "error": field_part + dyn_part + pct_part}
        row["dynamics_error"][objective] = dyn_part
    row["objective"] = row["objectives"][spec.objective]["value"]
    row["objective_error"] = row["objectives"][spec.objective]["error"]
    return row


def _at_contact_charge(points, dynamics, table, row):
    """``[charge] model = "contact"``: each band point scored at the steady charge its own
    contacts make (:func:`tengfield.contact_run.contact_source` along its trajectory: the
    plateau a device at that vibration reaches), ``(points at it, one curves per point)``;
    ``row["charge"]``: each point's steady σ [µC/m²], its 90 % rise time [s] and what binds,
    ``row[σ key]`` their mean."""
    from ..contact_run import breakdown_limit, contact_source, field_scene
    from ..surrogate import TerminalCurves

    at, curves, block = [], [], {"steady_uC_per_m2": [], "rise_time_90_s": [], "binds": []}
    limit = breakdown_limit(field_scene(points[0]), table)   # one geometry: once
    for point, motion in zip(points, dynamics):
        run = contact_source(point, motion, table, limit)
        at.append(run.scene)
        curves.append(TerminalCurves(table, point.circuit.reference,
                                     run.scene.device.ball_charge))
        for key in block:
            block[key].append(run.block[key])
    row["charge"] = block
    row[SURFACE_CHARGE_KEY] = float(np.mean(block["steady_uC_per_m2"]))
    return at, curves


def _curves_of(curves, i):
    """Band point ``i``'s terminal curves: one for every point, or each point's own (a
    contact charge)."""
    return curves[i] if isinstance(curves, list) else curves


#: design.csv's field_status of a candidate decided by its dynamics alone
AT_REST_STATUS = "not solved (at rest at every band point)"


def _decided_at_rest(row: dict, spec: DesignSpec, points) -> dict:
    """A candidate whose ball rests on the lower electrode in every band point's window
    (regime "rest": it never lifts off): Q_SC, V_OC, I_SC, the load and harvested power
    are 0 whatever the field, so it is scored 0 (exactly, error 0) without a field solve
    (issue #40); the stroke objective keeps its value. ``field_status`` names it."""
    n = len(points)
    band_values = {o: [float(p.device.stroke) if o == "stroke" else 0.0 for p in points]
                   for o in spec.objectives}
    row.update(band_values=band_values, band_spread={o: [0.0] * n for o in spec.objectives},
               windows=[1] * n, field_status=AT_REST_STATUS, relative_error=0.0,
               at_rest=True)
    for objective, values in band_values.items():
        row["objectives"][objective] = {"value": aggregate_values(values, spec.band_aggregate),
                                        "error": 0.0}
        row["dynamics_error"][objective] = 0.0
    row["objective"] = row["objectives"][spec.objective]["value"]
    row["objective_error"] = 0.0
    return row


#: design objective -> the run summary's output a percentile aggregate takes (SI)
ROBUST_OUTPUTS = {"power": "load.mean_power_W", "power_density": "load.power_density_W_per_m3",
                  "charge": "peak_to_peak.Q_sc_C", "voltage": "peak_to_peak.V_oc_V",
                  "current": "peak_to_peak.I_sc_A",
                  "harvested_power": "rectifier.average_harvested_power_W"}


def robust_values(spec, points, row, *, cache_dir=None, solve=None, simulate=None) -> dict:
    """``[design] aggregate = "pNN"``: at each band point the study of ``[uncertainty]``
    (:func:`tengfield.uncertainty_study.study.candidate_percentiles`, on this process) on the
    candidate's band scene, with the matched (or varied) load of the nominal search kept
    for power objectives and the ``[circuit]`` rectifier for harvested power ->
    ``{"objectives": {objective: {"band_percentiles", "band_intervals", "band_nominal",
    "percentile_error"}}, "evaluations", "field_solves"}`` (field_solves: surrogates the
    studies did not find in the cache; 0 when the candidate's own was cached). The percentile error: the half-widths of the
    percentiles' 95 % intervals combined over the band as sqrt(sum s^2) / n."""
    from ..uncertainty_study.study import candidate_percentiles

    power = [o for o in spec.objectives if o in ("power", "power_density")]

    def at_load(point, i):      # power at the candidate's matched load; Q, V, I as run
        return point.with_values(circuit={"kind": "load", "load_ohm": float(_load_of(row, i))}) \
            if power else point

    def into_store(point, i):   # harvested power: the scene's [circuit] rectifier and store
        return point.with_values(circuit={"kind": "rectifier"})

    groups = [(power + [o for o in spec.objectives if o in ("charge", "voltage", "current")],
               at_load),
              ([o for o in spec.objectives if o == "harvested_power"], into_store)]
    out = {o: {"band_percentiles": [], "band_intervals": [], "band_nominal": []}
           for o in spec.objectives}
    evaluations = solves = 0
    for i, point in enumerate(points):
        for objectives, scene_of in groups:
            if not objectives:
                continue
            scene = scene_of(point, i)
            names = [ROBUST_OUTPUTS[o] for o in objectives]
            study = candidate_percentiles(scene, spec.uncertainty, names, spec.percentile,
                                          cache_dir=cache_dir, solve=solve, simulate=simulate)
            evaluations += study["evaluations"]
            solves += study["field_solves"]
            for o, name in zip(objectives, names):
                out[o]["band_percentiles"].append(study["scores"][name])
                out[o]["band_intervals"].append(list(study["intervals"][name]))
                out[o]["band_nominal"].append(study["nominal"][name])
    for o, r in out.items():
        half = [0.5 * (hi - lo) for lo, hi in r["band_intervals"]]
        half = [h for h in half if math.isfinite(h)]
        r["percentile_error"] = (math.sqrt(sum(h * h for h in half)) / len(half)
                                 if half else 0.0)
    return {"objectives": out, "evaluations": evaluations, "field_solves": solves}


def _point_value(objective, point, dynamics, curves, volume, load) -> float:
    """The objective at one band point (``point``: its scene, ``dynamics`` its motion,
    ``load`` [ohm] the resistor of a power objective), SI."""
    if objective == "stroke":
        return float(point.device.stroke)
    if objective in ("charge", "voltage", "current"):
        name = {"charge": "Q_sc", "voltage": "V_oc", "current": "I_sc"}[objective]
        return float(electrical.terminal_peaks(point, dynamics, curves)[name])
    if objective == "harvested_power":
        rect_scene = point.with_values(circuit={"kind": "rectifier"})
        rect = electrical.rectifier_waveforms(rect_scene, dynamics, curves)
        mask, _ = electrical.steady_window(dynamics.t, rect_scene)
        summary = electrical.rectifier_summary(rect_scene, rect["fine"],
                                               float(dynamics.t[mask][0]))
        return float(summary["average_harvested_power_W"])
    power = _load_power(point, dynamics, curves, load)
    return power / volume if objective == "power_density" else power


def _objective_values(objective, spec, scene, points, dynamics, curves, volume, row):
    if objective not in ("power", "power_density"):
        return [_point_value(objective, p, d, _curves_of(curves, i), volume, None)
                for i, (p, d) in enumerate(zip(points, dynamics))]
    # power / power_density into the matched (or the varied) resistive load
    if "load_ohm" in spec.vary:
        load = scene.circuit.load
        powers = [_load_power(p, d, _curves_of(curves, i), load)
                  for i, (p, d) in enumerate(zip(points, dynamics))]
        row["load_ohm"] = load
    elif spec.load == "one":
        load, powers = matched_load(points, dynamics, curves, spec.band_aggregate,
                                    spec.load_range)
        row["load_ohm"] = load
    else:
        loads, powers = [], []
        for i, (p, d) in enumerate(zip(points, dynamics)):
            r, (power,) = matched_load([p], [d], _curves_of(curves, i), "mean",
                                       spec.load_range)
            loads.append(r)
            powers.append(power)
        row["load_ohm"] = loads
    if objective == "power_density":
        return [p / volume for p in powers]
    return list(powers)


def irregular(regime) -> bool:
    """A band point whose motion does not repeat in the window (``chaos``, or
    ``not-settled``: aperiodic within the settling check's bound): one window's value
    is one sample of it."""
    return regime.name in ("chaos", "not-settled")


def _load_of(row, i):
    load = row["load_ohm"]
    return load[i] if isinstance(load, list) else load


def window_values(objective, spec, point, curves, volume, load, simulate) -> list[float]:
    """The objective of one band point over DYNAMICS_WINDOWS - 1 further windows of the
    same length (the run continued: settle + j x window periods, then one window), the
    same load: the samples its spread over windows is taken from."""
    out = []
    f = point.excitation.frequency
    for j in range(1, DYNAMICS_WINDOWS):
        settle = spec.settle_periods + j * spec.window_periods
        later = point.with_values(run={"duration_s": (settle + spec.window_periods) / f,
                                       "settle_periods": settle})
        out.append(_point_value(objective, later, simulate(later), curves, volume, load))
    return out


def dynamics_spread(spec, points, dynamics, curves, volume, row, simulate) -> dict:
    """Per objective: the spread (sample standard deviation over DYNAMICS_WINDOWS windows)
    of each irregular band point's value (0 elsewhere) -> row["band_spread"]."""
    spread = {o: [0.0] * len(points) for o in spec.objectives}
    for i, (p, d) in enumerate(zip(points, dynamics)):
        if not irregular(d.regime):
            continue
        for o in spec.objectives:
            if o == "stroke":
                continue
            first = row["band_values"][o][i]
            more = window_values(o, spec, p, _curves_of(curves, i), volume, _load_of(row, i),
                                 simulate)
            spread[o][i] = float(np.std([first, *more], ddof=1))
    return spread


def aggregate_spread(values, spreads, how: str) -> float:
    """The spread of the band's aggregate: mean -> sqrt(sum s_i^2) / n (independent
    windows); min -> the spread of the smallest point."""
    s = np.asarray(spreads, dtype=float)
    if how == "mean":
        return float(math.sqrt(float(np.sum(s ** 2))) / len(s))
    return float(s[int(np.argmin(values))])
