"""The z -> 0 / z -> Δh rule and the error-estimate arithmetic, shared by the
axisymmetric and the 3D solvers (pure Python + numpy, no dolfinx, no gmsh).

Contact rule: no mesh has a ball–electrode gap below ``g = MIN_GAP_FRACTION · h``
(h the electrode spacing; 20 µm for the paper's device). A position closer than
g to a plate is extrapolated from the meshable anchor gaps (g, 2g, 4g) from that
plate (:func:`contact_anchors`) by the power law ``X(δ) = X0 + b δ^p``
(:func:`contact_exponent`, :func:`power_law_extrapolation`); its difference
from the straight line through the first two anchors is the extrapolation error
estimate. For the PTFE ball (εr = 2.1) C and q are linear in the gap there
(p = 1, error ~1e-4); for a nearly conducting ball (εr ≳ 10) the charge varies
as a lower power near contact and the estimate says so (docs/field.md).

Compared quantities: the five numbers a user reads, C_ll, C_lu, C_uu and the
induced fractions q_lower/q_ball, q_upper/q_ball (σ-independent, so an
uncharged ball compares cleanly), see :func:`relative_change`.
"""
from __future__ import annotations

import math
from typing import Callable

import numpy as np

# smallest meshed ball–electrode gap, as a fraction of the electrode spacing h: a limit
# of the scene (its field check needs it too)
from ..scene.limits import MIN_GAP_FRACTION

#: exponents of the near-contact power law X(δ) = X0 + b δ^p are clipped to this range
CONTACT_EXPONENT_RANGE = (0.25, 2.0)
#: A fitted exponent this close to 1 is mesh noise around a straight line
#: (PTFE gives 0.98-1.02): it is snapped to 1, so Q_SC(z) has no spurious
#: weak singularity inside the contact layer (which would bias dQ_SC/dz at
#: contact, hence the peak I_SC, by a few per cent).
CONTACT_EXPONENT_SNAP = 0.05


def minimum_gap(electrode_spacing: float) -> float:
    """Smallest ball–electrode gap meshed [m]: ``MIN_GAP_FRACTION · h``."""
    return MIN_GAP_FRACTION * electrode_spacing


def clamp_gap(position: float, stroke: float, electrode_spacing: float) -> float:
    """The gap actually meshed: ``position`` clamped to [g, Δh - g]."""
    g = minimum_gap(electrode_spacing)
    return min(max(position, g), stroke - g)


def contact_anchors(position: float, stroke: float,
                    electrode_spacing: float) -> tuple[float, float, float] | None:
    """Three meshable positions [m] to extrapolate from when ``position`` is closer
    than g to a plate: gaps (g, 2g, 4g) from that plate, i.e. positions (g, 2g, 4g)
    or (Δh - g, Δh - 2g, Δh - 4g); ``None`` when ``position`` can be meshed."""
    g = minimum_gap(electrode_spacing)
    if position < g:
        return g, 2.0 * g, 4.0 * g
    if position > stroke - g:
        return stroke - g, stroke - 2.0 * g, stroke - 4.0 * g
    return None


def linear_extrapolation(position: float, anchors, values) -> np.ndarray:
    """Value at ``position`` of the line through (anchors[0], values[0]) and
    (anchors[1], values[1]) (arrays of any shape)."""
    weight = (position - anchors[0]) / (anchors[1] - anchors[0])
    return np.asarray(values[0]) + weight * (np.asarray(values[1]) - np.asarray(values[0]))


def contact_exponent(values) -> float:
    """Exponent p of the near-contact law ``X(δ) = X0 + b δ^p`` from values at the
    gaps (g, 2g, 4g): ``p = log2((X(4g) - X(2g)) / (X(2g) - X(g)))`` of the entry
    that varies most (relative to its size), shared by every entry.

    One exponent describes the local field near contact; fitting it entry by
    entry would let a weakly varying entry (the far electrode's C) fit mesh
    noise. p = 1 (a straight line) for a low-permittivity ball such as PTFE; a
    high-permittivity ball gives p < 1 because its gap capacitance saturates
    only at gaps ~ R/εr² (0.35 µm for εr = 100), far below g. If the two
    differences of that entry do not share a sign, p = 1; p is clipped to
    :data:`CONTACT_EXPONENT_RANGE`; within :data:`CONTACT_EXPONENT_SNAP` of 1 it is 1.
    """
    near, middle, far = (np.ravel(np.asarray(v, dtype=float)) for v in values)
    first, second = middle - near, far - middle
    scale = np.where(near != 0.0, np.abs(near), 1.0)
    k = int(np.argmax(np.abs(first) / scale))
    if not first[k] * second[k] > 0.0:
        return 1.0
    exponent = float(np.clip(np.log2(second[k] / first[k]), *CONTACT_EXPONENT_RANGE))
    return 1.0 if abs(exponent - 1.0) < CONTACT_EXPONENT_SNAP else exponent


