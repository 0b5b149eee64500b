"""The charge a device holds, as a band (issue #38; docs/breakdown.md, pure numpy).

The static limit σ_max (:func:`tengfield.air_breakdown.evaluate`) assumes a gap breaks
down as soon as its voltage exceeds Paschen's V_b. A real gap needs a free electron
in its over-stressed volume to start the avalanche (statistical time lag, Laue's law:
P(no breakdown after t) = exp(−∫ rate dt)), and a sub-mm gap a ball crosses in
milliseconds holds almost none. The band, from the scene's own field and trajectory:

* **lower**: the static limit at the critical gap (today's rule) at the γ of
  ``[breakdown] gamma_range`` (widened to hold the scene's γ) that gives the lowest;
* **upper**: the static limit where the ball's smaller gap is widest along its
  trajectory (the largest over-stressed volume and the longest time), at the γ that
  gives the highest: a charge above it breaks down even there;
* **estimate**: the σ at which the expected number of seeded avalanches reaches
  ``breakdowns_per_s`` per second of the trajectory, with the scene's γ:

      N(σ) = ∫ (S_v + n_ion·r(t)) V_s(σ, t) dt,   r V_s = max(dV_s/dt, 0),

  V_s the over-stressed volume (the line columns whose voltage exceeds their V_b: the
  field above the breakdown field of the gap's Paschen line), S_v the volume
  ionisation rate, n_ion the small negative ions the growing volume takes in (each
  detaches its electron in the over-stressed field). Each seed is taken to start a
  breakdown (an upper bound on the rate: the estimate errs low).

lower ≤ estimate ≤ upper by construction: below the static limit at the scene's γ
(≥ lower) V_s is empty, so N = 0 < the criterion; the estimate is clamped to upper
where the seeds do not reach the criterion below it (the physics: above upper even the
widest gap breaks down at once).

Volume of a line: the line column from the ball's surface band around it to the
electrode, ``L(θ) · π R² d(sin² θ)`` (the band's area projected on the electrode),
the lines refined :data:`REFINE` times in θ (thresholds and lengths interpolated).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..paschen import Paschen
from .limit import Lines, _dense_minimum, evaluate

#: sub-intervals per interval between two lines (the volume's quadrature in θ)
REFINE = 4
#: the trajectory's samples used at most (the last ones of the steady window): the
#: stress track holds samples x 2 sides x refined lines (~250) doubles per array, so
#: 2^15 keeps it under ~0.1 GB (2^18 took a 900 s run to 1.6 GB); a steady window's
#: seeds per second do not depend on its length
MAX_SAMPLES = 2**15
#: the output quantities a band is given for, and how they scale with σ
LINEAR_QUANTITIES = ("V_oc_V", "Q_sc_C", "I_sc_A", "V_read_V")
#: volume ionisation S_v [1/(m^3 s)] and small ions n_ion [1/m^3] (the scene's defaults)
DEFAULT_SEED_RATE = 10.0e6
DEFAULT_ION_DENSITY = 500.0e6


@dataclass(frozen=True)
class Seeds:
    """The seed-limited estimate's inputs: ``seed_rate`` S_v [1/(m^3 s)],
    ``ion_density`` n_ion [1/m^3], ``breakdowns_per_s`` [1/s] (the criterion)."""
    seed_rate: float = DEFAULT_SEED_RATE
    ion_density: float = DEFAULT_ION_DENSITY
    breakdowns_per_s: float = 1.0

    @classmethod
    def from_scene(cls, scene) -> "Seeds":
        bd = scene.breakdown
        return cls(bd.seed_rate, bd.ion_density, bd.breakdowns_per_s)


@dataclass(frozen=True)
class Trajectory:
    """The ball's gap z(t) [m] at times t [s] (increasing)."""
    time: np.ndarray
    position: np.ndarray

    @property
    def duration(self) -> float:
        return float(self.time[-1] - self.time[0]) if self.time.size > 1 else 0.0


