"""A run's contacts as charge: the law of a scene's ``[charge]`` and the history of the ball's
charge along a trajectory's impacts (issue #52; docs/charge.md). Numbers in, numbers out:
the pipeline (:mod:`tengfield.pipeline`) calls these at its edge."""
from __future__ import annotations

import math

import numpy as np

from .charge import (ChargeHistory, ContactCharging, charge_history, effective_modulus,
                     hertz_contact_area)


def contact_law(scene, cap: float = math.inf) -> ContactCharging:
    """The condenser law of ``scene``'s ``[charge]`` on its ball (A = pi d^2), capped at
    ``cap`` [C/m^2] (the air-breakdown level of ``[charge] discharge``; inf: none);
    sigma_eq and tau at ``relative_humidity_percent`` (:mod:`tengfield.humidity`)."""
    from ..humidity import humid_equilibrium, humid_leakage_time

    charge, device = scene.charge, scene.device
    rh = charge.relative_humidity          # 0: dry, the values as given
    return ContactCharging(equilibrium=humid_equilibrium(charge.equilibrium, rh),
                           efficiency=charge.efficiency,
                           ball_area=math.pi * device.ball_diameter ** 2,
                           initial=charge.initial,
                           leakage_time=humid_leakage_time(charge.leakage_time, rh), cap=cap)


def contact_modulus(scene) -> float:
    """Hertz's E* [Pa] of the ball on an electrode: ``[contact]``'s ball and plate moduli
    and Poisson ratios (the same the 3D contact uses)."""
    c = scene.contact
    return effective_modulus(c.ball_youngs_modulus, c.ball_poisson_ratio,
                             c.plate_youngs_modulus, c.plate_poisson_ratio)


