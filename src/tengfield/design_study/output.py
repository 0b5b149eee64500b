"""design.csv, design.json, best.toml (and design.png through tengfield.plotting.design)."""
from __future__ import annotations

import math
from pathlib import Path

from ..files import (one_line, scene_dir, write_figure, scene_toml, write_json, write_rows,
                     write_text)
from .answer import (aggregate_words, band_table_lines, chosen_band_point, describe,
                     design_answer, on_bounds,
                     point_label, readable_unit)
from .candidate import band_run, followed_geometry
from ..scene.schema import SURFACE_CHARGE_KEY, update_section
from .spec import OBJECTIVES, OTHER_VARY, objective_label, periodic
from ..files import figure_file


def _band_label(f: float, a: float, kind: str = "sine") -> str:
    """``33hz_0.75mm``; a random or harmonics excitation (no band amplitude: the scene's
    excitation as given) ``33hz_random``."""
    return f"{f:g}hz_{a * 1e3:g}mm" if periodic(kind) else f"{f:g}hz_{kind}"


def csv_columns(result) -> list[str]:
    spec = result.spec
    cols = ["index", "phase", *spec.vary, "status"]
    for o in spec.objectives:
        unit = OBJECTIVES[o][0].replace("/", "_per_").replace("^", "")
        cols += [f"{o}_{unit}", f"{o}_error_{unit}"]
    for o in spec.objectives:
        cols += [f"{o}_at_{_band_label(f, a, result.scene.excitation.kind)}"
                 for f, a in spec.band]
    if spec.percentile is not None:   # the percentile aggregate: nominal and per band point
        tag = f"p{spec.percentile:g}"
        for o in spec.objectives:
            unit = OBJECTIVES[o][0].replace("/", "_per_").replace("^", "")
            cols += [f"{o}_nominal_{unit}", f"{o}_percentile_error_{unit}"]
            cols += [f"{o}_{tag}_at_{_band_label(f, a, result.scene.excitation.kind)}"
                     for f, a in spec.band]
        cols.append("uncertainty_evaluations")
    cols += [f"{spec.objective}_spread_per_band_point", "windows",
             "regimes", "upper_contact_fraction", "upper_contacts_per_period",
             *(["load_ohm"] if "load_ohm" not in spec.vary else []),   # varied: a column above
             "device_volume_m3", SURFACE_CHARGE_KEY, "field_relative_error",
             "interpolation_error", "positions",
             "field_status", "field_wall_s", "dynamics_wall_s", "circuit_wall_s", "reason",
             "field_hash"]
    return cols


def _fmt(x) -> str:
    if x is None:
        return ""
    if isinstance(x, float):
        return "" if not math.isfinite(x) else repr(x)
    if isinstance(x, (list, tuple)):
        return ";".join(_fmt(v) for v in x)
    return str(x)


def csv_record(result, row) -> dict:
    spec = result.spec
    rec = {"index": row["index"], "phase": row["phase"], "status": row["status"],
           "reason": row["reason"], **row["values"]}
    for o in spec.objectives:
        unit = OBJECTIVES[o][0].replace("/", "_per_").replace("^", "")
        got = row["objectives"].get(o, {})
        rec[f"{o}_{unit}"] = got.get("value")
        rec[f"{o}_error_{unit}"] = got.get("error")
        for (f, a), v in zip(spec.band, row["band_values"].get(o, [None] * len(spec.band))):
            rec[f"{o}_at_{_band_label(f, a, result.scene.excitation.kind)}"] = v
    if spec.percentile is not None and "robust" in row:
        tag = f"p{spec.percentile:g}"
        for o in spec.objectives:
            unit = OBJECTIVES[o][0].replace("/", "_per_").replace("^", "")
            got = row["objectives"].get(o, {})
            rec[f"{o}_nominal_{unit}"] = got.get("nominal")
            rec[f"{o}_percentile_error_{unit}"] = got.get("percentile_error")
            pts = row["robust"]["objectives"][o]["band_percentiles"]
            for (f, a), v in zip(spec.band, pts):
                rec[f"{o}_{tag}_at_{_band_label(f, a, result.scene.excitation.kind)}"] = v
        rec["uncertainty_evaluations"] = row.get("uncertainty_evaluations")
    rec.update({f"{spec.objective}_spread_per_band_point":
                row.get("band_spread", {}).get(spec.objective, []),
                "windows": row.get("windows", []), "regimes": row["regimes"], "upper_contact_fraction": row["upper_contact_fraction"],
                "upper_contacts_per_period": row["upper_contacts_per_period"],
                "load_ohm": row["load_ohm"], "device_volume_m3": row["device_volume_m3"],
                SURFACE_CHARGE_KEY: row.get(SURFACE_CHARGE_KEY),
                "field_relative_error": row["field_error"],
                "interpolation_error": row["interpolation_error"], "positions": row["positions"],
                "field_status": row["field_status"], "field_wall_s": row["wall_s"]["field"],
                "dynamics_wall_s": row["wall_s"]["dynamics"],
                "circuit_wall_s": row["wall_s"]["circuit"], "field_hash": row["field_hash"]})
    return rec


