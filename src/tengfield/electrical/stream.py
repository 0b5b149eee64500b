"""The electrical stage of a long run a chunk of output rows at a time: memory bounded by
the chunk, not by the run.

A run with more than :data:`STREAM_ROWS` output samples, a circuit kind that can
(:meth:`~tengfield.electrical.circuits.Circuit.can_stream`: every kind; a rectifier
with Q_SC = 0 has nothing to rectify) and the ball on the axis is evaluated here instead of as
whole-record arrays (:func:`tengfield.pipeline.electrical_stage` decides,
:func:`streams`); the entry's :meth:`~tengfield.electrical.circuits.Circuit.chunked`
carries its state from chunk to chunk and its
:meth:`~tengfield.electrical.circuits.Circuit.streamed` gives the stage's record:

* :class:`StreamedRun` walks the output rows in chunks of :data:`CHUNK_ROWS`: the
  trajectory rows, the terminal (V_OC, Q_SC, I_SC, V_read) and the circuit's columns
  (:class:`~tengfield.electrical.circuits.load.LoadChunks`,
  :class:`~tengfield.electrical.circuits.rectifier.RectifierChunks`), and :meth:`StreamedRun.reduce` takes in one pass what the
  summary needs as running reductions: peak and peak-to-peak over the steady window
  with the impact instants (:func:`tengfield.electrical.waveforms.impact_values`), the
  largest gap, the load's energy sums, the last 5 periods (waveforms.png, the V-Q loop)
  and a min/max envelope of every column in :data:`ENVELOPE_BINS` time bins;
* :class:`StreamedWaveforms` is ``RunResult.waveforms`` of such a run: a read-only
  mapping whose trajectory columns are the dynamics' own (a long 1-D run's sampled on
  request: :class:`tengfield.dynamics.columns.SampledColumn`, read here a chunk at a
  time, the steady window and the tail found by bisection), whose other columns are
  computed again on request (whole, cached: memory proportional to the run, for the
  library user who asks) and whose :meth:`~StreamedWaveforms.chunks` feed run.h5 a chunk
  at a time (:func:`tengfield.files.hdf5.write_tables`).

The numbers equal the whole-record computation: the same samples, the same terminal
and the same integrator steps (columns and extremes bit-identical; the energy sums to
rounding, 1e-12 relative: a sum in pieces). Units SI, signs as
:mod:`tengfield.terminals`.
"""
from __future__ import annotations

import bisect
from collections.abc import Mapping

import numpy as np

from ..source import Source
from .circuits import circuit_for
from .instrument import READ_COLUMNS, Reader, has_read
from .waveforms import (READ_COLUMN, WAVEFORM_COLUMNS, elapsed_times, impact_names,
                        impact_values, peak_quantities, steady_window_index,
                        waveform_columns)

#: the ball's charge column of a run whose contacts make it (tengfield.pipeline)
BALL_CHARGE_COLUMN = "q_ball_C"

#: runs with more output samples than this (52 s at 20 kHz) stream their electrical stage
STREAM_ROWS = 1 << 20
#: output rows per chunk (one of run.h5's chunks): ~30 MB of temporaries
CHUNK_ROWS = 1 << 18
#: time bins of the min/max envelope of a streamed run (a figure's pixel columns)
ENVELOPE_BINS = 2000
#: excitation periods kept whole at the end of a streamed run (waveforms.png, V-Q loop)
TAIL_PERIODS = 5.0

_TRAJECTORY = {"time_s": "t", "gap_m": "gap", "gap_velocity_m_per_s": "gap_velocity",
               "table_m": "table"}


def streams(scene, dynamics, curves) -> bool:
    """Whether the electrical stage of ``scene`` along ``dynamics`` is streamed: more
    than :data:`STREAM_ROWS` samples, a kind that can (:meth:`Circuit.can_stream`), the
    ball on the axis
    (no (z, r) surrogate), a dynamics result with its table column."""
    return (len(dynamics.t) > STREAM_ROWS
            and circuit_for(scene).can_stream(scene, curves)
            and (curves is None or not curves.radial)
            and getattr(dynamics, "table", None) is not None)


