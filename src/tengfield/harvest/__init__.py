"""Harvesting electronics on the TENG terminals: full-bridge rectifiers, a storage
capacitor with leakage and a power-management chip with an under-voltage lockout
(pure numerics, SI; DESIGN §6 and §8).

Conventions of :mod:`tengfield.terminals` and :mod:`tengfield.lumped`: the
terminal voltage of a cell is ``V = V_lower - V_upper`` [V]; with ``Q_SC(z)``
[C] and ``C_T(z)`` [F] of the cell, ``C = C_T + C_p`` and ``Q_b`` the charge
that has left the lower terminal through the bridge (lower -> upper outside
the device), the cell's terminal law is ``V = (Q_SC - Q_b) / C``.

Each cell feeds a full bridge (two conduction paths of two diodes in series);
the bridges of all cells charge one store ``C_L`` at voltage ``U >= 0``:

* path A (V > 0) carries ``i(V - U)``, path B (V < 0) carries ``i(-V - U)``,
  with ``i(x)`` the current of two diodes in series at forward voltage ``x``
  (:class:`Diode`): ideal with forward drop ``V_F`` and series resistance
  ``R_s`` (``i = max(0, x - 2 V_F) / R_s``; ``R_s = 0`` is a clamp), or
  Shockley ``x = 2 n V_T ln(1 + i / I_s) + R_s i``;
* the store: ``C_L dU/dt = sum_cells (i_A + i_B) - U / R_leak - I_chip(U)``.

Time stepping (Moreau's scheme for the non-smooth diode law, first order,
unconditionally stable for any ``C_L``, ``R_s`` and ``I_s``), per grid step:

1. *move*: the ball moves with the bridges blocked; ``Q_SC`` and ``C`` take
   their new values, the terminal charge ``D = Q_SC - Q_b`` gains ``ΔQ_SC``.
   The terminal energy ``D^2 / (2 C)`` then changes by exactly the mechanical
   work done on the charges along that move (``dE/dt = V I_SC - V^2 dC/dt / 2``);
2. *transfer*: at fixed ``C`` the bridges conduct for the step length ``h``
   (backward Euler): per cell ``C (V - V') = h [i(V' - U') - i(-V' - U')]``
   and ``C_L (U' - U) = h sum [i(V' - U') + i(-V' - U')]``, solved exactly
   (monotone in ``U'``: bisection; per cell monotone in ``V'``);
3. *store*: leakage, the chip's quiescent current and its load act on ``U``
   over ``h`` (each exactly; the lockout switches at the exact crossing).

Energy bookkeeping is exact for this scheme: mechanical work = change of the
terminal energy + energy through the bridges; energy through the bridges =
diode loss + stored energy gained in step 2; the store's loss in step 3 =
leakage + quiescent + chip input. :func:`harvest` checks both balances.

:class:`Harvester` runs the same scheme in time chunks (its state carries
over), so long runs and many-cell arrays never hold the whole record;
:func:`harvest` is one chunk of it. The compiled (numba) kernels of the scheme are
in :mod:`tengfield.harvest._kernel`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._args import checked_write
from ..errors import SceneError
from ._kernel import _harvest_kernel, _path_current

BOLTZMANN_OVER_CHARGE = 8.617333262e-5   # k_B / e [V/K]

DIODE_MODELS = ("ideal", "shockley")
_IDEAL, _SHOCKLEY = 0, 1

#: LTC3588-1 (Linear Technology/Analog Devices data sheet, Electrical
#: Characteristics, typical values) with the 3.3 V output selected
#: (D1 = 1, D0 = 0): UVLO rising 5.05 V, falling 4.04 V, input shunt 20 V,
#: input quiescent current in UVLO 450 nA.
LTC3588_UVLO_RISING_V = 5.05
LTC3588_UVLO_FALLING_V = 4.04
LTC3588_SHUNT_V = 20.0
LTC3588_QUIESCENT_A = 450e-9


@dataclass(frozen=True)
class Diode:
    """One bridge diode (the bridge's paths have two in series).

    ``model`` "ideal": conducts above ``forward_voltage`` [V] through
    ``series_resistance`` [ohm] (0: a clamp). "shockley": ``i = I_s (e^{v/(n V_T)} - 1)``
    with ``saturation_current`` I_s [A], ``emission_coefficient`` n and
    ``series_resistance`` (per diode) at ``temperature`` [K].
    """
    model: str = "ideal"
    forward_voltage: float = 0.0
    saturation_current: float = 1e-12
    emission_coefficient: float = 1.0
    series_resistance: float = 0.0
    temperature: float = 300.0

    def __post_init__(self):
        if self.model not in DIODE_MODELS:
            raise SceneError(f"[circuit] diode = {self.model!r} is not allowed: choose one of "
                             + ", ".join(repr(m) for m in DIODE_MODELS))
        _check("diode_forward_voltage_V", self.forward_voltage, 0.0, 100.0)
        _check("diode_saturation_current_A", self.saturation_current, 1e-18, 1.0, lo_open=True)
        _check("diode_emission_coefficient", self.emission_coefficient, 0.5, 10.0)
        _check("diode_series_resistance_ohm", self.series_resistance, 0.0, 1e12)

    @property
    def thermal_voltage(self) -> float:
        return BOLTZMANN_OVER_CHARGE * self.temperature

    def path_current(self, x):
        """Current [A] of two diodes in series at total forward voltage ``x`` [V]."""
        x = np.asarray(x, dtype=float)
        out = np.empty_like(x)
        flat = out.reshape(-1)
        for k, value in enumerate(x.reshape(-1)):
            flat[k] = _path_current(value, *self._params())
        return out

    def _params(self):
        return (_IDEAL if self.model == "ideal" else _SHOCKLEY, self.forward_voltage,
                self.saturation_current, self.emission_coefficient * self.thermal_voltage,
                self.series_resistance)


@dataclass(frozen=True)
class PowerChip:
    """Under-voltage-lockout power chip on the store (the LTC3588-1 behaviour).

    Off until the store voltage rises through ``uvlo_rising`` [V], on until it
    falls through ``uvlo_falling`` [V]. While on it regulates ``output_voltage``
    [V] into ``load`` [ohm] and draws ``output_voltage^2 / load / efficiency``
    [W] from the store; always ``quiescent_current`` [A]; an input shunt holds
    the store at or below ``shunt_voltage`` [V].
    """
    uvlo_rising: float = LTC3588_UVLO_RISING_V
    uvlo_falling: float = LTC3588_UVLO_FALLING_V
    output_voltage: float = 3.3
    load: float = 1e5
    efficiency: float = 0.9
    quiescent_current: float = LTC3588_QUIESCENT_A
    shunt_voltage: float = LTC3588_SHUNT_V

    def __post_init__(self):
        _check("uvlo_falling_V", self.uvlo_falling, 0.0, 1e6, lo_open=True)
        if not self.uvlo_rising > self.uvlo_falling:
            raise SceneError(f"[circuit] uvlo_rising_V = {self.uvlo_rising:g} must exceed "
                             f"uvlo_falling_V = {self.uvlo_falling:g} (the lockout's hysteresis)")
        _check("pmic_output_V", self.output_voltage, 0.0, self.uvlo_falling, lo_open=True,
               note="below uvlo_falling_V (a buck converter)")
        _check("pmic_load_ohm", self.load, 0.0, math.inf, lo_open=True)
        _check("pmic_efficiency", self.efficiency, 0.0, 1.0, lo_open=True)
        _check("pmic_quiescent_current_A", self.quiescent_current, 0.0, 1.0)
        if not self.shunt_voltage > self.uvlo_rising:
            raise SceneError(f"[circuit] pmic_shunt_V = {self.shunt_voltage:g} must exceed "
                             f"uvlo_rising_V = {self.uvlo_rising:g}")

    @property
    def input_power(self) -> float:
        """Power drawn from the store while on [W]."""
        return self.output_voltage**2 / self.load / self.efficiency


def _check(key, value, lo, hi, *, lo_open=False, note=""):
    bad = not math.isfinite(value) if hi != math.inf else math.isnan(value)
    bad = bad or value < lo or value > hi or (lo_open and value == lo)
    if bad:
        left = "(" if lo_open else "["
        raise SceneError(f"[circuit] {key} = {value!r} is out of range: allowed {left}{lo:g}, {hi:g}]"
                         + (f" ({note})" if note else ""))


# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class HarvestResult:
    """Rectifier run on a time grid (SI). Cumulative energies [J] from the start.

    ``voltage[k, j]`` terminal voltage of cell j; ``bridge_charge[k, j]`` charge
    through cell j's bridge (lower -> upper outside); ``store_voltage[k]`` U;
    ``store_current[k]`` dQ_store/dt over the step ending at k; ``chip_on[k]``.
    ``threshold_times``: first time U rose through the UVLO threshold
    (``uvlo_rising_s``) and first lockout after that (``uvlo_falling_s``), NaN if never.
    """
    time: np.ndarray
    voltage: np.ndarray
    bridge_charge: np.ndarray
    store_voltage: np.ndarray
    store_current: np.ndarray
    stored_energy: np.ndarray
    chip_on: np.ndarray
    mechanical_work: np.ndarray
    bridge_energy: np.ndarray
    diode_loss: np.ndarray
    store_input: np.ndarray
    leakage_loss: np.ndarray
    quiescent_loss: np.ndarray
    chip_input_energy: np.ndarray
    shunt_loss: np.ndarray
    numerical_dissipation: np.ndarray
    terminal_energy: np.ndarray
    threshold_times: dict
    initial_terminal_energy: float | None = None    # [J] at the run's start (chunked runs)
    initial_stored_energy: float | None = None      # [J]
    #: [s] absolute time of ``time`` = 0: ``time`` and ``threshold_times`` are on the run's
    #: own axis (``[initial] time_s`` subtracted), the step lengths exact at any origin
    time_origin: float = 0.0
    #: the scene run (its ``[circuit]``: the chip's UVLO levels in charging.png), else None
    scene: Any = field(default=None, repr=False, compare=False)

    @property
    def t(self) -> np.ndarray:
        """The sample times [s] on the run's own axis (``time``, the older name)."""
        return self.time

    @property
    def summary(self) -> dict:
        """JSON-ready: the energy balance at the end [J], the UVLO crossing times [s]
        and the store's final voltage [V]."""
        out = dict(self.balance())
        out.update({k: float(v) for k, v in self.threshold_times.items()})
        out["final_store_voltage_V"] = float(self.store_voltage[-1])
        return out

    def plot(self):
        """The store voltage U(t) [V] (a matplotlib Figure)."""
        from ..plotting import new_figure

        fig = new_figure((8, 3.5))
        ax = fig.subplots()
        ax.plot(self.time, self.store_voltage, lw=1.0)
        ax.set_xlabel("t [s]")
        ax.set_ylabel("U store [V]")
        ax.grid(alpha=0.3)
        return fig

    @checked_write
    def write(self, out_dir, plots: bool = True, *, scene=None, title: str = "") -> list:
        """Write what ``tengfield run`` writes of the store record: charging.png (with
        ``plots``; ``scene``: default ``self.scene``); returns the paths."""
        from .output import write_harvest_files

        return write_harvest_files(self, out_dir, plots=plots, scene=scene, title=title)

    def balance(self) -> dict:
        """Energy accounts at the end of the run [J] and the residuals of the three
        balances relative to the energy delivered into the bridges.

        mechanical work = Δ terminal energy + delivered; delivered = diode loss +
        store input; store input = Δ stored + leakage + quiescent + chip + shunt +
        the backward-Euler step's own dissipation ``C_L ΔU^2 / 2`` (reported as
        ``numerical_dissipation_J``: the scheme's error, O(step))."""
        delivered = float(self.bridge_energy[-1])
        scale = max(abs(delivered), 1e-300)
        term0 = self.terminal_energy[0] if self.initial_terminal_energy is None \
            else self.initial_terminal_energy
        store0 = self.stored_energy[0] if self.initial_stored_energy is None \
            else self.initial_stored_energy
        d_term = float(self.terminal_energy[-1] - term0)
        d_store = float(self.stored_energy[-1] - store0)
        sinks = float(self.leakage_loss[-1] + self.quiescent_loss[-1]
                      + self.chip_input_energy[-1] + self.shunt_loss[-1])
        return {
            "mechanical_work_J": float(self.mechanical_work[-1]),
            "delivered_J": delivered,
            "diode_loss_J": float(self.diode_loss[-1]),
            "stored_change_J": d_store,
            "leakage_J": float(self.leakage_loss[-1]),
            "quiescent_J": float(self.quiescent_loss[-1]),
            "chip_input_J": float(self.chip_input_energy[-1]),
            "shunt_J": float(self.shunt_loss[-1]),
            "numerical_dissipation_J": float(self.numerical_dissipation[-1]),
            "terminal_residual": abs(float(self.mechanical_work[-1]) - d_term - delivered) / scale,
            "bridge_residual": abs(delivered - float(self.diode_loss[-1])
                                   - float(self.store_input[-1])) / scale,
            "store_residual": abs(float(self.store_input[-1]) - d_store - sinks
                                  - float(self.numerical_dissipation[-1])) / scale,
        }


class Harvester:
    """A rectifier run that goes in time chunks (long or many-cell runs never hold
    the whole record): ``advance(times, q_sc, c_t)`` continues from where the last
    call ended and returns that chunk's :class:`HarvestResult` (energies and
    bridge charges cumulative from the start; ``balance()`` of any chunk covers
    the run so far). The first chunk's first row is the start (open-circuit
    state); later chunks continue from the last row seen (their first step goes
    from that row's time to their first time). Parameters as :func:`harvest`;
    ``time_origin`` [s]: the absolute time of ``times`` = 0 (pass times relative to
    the run's start: at 1.7e9 s the doubles are too coarse for the step lengths),
    kept in each result as ``HarvestResult.time_origin``.
    """

    def __init__(self, n_cells: int, *, storage_capacitance: float, diode: Diode = Diode(),
                 parallel_capacitance: float = 0.0, leakage: float = math.inf,
                 chip: PowerChip | None = None, initial_store_voltage: float = 0.0,
                 time_origin: float = 0.0):
        _check("storage_capacitance_uF", storage_capacitance * 1e6, 0.0, 1e12, lo_open=True)
        self.time_origin = float(time_origin)
        _check("storage_leakage_ohm", leakage, 0.0, math.inf, lo_open=True)
        self.n_cells = int(n_cells)
        self.storage_capacitance = float(storage_capacitance)
        self.diode = diode
        self.parallel_capacitance = float(parallel_capacitance)
        self.leakage = float(leakage)
        self.chip = chip
        self.deficit = np.zeros(self.n_cells)
        self.state = np.array([float(initial_store_voltage), 0.0, math.nan, math.nan])
        self.acc = np.zeros(9)
        self.last = None            # (t, q row, c row, bridge charge row) of the last row
        self.initial_terminal_energy = self.initial_stored_energy = None

    @property
    def store_voltage(self) -> float:
        return float(self.state[0])

    def advance(self, times, q_sc, c_t) -> "HarvestResult":
        t = np.ascontiguousarray(np.atleast_1d(times), dtype=float)
        q = np.asarray(q_sc, dtype=float)
        c = np.asarray(c_t, dtype=float) + self.parallel_capacitance
        if q.ndim == 1:
            q, c = q[:, None], c[:, None]
        if q.shape != c.shape or q.shape[0] != t.size or q.shape[1] != self.n_cells:
            raise ValueError(f"q_sc {q.shape} and c_t {c.shape} must have one row per time "
                             f"({t.size}) and {self.n_cells} columns")
        first = self.last is None
        if not first:
            t = np.concatenate([[self.last[0]], t])
            q = np.vstack([self.last[1][None, :], q])
            c = np.vstack([self.last[2][None, :], c])
        if np.any(np.diff(t) < 0):
            raise ValueError("times must be non-decreasing")
        q = np.ascontiguousarray(q)
        c = np.ascontiguousarray(c)
        if first:
            self.deficit[:] = q[0]            # Q_b = 0 at the start: open-circuit state
            self.initial_terminal_energy = float(0.5 * np.sum(q[0] ** 2 / c[0]))
            self.initial_stored_energy = 0.5 * self.storage_capacitance * self.state[0] ** 2
        n_steps = t.size
        volts = np.empty((n_steps, self.n_cells))
        store = np.empty(n_steps)
        bridge = np.empty((n_steps, self.n_cells))
        chip_on = np.empty(n_steps, dtype=np.int8)
        energies = np.empty((n_steps, 9))
        chip = self.chip or PowerChip()
        _harvest_kernel(q, c, t, self.storage_capacitance, self.leakage, *self.diode._params(),
                        self.chip is not None, chip.uvlo_rising, chip.uvlo_falling,
                        chip.input_power, chip.quiescent_current, chip.shunt_voltage,
                        self.deficit, self.state, self.acc, volts, store, bridge, chip_on,
                        energies)
        current = np.zeros(n_steps)           # bridge current into the store over each step [A]
        dt = np.diff(t)
        ok = dt > 0
        into_store = np.diff(energies[:, 3])
        current[1:][ok] = into_store[ok] / np.maximum(store[1:][ok], 1e-300) / dt[ok]
        if not first:
            bridge += self.last[3]
        self.last = (float(t[-1]), q[-1].copy(), c[-1].copy(), bridge[-1].copy())
        rows = slice(0 if first else 1, None)
        terminal = 0.5 * np.sum(volts[rows] ** 2 * c[rows], axis=1)
        e = energies[rows]
        return HarvestResult(
            time=t[rows], voltage=volts[rows], bridge_charge=bridge[rows],
            store_voltage=store[rows], store_current=current[rows],
            stored_energy=0.5 * self.storage_capacitance * store[rows] ** 2,
            chip_on=chip_on[rows].astype(bool), mechanical_work=e[:, 0], bridge_energy=e[:, 1],
            diode_loss=e[:, 2], store_input=e[:, 3], leakage_loss=e[:, 4],
            quiescent_loss=e[:, 5], chip_input_energy=e[:, 6], shunt_loss=e[:, 7],
            numerical_dissipation=e[:, 8], terminal_energy=terminal,
            threshold_times={"uvlo_rising_s": float(self.state[2]),
                             "uvlo_falling_s": float(self.state[3])},
            initial_terminal_energy=self.initial_terminal_energy,
            initial_stored_energy=self.initial_stored_energy, time_origin=self.time_origin)


def harvest(times, q_sc, c_t, *, storage_capacitance: float, diode: Diode = Diode(),
            parallel_capacitance: float = 0.0, leakage: float = math.inf,
            chip: PowerChip | None = None, initial_store_voltage: float = 0.0) -> HarvestResult:
    """Charge a store through full bridges, one per cell (columns of ``q_sc``/``c_t``).

    ``times`` [s] non-decreasing; ``q_sc`` [C] and ``c_t`` [F] of each cell at
    those times (1-D arrays for one cell); ``parallel_capacitance`` C_p [F]
    across each cell's terminals; ``storage_capacitance`` C_L [F];
    ``leakage`` [ohm] across the store (inf: none). All cells start in the
    open-circuit state (no charge through the bridges). One chunk of a
    :class:`Harvester`.
    """
    q = np.asarray(q_sc, dtype=float)
    n_cells = 1 if q.ndim == 1 else q.shape[1]
    run = Harvester(n_cells, storage_capacitance=storage_capacitance, diode=diode,
                    parallel_capacitance=parallel_capacitance, leakage=leakage, chip=chip,
                    initial_store_voltage=initial_store_voltage)
    return run.advance(times, q_sc, c_t)


def mean_bridge_current(result: HarvestResult, start: int = 0) -> float:
    """Mean current [A] through the bridges into the store from row ``start`` on: the
    charge every cell's bridge moved (``|Δ bridge_charge|``, summed over the cells and
    steps) over the time."""
    length = float(result.time[-1] - result.time[start])
    if length <= 0.0:
        return 0.0
    moved = np.abs(np.diff(result.bridge_charge[start:], axis=0)).sum()
    return float(moved) / length


def warn_quiescent_starvation(result: HarvestResult, quiescent_current: float,
                              start: int = 0) -> bool:
    """One ``tengfield: warning:`` line, and True, when the store stayed at 0 V from row
    ``start`` on under a chip whose quiescent current [A] exceeds the mean current the
    bridges deliver (:func:`mean_bridge_current`): the chip takes the charge as it
    comes, nothing is stored or harvested (the kernel books no energy into the store
    then; issue #30.5)."""
    if quiescent_current <= 0.0 or float(np.max(result.store_voltage[start:])) > 0.0:
        return False
    return warn_starved_store(float(np.max(result.store_voltage[start:])),
                              mean_bridge_current(result, start), quiescent_current)


def warn_starved_store(max_store_voltage: float, current: float,
                       quiescent_current: float) -> bool:
    """:func:`warn_quiescent_starvation` from its numbers: the store's largest voltage [V]
    and the bridges' mean current [A] over the window (a streamed run's reductions)."""
    import warnings

    if quiescent_current <= 0.0 or max_store_voltage > 0.0 or current >= quiescent_current:
        return False
    warnings.warn(
        f"rectifier: the chip's quiescent current ([circuit] pmic_quiescent_current_A = "
        f"{quiescent_current:.3g} A) exceeds the mean current the bridges deliver "
        f"({current:.3g} A): the store stays at 0 V and nothing is harvested (a larger "
        "charge or device, more cells, or a chip with a lower quiescent draw)",
        RuntimeWarning, stacklevel=3)
    return True


def saturation_voltage(q_sc_max: float, c_max: float, c_min: float, forward_voltage: float = 0.0):
    """Store voltage [V] a periodic TENG charges an ideal bridge's store to (no load).

    A half stroke moves the cell from (Q_SC = 0, C(0)) to (Q_SC,max, C(x_max)) and
    back; at saturation the terminal swings between ``±(U + 2 V_F)`` without
    conducting: ``Q_SC,max = (C_max + C_min)(U + 2 V_F)`` with C_max, C_min the
    terminal capacitances (C_T + C_p) at the two ends [F] (Niu et al., Nano
    Energy 2014). Returns ``U_sat = Q_SC,max / (C_max + C_min) - 2 V_F``.
    """
    return q_sc_max / (c_max + c_min) - 2.0 * forward_voltage


def max_energy_per_cycle(q_sc_max: float, c_at_max: float, c_at_zero: float) -> float:
    """Cycles for maximised energy output (Zi et al., Nat. Commun. 6:8376, 2015) [J].

    Move open-circuit 0 -> x_max (V rises to V_OC,max = Q_SC,max / C(x_max)),
    short at x_max, move back open (V' = -Q_SC,max / C(0)), short at 0:
    ``E_m = Q_SC,max (V_OC,max + |V'_max|) / 2``.
    """
    return 0.5 * q_sc_max**2 * (1.0 / c_at_max + 1.0 / c_at_zero)


def structural_figure_of_merit(energy_per_cycle: float, surface_charge: float, area: float,
                               max_displacement: float) -> float:
    """FOM_S = 2 ε0 E_m / (σ² A x_max) (Zi et al. 2015), dimensionless.

    ``area`` [m^2] is the charged area (tengfield uses the ball's surface π d²),
    ``max_displacement`` x_max [m] the free stroke.
    """
    from ..scene.constants import EPS0
    return 2.0 * EPS0 * energy_per_cycle / (surface_charge**2 * area * max_displacement)
