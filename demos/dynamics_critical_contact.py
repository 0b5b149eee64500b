"""Critical contact (the paper's Fig. 6): the ball just reaches the upper plate.

Only when the ball touches both electrodes is the full short-circuit charge
transferred. The paper's ADAMS model reaches the upper plate at 10 Hz from
an amplitude of 4.1 mm: the ball is flung off the lower plate when the
table's acceleration passes -g, with the launch speed of Eq. (10)
(0.205 m/s) and flies 0.037 s up to the upper plate. Fig. 6d shows this
contact onset at other frequencies. Here:

* the contact onset amplitude at each frequency (smallest amplitude whose
  run from rest reaches the upper plate), with the lift-off curve A w^2 = g;
* at 10 Hz: the onset amplitude, the launch speed and the flight time.

    .venv/bin/python demos/dynamics_critical_contact.py [--fast] [-o DIR]
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from tengfield.dynamics import simulate
from tengfield.dynamics.impact import Restitution
from tengfield.dynamics.onset import onset_amplitude
from tengfield.scene import G, default_scene

from demo_mpi import is_root


def launch_speed_eq10(amplitude: float, frequency: float) -> float:
    """Eq. (10): table (= ball) speed when y'' = -g, v0 = sqrt(A^2 w^4 - g^2) / w [m/s]."""
    w = 2 * math.pi * frequency
    return math.sqrt(max(amplitude**2 * w**4 - G**2, 0.0)) / w


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fast", action="store_true", help="coarse onset curve")
    ap.add_argument("-o", "--output", default="demos/out", help="output directory")
    args = ap.parse_args(argv)
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)

    base = default_scene()
    stroke = base.device.stroke
    rest = Restitution.from_contact(base.contact)

    # --- the onset curve of Fig. 6d ------------------------------------------
    freqs = np.array([10.0, 30.0, 50.0]) if args.fast else np.arange(10.0, 50.1, 2.5)
    onset = np.array([onset_amplitude(f, stroke, rest, stroke) for f in freqs])

    # --- the 10 Hz example of Figs. 6a-c -------------------------------------
    scene = base.with_values(excitation={"amplitude_mm": 4.1, "frequency_hz": 10.0},
                             run={"duration_s": 1.0, "settle_periods": 5})
    res = simulate(scene)
    w = scene.excitation.omega
    gamma = scene.excitation.gamma
    t_lift = math.asin(1 / gamma) / w                    # first lift-off (table at y=0 at t=0)
    first_upper = res.impacts.time[res.impacts.plate == "upper"]
    flight = first_upper[0] - t_lift if first_upper.size else math.nan
    v0 = launch_speed_eq10(4.1e-3, 10.0)
    print(f"restitution e = {rest.e:g}, stroke {stroke * 1e3:g} mm")
    print("quantity                                   paper     tengfield")
    print(f"contact onset amplitude at 10 Hz [mm]      4.1       {onset[0] * 1e3:.2f}")
    print(f"launch speed at 10 Hz, 4.1 mm [m/s]        0.205     {v0:.3f}  (Eq. 10)")
    print(f"flight lower -> upper plate [s]            0.037     {flight:.4f}")
    print(f"regime at 10 Hz, 4.1 mm                    critical  {res.regime.name} "
          f"(period {res.regime.period})")
    print("contact onset amplitude [mm] and launch speed (Fig. 6e) [m/s]:")
    for f, a in zip(freqs, onset):
        print(f"  {f:5.1f} Hz  {a * 1e3:6.3f} mm  v0 = {launch_speed_eq10(a, f):.3f}")

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.8))
    keep = res.t <= 0.45
    ax1.plot(res.t[keep], res.table[keep] * 1e3, color="0.35", label="lower plate")
    ax1.plot(res.t[keep], (res.table[keep] + stroke) * 1e3, "--", color="0.6", label="upper plate")
    ax1.plot(res.t[keep], (res.table[keep] + res.gap[keep]) * 1e3, color="#d62728", label="ball")
    if first_upper.size:
        ax1.axvspan(t_lift, first_upper[0], color="#2ca02c", alpha=0.12,
                    label=f"flight {flight * 1e3:.1f} ms")
    ax1.set_xlabel("time [s]")
    ax1.set_ylabel("position [mm]")
    ax1.set_title("Fig. 6a-c: 10 Hz, 4.1 mm")
    ax1.legend(fontsize=8)
    ax1.grid(alpha=0.3)
    ff = np.linspace(freqs[0], freqs[-1], 300)
    ax2.fill_between(freqs, 0, onset * 1e3, color="#fdd0a2", label="no upper contact")
    ax2.plot(freqs, onset * 1e3, "o-", color="#e6550d", ms=4, label="contact onset (tengfield)")
    ax2.plot(ff, G / (2 * np.pi * ff) ** 2 * 1e3, "k-", lw=1, label=r"lift-off $A\omega^2=g$")
    ax2.plot([10], [4.1], "k*", ms=10, label="paper: 10 Hz, 4.1 mm")
    ax2.set_xlabel("frequency [Hz]")
    ax2.set_ylabel("amplitude [mm]")
    ax2.set_title("Fig. 6d: onset of the critical contact")
    ax2.legend(fontsize=8)
    ax2.grid(alpha=0.3)
    fig.tight_layout()
    if is_root():
        fig.savefig(out / "dynamics_critical_contact.png", dpi=130)
    print(f"wrote {out / 'dynamics_critical_contact.png'}")

    return {"onset_amplitude_mm": dict(zip(freqs.tolist(), (onset * 1e3).tolist())),
            "launch_speed_m_per_s": v0, "flight_s": float(flight), "regime": res.regime.name}


if __name__ == "__main__":
    main()