def chunk_bounds(rows: int, size: int | None = None) -> list[tuple[int, int]]:
    """``[(i0, i1), ...]``: the output rows in chunks of ``size`` (:data:`CHUNK_ROWS`)."""
    size = CHUNK_ROWS if size is None else int(size)
    return [(i0, min(i0 + size, rows)) for i0 in range(0, rows, size)]


class StreamedRun:
    """The electrical stage of ``scene`` along ``dynamics`` a chunk at a time (above).
    ``columns``: the columns in waveforms.csv's order; :meth:`chunks` yields them."""

    def __init__(self, scene, dynamics, curves):
        self.scene, self.dynamics, self.curves = scene, dynamics, curves
        self.entry = circuit_for(scene)
        #: the device as a source along the run: the terminal, a chunk of rows at a time
        self.source = Source.of_scene(scene, curves, dynamics)
        self.rows = len(dynamics.t)
        self.chunk_rows = CHUNK_ROWS
        self.elapsed = elapsed_times(dynamics)
        self.window, self.window_rule = steady_window_index(self.elapsed, scene)
        self.columns = list(WAVEFORM_COLUMNS)
        if has_read(scene):
            self.columns.append(READ_COLUMN)
        if scene.instrument.given:
            self.columns += [c for c, _ in READ_COLUMNS.values() if c != READ_COLUMN]
        self.columns += list(self.entry.columns)
        if getattr(curves, "contact", False):    # [charge] model = "contact": q(t)
            self.columns.append(BALL_CHARGE_COLUMN)
        self.read_at_samples = READ_COLUMN in self.columns and \
            self.entry.read_column in self.entry.columns

    def _circuit(self):
        """A fresh chunked circuit (None: nothing to integrate)."""
        return self.entry.chunked(self.scene, self.dynamics, self.curves,
                                  float(self.elapsed[self.window]), self.chunk_rows)

    def chunks(self):
        """Yield ``(i0, i1, {column: array})`` for every chunk of output rows, in order."""
        load = self._circuit()       # the circuit's state, carried from chunk to chunk
        dyn, scene = self.dynamics, self.scene
        reader = Reader(scene, not self.read_at_samples) if scene.instrument.given else None
        for i0, i1, terminal in self.source.chunks(self.chunk_rows):
            out = waveform_columns(scene, np.asarray(dyn.t[i0:i1], dtype=float), terminal,
                                   dyn.table[i0:i1])
            if load is not None:
                out.update(load.chunk(i0, i1))
            elif self.entry.columns:            # Q_SC = 0: nothing moves
                out.update({c: np.zeros(i1 - i0) for c in self.entry.columns})
            if self.read_at_samples:
                out[READ_COLUMN] = out[self.entry.read_column]
            if reader is not None:     # the instrument's state, carried too
                out.update(reader.read(self.elapsed[i0:i1], out, out["C_T_F"]))
            if BALL_CHARGE_COLUMN in self.columns:
                out[BALL_CHARGE_COLUMN] = self.source.ball_charge(self.elapsed[i0:i1])
            self._last_circuit = load
            yield i0, i1, out

    def reduce(self) -> dict:
        """One pass over the chunks: what the summary and the figures need (see the module
        docstring): ``extremes`` ({"peak_to_peak", "peak"} by short name), ``max_gap``
        [m], ``circuit`` (the chunked circuit after the last chunk, or None), ``tail`` (the columns over the last
        :data:`TAIL_PERIODS` periods, with ``_elapsed``), ``envelope``."""
        scene, w = self.scene, self.window
        quantities = peak_quantities(scene)
        lo = {n: np.inf for n in quantities}
        hi = {n: -np.inf for n in quantities}
        top = {n: 0.0 for n in quantities}
        own = {c: [np.inf, -np.inf] for c in self.entry.columns}   # the circuit's columns
        max_gap = -np.inf
        t_abs = self.dynamics.t        # sorted; a long run's sampled on request: bisection
        tail_start = bisect.bisect_left(t_abs, float(t_abs[-1])
                                        - TAIL_PERIODS * scene.excitation.period)
        tail: dict = {}
        envelope = _Envelope(self.elapsed, self.columns)
        self._last_circuit = None
        for i0, i1, cols in self.chunks():
            envelope.add(i0, i1, cols)
            if i1 > tail_start:
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
                "max_gap": max_gap, "tail": {c: np.concatenate(v) for c, v in tail.items()},
                "column_peak_to_peak": {c: b[1] - b[0] for c, b in own.items()},
                "envelope": envelope.result(self.dynamics)}


