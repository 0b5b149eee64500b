"""record.png of a long (streamed) run: the whole record as a min/max envelope.

:mod:`tengfield.electrical.stream` keeps, while it streams, each column's lowest and
highest value in each of 2000 time bins (a figure's pixel columns): drawn as a band,
every peak of the run shows (a decimated line would drop them), in memory independent
of the run's length. waveforms.png keeps the last 5 periods at full resolution.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from . import new_figure, save_figure
from .waveforms import waveform_panels


def record_figure(envelope: dict, *, title: str = "", parallel_capacitance_pF: float = 0.0):
    """The panels of waveforms.png over the whole run, each a min/max band per time bin,
    and the gap's band on a panel of its own below (no secondary axes); time in s.
    ``envelope``: ``{"time_s": bin centres, column: (min, max)}``."""
    t = np.asarray(envelope["time_s"])
    panels = waveform_panels(envelope, parallel_capacitance_pF)
    gap = "gap_m" in envelope
    count = len(panels) + gap
    fig = new_figure((8, 2.1 * len(panels) + (1.3 if gap else 0.0)))
    axes = np.atleast_1d(fig.subplots(count, 1, sharex=True, gridspec_kw={
        "height_ratios": [1.0] * len(panels) + ([0.6] if gap else [])}))
    for ax, (key, label, factor) in zip(axes, panels):
        lo, hi = envelope[key]
        ax.fill_between(t, np.asarray(lo) * factor, np.asarray(hi) * factor, color="C0",
                        lw=0.6, edgecolor="C0", step="mid",
                        label=(f"V read through C_p = {parallel_capacitance_pF:.3g} pF"
                               if key == "V_read_V" else None))
        if key == "V_read_V":
            ax.legend(loc="upper right", fontsize=7)
        ax.set_ylabel(label, color="C0")
        ax.grid(alpha=0.3)
    if gap:
        g_lo, g_hi = envelope["gap_m"]
        axes[-1].fill_between(t, np.asarray(g_lo) * 1e3, np.asarray(g_hi) * 1e3, color="0.5",
                              alpha=0.5, lw=0.4, edgecolor="0.4", step="mid")
        axes[-1].set_ylabel("gap z [mm]")
        axes[-1].grid(alpha=0.3)
    axes[-1].set_xlabel("time [s]")
    fig.suptitle(title or "whole run", fontsize=10)
    fig.tight_layout()
    return fig


def plot_record(envelope: dict, path: str | Path, *, title: str = "",
                parallel_capacitance_pF: float = 0.0) -> Path:
    """record.png: :func:`record_figure` saved to ``path``."""
    save_figure(record_figure(envelope, title=title,
                              parallel_capacitance_pF=parallel_capacitance_pF), path, dpi=120)
    return Path(path)
