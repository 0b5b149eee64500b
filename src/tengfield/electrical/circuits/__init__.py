"""The circuit registry: one entry per ``[circuit] kind``, one module per entry.

:data:`CIRCUITS` maps each kind to its :class:`Circuit`. A module of this package
that defines ``CIRCUIT`` (or ``CIRCUITS``, a tuple) is an entry: the package finds
it by itself, so a new circuit kind is one new module here (+ its key(s) in
:mod:`tengfield.scene.schema` and the ``Circuit`` dataclass, and its tests and
docs). Every place that used to ask ``scene.circuit.kind == ...`` asks the entry:

* :func:`tengfield.pipeline.run`: :meth:`Circuit.check` before the dynamics; the one
  electrical loop (:mod:`tengfield.electrical.loop`, a whole run being one chunk)
  drives :meth:`Circuit.start` (its state) and the state's ``chunk`` (its
  ``columns`` of ``waveforms.csv`` over a chunk of output rows), then
  :meth:`Circuit.finish` (its stage text and record); :meth:`Circuit.summary` (the
  ``load`` block), :meth:`Circuit.cycle` (the energy-per-cycle numbers, its V-Q loops
  and further summary blocks);
* :mod:`tengfield.array`: :meth:`Circuit.array_identical` (cells without
  spread) and :meth:`Circuit.spread` (cells with their own dynamics);
* :mod:`tengfield.io`: :func:`all_columns` (the column order of waveforms.csv).

The scene layer cannot import this package (it is lower): ``[circuit] kind``'s
choices are a plain tuple in the schema, and a test holds them equal to
:data:`CIRCUITS`.
"""
from __future__ import annotations

import importlib
import pkgutil
from dataclasses import dataclass, field
from typing import Any

from ... import lumped
from ..._registry import lookup
from ..waveforms import steady_window


@dataclass
class CircuitRun:
    """What one circuit did along a run: its ``columns`` of ``waveforms.csv`` at the
    output samples, the stage (``status`` "ran" or "skipped", ``reason``, ``details``)
    and ``data``, the entry's own record for its summary and cycle blocks."""
    columns: dict
    reason: str
    details: dict = field(default_factory=dict)
    status: str = "ran"
    data: Any = None


class Circuit:
    """One ``[circuit] kind``. The base class is a circuit with nothing to integrate
    (the terminal's closed forms); entries override what they add."""
    #: the ``[circuit] kind`` value
    name: str = ""
    #: columns this kind adds to ``waveforms.csv`` (SI units in the names)
    columns: tuple[str, ...] = ()
    #: ``[circuit]`` keys (file names) this kind reads besides ``kind``,
    #: ``parallel_capacitance_pF`` and ``reference`` (docs, scene checks)
    keys: tuple[str, ...] = ()
    #: the column an instrument of capacitance C_p across the terminal reads with this
    #: circuit connected (``V_read_V``); "" : the open terminal's Q_SC / (C_T + C_p)
    read_column: str = ""
    #: a resistive load takes the power (``[circuit] load_ohm``; summary.json's
    #: ``load`` block has its mean power)
    has_load: bool = False
    #: ``tengfield fit`` models this kind's V and I by the R ∥ C_p load ODE (and can
    #: fit ``load_ohm``); otherwise it compares the terminal's V_OC, Q_SC, I_SC
    fit_load: bool = False
    #: the waveforms.csv columns (name, unit) of V, Q and I that ``tengfield fit``
    #: compares a measured run with when ``[fit.columns]`` is absent
    fit_columns: dict = {"V": ("V_oc_V", "V"), "Q": ("Q_sc_C", "C"), "I": ("I_sc_A", "A")}
    #: every output is linear in the ball's charge (σ): the breakdown band scales a run's
    #: outputs to its edges (σ, power σ²) instead of running at each; False where
    #: something nonlinear sits in the circuit (a rectifier's diodes)
    linear_in_charge: bool = True
    #: the circuit fills a store from empty, so its output is the whole run's history:
    #: a contact-charged run with ``[charge] waveforms = "auto"`` runs it over the whole
    #: run (the start-up), not only over the steady window (tengfield.contact_run)
    fills_store: bool = False
    #: the circuit states whose breakdown limit binds (tengfield.air_breakdown): all three
    #: for a load or a rectifier (its transferred charge lies between the open ones)
    breakdown_states: tuple[str, ...] = ("open", "open-top", "short")

    def states(self, scene) -> tuple[str, ...]:
        """The breakdown states of this kind in ``scene`` (an entry may depend on its
        keys, as the open circuit read through C_p does)."""
        return self.breakdown_states

    # -- one run: the contract the one loop drives (tengfield.electrical.loop) -----
    def check(self, scene) -> None:
        """Refuse a scene this circuit cannot run, before any work (SceneError)."""

    def start(self, scene, source, window_start: float, chunk_rows: int):
        """The circuit's state at the start of the run of ``source`` (a
        :class:`tengfield.source.Source`: the trajectory, the curves, the terminal), or None
        when there is nothing to integrate (the closed forms, or no charge moving). The state's ``chunk(i0, i1) -> {column: array}`` is a step over the
        output rows ``i0:i1`` (fed every chunk in order, the state carried);
        ``window_start`` [s] is the steady window's start on the run's own axis,
        ``chunk_rows`` the loop's chunk (the whole run: one chunk)."""
        return None

    def finish(self, scene, source, state, record: dict, note: str) -> CircuitRun:
        """The :class:`CircuitRun` after the last chunk: its stage text (``note`` ends it),
        details and ``data`` (what :meth:`summary` and :meth:`cycle` read), from ``state``
        (None where :meth:`start` gave none) and the loop's ``record``
        (:meth:`tengfield.electrical.loop.Loop.reduce`: ``tail``, the columns over the
        last periods, every row for a whole run, with ``_elapsed``;
        ``column_peak_to_peak``, this kind's columns over the window; ``columns``, a whole
        run's every column). No columns of its own: the loop has them."""
        return CircuitRun({}, f"kind = {scene.circuit.kind!r}: V_OC, Q_SC, I_SC in "
                              f"closed form; load ODE not run (no load){note}")

    def summary(self, scene, run: CircuitRun, waveforms, mask) -> dict:
        """The ``load`` block of summary.json (and ``load_reason`` when there is none);
        ``mask``: the steady window over the output samples."""
        return no_load(scene)

    def cycle(self, scene, source, run: CircuitRun, t, mask, max_gap) -> dict:
        """What this circuit adds to the energy per cycle: ``energy_per_cycle`` (numbers
        beside the CMEO bound), ``_vq`` (the V-Q loops of vq.png), ``_fine`` (the
        record of charging.png) and further summary blocks. ``t``: the output times on
        the run's own axis (a chunked run's last periods), ``mask`` its steady window
        (None: a chunked run's ``t`` lies in it), ``max_gap`` [m] the largest gap in it."""
        return {}

    # -- arrays (tengfield.array) -------------------------------------------
    def array_identical(self, scaled, dynamics, curves, waves) -> dict:
        """An array without spread (``scaled``: one cell with [device] cells = N): adds
        this kind's columns to ``waves`` and returns what array.png compares (``value``,
        ``reference_value``, ``compared``, ``output``, ``reference``, ``label``), and
        ``load``, ``fine``, ``summary`` blocks where the kind has them."""
        mask, _ = steady_window(waves["time_s"], scaled)
        p2p = lumped.peak_to_peak(waves["Q_sc_C"][mask])
        return dict(value=p2p, reference_value=p2p, compared="Q_SC peak-to-peak [C]",
                    output=waves["Q_sc_C"], reference=waves["Q_sc_C"], label="Q_SC [C]")

    def spread(self, scene, t, weights, origin) -> "SpreadCircuit":
        """The circuit of an array whose cells have their own dynamics, fed chunk by
        chunk (:class:`SpreadCircuit`); ``t``: the output times on the run's own axis,
        ``weights``: each distinct cell's count, ``origin``: the run's time origin."""
        return SpreadCircuit(scene, t, weights)


