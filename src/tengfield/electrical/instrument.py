"""What the bench's instrument records (``[instrument]``, issue #39).

An electrometer or a scope does not show the terminal's waveforms as they are: it
reads through its own capacitance C_p and input resistance R_in, its analog front end
has a finite bandwidth, each reading integrates over an aperture and the readings
come at its own sample rate. :class:`Reader` turns the terminal's columns into the
read ones, in this order:

1. the voltage across the instrument: Q_SC / (C_T + C_p) with R_in infinite (or the
   connected circuit's voltage, ``read_column``); with a finite R_in across an open
   terminal the instrument is the load R_in || C_p (:func:`tengfield.lumped.load_response`).
   Charge and current are read in short circuit (a virtual-ground input: Q_SC, I_SC);
2. a first-order low-pass of bandwidth f_c (τ = 1 / (2π f_c)), integrated exactly for
   an input linear between samples (:class:`FirstOrder`);
3. the mean over the aperture T_a before each instant (:class:`Aperture`);
4. a reading at every 1 / f_s on the run's own axis (k / f_s, k = 0, 1, ...), held until
   the next one (:class:`SampleHold`): the columns keep the run's rows, and their
   extremes are those of the readings.

Every stage carries its state from one call to the next, so a long run read a chunk at
a time (:mod:`tengfield.electrical.stream`) gives the numbers of the whole run read at
once. With every ``[instrument]`` key 0 but C_p (an ideal instrument) the read columns
are the terminal's own: ``V_read`` = Q_SC / (C_T + C_p), ``Q_read`` = Q_SC, ``I_read`` = I_SC.

Units SI; signs those of :mod:`tengfield.terminals`.
"""
from __future__ import annotations

import math

import numpy as np

from .. import lumped

#: the read columns: short name -> (the waveforms column, the terminal column it reads)
READ_COLUMNS = {"V_read": ("V_read_V", "V_read_V"), "Q_read": ("Q_read_C", "Q_sc_C"),
                "I_read": ("I_read_A", "I_sc_A")}


def time_constant(bandwidth: float) -> float:
    """τ = 1 / (2π f_c) [s] of a first-order low-pass of bandwidth ``f_c`` [Hz] (0: none)."""
    return 0.0 if bandwidth <= 0.0 else 1.0 / (2.0 * math.pi * bandwidth)


class FirstOrder:
    """τ dy/dt = x - y, integrated exactly for x linear between samples: over a step h,
    u = h / τ,

        y1 = e^(-u) y0 + u ψ(u) x0 + u (φ1(u) - ψ(u)) x1,

    φ1(u) = (1 - e^(-u)) / u, ψ(u) = (1 - e^(-u) (1 + u)) / u² (the load's exponential
    integrator, :func:`tengfield.lumped.load_response`, with its cancellation-free φ1 and
    ψ): the same as y1 = x1 - s τ + (y0 - x0 + s τ) e^(-u) with s = (x1 - x0) / h, without
    cancelling s τ against s τ e^(-u) (at f_c = 1e-9 Hz that form lost 1e-4 of the input).
    A step of zero length (a jump of x) keeps y. Starts at rest on the first input
    (y = x: the instrument has been reading the device in its reference state).
    ``tau`` = 0: y = x."""

    def __init__(self, tau: float):
        self.tau = float(tau)
        self.last = None            # (t, x, y) of the previous sample

    def __call__(self, t, x) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        x = np.asarray(x, dtype=float)
        if self.tau == 0.0 or x.size == 0:
            return x.copy()
        if self.last is None:               # at rest on the first input
            first = x[0]
            tt, xx = t, x
        else:                               # from the previous call's last sample
            t0, x0, first = self.last
            tt, xx = np.r_[t0, t], np.r_[x0, x]
        u = np.diff(tt) / self.tau                    # >= 0; 0: a jump of x, y kept
        psi = lumped._psi(u)
        weight_start = u * psi
        weight_end = u * (lumped._phi1(u) - psi)
        steps = _recurrence(np.exp(-u), weight_start * xx[:-1] + weight_end * xx[1:], first)
        y = np.r_[first, steps] if self.last is None else steps
        self.last = (float(t[-1]), float(x[-1]), float(y[-1]))
        return y


