"""Parameter sweeps: one surrogate, many excitations and loads (paper Figs. 9e-f, S13).

:func:`sweep_point` simulates one excitation and reports the same
peak-to-peak values as ``tengfield run`` (:func:`tengfield.electrical.terminal_peaks`:
steady window, samples and impact instants) and the mean power into each
load; :func:`sweep` runs it over a frequency x amplitude grid in worker
processes. ``tengfield.io.write_sweep_csv`` writes the rows.
"""
from __future__ import annotations

import sys
from typing import Callable

from . import electrical
from ._json import regime_dict

#: columns of ``sweep.csv`` (one row per grid point and load)
SWEEP_COLUMNS = ["frequency_hz", "amplitude_mm", "load_ohm", "regime", "period",
                 "V_oc_pp_V", "Q_sc_pp_C", "I_sc_pp_A", "P_mean_W", "power_density_W_per_m3"]


def _default_simulate():
    from .dynamics import simulate
    return simulate


def sweep_point(scene, table, frequency: float, amplitude: float,
                loads=(), simulate: Callable | None = None) -> list[dict]:
    """Peak-to-peak V_OC, Q_SC, I_SC at one excitation (frequency [Hz],
    amplitude [m]) and the mean power into each load [ohm] (steady window).

    ``table``: the scene's :class:`tengfield.surrogate.SurrogateTable`. One
    row per load (``load_ohm`` None and no power without loads).
    """
    from .surrogate import TerminalCurves

    simulate = simulate or _default_simulate()
    point = scene.with_values(excitation={"frequency_hz": float(frequency),
                                          "amplitude_mm": float(amplitude) * 1e3})
    dynamics = simulate(point)
    curves = TerminalCurves(table, point.circuit.reference)
    peaks = electrical.terminal_peaks(point, dynamics, curves)
    regime = regime_dict(dynamics.regime) or {}
    base = {"frequency_hz": float(frequency), "amplitude_mm": float(amplitude) * 1e3,
            "regime": regime.get("regime", ""), "period": regime.get("period", 0),
            "V_oc_pp_V": peaks["V_oc"], "Q_sc_pp_C": peaks["Q_sc"], "I_sc_pp_A": peaks["I_sc"]}
    if not len(loads):
        return [{**base, "load_ohm": None, "P_mean_W": None, "power_density_W_per_m3": None}]
    rows = []
    volume = point.device.cell_volume * point.device.cells
    for load in loads:
        loaded = point.with_values(circuit={"kind": "load", "load_ohm": float(load)})
        result = electrical.steady_load(loaded, dynamics, curves)
        rows.append({**base, "load_ohm": float(load), "P_mean_W": result["mean_power_W"],
                     "power_density_W_per_m3": result["mean_power_W"] / volume})
    return rows


def _sweep_task(args):
    return sweep_point(*args)


def sweep(scene, table, frequencies, amplitudes, loads=(), *,
          jobs: int | None = None, progress: bool = False) -> list[dict]:
    """:func:`sweep_point` over the grid ``frequencies`` [Hz] x ``amplitudes`` [m],
    in ``jobs`` worker processes (default: all cores), with a progress bar
    (stderr, only when it is a terminal)."""
    import multiprocessing
    import os
    from concurrent.futures import ProcessPoolExecutor

    from tqdm import tqdm

    # validate every grid scene first: a bad point fails before any work starts
    for f in frequencies:
        for a in amplitudes:
            scene.with_values(excitation={"frequency_hz": float(f), "amplitude_mm": float(a) * 1e3})
    tasks = [(scene, table, float(f), float(a), tuple(loads)) for f in frequencies for a in amplitudes]
    jobs = max(1, min(jobs or os.cpu_count() or 1, len(tasks)))
    bar = tqdm(total=len(tasks), desc="sweep", unit="point", file=sys.stderr,
               disable=not (progress and sys.stderr.isatty()))
    rows: list[dict] = []
    if jobs == 1:
        for task in tasks:
            rows.extend(_sweep_task(task))
            bar.update()
    else:
        context = multiprocessing.get_context("spawn")  # safe after MPI/dolfinx initialisation
        with ProcessPoolExecutor(max_workers=jobs, mp_context=context) as pool:
            for result in pool.map(_sweep_task, tasks):
                rows.extend(result)
                bar.update()
    bar.close()
    return rows