def write_design_csv(path, result) -> Path:
    cols = csv_columns(result)
    records = (csv_record(result, row) for row in result.rows)
    return write_rows(path, cols, ([_fmt(rec.get(c)) for c in cols] for rec in records))


def cost_split(result) -> dict:
    """Mean wall seconds per evaluated candidate in field, dynamics and circuit."""
    done = [r for r in result.rows if r["status"] != "skipped"]
    n = max(len(done), 1)
    split = {k: sum(r["wall_s"][k] for r in done) / n for k in ("field", "dynamics", "circuit")}
    solved = [r["wall_s"]["field"] for r in done if r["field_status"] in ("computed",
                                                                          "recomputed")]
    split["field_per_new_geometry"] = sum(solved) / len(solved) if solved else 0.0
    split["new_geometries"] = len(solved)
    placed = {"moved": 0, "meshed": 0, "mapped": 0}   # [field] mesh_motion = "move"
    for r in done:
        for key, count in (r.get("mesh_placements") or {}).items():
            placed[key] = placed.get(key, 0) + int(count)
    split["mesh_placements"] = placed
    split["candidates"] = len(done)
    if result.spec.percentile is not None:   # the studies of a percentile aggregate
        robust = [r for r in done if "robust" in r]
        split["uncertainty"] = sum(r["wall_s"].get("uncertainty", 0.0) for r in robust) / n
        split["uncertainty_evaluations"] = sum(r["robust"]["evaluations"] for r in robust)
        split["uncertainty_field_solves"] = sum(r["robust"]["field_solves"] for r in robust)
    return split