def trajectory_of(dynamics, scene) -> Trajectory:
    """The steady window of a :class:`~tengfield.dynamics.DynamicsResult` (its last
    :data:`MAX_SAMPLES` samples: the window is steady, the rate per second is kept)."""
    from ..electrical import steady_window_index

    t = dynamics.t
    first, _ = steady_window_index(t, scene)
    n = len(t)
    first = max(int(first), n - MAX_SAMPLES)
    return Trajectory(np.asarray(t[first:], dtype=float), np.asarray(dynamics.gap[first:],
                                                                       dtype=float))


@dataclass
class StressTrack:
    """Per trajectory sample, side and (refined) line: the σ [C/m²] at which the line's
    voltage reaches its V_b (``threshold``, min over the circuit states; inf: no line)
    and its column's volume [m^3] (``volume``); ``smaller_gap`` [m] per sample."""
    time: np.ndarray
    position: np.ndarray
    threshold: np.ndarray
    volume: np.ndarray
    smaller_gap: np.ndarray

    def over_stressed_volume(self, sigma: float) -> np.ndarray:
        """V_s(t) [m^3] at |σ| = ``sigma``."""
        return np.sum(np.where(self.threshold < sigma, self.volume, 0.0), axis=(1, 2))

    def below(self, cap: float) -> "StressTrack":
        """The same track holding only the columns whose threshold is below ``cap``
        (flattened: V_s(σ ≤ cap) unchanged, a fraction of the work)."""
        keep = self.threshold < cap
        return _CompactTrack(self.time, np.nonzero(keep)[0], self.threshold[keep],
                             self.volume[keep])

    def ratio(self, sigma: float) -> np.ndarray:
        """max over lines of |V_gap| / V_b at each sample (|σ| = ``sigma``)."""
        with np.errstate(divide="ignore"):
            return sigma / np.min(self.threshold, axis=(1, 2))


@dataclass
class _CompactTrack:
    """:meth:`StressTrack.below`: sample index, threshold and volume of each column kept."""
    time: np.ndarray
    sample: np.ndarray
    threshold: np.ndarray
    volume: np.ndarray

    def over_stressed_volume(self, sigma: float) -> np.ndarray:
        hot = self.threshold < sigma
        return np.bincount(self.sample[hot], weights=self.volume[hot],
                           minlength=self.time.size).astype(float)


def stress_track(lines: Lines, paschen: Paschen, states, reference: str,
                 trajectory: Trajectory) -> StressTrack:
    """:class:`StressTrack` of ``trajectory`` (positions clipped to the stroke)."""
    z = np.clip(trajectory.position, 0.0, lines.stroke)
    thresholds = None
    lengths = None
    for state in states:
        lengths, _, limits = _dense_minimum(lines, paschen, state, reference, z)
        thresholds = limits if thresholds is None else np.minimum(thresholds, limits)
    smaller = _smaller_gap(lines, z)
    lengths = np.where(np.isfinite(lengths), lengths, 0.0)
    foot = getattr(lines, "foot_areas", None)
    if foot is not None:     # given per line (the planar stand-in): no refinement
        return StressTrack(trajectory.time, z, thresholds,
                           lengths * np.asarray(foot)[None, None], smaller)
    theta = lines.angles
    if theta.size < 2:
        return StressTrack(trajectory.time, z, thresholds, np.zeros_like(lengths), smaller)
    fraction = (np.arange(REFINE) + 0.5) / REFINE
    j = np.repeat(np.arange(theta.size - 1), REFINE)
    f = np.tile(fraction, theta.size - 1)
    edges = np.concatenate([[theta[0]], np.repeat(theta[:-1], REFINE)
                            + np.tile(np.arange(1, REFINE + 1) / REFINE, theta.size - 1)
                            * np.repeat(np.diff(theta), REFINE)])
    band_area = math.pi * lines.ball_radius**2 * np.diff(np.sin(edges) ** 2)
    thr = (1.0 - f) * thresholds[..., j] + f * thresholds[..., j + 1]   # inf stays inf
    length = (1.0 - f) * lengths[..., j] + f * lengths[..., j + 1]
    return StressTrack(trajectory.time, z, thr, length * band_area, smaller)


