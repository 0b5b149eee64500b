"""Figures of the dynamics: trajectory (like the paper's Figs. 5a/6a/7a), regime maps and
the 3D ball's side and top views."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..scene.constants import G
from . import new_figure, save_figure

REGIME_COLOURS = {
    "rest": "#d9d9d9",
    "bounce": "#9ecae1",
    "chaos": "#fdae6b",
    "not-settled": "#bcbddc",
    "critical-contact": "#a1d99b",
    "regular-contact": "#31a354",
    "error": "#e31a1c",
}


#: plot_trajectory shows at most this many excitation periods (the last ones) ...
MAX_PLOT_PERIODS = 200
#: ... drawn from this many points of the exact trajectory.
PLOT_POINTS = 4000


@dataclass(frozen=True)
class TrajectoryFigure:
    """What trajectory.png shows, as plain numbers (small and picklable, so that a
    figure process can draw it): the exact trajectory at PLOT_POINTS times ``t`` [s],
    the lower plate ``y`` and the gap ``z`` [m], the impacts in that span, the plate
    distance ``stroke`` [m], the start of the steady window [s], the title and whether
    the cell is a spherical shell (``shell``: its bottom and top are the cavity wall)."""

    t: np.ndarray
    y: np.ndarray
    z: np.ndarray
    impact_time: np.ndarray
    impact_y: np.ndarray
    impact_z: np.ndarray
    impact_upper: np.ndarray     # bool: the impact is on the upper plate
    stroke: float
    window_start: float
    title: str
    shell: bool = False          # a spherical shell: the "plates" are the cavity wall


def motion_words(scene, *, stroke: bool = False) -> str:
    """The excitation and contact of ``scene`` as a figure's title names them:
    "A = 1.5 mm, 20 Hz, restitution 0.1" (with ``stroke``: ", Δh = 3 mm" too)."""
    exc = scene.excitation
    words = (f"A = {exc.amplitude * 1e3:g} mm, {exc.frequency:g} Hz, "
             f"restitution {scene.contact.restitution:g}")
    return words + (f", Δh = {scene.device.stroke * 1e3:g} mm" if stroke else "")


def trajectory_figure(result, *, title: str | None = None,
                      max_periods: float | None = None) -> TrajectoryFigure:
    """The numbers of :func:`plot_trajectory` (``result`` a DynamicsResult)."""
    limit = MAX_PLOT_PERIODS if max_periods is None else min(max_periods, MAX_PLOT_PERIODS)
    t_all = result.t
    start = t_all[0]
    if result.period > 0 and t_all[-1] - t_all[0] > limit * result.period:
        start = t_all[-1] - limit * result.period
    origin = getattr(result, "time_origin", t_all[0])
    full = getattr(result, "elapsed", None)
    elapsed_end = full[-1] if full is not None else t_all[-1] - origin
    elapsed = np.linspace(max(start - origin, 0.0), elapsed_end, PLOT_POINTS)
    if hasattr(result, "sample_elapsed"):
        z, _, y = result.sample_elapsed(elapsed)
    else:
        z, _, y = result.sample(origin + elapsed)
    t = origin + elapsed
    imp = result.impacts
    ti, yi, zi, upper = (np.zeros(0),) * 3 + (np.zeros(0, dtype=bool),)
    if len(imp):
        sel = (imp.time >= t[0]) & (imp.time <= t[-1])
        if np.any(sel):
            ti = imp.time[sel]
            zi, _, yi = result.sample(ti)
            upper = imp.plate[sel] != "lower"
    reg = result.regime
    head = title or "ball between two vibrating plates"
    period = int(reg.period) if reg.period is not None and np.isfinite(reg.period) else 0
    said = (f"{reg.name}, period {period}" if period > 0 and reg.name != "rest"
            else reg.name)          # a period of 0 (aperiodic, at rest): the name alone
    full_title = (f"{head}\nregime: {said}, max gap {reg.max_gap * 1e3:.3g} mm; contacts "
                  f"per excitation period: lower {reg.lower_contacts_per_period:.3g}, upper "
                  f"{reg.upper_contacts_per_period:.3g}")
    return TrajectoryFigure(t=t, y=np.asarray(y), z=np.asarray(z), impact_time=ti,
                            impact_y=np.asarray(yi), impact_z=np.asarray(zi),
                            impact_upper=np.asarray(upper, dtype=bool),
                            stroke=float(result.stroke),
                            window_start=float(result.window_start), title=full_title,
                            shell=getattr(result, "cavity_radius", 0.0) > 0.0)


def plot_trajectory(result, path, *, title: str | None = None, max_periods: float | None = None):
    """Ball, lower and upper plate vs time (top) and the gap z(t) (bottom); impacts marked.

    ``result`` is a :class:`tengfield.dynamics.DynamicsResult`; lengths in mm.
    ``max_periods`` limits the plot to the last that many excitation periods
    (at most MAX_PLOT_PERIODS); the curves are the exact trajectory at
    PLOT_POINTS times, so the cost does not grow with the run.
    """
    return draw_trajectory(trajectory_figure(result, title=title, max_periods=max_periods),
                           path)


def draw_trajectory(data: TrajectoryFigure, path):
    """Draw a :class:`TrajectoryFigure` to the PNG ``path``."""
    return save_figure(trajectory_plot(data), path, dpi=130)


def trajectory_plot(data: TrajectoryFigure):
    """The trajectory figure (matplotlib Figure) of a :class:`TrajectoryFigure`."""
    t, y, z = data.t, data.y, data.z
    stroke_mm = data.stroke * 1e3
    fig = new_figure((9, 6))
    ax1, ax2 = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [3, 2]})
    bottom, top = (("cavity wall, bottom", "cavity wall, top") if data.shell
                   else ("lower plate", "upper plate"))
    ax1.plot(t, y * 1e3, color="0.35", lw=1.2, label=f"{bottom} $y(t)$")
    ax1.plot(t, (y + data.stroke) * 1e3, color="0.6", lw=1.2, ls="--",
             label=f"{top} $y + \\Delta h$")
    ax1.plot(t, (y + z) * 1e3, color="#d62728", lw=1.4, label="ball bottom $y + z$")
    ax1.fill_between(t, (y + z) * 1e3, y * 1e3, color="#d62728", alpha=0.08)
    ax2.plot(t, z * 1e3, color="#1f77b4", lw=1.3, label="gap $z(t)$")
    ax2.axhline(0.0, color="0.35", lw=0.8)
    ax2.axhline(stroke_mm, color="0.6", lw=0.8, ls="--")
    ti, yi, zi = data.impact_time, data.impact_y, data.impact_z
    upper = data.impact_upper
    where = ("bottom", "top") if data.shell else ("lower", "upper")
    for which, marker, colour, label in ((~upper, "v", "k", f"impact, {where[0]}"),
                                         (upper, "^", "#9467bd", f"impact, {where[1]}")):
        if np.any(which):
            ax1.plot(ti[which], (yi[which] + zi[which]) * 1e3, marker, ms=4,
                     color=colour, label=label)
            ax2.plot(ti[which], zi[which] * 1e3, marker, ms=4, color=colour)
    ax1.set_ylabel("position [mm]")
    ax2.set_ylabel("gap $z$ [mm]")
    ax2.set_xlabel("time [s]")
    ax2.set_ylim(-0.05 * stroke_mm, 1.08 * stroke_mm)
    ax1.set_title(data.title, fontsize=10)
    ax1.legend(loc="upper right", fontsize=8, ncol=3, framealpha=0.85)
    for ax in (ax1, ax2):
        ax.grid(alpha=0.3)
        if data.window_start > t[0]:
            ax.axvspan(t[0], data.window_start, color="0.9", zorder=-1)
    fig.tight_layout()
    return fig


def plot_regime_map(map_result, path, *, title: str | None = None):
    """map.png: :func:`regime_map_figure` saved to ``path``."""
    return save_figure(regime_map_figure(map_result, title=title), path, dpi=130)


def regime_map_figure(map_result, *, title: str | None = None):
    """Regime colours over (frequency, amplitude) with the lift-off curve A w^2 = g."""
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    names = list(REGIME_COLOURS)
    code = np.vectorize(lambda s: names.index(s) if s in names else names.index("error"))(
        map_result.regime)
    cmap = ListedColormap([REGIME_COLOURS[n] for n in names])
    f = map_result.frequency
    a_mm = map_result.amplitude * 1e3
    fig = new_figure((7.5, 5.5))
    ax = fig.subplots()

    def edges(v):
        if v.size == 1:
            return np.array([v[0] * 0.95, v[0] * 1.05 + 1e-12])
        mid = 0.5 * (v[1:] + v[:-1])
        return np.concatenate([[v[0] - (mid[0] - v[0])], mid, [v[-1] + (v[-1] - mid[-1])]])

    ax.pcolormesh(edges(f), edges(a_mm), code, cmap=cmap, vmin=-0.5, vmax=len(names) - 0.5,
                  shading="flat")
    ff = np.linspace(max(edges(f)[0], 1e-3), edges(f)[-1], 400)
    a_lift = G / (2 * np.pi * ff) ** 2 * 1e3
    ax.plot(ff, a_lift, color="k", lw=1.8, label=r"lift-off $A\omega^2 = g$")
    ax.set_xlim(edges(f)[0], edges(f)[-1])
    ax.set_ylim(edges(a_mm)[0], edges(a_mm)[-1])
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("amplitude [mm]")
    present = [n for n in names if np.any(map_result.regime == n)]
    handles = [Patch(color=REGIME_COLOURS[n], label=n) for n in present]
    handles.append(ax.get_lines()[0])
    ax.legend(handles=handles, loc="upper right", fontsize=8, framealpha=0.9)
    ax.set_title(title or "motion regimes of the ball", fontsize=10)
    fig.tight_layout()
    return fig


def plot_trajectory3d(result, path, *, title: str | None = None):
    """trajectory3d.png: :func:`trajectory3d_figure` saved to ``path``."""
    return save_figure(trajectory3d_figure(result, title=title), path, dpi=120)


def trajectory3d_figure(result, *, title: str | None = None):
    """Side view (gap z and radial offset r vs time) and top view (x-y) [mm]; in a
    spherical shell (``result.cavity_radius`` > 0) also the meridian view: the centre's
    (r, z) inside the circle it cannot leave, with the band's rims.

    Drawn without pyplot (the caller's matplotlib backend is left alone).
    """
    from matplotlib.patches import Circle

    t = result.t
    clearance_mm = result.tube_clearance * 1e3
    shell = getattr(result, "cavity_radius", 0.0) > 0.0
    top_label, wall_label = (("top of the cavity", "equator (largest r)") if shell
                             else ("upper plate", "tube wall (r)"))
    fig = new_figure((15, 5) if shell else (11, 5))
    ax_side = fig.add_subplot(1, 3 if shell else 2, 1)
    ax_top = fig.add_subplot(1, 3 if shell else 2, 3 if shell else 2)
    ax_side.plot(t, result.gap * 1e3, color="#1f77b4", lw=1.2, label="gap $z$")
    ax_side.plot(t, result.radial * 1e3, color="#d62728", lw=1.0, label="radial offset $r$")
    ax_side.axhline(0.0, color="0.35", lw=0.8)
    ax_side.axhline(result.stroke * 1e3, color="0.6", lw=0.8, ls="--", label=top_label)
    ax_side.axhline(clearance_mm, color="#d62728", lw=0.8, ls=":", label=wall_label)
    ax_side.set_xlabel("time [s]")
    ax_side.set_ylabel("[mm]")
    ax_side.set_title("side view")
    ax_side.legend(loc="upper right", fontsize=8)
    ax_side.grid(alpha=0.3)
    if shell:
        _meridian_view(fig.add_subplot(1, 3, 2), result)
    ax_top.plot(result.x * 1e3, result.y * 1e3, color="#2ca02c", lw=0.8)
    circle = Circle((0.0, 0.0), clearance_mm, fill=False, color="0.3", ls="--")
    ax_top.add_patch(circle)
    lim = 1.15 * max(clearance_mm, float(np.max(result.radial, initial=0.0)) * 1e3)
    ax_top.set_xlim(-lim, lim)
    ax_top.set_ylim(-lim, lim)
    ax_top.set_aspect("equal")
    ax_top.set_xlabel("x [mm]")
    ax_top.set_ylabel("y [mm]")
    ax_top.set_title("top view (centre; dashed: wall contact)")
    ax_top.grid(alpha=0.3)
    head = title or "ball in 3D"
    s = result.summary
    third = "band" if shell else "wall"
    fig.suptitle(f"{head}: regime {s['regime']}, {s['impacts']} "
                 f"{'electrode' if shell else 'plate'} impacts, "
                 f"{s['wall_contacts']} {third} contacts", fontsize=10)
    fig.tight_layout()
    return fig


def _meridian_view(ax, result):
    """The centre in the (r, z) half-plane of the shell [mm], z from the cavity's centre:
    the circle a - R it cannot leave (contact), the rays to the band's rims."""
    a = result.cavity_radius
    c = result.tube_clearance                      # a - R
    z = (result.gap - c) * 1e3                     # gap + R - a
    phi = np.linspace(-0.5 * np.pi, 0.5 * np.pi, 181)
    ax.plot(c * 1e3 * np.cos(phi), c * 1e3 * np.sin(phi), color="0.3", ls="--", lw=0.8,
            label="contact (|c| = a - R)")
    rim = float(np.arcsin(min(result.band_half_height / a, 1.0)))
    for sign in (-1.0, 1.0):
        ax.plot([0.0, c * 1e3 * np.cos(rim)], [0.0, sign * c * 1e3 * np.sin(rim)],
                color="#ff7f0e", lw=0.8, ls=":", label="band's rims" if sign > 0 else None)
    ax.plot(result.radial * 1e3, z, color="#9467bd", lw=0.8, label="centre")
    ax.set_xlim(-0.05 * c * 1e3, 1.15 * c * 1e3)
    ax.set_ylim(-1.15 * c * 1e3, 1.15 * c * 1e3)
    ax.set_aspect("equal")
    ax.set_xlabel("r [mm]")
    ax.set_ylabel("z from the cavity's centre [mm]")
    ax.set_title("meridian view (centre)")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=3, fontsize=7,
              frameon=False)
    ax.grid(alpha=0.3)