def design_summary(result) -> dict:
    spec = result.spec
    best = result.best
    answer = design_answer(result)
    summary = {
        "scene": result.scene.source,
        "objective": spec.objective, "objectives": spec.objectives,
        "unit": OBJECTIVES[spec.objective][0], "aggregate": spec.aggregate,
        "best": None if best is None else {
            **best["values"], "index": best["index"], "objective": best["objective"],
            "objective_error": best["objective_error"],
            "relative_error": best.get("relative_error"),
            "objectives": best["objectives"], "band_values": best["band_values"],
            "regimes": best["regimes"], "upper_contact_fraction": best["upper_contact_fraction"],
            "load_ohm": best["load_ohm"],
            **({"robust": answer["best"]["robust"]} if "robust" in answer["best"] else {}),
            # [charge] model = "contact": each band point's steady charge and rise time
            **({"charge": answer["best"]["charge"]} if answer["best"].get("charge") else {}),
            "followed": followed_geometry(
                result.scene.to_dict()["device"],
                {k: v for k, v in best["values"].items() if k not in OTHER_VARY})
            if spec.geometry == "follow" else {},
            **{k: answer["best"][k] for k in (answer["best"]["derived_length"]["key"],
                                              "derived_length", "changed",
                                              SURFACE_CHARGE_KEY, "breakdown", "load",
                                              "field_error", "dynamics_error", "band_points")},
            "on_bound": [{"key": k, "bound": side, "value": b}
                         for k, side, b in on_bounds(result, best)]},
        "runner_up": answer["runner_up"],
        "best_toml_band_point": answer.get("best_toml_band_point"),
        "best_breakdown_band": result.breakdown_band(),
        "warnings": answer["warnings"],
        "confidence": result.confidence(),
        "error_bar_rule": "objective x factor x (largest field error estimate + surrogate "
                          "interpolation error estimate) of the candidate's surrogate; factor "
                          "3 for powers (P ~ Q_SC^2 / C_T), 2 for voltage (Q_SC / C_T) and "
                          "current (dQ_SC/dz), 1 for charge, 0 for stroke; plus the dynamics: "
                          "a chaotic band point is scored over 3 windows, the standard "
                          "deviation of its value enters the aggregate (mean: sqrt(sum s^2)/n, "
                          "min: the smallest point's)",
        "ranking": [{"index": result.rows[i]["index"], **result.rows[i]["values"],
                     "objective": result.rows[i]["objective"],
                     "objective_error": result.rows[i]["objective_error"]}
                    for i in result.ranking[:50]],
        "pareto": [result.rows[i]["index"] for i in result.pareto()]
        if len(spec.objectives) > 1 else None,
        "counts": {s: sum(r["status"] == s for r in result.rows)
                   for s in ("ok", "infeasible", "skipped")},
        "skipped_reasons": sorted({r["reason"] for r in result.rows if r["status"] == "skipped"}),
        "settings": {**spec.as_dict(), **({} if periodic(result.scene.excitation.kind) else {
            "band": [{"frequency_hz": f, "excitation": result.scene.excitation.kind}
                     for f, _ in spec.band]})},
        "field_settings": ("coarse: degree 2, mesh_size_mm = min(1, 0.2 x ball diameter), "
                           "tolerance 0.02 (17 positions), meshes moved and mapped from each "
                           "candidate's canonical geometry") if spec.field == "coarse"
        else "the scene's [field]",
        "rounds": result.rounds,
        "wall_time_s": result.wall_time, "ranks": result.ranks, "jobs": result.jobs,
        "cost_per_candidate_s": cost_split(result),
    }
    return summary


def best_scene_dict(result) -> dict:
    """The scene (file-level dict, ``[design]`` dropped) with the best candidate's values,
    its followed geometry, (for a power objective) the matched load, (for harvested power)
    the rectifier, the chosen band point as a sine ``[excitation]`` (a random or harmonics
    excitation is kept as given) and the run a band point was scored on (settle + window
    periods) at the band point :func:`~tengfield.design_study.answer.chosen_band_point` names
    (nearest the band's centre among those where the design scored non-zero):
    ``tengfield run`` on it gives the design's value there."""
    best = result.best
    if best is None:
        raise ValueError("no feasible candidate")
    from ..scene.shapes import derived_stroke

    data = {sec: dict(v) for sec, v in result.scene.raw.items() if sec != "design"}
    device = {k: v for k, v in best["values"].items() if k not in OTHER_VARY}
    base_device = result.scene.to_dict()["device"]
    if result.spec.geometry == "follow":
        device.update(followed_geometry(base_device, device))
    # a shell written with stroke_mm: that key at the best's cavity - ball
    device.update(derived_stroke(result.scene.device.shape, data.get("device", {}),
                                 {**base_device, **device}))
    update_section(data, "device", device)   # a varied stroke_mm replaces a written gap_mm
    for key, value in best["values"].items():
        if key in OTHER_VARY:
            data.setdefault(OTHER_VARY[key], {})[key] = value
    k = chosen_band_point(result, best)
    if result.spec.objective == "harvested_power":   # scored through the [circuit] bridge
        data.setdefault("circuit", {})["kind"] = "rectifier"
    elif best["load_ohm"] is not None:   # load = "each": the chosen band point's own load
        load = best["load_ohm"][k] if isinstance(best["load_ohm"], list) else best["load_ohm"]
        data.setdefault("circuit", {}).update({"kind": "load",
                                               "load_ohm": float(f"{float(load):.6g}")})
    f, a = result.spec.band[k]
    if periodic(result.scene.excitation.kind):      # random / harmonics: scored as given
        data.setdefault("excitation", {}).update({"frequency_hz": f, "amplitude_mm": a * 1e3})
    data.setdefault("run", {}).update(band_run(result.spec, f))
    return data


