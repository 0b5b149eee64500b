"""Synthetic traces for the fit tests (helpers, no tests): made by the tool with known parameters."""
from __future__ import annotations

import numpy as np

from tengfield.fit._model import ForwardModel
from tengfield.fit.spec import Column, Trace

#: the parameters the synthetic traces are made with (file units)
TRUE = {"surface_charge_uC_per_m2": -30.0, "parallel_capacitance_pF": 100.0, "restitution": 0.1}
SHIFT = 0.0123          # [s], unknown to the fit
UNITS = {"V": ("V", 1.0), "Q": ("nC", 1e-9), "I": ("nA", 1e-9)}


def trace_scene(parameters: str) -> str:
    """The scene text the trace-fit CLI tests share (V and Q columns in V and nC, time in
    ms, C_p = 100 pF, a 1 s run), with ``parameters`` as its ``[fit.parameters]`` lines."""
    return ("\n[run]\nduration_s = 1.0\nsettle_periods = 10\n\n[instrument]\n"
            "capacitance_pF = 100.0\n\n[fit]\ntime_column = \"time_ms\"\n"
            "time_unit = \"ms\"\n\n[fit.columns.V]\ncolumn = \"V_meas\"\nunit = \"V\"\n\n"
            "[fit.columns.Q]\ncolumn = \"Q_meas\"\nunit = \"nC\"\n\n[fit.parameters]\n"
            + parameters)


def synthetic(scene, surrogate, seed, quantities=("V", "Q"), *, true=TRUE, shift=SHIFT,
              white=0.01, hum=0.01, duration=0.5, rate=5000.0, start=3.7):
    """A trace made by the tool: ``true`` parameters, the trace starting ``shift`` after the
    steady-window start, white noise and 50 Hz hum (each a fraction of the peak-to-peak)."""
    curves, sigma_ref = surrogate
    rng = np.random.default_rng(seed)
    t = start + np.arange(int(duration * rate)) / rate
    model = ForwardModel(scene, curves, sigma_ref, span=duration + 0.2)
    clean = model.waveforms(true, model.model_times(t, shift), quantities)
    values = {}
    for q in quantities:
        pp = float(np.ptp(clean[q]))
        values[q] = (clean[q] + white * pp * rng.standard_normal(t.size)
                     + hum * pp * np.sin(2 * np.pi * 50.0 * t + rng.uniform(0, 2 * np.pi)))
    columns = [Column(q, q, "V" if q == "V" else "C" if q == "Q" else "A", None)
               for q in quantities]
    return Trace(f"synthetic seed {seed}", t, values, columns), clean


def write_csv(path, trace, units=UNITS):
    """The trace as a CSV with columns time_ms, V_meas [V], Q_meas [nC], I_meas [nA]."""
    names = ["time_ms"] + [f"{q}_meas" for q in trace.values]
    data = [trace.time * 1e3] + [trace.values[q] / units[q][1] for q in trace.values]
    np.savetxt(path, np.column_stack(data), delimiter=",", header=",".join(names),
               comments="", fmt="%.10g")
    return path
