"""A long 1-D run samples its columns on request (issue #28 last item, #30.11;
tengfield/dynamics/columns.py): past LAZY_ROWS (forced low here) ``t``, ``elapsed``,
``gap``, ``gap_velocity`` and ``table`` are SampledColumns whose slices, items, index
arrays and whole arrays equal the whole-record arrays bit for bit (ranges across impacts
and across chunk edges), for the impact map and the soft model; short runs keep arrays."""
from __future__ import annotations

import pickle

import numpy as np
import pytest

from tengfield.dynamics import columns, simulate

import plate_model as fx

NAMES = ("t", "elapsed", "gap", "gap_velocity", "table")


def _both(monkeypatch, **sections):
    scene = fx.scene_with(**sections)
    whole = simulate(scene)
    monkeypatch.setattr(columns, "LAZY_ROWS", 100)
    lazy = simulate(scene)
    monkeypatch.undo()
    return whole, lazy


def _ranges(whole, n):
    """Ranges around impacts (a few samples either side) and odd chunks of the run."""
    rate = 1.0 / (whole.elapsed[1] - whole.elapsed[0])
    out = []
    for time in whole.impacts.time[:: max(1, len(whole.impacts) // 12)]:
        i = int((time - whole.time_origin) * rate)
        out.append((max(i - 3, 0), min(i + 4, n)))
    out += [(0, 1), (n - 1, n), (0, n), (17, 17), (n - 333, n)]
    return out


def _check(whole, lazy):
    n = len(whole.t)
    assert all(isinstance(getattr(whole, c), np.ndarray) for c in NAMES)
    assert all(isinstance(getattr(lazy, c), columns.SampledColumn) for c in NAMES)
    ranges = _ranges(whole, n)
    for name in NAMES:
        w, s = getattr(whole, name), getattr(lazy, name)
        assert len(s) == n and s.shape == (n,) and s.size == n
        np.testing.assert_array_equal(np.asarray(s), w, err_msg=name)
        for i0, i1 in ranges:
            np.testing.assert_array_equal(s[i0:i1], w[i0:i1], err_msg=f"{name}[{i0}:{i1}]")
        for size in (977, 1 << 12):          # chunk edges anywhere, cut through impacts
            parts = [s[i:i + size] for i in range(0, n, size)]
            np.testing.assert_array_equal(np.concatenate(parts), w, err_msg=f"{name} {size}")
        for i in (0, 1, n // 2, -1, -n):
            assert s[i] == w[i], (name, i)
        index = np.array([n - 1, 0, 5, n // 3, 5])
        np.testing.assert_array_equal(s[index], w[index])
        mask = np.zeros(n, dtype=bool)
        mask[::13] = True
        np.testing.assert_array_equal(s[mask], w[mask])
        np.testing.assert_array_equal(s[::7], w[::7])
    assert lazy.gap.max() == w_max(whole) and np.array_equal(lazy.t - 1.0, whole.t - 1.0)
    with pytest.raises(IndexError):
        lazy.gap[n]
    assert not hasattr(lazy.gap, "rows") and not hasattr(lazy.gap, "tail")
    assert lazy.summary | {"wall_time_s": 0} == whole.summary | {"wall_time_s": 0}
    assert lazy.regime == whole.regime
    np.testing.assert_array_equal(lazy.impacts.time, whole.impacts.time)


def w_max(whole):
    return float(np.max(whole.gap))


def test_impact_map_columns_sampled_on_request_equal_the_arrays(monkeypatch):
    whole, lazy = _both(monkeypatch, run={"duration_s": 2.0, "settle_periods": 2},
                        initial={"time_s": 1234.5})
    assert len(whole.impacts) > 20
    _check(whole, lazy)
    again = pickle.loads(pickle.dumps(lazy))           # sweeps and pools pickle results
    np.testing.assert_array_equal(again.gap[100:200], whole.gap[100:200])


@pytest.mark.slow
def test_soft_model_columns_sampled_on_request_equal_the_arrays(monkeypatch):
    """The soft model's dense output is evaluated over whole solver steps (a step's
    interpolant is a matrix product: cut in two it could differ in the last bit)."""
    whole, lazy = _both(monkeypatch, run={"duration_s": 0.8, "settle_periods": 2},
                        contact={"model": "soft"})
    assert len(whole.impacts) > 5
    _check(whole, lazy)


def test_short_runs_keep_their_arrays():
    scene = fx.scene_with(run={"duration_s": 0.5, "settle_periods": 2})
    result = simulate(scene)
    assert len(result.t) <= columns.LAZY_ROWS
    assert all(type(getattr(result, c)) is np.ndarray for c in NAMES)


def test_trajectory_csv_of_sampled_columns_is_written_in_chunks_with_the_same_bytes(
        monkeypatch, tmp_path):
    """`tengfield dynamics` of a long run: trajectory.csv a chunk at a time (chunks of
    1000 rows here), the same bytes as from the arrays."""
    from tengfield import io as tio

    whole, lazy = _both(monkeypatch, run={"duration_s": 0.6, "settle_periods": 2})
    monkeypatch.setattr(columns, "CHUNK", 1000)
    tio.write_trajectory_csv(whole, tmp_path / "whole.csv")
    tio.write_trajectory_csv(lazy, tmp_path / "lazy.csv")
    text = (tmp_path / "lazy.csv").read_bytes()
    assert text == (tmp_path / "whole.csv").read_bytes()
    assert text.count(b"\n") == len(whole.t) + 1 > 10_000
