"""The design's answer, stated: what to build, how much it gives, what it rests on.

Pure functions of a :class:`~tengfield.design_study.search.DesignResult` (numbers and text,
no files): :func:`design_answer` (the best design and the runner-up: every varied key,
the shape's derived length (the tube's plate spacing h = stroke + ball diameter, the
shell's stroke = cavity - ball diameter), the sizes that followed, σ, the load, the
band table), :func:`chosen_band_point` (the band point best.toml runs at),
:func:`design_warnings` (one line each) and :func:`answer_lines` (the terminal's text).
"""
from __future__ import annotations

import math

import numpy as np

from .candidate import followed_geometry
from .spec import BENCH_MAX_LOAD_OHM, LOG_KEYS, OBJECTIVES, OTHER_VARY, periodic
from ..scene.schema import SURFACE_CHARGE_KEY, stated_surface_charge

#: a varied value within this fraction of its range from an end is "on the bound"
BOUND_FRACTION = 0.02
#: SI unit -> (label, factor) choices for readable numbers (value x factor)
_PREFIXED = {
    "W": [("pW", 1e12), ("nW", 1e9), ("µW", 1e6), ("mW", 1e3), ("W", 1.0)],
    "W/m^3": [("nW/cm^3", 1e3), ("µW/cm^3", 1.0), ("mW/cm^3", 1e-3), ("W/cm^3", 1e-6)],
    "C": [("pC", 1e12), ("nC", 1e9), ("µC", 1e6), ("C", 1.0)],
    "V": [("mV", 1e3), ("V", 1.0), ("kV", 1e-3)],
    "A": [("pA", 1e12), ("nA", 1e9), ("µA", 1e6), ("mA", 1e3), ("A", 1.0)],
    "m": [("mm", 1e3)],
}


def readable_unit(unit: str, magnitude: float) -> tuple[str, float]:
    """(label, factor) of ``unit`` for numbers around ``magnitude`` (SI): the largest
    prefix that keeps ``magnitude x factor`` >= 1 (µW, mW/cm^3, nC...: the quantity
    table's style, µ and ^)."""
    choices = _PREFIXED.get(unit, [(unit, 1.0)])
    m = abs(float(magnitude)) if magnitude is not None and np.isfinite(magnitude) else 0.0
    if m == 0.0:
        return choices[min(2, len(choices) - 1)] if unit == "W" else choices[0]
    fit = [c for c in choices if m * c[1] >= 1.0]
    return fit[-1] if fit else choices[0]


def point_label(f: float, a: float, kind: str = "sine") -> str:
    """``25 Hz / 0.3 mm`` (a random or harmonics excitation: ``33 Hz (random)``)."""
    return f"{f:g} Hz / {a * 1e3:g} mm" if periodic(kind) else f"{f:g} Hz ({kind})"


def _kind(result) -> str:
    return result.scene.excitation.kind


def band_points(result, row) -> list[dict]:
    """[{frequency_hz, amplitude_mm, regime, value, spread}] of ``row`` (the first
    objective, SI; ``spread``: its standard deviation over windows, 0 if regular)."""
    obj = result.spec.objective
    values = row["band_values"].get(obj, [math.nan] * len(result.spec.band))
    spreads = row.get("band_spread", {}).get(obj, [0.0] * len(values))
    regimes = row["regimes"] or [""] * len(values)
    out = []
    for (f, a), regime, v, s in zip(result.spec.band, regimes, values, spreads):
        out.append({"frequency_hz": f,
                    "amplitude_mm": a * 1e3 if periodic(_kind(result)) else None,
                    "regime": regime, "value": v, "spread": s})
    return out


def chosen_band_point(result, row) -> int:
    """Index of the band point best.toml runs at: among the points where ``row`` scored a
    non-zero value, the one nearest the band's centre (frequency and amplitude each
    relative to its span); among equally near ones a regular (not chaotic) one, then the
    larger value. None non-zero: the largest."""
    band = result.spec.band
    values = row["band_values"][result.spec.objective]
    live = [i for i, v in enumerate(values) if np.isfinite(v) and v != 0]
    if not live:
        return int(np.nanargmax(values)) if np.isfinite(values).any() else 0
    f = np.array([p[0] for p in band])
    a = np.array([p[1] for p in band])

    def rel(x, i):
        span = x.max() - x.min()
        return 0.0 if span == 0 else (x[i] - 0.5 * (x.max() + x.min())) / span

    regimes = row["regimes"] or [""] * len(values)
    return min(live, key=lambda i: (round(math.hypot(rel(f, i), rel(a, i)), 12),
                                    regimes[i] in ("chaos", "not-settled"), -values[i], i))


