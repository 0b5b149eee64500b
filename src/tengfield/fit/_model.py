"""The forward model of a fit: one surrogate, dynamics re-run only when needed.

The ONLY place :mod:`tengfield.fit` reads the device as a source
(:class:`tengfield.source.Source`) and imports the electrical helpers
(``load_waveforms``, and the one peak rule: ``extreme_times``, ``extremes``,
``steady_start``).

Electrostatics is linear in the ball's charge: Q_SC, I_SC and every voltage
scale with σ while C_T does not. The surrogate is obtained once at a
reference σ_ref and :class:`ScaledCurves` multiplies its charge by σ/σ_ref,
so changing σ (or C_p, R, the time shift) never re-solves the field and
changing the restitution or the amplitude only re-runs the impact map.
"""
from __future__ import annotations

import math
from collections import OrderedDict
from typing import Callable

import numpy as np

from ..electrical import circuit_for, extreme_times, extremes, load_waveforms, steady_start
from ..source import Source
from ..surrogate import OnAxisCurves
from ..scene.schema import SURFACE_CHARGE_KEY

#: quantities a fit compares, with the waveform key per circuit kind
QUANTITIES = ("V", "Q", "I")


class ScaledCurves(OnAxisCurves):
    """``TerminalCurves`` with Q_SC and dQ_SC/dz multiplied by ``scale`` (C_T unchanged)."""

    def __init__(self, curves, scale: float):
        self._curves = curves
        self.scale = float(scale)
        self.capacitance_samples = curves.capacitance_samples
        self.stroke = curves.stroke

    def charge(self, z):
        return self.scale * self._curves.charge(z)

    def charge_derivative(self, z):
        return self.scale * self._curves.charge_derivative(z)

    def capacitance(self, z):
        return self._curves.capacitance(z)

    def capacitance_derivative(self, z):
        return self._curves.capacitance_derivative(z)


class _OnGrid:
    """A dynamics result seen on another output grid (for :func:`load_waveforms`)."""

    def __init__(self, dynamics, times):
        self.t = np.asarray(times, dtype=float)
        self.impacts = dynamics.impacts
        self._dynamics = dynamics
        self.gap, self.gap_velocity, self.table = dynamics.sample(self.t)

    def sample(self, times):
        return self._dynamics.sample(times)


def _default_simulate():
    from ..dynamics import simulate
    return simulate


def _check_record_covers(scene, settle: float, span: float, duration: float) -> None:
    """The fit runs the dynamics for ``duration`` = settle + trace span with shifts + one
    period, not for [run] duration_s: a recorded excitation too short for it is named so."""
    from ..errors import SceneError

    from ..dynamics.excitation import excitation_kind

    exc = scene.excitation
    if not excitation_kind(scene).recorded or exc.times is None or not len(exc.times):
        return
    t0, first, last = scene.initial.time, float(exc.times[0]), float(exc.times[-1])
    if t0 < first or t0 + duration > last:
        raise SceneError(f"fit: the model runs {duration:.6g} s ({settle:.6g} s of settle_periods "
                         f"/ frequency_hz, {span:.6g} s of the measured trace with its time "
                         f"shifts, one period) from {t0:g} s; the recorded excitation "
                         f"[{first:g}, {last:g}] s is shorter: give a longer record, a shorter "
                         "--measured trace or fewer [run] settle_periods")


