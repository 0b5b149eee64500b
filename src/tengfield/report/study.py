"""Error against run time for every stage, and the cheapest settings for a target accuracy.

``tengfield report [SCENE] -o DIR [--fast]`` (see ``docs/report.md``) runs
each stage of the pipeline at several accuracy levels and measures the
relative error of the *final waveforms* — the peak-to-peak open-circuit
voltage V_OC, short-circuit charge Q_SC and short-circuit current I_SC over
the steady window — against stated references:

* **field** (mesh size, degree, axisymmetric vs 3D, far-field treatment):
  every setting is solved at the same Chebyshev–Lobatto positions; the
  reference is the Richardson extrapolation (rate h⁴ of degree 2) of the two
  finest degree-2 axisymmetric Kelvin settings. A 3D row compares C and q at
  mid-stroke only (``error_position``), a 3D surrogate being too dear.
* **surrogate** (number of positions): nested Lobatto sets at the finest
  field setting against the largest set.
* **dynamics**: output sampling rate of the exact impact map against a
  much finer rate (the event location itself is exact to 1e-13 m and has
  no knob), and the soft contact of Eq. 1 at growing stiffness against the
  impact map (its rigid limit).
* **circuit**: the load ODE's step (the output sampling) for a stiff, a
  medium and a slow load, against a 16× finer step.

It then picks, for each target (1e-2, 1e-3), the cheapest combination whose
measured errors add up to at most the target, *runs it* (adaptive surrogate as
``tengfield run`` builds it, trajectory at the chosen rate) and states the
error it really reaches against the overall reference (largest surrogate at
the finest field setting, finest sampling). :func:`recommended_field_settings`
turns a tolerance into the ``[field]`` keys; :func:`scene_with_recommended`
applies them to the keys a scene file does not set.

All numbers are SI; errors are relative (|x − x_ref| / |x_ref|).
"""
from __future__ import annotations

import dataclasses
import math
import sys
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Iterable

import numpy as np

from .. import circuit, electrical
from ..errors import SceneError
from ..surrogate import FEWEST_POSITIONS

QUANTITIES = ("V_oc", "Q_sc", "I_sc")
TARGETS = (1e-2, 1e-3)
#: the surrogate's ``[field] tolerance`` is at most this share of the target
BUDGET_SHARE = 1.0 / 3.0
#: fewest positions the adaptive surrogate ends with: its initial Lobatto set and the
#: positions held out between them (9 + 8 = 17), see :func:`tengfield.surrogate.precompute`
MIN_ADAPTIVE_POSITIONS = FEWEST_POSITIONS


# ---------------------------------------------------------------------------
# settings and rows
@dataclass(frozen=True)
class FieldSetting:
    """One discretisation of the field solve (file-level ``[field]`` units)."""
    method: str = "axisymmetric"
    degree: int = 2
    mesh_size_mm: float = 0.5
    far_field: str = "kelvin"
    domain_radius_mm: float = 20.0

    @property
    def label(self) -> str:
        text = f"{self.method} p{self.degree} h={self.mesh_size_mm:g}mm"
        if self.far_field != "kelvin" or self.domain_radius_mm != 20.0:
            text += f" {self.far_field} R={self.domain_radius_mm:g}mm"
        return text

    def overrides(self) -> dict:
        """Keyword arguments of :func:`tengfield.field.solve_position`."""
        return {"method": self.method, "degree": self.degree, "mesh_size_mm": self.mesh_size_mm,
                "far_field": self.far_field, "domain_radius_mm": self.domain_radius_mm}

    def field_block(self) -> dict:
        """The ``[field]`` keys of this setting."""
        return {"method": self.method, "degree": self.degree,
                "mesh_size_mm": self.mesh_size_mm, "far_field": self.far_field,
                "domain_radius_mm": self.domain_radius_mm}


