"""The error-against-run-time figures of ``tengfield report`` (one PNG per stage)."""
from __future__ import annotations

import math
from pathlib import Path

from . import new_figure, save_figure
from ..scene.shapes.methods import FIELD_METHODS


def plot_stage(path: Path, rows: list, stage: str, title: str, targets=(1e-2, 1e-3), *,
               ylabel: str = "relative error") -> Path:
    """``<stage>.png``: :func:`stage_figure` saved to ``path``."""
    return Path(save_figure(stage_figure(rows, stage, title, targets, ylabel=ylabel), path,
                            dpi=100))


def stage_figure(rows: list, stage: str, title: str, targets=(1e-2, 1e-3), *,
                 ylabel: str = "relative error"):
    """Log-log error against wall time for one stage of ``tengfield report`` (``rows``:
    :class:`tengfield.accuracy_report.plan.Row`; one marker series per group), titled ``title``,
    the y axis ``ylabel`` (the report names the errors' quantities); a matplotlib Figure."""
    fig = new_figure((6.4, 4.2), dpi=100)
    ax = fig.subplots()
    groups: dict[str, list] = {}
    for row in rows:
        groups.setdefault(_group(row), []).append(row)
    markers = "osD^v<>ph*"
    for i, (name, members) in enumerate(groups.items()):
        pts = []
        for r in members:
            err = r.error if math.isfinite(r.error) else r.error_position
            if math.isfinite(err) and r.wall_time_s > 0:
                pts.append((r.wall_time_s, max(err, 1e-12)))
        if not pts:
            continue
        pts.sort()
        xs, ys = zip(*pts)
        ax.loglog(xs, ys, marker=markers[i % len(markers)], linestyle="-" if len(pts) > 1 else "",
                  label=name)
    for t in targets:
        ax.axhline(t, color="0.6", lw=0.8, ls="--")
        ax.text(ax.get_xlim()[0] if ax.lines else 1, t, f" {t:g}", va="bottom", fontsize=7,
                color="0.4")
    ax.set_xlabel("wall time [s]")
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="best")
    fig.tight_layout()
    return fig


def _group(row) -> str:
    k = row.knobs
    if row.stage == "field":
        if k.get("method") in FIELD_METHODS and FIELD_METHODS[k["method"]].dimension == 3:
            return "3D (C, q at mid-stroke)"
        if k.get("far_field") != "kelvin":
            return f"{k.get('far_field')} far field"
        return f"axisymmetric p{k.get('degree')}"
    if row.stage == "dynamics":
        return "impact map: sampling" if k.get("model") == "impact" else "soft contact vs impact map"
    if row.stage == "circuit":
        return f"R = {k.get('load_ohm'):.0e} ohm"
    return row.stage