def _recurrence(decay, source, first: float) -> np.ndarray:
    """y_k = decay_k y_(k-1) + source_k from y_(-1) = ``first``: by SciPy's compiled
    ``lfilter`` when the steps are equal (the run's output samples: the decays the same to
    1e-12 of 1 - decay, what the step takes off y), else by the load's compiled recurrence
    (:func:`tengfield._lumped_kernel.deficit_recurrence`). Equal to 1e-12 of the decay
    alone was not enough: at f_c = 1e-10 Hz the decays of unequal steps differ by 1e-13,
    as large as 1 - decay itself."""
    if decay.size and np.max(np.abs(decay - decay[0])) <= 1e-12 * (1.0 - decay[0]):
        from scipy.signal import lfilter
        d = float(decay[0])
        out, _ = lfilter([1.0], [1.0, -d], source, zi=[d * first])
        return out
    from .._lumped_kernel import deficit_recurrence   # numba: loaded when needed

    return deficit_recurrence(np.ascontiguousarray(decay, dtype=float),
                              np.ascontiguousarray(source, dtype=float), float(first))[1:]


class Aperture:
    """The mean of y over [t - T_a, t] (over [t_0, t] while fewer than T_a have passed),
    y linear between samples (the trapezoidal integral, read off linearly). Keeps the
    samples of the last T_a between calls. ``aperture`` = 0: y itself."""

    def __init__(self, aperture: float):
        self.aperture = float(aperture)
        self.t = np.empty(0)
        self.y = np.empty(0)
        self.integral = np.empty(0)     # ∫ y dt from the first sample, at self.t

    def __call__(self, t, y) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        y = np.asarray(y, dtype=float)
        if self.aperture == 0.0 or y.size == 0:
            return y.copy()
        if self.t.size:
            tt = np.concatenate([self.t[-1:], t])
            yy = np.concatenate([self.y[-1:], y])
            base = self.integral[-1]
        else:
            tt, yy, base = t[:1], y[:1], 0.0
            tt = np.concatenate([tt, t[1:]])
            yy = np.concatenate([yy, y[1:]])
        steps = 0.5 * (yy[1:] + yy[:-1]) * np.diff(tt)
        new_integral = base + np.concatenate([[0.0], np.cumsum(steps)])
        if self.t.size:                       # drop the repeated first sample
            new_t, new_y, new_int = tt[1:], yy[1:], new_integral[1:]
        else:
            new_t, new_y, new_int = tt, yy, new_integral
        all_t = np.concatenate([self.t, new_t])
        all_y = np.concatenate([self.y, new_y])
        all_int = np.concatenate([self.integral, new_int])
        lower = np.maximum(new_t - self.aperture, all_t[0])    # since the first sample
        width = new_t - lower
        at_lower = _integral_at(all_t, all_y, all_int, lower)
        with np.errstate(divide="ignore", invalid="ignore"):
            out = np.where(width > 0, (new_int - at_lower) / np.where(width > 0, width, 1.0),
                           new_y)
        keep = all_t >= all_t[-1] - self.aperture
        keep[max(int(np.argmax(keep)) - 1, 0)] = True    # one sample before the window
        self.t, self.y, self.integral = all_t[keep], all_y[keep], all_int[keep]
        return out


def _integral_at(t, y, integral, at) -> np.ndarray:
    """∫ y from the first sample to ``at`` for y linear between the samples ``t``."""
    i = np.clip(np.searchsorted(t, at, side="right") - 1, 0, t.size - 1)
    j = np.minimum(i + 1, t.size - 1)
    h = t[j] - t[i]
    dt = at - t[i]
    with np.errstate(divide="ignore", invalid="ignore"):
        slope = np.where(h > 0, (y[j] - y[i]) / np.where(h > 0, h, 1.0), 0.0)
    return integral[i] + y[i] * dt + 0.5 * slope * dt * dt


