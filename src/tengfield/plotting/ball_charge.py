"""ball_charge.png: the charge the contacts make (``[charge] model = "contact"``): the ball's
surface density against time and against the number of contacts, with the pair's
equilibrium density sigma_eq and the air-breakdown cap the run used."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from . import new_figure, save_figure


def plot_ball_charge(record: dict, block: dict, path: str | Path, *, title: str = "") -> Path:
    """ball_charge.png: :func:`ball_charge_figure` saved to ``path``."""
    return Path(save_figure(ball_charge_figure(record, block, title=title), path, dpi=110))


def ball_charge_figure(record: dict, block: dict, *, title: str = ""):
    """Two panels: sigma against time (with its 90 % rise time) and against contacts, and
    the levels sigma_eq, the cap and the steady charge. A matplotlib Figure."""
    fig = new_figure((10.0, 4.0))
    left, right = fig.subplots(1, 2)
    cells = record.get("cells") or []     # an [array]: the other cells' own histories
    for k, line in enumerate(cells):
        left.plot(record["grid_s"], line, color="0.7", lw=0.7,
                  label=f"the other cells ({len(cells)} distinct histories)"
                  if k == 0 else None)
    ball = "ball (leaks between contacts)" if block.get("leakage_time_s") else "ball"
    if "cell_count" in record:
        ball = f"cell {block['cells']['reported_cell']} (median steady σ of " \
               f"{record['cell_count']})"
    left.plot(record["grid_s"], record["grid_uC_per_m2"], color="C0", lw=1.3, label=ball)
    contact = np.concatenate([[0], record["contact"]])
    after = np.concatenate([[record["start_uC_per_m2"]], record["after_uC_per_m2"]])
    right.plot(contact, after, color="C0", lw=1.3, label="just after each contact")
    levels = [("sigma_eq (pair's equilibrium)", block.get("equilibrium_uC_per_m2"), "C3"),
              (f"cap: air breakdown ({block.get('cap_level')})",
               None if block.get("cap_uC_per_m2") is None
               else np.sign(block.get("equilibrium_uC_per_m2") or -1.0) * block["cap_uC_per_m2"],
               "C1"),
              ("steady", block.get("steady_uC_per_m2"), "0.4")]
    for ax in (left, right):
        for label, value, color in levels:
            if value is not None:
                ax.axhline(value, color=color, lw=1.0,
                           ls=(0, (4, 2)) if color != "0.4" else (0, (1, 2)), label=label)
        ax.set_ylabel("ball surface charge σ [µC/m²]")
        ax.grid(alpha=0.3)
    approach = block.get("approach")
    if approach and block.get("rise_time_90_s"):   # past the run's end: the geometric law
        t_end = float(record["grid_s"][-1])
        later = np.linspace(t_end, 1.15 * block["rise_time_90_s"], 200)
        area = block["ball_area_m2"]
        start = block["end_of_run_uC_per_m2"] * 1e-6 * area
        q_u = approach["unclipped_C"]
        q = q_u - (q_u - start) * approach["per_stretch"] ** ((later - t_end)
                                                             / approach["stretch_s"])
        cap = block.get("cap_uC_per_m2")
        if cap is not None:
            q = np.clip(q, -cap * 1e-6 * area, cap * 1e-6 * area)
        left.plot(later, q / area * 1e6, color="C0", lw=1.1, ls=(0, (1, 1.5)),
                  label="extrapolated past the run")
    window = record.get("window_s")   # the waveforms' steady window (the run's end)
    if window is not None:
        left.axvspan(window[0], window[1], color="C2", alpha=0.25, lw=0,
                     label=f"waveforms.csv, peaks ({window[1] - window[0]:.3g} s)")
    rise = block.get("rise_time_90_s")
    if rise is not None and rise > 0.0:
        left.axvline(rise, color="0.5", lw=0.8)
        left.annotate(f"90 % at {rise:.3g} s", (rise, 0.5), xycoords=("data", "axes fraction"),
                      fontsize=8, rotation=90, ha="right", va="center")
    left.set_xlabel("time [s]")
    right.set_xlabel("contacts")
    left.set_title(f"σ against time: steady {block['steady_uC_per_m2']:.3g} µC/m²", fontsize=9)
    right.set_title(f"σ against contacts ({block['contacts']}): limited by\n{block['binds']}",
                    fontsize=9)
    left.legend(fontsize=7, loc="best")
    right.legend(fontsize=7, loc="best")
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return fig