def expected_seeds(track: StressTrack, sigma: float, seeds: Seeds) -> dict:
    """Expected seed electrons over the trajectory at |σ| = ``sigma``: from volume
    ionisation S_v ∫ V_s dt and from the ions the growing volume takes in
    n_ion ∫ max(dV_s/dt, 0) dt, their sum and its rate per second."""
    volume = track.over_stressed_volume(sigma)
    t = track.time
    volume_time = float(np.sum(0.5 * (volume[1:] + volume[:-1]) * np.diff(t))) if t.size > 1 \
        else 0.0
    taken_in = float(np.sum(np.maximum(np.diff(volume), 0.0)))
    total = seeds.seed_rate * volume_time + seeds.ion_density * taken_in
    duration = float(t[-1] - t[0]) if t.size > 1 else 0.0
    return {"volume_ionisation": seeds.seed_rate * volume_time,
            "ions_taken_in": seeds.ion_density * taken_in, "total": total,
            "per_s": total / duration if duration > 0 else 0.0,
            "volume_time_m3_s": volume_time, "peak_volume_m3": float(np.max(volume, initial=0.0))}


@dataclass
class Band:
    """σ [C/m²] (magnitudes) the device holds: ``lower``, ``estimate``, ``upper``, with
    the γ and position [m] / gap [m] where each binds, the seed inputs and the track."""
    lower: float
    estimate: float
    upper: float
    gamma_range: tuple
    gamma: float
    gamma_lower: float
    gamma_upper: float
    seeds: Seeds
    lower_position: float
    lower_gap: float
    upper_position: float
    upper_gap: float
    estimate_gap: float
    estimate_rule: str
    static_at_gamma: float
    seeds_at_estimate: dict
    paschen_curve: str
    track: StressTrack | None = field(default=None, repr=False)
    #: the static limit σ_max [C/m²] at each γ taken (the range's ends and the scene's)
    static_by_gamma: dict = field(default_factory=dict)

    def edges(self) -> dict:
        return {"lower": self.lower, "estimate": self.estimate, "upper": self.upper}

    def to_json(self) -> dict:
        return {"lower_uC_per_m2": self.lower * 1e6, "estimate_uC_per_m2": self.estimate * 1e6,
                "upper_uC_per_m2": self.upper * 1e6,
                "gamma_range": list(self.gamma_range), "gamma": self.gamma,
                "gamma_at_lower": self.gamma_lower, "gamma_at_upper": self.gamma_upper,
                "paschen": self.paschen_curve,
                "S_v_per_m3_s": self.seeds.seed_rate, "n_ion_per_m3": self.seeds.ion_density,
                "breakdowns_per_s": self.seeds.breakdowns_per_s,
                "lower_binds_at": {"position_m": self.lower_position, "gap_m": self.lower_gap},
                "upper_binds_at": {"position_m": self.upper_position, "gap_m": self.upper_gap},
                "estimate_binds_at": {"gap_m": self.estimate_gap},
                "estimate_rule": self.estimate_rule,
                "static_limit_at_gamma_uC_per_m2": self.static_at_gamma * 1e6,
                "static_limit_by_gamma_uC_per_m2": {f"{g:g}": v * 1e6 for g, v in
                                                    self.static_by_gamma.items()},
                "seeds_at_estimate": self.seeds_at_estimate,
                "assumptions": assumption_lines(self)}


