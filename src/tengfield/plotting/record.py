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
    with the gap's band in grey (right axis); time in s. ``envelope``: ``{"time_s": bin
    centres, column: (min, max)}``."""
    t = np.asarray(envelope["time_s"])
    panels = waveform_panels(envelope, parallel_capacitance_pF)
    fig = new_figure((8, 2.1 * len(panels)))
    axes = np.atleast_1d(fig.subplots(len(panels), 1, sharex=True))
    for ax, (key, label, factor) in zip(axes, panels):
        lo, hi = envelope[key]
        ax.fill_between(t, np.asarray(lo) * factor, np.asarray(hi) * factor, color="C0",
                        lw=0.6, edgecolor="C0", step="mid")
        ax.set_ylabel(label, color="C0")
        if "gap_m" in envelope:
            twin = ax.twinx()
            g_lo, g_hi = envelope["gap_m"]
            twin.fill_between(t, np.asarray(g_lo) * 1e3, np.asarray(g_hi) * 1e3, color="0.6",
                              alpha=0.25, lw=0, step="mid")
            twin.set_ylabel("gap z [mm]", color="0.45")
        ax.grid(alpha=0.3)
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