class SpreadCircuit:
    """The circuit of an array with spread: :meth:`chunk` sees every chunk of output
    times (the cells' Q_SC, C_T as (rows, cells) arrays and N x the nominal cell's),
    :meth:`finish` the sums and returns what array.png compares (as
    :meth:`Circuit.array_identical`). The base compares the Q_SC peak-to-peak."""

    def __init__(self, scene, t, weights):
        self.scene, self.t, self.weights = scene, t, weights

    def chunk(self, block, times, q, c, sums, ref_q, ref_c) -> None:
        """One chunk of rows ``block`` at ``times``: per-cell ``q``, ``c``; ``sums`` the
        array's Q, C, I so far; ``ref_q``, ``ref_c`` of one nominal cell."""

    def finish(self, sums, ref, columns, mask) -> dict:
        """What array.png compares; may add columns to ``columns``."""
        p2p = lumped.peak_to_peak(sums["Q"][mask])
        ref_p2p = lumped.peak_to_peak(ref["Q"][mask])
        return dict(value=p2p, reference_value=ref_p2p, compared="Q_SC peak-to-peak [C]",
                    output=sums["Q"], reference=ref["Q"], label="Q_SC [C]")


def no_load(scene) -> dict:
    """summary.json's blocks of a run with no load to report."""
    return {"load": None,
            "load_reason": f"[circuit] kind = {scene.circuit.kind!r}: no load to report"}


def _discover() -> dict[str, Circuit]:
    found: dict[str, Circuit] = {}
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
        module = importlib.import_module(f"{__name__}.{info.name}")
        entries = getattr(module, "CIRCUITS", None) or (
            (module.CIRCUIT,) if hasattr(module, "CIRCUIT") else ())
        for entry in entries:
            if entry.name in found:
                raise RuntimeError(f"circuit kind {entry.name!r} registered twice")
            found[entry.name] = entry
    return found


#: ``[circuit] kind`` -> its :class:`Circuit` (every module of this package that has one)
CIRCUITS: dict[str, Circuit] = _discover()


def circuit_for(scene) -> Circuit:
    """The registry entry of ``scene``'s ``[circuit] kind``."""
    return lookup(CIRCUITS, scene.circuit.kind, "[circuit] kind")


def all_columns() -> list[str]:
    """Every circuit's extra ``waveforms.csv`` columns, once each, in registry order
    (the order waveforms.csv writes those present)."""
    out: list[str] = []
    for entry in CIRCUITS.values():
        out += [c for c in entry.columns if c not in out]
    return out
