"""The one electrical loop: a circuit driven over the chunks of a :class:`~tengfield.source.Source`.

As SciPy's ``solve_ivp`` owns the loop and a method gives a step, :class:`Loop` owns the
pass over the output rows and a circuit kind (:mod:`tengfield.electrical.circuits`) gives
a small contract: :meth:`~tengfield.electrical.circuits.Circuit.start` (its state, or None
with nothing to integrate), the state's ``chunk(i0, i1)`` (a step over one chunk of
output rows: its columns there) and :meth:`~tengfield.electrical.circuits.Circuit.finish`
(its :class:`~tengfield.electrical.circuits.CircuitRun` after the last chunk). A whole
run is one chunk; a long run (:mod:`tengfield.electrical.stream`) is many, its memory
bounded by the chunk. Done once here, for every circuit and both:

* the terminal of every chunk (:meth:`tengfield.source.Source.chunks`: V_OC, Q_SC, I_SC,
  C_T, V_read through C_p) and the trajectory columns;
* the instrument (``[instrument]``: its state carried from chunk to chunk), reading the
  circuit's voltage where the circuit has one across C_p (``read_column``);
* the ball's charge column where its contacts make it;
* peak and peak-to-peak over the steady window, at the output samples and just before
  and after every impact (:func:`~tengfield.electrical.waveforms.impact_values`), the
  largest gap there, the circuit's columns' peak-to-peak, the last periods
  (:data:`TAIL_PERIODS`; a whole run keeps every row) and a min/max envelope of every
  column of a chunked run (:data:`ENVELOPE_BINS` time bins).

The numbers do not depend on the chunk size: the same samples, the same terminal, the
same integrator steps (columns and extremes bit for bit; a circuit's energy sums to
rounding, 1e-12 relative: a sum in pieces). Units SI, signs as :mod:`tengfield.terminals`.
"""
from __future__ import annotations

import bisect

import numpy as np

from ..source import Source
from .circuits import circuit_for
from .instrument import READ_COLUMNS, Reader, has_read
from .waveforms import (READ_COLUMN, WAVEFORM_COLUMNS, elapsed_times, impact_names,
                        impact_values, peak_quantities, steady_window_index,
                        waveform_columns)

#: the ball's charge column of a run whose contacts make it (tengfield.pipeline)
BALL_CHARGE_COLUMN = "q_ball_C"
#: time bins of the min/max envelope of every column (a figure's pixel columns)
ENVELOPE_BINS = 2000
#: excitation periods kept whole at the end of a chunked run (waveforms.png, V-Q loop)
TAIL_PERIODS = 5.0


def chunk_bounds(rows: int, size: int) -> list[tuple[int, int]]:
    """``[(i0, i1), ...]``: ``rows`` output rows in chunks of ``size``."""
    size = int(size)
    return [(i0, min(i0 + size, rows)) for i0 in range(0, rows, size)]