def on_bounds(result, row) -> list[tuple[str, str, float]]:
    """[(key, "lower" | "upper", bound)] of the varied keys ``row`` sits on (within
    BOUND_FRACTION of the range, or the search's resolution, of its end)."""
    spec = result.spec
    tol = max(spec.resolution, BOUND_FRACTION)
    out = []
    for key, (lo, hi) in spec.vary.items():
        v = row["values"][key]
        if key in LOG_KEYS:
            u = (math.log10(v) - math.log10(lo)) / (math.log10(hi) - math.log10(lo))
        else:
            u = (v - lo) / (hi - lo)
        if u <= tol:
            out.append((key, "lower", lo))
        elif u >= 1 - tol:
            out.append((key, "upper", hi))
    return out


def _load(result, row) -> dict:
    spec = result.spec
    if spec.objective == "harvested_power":
        return {"rule": "the [circuit] rectifier and store", "ohm": None}
    if row["load_ohm"] is None:
        return {"rule": "none (the ball rests at every band point: no power at any load)"
                if row.get("at_rest") else "none (the objective needs no load)", "ohm": None}
    if "load_ohm" in spec.vary:
        return {"rule": "varied", "ohm": row["load_ohm"]}
    if isinstance(row["load_ohm"], list):
        return {"rule": "matched at each band point", "ohm": row["load_ohm"]}
    return {"rule": f"matched, one resistor for the band ({spec.aggregate})",
            "ohm": row["load_ohm"]}


def derived_length(result, device: dict) -> dict:
    """The length the answer states beside the varied keys, by the shape's rule
    (``scene/shapes/``): the tube's plate spacing h = stroke + ball diameter, the
    shell's stroke = cavity - ball diameter -> {"key", "words", "value_mm"}."""
    from ..scene.shapes import shape_of

    rules = shape_of(result.scene.device.shape)
    key, words = rules.derived
    return {"key": key, "words": words,
            "value_mm": float(f"{rules.derived_mm(device):.12g}")}


def describe(result, row) -> dict:
    """One design, stated: varied keys, the shape's derived length (the tube's plate
    spacing, the shell's stroke), what followed, σ, load, band table."""
    base = result.scene.to_dict()["device"]
    device_values = {k: v for k, v in row["values"].items() if k not in OTHER_VARY}
    followed = followed_geometry(base, device_values) if result.spec.geometry == "follow" \
        else {}
    derived = derived_length(result, {**base, **device_values, **followed})
    obj = result.spec.objective
    sigma = row.get(SURFACE_CHARGE_KEY, math.nan)
    if not (isinstance(sigma, float) and math.isfinite(sigma)):
        sigma = base.get(SURFACE_CHARGE_KEY)
    error = row["objective_error"]
    dyn = row.get("dynamics_error", {}).get(obj, 0.0)
    pct = row["objectives"].get(obj, {}).get("percentile_error", 0.0)
    return {
        "index": row["index"], "values": dict(row["values"]),
        derived["key"]: derived["value_mm"], "derived_length": derived,
        "changed": {k: {"from": base[k], "to": v} for k, v in followed.items()
                    if v != base[k]},
        SURFACE_CHARGE_KEY: sigma,
        "breakdown": stated_surface_charge(result.scene) == "breakdown",
        # [charge] model = "contact": each band point's steady charge, its rise time
        "charge": row.get("charge"),
        "load": _load(result, row),
        "objective": row["objective"], "objective_error": error,
        "field_error": error - dyn - pct, "dynamics_error": dyn,
        "band_points": band_points(result, row),
        **({"robust": robust_statement(result, row)} if "robust" in row else {}),
    }


def robust_statement(result, row) -> dict:
    """A percentile aggregate stated: the percentile, the study's sample count and
    evaluations, the value at the nominal inputs, the percentile's sampling error and
    the percentile at each band point."""
    spec, obj = result.spec, result.spec.objective
    u = spec.uncertainty
    got = row["objectives"][obj]
    return {"percentile": spec.percentile, "samples": u.samples, "method": u.method,
            "evaluations_per_band_point": u.evaluations,
            "evaluations": row.get("uncertainty_evaluations"), "inputs": list(u.keys),
            "nominal": got.get("nominal"), "percentile_error": got.get("percentile_error"),
            "band_percentiles": row["robust"]["objectives"][obj]["band_percentiles"]}


