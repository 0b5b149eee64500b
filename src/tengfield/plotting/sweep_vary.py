"""sweep_<key>.png: a ``--vary`` sweep's outputs against one varied scene key."""
from __future__ import annotations

import math

from . import new_figure

#: most lines one panel draws (one per setting of the other axes); past it, the first ones
MAX_LINES = 8


def _number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _text(value) -> str:
    return f"{value:g}" if _number(value) else str(value)


def _legend_name(key: str) -> str:
    """A legend's name of a varied key or an axis: its label without the unit."""
    from .design import key_label

    name = key.rpartition(".")[2]
    words = {"frequency_hz": "f [Hz]", "amplitude_mm": "A [mm]"}.get(name) or key_label(name)
    return words


def vary_figure(result, key: str):
    """Peak-to-peak V_OC, Q_SC, I_SC (and, with loads, the mean power) against the values
    of the varied scene key ``key`` (its label and unit as design.png names them), one line
    per setting of the other varied keys, frequency, amplitude and load (at most
    :data:`MAX_LINES`, said in the title when more)."""
    from ..quantities import QUANTITIES, TERMINAL, axis_label, column_name
    from .design import key_label

    rows = list(result)
    others = [k for k in result.vary if k != key] + ["frequency_hz", "amplitude_mm", "load_ohm"]
    groups: dict[tuple, list] = {}
    for row in rows:
        groups.setdefault(tuple(row.get(k) for k in others), []).append(row)
    varying = [k for i, k in enumerate(others) if len({g[i] for g in groups}) > 1]
    loads = any(row.get("load_ohm") is not None for row in rows)
    panels = [(column_name(n, "peak_to_peak"), axis_label(n, statistic="peak_to_peak"),
               QUANTITIES[n].display_scale) for n in TERMINAL]
    if loads:
        panels.append(("P_mean_W", "mean power P [µW]", 1e6))
    values = []
    for row in rows:
        if row[key] not in values:
            values.append(row[key])
    numeric = all(_number(v) for v in values)
    position = {v: (float(v) if numeric else i) for i, v in enumerate(values)}
    fig = new_figure((4 * len(panels), 3.6))
    axes = fig.subplots(1, len(panels))
    shown = list(groups.items())[:MAX_LINES]
    section, _, name = key.rpartition(".")
    for ax, (column, label, factor) in zip(axes, panels):
        for setting, members in shown:
            pts = sorted((position[r[key]], r[column]) for r in members
                         if r.get(column) is not None and math.isfinite(r[column]))
            words = ", ".join(f"{_legend_name(k)} = {_text(v)}"
                              for k, v in zip(others, setting) if k in varying)
            ax.plot([p[0] for p in pts], [p[1] * factor for p in pts], "o-", ms=3,
                    label=words or None)
        ax.set_xlabel(f"[{section}] {key_label(name)}")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
        if not numeric:
            ax.set_xticks(range(len(values)), [_text(v) for v in values])
    if varying and len(shown) > 1:
        axes[0].legend(fontsize=7)
    more = f" (first {MAX_LINES} of {len(groups)} settings)" if len(groups) > MAX_LINES else ""
    fig.suptitle(f"sweep over {key_label(name)}{more}", fontsize=10)
    fig.tight_layout()
    return fig
