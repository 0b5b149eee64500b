"""The electrical stage of a long run a chunk of output rows at a time: memory bounded by
the chunk, not by the run.

A run with more than :data:`STREAM_ROWS` output samples and the ball on the axis (no
(z, r) surrogate) runs the one electrical loop (:class:`tengfield.electrical.loop.Loop`)
in chunks of :data:`CHUNK_ROWS` rows instead of as one chunk
(:func:`tengfield.pipeline.electrical_stage` decides, :func:`streams`): the circuit's
state (:meth:`~tengfield.electrical.circuits.Circuit.start`, ``chunk``) is carried from
chunk to chunk, :meth:`~tengfield.electrical.loop.Loop.reduce` takes what the summary
needs as running reductions (peaks over the steady window with the impact instants, the
largest gap, the last 5 periods for waveforms.png and the V-Q loop, a min/max envelope of
every column) and :meth:`~tengfield.electrical.circuits.Circuit.finish` gives the stage's
record. :class:`StreamedWaveforms` is ``RunResult.waveforms`` of such a run: a read-only
mapping whose trajectory columns are the dynamics' own (a long 1-D run's sampled on
request: :class:`tengfield.dynamics.columns.SampledColumn`), whose other columns are
computed again on request (whole, cached: memory proportional to the run, for the
library user who asks) and whose :meth:`~StreamedWaveforms.chunks` feed run.h5 a chunk at
a time (:func:`tengfield.files.hdf5.write_tables`).

The numbers equal the whole run's (one chunk): the same samples, the same terminal and
the same integrator steps (columns and extremes bit-identical; the energy sums to
rounding, 1e-12 relative: a sum in pieces). Units SI, signs as :mod:`tengfield.terminals`.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from .loop import (BALL_CHARGE_COLUMN, ENVELOPE_BINS, TAIL_PERIODS, Loop,  # noqa: F401
                   chunk_bounds as _bounds)

#: runs with more output samples than this (52 s at 20 kHz) stream their electrical stage
STREAM_ROWS = 1 << 20
#: output rows per chunk (one of run.h5's chunks): ~30 MB of temporaries
CHUNK_ROWS = 1 << 18

_TRAJECTORY = {"time_s": "t", "gap_m": "gap", "gap_velocity_m_per_s": "gap_velocity",
               "table_m": "table"}


def streams(scene, dynamics, curves) -> bool:
    """Whether the electrical stage of ``scene`` along ``dynamics`` is streamed: more
    than :data:`STREAM_ROWS` samples, the ball on the axis (no (z, r) surrogate), a
    dynamics result with its table column."""
    return (len(dynamics.t) > STREAM_ROWS
            and (curves is None or not curves.radial)
            and getattr(dynamics, "table", None) is not None)


def chunk_bounds(rows: int, size: int | None = None) -> list[tuple[int, int]]:
    """``[(i0, i1), ...]``: the output rows in chunks of ``size`` (:data:`CHUNK_ROWS`)."""
    return _bounds(rows, CHUNK_ROWS if size is None else size)


class StreamedRun(Loop):
    """The one loop of ``scene`` on ``source`` in chunks of :data:`CHUNK_ROWS` rows."""

    def __init__(self, scene, source):
        super().__init__(scene, source, CHUNK_ROWS)


class StreamedWaveforms(Mapping):
    """``RunResult.waveforms`` of a streamed run (module docstring): the trajectory
    columns are the dynamics' own (arrays, or columns sampled on request); asking for another column computes every column
    again, whole (cached). ``chunks()`` yields ``{column: array}`` a chunk at a time
    (run.h5); ``tail`` holds the last :data:`TAIL_PERIODS` periods, ``envelope`` the
    min/max envelope; ``rows`` the number of samples."""

    def __init__(self, run: Loop, reduced: dict):
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