def assumption_lines(band: Band) -> dict:
    """One line per edge: what it assumes, said against the static limit σ_max (the
    Paschen rule without seeds at the critical gap) so that no two numbers on one
    screen read as the same thing: the estimate is the seeded value *above* the static
    limit at the same γ; upper is the static limit at the widest gap (not at the
    critical gap, whose static limit at that γ is given beside it)."""
    by = band.static_by_gamma
    if band.paschen_curve == "empirical":   # γ does not enter the measured curve
        words = {k: "the empirical air curve" for k in ("lower", "estimate", "upper")}
        at_upper = at_estimate = band.static_at_gamma
    else:
        words = {"lower": f"gamma = {band.gamma_lower:g}", "estimate": f"gamma = {band.gamma:g}",
                 "upper": f"gamma = {band.gamma_upper:g}"}
        at_upper = by.get(band.gamma_upper, math.nan)
        at_estimate = band.static_at_gamma
    return {
        "lower": f"lower    {band.lower * 1e6:.4g} µC/m^2: the static limit (breaks down the "
                 f"moment the critical gap ({band.lower_gap * 1e3:.3g} mm) exceeds Paschen's "
                 f"V_b), {words['lower']} (a seed electron always present)",
        "estimate": f"estimate {band.estimate * 1e6:.4g} µC/m^2: seeded, at or above the static "
                    f"limit {at_estimate * 1e6:.4g} of the same gamma: "
                    f"{band.seeds.breakdowns_per_s:g} "
                    f"seeded breakdown(s) per second from S_v = {band.seeds.seed_rate * 1e-6:g} "
                    f"/cm^3/s and n_ion = {band.seeds.ion_density * 1e-6:g} /cm^3 in the "
                    f"over-stressed volume along the trajectory, {words['estimate']} "
                    f"({band.estimate_rule})",
        "upper": f"upper    {band.upper * 1e6:.4g} µC/m^2: the static limit where the smaller "
                 f"gap is widest along the trajectory ({band.upper_gap * 1e3:.3g} mm), "
                 f"{words['upper']} (at the critical gap this gamma's static limit is "
                 f"{at_upper * 1e6:.4g}): breaks down even there"}


def gamma_line(band: Band) -> str:
    """``tengfield breakdown``'s line: the static limit σ_max at each γ taken (the
    range's ends and the scene's), none of them an edge of the band but lower."""
    by = band.static_by_gamma
    if band.paschen_curve == "empirical":
        return (f"static limit sigma_max = {band.static_at_gamma * 1e6:.4g} µC/m^2 (empirical "
                "air curve: gamma does not enter)")
    each = ", ".join(f"{by[g] * 1e6:.4g} at gamma {g:g}"
                     + (" (the scene's)" if g == band.gamma else "")
                     for g in sorted(by, reverse=True))
    return (f"static limit sigma_max by gamma in [{band.gamma_range[0]:g}, "
            f"{band.gamma_range[1]:g}]: {each} µC/m^2 ({band.paschen_curve})")


def _gammas(paschen: Paschen, gamma_range) -> list[float]:
    return sorted({float(gamma_range[0]), float(gamma_range[1]), float(paschen.gamma)})


def _smaller_gap(lines: Lines, z) -> np.ndarray:
    """The ball's smaller axial gap [m] at positions ``z`` (the cell's own lines)."""
    axial = lines.lengths(z)[:, :, 0]
    present = [k for k, on in enumerate(lines.sides) if on]
    return np.nanmin(axial[:, present], axis=1)


