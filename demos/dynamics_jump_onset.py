"""Jump onset of the ball (the paper's Figs. 4c and 4f), from the dynamics alone.

The ball rests on the lower plate of the paper's device (stroke 3 mm) while
the table moves as y = A sin(2 pi f t). It can only leave the plate once the
table accelerates downwards faster than gravity, A w^2 > g (Gamma > 1); it
*jumps* visibly once its gap reaches 0.1 mm or 0.5 mm, the two thresholds
the paper uses. We find, by bisection with the impact map:

* Fig. 4c: the smallest amplitude that gives a 0.1 / 0.5 mm jump at each frequency,
* Fig. 4f: the smallest frequency that gives it at each amplitude,

and compare with the values the paper quotes.

    .venv/bin/python demos/dynamics_jump_onset.py [--fast] [-o DIR]
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from tengfield.dynamics.impact import Restitution
from tengfield.dynamics.onset import onset_amplitude, onset_frequency
from tengfield.scene import G, default_scene

from demo_mpi import is_root


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fast", action="store_true", help="coarse grids (a few seconds)")
    ap.add_argument("-o", "--output", default="demos/out", help="output directory")
    args = ap.parse_args(argv)
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)

    # The device and the restitution of the embedded default scene.
    scene = default_scene()
    stroke = scene.device.stroke
    rest = Restitution.from_contact(scene.contact)

    # --- Fig. 4c: onset amplitude vs frequency ------------------------------
    freqs = np.array([5, 10, 30, 50.0]) if args.fast else np.arange(5, 51, 2.5)
    heights = [0.1e-3, 0.5e-3]
    amp_curves = {h: np.array([onset_amplitude(f, h, rest, stroke) for f in freqs])
                  for h in heights}

    # --- Fig. 4f: onset frequency vs amplitude ------------------------------
    amps = np.array([0.5e-3, 1e-3, 1.5e-3]) if args.fast else np.arange(0.5e-3, 3.01e-3, 0.125e-3)
    freq_curves = {h: np.array([onset_frequency(a, h, rest, stroke) for a in amps])
                   for h in heights}

    # --- compare with the numbers quoted in the paper -----------------------
    print(f"restitution e = {rest.e:g}, stroke {stroke * 1e3:g} mm")
    print("quantity                               paper     tengfield")
    i5 = int(np.argmin(abs(freqs - 5)))
    print(f"5 Hz, 0.1 mm jump: amplitude [mm]       10.5      {amp_curves[0.1e-3][i5] * 1e3:.2f}")
    print(f"5 Hz, 0.5 mm jump: amplitude [mm]       11.0      {amp_curves[0.5e-3][i5] * 1e3:.2f}")
    for a_mm, f_paper in [(0.5, 30.0), (1.0, 19.5), (1.5, 16.0)]:
        k = int(np.argmin(abs(amps - a_mm * 1e-3)))
        print(f"{a_mm:.1f} mm, 0.5 mm jump: frequency [Hz]    {f_paper:5.1f}     "
              f"{freq_curves[0.5e-3][k]:.1f}")
    amax_c = amp_curves[0.1e-3] * (2 * np.pi * freqs) ** 2
    amax_f = amps * (2 * np.pi * freq_curves[0.1e-3]) ** 2
    print(f"smallest |a_max| = A w^2 at the 0.1 mm jump [m/s^2] (g = {G}):")
    print(f"  over frequencies (Fig. 4d)            10.363    {amax_c.min():.3f} "
          f"({freqs[np.argmin(amax_c)]:g} Hz)")
    print(f"  over amplitudes  (Fig. 4g)            10.689    {amax_f.min():.3f} "
          f"({amps[np.argmin(amax_f)] * 1e3:g} mm)")

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.5))
    ff = np.linspace(freqs[0], freqs[-1], 300)
    ax1.fill_between(ff, 0, G / (2 * np.pi * ff) ** 2 * 1e3, color="0.88", label="rest ($A\\omega^2 < g$)")
    for h, style in zip(heights, ["-o", "-s"]):
        ax1.plot(freqs, amp_curves[h] * 1e3, style, ms=4, label=f"{h * 1e3:g} mm jump")
    ax1.plot([5, 5, 30, 19.5, 16], [10.5, 11, 0.5, 1.0, 1.5], "k*", ms=9, label="paper (quoted)")
    ax1.set_yscale("log")
    ax1.set_xlabel("frequency [Hz]")
    ax1.set_ylabel("amplitude [mm]")
    ax1.set_title("Fig. 4c: jump onset vs frequency")
    ax1.legend(fontsize=8)
    ax1.grid(alpha=0.3, which="both")
    aa = np.linspace(amps[0], amps[-1], 300)
    ax2.fill_between(aa * 1e3, 0, np.sqrt(G / aa) / (2 * np.pi), color="0.88", label="rest")
    for h, style in zip(heights, ["-o", "-s"]):
        ax2.plot(amps * 1e3, freq_curves[h], style, ms=4, label=f"{h * 1e3:g} mm jump")
    ax2.plot([0.5, 1.0, 1.5], [30, 19.5, 16], "k*", ms=9, label="paper (quoted)")
    ax2.set_ylim(bottom=5.0)
    ax2.set_xlabel("amplitude [mm]")
    ax2.set_ylabel("frequency [Hz]")
    ax2.set_title("Fig. 4f: jump onset vs amplitude")
    ax2.legend(fontsize=8)
    ax2.grid(alpha=0.3)
    fig.tight_layout()
    if is_root():
        fig.savefig(out / "dynamics_jump_onset.png", dpi=130)
    print(f"wrote {out / 'dynamics_jump_onset.png'}")

    return {"onset_amplitude_mm_at_5hz": {h * 1e3: float(c[i5] * 1e3)
                                          for h, c in amp_curves.items()},
            "onset_frequency_hz_0.5mm_jump": dict(zip((amps * 1e3).tolist(),
                                                      freq_curves[0.5e-3].tolist())),
            "min_acceleration_over_frequency": float(amax_c.min()),
            "min_acceleration_over_amplitude": float(amax_f.min())}


if __name__ == "__main__":
    main()
