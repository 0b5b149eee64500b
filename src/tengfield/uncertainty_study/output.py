"""uncertainty.csv, uncertainty.json and uncertainty.png of a study, and the lines
``tengfield uncertainty`` prints (every file through :mod:`tengfield.files`)."""
from __future__ import annotations

from pathlib import Path

from ..files import write_figure, write_json, write_rows
from .._json import jsonable
from .statistics import dominant_input
from ..files import figure_file


def csv_rows(study) -> tuple[list[str], list[list]]:
    """``(header, rows)`` of uncertainty.csv: per evaluation its index, the sampled
    inputs (file units), the regime and every output (empty where it has none)."""
    keys = study.spec.keys
    outputs = study.output_keys
    header = ["evaluation", *keys, "regime", *outputs]
    rows = []
    for i, (values, out, regime) in enumerate(zip(study.values, study.evaluations.rows,
                                                  study.evaluations.regimes)):
        rows.append([i, *(repr(float(v)) for v in values), regime,
                     *("" if out.get(k) is None else repr(float(out[k])) for k in outputs)])
    return header, rows


def write_outputs(study, out, *, plots: bool = True) -> list[Path]:
    """The study's files in directory ``out``."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    header, rows = csv_rows(study)
    written = [write_rows(out / "uncertainty.csv", header, rows),
               write_json(out / "uncertainty.json", jsonable(study.summary))]
    if plots:
        from ..plotting import save_figure
        written.append(write_figure(save_figure, study.plot(), dpi=110,  # a notebook's figure
                                    path=out / figure_file("uncertainty")))
    return written


def summary_lines(study) -> list[str]:
    """Per main output: the nominal value, the median and the 90 % interval (5-95 %), and
    the input that dominates it (largest total Sobol index)."""
    from ..plotting.uncertainty import display_unit

    s = study.summary
    lines = [f"{s['evaluations']} evaluations ({s['method']}, N = {s['samples']}, seed "
             f"{s['seed']}): {s['dynamics_runs']} dynamics runs, {s['field_solves']} field "
             f"solve{'s' * (s['field_solves'] != 1)}"]
    for name in study.main or s["output_keys"][:3]:
        block = s["outputs"][name]
        unit, scale = display_unit(name)
        p = block["percentiles"]
        if not p:
            lines.append(f"  {name}: no values")
            continue
        nominal = block.get("nominal")
        text = (f"  {output_label(name, unit)}: nominal "
                f"{'-' if nominal is None else f'{nominal * scale:.4g}'}, "
                f"median {p['50'] * scale:.4g}, 90 % in [{p['5'] * scale:.4g}, "
                f"{p['95'] * scale:.4g}]")
        side = _outside(study, name, nominal)
        if side:
            text += f" (the nominal lies outside every draw: {side[0]} them)"
        top = dominant_input(block.get("sobol"))
        if top is not None:
            text += f"; dominated by {top[0]} (ST = {top[1]:.2f})"
        lines.append(text)
    regimes = ", ".join(f"{k} {v['fraction']:.0%}" for k, v in s["regimes"].items())
    lines.append(f"  regimes: {regimes}")
    return lines


def output_label(name: str, unit: str = "") -> str:
    """``"peak_to_peak.I_sc_A"`` as the terminal says it: ``"I_SC peak-to-peak [µA]"``
    (the quantity table's symbol and the unit shown; the SI key only for a name the
    table does not hold)."""
    from ..quantities import QUANTITIES

    from ..quantities import CHARGE_LABELS

    if name in CHARGE_LABELS:
        return CHARGE_LABELS[name]
    stat, _, base = name.rpartition(".")
    q = QUANTITIES.get(base)
    if q is None:
        return name + (f" [{unit}]" if unit else "")
    words = {"peak_to_peak": " peak-to-peak", "peak": " peak"}.get(stat, "")
    return f"{q.symbol}{words}" + (f" [{unit}]" if unit else "")


def _draws(study, name) -> list[float]:
    return [float(r[name]) for r in study.evaluations.rows
            if r.get(name) is not None and r[name] == r[name]]


def _outside(study, name, nominal) -> tuple[str, int] | None:
    """("below" | "above", draws) when the nominal value lies outside every draw."""
    if nominal is None:
        return None
    draws = _draws(study, name)
    if not draws:
        return None
    if nominal < min(draws):
        return "below", len(draws)
    if nominal > max(draws):
        return "above", len(draws)
    return None


def nominal_outside_warnings(study) -> list[str]:
    """One warning line per main output whose nominal value lies outside every draw (the
    scene's own values are not inside the varied ranges, or the output is not monotone
    where they are)."""
    from ..plotting.uncertainty import display_unit

    s = study.summary
    out = []
    for name in study.main or s["output_keys"][:3]:
        nominal = s["outputs"][name].get("nominal")
        side = _outside(study, name, nominal)
        if side:
            unit, scale = display_unit(name)
            draws = _draws(study, name)
            edge = min(draws) if side[0] == "below" else max(draws)
            out.append(f"uncertainty: {output_label(name)} of the nominal scene, "
                       f"{nominal * scale:.4g} {unit}, lies {side[0]} every one of the "
                       f"{side[1]} draws ({'lowest' if side[0] == 'below' else 'highest'} "
                       f"{edge * scale:.4g} {unit}): the scene's own values are outside the "
                       "[uncertainty.vary] ranges, or the output is not monotone in them")
    return out