def runner_up(result) -> dict | None:
    """The second-ranked design (None with fewer than two) and whether it lies within
    the error bars of the best."""
    if len(result.ranking) < 2:
        return None
    best, second = result.rows[result.ranking[0]], result.rows[result.ranking[1]]
    within = best["objective"] - second["objective"] <= (best["objective_error"]
                                                         + second["objective_error"])
    return {**describe(result, second), "within_error_bars": bool(within)}


def design_warnings(result) -> list[str]:
    """What the user must know, one line each (the text after ``tengfield: warning:``)."""
    spec, out = result.spec, []
    kind = _kind(result)
    moved = [r for r in result.rows if r["regimes"]]
    for i, (f, a) in enumerate(spec.band):
        if moved and all(r["regimes"][i] == "rest" for r in moved):
            gamma = a * (2 * math.pi * f) ** 2 / 9.80665
            out.append(f"{point_label(f, a, kind)}: no candidate moves (the ball rests on the "
                       f"lower electrode in all {len(moved)}" + (f"; Γ = Aω²/g = {gamma:.2f} < 1"
                                                             if periodic(kind) and gamma < 1
                                                             else "")
                       + "): it scores 0 for every design; raise the amplitude or drop it "
                       "from [design.excitation]")
    best = result.best
    if best is None:
        return out
    unit = OBJECTIVES[spec.objective][0]
    for key, side, bound in on_bounds(result, best):
        out.append(f"the best {key} = {best['values'][key]:g} is on the {side} bound of its "
                   f"range [design.vary] {key} = [{spec.vary[key][0]:g}, {spec.vary[key][1]:g}]"
                   f": the optimum may lie beyond it; widen the range")
    ok = [result.rows[i]["objective"] for i in result.ranking]
    if len(ok) > 1 and max(ok) == min(ok):
        out.append(f"aggregate = {spec.aggregate!r} ties: all {len(ok)} candidates score "
                   f"{spec.objective} = {ok[0]:.4g} {unit}, so no design is better than "
                   "another" + ("; a band point where every design scores 0 decides the "
                                "minimum: use aggregate = 'mean' or drop that point"
                                if ok[0] == 0 and spec.aggregate == "min" else ""))
    loads = best["load_ohm"] if isinstance(best["load_ohm"], list) else [best["load_ohm"]]
    high = max((r for r in loads if r is not None), default=0.0)
    if high > BENCH_MAX_LOAD_OHM and spec.load_range is None and "load_ohm" not in spec.vary:
        out.append(f"the best design's matched load {_ohm(high)} is past what a bench builds "
                   f"and reads (resistors and meter inputs reach ~{_ohm(BENCH_MAX_LOAD_OHM)}): "
                   "set [design] load_ohm = [1e6, 1e9] to match within loads a bench can build")
    for name, said in (("chaos", "chaotic (aperiodic over the settling check's longest "
                                 "run)"),
                       ("not-settled", "not settled (aperiodic, no repeating motion within "
                                       "the settling check's bound)")):
        chaotic = [i for i, r in enumerate(best["regimes"]) if r == name]
        if chaotic:
            pts = band_points(result, best)
            names = ", ".join(f"{point_label(*spec.band[i], kind)} "
                              f"(±{_pct(pts[i]['spread'], pts[i]['value'])} over windows)"
                              for i in chaotic)
            out.append(f"the best design is {said} at {len(chaotic)} of {len(spec.band)} "
                       f"band point(s): {names}; its ± includes that spread")
    return out


def _pct(spread, value) -> str:
    return f"{100 * spread / abs(value):.2g} %" if value else f"{spread:.3g}"


def design_answer(result) -> dict:
    """design.json's answer: ``best`` and ``runner_up`` (:func:`describe`), the band point
    best.toml runs at, the warnings."""
    if result.best is None:
        return {"best": None, "runner_up": None, "warnings": design_warnings(result)}
    k = chosen_band_point(result, result.best)
    f, a = result.spec.band[k]
    return {"best": describe(result, result.best), "runner_up": runner_up(result),
            "best_toml_band_point": {"index": k, "frequency_hz": f,
                                     "amplitude_mm": a * 1e3 if periodic(_kind(result))
                                     else None,
                                     "value": result.best["band_values"][
                                         result.spec.objective][k]},
            "warnings": design_warnings(result)}


def _fmt(value, unit) -> str:
    label, factor = readable_unit(unit, value)
    return f"{value * factor:.4g} {label}"


