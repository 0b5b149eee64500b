"""Recommendations: the cheapest measured combination for a target accuracy.

:func:`recommend` picks it from the measured rows; :func:`recommended_field_settings`
turns a tolerance into the ``[field]`` keys (default: the recommendations in
``calibration.json``, :func:`default_recommendations`); :func:`scene_with_recommended`
applies them to the keys a scene file does not set.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

from ..errors import SceneError
from .plan import BUDGET_SHARE, MIN_ADAPTIVE_POSITIONS, FieldSetting, Row, solves_needed

@dataclass
class Recommendation:
    """The cheapest measured combination for one ``target`` relative accuracy."""
    target: float
    field: dict                 # [field] keys
    sample_rate_hz: float       # [run] sample_rate_hz
    predicted_error: float      # sum of the parts' measured errors
    predicted_cost_s: float     # solves x time per solve
    measured_error: float = math.nan   # of the verification run against the overall reference
    measured_errors: dict = field(default_factory=dict)
    measured_wall_time_s: float = math.nan
    positions: int = 0
    reached: bool = False
    note: str = ""

    def scene_sections(self) -> dict:
        return {"field": dict(self.field), "run": {"sample_rate_hz": self.sample_rate_hz}}


def recommend(rows: list[Row], target: float) -> Recommendation:
    """Cheapest field setting, surrogate size and sampling rate for ``target``.

    Every combination of a measured axisymmetric field level, a surrogate
    level and an impact-map sampling level competes; its predicted error is
    the sum of the three measured errors (they add at worst), its predicted
    cost the field solves the surrogate needs times the time per solve plus
    the dynamics. The cheapest combination whose predicted error is at most
    ``target`` wins. The adaptive surrogate always solves at least
    ``MIN_ADAPTIVE_POSITIONS``, so smaller levels do not compete. When no
    combination is predicted to reach the target, the most accurate one is
    used and ``note`` says so. Field levels compete only with the Kelvin far
    field (exact, and no dearer than the truncated ones) and only if their
    own C and q error (``error_position``) is within the target. A 3D row
    has no waveform errors and does not compete.
    """
    kelvin = [r for r in rows if r.stage == "field" and r.knobs.get("method") == "axisymmetric"
              and r.knobs.get("far_field") == "kelvin" and math.isfinite(r.error)]
    # C and q themselves must be accurate: a truncated far field or a coarse mesh can
    # hit one scene's peaks by cancellation, which would not carry over to another scene
    field_rows = [r for r in kelvin if r.error_position <= target] or kelvin
    surrogate_rows = [r for r in rows if r.stage == "surrogate"]
    usable_surrogates = [r for r in surrogate_rows if math.isfinite(r.error)
                         and int(r.knobs["positions"]) >= MIN_ADAPTIVE_POSITIONS] or \
        [r for r in surrogate_rows if math.isfinite(r.error)]
    sampling_rows = [r for r in rows if r.stage == "dynamics" and r.knobs.get("model") == "impact"
                     and "sample_rate_hz" in r.knobs and math.isfinite(r.error)]
    if not (field_rows and usable_surrogates and sampling_rows):
        raise ValueError("recommend needs measured field, surrogate and sampling rows")

    def per_solve(f: Row) -> float:
        return f.wall_time_s / max(1, f.knobs.get("solves", 1))

    combos = []
    for f in field_rows:
        for s in usable_surrogates:
            for d in sampling_rows:
                cost = per_solve(f) * solves_needed(int(s.knobs["positions"])) + d.wall_time_s
                combos.append((f.error + s.error + d.error, cost, f, s, d))
    feasible = [c for c in combos if c[0] <= target]
    note = ""
    if feasible:
        error, cost, f, s, d = min(feasible, key=lambda c: (c[1], c[0]))
    else:
        error, cost, f, s, d = min(combos, key=lambda c: (c[0], c[1]))
        note = (f"no measured combination is predicted to reach {target:g}; the most accurate "
                "one is used")
    setting = FieldSetting(**{k: f.knobs[k] for k in
                              ("method", "degree", "mesh_size_mm", "far_field", "domain_radius_mm")})
    positions = int(s.knobs["positions"])
    tolerance = surrogate_tolerance(surrogate_rows, positions, BUDGET_SHARE * target)
    return Recommendation(
        target=target, field={**setting.field_block(), "tolerance": float(f"{tolerance:.3g}")},
        sample_rate_hz=float(d.knobs["sample_rate_hz"]), predicted_error=error,
        predicted_cost_s=cost, positions=positions, note=note)


def surrogate_tolerance(surrogate_rows: list[Row], positions: int, budget: float) -> float:
    """``[field] tolerance`` that makes the adaptive surrogate end with at least ``positions``.

    :func:`tengfield.surrogate.precompute` refines a Lobatto set of m
    positions to 2m − 1 while the held-out estimate e(m) exceeds the
    tolerance. The estimate measures Q_SC, C_T and V_OC, not dQ_SC/dz, so
    I_SC can need more positions than the estimate asks for: the tolerance
    is then set to half the estimate of the last level that must still be
    refined (the largest m with 2m − 1 < ``positions``).
    """
    tolerance = budget
    estimates = {int(r.knobs["positions"]): float(r.knobs.get("held_out_estimate", math.nan))
                 for r in surrogate_rows}
    first = (MIN_ADAPTIVE_POSITIONS + 1) // 2          # the adaptive surrogate starts here
    must_refine = [m for m in estimates if first <= m and 2 * m - 1 < positions
                   and math.isfinite(estimates[m])]
    if must_refine:
        tolerance = min(tolerance, 0.5 * estimates[max(must_refine)])
    return tolerance


def recommended_field_settings(tolerance: float, recommendations=None) -> dict:
    """``[field]`` keys (file units) whose final waveforms reach ``tolerance``.

    ``recommendations``: a list of :class:`Recommendation` (or their dicts,
    e.g. ``report.json → recommendations``); default: those measured by
    ``tengfield report`` on the default scene (:func:`default_recommendations`).
    The loosest measured target at or below ``tolerance`` is used (so the
    cheapest one that is accurate enough), with its verified ``tolerance``
    key (the surrogate's threshold, a share of the target). A tolerance
    tighter than every measured target extrapolates the strictest setting:
    degree 2, ``mesh_size × (tolerance / target)^(1/4)`` (the rate h⁴) and
    the surrogate threshold scaled by ``tolerance / target``.
    """
    if not (isinstance(tolerance, (int, float)) and 0.0 < tolerance < 1.0):
        raise SceneError(f"[field] tolerance = {tolerance!r} is out of range: allowed (0, 1)")
    if recommendations is None:
        recommendations = default_recommendations()
    entries = sorted((_as_dict(r) for r in recommendations), key=lambda r: r["target"])
    if not entries:
        raise ValueError("no recommendations to choose from")
    usable = [e for e in entries if e["target"] <= tolerance * (1 + 1e-9)]
    if usable:
        block = dict(usable[-1]["field"])
    else:
        chosen = entries[0]
        block = dict(chosen["field"])
        ratio = tolerance / chosen["target"]
        block["degree"] = 2
        block["mesh_size_mm"] = float(f"{block['mesh_size_mm'] * ratio ** 0.25:.3g}")
        block["tolerance"] = float(f"{block['tolerance'] * ratio:.3g}")
    return block


def recommended_sample_rate(tolerance: float, recommendations=None) -> float:
    """``[run] sample_rate_hz`` paired with :func:`recommended_field_settings`."""
    if recommendations is None:
        recommendations = default_recommendations()
    entries = sorted((_as_dict(r) for r in recommendations), key=lambda r: r["target"])
    usable = [e for e in entries if e["target"] <= tolerance * (1 + 1e-9)]
    chosen = usable[-1] if usable else entries[0]
    rate = float(chosen["sample_rate_hz"])
    if not usable:
        rate *= chosen["target"] / tolerance
    return rate


def scene_with_recommended(scene, recommendations=None):
    """``scene`` with its ``[field] tolerance`` read as the target accuracy of the
    final waveforms: the recommended discretisation fills in every ``[field]``
    key the scene file does not set itself (explicit keys win), and
    ``tolerance`` becomes the recommended surrogate threshold."""
    block = recommended_field_settings(scene.field.tolerance, recommendations)
    explicit = set((scene.raw.get("field") or {}).keys()) - {"tolerance"}
    chosen = {k: v for k, v in block.items() if k not in explicit}
    return scene.with_values(field=chosen)


def default_recommendations() -> list[dict]:
    """The recommendations measured by ``tengfield report`` on the embedded default
    scene (``tengfield/accuracy_report/calibration.json``; how to regenerate: its ``about``)."""
    import json
    from importlib import resources

    text = resources.files(__package__).joinpath("calibration.json").read_text()
    return json.loads(text)["recommendations"]


def _as_dict(entry) -> dict:
    return dataclasses.asdict(entry) if dataclasses.is_dataclass(entry) else dict(entry)
