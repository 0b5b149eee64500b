"""The rectifier of a long run a chunk of output rows at a time (``[circuit] kind =
"rectifier"``, :mod:`tengfield.electrical.stream`): :class:`RectifierChunks` carries the
harvester's state and takes :func:`.rectifier.summary_block`'s numbers as running
reductions; the last period (the V-Q loop) and a min/max envelope of the store's voltage
(charging.png) are all it keeps."""
from __future__ import annotations

import dataclasses
import math

import numpy as np

from ...source import Source
from ..waveforms import elapsed_times, impact_elapsed, sample_elapsed, time_origin
from .rectifier_store import check_store_resolution, first_crossing, harvester_options


class RectifierChunks:
    """The rectifier a chunk of output rows at a time (the streamed stage of a long run,
    :mod:`tengfield.electrical.stream`): the grid, terminal and harvester steps of
    :func:`rectifier_waveforms` (the :class:`tengfield.harvest.Harvester` carries its
    state), and what :func:`summary_block` reads taken as running reductions
    (:meth:`numbers`), the last period of the record (the V-Q loop) and a min/max
    envelope of the store's voltage (charging.png). Feed every chunk in order."""

    def __init__(self, scene, source: Source, window_start: float, bins: int = 2000):
        from ...harvest import Harvester

        check_store_resolution(scene)
        dynamics = source.dynamics
        self.scene, self.dynamics, self.curves = scene, dynamics, source.curves
        self.source = source
        self.t = elapsed_times(dynamics)
        self.impacts = impact_elapsed(dynamics, self.t[0], self.t[-1])
        self.harvester = Harvester(1, time_origin=time_origin(dynamics),
                                   **harvester_options(scene))
        self.window_start = window_start
        self.tail_start = float(self.t[-1]) - scene.excitation.period
        c = scene.circuit
        self.levels = {"crossing_falling": c.uvlo_falling, "crossing_rising": c.uvlo_rising}
        self.n = {"t0": float(self.t[0]), "t_end": float(self.t[-1]), "switch_on": 0,
                  "switch_off": 0, "on_time": 0.0, "max_store_voltage": -math.inf,
                  "max_store_voltage_window": -math.inf, "moved": 0.0,
                  "crossing_falling": math.nan, "crossing_rising": math.nan,
                  "origin": time_origin(dynamics)}
        self.prev = None           # (time, U, chip on, bridge charge) of the last row
        self.points = 0
        self.tail: list = []
        self.bins = bins
        self.envelope: list = []

    def chunk(self, i0: int, i1: int) -> dict:
        """The ``RECTIFIER_COLUMNS`` at the output rows ``i0:i1``."""
        t_all, n_all = self.t, self.t.size
        t_out = t_all[i0:i1]
        hi = t_all[i1] if i1 < n_all else math.inf
        imp = self.impacts[(self.impacts >= t_out[0]) & (self.impacts < hi)]
        imp = imp[~np.isin(imp, t_out)]
        grid = np.concatenate([t_out, imp])
        order = np.argsort(grid, kind="stable")
        grid, output_index = grid[order], np.flatnonzero(order < t_out.size)
        gap, _, _ = sample_elapsed(self.dynamics, grid)
        charge, capacitance = self.source.state(grid, gap)
        res = self.harvester.advance(grid, charge, capacitance)
        self._reduce(res)
        self.points += res.time.size
        return {"V_store_V": res.store_voltage[output_index],
                "I_store_A": res.store_current[output_index],
                "E_store_J": res.stored_energy[output_index],
                "pmic_on": res.chip_on[output_index].astype(float)}

    def _reduce(self, res) -> None:
        n, t, u, on = self.n, res.time, res.store_voltage, res.chip_on
        bridge = res.bridge_charge[:, 0]
        prev = self.prev
        t_ext = t if prev is None else np.concatenate([[prev[0]], t])
        on_ext = on if prev is None else np.concatenate([[prev[2]], on])
        n["switch_on"] += int(np.count_nonzero(on_ext[1:] & ~on_ext[:-1]))
        n["switch_off"] += int(np.count_nonzero(~on_ext[1:] & on_ext[:-1]))
        n["on_time"] += float(np.sum(np.diff(t_ext)[on_ext[1:]]))
        n["max_store_voltage"] = max(n["max_store_voltage"], float(np.max(u)))
        for key, level in self.levels.items():
            if math.isnan(n[key]):
                hit = np.flatnonzero(u >= level)
                if hit.size:
                    k = int(hit[0])
                    if k > 0:
                        n[key] = first_crossing(t[k - 1:], u[k - 1:], level)
                    elif prev is None:
                        n[key] = float(t[0])
                    else:
                        n[key] = first_crossing(np.array([prev[0], t[0]]),
                                                np.array([prev[1], u[0]]), level)
        inside = np.flatnonzero(t >= self.window_start)
        if inside.size:
            k0 = int(inside[0])
            if "t_k0" not in n:
                n.update(t_k0=float(t[k0]), store_input_k0=float(res.store_input[k0]),
                         bridge_energy_k0=float(res.bridge_energy[k0]))
                moved = bridge[k0:]
            else:
                moved = np.concatenate([[prev[3]], bridge])
            n["moved"] += float(np.abs(np.diff(moved)).sum())
            n["max_store_voltage_window"] = max(n["max_store_voltage_window"],
                                                float(np.max(u[k0:])))
        keep = t >= self.tail_start
        if keep.any():
            self.tail.append((t[keep], res.voltage[keep, 0], res.bridge_charge[keep, 0]))
        self.envelope.append(_min_max_bins(t, u, on, self.n["t0"], self.n["t_end"],
                                           self.bins))
        self.prev = (float(t[-1]), float(u[-1]), bool(on[-1]), float(bridge[-1]))
        self.last = res

    def numbers(self) -> dict:
        """:func:`record_numbers` of the whole record, from the reductions."""
        n = dict(self.n, last=self.last)
        length = n["t_end"] - n["t_k0"]
        n["mean_bridge_current_window"] = n.pop("moved") / length if length > 0 else 0.0
        return n

    def last_period(self) -> "_Record":
        """The record's rows over the last excitation period (time, voltage and bridge
        charge as (rows, 1) arrays): :meth:`Rectifier.cycle`'s V-Q loop."""
        t, v, q = (np.concatenate(x) for x in zip(*self.tail))
        return _Record(time=t, voltage=v[:, None], bridge_charge=q[:, None])

    def charging(self) -> "_Record":
        """The store's voltage as a min/max envelope (each time bin's lowest and highest
        U at their own instants; chip on if it was on in the bin): charging.png."""
        t, u, on = (np.concatenate(x) for x in zip(*self.envelope))
        return _Record(time=t, store_voltage=u, chip_on=on)