class Loop:
    """``scene``'s circuit on ``source`` (a :class:`~tengfield.source.Source` along the
    run's trajectory), a chunk of ``chunk_rows`` output rows at a time (None: one chunk,
    the whole run). ``columns``: the waveforms' columns in the order the chunks give
    them."""

    def __init__(self, scene, source: Source, chunk_rows: int | None = None):
        #: the device as a source along the run: the terminal, a chunk of rows at a time
        self.source = source
        self.scene, self.dynamics, self.curves = scene, source.dynamics, source.curves
        dynamics = source.dynamics
        self.entry = circuit_for(scene)
        self.rows = len(dynamics.t)
        self.chunk_rows = self.rows if chunk_rows is None else int(chunk_rows)
        self.elapsed = elapsed_times(dynamics)
        self.window, self.window_rule = steady_window_index(self.elapsed, scene)
        self.columns = list(WAVEFORM_COLUMNS)
        if has_read(scene):
            self.columns.append(READ_COLUMN)
        if scene.instrument.given:
            self.columns += [c for c, _ in READ_COLUMNS.values() if c != READ_COLUMN]
        self.columns += list(self.entry.columns)
        if self.source.contact:                # [charge] model = "contact": q(t)
            self.columns.append(BALL_CHARGE_COLUMN)
        self.read_at_samples = READ_COLUMN in self.columns and \
            self.entry.read_column in self.entry.columns
        self._last_circuit = None

    @property
    def whole(self) -> bool:
        """Whether the run is one chunk."""
        return self.chunk_rows >= self.rows

    @property
    def chunk_count(self) -> int:
        return len(chunk_bounds(self.rows, self.chunk_rows))

    def _circuit(self):
        """A fresh state of the circuit (None: nothing to integrate)."""
        return self.entry.start(self.scene, self.source, float(self.elapsed[self.window]),
                                self.chunk_rows)

    def chunks(self):
        """Yield ``(i0, i1, {column: array})`` for every chunk of output rows, in order
        (a fresh pass: the circuit and the instrument start again)."""
        circuit = self._circuit()     # the circuit's state, carried from chunk to chunk
        dyn, scene, entry = self.dynamics, self.scene, self.entry
        table = getattr(dyn, "table", None)
        reader = Reader(scene, not self.read_at_samples) if scene.instrument.given else None
        for i0, i1, terminal in self.source.chunks(self.chunk_rows):
            out = waveform_columns(scene, np.asarray(dyn.t[i0:i1], dtype=float), terminal,
                                   None if table is None else table[i0:i1])
            if circuit is not None:
                out.update(circuit.chunk(i0, i1))
            elif entry.columns:            # Q_SC = 0: nothing moves
                out.update({c: np.zeros(i1 - i0) for c in entry.columns})
            if self.read_at_samples:
                out[READ_COLUMN] = out[entry.read_column]
            if reader is not None:     # the instrument's state, carried too
                out.update(reader.read(self.elapsed[i0:i1], out, out["C_T_F"]))
            if BALL_CHARGE_COLUMN in self.columns:
                out[BALL_CHARGE_COLUMN] = self.source.ball_charge(self.elapsed[i0:i1])
            self._last_circuit = circuit
            yield i0, i1, out

    def reduce(self) -> dict:
        """One pass over the chunks: ``extremes`` ({"peak_to_peak", "peak"} by short
        name), ``max_gap`` [m] over the window, ``circuit`` (its state after the last
        chunk, or None), ``tail`` (the columns over the last :data:`TAIL_PERIODS` periods
        with ``_elapsed``; a whole run's every row), ``column_peak_to_peak`` (the
        circuit's columns over the window), ``envelope`` (a chunked run's; None for a
        whole run) and ``columns`` (a whole run's every column; None when chunked)."""
        scene, w = self.scene, self.window
        quantities = peak_quantities(scene)
        lo = {n: np.inf for n in quantities}
        hi = {n: -np.inf for n in quantities}
        top = {n: 0.0 for n in quantities}
        own = {c: [np.inf, -np.inf] for c in self.entry.columns}   # the circuit's columns
        max_gap = -np.inf
        t_abs = self.dynamics.t        # sorted; a long run's sampled on request: bisection
        tail_start = 0 if self.whole else bisect.bisect_left(
            t_abs, float(t_abs[-1]) - TAIL_PERIODS * scene.excitation.period)
        tail: dict = {}
        # a whole run's figures read its columns; a chunked run's the envelope
        envelope = None if self.whole else _Envelope(self.elapsed, self.columns)
        self._last_circuit = None
        whole = None
        for i0, i1, cols in self.chunks():
            if envelope is not None:
                envelope.add(i0, i1, cols)
            if self.whole:
                whole = cols
                tail = {c: [v] for c, v in cols.items()}
                tail["_elapsed"] = [np.asarray(self.elapsed)]
            elif i1 > tail_start:
                a = max(tail_start - i0, 0)
                for c, v in cols.items():
                    tail.setdefault(c, []).append(v[a:].copy())
                tail.setdefault("_elapsed", []).append(self.elapsed[i0 + a:i1])
            if i1 <= w:
                continue
            a = max(w - i0, 0)
            max_gap = max(max_gap, float(np.max(cols["gap_m"][a:])))
            for name, column in quantities.items():
                x = cols[column][a:]
                lo[name] = min(lo[name], float(np.min(x)))
                hi[name] = max(hi[name], float(np.max(x)))
                top[name] = max(top[name], float(np.max(np.abs(x))))
            for c, bounds in own.items():
                bounds[0] = min(bounds[0], float(np.min(cols[c][a:])))
                bounds[1] = max(bounds[1], float(np.max(cols[c][a:])))
        at_impacts = impact_names(scene, self.read_at_samples)
        found = impact_values(scene, self.dynamics, self.curves, self.elapsed[w],
                              self.elapsed[-1], set(at_impacts.values()))
        for name, source in at_impacts.items():
            x = found.get(source, np.empty(0))
            if x.size:
                lo[name] = min(lo[name], float(np.min(x)))
                hi[name] = max(hi[name], float(np.max(x)))
                top[name] = max(top[name], float(np.max(np.abs(x))))
        return {"circuit": self._last_circuit,
                "extremes": {"peak_to_peak": {n: hi[n] - lo[n] for n in quantities},
                             "peak": dict(top)},
                "max_gap": max_gap,
                "tail": {c: v[0] if len(v) == 1 else np.concatenate(v)
                         for c, v in tail.items()},
                "column_peak_to_peak": {c: b[1] - b[0] for c, b in own.items()},
                "envelope": None if envelope is None else envelope.result(self.dynamics),
                "columns": whole}

    def finish(self, reduced: dict, note: str = ""):
        """The circuit's :class:`~tengfield.electrical.circuits.CircuitRun` after the
        pass :meth:`reduce` made (``note`` ends its stage text)."""
        return self.entry.finish(self.scene, self.source, reduced["circuit"], reduced, note)


class _Envelope:
    """min/max of every column in :data:`ENVELOPE_BINS` equal bins of the run's time."""

    def __init__(self, elapsed, columns):
        self.elapsed = elapsed
        self.span = float(elapsed[-1] - elapsed[0]) or 1.0
        self.bins = ENVELOPE_BINS
        self.lo = {c: np.full(self.bins, np.inf) for c in columns}
        self.hi = {c: np.full(self.bins, -np.inf) for c in columns}

    def add(self, i0, i1, cols) -> None:
        e = np.asarray(self.elapsed[i0:i1])
        b = np.minimum(((e - self.elapsed[0]) / self.span * self.bins).astype(np.int64),
                       self.bins - 1)
        starts = np.flatnonzero(np.r_[True, b[1:] != b[:-1]])
        at = b[starts]
        for c, v in cols.items():
            np.minimum.at(self.lo[c], at, np.minimum.reduceat(v, starts))
            np.maximum.at(self.hi[c], at, np.maximum.reduceat(v, starts))

    def result(self, dynamics) -> dict:
        """``{"time_s": bin centres (absolute) [s], column: (min, max)}`` of the filled bins."""
        edges = np.linspace(0.0, self.span, self.bins + 1) + float(self.elapsed[0])
        filled = np.isfinite(self.lo["time_s"])
        origin = float(getattr(dynamics, "time_origin", 0.0) or 0.0)
        out: dict = {"time_s": origin + 0.5 * (edges[:-1] + edges[1:])[filled]}
        for c in self.lo:
            if c != "time_s":
                out[c] = (self.lo[c][filled], self.hi[c][filled])
        return out