class SampleHold:
    """Readings at k / f_s (k = 0, 1, ... on the run's own axis, from its first sample),
    each the input linear between samples at that instant, held until the next reading.
    ``rate`` = 0: the input itself."""

    def __init__(self, rate: float):
        self.rate = float(rate)
        self.last = None      # (t, x) of the previous sample
        self.held = None      # the reading being held
        self.next_k = 0

    def __call__(self, t, x) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        x = np.asarray(x, dtype=float)
        if self.rate == 0.0 or x.size == 0:
            return x.copy()
        if self.last is None:
            self.next_k = int(math.ceil(t[0] * self.rate - 1e-9))
            tt, xx = t, x
        else:
            tt = np.concatenate([[self.last[0]], t])
            xx = np.concatenate([[self.last[1]], x])
        k_last = int(math.floor(t[-1] * self.rate + 1e-9))
        ks = np.arange(self.next_k, k_last + 1)
        reading_t = ks / self.rate
        readings = np.interp(reading_t, tt, xx)
        # each row shows the latest reading at or before it (1e-9 of a period: rounding)
        idx = np.searchsorted(reading_t, t + 1e-9 / self.rate, side="right") - 1
        before = x if self.held is None else np.full_like(x, self.held)
        out = np.where(idx >= 0, readings[np.maximum(idx, 0)] if ks.size else before, before)
        if ks.size:
            self.held = float(readings[-1])
            self.next_k = int(ks[-1]) + 1
        self.last = (float(t[-1]), float(x[-1]))
        return out


class Chain:
    """Bandwidth, aperture and sampling of one quantity, in that order, state carried."""

    def __init__(self, instrument):
        self.stages = [FirstOrder(time_constant(instrument.bandwidth)),
                       Aperture(instrument.aperture), SampleHold(instrument.sample_rate)]

    def __call__(self, t, x) -> np.ndarray:
        y = np.asarray(x, dtype=float)
        for stage in self.stages:
            y = stage(t, y)
        return y


class Reader:
    """The read columns of a scene's ``[instrument]`` along a run, a call per chunk of
    rows in order (:meth:`read`). ``loaded``: the instrument's R_in is the terminal's
    load (an open terminal; with a circuit connected it reads the circuit's voltage)."""

    def __init__(self, scene, loaded: bool):
        self.instrument = scene.instrument
        self.c_p = scene.circuit.parallel_capacitance
        self.loaded = loaded and self.instrument.input_resistance > 0.0
        self.chains = {name: Chain(self.instrument) for name in READ_COLUMNS}
        self.previous = None     # the last sample (t, Q_SC, I_SC, C_T) and the charge through R_in

    def read(self, elapsed, columns: dict, c_t=None) -> dict:
        """``{"V_read_V", "Q_read_C", "I_read_A"}`` at the ``elapsed`` rows [s] (the run's
        own axis) from ``columns`` (``Q_sc_C``, ``I_sc_A``, ``V_read_V``: the voltage
        across C_p without R_in, or the circuit's); ``c_t`` C_T [F] at the rows (needed
        with a finite R_in)."""
        t = np.asarray(elapsed, dtype=float)
        voltage = np.asarray(columns["V_read_V"], dtype=float)
        if self.loaded:
            voltage = self._loaded_voltage(t, columns, c_t)
        out = {}
        for name, (column, source) in READ_COLUMNS.items():
            x = voltage if name == "V_read" else np.asarray(columns[source], dtype=float)
            out[column] = self.chains[name](t, x)
        return out

    def _loaded_voltage(self, t, columns, c_t) -> np.ndarray:
        q = np.asarray(columns["Q_sc_C"], dtype=float)
        i = np.asarray(columns["I_sc_A"], dtype=float)
        c = np.asarray(c_t, dtype=float)
        r_in = self.instrument.input_resistance
        if _quasi_static(t, self.previous, r_in * np.max(c + self.c_p)):
            v = r_in * i                 # the R_in -> 0 limit, exact to double precision
            if self.previous is None:    # the start: the open-circuit voltage, as the
                v[0] = q[0] / (c[0] + self.c_p)     # integrator's (no charge through R_in)
            self.previous = (float(t[-1]), float(q[-1]), float(i[-1]), float(c[-1]),
                             float(q[-1] - (c[-1] + self.c_p) * v[-1]))
            return v
        if self.previous is None:
            response = lumped.load_response(t, q, i, c, self.instrument.input_resistance,
                                             self.c_p)
            v = response.voltage
        else:
            t0, q0, i0, c0, charge0 = self.previous
            response = lumped.load_response(np.r_[t0, t], np.r_[q0, q], np.r_[i0, i],
                                             np.r_[c0, c], self.instrument.input_resistance,
                                             self.c_p, initial_load_charge=charge0)
            v = response.voltage[1:]
        self.previous = (float(t[-1]), float(q[-1]), float(i[-1]), float(c[-1]),
                         float(response.charge[-1]))
        return v