class _Envelope:
    """min/max of every column in :data:`ENVELOPE_BINS` equal bins of the run's time."""

    def __init__(self, elapsed, columns):
        self.elapsed = elapsed
        self.span = float(elapsed[-1] - elapsed[0]) or 1.0
        self.bins = ENVELOPE_BINS
        self.lo = {c: np.full(self.bins, np.inf) for c in columns}
        self.hi = {c: np.full(self.bins, -np.inf) for c in columns}

    def add(self, i0, i1, cols) -> None:
        e = self.elapsed[i0:i1]
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


class StreamedWaveforms(Mapping):
    """``RunResult.waveforms`` of a streamed run (module docstring): the trajectory
    columns are the dynamics' own (arrays, or columns sampled on request); asking for another column computes every column
    again, whole (cached). ``chunks()`` yields ``{column: array}`` a chunk at a time
    (run.h5); ``tail`` holds the last :data:`TAIL_PERIODS` periods, ``envelope`` the
    min/max envelope; ``rows`` the number of samples."""

    def __init__(self, run: StreamedRun, reduced: dict):
        self._run = run
        self.tail = {k: v for k, v in reduced["tail"].items() if not k.startswith("_")}
        self.envelope = reduced["envelope"]
        self.rows = run.rows
        self._whole: dict | None = None

    def __iter__(self):
        return iter(self._run.columns)

    def __len__(self) -> int:
        return len(self._run.columns)

    def __contains__(self, name) -> bool:
        return name in self._run.columns

    def __getitem__(self, name):
        if name not in self._run.columns:
            raise KeyError(name)
        if name in _TRAJECTORY:
            return self.source_of(name)
        if self._whole is None:
            parts: dict = {c: [] for c in self._run.columns if c not in _TRAJECTORY}
            for _, _, cols in self._run.chunks():
                for c in parts:
                    parts[c].append(cols[c])
            self._whole = {c: np.concatenate(v) for c, v in parts.items()}
        return self._whole[name]

    def source_of(self, name):
        """The dynamics' own array of a trajectory column (``time_s``, ``gap_m``...),
        else None: run.h5 stores those once (hard links). A long run's are its columns
        sampled on request (:class:`tengfield.dynamics.columns.SampledColumn`)."""
        attr = _TRAJECTORY.get(name)
        if attr is None:
            return None
        column = getattr(self._run.dynamics, attr)
        return column if hasattr(column, "chunks") else np.asarray(column)

    def chunks(self):
        """Yield ``{column: array}`` for consecutive chunks of rows (all columns)."""
        for _, _, cols in self._run.chunks():
            yield cols

    def terminal_rows(self, i0: int, i1: int) -> dict[str, np.ndarray]:
        """``{"time_s", "V_oc_V", "C_T_F"}`` of the rows ``i0:i1`` only (the values of the
        whole columns, bit for bit: the terminal is evaluated sample by sample), without a
        pass over the run: the SPICE export's start-up and steady period
        (:mod:`tengfield.spice`) of a run of any length."""
        dyn = self._run.dynamics
        terminal = self._run.source.rows(i0, i1)
        return {"time_s": np.asarray(dyn.t[i0:i1], dtype=float), "V_oc_V": terminal["V_oc"],
                "C_T_F": terminal["C_T"]}


def streamed_stage(scene, dynamics, curves) -> tuple:
    """``(waveforms, ran, extremes, reduced)`` of a streamed run: the
    :class:`StreamedWaveforms`, the circuit's
    :class:`~tengfield.electrical.circuits.CircuitRun` (from the entry's ``streamed``:
    no whole columns), the peak blocks, and :meth:`StreamedRun.reduce`'s record."""
    run = StreamedRun(scene, dynamics, curves)
    reduced = run.reduce()
    waveforms = StreamedWaveforms(run, reduced)
    note = (f" (streamed: {len(chunk_bounds(run.rows, run.chunk_rows))} chunks of "
            f"{run.chunk_rows} rows)")
    ran = run.entry.streamed(scene, dynamics, curves, reduced["circuit"], reduced, note)
    return waveforms, ran, reduced["extremes"], reduced