def _design_lines(result, d: dict, title: str) -> list[str]:
    spec = result.spec
    unit = OBJECTIVES[spec.objective][0]
    label, factor = readable_unit(unit, d["objective"])
    n = len(spec.band)
    lines = [f"{title}: " + ", ".join(f"{k} = {v:g}" for k, v in d["values"].items())
             + f"  ->  {d['derived_length']['words']} = {d['derived_length']['value_mm']:g} mm",
             f"  {spec.objective} = {d['objective'] * factor:.4g} ± "
             f"{d['objective_error'] * factor:.2g} {label} ({aggregate_words(spec)} {n} band "
             f"point{'s' * (n != 1)}; ± = field/surrogate {d['field_error'] * factor:.2g}"
             f" + dynamics {d['dynamics_error'] * factor:.2g}"
             + (f" + percentile {d['robust']['percentile_error'] * factor:.2g}"
                if "robust" in d else "") + ")"]
    if "robust" in d:
        r = d["robust"]
        lines.append(f"  = the {r['percentile']:g}th percentile over [uncertainty.vary] "
                     f"({', '.join(r['inputs'])}; {r['method']}, N = {r['samples']}: "
                     f"{r['evaluations_per_band_point']} evaluations per band point), the "
                     f"band's mean; ± includes its sampling error "
                     f"{r['percentile_error'] * factor:.2g}; at the nominal inputs "
                     f"{r['nominal'] * factor:.4g} {label}")
    if d["changed"]:
        lines.append("  changed to follow: " + ", ".join(
            f"{k} {c['from']:g} -> {c['to']:g}" for k, c in d["changed"].items()))
    sigma = d[SURFACE_CHARGE_KEY]
    charge = d.get("charge")
    if charge:
        rise = [r for r in charge["rise_time_90_s"] if r is not None]
        lines.append(f"  σ = {sigma:.4g} µC/m^2 (the steady charge its contacts make, "
                     + ("the band's mean" if len(charge["steady_uC_per_m2"]) > 1 else
                        "at the band point")
                     + (f"; 90 % of it after {max(rise):.3g} s" if rise else "") + ")")
    else:
        lines.append(f"  σ = {sigma:.4g} µC/m^2" + (
            " (the air-breakdown limit of this geometry)" if d["breakdown"] else
            " (the scene's)"))
    load = d["load"]
    if load["ohm"] is not None:
        ohms = load["ohm"] if isinstance(load["ohm"], list) else [load["ohm"]]
        lines.append(f"  load: {load['rule']}: " + ", ".join(_ohm(r) for r in ohms))
    else:
        lines.append(f"  load: {load['rule']}")
    return lines


def aggregate_words(spec) -> str:
    """How the band was aggregated, in words ("mean over", "p10 over [uncertainty.vary],
    mean over"), followed by the band's point count."""
    if spec.percentile is not None:
        return f"{spec.aggregate} over [uncertainty.vary], mean over"
    return f"{spec.aggregate} over"


def _ohm(r: float) -> str:
    for label, f in (("GΩ", 1e9), ("MΩ", 1e6), ("kΩ", 1e3)):
        if r >= f:
            return f"{r / f:.3g} {label}"
    return f"{r:.3g} Ω"


def band_table_lines(result, row) -> list[str]:
    """The band table: frequency, amplitude, regime, value (± its spread over windows)."""
    unit = OBJECTIVES[result.spec.objective][0]
    pts = band_points(result, row)
    label, factor = readable_unit(unit, max((abs(p["value"]) for p in pts
                                             if np.isfinite(p["value"])), default=0.0))
    robust = row.get("robust", {}).get("objectives", {}).get(result.spec.objective)
    tag = f"   {result.spec.aggregate} [{label}]" if robust else ""
    lines = [f"  {'frequency':>10} {'amplitude':>10}  {'regime':<16} {result.spec.objective} "
             f"[{label}]" + (" (nominal)" if robust else "") + tag]
    for i, p in enumerate(pts):
        amp = f"{p['amplitude_mm']:g} mm" if p["amplitude_mm"] is not None \
            else result.scene.excitation.kind
        spread = f" ± {p['spread'] * factor:.2g} (windows)" if p["spread"] else ""
        lines.append(f"  {p['frequency_hz']:>7g} Hz {amp:>10}  {p['regime']:<16} "
                     f"{p['value'] * factor:.4g}{spread}"
                     + (f"   {robust['band_percentiles'][i] * factor:.4g}" if robust else ""))
    return lines