def best_toml_header(result) -> str:
    """best.toml's header: the design's value, the band table, the band point it runs at."""
    best, spec = result.best, result.spec
    objective = spec.objective
    unit = OBJECTIVES[objective][0]
    k = chosen_band_point(result, best)
    f, a = spec.band[k]
    kind = result.scene.excitation.kind
    value = best["band_values"][objective][k]
    n = len(spec.band)
    why = "the band point nearest the band's centre where the design scores non-zero" \
        if value != 0 else "no band point scores non-zero: the largest"
    return (f"best design of `tengfield design` on {one_line(result.scene.source)}\n"
            f"{objective} ({aggregate_words(spec)} {n} band point{'s' * (n != 1)}) = "
            f"{best['objective']:.6g} +- {best['objective_error']:.2g} {unit}\n"
            + ", ".join(f"{k} = {v:g}" for k, v in best["values"].items())
            + " ({words} = {value_mm:g} mm)\n".format(**describe(result, best)["derived_length"])
            + "band table:\n" + "\n".join(band_table_lines(result, best)) + "\n"
            f"excitation and [run]: {point_label(f, a, kind)} ({why}), where the design "
            f"scored {objective} = {value:.6g} {unit}\n[field]: the scene's (the design used "
            + ("coarse settings)" if spec.field == "coarse" else "these)")
            + _contact_note(best, k))


def _contact_note(best, k) -> str:
    """best.toml's line for ``[charge] model = "contact"``: the design scored the plateau
    (the steady charge the contacts make), which a run reaches after its rise time."""
    charge = best.get("charge")
    if not charge:
        return ""
    rise = charge["rise_time_90_s"][k]
    return (f"\n[charge]: scored at the steady charge its contacts make there, "
            f"{charge['steady_uC_per_m2'][k]:.4g} µC/m^2 ("
            + ("reached after ~" + f"{rise:.3g} s of running: set [run] duration_s past it"
               if rise is not None else "never reached") + " to see that value in a run)")


def plot_scales(result) -> dict:
    """objective -> (readable unit, factor) for design.png, from the largest value."""
    out = {}
    for o in result.spec.objectives:
        vals = [abs(r["objectives"][o]["value"]) for r in result.rows if r["status"] == "ok"
                and math.isfinite(r["objectives"][o]["value"])]
        out[o] = readable_unit(OBJECTIVES[o][0], max(vals, default=0.0))
    return out


def plot_options(result) -> dict:
    """The keywords of :func:`tengfield.plotting.design.design_figure` for ``result``
    (units, the objectives' words, readable scales, the bounds the best sits on): design.png
    and :meth:`DesignResult.plot` draw the same figure."""
    best = result.best
    return {"units": {k: v[0] for k, v in OBJECTIVES.items()},
            "names": {k: objective_label(k) for k in OBJECTIVES},
            "scales": plot_scales(result),
            "on_bound": on_bounds(result, best) if best is not None else []}


def write_design_outputs(result, out_dir, *, plots: bool = True) -> list[Path]:
    """design.csv, design.json, best.toml (if a candidate is feasible), design.png."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written = [write_design_csv(out / "design.csv", result),
               write_json(out / "design.json", design_summary(result))]
    best = result.best
    if best is not None:
        write_text(out / "best.toml", scene_toml(best_scene_dict(result),
                                                 best_toml_header(result),
                                                 base_dir=scene_dir(result.scene.source)))
        written.append(out / "best.toml")
    if plots:
        from ..plotting.design import plot_design
        written.append(write_figure(plot_design, result, path=out / figure_file("design"),
                                    **plot_options(result)))
    return written