def compute_band(lines: Lines, paschen: Paschen, states, reference: str,
                 trajectory: Trajectory | None, gamma_range=(1e-4, 0.1),
                 seeds: Seeds = Seeds()) -> Band:
    """The band (module docstring) of ``lines`` along ``trajectory`` (None or a ball at
    rest: the whole stroke stands for it and the estimate is the upper edge)."""
    states = tuple(states)
    gammas = _gammas(paschen, gamma_range)
    static = {g: evaluate(lines, paschen.with_gamma(g), states, reference) for g in gammas}
    gamma_lower = min(gammas, key=lambda g: static[g].sigma_max)
    lower = static[gamma_lower].sigma_max
    track = None
    if trajectory is not None and trajectory.duration > 0:
        track = stress_track(lines, paschen, states, reference, trajectory)
        if not np.any(track.smaller_gap > 0):
            track = None          # a ball at rest
    if track is not None:
        z_path, smaller = track.position, track.smaller_gap
    else:
        z_path = np.linspace(0.0, lines.stroke, 801)
        smaller = _smaller_gap(lines, z_path)
    widest = int(np.nanargmax(smaller))
    z_wide = float(z_path[widest])
    at_wide = {}
    for g in gammas:
        limits = [np.min(_dense_minimum(lines, paschen.with_gamma(g), s, reference,
                                        np.array([z_wide]))[2]) for s in states]
        at_wide[g] = float(min(limits))
    gamma_upper = max(gammas, key=lambda g: at_wide[g])
    upper = max(at_wide[gamma_upper], lower)
    static_scene = static[paschen.gamma].sigma_max
    if track is not None:
        start = min(max(static_scene, float(np.min(track.threshold))), upper)
        estimate, rule = _seed_limited(track, seeds, start, upper)
    else:
        estimate, rule = upper, "ball at rest: no trajectory, the upper edge"
    estimate = min(max(estimate, lower), upper)
    gap = math.nan
    if track is not None:
        volume = track.over_stressed_volume(estimate * (1 + 1e-9))
        i = int(np.argmax(volume)) if np.any(volume > 0) else int(np.argmax(track.ratio(1.0)))
        gap = float(track.smaller_gap[i])
    # the range the edges were taken over: [breakdown] gamma_range widened to hold the
    # scene's gamma (a gamma = 0.5 outside 1e-4 ... 0.1 is an edge's own gamma)
    return Band(lower=lower, estimate=estimate, upper=upper,
                gamma_range=(gammas[0], gammas[-1]),
                gamma=paschen.gamma, gamma_lower=gamma_lower, gamma_upper=gamma_upper,
                seeds=seeds, lower_position=static[gamma_lower].binding.position,
                lower_gap=static[gamma_lower].binding.gap, upper_position=z_wide,
                upper_gap=float(smaller[widest]),
                estimate_gap=gap, estimate_rule=rule, static_at_gamma=static_scene,
                seeds_at_estimate=(expected_seeds(track, estimate, seeds) if track is not None
                                   else {}),
                paschen_curve=paschen.curve, track=track,
                static_by_gamma={g: static[g].sigma_max for g in gammas})


def edge_ratios(result, band: Band, points: int = 301) -> dict:
    """Each edge's max over lines of |V_gap| / V_b against the ball position z [m] over the
    positions its trajectory visits, with V_b at the edge's own γ (``lower`` at
    ``gamma_lower``, ``estimate`` at the scene's, ``upper`` at ``gamma_upper``): lower
    touches 1 at its binding position, upper at the widest gap (its minimum), each once
    (a function of z: the ball's way up and down fall on one curve). Returns
    ``{"z": z, edge: (γ, ratio)}``; empty without a trajectory."""
    if band.track is None or result.lines is None:
        return {}
    track, lines = band.track, result.lines
    z = np.linspace(float(np.min(track.position)), float(np.max(track.position)), points)
    for known in (band.lower_position, band.upper_position):
        if z[0] <= known <= z[-1]:
            z = np.union1d(z, [known])       # the binding positions on the curve exactly
    gammas = {"lower": band.gamma_lower, "estimate": band.gamma, "upper": band.gamma_upper}
    out = {"z": z}
    for edge, sigma in band.edges().items():
        paschen = result.paschen.with_gamma(gammas[edge])
        threshold = np.full(z.size, np.inf)
        for state in result.states:
            limits = _dense_minimum(lines, paschen, state, result.reference, z)[2]
            threshold = np.minimum(threshold, np.min(limits.reshape(z.size, -1), axis=1))
        with np.errstate(divide="ignore"):
            out[edge] = (gammas[edge], sigma / threshold)
    return out