@dataclass
class Row:
    """One accuracy level of one stage: its cost and its errors."""
    stage: str
    setting: str
    knobs: dict
    wall_time_s: float
    errors: dict                      # quantity -> relative error
    reference: str
    error_position: float = math.nan  # field only: max relative error of C, q
    note: str = ""

    @property
    def error(self) -> float:
        """Largest relative error over the waveform quantities (NaN if none)."""
        values = [v for v in self.errors.values() if v is not None and math.isfinite(v)]
        return max(values) if values else math.nan


@dataclass(frozen=True)
class Plan:
    """What :func:`build_report` measures (``fast`` is the CI-sized plan)."""
    field_positions: int
    field_settings: tuple
    reference_pair: tuple               # (coarser, finer) degree-2 axisymmetric kelvin
    far_field_settings: tuple
    settings_3d: tuple
    surrogate_counts: tuple
    reference_count: int
    sample_rates: tuple
    reference_sample_rate: float
    stiffnesses: tuple
    loads: tuple
    circuit_rates: tuple
    circuit_refinement: int = 16


def _settings(levels, **keys) -> tuple:
    """FieldSettings of ``(degree, mesh_size_mm)`` pairs with the same other ``keys``."""
    return tuple(FieldSetting(degree=degree, mesh_size_mm=size, **keys) for degree, size in levels)


def make_plan(fast: bool = False) -> Plan:
    """The accuracy levels of the report; ``fast`` keeps it to about a minute."""
    if fast:
        ref = _settings([(2, 1.0), (2, 0.5)])
        return Plan(
            field_positions=5,
            field_settings=_settings([(1, 2.0), (1, 1.0), (2, 2.0), (2, 1.4)]) + ref,
            reference_pair=ref,
            far_field_settings=(_settings([(2, 1.0)], far_field="robin")
                                + _settings([(2, 1.0)], far_field="dirichlet")),
            settings_3d=_settings([(1, 2.5)], method="3d", far_field="robin"),
            surrogate_counts=(5, 9, 17), reference_count=33,
            sample_rates=(5000.0, 20000.0, 80000.0, 320000.0), reference_sample_rate=1.28e6,
            stiffnesses=(1e4, 1e5),
            loads=(1e4, 1e8), circuit_rates=(2500.0, 5000.0, 10000.0), circuit_refinement=8)
    ref = _settings([(2, 0.5), (2, 0.25)])
    return Plan(
        field_positions=9,
        field_settings=_settings([(1, 2.0), (1, 1.0), (1, 0.5), (1, 0.25),
                                      (2, 2.0), (2, 1.4), (2, 1.0), (2, 0.7)]) + ref,
        reference_pair=ref,
        far_field_settings=tuple(FieldSetting(degree=2, mesh_size_mm=0.5, far_field=far,
                                              domain_radius_mm=radius)
                                 for far in ("robin", "dirichlet") for radius in (20.0, 40.0)),
        settings_3d=(_settings([(1, 2.0), (1, 1.4)], method="3d", far_field="robin")
                     + _settings([(2, 2.0)], method="3d", far_field="kelvin")),
        surrogate_counts=(5, 9, 17, 33), reference_count=65,
        sample_rates=tuple(2500.0 * 2 ** k for k in range(9)),       # 2.5 kHz .. 640 kHz
        reference_sample_rate=2.56e6,
        stiffnesses=(1e4, 1e5, 1e6),
        loads=(1e4, 1e8, 1e11), circuit_rates=(2500.0, 5000.0, 10000.0, 20000.0, 40000.0))


# ---------------------------------------------------------------------------
# pure pieces
def relative_error(value: float, reference: float) -> float:
    """|value − reference| / |reference| (NaN when the reference is 0)."""
    return abs(value - reference) / abs(reference) if reference != 0.0 else math.nan


def peak_errors(peaks: dict, reference: dict) -> dict:
    """Relative error of each peak-to-peak value against the reference's."""
    return {k: relative_error(peaks[k], reference[k]) for k in peaks}


def richardson(coarse, fine, ratio: float, order: float):
    """Richardson extrapolation ``fine + (fine − coarse) / (ratio^order − 1)`` (elementwise)."""
    coarse, fine = np.asarray(coarse, dtype=float), np.asarray(fine, dtype=float)
    return fine + (fine - coarse) / (ratio**order - 1.0)


