"""The 0.5 mm amplitude sweep of the paper's Fig. 5a (5-70 Hz), from the dynamics alone.

At a fixed table amplitude of 0.5 mm the ball rests below ~22 Hz
(A w^2 < g), hops a little at 25 Hz and bounces higher as the frequency
grows: the paper reports a maximum displacement rising almost linearly
from 0.09 mm (25 Hz) to the full 3 mm stroke (critical contact, 70 Hz),
with chaotic motion from 45 to 70 Hz. For each frequency we simulate the
ball from rest with the impact map and report the steady regime, its
period and the maximum gap.

    .venv/bin/python demos/dynamics_amplitude_sweep.py [--fast] [-o DIR]
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from tengfield.dynamics import simulate
from tengfield.scene import default_scene

from demo_mpi import is_root


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fast", action="store_true", help="fewer frequencies, shorter runs")
    ap.add_argument("-o", "--output", default="demos/out", help="output directory")
    args = ap.parse_args(argv)
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)

    freqs = [5, 25, 45, 70] if args.fast else list(range(5, 71, 5))
    periods, settle = (60, 30) if args.fast else (300, 150)
    results = {}
    for f in freqs:
        scene = default_scene().with_values(
            excitation={"amplitude_mm": 0.5, "frequency_hz": float(f)},
            run={"duration_s": periods / f, "settle_periods": settle, "sample_rate_hz": 400.0 * f})
        results[f] = simulate(scene)

    # --- the numbers, next to the paper's -----------------------------------
    print("f [Hz]  regime            period  max gap [mm]   paper")
    paper = {25: "0.09 mm", 45: "chaos", 50: "chaos", 55: "chaos", 60: "chaos", 65: "chaos",
             70: "chaos, ~3 mm (critical contact)"}
    for f, res in results.items():
        reg = res.regime
        print(f"{f:5d}   {reg.name:16s}  {reg.period:5d}   {reg.max_gap * 1e3:8.3f}      "
              f"{paper.get(f, '')}")
    fs = np.array([f for f in freqs if f >= 25], dtype=float)
    gaps = np.array([results[int(f)].regime.max_gap for f in fs])
    if fs.size >= 3:
        slope, icpt = np.polyfit(fs, gaps, 1)
        r2 = 1 - np.sum((gaps - (slope * fs + icpt)) ** 2) / np.sum((gaps - gaps.mean()) ** 2)
        print(f"linear fit of max gap over 25-70 Hz: {slope * 1e6:.1f} um/Hz, R^2 = {r2:.3f} "
              "(paper: 0.09 -> 3 mm, R^2 = 0.98)")

    # --- a figure in the spirit of Fig. 5a: the last periods at each frequency
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 5.5), gridspec_kw={"width_ratios": [3, 2]})
    offset = 0.0
    for f, res in results.items():
        window = res.t >= res.t[-1] - 0.2
        tt = res.t[window] - res.t[window][0]
        ax1.plot(tt, res.gap[window] * 1e3 + offset, lw=1)
        ax1.text(0.201, offset, f"{f} Hz", fontsize=7, va="bottom")
        offset += 3.5
    ax1.set_xlabel("time in the steady window [s]")
    ax1.set_ylabel("gap z [mm] (offset 3.5 mm per frequency)")
    ax1.set_title("Fig. 5a: A = 0.5 mm, 5-70 Hz")
    ax1.set_xlim(0, 0.23)
    colours = {"rest": "0.6", "bounce": "#1f77b4", "chaos": "#ff7f0e", "not-settled": "#9e9ac8",
               "critical-contact": "#2ca02c", "regular-contact": "#006d2c"}
    for f, res in results.items():
        ax2.plot(f, res.regime.max_gap * 1e3, "o", color=colours[res.regime.name])
    for name, c in colours.items():
        ax2.plot([], [], "o", color=c, label=name)
    ax2.plot([25, 70], [0.09, 3.0], "k--", lw=1, label="paper: linear 0.09 -> 3 mm")
    ax2.set_xlabel("frequency [Hz]")
    ax2.set_ylabel("max gap [mm]")
    ax2.legend(fontsize=8)
    ax2.grid(alpha=0.3)
    fig.tight_layout()
    if is_root():
        fig.savefig(out / "dynamics_amplitude_sweep.png", dpi=130)
    print(f"wrote {out / 'dynamics_amplitude_sweep.png'}")

    return {"regime": {f: r.regime.name for f, r in results.items()},
            "max_gap_mm": {f: r.regime.max_gap * 1e3 for f, r in results.items()}}


if __name__ == "__main__":
    main()
