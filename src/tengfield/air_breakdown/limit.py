"""Air breakdown: the largest surface charge density the device can hold (pure numpy).

The potential is linear in σ and in the electrode potentials, so every gap
voltage is ``σ`` times a number per unit σ. Per sampled position the field
solves give three basis potentials on the ball surface (φ_1 of σ = 1 C/m²
with the electrodes grounded, ψ_lower, ψ_upper; :mod:`tengfield.field.breakdown`)
and the surrogate the capacitance matrix C and the induced fractions q/q_ball.
A circuit state fixes the electrode potentials per unit σ:

* ``open``: the terminals open, the electrodes keep the charges of the
  reference state (ball on the lower plate, terminals shorted):
  ``V = C⁻¹ (Q_ref − q)`` (the topology's ``open_potentials``, :mod:`tengfield.terminals`);
* ``open-top``: the same with the charges of the short circuit at z = Δh (the
  other extreme of a load's charge: between the two, a load's transferred
  charge lies, and the gap voltages are linear in it);
* ``short``: terminals shorted, ``V_lower = V_upper`` (floating pair with total
  charge −q_ball, or both 0 with the lower electrode grounded).

The gap voltage of a line from the ball to electrode k is ``ΔV = φ(surface
point) − V_k``; breakdown where ``|σ ΔV| ≥ V_b(p L)`` (Paschen, :mod:`tengfield.paschen`)
with L the line's length. Hence

    σ_max = min over positions, lines and states of V_b(p L) / |ΔV per σ|.

Between the sampled positions the per-σ gap voltages are cubic splines in z
(as Q_SC and C_T are) and the lengths exact; the minimum is taken on a dense
grid. Error estimate: the change of σ_max when every other sampled position is
dropped (interpolation), the change of the per-position limit on the field
error estimate's half-size mesh (where the field error is measured; times
1.25 as the surrogate carries its field error), and the surrogate's own field
error estimate of C and q, added.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..paschen import Paschen
from ..terminals import wiring as terminals_wiring

#: circuit states checked: see the module docstring
STATES = ("open", "open-top", "short")
STATE_TEXT = {"open": "open circuit (electrode charges of the ball resting on the lower plate)",
              "open-top": "open circuit with the charges of the ball at the top (a load's other "
                          "extreme)",
              "short": "short circuit"}
SIDES = ("lower", "upper")
#: the per-position field error margin of the surrogate (refinement.FIELD_ERROR_MARGIN)
CHECK_MARGIN = 1.25
#: dense grid of the minimum over z (plus the sampled positions)
DENSE_POINTS = 801


@dataclass
class Lines:
    """What the breakdown check needs per sampled position (SI, per unit σ).

    ``basis[i, side, j]`` = [φ_1, ψ_lower, ψ_upper] at line j's surface point on
    side (0 lower, 1 upper); ``fractions[i]`` = [q_lower, q_upper] / q_ball;
    ``ball_area`` = π d² (q_ball per unit σ). Line j starts at polar angle
    ``angles[j]`` [rad] and runs parallel to the axis: its length is the local gap
    ``z + R (1 − cos θ)`` (lower) or ``Δh − z + R (1 − cos θ)`` (upper); lines whose
    foot lies beyond ``electrode_radius`` are left out. ``check``: ``basis`` on the
    half-size mesh (NaN where not computed). ``sides``: which sides have gaps.
    """
    positions: np.ndarray
    capacitance: np.ndarray
    fractions: np.ndarray
    ball_area: float
    basis: np.ndarray
    angles: np.ndarray
    ball_radius: float
    stroke: float
    electrode_radius: float
    check: np.ndarray | None = None
    sides: tuple = (True, True)
    field_error: float = 0.0
    #: a cell's own lines: ``line_lengths(z, angles)`` -> (len(z), 2, lines) [m] (a
    #: spherical shell's, field/cells); None: the tube's lines parallel to the axis
    line_lengths: object = None
    #: the area [m^2] of the column each line stands for (None: the ball's surface band
    #: around it projected on the electrode, :mod:`.band`; the planar stand-in gives its own)
    foot_areas: np.ndarray | None = None

    def lengths(self, z) -> np.ndarray:
        """Line lengths [m], shape (len(z), 2, lines); NaN for lines not used."""
        z = np.atleast_1d(np.asarray(z, dtype=float))
        if self.line_lengths is not None:
            out = np.array(self.line_lengths(z, self.angles), dtype=float)
        else:
            rise = self.ball_radius * (1.0 - np.cos(self.angles))
            lower = z[:, None] + rise[None, :]
            upper = (self.stroke - z)[:, None] + rise[None, :]
            out = np.stack([lower, upper], axis=1)
            beyond = self.ball_radius * np.sin(self.angles) > self.electrode_radius * (1 + 1e-12)
            out[:, :, beyond] = np.nan
        for k, present in enumerate(self.sides):
            if not present:
                out[:, k, :] = np.nan
        return out


def lines_from_table(table, scene) -> Lines:
    """:class:`Lines` of a surrogate table with breakdown lines (``table.line_potential``)."""
    from ..errors import TengfieldError
    from ..field.breakdown import LINE_ANGLES_DEG
    from ..field.cells import cell_of

    if table.line_potential is None:
        raise TengfieldError("the surrogate has no breakdown lines (made by the 3D solver or "
                             "a custom solve): the breakdown check needs the axisymmetric solver")
    angles = table.provenance.get("breakdown_line_angles_deg", LINE_ANGLES_DEG)
    dev = scene.device
    fractions = np.asarray(table.induced_fraction, dtype=float)   # per unit ball charge
    electrodes = fractions.shape[1]
    field_error = np.asarray(table.field_error, dtype=float)
    return Lines(positions=np.asarray(table.positions), capacitance=np.asarray(table.capacitance),
                 fractions=fractions, ball_area=math.pi * dev.ball_diameter**2,
                 basis=np.asarray(table.line_potential), angles=np.radians(np.asarray(angles)),
                 ball_radius=dev.ball_radius, stroke=float(table.stroke),
                 electrode_radius=dev.electrode_radius, check=table.line_check,
                 line_lengths=getattr(cell_of(scene), "line_lengths", None),
                 field_error=float(np.nanmax(field_error)) if np.any(np.isfinite(field_error))
                 else 0.0,
                 # the single-electrode cell: the upper side faces the bare plate, no gap
                 sides=(True, True) if electrodes == 2 else (True, False))


def electrode_potentials(lines: Lines, state: str, reference: str = "floating") -> np.ndarray:
    """[V_lower, V_upper] per unit σ [V per C/m²] at each sampled position, shape (n, 2)
    ((n, 1): the single-electrode cell's [V_lower])."""
    C = lines.capacitance
    q = lines.fractions * lines.ball_area
    q_ball = lines.ball_area
    n = lines.positions.size
    wiring = terminals_wiring(reference, q.shape[1])   # the pair's, or one electrode's
    if state == "short":
        return wiring.short_potentials(C, q, q_ball)
    if state not in ("open", "open-top"):
        raise ValueError(f"state = {state!r}: choose one of {STATES}")
    ref = 0 if state == "open" else n - 1
    charges = wiring.reference_charges(C[ref], q[ref], q_ball)
    return np.array([wiring.open_potentials(C[i], q[i], charges) for i in range(n)])


def gap_voltages(lines: Lines, state: str, reference: str = "floating",
                 basis: np.ndarray | None = None) -> np.ndarray:
    """ΔV = φ(surface point) − V_electrode per unit σ [V per C/m²], shape (n, 2, lines)."""
    basis = lines.basis if basis is None else basis
    V = electrode_potentials(lines, state, reference)
    phi = basis[..., 0] + sum(V[:, None, None, k] * basis[..., 1 + k] for k in range(V.shape[1]))
    return phi - V[:, :, None]    # one electrode: the upper side's (no gap) is left out


#: gaps shorter than this [m] are taken as closed: the field solves do not resolve them
#: (the first sampled position after contact lies µm away; between them the per-σ gap
#: voltage is the spline's, whose residual at contact, paired with a field-emission V_b
#: that falls to 0 with the gap, would "break down" a trajectory sample nm after
#: lift-off). The static limit's dense grid (3.75 µm steps) never reaches below it.
CLOSED_GAP = 1e-6


def _limits(paschen: Paschen, lengths, dv) -> np.ndarray:
    """σ at which each line breaks down [C/m²] (inf for a closed gap, no voltage or no line)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        vb = paschen.voltage(np.where(np.isfinite(lengths), lengths, 0.0))
        out = vb / np.abs(dv)
    bad = ~np.isfinite(lengths) | (lengths < CLOSED_GAP) | ~np.isfinite(out) | (np.abs(dv) == 0.0)
    return np.where(bad, np.inf, out)


@dataclass
class Binding:
    """Where the limit binds: the state, side, line angle [rad], position z [m], line
    length [m], ΔV per unit σ [V per C/m²], V_b [V], Paschen regime and the limit [C/m²]."""
    sigma: float
    state: str
    side: str
    angle: float
    position: float
    gap: float
    dv_per_sigma: float
    breakdown_voltage: float
    regime: str

    def to_json(self) -> dict:
        return {"sigma_max_uC_per_m2": self.sigma * 1e6, "state": self.state,
                "gap": self.side, "line_angle_deg": math.degrees(self.angle),
                "position_m": self.position, "gap_length_m": self.gap,
                "gap_voltage_per_sigma_V_per_uC_per_m2": self.dv_per_sigma * 1e-6,
                "gap_voltage_at_sigma_max_V": abs(self.dv_per_sigma) * self.sigma,
                "breakdown_voltage_V": self.breakdown_voltage, "paschen_regime": self.regime}


@dataclass
class BreakdownResult:
    """σ_max [C/m²] (positive: the magnitude) with where it binds, per state, the
    per-position rows, the dense curves for the figure and the error estimate."""
    sigma_max: float
    binding: Binding
    per_state: dict
    states: tuple
    reference: str
    paschen: Paschen
    rows: list
    curves: dict
    error: dict = field(default_factory=dict)
    #: the lines it was evaluated on (the band's input, :mod:`.band`)
    lines: Lines | None = field(default=None, repr=False)

    @property
    def relative_error_estimate(self) -> float:
        return float(self.error.get("relative", math.nan))

    scene: Any = field(default=None, repr=False, compare=False)   # the scene bounded
    field_status: str = ""       # how the surrogate was obtained ("cached", "solved", ...)

    @property
    def summary(self) -> dict:
        """JSON-ready: breakdown.json's content at the binding limit (``to_json()``)."""
        return self.to_json()

    def plot(self, sigma: float | None = None, *, title: str | None = None):
        """The breakdown figure (a matplotlib Figure; ``tengfield breakdown`` saves it as
        breakdown.png): the gap voltages at ``sigma`` [C/m²] (default −σ_max) against
        Paschen's curve, and their ratio to it over the stroke."""
        from ..plotting.breakdown import breakdown_figure   # the edge, imported on use

        return breakdown_figure(self, -self.sigma_max if sigma is None else sigma, title=title)

    def margin(self, sigma: float) -> float:
        """|σ| / σ_max (above 1: the air breaks down before the charge is reached)."""
        return abs(sigma) / self.sigma_max if self.sigma_max > 0 else math.inf

    def to_json(self, sigma: float | None = None) -> dict:
        out = {"sigma_max_uC_per_m2": self.sigma_max * 1e6,
               "relative_error_estimate": self.relative_error_estimate,
               "error_estimate": self.error,
               "binding": self.binding.to_json(),
               "states_checked": list(self.states),
               "state_meaning": {s: STATE_TEXT[s] for s in self.states},
               "per_state": {s: b.to_json() for s, b in self.per_state.items()},
               "reference": self.reference,
               "pressure_Pa": self.paschen.pressure,
               "paschen": self.paschen.to_json(),
               "lines": "from the ball surface at polar angles 0-85 deg straight to the electrode, "
                        "parallel to the axis (on the axis a field line; off it the shortest "
                        "path to the electrode, so the limit errs on the safe side)"}
        if sigma is not None:
            out["scene_sigma_uC_per_m2"] = sigma * 1e6
            out["margin"] = self.margin(sigma)
        return out


def _binding(lines, paschen, state, z, lengths, dv, limits) -> Binding:
    i, k, j = np.unravel_index(int(np.argmin(limits)), limits.shape)
    gap = float(lengths[i, k, j])
    return Binding(sigma=float(limits[i, k, j]), state=state, side=SIDES[k],
                   angle=float(lines.angles[j]), position=float(z[i]), gap=gap,
                   dv_per_sigma=float(dv[i, k, j]), breakdown_voltage=float(paschen.voltage(gap)),
                   regime=str(paschen.regime(gap)[0]))


def _dense_minimum(lines: Lines, paschen: Paschen, state: str, reference: str, dense: np.ndarray,
                   keep=None):
    """(z, lengths, ΔV, limits) on ``dense`` from splines through the sampled positions
    (``keep``: a mask of the positions used)."""
    from scipy.interpolate import CubicSpline

    dv = gap_voltages(lines, state, reference)
    z = lines.positions
    if keep is not None:
        dv, z = dv[keep], z[keep]
    kind = "not-a-knot" if z.size >= 4 else "natural"
    dv_dense = CubicSpline(z, np.nan_to_num(dv), axis=0, bc_type=kind)(dense)
    lengths = lines.lengths(dense)
    return lengths, dv_dense, _limits(paschen, lengths, dv_dense)


def evaluate(lines: Lines, paschen: Paschen, states=STATES, reference: str = "floating",
             sigma: float | None = None) -> BreakdownResult:
    """σ_max of ``lines`` over ``states`` (module docstring); ``sigma`` [C/m²] (the
    scene's) only sets the gap voltages of the rows and curves."""
    states = tuple(states)
    dense = np.union1d(lines.positions, np.linspace(0.0, lines.stroke, DENSE_POINTS))
    per_state, curves = {}, {}
    coarse_limits = []
    coarse = np.zeros(lines.positions.size, dtype=bool)
    coarse[::2] = True
    coarse[-1] = True
    for state in states:
        lengths, dv, limits = _dense_minimum(lines, paschen, state, reference, dense)
        per_state[state] = _binding(lines, paschen, state, dense, lengths, dv, limits)
        curves[state] = {"position_m": dense, "length_m": lengths, "dv_per_sigma": dv,
                         "limit": limits}
        if coarse.sum() >= 3 and coarse.sum() < lines.positions.size:
            coarse_limits.append(float(np.min(_dense_minimum(
                lines, paschen, state, reference, dense, keep=coarse)[2])))
    binding = min(per_state.values(), key=lambda b: b.sigma)
    sigma_max = binding.sigma
    rows = _rows(lines, paschen, states, reference, sigma)
    interpolation = (abs(min(coarse_limits) - sigma_max) / sigma_max
                     if coarse_limits and math.isfinite(sigma_max) and sigma_max > 0 else 0.0)
    mesh = _mesh_change(lines, paschen, states, reference)
    error = {"relative": interpolation + CHECK_MARGIN * mesh + lines.field_error,
             "interpolation": interpolation, "mesh": mesh, "field": lines.field_error,
             "rule": "interpolation (every other sampled position dropped) + 1.25 x the change "
                     "of the per-position limit on the half-size mesh (where the field error "
                     "is measured) + the surrogate's field error estimate"}
    return BreakdownResult(sigma_max=sigma_max, binding=binding, per_state=per_state,
                           states=states, reference=reference, paschen=paschen, rows=rows,
                           curves=curves, error=error, lines=lines)


def _mesh_change(lines: Lines, paschen, states, reference) -> float:
    """Largest relative change of the per-position limit (min over lines and states)
    from the coarse to the half-size mesh, over the positions that have both."""
    if lines.check is None:
        return math.nan
    have = np.all(np.isfinite(lines.check), axis=(1, 2, 3))
    if not np.any(have):
        return math.nan
    lengths = lines.lengths(lines.positions)
    worst = 0.0
    for i in np.flatnonzero(have):
        here = [], []
        for state in states:
            for k, basis in enumerate((lines.basis, lines.check)):
                dv = gap_voltages(lines, state, reference, basis)[i]
                here[k].append(np.min(_limits(paschen, lengths[i], dv)))
        a, b = min(here[0]), min(here[1])
        if math.isfinite(a) and a > 0:
            worst = max(worst, abs(b - a) / a)
    return worst


def _rows(lines: Lines, paschen: Paschen, states, reference, sigma) -> list[dict]:
    """One row per sampled position, state and gap: its most critical line."""
    lengths = lines.lengths(lines.positions)
    rows = []
    for state in states:
        dv = gap_voltages(lines, state, reference)
        limits = _limits(paschen, lengths, dv)
        for i, z in enumerate(lines.positions):
            for k, side in enumerate(SIDES):
                if not lines.sides[k]:
                    continue
                j = int(np.argmin(limits[i, k]))
                gap = lengths[i, k, j]
                vb = float(paschen.voltage(gap)) if np.isfinite(gap) else math.nan
                v_gap = dv[i, k, j] * sigma if sigma is not None else math.nan
                rows.append({
                    "position_m": float(z), "state": state, "gap": side,
                    "line_angle_deg": math.degrees(lines.angles[j]), "gap_length_m": float(gap),
                    "axial_gap_length_m": float(lengths[i, k, 0]),
                    "gap_voltage_per_sigma_V_per_uC_per_m2": float(dv[i, k, j]) * 1e-6,
                    "gap_voltage_at_scene_sigma_V": float(v_gap),
                    "breakdown_voltage_V": vb,
                    "sigma_limit_uC_per_m2": float(limits[i, k, j]) * 1e6,
                    "margin": (vb / abs(v_gap) if v_gap and np.isfinite(v_gap) else math.inf)})
    return rows


CSV_COLUMNS = ("position_m", "state", "gap", "line_angle_deg", "gap_length_m",
               "axial_gap_length_m", "gap_voltage_per_sigma_V_per_uC_per_m2",
               "gap_voltage_at_scene_sigma_V", "breakdown_voltage_V", "sigma_limit_uC_per_m2",
               "margin")


def limited_energy(energy: dict, result: BreakdownResult, sigma: float) -> dict:
    """The CMEO bound and the figures of merit at σ_max beside the ideal ones (E ∝ σ²):
    ``max_energy_per_cycle_breakdown_limited_J`` = E_m (σ_max/σ)², the performance figure
    of merit FOM_P = FOM_S σ² (Zi et al. 2015) ideal and at σ_max."""
    if not energy or sigma == 0:
        return {}
    scale = (result.sigma_max / abs(sigma)) ** 2
    fom = energy.get("figure_of_merit_structural", math.nan)
    return {"max_energy_per_cycle_breakdown_limited_J": energy["max_energy_per_cycle_J"] * scale,
            "Q_sc_max_breakdown_limited_C": energy["Q_sc_max_C"] * math.sqrt(scale),
            "figure_of_merit_performance_C2_per_m4": fom * sigma**2,
            "figure_of_merit_performance_breakdown_limited_C2_per_m4": fom * result.sigma_max**2,
            "breakdown_rule": "at sigma_max: energies scale with sigma^2, charges with sigma; "
                              "FOM_S does not depend on sigma, FOM_P = FOM_S sigma^2"}
