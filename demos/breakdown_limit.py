"""Air breakdown: the largest charge density the paper's devices can hold, and their output there.

The ball's surface charge density σ is the one number the model cannot compute from
first principles, and every charge, current and voltage scales with it. The air in the
gaps between the ball and the electrodes caps it: once the voltage across a gap exceeds
Paschen's breakdown voltage of that gap, the gap discharges. ``tengfield breakdown``
takes the gap voltages per unit σ from the field solves of the surrogate (along lines
from the ball surface to each electrode, at every sampled position, in each circuit
state) and gives σ_max (docs/breakdown.md).

This demo

* gives σ_max for the paper's device (7 mm ball, Δh = 3 mm) and for the honeycomb
  cell of Fig. 10 (5 mm ball, Δh = 2 mm; the equal-area cylindrical cell, axisymmetric),
  and the outputs at σ = −σ_max read through the instruments the measurements imply
  (C_p = 338 pF and 321 pF, docs/demos.md), beside the paper's readings;
* sweeps σ_max over the stroke Δh and the ball diameter d of the paper's device family
  (Figs. 9g–h: 35 Hz, 1.5 mm) and gives the breakdown-limited output there.

    .venv/bin/python demos/breakdown_limit.py [--fast] [-o DIR] [--cache-dir DIR]
"""
from __future__ import annotations

import sys
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from electrical_common import (demo_arguments, paper_scene, pyplot,  # noqa: E402
                               run_length, save_small_png)
from demo_mpi import world  # noqa: E402
from electrical_geometry import device_for  # noqa: E402

PAPER = {"device": {"Q_sc": 1.42e-9, "V_oc": 4.2, "I_sc": 0.16e-6, "sigma_fit": -35.8e-6,
                    "C_p": 338e-12},
         "honeycomb": {"Q_sc": 153.14e-9, "V_oc": 342.56, "I_sc": 26.72e-6, "sigma_fit": -37.9e-6,
                       "C_p": 321e-12}}


def at_limit(scene, cache_dir) -> dict:
    """``tengfield run`` of ``scene`` with σ = "breakdown": σ_max and the peaks there."""
    from tengfield.pipeline import run

    scene = scene.with_values(device={"surface_charge_uC_per_m2": "breakdown"})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        r = run(scene, cache_dir=cache_dir, comm=world())
    block = r.summary["breakdown"]
    i_abs = np.abs(np.asarray(r.I_sc))
    return {"sigma_max": block["sigma_max_uC_per_m2"] * 1e-6,
            "error": block["relative_error_estimate"], "binding": block["binding"],
            "Q_sc": r.peaks["Q_sc"], "V_oc": r.peaks.get("V_read", r.peaks["V_oc"]),   # the reading
            "I_sc": r.peaks["I_sc"],
            "I_peak": float(np.max(i_abs)), "regime": r.summary["regime"]["regime"]}


def honeycomb(fast: bool):
    from electrical_honeycomb import honeycomb_scene
    _, scene = honeycomb_scene(fast)
    return scene