def answer_lines(result) -> list[str]:
    """The terminal's answer (stdout): the best design, its band table, the runner-up."""
    answer = design_answer(result)
    if answer["best"] is None:
        return ["no candidate is feasible: see design.csv (reason)"]
    lines = _design_lines(result, answer["best"], "best")
    lines += band_table_lines(result, result.best)
    point = answer["best_toml_band_point"]
    lines.append("  best.toml runs at " + point_label(
        point["frequency_hz"], result.spec.band[point["index"]][1], _kind(result))
        + f" ({result.spec.objective} = {_fmt(point['value'], OBJECTIVES[result.spec.objective][0])} there)")
    second = answer["runner_up"]
    if second is not None:
        conf = result.confidence()
        verdict = "within the error bars of the best" if second["within_error_bars"] \
            else "outside the error bars"
        lines += _design_lines(result, second, f"runner-up #{second['index']} ({verdict})")
        ratio = conf.get("margin_over_error_bars")
        if ratio is not None and math.isinf(ratio):   # both bars 0 (design.json: null)
            unit = OBJECTIVES[result.spec.objective][0]
            lines.append(f"  margin {_fmt(conf['margin'], unit)}; the error bars are 0 (no "
                         "field, surrogate or dynamics error enters this objective), so the "
                         "best leads by the margin alone")
        elif ratio is not None:
            unit = OBJECTIVES[result.spec.objective][0]
            lines.append(f"  margin {_fmt(conf['margin'], unit)} = "
                         f"{conf['margin_over_error_bars']:.3g} x the error bars; "
                         f"{conf['candidates_within_error_bars']} candidate(s) within the "
                         "error bars of the best")
    return lines



#: how each objective scales with σ (issue #38: its band costs no solve); a rectifier's
#: harvested power is not a power of σ (its diodes) and has no band here
SIGMA_POWER = {"charge": 1, "voltage": 1, "current": 1, "power": 2, "power_density": 2,
               "stroke": 0}


def best_breakdown_band(result, *, cache_dir=None) -> dict | None:
    """With ``σ = "breakdown"``: the best design's objective
    at the edges of its breakdown band (docs/breakdown.md), ``{"lower", "estimate",
    "upper"}`` aggregated over the band points like the objective, and the σ edges of
    each band point [µC/m²] (its own trajectory). None when not asked for (another σ,
    no feasible design, a percentile aggregate, an objective not a power of σ). Reads
    the best geometry's surrogate from ``cache_dir`` (the design's) and reruns its
    dynamics at each band point (seconds)."""
    from ..air_breakdown import obtain_breakdown_table, scene_band, scene_breakdown
    from .candidate import aggregate_values, band_scene, candidate_scene

    best, spec = result.best, result.spec
    objective = spec.objective
    if best is None or not describe(result, best)["breakdown"] or \
            spec.percentile is not None or objective not in SIGMA_POWER:
        return None
    scene = candidate_scene(result.scene, spec, best["values"])
    table, _ = obtain_breakdown_table(scene, cache_dir=cache_dir)
    limit = scene_breakdown(scene, table)
    power = SIGMA_POWER[objective]
    at = {"lower": [], "estimate": [], "upper": []}
    edges = []
    for k, (f, a) in enumerate(spec.band):
        band = scene_band(band_scene(scene, spec, f, a), limit)
        edges.append({e: s * 1e6 for e, s in band.edges().items()})
        for edge, sigma in band.edges().items():
            at[edge].append(best["band_values"][objective][k] * (sigma / limit.sigma_max) ** power)
    out = {edge: float(aggregate_values(values, spec.band_aggregate))
           for edge, values in at.items()}
    return {**out, "sigma_edges_uC_per_m2": edges, "sigma_max_uC_per_m2": limit.sigma_max * 1e6,
            "rule": f"the objective scales with sigma^{power}: its value at -sigma_max times "
                    "(edge / sigma_max)^power at each band point, aggregated as the objective"}


def breakdown_band_lines(result, band: dict | None) -> list[str]:
    """The terminal's line for :func:`best_breakdown_band`."""
    if band is None:
        return []
    unit = OBJECTIVES[result.spec.objective][0]
    return [f"  {result.spec.objective} over the breakdown band (lower / estimate / upper): "
            + " / ".join(_fmt(band[e], unit) for e in ("lower", "estimate", "upper"))
            + f" (sigma_max {band['sigma_max_uC_per_m2']:.4g} uC/m^2; docs/breakdown.md)"]
