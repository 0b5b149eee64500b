"""The sampled columns of a long run, evaluated on request (memory bounded by the request).

A 1-D run (impact map, soft contact) with more than :data:`LAZY_ROWS` samples keeps its
compact trajectory (the impact map's piecewise-analytic segments, the soft model's dense
output) and no whole-record arrays: its ``t``, ``elapsed``, ``gap``, ``gap_velocity``
and ``table`` are :class:`SampledColumn` objects. ``len(col)``, ``col[i]``,
``col[i0:i1]`` (only that range is sampled), ``col[index array]`` and
:func:`iter_chunks` cost what they return; ``np.asarray(col)`` (and arithmetic, methods
such as ``col.max()``) builds the whole column: memory proportional to the run, for the
code that asks. The samples are those of the whole-record arrays, bit for bit: sample
``i`` is at ``elapsed = i / rate`` (the same division), ``t = time_origin + elapsed``,
and the trajectory is evaluated sample by sample.
"""
from __future__ import annotations

import numpy as np
from numpy.lib.mixins import NDArrayOperatorsMixin

#: a 1-D run with more samples than this (2^20, 52 s at 20 kHz) samples its columns on
#: request (``tengfield.electrical.stream.STREAM_ROWS`` streams its electrical stage)
LAZY_ROWS = 1 << 20
#: rows sampled at a time when a whole column is built or iterated
CHUNK = 1 << 18

#: recent ranges whose samples are kept (the streamed stage's chunk and its circuit's)
KEEP = 2

#: the columns of a run: elapsed / absolute time, then the sampler's outputs in order
COLUMNS = ("elapsed", "t", "gap", "gap_velocity", "table")
#: the 3D model's other per-sample columns (tengfield.dynamics.motion3d.Motion3DResult)
PER_SAMPLE_3D = ("x", "y", "radial", "velocity", "spin")


class Samples:
    """The shared source of a run's columns: ``count`` samples at ``(first + i) / rate``
    [s] after ``origin`` [s] (``first``: the run's sample the columns start at, 0 but in a
    :func:`tail`), ``sampler(elapsed) -> (gap, gap velocity, table)``; the last
    :data:`KEEP` ranges sampled are kept (a chunk each), so the three trajectory columns
    of a range cost one evaluation (and a circuit's chunk one row longer, another)."""

    def __init__(self, count: int, rate: float, origin: float, sampler, first: int = 0):
        self.count, self.rate, self.origin, self.sampler = int(count), float(rate), \
            float(origin), sampler
        self.first = int(first)
        self._kept: tuple = ()          # ((key, values), ...), replaced whole (threads)

    def __getstate__(self):
        state = dict(self.__dict__)
        state["_kept"] = ()
        return state

    def elapsed(self, index: np.ndarray) -> np.ndarray:
        """Elapsed times [s] of the integer sample indices ``index``."""
        return (index + self.first if self.first else index) / self.rate

    def column(self, name: str, index: np.ndarray, key=None) -> np.ndarray:
        """Column ``name`` at the integer sample indices ``index`` (``key``: a hashable
        name of that range, to reuse a recent evaluation)."""
        elapsed = self.elapsed(index)
        if name == "elapsed":
            return elapsed
        if name == "t":
            return self.origin + elapsed
        kept = self._kept
        values = next((v for k, v in kept if key is not None and k == key), None)
        if values is None:
            values = self._sample(index, elapsed)
            if key is not None:
                self._kept = ((key, values),) + kept[:KEEP - 1]
        return np.asarray(values[COLUMNS.index(name) - 2], dtype=float)

    def _sample(self, index: np.ndarray, elapsed: np.ndarray):
        """The sampler at ``elapsed``; a sampler with ``cover(lo, hi)`` (the soft model's
        dense output, whose interpolants are evaluated by a matrix product) is called on
        every sample of the interval it names, so that each of its steps sees the points
        it sees in a whole-record evaluation (the same bits), and cut to ``index``."""
        cover = getattr(self.sampler, "cover", None)
        if cover is None or index.size == 0:
            return self.sampler(np.ascontiguousarray(elapsed))
        lo, hi, first = int(index.min()), int(index.max()), self.first
        a, b = cover(float(elapsed.min()), float(elapsed.max()))
        j0 = 0 if not np.isfinite(a) else \
            max(0, min(lo, int(np.floor(a * self.rate)) - 1 - first))
        j1 = self.count if not np.isfinite(b) else \
            min(self.count, max(hi + 1, int(np.ceil(b * self.rate)) + 2 - first))
        values = self.sampler(np.ascontiguousarray(self.elapsed(np.arange(j0, j1))))
        return tuple(np.asarray(x)[index - j0] for x in values)


