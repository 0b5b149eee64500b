"""Shared pieces of the electrical demos (not a demo itself).

* :func:`demo_arguments`: ``--fast``, ``-o DIR``, ``--cache-dir DIR``.
* :func:`field_settings`: the ``[field]`` keys of a demo (coarse in fast mode).
* :func:`surrogate_curves`: build (or reuse from the cache) the surrogate of a scene.
* :func:`measure`: the peaks ``tengfield run`` reports, and the waveforms to plot.
* :func:`electrometer`: the instrument capacitance C_p and the surface charge σ
  that reconcile the ideal model with the paper's electrometer readings.

Units are SI inside; printed numbers carry their unit.
"""
from __future__ import annotations

import argparse
import math
import os
import sys
import warnings
from pathlib import Path

import numpy as np

from demo_mpi import is_root, world

from tengfield import electrical

#: The paper's measured peaks at 1.5 mm / 20 Hz (Figs. 9b-d): V_OC, Q_SC, I_SC.
PAPER_PEAKS = {"V_oc": 4.2, "Q_sc": 1.42e-9, "I_sc": 0.16e-6}


def demo_arguments(doc: str, argv: list[str] | None = None) -> argparse.Namespace:
    """The demo's options from ``argv`` (default: the command line)."""
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--fast", action="store_true", help="coarse fields and short runs (CI)")
    ap.add_argument("-o", "--output", default="demos/out", help="output directory")
    ap.add_argument("--cache-dir", default=None,
                    help="surrogate cache (default: tengfield's cache directory)")
    args = ap.parse_args(argv)
    Path(args.output).mkdir(parents=True, exist_ok=True)
    return args


def field_settings(fast: bool) -> dict:
    """``[field]`` keys: fast = degree 1 at 1 mm (a few per cent), full = the defaults (1e-3)."""
    if fast:
        return {"degree": 1, "mesh_size_mm": 1.0, "tolerance": 0.03}
    return {"degree": 2, "mesh_size_mm": 0.5, "tolerance": 1e-3}


def _solve_without_estimate(scene, z, comm):
    """The field solve of ``tengfield run`` without the a-posteriori estimate
    (the same numbers, a quarter of the cost; the demos state accuracy via the report)."""
    from tengfield.field import solve_position
    return solve_position(scene, z, comm=comm, estimate_error=False)


def surrogate_curves(scene, cache_dir=None, solve=None):
    """``(table, curves)`` of ``scene`` (cached by its field hash)."""
    from tengfield.surrogate import TerminalCurves, obtain_table

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        table, outcome = obtain_table(scene, cache_dir=cache_dir, comm=world(),
                                      solve=solve or _solve_without_estimate)
    print(f"  surrogate: {table.count} positions ({outcome.status}), "
          f"interpolation error estimate {table.interpolation_error:.2g}", file=sys.stderr)
    return table, TerminalCurves(table, scene.circuit.reference, scene.device.ball_charge)


def measure(curves, dynamics, scene, *, parallel_capacitance: float | None = None) -> dict:
    """What ``tengfield run`` reports for ``scene`` read through an instrument of
    capacitance ``parallel_capacitance`` C_p [F] (default: the scene's): peak-to-peak
    ``V_oc`` [V], ``Q_sc`` [C], ``I_sc`` [A] (:func:`tengfield.electrical.terminal_peaks`:
    steady window, samples and impact instants), and for the plots the sampled
    ``waveforms``, the steady-window ``mask`` and ``C_T_max`` [F] over it. ``V_oc`` here
    is what the instrument reads (tengfield's ``V_read``; the ideal V_OC when C_p = 0)."""
    if parallel_capacitance is not None:
        scene = scene.with_values(circuit={"parallel_capacitance_pF": parallel_capacitance * 1e12})
    wf = electrical.scene_terminal_waveforms(scene, curves, dynamics.gap, dynamics.gap_velocity)
    wf["V_oc"] = wf["V_read"]
    mask, _ = electrical.steady_window(dynamics.t, scene)
    peaks = electrical.terminal_peaks(scene, dynamics, curves)
    peaks["V_oc"] = peaks.pop("V_read", peaks["V_oc"])
    return {**peaks, "C_T_max": float(np.max(wf["C_T"][mask])), "waveforms": wf, "mask": mask}


def reconciling_capacitance(charge_pp: float, voltage_measured: float, c_t: float) -> float:
    """C_p [F] with ``charge_pp / (C_T + C_p) = voltage_measured`` (≥ 0).

    An electrometer in voltage mode loads the floating pair with its input
    and cable capacitance C_p, so it reads ``Q_SC / (C_T + C_p)`` instead of
    V_OC = Q_SC / C_T; in charge mode (a short circuit) it reads Q_SC itself.
    """
    return max(0.0, charge_pp / voltage_measured - c_t)


def reconciling_charge_density(sigma: float, charge_model: float, charge_measured: float) -> float:
    """σ [C/m²] that makes the model's Q_SC equal the measured one (Q_SC ∝ σ)."""
    return sigma * charge_measured / charge_model


def save_small_png(fig, path: Path, dpi: int = 90) -> Path:
    """Save ``fig`` to ``path`` under 300 kB (rank 0 only under mpirun)."""
    if not is_root():
        return path
    fig.savefig(path, dpi=dpi)
    size = os.path.getsize(path)
    if size > 300_000:
        fig.savefig(path, dpi=int(dpi * math.sqrt(280_000 / size)))
    return path


def pyplot():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def paper_scene(fast: bool):
    """The default scene (paper's device) with the demo's field settings."""
    from tengfield.scene import default_scene
    return default_scene().with_values(field=field_settings(fast))


def run_length(frequency: float, fast: bool) -> dict:
    """``[run]`` keys: settle then measure a whole number of periods at ``frequency`` [Hz]."""
    settle, window = (6, 6) if fast else (15, 15)
    return {"duration_s": (settle + window) / frequency, "settle_periods": settle,
            "sample_rate_hz": 20000.0 if fast else 50000.0}


def reconcile(curves, fast: bool) -> tuple[float, float]:
    """``(charge_scale, C_p)`` at 1.5 mm / 20 Hz on the paper's device:
    σ_fit/σ from the charge-mode reading (1.42 nC) and the instrument
    capacitance [F] that turns the ideal V_OC into the 4.2 V read."""
    from tengfield.dynamics import simulate

    scene = paper_scene(fast).with_values(run=run_length(20.0, fast))
    ideal = measure(curves, simulate(scene), scene)
    scale = PAPER_PEAKS["Q_sc"] / ideal["Q_sc"]
    return scale, reconciling_capacitance(ideal["Q_sc"] * scale, PAPER_PEAKS["V_oc"],
                                          ideal["C_T_max"])