def _seed_limited(track: StressTrack, seeds: Seeds, start: float, upper: float):
    """The smallest σ in [start, upper] whose expected seeded breakdowns per second reach
    the criterion (a scan, then bisection), or ``upper`` when they do not."""
    target = seeds.breakdowns_per_s
    track = track.below(upper * (1 + 1e-9))

    def reached(sigma):
        return expected_seeds(track, sigma, seeds)["per_s"] >= target

    if not reached(upper):
        return upper, "clamped to the upper edge: the seeds stay below the criterion"
    if reached(start):
        return start, "at the static limit: seeds are plentiful"
    grid = np.geomspace(start, upper, 41)
    hit = next(i for i, s in enumerate(grid) if reached(s))
    lo, hi = grid[hit - 1], grid[hit]
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if reached(mid) else (mid, hi)
        if hi - lo <= 1e-12 * hi:
            break
    return hi, "seeded breakdowns per second reach the criterion"


def scene_band(scene, result, dynamics=None) -> Band:
    """The band of a scene from its :class:`BreakdownResult` (which holds its lines) and
    its dynamics (None: the scene's own, simulated)."""
    if dynamics is None:
        from ..dynamics import simulate
        dynamics = simulate(scene)
    trajectory = trajectory_of(dynamics, scene)
    return compute_band(result.lines, result.paschen, result.states, result.reference,
                        trajectory, scene.breakdown.gamma_range, Seeds.from_scene(scene))


def trajectory_block(band: Band, sigma: float) -> dict:
    """At the scene's σ: the trajectory's peak max |V_gap| / V_b and the time [s] above 1
    (and the fraction of the trajectory)."""
    if band.track is None or sigma == 0:
        return {"peak_gap_voltage_over_breakdown": 0.0, "time_above_breakdown_s": 0.0}
    ratio = band.track.ratio(abs(sigma))
    t = band.track.time
    dt = np.diff(t)
    above = 0.5 * ((ratio[1:] > 1).astype(float) + (ratio[:-1] > 1)) @ dt if t.size > 1 else 0.0
    duration = float(t[-1] - t[0]) if t.size > 1 else 0.0
    return {"peak_gap_voltage_over_breakdown": float(np.max(ratio)),
            "time_above_breakdown_s": float(above),
            "fraction_above_breakdown": float(above / duration) if duration else 0.0,
            "over_s": duration,
            "rule": "max over lines, sides and circuit states of |V_gap| / V_b along the "
                    "trajectory's steady window at the scene's sigma and gamma"}


def output_band(summary: dict, band: Band, sigma: float, linear: bool = True) -> dict:
    """``summary.json["breakdown_band"]``: each main output (``peak.I_sc_A``, ...) at the
    band's three σ, scaled from the run at |σ| = ``sigma`` (outputs linear in σ; powers
    ∝ σ²): no solve."""
    from ..quantities import summary_keys, summary_value

    out = {}
    if not linear or sigma == 0:
        return out
    for key in summary_keys(instrument=True):
        name = key.split(".")[-1]
        value = summary_value(summary, key)
        if value is None or not isinstance(value, (int, float)):
            continue
        if name in LINEAR_QUANTITIES:
            power = 1
        elif key in ("load.mean_power_W", "load.power_density_W_per_m3"):
            power = 2
        else:
            continue
        out[key] = {edge: float(value) * (s / abs(sigma)) ** power
                    for edge, s in band.edges().items()}
    return out


def band_summary(summary: dict, scene, given, result, dynamics) -> dict:
    """A run's additions to ``summary["breakdown"]``: ``band``, ``trajectory`` (at the
    scene's σ) and, for σ = "breakdown" (``given``: the scene as loaded), ``outputs``:
    each main output at the band's three σ (``summary.json["breakdown_band"]``)."""
    from .charge import uses_breakdown_charge

    band = scene_band(scene, result, dynamics)
    sigma = scene.device.surface_charge
    out = {"band": band.to_json(), "trajectory": trajectory_block(band, sigma)}
    if uses_breakdown_charge(given):
        from ..electrical import circuit_for

        linear = circuit_for(scene).linear_in_charge     # the entry says, not its name
        out["outputs"] = output_band(summary, band, sigma, linear)
        if not linear:
            out["outputs"] = {"available": False,
                              "reason": f"[circuit] kind = {scene.circuit.kind!r} is not "
                                        "linear in sigma: run at each edge's sigma"}
    return out