def contacts_of(scene, impacts, elapsed_times) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(times, areas, upper)`` of the impacts that touch an electrode: ``elapsed_times``
    [s] (the run's axis) of ``impacts`` (:class:`tengfield.dynamics.result.Impacts`),
    Hertz's area [m^2] at each one's normal speed (the speed before it), and whether it
    was the upper electrode (Hertz with the ball's equivalent radius on that electrode,
    :func:`electrode_contact_radius`). Impacts at zero speed (resting contact) touch no
    new area. The single-electrode cell's bare upper plate is no electrode: its impacts
    are left out (the contact with a dielectric, like the tube wall's, is not modelled)."""
    device = scene.device
    plates = np.asarray(impacts.plate)
    on_electrode = np.isin(plates, device.electrode_names)
    speed = np.asarray(impacts.speed_before, dtype=float)[on_electrode]
    upper = plates[on_electrode] == "upper"
    radius = electrode_contact_radius(scene)
    modulus = contact_modulus(scene)
    areas = np.where(upper,
                     hertz_contact_area(device.ball_mass, radius["upper"], speed, modulus),
                     hertz_contact_area(device.ball_mass, radius["lower"], speed, modulus))
    times = np.asarray(elapsed_times, dtype=float)[on_electrode]
    order = np.argsort(times, kind="stable")
    return times[order], np.asarray(areas, dtype=float)[order], upper[order]


def electrode_contact_radius(scene) -> dict[str, float]:
    """Hertz's equivalent radius [m] of the ball on each electrode, ``{"lower", "upper"}``:
    R on a flat plate, R a/(a − R) inside the spherical shell's concave electrodes (the 3D
    contact's own rule, :func:`tengfield.dynamics.motion3d.contact.equivalent_radius`, over
    the cell's contact surfaces); R for a cell whose walls are not described (the
    honeycomb's flat plates)."""
    from ..dynamics.motion3d.contact import equivalent_radius
    from ..field.cells import cell_of
    from ..field.cells.contact_surfaces import contact_surfaces

    radius = scene.device.ball_radius
    try:
        surfaces = contact_surfaces(cell_of(scene)).surfaces
    except ValueError:                 # no walls described: flat electrode plates
        return {"lower": radius, "upper": radius}
    return {s.name: equivalent_radius(radius, s) for s in surfaces
            if s.name in ("lower", "upper")}


def run_history(scene, impacts, elapsed_times, cap: float = math.inf) -> tuple:
    """``(history, upper, law, areas)``: the ball's charge along the run's contacts (the
    run's axis, from t = 0), which of them were on the upper electrode, the law used and
    each contact's area [m^2]."""
    law = contact_law(scene, cap)
    times, areas, upper = contacts_of(scene, impacts, elapsed_times)
    return charge_history(law, times, areas, t0=0.0), upper, law, areas


def steady_state(history: ChargeHistory, law: ContactCharging, areas, window_start: float,
                 duration: float, period: float = 0.0) -> dict:
    """The charge the run's steady contacts hold the ball at, and when it gets there.

    A contact maps q -> (1 - k) q + k q_eq (k = eta S/A) and leakage between contacts
    q -> d q, so the contacts of one stretch of time compose to an affine map
    q -> P q + Q. Over the last whole number of excitation ``period`` s of the steady
    window (the whole window when the excitation has no period) its fixed point
    q* = Q / (1 - P) is the charge at the stretch's start once the run is steady, and
    the steady charge is the mean charge just after the stretch's contacts from q*
    (exact for any periodic pattern of contacts: chatter, period-n bounce), capped at the
    cap. The 90 % rise time is the history's where the run reached it, else extrapolated
    from the run's end along the geometric approach P^(t / stretch). Returns ``steady``
    [C], ``rise_time`` [s] or None, ``extrapolated``, ``end`` (q at the end) and
    ``approach`` (P, the stretch [s], the uncapped fixed point [C]) where extrapolated."""
    from ._kernel import contact_recurrence

    times = history.times
    end = float(history.at(duration)) if history.contacts else float(history.start)
    span = duration - window_start
    if period > 0.0 and span >= period:
        span = math.floor(span / period * (1.0 + 1e-12)) * period
    first = duration - span
    inside = (times >= first) & (times <= duration)
    if not np.any(inside) or span <= 0.0:
        return {"steady": end, "rise_time": None, "extrapolated": False, "end": end}
    A = law.ball_area
    k = np.minimum(1.0, law.efficiency * np.asarray(areas, dtype=float)[inside] / A)
    at = times[inside]
    gaps = np.diff(np.concatenate(([first], at)))
    tau = law.leakage_time
    with np.errstate(over="ignore"):
        decay = np.exp(-gaps / tau) if tau > 0.0 else np.ones_like(gaps)
        tail = float(np.exp(-(duration - at[-1]) / tau)) if tau > 0.0 else 1.0
    q_eq = law.equilibrium * A
    P = float(np.prod((1.0 - k) * decay)) * tail
    Q = float(contact_recurrence(decay, k, q_eq, math.inf, 0.0)[1][-1]) * tail
    if P >= 1.0:
        return {"steady": end, "rise_time": None, "extrapolated": False, "end": end}
    unclipped = Q / (1.0 - P)
    after = contact_recurrence(decay, k, q_eq, math.inf, unclipped)[1]
    cap = law.cap * A
    steady = float(np.clip(np.mean(after), -cap, cap))
    if steady == 0.0:
        return {"steady": 0.0, "rise_time": None, "extrapolated": False, "end": end}
    target = 0.9 * steady
    if abs(history.start) >= abs(target):
        return {"steady": steady, "rise_time": 0.0, "extrapolated": False, "end": end}
    reached = np.nonzero(np.abs(history.after) >= abs(target))[0]
    if reached.size:
        return {"steady": steady, "rise_time": float(times[reached[0]]), "extrapolated": False,
                "end": end}
    left, needed = unclipped - end, unclipped - target
    if P <= 0.0 or left == 0.0 or needed / left <= 0.0:
        return {"steady": steady, "rise_time": None, "extrapolated": True, "end": end}
    more = math.log(needed / left) / math.log(P) * span
    return {"steady": steady, "rise_time": duration + max(more, 0.0), "extrapolated": True,
            "end": end, "approach": {"per_stretch": P, "stretch_s": span,
                                     "unclipped_C": unclipped}}


def charge_summary(history: ChargeHistory, law: ContactCharging, *, cap_level: str,
                   duration: float, areas=None, window_start: float = 0.0,
                   period: float = 0.0) -> dict:
    """summary.json's ``charge`` block (SI, densities in µC/m^2): the steady charge
    (:func:`steady_state`), the rise time to 90 % of it, the charge at the run's end, the
    contacts, the mean gain per contact, the shares of sigma_eq and of the cap reached, and
    what binds the steady charge."""
    A = law.ball_area
    state = steady_state(history, law, np.zeros(history.contacts) if areas is None else areas,
                         window_start, duration, period)
    steady = state["steady"]
    gains = history.gains
    eq = law.equilibrium
    share_eq = abs(steady / (eq * A)) if eq != 0.0 else None
    share_cap = abs(steady / (law.cap * A)) if math.isfinite(law.cap) else None
    if not history.contacts:
        binds = "no contacts: the ball keeps its initial charge"
    elif share_cap is not None and share_cap >= 0.999:
        binds = f"the air-breakdown cap ([charge] discharge = {cap_level!r})"
    elif share_eq is not None and share_eq >= 0.99:
        binds = "the equilibrium density sigma_eq (the contacts saturate)"
    elif law.leakage_time > 0.0:
        binds = "leakage against the charging rate ([charge] leakage_time_s)"
    else:
        binds = "the contacts' charging rate"
    rise = state["rise_time"]
    return {
        "model": "contact",
        "steady_uC_per_m2": steady / A * 1e6,
        "end_of_run_uC_per_m2": state["end"] / A * 1e6,
        "share_of_steady_at_end": abs(state["end"] / steady) if steady else None,
        "rise_time_90_s": rise,
        "rise_time_extrapolated": state["extrapolated"],
        # the geometric approach past the run's end (the figure's dotted extension)
        "approach": state.get("approach"),
        "contacts": history.contacts,
        "contact_rate_per_s": history.contacts / duration if duration > 0 else None,
        "mean_delta_per_contact_C": float(np.mean(gains)) if gains.size else 0.0,
        "equilibrium_uC_per_m2": eq * 1e6,
        "efficiency": law.efficiency,
        "leakage_time_s": law.leakage_time,
        "share_of_equilibrium": share_eq,
        "cap_uC_per_m2": law.cap * 1e6 if math.isfinite(law.cap) else None,
        "cap_level": cap_level,
        "ball_area_m2": A,
        "share_of_cap": share_cap,
        "binds": binds,
        "rule": ("steady: the fixed point of the steady window's contacts (their mean "
                 "condenser map with leakage, capped); rise time: from the start to the first "
                 "contact at 90 % of it, extrapolated past the run's end along the geometric "
                 "approach where the run ends before"),
    }


def charge_line(block: dict) -> str:
    """The terminal's line: the steady charge and what limits it."""
    rise = block["rise_time_90_s"]
    rise_text = "never" if rise is None else f"{rise:.3g} s" + (
        " (extrapolated past the run)" if block.get("rise_time_extrapolated") else "")
    end = block.get("share_of_steady_at_end")
    end_text = "" if end is None else \
        f", {block['end_of_run_uC_per_m2']:.4g} ({100 * end:.3g} %) at the run's end"
    line = (f"ball charge (contacts): steady {block['steady_uC_per_m2']:.4g} µC/m^2 "
            f"(limited by {block['binds']}){end_text}; 90 % at {rise_text}; "
            f"{block['contacts']} contacts")
    cells = block.get("cells")
    if cells:        # an [array]: the line above is one cell's
        line = (f"{line} (cell {cells['reported_cell']} of {cells['count']}, the median; "
                f"the cells' steady charge from {cells['steady_min_uC_per_m2']:.4g} to "
                f"{cells['steady_max_uC_per_m2']:.4g} µC/m^2, mean "
                f"{cells['steady_mean_uC_per_m2']:.4g})")
    return line


def charge_record(history, ball_area: float, duration: float, points: int = 4000) -> dict:
    """What the figure draws (picklable, bounded in size whatever the contact count):
    sigma [µC/m^2] just after each contact (thinned to ``points``), its contact number,
    its time [s], and sigma on a time grid over the run (leakage between contacts)."""
    n = history.contacts
    keep = np.unique(np.linspace(0, n - 1, min(n, points)).astype(int)) if n else np.empty(0, int)
    grid = np.linspace(0.0, duration, points)
    return {"contact": keep + 1, "time_s": history.times[keep],
            "after_uC_per_m2": history.after[keep] / ball_area * 1e6,
            "grid_s": grid, "grid_uC_per_m2": history.at(grid) / ball_area * 1e6,
            "start_uC_per_m2": history.start / ball_area * 1e6}