def main(argv: list[str] | None = None) -> dict:
    args = demo_arguments(__doc__, argv)
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    fast = args.fast
    numbers: dict = {}

    # the paper's device (Figs. 8-9: 1.5 mm, 20 Hz) and the honeycomb (Fig. 10: 0.5 mm, 33 Hz)
    device = paper_scene(fast).with_values(
        excitation={"frequency_hz": 20.0, "amplitude_mm": 1.5}, run=run_length(20.0, fast),
        circuit={"parallel_capacitance_pF": PAPER["device"]["C_p"] * 1e12})
    comb = honeycomb(fast).with_values(
        circuit={"parallel_capacitance_pF": PAPER["honeycomb"]["C_p"] * 1e12})
    for name, scene in (("device", device), ("honeycomb", comb)):
        res = at_limit(scene, args.cache_dir)
        numbers[name] = res
        paper = PAPER[name]
        print(f"{name}: sigma_max = {res['sigma_max'] * 1e6:.3g} uC/m2 (+-{res['error']:.1%}; "
              f"binds {res['binding']['state']}, {res['binding']['gap']} gap "
              f"{res['binding']['gap_length_m'] * 1e3:.3g} mm); the paper's readings need "
              f"{-paper['sigma_fit'] * 1e6:.3g}. At the limit: Q_SC {res['Q_sc'] * 1e9:.4g} nC "
              f"(paper {paper['Q_sc'] * 1e9:.4g}), V read through C_p {res['V_oc']:.4g} V "
              f"(paper {paper['V_oc']:.4g}), I_SC {res['I_sc'] * 1e6:.4g} uA pp, "
              f"|I| {res['I_peak'] * 1e6:.4g} uA (paper {paper['I_sc'] * 1e6:.4g})")

    # the device family of Figs. 9g-h (35 Hz, 1.5 mm)
    strokes = (1.0, 3.0, 5.0) if fast else (1.0, 2.0, 3.0, 4.0, 5.0)
    diameters = (5.0, 7.0) if fast else (5.0, 6.35, 7.0, 8.0, 10.0)
    family = paper_scene(fast).with_values(
        excitation={"frequency_hz": 35.0, "amplitude_mm": 1.5}, run=run_length(35.0, fast),
        circuit={"parallel_capacitance_pF": PAPER["device"]["C_p"] * 1e12})
    sweep = {"stroke": [], "diameter": []}
    for key, values in (("stroke", strokes), ("diameter", diameters)):
        for v in values:
            dims = device_for(7.0, v) if key == "stroke" else device_for(v, 3.0)
            res = at_limit(family.with_values(device=dims), args.cache_dir)
            sweep[key].append((v, res))
            print(f"  {key} {v:g} mm: sigma_max {res['sigma_max'] * 1e6:.3g} uC/m2 "
                  f"({res['binding']['state']}, {res['binding']['gap']} gap "
                  f"{res['binding']['gap_length_m'] * 1e3:.3g} mm), Q_SC {res['Q_sc'] * 1e9:.3g} nC,"
                  f" V read {res['V_oc']:.3g} V, {res['regime']}")
    numbers["sweep"] = sweep

    plt = pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(13, 4.0), layout="constrained")
    for ax, key, label in ((axes[0], "stroke", "stroke Δh [mm] (d = 7 mm)"),
                           (axes[1], "diameter", "ball diameter d [mm] (Δh = 3 mm)")):
        x = [v for v, _ in sweep[key]]
        ax.plot(x, [r["sigma_max"] * 1e6 for _, r in sweep[key]], "o-", label="σ_max (this model)")
        ax.axhline(-PAPER["device"]["sigma_fit"] * 1e6, color="k", ls="--",
                   label="σ the paper's 1.42 nC needs")
        ax.axhline(8.0, color="0.5", ls=":", label="σ of the paper's COMSOL model")
        ax.set_xlabel(label)
        ax.set_ylabel("σ_max [µC/m²]")
        ax.set_ylim(0, None)
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
    ax = axes[2]
    for key, marker in (("stroke", "o"), ("diameter", "s")):
        x = [v for v, _ in sweep[key]]
        ax.plot(x, [r["V_oc"] for _, r in sweep[key]], marker + "-",
                label=f"V read (C_p 338 pF) vs {'Δh' if key == 'stroke' else 'd'}")
    ax2 = ax.twinx()
    for key, marker in (("stroke", "o"), ("diameter", "s")):
        x = [v for v, _ in sweep[key]]
        ax2.plot(x, [r["Q_sc"] * 1e9 for _, r in sweep[key]], marker + ":", color="tab:red")
    ax.set_xlabel("Δh or d [mm]")
    ax.set_ylabel("V read at σ_max [V]")
    ax2.set_ylabel("Q_SC at σ_max [nC] (dotted)", color="tab:red")
    ax.legend(fontsize=7, loc="upper left")
    ax.set_title("breakdown-limited output, Figs. 9g-h (35 Hz, 1.5 mm)", fontsize=9)
    fig.suptitle(f"air breakdown: σ_max = {numbers['device']['sigma_max'] * 1e6:.3g} µC/m² "
                 f"(paper's device), {numbers['honeycomb']['sigma_max'] * 1e6:.3g} µC/m² "
                 "(honeycomb cell)", fontsize=10)
    png = save_small_png(fig, out / "breakdown_limit.png")
    plt.close(fig)
    print(f"wrote {png}")
    return numbers


if __name__ == "__main__":
    main()
