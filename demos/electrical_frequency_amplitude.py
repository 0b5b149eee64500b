"""Peak voltage over frequency (1.5 mm, 5-50 Hz) and over frequency x amplitude (Figs. 9e-f).

One surrogate of the paper's device serves every excitation (the field does
not depend on the table motion): for each frequency and amplitude the impact
map gives the trajectory and the surrogate the waveforms. The paper reports
(Fig. 9e): no output below 16 Hz at 1.5 mm (the ball does not lift off),
contact with the upper plate from 20 Hz with a jump of the voltage, and a
plateau of the voltage from 20 to 50 Hz; (Fig. 9f) the peak (> 4 V)
saturates quickly once the ball bounces, a bandwidth above 35 Hz at 3 mm.

Voltages are shown as the electrometer reads them: σ and the instrument
capacitance C_p are the ones that reconcile the 1.5 mm / 20 Hz point with
the paper (see demos/electrical_waveforms.py).

    .venv/bin/python demos/electrical_frequency_amplitude.py [--fast] [-o DIR] [--cache-dir DIR]
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from electrical_common import (demo_arguments, measure, paper_scene, pyplot,  # noqa: E402
                               reconcile, run_length, save_small_png, surrogate_curves)

from tengfield.dynamics import simulate  # noqa: E402


def voltage_grid(scene, curves, frequencies, amplitudes, fast, scale, c_p):
    """Peak-to-peak V read with C_p [V], Q_SC [C] and max gap [m], indexed [amplitude, frequency]."""
    shape = (len(amplitudes), len(frequencies))
    volts, charge, max_gap = np.zeros(shape), np.zeros(shape), np.zeros(shape)
    for i, a in enumerate(amplitudes):
        for j, f in enumerate(frequencies):
            point = scene.with_values(excitation={"frequency_hz": float(f),
                                                  "amplitude_mm": float(a) * 1e3},
                                      run=run_length(float(f), fast))
            dyn = simulate(point)
            p = measure(curves, dyn, point, parallel_capacitance=c_p)
            volts[i, j] = p["V_oc"] * scale
            charge[i, j] = p["Q_sc"] * scale
            max_gap[i, j] = dyn.regime.max_gap
    return volts, charge, max_gap


def main(argv: list[str] | None = None) -> dict:
    args = demo_arguments(__doc__, argv)
    out = Path(args.output)
    scene = paper_scene(args.fast)
    _, curves = surrogate_curves(scene, args.cache_dir)
    scale, c_p = reconcile(curves, args.fast)
    print(f"sigma x {scale:.3g} (Q_SC = 1.42 nC at 1.5 mm / 20 Hz), C_p = {c_p * 1e12:.0f} pF")

    # Fig. 9e: 1.5 mm, 5-50 Hz
    freqs = np.array([5, 10, 15, 16, 18, 20, 25, 35, 50.0]) if args.fast else \
        np.arange(5.0, 50.01, 1.0)
    volts, charge, gap = voltage_grid(scene, curves, freqs, [1.5e-3], args.fast, scale, c_p)
    volts, charge, gap = volts[0], charge[0], gap[0]
    onset = freqs[np.argmax(volts > 0.01 * volts.max())]
    plateau = (freqs >= 20) & (freqs <= 50)
    print("Fig. 9e, 1.5 mm                        paper                 tengfield")
    print(f"lowest frequency with output           16-20 Hz (none < 16)  {onset:g} Hz")
    print(f"V_pp over 20-50 Hz (read, C_p)         plateau ~4 V          "
          f"{volts[plateau].min():.3g}-{volts[plateau].max():.3g} V")
    print("f [Hz]  max gap [mm]  V_pp [V]  Q_pp [nC]")
    for f, g, v, q in zip(freqs, gap, volts, charge):
        print(f"{f:6.1f}  {g * 1e3:11.3f}  {v:8.3f}  {q * 1e9:9.3f}")

    # Fig. 9f: frequency x amplitude
    amps = np.array([0.5, 1.5, 3.0]) * 1e-3 if args.fast else np.arange(0.5, 3.01, 0.25) * 1e-3
    freqs_f = np.array([10, 20, 35, 50.0]) if args.fast else np.arange(5.0, 50.01, 2.5)
    grid, _, gap_grid = voltage_grid(scene, curves, freqs_f, amps, args.fast, scale, c_p)
    at3 = grid[np.argmin(abs(amps - 3e-3))]
    above = freqs_f[at3 > 4.0]
    band = (above.max() - above.min()) if above.size else 0.0
    print("Fig. 9f                                paper                 tengfield")
    print(f"bandwidth with V_pp > 4 V at 3 mm      > 35 Hz               {band:g} Hz "
          f"({above.min() if above.size else 0:g}-{above.max() if above.size else 0:g} Hz)")
    print(f"V_pp at 3 mm over {freqs_f.min():g}-{freqs_f.max():g} Hz         saturates > 4 V       "
          f"{at3.min():.3g}-{at3.max():.3g} V")

    plt = pyplot()
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 3.8))
    ax1.plot(freqs, volts, "o-", ms=3, label="V_pp read (C_p)")
    ax1.set_xlabel("frequency [Hz]")
    ax1.set_ylabel("V_pp [V]")
    ax1.axhline(4.2, color="C3", ls="--", lw=0.8, label="paper: 4.2 V")
    ax1.axvline(16, color="0.5", ls=":", lw=0.8)
    ax1.legend(fontsize=7, loc="center right")
    twin = ax1.twinx()
    twin.plot(freqs, gap * 1e3, "s--", color="0.5", ms=3)
    twin.set_ylabel("max gap [mm]", color="0.45")
    ax1.set_title("Fig. 9e: 1.5 mm", fontsize=10)
    mesh = ax2.pcolormesh(freqs_f, amps * 1e3, grid, shading="nearest", cmap="viridis")
    ax2.contour(freqs_f, amps * 1e3, gap_grid, levels=[1e-6, scene.device.stroke * 0.999],
                colors="w", linewidths=0.8)
    fig.colorbar(mesh, ax=ax2, label="V_pp read [V]")
    ax2.set_xlabel("frequency [Hz]")
    ax2.set_ylabel("amplitude [mm]")
    ax2.set_title("Fig. 9f: V_pp (white: lift-off and contact)", fontsize=10)
    fig.tight_layout()
    path = save_small_png(fig, out / "electrical_frequency_amplitude.png")
    plt.close(fig)
    print(f"wrote {path}")

    return {"onset_hz": float(onset),
            "V_pp_read_V": {float(f): float(v) for f, v in zip(freqs, volts)},
            "bandwidth_above_4V_at_3mm_hz": float(band)}


if __name__ == "__main__":
    main()