class ForwardModel:
    """V, Q, I of ``scene`` for a set of parameter values (file units, see ``fit.spec``).

    ``curves`` is the surrogate at surface charge ``reference_sigma`` [C/m²];
    ``span`` [s] is the longest stretch of model time asked for after the
    steady-window start (trace length + largest time shift). Dynamics results
    are cached by (restitution, amplitude scale).
    """

    def __init__(self, scene, curves, reference_sigma: float, *, span: float,
                 simulate: Callable | None = None, sample_rate: float | None = None):
        if reference_sigma == 0.0:
            raise ValueError("reference_sigma must be non-zero")
        self.scene = scene
        self.curves = curves
        self.reference_sigma = float(reference_sigma)
        self.simulate = simulate or _default_simulate()
        period = scene.excitation.period
        self.window_start = scene.initial.time + steady_start(scene)
        self.duration = steady_start(scene) + span + period
        _check_record_covers(scene, steady_start(scene), span, self.duration)
        self.sample_rate = float(sample_rate or max(scene.run.sample_rate, 200.0 / period))
        self._cache: OrderedDict = OrderedDict()
        self.dynamics_runs = 0

    # -- dynamics ----------------------------------------------------------
    def dynamics(self, values: dict):
        """The trajectory for ``values`` (restitution, amplitude_scale), cached."""
        restitution = float(values.get("restitution", self.scene.contact.restitution))
        amplitude_scale = float(values.get("amplitude_scale", 1.0))
        key = (restitution, amplitude_scale)
        if key in self._cache:
            self._cache.move_to_end(key)
            return self._cache[key]
        scene = self.dynamics_scene(values)
        result = self.simulate(scene)
        self.dynamics_runs += 1
        self._cache[key] = result
        if len(self._cache) > 16:
            self._cache.popitem(last=False)
        return result

    def dynamics_scene(self, values: dict):
        """The scene the dynamics runs: long enough for the trace, fitted contact/amplitude."""
        changes = {"run": {"duration_s": self.duration, "sample_rate_hz": self.sample_rate}}
        if "restitution" in values:
            changes["contact"] = {"restitution": float(values["restitution"])}
        if "amplitude_scale" in values:
            changes["excitation"] = {"amplitude_mm": self.scene.excitation.amplitude * 1e3
                                     * float(values["amplitude_scale"])}
        return self.scene.with_values(**changes)

    def charge_scale(self, values: dict) -> float:
        sigma = values.get(SURFACE_CHARGE_KEY)
        sigma = self.scene.device.surface_charge if sigma is None else float(sigma) * 1e-6
        return sigma / self.reference_sigma

    def circuit(self, values: dict) -> tuple[float, float]:
        """(C_p [F], R [ohm]) for ``values``."""
        c_p = values.get("parallel_capacitance_pF")
        c_p = self.scene.circuit.parallel_capacitance if c_p is None else float(c_p) * 1e-12
        load = values.get("load_ohm")
        return c_p, self.scene.circuit.load if load is None else float(load)

    # -- waveforms ---------------------------------------------------------
    def model_times(self, times, shift: float) -> np.ndarray:
        """Model time of measured samples ``times`` [s]: the trace starts ``shift`` [s]
        after the steady-window start."""
        t = np.asarray(times, dtype=float)
        return self.window_start + (t - t[0]) + shift

    def waveforms(self, values: dict, model_times, quantities=QUANTITIES, *,
                  readings: bool = False) -> dict:
        """{quantity: array [SI]} at ``model_times`` (ascending) for ``values``: what the
        scene's ``[instrument]`` records when it has one that is not ideal (bandwidth and
        aperture; its sample rate too with ``readings``, the scalar targets' case: a
        measured trace's own samples are the instrument's readings), else
        :meth:`terminal`."""
        inst = self.scene.instrument
        if not inst.given or inst.ideal:
            return self.terminal(values, model_times, quantities)
        import dataclasses

        from ..electrical.instrument import Chain, time_constant
        t = np.asarray(model_times, dtype=float)
        rate = inst.sample_rate if readings else 0.0
        lead = 10.0 * time_constant(inst.bandwidth) + inst.aperture + (1.0 / rate if rate else 0.0)
        own = np.asarray(self.dynamics(values).t, dtype=float)
        grid = np.union1d(own[(own >= t[0] - lead) & (own <= t[-1])], t)
        raw = self.terminal(values, grid, quantities)
        where = np.searchsorted(grid, t)
        reader = dataclasses.replace(inst, sample_rate=rate, input_resistance=0.0)
        return {q: Chain(reader)(grid, x)[where] for q, x in raw.items()}

    def terminal(self, values: dict, model_times, quantities=QUANTITIES) -> dict:
        """{quantity: array [SI]} of the terminal at ``model_times`` (ascending).

        Open or short circuit: V is what an instrument of capacitance C_p reads,
        Q_SC / (C_T + C_p); Q = Q_SC; I = I_SC. ``[circuit] kind = "load"``: V and I
        are the load's voltage and current (the load ODE is integrated from the start
        of the dynamics so its start-up transient has settled), Q = Q_SC.
        """
        dynamics = self.dynamics(values)
        curves = ScaledCurves(self.curves, self.charge_scale(values))
        c_p, load = self.circuit(values)
        t = np.asarray(model_times, dtype=float)
        gap, velocity, _ = dynamics.sample(t)
        cells = self.scene.device.cells
        terminal = Source(curves, cells=cells, parallel_capacitance=c_p).terminal(None, gap,
                                                                                  velocity)
        out = {"V": terminal["V_read"], "Q": terminal["Q_sc"], "I": terminal["I_sc"]}
        if circuit_for(self.scene).fit_load and ({"V", "I"} & set(quantities)):
            out.update(self._load(dynamics, curves, c_p, load, t))
        return {q: np.asarray(out[q], dtype=float) for q in quantities}

    def _load(self, dynamics, curves, c_p, load, t) -> dict:
        start = float(dynamics.t[0])
        period = self.scene.excitation.period
        n_before = int(math.ceil((t[0] - start) / period * 200.0))
        before = np.linspace(start, t[0], n_before + 1)[:-1] if t[0] > start else np.empty(0)
        grid = np.concatenate([before, t])
        scene = self.scene.with_values(circuit={"load_ohm": load,
                                                "parallel_capacitance_pF": c_p * 1e12})
        result = load_waveforms(scene, _OnGrid(dynamics, grid), curves, window_start=float(t[0]))
        return {"V": result["V_load"][before.size:], "I": result["I_load"][before.size:]}

    def scalars(self, values: dict) -> dict:
        """Peak-to-peak and peak |x| of V, Q, I over the steady window [SI].

        Samples: the dynamics' own output grid in the window plus just before and
        after every impact (where I_SC jumps and takes its extremes): the rule of
        :func:`tengfield.electrical.terminal_peaks` (:func:`~tengfield.electrical.extremes`).
        """
        grid = extreme_times(self.scene, self.dynamics(values), self.window_start)
        out = {}
        for q, x in self.waveforms(values, grid, readings=True).items():
            out[f"{q}_pp"], out[f"{q}_peak"] = extremes(x)
        return out
