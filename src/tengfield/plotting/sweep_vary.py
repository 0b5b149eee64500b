"""sweep_<key>.png: a ``--vary`` sweep's outputs against one varied scene key."""
from __future__ import annotations

import math

from . import new_figure

#: past this many lines in a panel (one per setting of the other axes) their colours run
#: along a colour map (the default cycle repeats after 10)
CYCLE_LINES = 10


def _number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _text(value) -> str:
    return f"{value:.4g}" if _number(value) else str(value)


def _legend_text(key: str, value) -> str:
    """``ball diameter d = 6 mm`` (a varied key or an axis at one value)."""
    from .design import key_label

    name = key.rpartition(".")[2]
    label = {"frequency_hz": "f [Hz]", "amplitude_mm": "A [mm]"}.get(name) or key_label(name)
    if label.endswith("]") and " [" in label:
        words, unit = label[:-1].rsplit(" [", 1)
        return f"{words} = {_text(value)} {unit}"
    return f"{label} = {_text(value)}"


def _groups(rows, others) -> dict[tuple, list]:
    groups: dict[tuple, list] = {}
    for row in rows:
        groups.setdefault(tuple(row.get(k) for k in others), []).append(row)
    return groups


def vary_figure(result, key: str):
    """Peak-to-peak V_OC, Q_SC, I_SC (at the first load; they do not depend on it),
    the steady ball charge where the contacts make it, and, with loads, the mean power
    against the values of the varied scene key ``key`` (its
    label and unit as design.png names them), one line per setting of the other varied
    keys, frequency, amplitude (and load, in the power panel): every setting drawn
    (past :data:`CYCLE_LINES` in colours along a map)."""
    from ..quantities import QUANTITIES, TERMINAL, axis_label, column_name
    from matplotlib import cm

    from .design import key_label

    rows = list(result)
    # no --load-ohm axis: a row's load is its point's own circuit's (a varied key), no axis
    own = getattr(result, "loads", None) == ()
    loads = [] if own else sorted({r["load_ohm"] for r in rows if r.get("load_ohm") is not None})
    others = [k for k in result.vary if k != key] + ["frequency_hz", "amplitude_mm"]
    first = rows if own else [r for r in rows
                              if r.get("load_ohm") == (loads[0] if loads else None)]
    panels = [(column_name(n, "peak_to_peak"), axis_label(n, statistic="peak_to_peak"),
               QUANTITIES[n].display_scale, _groups(first, others), others) for n in TERMINAL]
    if loads or (own and any(r.get("P_mean_W") is not None for r in rows)):
        with_load = others + ([] if own else ["load_ohm"])
        panels.append(("P_mean_W", "mean power P [µW]", 1e6, _groups(rows, with_load),
                       with_load))
    if any(r.get("sigma_steady_uC_per_m2") is not None for r in first):
        # [charge] model = "contact": the steady charge the contacts make at each setting
        panels.append(("sigma_steady_uC_per_m2", "steady ball charge σ [µC/m²]", 1.0,
                       _groups(first, others), others))
    values = []
    for row in rows:
        if row[key] not in values:
            values.append(row[key])
    numeric = all(_number(v) for v in values)
    position = {v: (float(v) if numeric else i) for i, v in enumerate(values)}
    fig = new_figure((4 * len(panels) + 1.5, 3.6), layout="constrained")
    axes = fig.subplots(1, len(panels))
    decades = numeric and all(float(v) > 0 for v in values) and len(values) > 2 \
        and max(float(v) for v in values) >= 100 * min(float(v) for v in values)
    shared = None      # the legend every terminal panel shares: once, beside the figure
    section, _, name = key.rpartition(".")
    for ax, (column, label, factor, groups, names) in zip(axes, panels):
        varying = [k for i, k in enumerate(names) if len({g[i] for g in groups}) > 1]
        colours = (None if len(groups) <= CYCLE_LINES else
                   [cm.viridis(i / (len(groups) - 1)) for i in range(len(groups))])
        for n, (setting, members) in enumerate(groups.items()):
            pts = sorted((position[r[key]], r[column]) for r in members
                         if r.get(column) is not None and math.isfinite(r[column]))
            words = ", ".join(_legend_text(k, v) for k, v in zip(names, setting)
                              if k in varying)
            ax.plot([p[0] for p in pts], [p[1] * factor for p in pts], "o-", ms=3,
                    label=words or None, color=None if colours is None else colours[n])
        if decades:        # a key spanning decades (a load R): a log axis
            ax.set_xscale("log")
        ax.set_xlabel(f"[{section}] {key_label(name)}")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
        if not numeric:
            ax.set_xticks(range(len(values)), [_text(v) for v in values])
        if varying and len(groups) > 1:
            labels = ax.get_legend_handles_labels()
            if shared is None:
                shared = labels
            elif labels[1] != shared[1]:      # the power panel's loads: its own legend
                ax.legend(fontsize=7, ncol=1 if len(groups) <= CYCLE_LINES else 2)
    if shared is not None:
        fig.legend(*shared, loc="outside right upper", fontsize=7,
                   ncol=1 if len(shared[1]) <= 2 * CYCLE_LINES else 2)
    at = f", Q_SC/V_OC/I_SC at load R = {_text(loads[0])} Ω" if len(loads) > 1 else ""
    fig.suptitle(f"sweep over {key_label(name)}{at}", fontsize=10)
    return fig
