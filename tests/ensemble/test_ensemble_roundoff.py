"""Round-off is not spread (issue #42 item 4): V_OC of an ensemble that differs only in
its last bits was printed `V_OC 1256 +- 2.28e-07 V`, I_SC (the output that varies)
was left out, and ensemble.png zoomed its V_OC axis into the round-off."""
from __future__ import annotations

import re

import numpy as np

from tengfield.commands.run import ensemble_line
from tengfield.ensemble import ROUNDOFF_RELATIVE, ensemble_block, statistics


def rows(n=8):
    rng = np.random.default_rng(3)
    out = []
    for k in range(n):
        out.append({"realisation": k, "seed": k, "regime": "bounce",
                    "V_oc_pp_V": 1256.0 * (1 + 1e-13 * rng.standard_normal()),
                    "Q_sc_pp_C": 0.36e-9 * (1 + 1e-14 * k),
                    "I_sc_pp_A": 1e-7 * (0.95 + 0.26 * rng.random()),
                    "I_sc_peak_A": 6e-8 * (0.95 + 0.26 * rng.random())})
    return out


def test_a_spread_below_round_off_is_exact():
    s = statistics([1256.0, 1256.0 * (1 + 3e-14), 1256.0 * (1 - 2e-14)])
    assert s["equal_within_round_off"] is True
    assert s["std"] < ROUNDOFF_RELATIVE * 1256.0
    spread = statistics([95e-9, 121e-9, 108e-9])
    assert spread["equal_within_round_off"] is False and spread["ci95_half_width"] > 0


def test_the_line_says_exact_and_includes_i_sc():
    block = ensemble_block(rows())
    line = ensemble_line(block)
    assert "+- 2" not in line.split("V_OC")[1].split(",")[0]
    assert "V_OC 1256 V (same in every realisation" in line
    assert "I_SC" in line and re.search(r"I_SC \d+(\.\d+)? \+- \d", line)
    assert "round-off" in line


def test_the_figure_does_not_zoom_into_round_off():
    import matplotlib
    matplotlib.use("Agg")
    block = ensemble_block(rows())
    fig = block.plot()
    voc = [ax for ax in fig.axes if ax.get_ylabel().startswith("V_OC")][0]
    low, high = voc.get_ylim()
    assert (high - low) / 1256.0 >= 0.01          # not 1e-10 of the value
    isc = [ax for ax in fig.axes if ax.get_ylabel().startswith("I_SC")]
    assert isc



