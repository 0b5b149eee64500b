"""``tengfield breakdown``'s words and files: what it prints, breakdown.json,
breakdown.csv and breakdown.png (the figure through :mod:`tengfield.plotting`)."""
from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from typing import Any
from pathlib import Path

from .._args import checked_write
from .band import scene_band
from .charge import (obtain_breakdown_table, scene_breakdown, scene_surface_charge,
                     uses_breakdown_charge)
from .limit import CSV_COLUMNS, STATE_TEXT, BreakdownResult
from ..files import figure_file

def summary_lines(result: BreakdownResult, scene, band=None) -> list[str]:
    """What ``tengfield breakdown`` prints (with ``band``: σ_max over the γ range and one
    line per edge of the band saying what it assumes)."""
    b = result.binding
    sigma = scene_surface_charge(scene, result)
    gamma = ("" if getattr(result.paschen, "curve", "") == "empirical"
             else f" at gamma {result.paschen.gamma:g}")
    lines = [f"static limit sigma_max = {result.sigma_max * 1e6:.4g} µC/m^2{gamma} (relative "
             f"error estimate {result.relative_error_estimate:.2g}), "
             f"{result.paschen.pressure / 1e3:.6g} kPa",
             f"binds: {b.state} ({STATE_TEXT[b.state]}), {b.side} gap, line at "
             f"{math.degrees(b.angle):.0f} deg, ball at z = {b.position * 1e3:.4g} mm: gap "
             f"{b.gap * 1e3:.4g} mm, V_b = {b.breakdown_voltage:.4g} V ({b.regime})"]
    for state, bind in result.per_state.items():
        lines.append(f"  {state:8s} sigma_max = {bind.sigma * 1e6:8.4g} µC/m^2 at z = "
                     f"{bind.position * 1e3:.4g} mm, {bind.side} gap {bind.gap * 1e3:.4g} mm")
    lines.append(f"scene sigma = {sigma * 1e6:.4g} µC/m^2: |sigma| / sigma_max = "
                 f"{result.margin(sigma):.3g}")
    if band is not None:
        from .band import assumption_lines, gamma_line
        lines.append(gamma_line(band))
        lines.append("the charge the device holds, as a band (docs/breakdown.md):")
        lines.extend("  " + text for text in assumption_lines(band).values())
    return lines


def write_outputs(result: BreakdownResult, scene, out, *, plots: bool = True,
                  field_status: str = "", band=None) -> list:
    """breakdown.json, breakdown.csv and (``plots``) breakdown.png in directory ``out``
    (with ``band``: breakdown.json's ``band`` and its panel in the figure)."""
    from pathlib import Path

    from ..files import atomic_path, write_csv, write_figure, write_json

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    sigma = scene_surface_charge(scene, result)
    data = result.to_json(sigma)
    data.update({"scene": scene.source, "field_hash": scene.field_hash(),
                 "field_stage": field_status,
                 "sigma_mode": "breakdown" if uses_breakdown_charge(scene) else "scene"})
    if band is not None:
        from .band import trajectory_block
        data["band"] = band.to_json()
        data["trajectory"] = trajectory_block(band, sigma)
    written = [write_json(out / "breakdown.json", data)]
    columns = [[row[c] for row in result.rows] for c in CSV_COLUMNS]
    with atomic_path(out / "breakdown.csv") as tmp:
        write_csv(tmp, list(CSV_COLUMNS), columns)
    written.append(out / "breakdown.csv")
    if plots:
        from ..plotting.breakdown import plot_breakdown
        drawn, title = drawn_charge(result, sigma)
        written.append(write_figure(plot_breakdown, result, drawn, title=title, band=band,
                                    ratios=_edge_curves(result, band),
                                    path=out / figure_file("breakdown")))
    return written


def _edge_curves(result, band):
    """The band panel's curves (:func:`tengfield.air_breakdown.band.edge_ratios`), None
    without a band along a trajectory."""
    if band is None or band.track is None:
        return None
    from .band import edge_ratios
    return edge_ratios(result, band)


def drawn_charge(result: BreakdownResult, sigma: float) -> tuple:
    """The σ [C/m²] breakdown.png draws the gap voltages at (the scene's; an uncharged
    ball has none: −σ_max) and the title saying so (None: the figure's own)."""
    if sigma != 0.0:
        return sigma, None
    return -result.sigma_max, (f"air breakdown: static limit σ_max = "
                               f"{result.sigma_max * 1e6:.3g} µC/m² (the scene's σ is 0: gap "
                               f"voltages drawn at −σ_max)")


@dataclass
class BreakdownStudy(BreakdownResult):
    """The :class:`BreakdownResult` of :func:`study`, with :meth:`write`."""
    #: how the surrogate was obtained (:class:`tengfield.surrogate.CacheOutcome`)
    field_outcome: Any = field(default=None, repr=False, compare=False)

    @checked_write
    def write(self, out_dir, plots: bool = True) -> list:
        """Write what ``tengfield breakdown -o out_dir`` writes (the band of the scene's
        own trajectory included); returns the paths."""
        return write_outputs(self, self.scene, Path(out_dir), plots=plots, band=self.band,
                             field_status=self.field_status)

    def plot(self, sigma: float | None = None, *, title: str | None = None):
        """breakdown.png as a matplotlib Figure, its three panels: the gap voltages at
        ``sigma`` [C/m²] (default: the scene's, as the file draws them) against Paschen's
        curve, their ratio to it over the stroke, and the band along the trajectory."""
        from ..plotting.breakdown import breakdown_figure

        if sigma is None:
            sigma, drawn_title = drawn_charge(self, scene_surface_charge(self.scene, self))
            title = title or drawn_title
        band = self.band
        return breakdown_figure(self, sigma, title=title, band=band,
                                ratios=_edge_curves(self, band))

    @property
    def band(self):
        """The band of the charge along the scene's own trajectory (its dynamics run once,
        on first use): breakdown.json's ``band``."""
        if "_band" not in self.__dict__:
            self.__dict__["_band"] = scene_band(self.scene, self)
        return self.__dict__["_band"]


def study(scene, *, states=None, cache_dir=None, comm=None, progress: bool = False,
          solve=None, command_line: str = "") -> BreakdownStudy:
    """``tf.breakdown(scene)``, ``tengfield breakdown`` from Python: the scene (a Scene, a
    scene file's path, or None: the default scene), its surrogate with breakdown lines
    (cached), :func:`scene_breakdown` (``states``: the circuit states checked, default
    the scene's; :data:`STATES` all of them, the CLI's ``--states all``). Returns a
    :class:`BreakdownResult` with ``.summary``, ``.plot()`` and ``.write(out_dir)``."""
    from ..charge_models import check_command
    check_command(scene, "breakdown")   # a charge model it runs
    from ..scene import check_field
    from ..scene.parse import verb_scene

    from .._args import names, path
    scene = verb_scene("tengfield.breakdown", scene)
    states = names("tengfield.breakdown", states, "states")   # "open": one state
    cache_dir = path("tengfield.breakdown", cache_dir, "cache_dir", allow_none=True,
                     what="a folder name")
    check_field(scene)
    table, outcome = obtain_breakdown_table(scene, cache_dir=cache_dir, comm=comm,
                                            progress=progress, solve=solve,
                                            command_line=command_line)
    result = scene_breakdown(scene, table, states)
    values = {f.name: getattr(result, f.name) for f in fields(result) if f.init}
    return BreakdownStudy(**{**values, "field_status": outcome.status, "field_outcome": outcome})
