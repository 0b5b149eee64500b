"""What the contact charge model gives against the reference paper's two observations it
was built to examine (docs/charge.md, "Against the paper"): the onset of output with
frequency at 1.5 mm (the paper: no output below 16 Hz, lift-off at 12.9 Hz), and the
current against the stroke at 35 Hz / 1.5 mm (the paper: Q_SC saturates at 3 mm, the
current falls at 4-5 mm). Literature constants, not tuned: sigma_eq = -113 µC/m^2, eta = 1,
the cap at the breakdown band's estimate, tau = 0 / 10 / 60 s (none, and "minutes in
humid air").

    .venv/bin/python benchmarks/charge_against_paper.py        # ~1 min, cached field

Prints one table per study: the run's (4 s) peak-to-peak V_OC, the steady charge its
contacts make and the time to 90 % of it.
"""
from __future__ import annotations

import numpy as np

import tengfield as tf
from tengfield.sweeps import sweep_study


def onset(tau: float) -> None:
    scene = tf.default_scene().with_values(run={"duration_s": 4.0}, charge={
        "model": "contact", "leakage_time_s": tau})
    rows = sweep_study(scene, frequencies=np.arange(12.0, 25.0), amplitudes=[1.5e-3])
    print(f"\nonset at 1.5 mm, tau = {tau:g} s")
    print(" f [Hz]  regime            V_oc_pp [V]  sigma_steady [uC/m^2]  rise_90 [s]")
    for r in rows:
        rise = r["rise_time_90_s"]
        print(f"{r['frequency_hz']:6.0f}  {r['regime']:16s}  {r['V_oc_pp_V']:11.4g}  "
              f"{r['sigma_steady_uC_per_m2'] or 0.0:21.4g}  "
              f"{'-' if rise is None else format(rise, '.3g'):>11s}")


def stroke(model: str) -> None:
    scene = tf.default_scene().with_values(
        run={"duration_s": 4.0}, excitation={"frequency_hz": 35.0, "amplitude_mm": 1.5},
        charge={"model": model, **({"leakage_time_s": 60.0} if model == "contact" else {})})
    rows = sweep_study(scene, vary={"device.stroke_mm": [1.0, 2.0, 3.0, 4.0, 5.0]})
    print(f"\nstroke at 35 Hz / 1.5 mm, [charge] model = {model!r}")
    print(" dh [mm]  Q_sc_pp [nC]  I_sc_peak [nA]  sigma_steady [uC/m^2]")
    for r in rows:
        sigma = r.get("sigma_steady_uC_per_m2")
        print(f"{r['device.stroke_mm']:7.0f}  {r['Q_sc_pp_C'] * 1e9:12.4g}  "
              f"{r['I_sc_peak_A'] * 1e9:14.4g}  "
              f"{'-' if sigma is None else format(sigma, '.4g'):>21s}")


for tau in (0.0, 10.0, 60.0):
    onset(tau)
for model in ("contact", "constant"):
    stroke(model)