class SampledColumn(NDArrayOperatorsMixin):
    """One column (``name`` in :data:`COLUMNS`) of a long run, sampled on request
    (module docstring). Read-only; float64; one dimension."""

    __array_priority__ = 20
    dtype = np.dtype(float)
    ndim = 1

    def __init__(self, samples: Samples, name: str):
        if name not in COLUMNS:
            raise ValueError(f"column {name!r}: one of {COLUMNS}")
        self.samples, self.name = samples, name

    def __len__(self) -> int:
        return self.samples.count

    @property
    def shape(self) -> tuple[int]:
        return (self.samples.count,)

    @property
    def size(self) -> int:
        return self.samples.count

    @property
    def nbytes(self) -> int:
        return 8 * self.samples.count

    def __repr__(self) -> str:
        return f"SampledColumn({self.name!r}, {self.samples.count} samples, sampled on request)"

    def __getitem__(self, key):
        n = self.samples.count
        if isinstance(key, (int, np.integer)):
            i = int(key)
            if not -n <= i < n:
                raise IndexError(f"index {i} is out of bounds for a column of {n} samples")
            return float(self.samples.column(self.name, np.arange(i % n, i % n + 1))[0])
        if isinstance(key, slice):
            start, stop, step = key.indices(n)
            index = np.arange(start, stop, step)
            return self.samples.column(self.name, index, key=(start, stop, step))
        if key is Ellipsis:
            return np.asarray(self)
        index = np.asarray(key)
        if index.dtype == bool:
            if index.shape != (n,):
                raise IndexError(f"boolean index of shape {index.shape} for {n} samples")
            index = np.flatnonzero(index)
        elif index.dtype.kind not in "iu":
            raise IndexError(f"only integers, slices and integer or boolean arrays are "
                             f"valid indices of a sampled column, not {index.dtype}")
        index = np.where(index < 0, index + n, index)
        if index.size and (index.min() < 0 or index.max() >= n):
            raise IndexError(f"index out of bounds for a column of {n} samples")
        index = index.astype(np.int64)
        if index.size and int(index.max()) - int(index.min()) > CHUNK:
            # spread indices: sampled a block of CHUNK rows at a time (bounded memory)
            out = np.empty(index.shape)
            block = index // CHUNK
            for b in np.unique(block):
                sel = block == b
                out[sel] = self.samples.column(self.name, index[sel])
            return out
        return self.samples.column(self.name, index)

    def chunks(self, size: int = CHUNK):
        """Yield ``(i0, i1, values)`` over the column, ``size`` rows at a time."""
        n = self.samples.count
        for i0 in range(0, n, size):
            i1 = min(i0 + size, n)
            yield i0, i1, self[i0:i1]

    def __iter__(self):
        for _, _, values in self.chunks():
            yield from values

    def __array__(self, dtype=None, copy=None):
        """The whole column (costly: memory proportional to the run)."""
        out = np.empty(self.samples.count)
        for i0, i1, values in self.chunks():
            out[i0:i1] = values
        return out if dtype is None else out.astype(dtype, copy=False)

    def __array_ufunc__(self, ufunc, method, *inputs, **kwargs):
        inputs = tuple(np.asarray(x) if isinstance(x, SampledColumn) else x for x in inputs)
        return getattr(ufunc, method)(*inputs, **kwargs)

    def __getattr__(self, attr):
        # ndarray methods (max, min, copy, ...) on the whole column (costly); any other
        # name is missing without building it (hasattr probes stay cheap)
        if attr.startswith("_") or attr in ("samples", "name") or not hasattr(np.ndarray, attr):
            raise AttributeError(attr)
        return getattr(np.asarray(self), attr)


def sampled_columns(count: int, rate: float, origin: float, sampler, first: int = 0) -> dict:
    """``{name: SampledColumn}`` of :data:`COLUMNS` for ``count`` samples at ``rate`` [Hz]
    after ``origin`` [s] of ``sampler(elapsed) -> (gap, gap velocity, table)``, from the
    run's sample ``first`` on."""
    samples = Samples(count, rate, origin, sampler, first)
    return {name: SampledColumn(samples, name) for name in COLUMNS}


def tail(result, index: int, *, window_start: float | None = None):
    """``result`` (a DynamicsResult, the 3D model's too) from its sample ``index`` on:
    every per-sample column cut to ``[index:]`` (the same samples, on the run's own time
    axis: ``elapsed`` still counts from the run's start), sampled on request while still
    longer than :data:`LAZY_ROWS`; the impacts, the contact episodes, the regime and the
    counts stay the whole run's. ``window_start`` [s, absolute]: the steady window of the
    cut (default: the run's). ``index`` <= 0: ``result`` itself."""
    import dataclasses

    n, index = len(result.t), int(index)
    if index <= 0:
        return result
    if index >= n:
        raise ValueError(f"tail from sample {index}: the run has {n}")
    changes: dict = {}
    if is_sampled(result.t):
        samples, count = result.t.samples, n - index
        if count > LAZY_ROWS:
            changes.update(sampled_columns(count, samples.rate, samples.origin,
                                           samples.sampler, samples.first + index))
        else:
            changes.update({c: np.asarray(getattr(result, c)[index:], dtype=float)
                            for c in COLUMNS})
    else:
        for name in COLUMNS + PER_SAMPLE_3D:
            value = getattr(result, name, None)
            if value is not None and len(value) == n:
                changes[name] = np.asarray(value)[index:]
    if window_start is not None:
        changes["window_start"] = float(window_start)
    return dataclasses.replace(result, **changes)


def iter_chunks(column, size: int = CHUNK):
    """Yield ``(i0, i1, values)`` over a column (a :class:`SampledColumn` or an array),
    ``size`` rows at a time."""
    n = len(column)
    for i0 in range(0, n, size):
        i1 = min(i0 + size, n)
        yield i0, i1, np.asarray(column[i0:i1], dtype=float)


def is_sampled(column) -> bool:
    """Whether ``column`` is sampled on request (a long run's)."""
    return isinstance(column, SampledColumn)


def with_arrays(result):
    """``result`` (a DynamicsResult) with its sampled columns built as arrays (memory
    proportional to the run: for code that needs them whole, e.g. an ``[array]`` run);
    ``result`` itself when it holds arrays."""
    import dataclasses

    names = ("t", "elapsed", "gap", "gap_velocity", "table")
    if not any(is_sampled(getattr(result, c, None)) for c in names):
        return result
    return dataclasses.replace(result, **{c: np.asarray(getattr(result, c)) for c in names
                                          if is_sampled(getattr(result, c, None))})