def max_relative_deviation(values, reference) -> float:
    """Largest |values − reference| / |reference| over the entries (C and q arrays)."""
    values, reference = np.asarray(values, dtype=float), np.asarray(reference, dtype=float)
    scale = np.abs(reference)
    ok = scale > 0
    return float(np.max(np.abs(values - reference)[ok] / scale[ok]))


def cheapest(rows: Iterable[Row], target: float, *, key: Callable[[Row], float] | None = None):
    """The row of least wall time whose error is at most ``target`` (None if none)."""
    key = key or (lambda r: r.error)
    good = [r for r in rows if math.isfinite(key(r)) and key(r) <= target]
    return min(good, key=lambda r: r.wall_time_s) if good else None


def solves_needed(count: int, symmetric: bool = True) -> int:
    """Field solves for a Lobatto set of ``count`` positions (mirror symmetry halves it)."""
    return (count + 1) // 2 if symmetric else count


# ---------------------------------------------------------------------------
# recommendations
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
    scene (``tengfield/report/calibration.json``; how to regenerate: its ``about``)."""
    import json
    from importlib import resources

    text = resources.files(__package__).joinpath("calibration.json").read_text()
    return json.loads(text)["recommendations"]


def _as_dict(entry) -> dict:
    return dataclasses.asdict(entry) if dataclasses.is_dataclass(entry) else dict(entry)


# ---------------------------------------------------------------------------
# the measurement
@dataclass
class Report:
    """Everything :func:`build_report` measured (``rows``) and recommends."""
    scene: Any
    plan: Plan
    rows: list
    recommendations: list
    references: dict
    trajectory: dict
    wall_time_s: float
    fast: bool


class _Solver:
    """Field solves at (setting, position), each done once (mirror images are free)."""

    def __init__(self, scene, comm, solve=None, progress=None):
        self.scene = scene
        self.comm = comm
        self.stroke = scene.device.stroke
        self.symmetric = scene.field.environment == "free-space"
        self.cache: dict = {}
        self._solve = solve
        self.progress = progress

    def key(self, setting: FieldSetting, z: float):
        return (setting, round(z / self.stroke, 12))

    def compute(self, setting: FieldSetting, z: float):
        """One field solve, not cached (what a rank of the farm runs)."""
        if self._solve is None:
            from ..field import solve_position
            self._solve = solve_position
        return self._solve(self.scene, float(z), comm=self.comm, estimate_error=False,
                           **setting.overrides())

    def solve(self, setting: FieldSetting, z: float):
        key = self.key(setting, z)
        if key not in self.cache:
            self.cache[key] = self.compute(setting, z)
            if self.progress is not None:
                self.progress(1)
        return self.cache[key]

    def solved_positions(self, count: int) -> list[float]:
        """The positions a table of ``count`` Lobatto positions solves (mirror images are free)."""
        from ..surrogate import lobatto_positions

        return [float(self.stroke - z) if self._mirror(z) else float(z)
                for z in lobatto_positions(self.stroke, count)]

    def _mirror(self, z: float) -> bool:
        return self.symmetric and z > 0.5 * self.stroke * (1 + 1e-12)

    def prefetch(self, pairs, farm_comm) -> None:
        """Solve every (setting, z) of ``pairs`` not yet cached, farmed over the ranks of
        ``farm_comm`` (:func:`tengfield._mpi.farm`, dearest first); every rank then holds
        every result, so the stages that follow run the same on every rank."""
        from .._mpi import farm, rank_of

        todo = {}
        for setting, z in pairs:
            key = self.key(setting, z)
            if key not in self.cache and key not in todo:
                todo[key] = (setting, float(z))
        # dearest first (3D, then the most cells x degree^2), so the dynamic schedule balances
        items = sorted(todo.values(), key=lambda p: (p[0].method == "3d",
                                                     p[0].degree**2 / p[0].mesh_size_mm**2),
                       reverse=True)
        progress = self.progress if rank_of(farm_comm) == 0 else None
        results = farm(farm_comm, items, lambda item: self.compute(*item), progress=progress)
        for (setting, z), result in zip(items, results):
            self.cache[self.key(setting, z)] = result

    def table(self, setting: FieldSetting, count: int):
        """Surrogate table of ``count`` Lobatto positions and its solve wall time [s]."""
        from ..surrogate import lobatto_positions, mirrored, table_from_results

        positions = lobatto_positions(self.stroke, count)
        results, wall = [], 0.0
        for z in positions:
            if self._mirror(z):
                results.append(mirrored(self.solve(setting, self.stroke - z), self.stroke))
            else:
                res = self.solve(setting, z)
                wall += res.wall_time
                results.append(res)
        return table_from_results(results, stroke=self.stroke), wall


def planned_solves(solver: _Solver, plan: Plan) -> list:
    """Every (setting, position) the field and surrogate stages solve
    (for :meth:`_Solver.prefetch`)."""
    pairs = []
    for setting in dict.fromkeys(plan.field_settings + plan.far_field_settings):
        pairs += [(setting, z) for z in solver.solved_positions(plan.field_positions)]
    mid = 0.5 * solver.stroke
    pairs += [(setting, mid) for setting in plan.reference_pair + tuple(plan.settings_3d)]
    finest = plan.reference_pair[1]
    for count in {plan.reference_count, *plan.surrogate_counts,
                  *(2 * c - 1 for c in plan.surrogate_counts)}:
        pairs += [(finest, z) for z in solver.solved_positions(count)]
    return pairs


def _curves(table, scene):
    from ..surrogate import TerminalCurves
    return TerminalCurves(table, scene.circuit.reference)


def _trajectory(scene, sample_rate: float | None = None, **contact):
    """Simulate ``scene`` (optionally at another sampling rate / contact model);
    returns (dynamics result, wall time [s], the scene that was simulated)."""
    from ..dynamics import simulate

    changes = {}
    if sample_rate is not None:
        changes["run"] = {"sample_rate_hz": float(sample_rate)}
    if contact:
        changes["contact"] = contact
    run_scene = scene.with_values(**changes) if changes else scene
    start = time.perf_counter()
    dyn = simulate(run_scene)
    return dyn, time.perf_counter() - start, run_scene


def field_rows(solver: _Solver, plan: Plan, scene, trajectory, progress=None) -> tuple[list, dict]:
    """The field stage: every setting at the same Lobatto positions (see the module docstring)."""
    rows = []
    n = plan.field_positions
    tables = {}
    for setting in dict.fromkeys(plan.field_settings + plan.far_field_settings):
        tables[setting] = solver.table(setting, n)
    coarse, fine = plan.reference_pair
    ratio = coarse.mesh_size_mm / fine.mesh_size_mm
    t_coarse, t_fine = tables[coarse][0], tables[fine][0]
    ref_table = dataclasses.replace(
        t_fine, capacitance=richardson(t_coarse.capacitance, t_fine.capacitance, ratio, 4),
        induced_charge=richardson(t_coarse.induced_charge, t_fine.induced_charge, ratio, 4))
    ref_peaks = electrical.terminal_peaks(scene, trajectory, _curves(ref_table, scene))
    reference = (f"Richardson extrapolation (h^4) of {coarse.label} and {fine.label} "
                 f"at the same {n} Lobatto positions")
    for setting, (table, wall) in tables.items():
        peaks = electrical.terminal_peaks(scene, trajectory, _curves(table, scene))
        pos_err = max(max_relative_deviation(table.capacitance, ref_table.capacitance),
                      max_relative_deviation(table.induced_charge, ref_table.induced_charge))
        rows.append(Row("field", setting.label,
                        {**setting.field_block(), "positions": n,
                         "solves": solves_needed(n, solver.symmetric),
                         "dofs": int(np.max(table.dofs))},
                        wall, peak_errors(peaks, ref_peaks), reference, pos_err))
    # 3D: C and q at mid-stroke against the Richardson reference of the axisymmetric solves
    mid = 0.5 * scene.device.stroke
    ref_mid = [solver.solve(s, mid) for s in plan.reference_pair]
    ref_C = richardson(ref_mid[0].capacitance, ref_mid[1].capacitance, ratio, 4)
    ref_q = richardson(ref_mid[0].induced_charge, ref_mid[1].induced_charge, ratio, 4)
    for setting in plan.settings_3d:
        res = solver.solve(setting, mid)
        err = max(max_relative_deviation(res.capacitance, ref_C),
                  max_relative_deviation(res.induced_charge, ref_q))
        rows.append(Row("field", setting.label, {**setting.field_block(), "positions": 1,
                                                  "solves": 1, "dofs": int(res.dofs)},
                        res.wall_time, {k: math.nan for k in QUANTITIES},
                        "Richardson axisymmetric reference at mid-stroke (C and q only)", err,
                        note="3D: position-level error only"))
    return rows, {"field": reference, "field_peaks": ref_peaks}


def surrogate_rows(solver: _Solver, plan: Plan, scene, trajectory) -> tuple[list, Any]:
    """The surrogate stage: nested Lobatto sets at the finest field setting."""
    setting = plan.reference_pair[1]
    ref_table, _ = solver.table(setting, plan.reference_count)
    ref_curves = _curves(ref_table, scene)
    ref_peaks = electrical.terminal_peaks(scene, trajectory, ref_curves)
    reference = f"{plan.reference_count} Lobatto positions, {setting.label}"
    rows = []
    from ..surrogate import held_out_error, lobatto_positions
    for count in plan.surrogate_counts:
        table, wall = solver.table(setting, count)
        finer = lobatto_positions(scene.device.stroke, 2 * count - 1)[1::2]
        held = solver.table(setting, 2 * count - 1)[0]
        held_out = held.subset(np.isin(np.round(held.positions / scene.device.stroke, 12),
                                       np.round(finer / scene.device.stroke, 12)))
        estimate = held_out_error(table, held_out)
        peaks = electrical.terminal_peaks(scene, trajectory, _curves(table, scene))
        rows.append(Row("surrogate", f"{count} positions",
                        {"positions": count, "solves": solves_needed(count, solver.symmetric),
                         "held_out_estimate": estimate, **setting.field_block()},
                        wall, peak_errors(peaks, ref_peaks), reference))
    return rows, ref_curves


def _peaks_task(scene, curves, sample_rate, contact):
    """Peak-to-peak values of one trajectory and its wall time [s] (one farm task)."""
    dyn, wall, run_scene = _trajectory(scene, sample_rate, **contact)
    return electrical.terminal_peaks(run_scene, dyn, curves), wall


def _tasks(farm_comm, tasks, work, progress):
    """``[work(*t) for t in tasks]``, farmed over ``farm_comm``'s ranks (if any);
    ``progress(n)`` on rank 0 only."""
    from .._mpi import farm, rank_of

    if rank_of(farm_comm) != 0:
        progress = None
    return farm(farm_comm, list(tasks), lambda task: work(*task), progress=progress)


def dynamics_rows(plan: Plan, scene, curves, progress=None, farm_comm=None) -> tuple[list, Any]:
    """Output sampling of the impact map, and soft contact against the impact map.

    Returns the rows and ``(None, reference scene, reference peaks)``; the
    trajectories are farmed over ``farm_comm``'s ranks (every rank gets every row).
    """
    rate = scene.run.sample_rate
    tasks = ([(scene, curves, plan.reference_sample_rate, {})]
             + [(scene, curves, r, {}) for r in plan.sample_rates]
             + [(scene, curves, rate, {})]
             + [(scene, curves, rate, {"model": "soft", "stiffness_N_per_m": k})
                for k in plan.stiffnesses])
    done = _tasks(farm_comm, tasks, _peaks_task, progress)
    ref_peaks = done[0][0]
    sampled = done[1:1 + len(plan.sample_rates)]
    impact_peaks = done[1 + len(plan.sample_rates)][0]
    soft = done[2 + len(plan.sample_rates):]
    rows = []
    for r, (peaks, wall) in zip(plan.sample_rates, sampled):
        rows.append(Row("dynamics", f"impact map, {r:g} Hz sampling",
                        {"model": "impact", "sample_rate_hz": r}, wall,
                        peak_errors(peaks, ref_peaks),
                        f"impact map sampled at {plan.reference_sample_rate:g} Hz plus the "
                        "impact instants (exact extremes)"))
    for k, (peaks, wall) in zip(plan.stiffnesses, soft):
        rows.append(Row("dynamics", f"soft contact k={k:.0e} N/m",
                        {"model": "soft", "stiffness_N_per_m": k, "contact_sample_rate_hz": rate},
                        wall, peak_errors(peaks, impact_peaks),
                        f"impact map (rigid limit), same sampling {rate:g} Hz"))
    ref_scene = scene.with_values(run={"sample_rate_hz": float(plan.reference_sample_rate)})
    return rows, (None, ref_scene, ref_peaks)


def _load_task(scene, curves, load, rate):
    """Mean load power [W], peak-to-peak load voltage [V] and the integrator's wall
    time [s] for one load [ohm] at one step (sampling rate [Hz]); one farm task."""
    loaded = scene.with_values(circuit={"kind": "load", "load_ohm": float(load)})
    dyn, _, run_scene = _trajectory(loaded, rate)
    mask = electrical.steady_window(dyn.t, run_scene)[0]
    start = time.perf_counter()
    out = electrical.steady_load(run_scene, dyn, curves)
    wall = time.perf_counter() - start
    return out["mean_power_W"], circuit.peak_to_peak(out["V_load"][mask]), wall


def circuit_rows(plan: Plan, scene, curves, progress=None, farm_comm=None) -> list:
    """Step of the load integrator (output sampling) for stiff to slow loads
    (the runs farmed over ``farm_comm``'s ranks; every rank gets every row)."""
    ref_rate = plan.circuit_rates[-1] * plan.circuit_refinement
    rates = (ref_rate, *plan.circuit_rates)
    tasks = [(scene, curves, load, rate) for load in plan.loads for rate in rates]
    done = iter(_tasks(farm_comm, tasks, _load_task, progress))
    rows = []
    for load in plan.loads:
        ref_power, ref_v, _ = next(done)
        tau = load * float(np.max(curves.capacitance_samples))
        for rate in plan.circuit_rates:
            power, v, wall = next(done)
            rows.append(Row("circuit", f"R={load:.0e} ohm, {rate:g} Hz step",
                            {"load_ohm": load, "sample_rate_hz": rate,
                             "time_constant_s": tau},
                            wall, {"P_load": relative_error(power, ref_power),
                                   "V_load": relative_error(v, ref_v)},
                            f"exponential integrator at {ref_rate:g} Hz"))
    return rows


def verify(recommendation: Recommendation, scene, reference_peaks, solver: "_Solver",
           farm_comm=None) -> Recommendation:
    """Run the recommended settings the way ``tengfield run`` does and measure them.

    The adaptive surrogate is built by :func:`tengfield.surrogate.precompute`
    with the recommended ``[field]`` keys (its ``tolerance`` decides how many
    positions); solves the report already did are reused (same setting and
    position, hence the same numbers), and the cost counted is the sum of the
    wall times of every solve the surrogate needed plus the dynamics. New solves
    are farmed over ``farm_comm``'s ranks (every rank gets the same table).
    """
    import warnings

    from ..surrogate import TerminalCurves, precompute

    f = recommendation.field
    setting = FieldSetting(method=f["method"], degree=f["degree"], mesh_size_mm=f["mesh_size_mm"],
                           far_field=f["far_field"], domain_radius_mm=f["domain_radius_mm"])

    def solve(_scene, z, comm=None):
        return solver.solve(setting, z)

    chosen = scene.with_values(**recommendation.scene_sections())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        table = precompute(chosen, comm=farm_comm, solve=solve, solve_comm=solver.comm)
    dyn, dyn_wall, run_scene = _trajectory(chosen)
    wall = table.total_solve_wall_time + dyn_wall
    peaks = electrical.terminal_peaks(run_scene, dyn,
                                      TerminalCurves(table, chosen.circuit.reference))
    errors = peak_errors(peaks, reference_peaks)
    worst = max(errors.values())
    return dataclasses.replace(recommendation, measured_error=worst, measured_errors=errors,
                               measured_wall_time_s=wall, positions=table.count,
                               reached=bool(worst <= recommendation.target))


def build_report(scene, *, fast: bool = False, comm=None, plan: Plan | None = None,
                 progress: bool = False, solve=None, farm_comm=None) -> Report:
    """Measure every stage of ``scene`` at several accuracy levels (see the module docstring).

    ``comm``: communicator of each field solve (default ``MPI.COMM_SELF``);
    ``solve``: the field solver (default :func:`tengfield.field.solve_position`,
    called as ``solve(scene, z, comm=..., estimate_error=False, **setting)``).
    ``farm_comm``: with several ranks (``mpirun -n N tengfield report``, the CLI
    passes ``COMM_WORLD``) the field solves, the trajectories of the dynamics
    and circuit stages and the verification solves are farmed over its ranks
    (:func:`tengfield._mpi.farm`); every rank returns the same rows and
    recommendations, whose errors equal a serial run's (wall times are measured
    on whichever rank ran the job).
    """
    from tqdm import tqdm

    from .._mpi import rank_of

    if comm is None:
        from mpi4py import MPI
        comm = MPI.COMM_SELF
    plan = plan or make_plan(fast)
    started = time.perf_counter()
    total = _task_estimate(plan)
    bar = tqdm(total=total, desc="report", unit="task", file=sys.stderr,
               disable=not progress or rank_of(farm_comm) != 0 or not sys.stderr.isatty())

    def advance(n=1):
        bar.update(n)

    solver = _Solver(scene, comm, solve=solve, progress=advance)
    trajectory, _, traj_scene = _trajectory(scene)
    solver.prefetch(planned_solves(solver, plan), farm_comm)
    rows, references = [], {}
    f_rows, f_ref = field_rows(solver, plan, traj_scene, trajectory)
    rows += f_rows
    references.update(f_ref)
    s_rows, ref_curves = surrogate_rows(solver, plan, traj_scene, trajectory)
    rows += s_rows
    references["surrogate"] = s_rows[0].reference
    d_rows, (_, _, overall_peaks) = dynamics_rows(plan, scene, ref_curves, advance, farm_comm)
    rows += d_rows
    references["dynamics"] = d_rows[0].reference
    rows += circuit_rows(plan, scene, ref_curves, advance, farm_comm)
    references["overall"] = (f"{plan.reference_count} Lobatto positions at "
                             f"{plan.reference_pair[1].label}, impact map sampled at "
                             f"{plan.reference_sample_rate:g} Hz")
    references["overall_peaks"] = overall_peaks
    recommendations = []
    for target in TARGETS:
        rec = recommend(rows, target)
        rec = verify(rec, scene, overall_peaks, solver, farm_comm)
        recommendations.append(rec)
        advance()
    bar.close()
    return Report(scene=scene, plan=plan, rows=rows, recommendations=recommendations,
                  references=references,
                  trajectory={"regime": getattr(trajectory.regime, "name", ""),
                              "sample_rate_hz": traj_scene.run.sample_rate},
                  wall_time_s=time.perf_counter() - started, fast=fast)


def _task_estimate(plan: Plan) -> int:
    field_solves = len(set(plan.field_settings + plan.far_field_settings)) * \
        solves_needed(plan.field_positions) + len(plan.settings_3d)
    surrogate_solves = solves_needed(plan.reference_count)
    # dynamics: the reference, each rate, the impact map at the run's rate, each stiffness;
    # circuit: per load the reference step and each step
    return (field_solves + surrogate_solves + len(plan.sample_rates) + len(plan.stiffnesses) + 2
            + len(plan.loads) * (len(plan.circuit_rates) + 1) + len(TARGETS))