@dataclasses.dataclass
class _Record:
    """Columns of a HarvestResult a figure reads (a streamed run keeps no whole record)."""
    time: np.ndarray
    voltage: np.ndarray | None = None
    bridge_charge: np.ndarray | None = None
    store_voltage: np.ndarray | None = None
    chip_on: np.ndarray | None = None


def _min_max_bins(t, u, on, t0: float, t_end: float, bins: int):
    """(times, U, chip on) of each bin's min and max of ``u`` at their own instants, in
    time order, the chip on at both if it was on anywhere in the bin (a bin cut by a
    chunk boundary gives its extremes in both pieces)."""
    span = (t_end - t0) or 1.0
    b = np.minimum(((t - t0) / span * bins).astype(np.int64), bins - 1)
    starts = np.flatnonzero(np.r_[True, b[1:] != b[:-1]])
    ends = np.r_[starts[1:], t.size]
    picks, flags = [], []
    for a, e in zip(starts, ends):
        seg = u[a:e]
        both = sorted({a + int(np.argmin(seg)), a + int(np.argmax(seg))})
        picks += both
        flags += [bool(on[a:e].any())] * len(both)
    picks = np.asarray(picks, dtype=np.int64)
    return t[picks], u[picks], np.asarray(flags, dtype=bool)