#: R_in (C_T + C_p) below this fraction of every step: the voltage is R_in I_SC (the
#: exponential integrator's answer differs from it by this fraction, below a double's
#: rounding; beyond it 1 / (R_in C) overflows: R_in = 1e-300 ohm gave NaN)
QUASI_STATIC_FRACTION = 1e-17


def _quasi_static(t, previous, time_constant_max: float) -> bool:
    """Is the loaded voltage along ``t`` [s] (after the ``previous`` sample, if any) its
    quasi-static limit R_in I_SC: the longest R_in (C_T + C_p) [s] below
    :data:`QUASI_STATIC_FRACTION` of every step (a step of zero length, an impact's
    repeated instant, keeps the integrator; the first sample alone is its start value)."""
    times = t if previous is None else np.r_[previous[0], t]
    steps = np.diff(times)
    if steps.size == 0:          # the first sample alone: its start value, no step
        return True
    return bool(np.min(steps) > 0.0
                and time_constant_max < QUASI_STATIC_FRACTION * float(np.min(steps)))


def has_read(scene) -> bool:
    """Does a run of ``scene`` write ``V_read_V`` (C_p > 0, or an ``[instrument]``)?"""
    return scene.circuit.parallel_capacitance > 0.0 or scene.instrument.given


def as_terminal(scene, read_at_samples: bool = False) -> dict[str, str]:
    """``{read quantity: terminal quantity}`` of the read quantities ``scene``'s reader
    leaves as the terminal's own, row by row (their extremes are the terminal's, impacts
    included): Q_read and I_read (read in short circuit, R_in does not touch them) without
    a bandwidth, an aperture or a sample rate; V_read with none of these and no R_in
    either, unless it is a circuit's voltage (``read_at_samples``: continuous at the
    impacts, taken at its samples). The deprecated C_p alone: V_read, Q_SC / (C_T + C_p)."""
    inst = scene.instrument
    chain_is_identity = inst.bandwidth == 0.0 and inst.aperture == 0.0 \
        and inst.sample_rate == 0.0
    if inst.given and not chain_is_identity:
        return {}
    out = {}
    for name in read_names(scene):
        if name == "V_read":
            if not read_at_samples and (not inst.given or inst.input_resistance == 0.0):
                out[name] = "V_read"
        else:
            out[name] = READ_COLUMNS[name][1].rpartition("_")[0]    # Q_sc_C -> Q_sc
    return out


def read_names(scene) -> tuple[str, ...]:
    """The read quantities' short names a run of ``scene`` reports."""
    if scene.instrument.given:
        return tuple(READ_COLUMNS)
    return ("V_read",) if scene.circuit.parallel_capacitance > 0.0 else ()