def power_law_extrapolation(distance: float, anchor_gap: float, values,
                            exponent: float) -> np.ndarray:
    """Value at plate distance ``distance`` [m] of ``X(δ) = X0 + b δ^p`` through the
    values at distances (g, 2g, 4g), ``g = anchor_gap`` (arrays of any shape), with
    ``p = exponent`` (:func:`contact_exponent`); p = 1 is the straight line
    through the first two anchors."""
    near, middle = (np.asarray(v, dtype=float) for v in values[:2])
    u = distance / anchor_gap
    return near + (middle - near) * (u**exponent - 1.0) / (2.0**exponent - 1.0)


def relative_difference(values, reference) -> float:
    """``max_i |values_i - reference_i| / |reference_i|``; entries where both are 0 count 0."""
    a = np.ravel(np.asarray(values, dtype=float))
    b = np.ravel(np.asarray(reference, dtype=float))
    diff = np.abs(a - b)
    scale = np.abs(b)
    out = np.zeros_like(diff)
    nonzero = scale > 0.0
    out[nonzero] = diff[nonzero] / scale[nonzero]
    out[~nonzero & (diff > 0.0)] = math.inf
    return float(np.max(out, initial=0.0))


def compared_quantities(capacitance, induced_fraction) -> np.ndarray:
    """[C_ll, C_lu, C_uu, q_lower/q_ball, q_upper/q_ball]: what the estimates compare (the
    upper triangle of the capacitance matrix and the fractions, for any number of
    electrodes: [C_ll, q_lower/q_ball] for the single-electrode cell)."""
    fraction = np.ravel(np.asarray(induced_fraction, dtype=float))
    n = fraction.size
    capacitance = np.asarray(capacitance, dtype=float).reshape(n, n)
    return np.array([*capacitance[np.triu_indices(n)], *fraction])


def relative_change(value, reference) -> float:
    """Largest relative change of C_ll, C_lu, C_uu and the induced fractions from
    ``reference`` to ``value`` (objects with ``capacitance`` and ``induced_fraction``),
    relative to ``reference``."""
    return relative_difference(compared_quantities(value.capacitance, value.induced_fraction),
                               compared_quantities(reference.capacitance,
                                                   reference.induced_fraction))


def extrapolate_to_contact(position: float, anchors, stroke: float,
                           solve_at: Callable[[float], object]) -> dict:
    """The contact rule on any solver: ``solve_at(z)`` returns an object with
    ``capacitance`` (2x2), ``induced_fraction`` (2) and optionally ``extras`` (a
    dict of arrays that are extrapolated too), solved at each of the three
    ``anchors``. Returns ``{"solves", "capacitance", "induced_fraction",
    "extras", "error", "exponent", "distances"}`` with ``error`` the relative
    difference of the straight line from the power law."""
    solves = [solve_at(z) for z in anchors]
    plate = 0.0 if anchors[0] < anchors[1] else stroke
    exponent = contact_exponent([compared_quantities(s.capacitance, s.induced_fraction)
                                 for s in solves])
    distance, anchor_gap = abs(position - plate), abs(anchors[0] - plate)

    def extrapolate(get):
        values = [np.asarray(get(s), dtype=float) for s in solves]
        return (power_law_extrapolation(distance, anchor_gap, values, exponent),
                linear_extrapolation(position, anchors[:2], values[:2]))

    C, C_line = extrapolate(lambda s: s.capacitance)
    fraction, fraction_line = extrapolate(lambda s: s.induced_fraction)
    extras = {}
    for key in getattr(solves[0], "extras", {}) or {}:
        extras[key] = extrapolate(lambda s: s.extras[key])[0]
    error = relative_difference(compared_quantities(C_line, fraction_line),
                                compared_quantities(C, fraction))
    return {"solves": solves, "capacitance": C, "induced_fraction": fraction, "extras": extras,
            "error": error, "exponent": exponent,
            "distances": [abs(a - plate) for a in anchors]}
