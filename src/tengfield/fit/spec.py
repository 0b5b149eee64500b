"""The ``[fit]`` section of a scene, measured traces and scalar targets, validated.

Scene syntax (every key optional)::

    [fit]
    time_column = "time_s"        # the measured CSV's time column
    time_unit = "s"               # s, ms, us (default: the header's, "TIME [ms]", else s)
    header_row = 0                # the header's line (1-based); 0: the first naming time_column
    loss = "linear"               # or soft_l1, huber, cauchy, arctan (robust)
    loss_scale = 1.0              # residual (in noise units) where a robust loss turns over
    max_evaluations = 200
    profile = false               # profile the poorly determined parameters
    bootstrap = 0                 # moving-block bootstrap replicas (trace fits)

    [fit.columns.V]               # V, Q and/or I; each: a CSV column, its unit, its noise
    column = "V_meas"
    unit = "V"                    # V: uV mV V kV; Q: pC nC uC C; I: pA nA uA mA A
    noise = 0.02                  # 1-sigma noise, in `unit` (optional: else estimated)

    [fit.parameters]              # the free parameters, in scene-file units
    <σ's key> = {start = -20.0, min = -100.0, max = 0.0}   # SURFACE_CHARGE_KEY, µC/m^2
    parallel_capacitance_pF = {min = 0.0, max = 1000.0}
    time_shift_s = {}             # defaults: start from cross-correlation, bounds [0, 2 periods]

Without ``[fit.columns]`` the columns of a ``tengfield run`` waveforms.csv
(``V_oc_V``, ``Q_sc_C``, ``I_sc_A``) found in the file are used; without
``[fit.parameters]`` σ and the time shift are free.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

import numpy as np

from ..dynamics.excitation import excitation_kind as _excitation
from ..electrical import CIRCUITS, Circuit, circuit_for
from ..errors import SceneError, header_described, same_name_in_file
from ..quantities import describe
from ..scene.recorded import (HEADER_TIME_UNITS, Export, check_magnitude, check_time_steps,
                              read_export, split_unit)
from ..scene.schema import SURFACE_CHARGE_KEY
from ..scene.schema import suggest as _suggest
from .compared import INFIXES, LETTERS, MEASURED_KEYS, model_columns

#: the free parameters a fit knows: (default bounds, transform, unit, meaning)
PARAMETERS = {
    SURFACE_CHARGE_KEY: ((-200.0, 200.0), "linear", "µC/m^2", "ball surface charge σ"),
    "parallel_capacitance_pF": ((0.0, 1.0e5), "linear", "pF", "instrument + cable capacitance C_p"),
    "restitution": ((0.0, 0.99), "linear", "", "coefficient of restitution e"),
    "load_ohm": ((1.0, 1.0e14), "log", "ohm", "load resistance R"),
    "time_shift_s": ((None, None), "linear", "s", "model time of the trace's first sample "
                     "after the steady-window start"),
    "amplitude_scale": ((0.2, 5.0), "linear", "", "excitation amplitude / scene amplitude"),
}

UNITS = {
    "V": {"uV": 1e-6, "mV": 1e-3, "V": 1.0, "kV": 1e3},
    "Q": {"pC": 1e-12, "nC": 1e-9, "uC": 1e-6, "C": 1.0},
    "I": {"pA": 1e-12, "nA": 1e-9, "uA": 1e-6, "mA": 1e-3, "A": 1.0},
}
TIME_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6}
#: columns of a ``tengfield run`` waveforms.csv (the terminal's), used when [fit.columns]
#: is absent and the circuit names no others
RUN_COLUMNS = Circuit.fit_columns


def run_columns(kind: str) -> dict:
    """The waveforms.csv columns (name, unit) of V, Q and I the fit compares for a scene
    with ``[circuit] kind``: its registry entry's ``fit_columns`` (the load's voltage
    and current for "load", else V_OC, I_SC)."""
    from .._registry import lookup
    return lookup(CIRCUITS, kind, "[circuit] kind").fit_columns
LOSSES = ("linear", "soft_l1", "huber", "cauchy", "arctan")
MIN_SAMPLES = 8
#: Bytes and data rows of a measured trace (checked before / while reading): every row
#: costs a dynamics sample and a residual per evaluation; 2e6 rows is 100 s at 20 kHz.
MAX_TRACE_BYTES = 200_000_000
MAX_TRACE_ROWS = 2_000_000
#: |value| in SI of a measured column (1 MV, 1 C, 1 kA are far beyond any TENG):
#: a trace scaled by 1e300 overflowed the residual's squares
MAX_TRACE_VALUE = {"V": 1e6, "Q": 1.0, "I": 1e3}
#: widest time_shift_s range [periods]: the start scan and the dynamics span it (1e9 s
#: asked for a 146 TiB grid)
MAX_SHIFT_PERIODS = 100
#: |time| [s] of a trace (the [initial] time_s bound)
MAX_TRACE_TIME = 1e12


def _interval(lo: float, hi: float, lo_open: bool = False, hi_open: bool = False) -> str:
    """``[lo, hi]`` as a message writes it (an infinite end open: ``(0, inf)``)."""
    left = "(" if lo_open or lo == -math.inf else "["
    right = ")" if hi_open or hi == math.inf else "]"
    return f"{left}{lo:g}, {hi:g}{right}"


def _number(where: str, value, lo=-math.inf, hi=math.inf, lo_open: bool = False,
            hi_open: bool = False) -> float:
    """``value`` a finite number in the key's range (the ends open as given); a NaN or an
    infinity is "expected a finite number", with the range when it bounds anything."""
    bounded = lo != -math.inf or hi != math.inf
    interval = _interval(lo, hi, lo_open, hi_open)
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise SceneError(f"{where} = {value!r}: expected a finite number"
                         + (f" in {interval}" if bounded else ""))
    inside = (value > lo if lo_open else value >= lo) and (value < hi if hi_open else value <= hi)
    if not inside:
        raise SceneError(f"{where} = {value!r} is out of range: allowed {interval}")
    return float(value)


#: the range of a free parameter's bounds (min, max), by name: (lo, hi, lo_open, hi_open);
#: a log-scaled parameter's are above 0, the others any finite number
BOUND_RANGES = {"restitution": (0.0, 1.0, False, False),
                "parallel_capacitance_pF": (0.0, math.inf, False, True),
                "amplitude_scale": (0.0, math.inf, True, True)}


def _bound_range(name: str, transform: str) -> tuple:
    if name in BOUND_RANGES:
        return BOUND_RANGES[name]
    return (0.0, math.inf, True, True) if transform == "log" else (-math.inf, math.inf, True, True)


def _refuse_unknown_keys(entry: dict, keys: tuple, where: str, separator: str) -> None:
    """SceneError "unknown key {where}{separator}{key}; keys are ..." for the first key of
    the sub-table ``entry`` that is not in ``keys``."""
    for key in entry:
        if key not in keys:
            raise SceneError(f"unknown key {where}{separator}{key}; keys are {', '.join(keys)}"
                             + _suggest(key, keys))


def _whole_number(where: str, value, lo: int, hi: int, what: str = "a whole number") -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
        raise SceneError(f"{where} = {value!r}: expected {what} in [{lo}, {hi}]")
    return value


@dataclass
class Parameter:
    """A free parameter in scene-file units with bounds [lo, hi] and a start value."""
    name: str
    start: float | None
    lo: float
    hi: float
    transform: str = "linear"
    start_given: bool = True


@dataclass
class Column:
    quantity: str           # V, Q or I
    column: str
    unit: str
    noise: float | None     # SI, 1-sigma
    unit_given: bool = False   # [fit.columns.X] unit given (else a header's unit is used)

    @property
    def factor(self) -> float:
        return UNITS[self.quantity][self.unit]


@dataclass
class FitSpec:
    time_column: str = "time_s"
    time_unit: str = "s"
    loss: str = "linear"
    loss_scale: float = 1.0
    max_evaluations: int = 200
    profile: bool = False
    bootstrap: int = 0
    header_row: int = 0
    time_unit_given: bool = False
    columns: list[Column] | None = None
    parameters: list[Parameter] = field(default_factory=list)
    #: columns used without [fit.columns]: :func:`run_columns` of the scene's circuit
    default_columns: dict = field(default_factory=lambda: dict(RUN_COLUMNS))
    #: {V|Q|I: (column, same)}: the run's column of what the model compares, and whether
    #: the default column holds the same numbers (:func:`~.compared.model_columns`)
    model_columns: dict = field(default_factory=dict)


def parse_fit_section(scene, free: list[str] | None = None) -> FitSpec:
    """Validate ``scene.raw["fit"]``; ``free`` (names) overrides the free parameters."""
    raw = scene.raw.get("fit", {}) or {}
    known = ("time_column", "time_unit", "loss", "loss_scale", "max_evaluations", "profile",
             "bootstrap", "columns", "parameters", "header_row")
    for key in raw:
        if key not in known:
            raise SceneError(f"unknown key [fit] {key}" + _suggest(key, known)
                             + f"; keys are {', '.join(known)}")
    spec = FitSpec()
    for key in ("time_column", "time_unit", "loss"):
        if key in raw:
            if not isinstance(raw[key], str):
                raise SceneError(f"[fit] {key} = {raw[key]!r}: expected a string")
            setattr(spec, key, raw[key])
    if spec.time_unit not in TIME_UNITS:
        raise SceneError(f"[fit] time_unit = {spec.time_unit!r} is not allowed: choose one of "
                         + ", ".join(map(repr, TIME_UNITS)))
    if spec.loss not in LOSSES:
        raise SceneError(f"[fit] loss = {spec.loss!r} is not allowed: choose one of "
                         + ", ".join(map(repr, LOSSES)) + _suggest(spec.loss, LOSSES))
    if "loss_scale" in raw:
        spec.loss_scale = _number("[fit] loss_scale", raw["loss_scale"], 1e-12, 1e12)
        if spec.loss_scale <= 0:
            raise SceneError(f"[fit] loss_scale = {raw['loss_scale']!r} must be > 0")
    if "max_evaluations" in raw:
        spec.max_evaluations = _whole_number("[fit] max_evaluations", raw["max_evaluations"],
                                             5, 100000)
    if "profile" in raw:
        if not isinstance(raw["profile"], bool):
            raise SceneError(f"[fit] profile = {raw['profile']!r}: expected true or false")
        spec.profile = raw["profile"]
    spec.time_unit_given = "time_unit" in raw
    if "header_row" in raw:
        spec.header_row = _whole_number("[fit] header_row", raw["header_row"], 0, 10**7,
                                        "a line number (0: found)")
    if "bootstrap" in raw:
        spec.bootstrap = _whole_number("[fit] bootstrap", raw["bootstrap"], 0, 10000,
                                       "a whole number of replicas")
    spec.default_columns = dict(run_columns(scene.circuit.kind))
    spec.model_columns = model_columns(scene)
    spec.columns = _columns(raw.get("columns"), spec.default_columns) if "columns" in raw \
        else None
    spec.parameters = _parameters(scene, raw.get("parameters"), free)
    return spec


def _columns(raw, defaults: dict = RUN_COLUMNS) -> list[Column]:
    if not isinstance(raw, dict) or not raw:
        raise SceneError("[fit.columns] must be a table with V, Q and/or I sub-tables")
    columns = []
    for quantity, entry in raw.items():
        where = f"[fit.columns.{quantity}]"
        if quantity not in UNITS:
            raise SceneError(f"unknown quantity {where}: allowed V, Q, I" + _suggest(quantity, UNITS))
        if not isinstance(entry, dict):
            raise SceneError(f"{where} must be a table (column, unit, noise)")
        _refuse_unknown_keys(entry, ("column", "unit", "noise"), where, " ")
        column = entry.get("column", defaults[quantity][0])
        unit = entry.get("unit", defaults[quantity][1])
        if not isinstance(column, str) or not column:
            raise SceneError(f"{where} column = {column!r}: expected a column name")
        if unit not in UNITS[quantity]:
            raise SceneError(f"{where} unit = {unit!r} is not allowed: choose one of "
                             + ", ".join(map(repr, UNITS[quantity])) + _suggest(unit, UNITS[quantity]))
        noise = None
        if "noise" in entry:
            noise = _number(f"{where} noise", entry["noise"], 0.0, math.inf, lo_open=True)
            noise *= UNITS[quantity][unit]
        columns.append(Column(quantity, column, unit, noise, unit_given="unit" in entry))
    return columns


def _parameters(scene, raw, free) -> list[Parameter]:
    if raw is None:
        raw = {}
    if not isinstance(raw, dict):
        raise SceneError("[fit.parameters] must be a table: name = {start, min, max}")
    if free is not None:
        names = list(free)
        raw = {name: raw.get(name, {}) for name in names}
    elif not raw:
        raw = {SURFACE_CHARGE_KEY: {}, "time_shift_s": {}}
    params = []
    period = scene.excitation.period
    for name, entry in raw.items():
        where = f"[fit.parameters] {name}"
        if name not in PARAMETERS:
            raise SceneError(f"unknown fit parameter {name!r}" + _suggest(name, PARAMETERS)
                             + f"; free parameters are {', '.join(PARAMETERS)}")
        if not isinstance(entry, dict):
            raise SceneError(f"{where} = {entry!r}: expected a table {{start, min, max}}")
        _refuse_unknown_keys(entry, ("start", "min", "max"), where, ".")
        (lo, hi), transform, _, _ = PARAMETERS[name]
        if name == "time_shift_s":
            lo, hi = 0.0, 2.0 * period
        allowed = _bound_range(name, transform)
        lo = _number(f"{where}.min", entry["min"], *allowed) if "min" in entry else lo
        hi = _number(f"{where}.max", entry["max"], *allowed) if "max" in entry else hi
        if not lo < hi:
            raise SceneError(f"{where}: min = {lo:g} must be < max = {hi:g}")
        if name == "time_shift_s" and hi - lo > MAX_SHIFT_PERIODS * period:
            raise SceneError(f"{where}: bounds [{lo:g}, {hi:g}] s span {(hi - lo) / period:.3g} "
                             f"periods: allowed at most {MAX_SHIFT_PERIODS} periods "
                             f"({MAX_SHIFT_PERIODS * period:g} s; in a steady state shifts one "
                             "period apart are equivalent)")
        if name == "amplitude_scale":
            if not _excitation(scene).periodic:
                raise SceneError(f"{where}: only a sine excitation can be scaled "
                                 f"([excitation] kind = {scene.excitation.kind!r})")
        if name == "load_ohm" and not circuit_for(scene).fit_load:
            raise SceneError(f"{where}: the scene has no load ([circuit] kind = "
                             f"{scene.circuit.kind!r}); set kind = 'load' to fit load_ohm")
        given = "start" in entry
        start = _number(f"{where}.start", entry["start"], lo, hi) if given else _scene_value(scene, name)
        if start is not None:
            start = min(max(start, lo), hi)
        if name == SURFACE_CHARGE_KEY and start == 0.0:
            raise SceneError(f"{where}.start = 0: a zero charge gives no signal to scale; "
                             "start from a non-zero value in [min, max]")
        params.append(Parameter(name, start, lo, hi, transform, given))
    return params


def _scene_value(scene, name: str) -> float | None:
    """The scene's own value of a fit parameter (file units); None for the time shift."""
    return {SURFACE_CHARGE_KEY: scene.device.surface_charge * 1e6 or -1.0,
            "parallel_capacitance_pF": scene.circuit.parallel_capacitance * 1e12,
            "restitution": scene.contact.restitution,
            "load_ohm": scene.circuit.load,
            "amplitude_scale": 1.0,
            "time_shift_s": None}[name]


# ---------------------------------------------------------------------------
@dataclass
class Trace:
    """A measured trace: times [s] and {quantity: values [SI]}, with its columns."""
    source: str
    time: np.ndarray
    values: dict
    columns: list[Column]

    @property
    def span(self) -> float:
        return float(self.time[-1] - self.time[0])


def read_trace(path, spec: FitSpec) -> Trace:
    """Read the measured CSV named by ``--measured`` (header row, comma separated; the
    scene's CSV reader, :func:`tengfield.scene.recorded.read_table`)."""
    name = str(path)
    what = f"--measured {name!r}"
    from ..files.hdf5 import is_hdf5, read_waveform_table

    if is_hdf5(name):     # tengfield run's own run.h5: its /waveforms table (SI columns)
        table = read_waveform_table(name, what, max_rows=MAX_TRACE_ROWS)
        layout = Export(1, ",", False, {})
    else:
        table, layout = read_export(name, None, what, time_column=spec.time_column,
                                    header_row=spec.header_row, max_bytes=MAX_TRACE_BYTES,
                                    max_rows=MAX_TRACE_ROWS)
    header = table.header
    if not header:
        raise SceneError(f"{what} is empty: expected a header row and at least "
                         f"{MIN_SAMPLES} data rows")
    columns = spec.columns
    if columns is not None:     # a name given with its unit ("CH1(V)") names the column
        columns = [Column(c.quantity, split_unit(c.column)[0], c.unit, c.noise, c.unit_given)
                   for c in columns]
    if columns is None:
        defaults = dict(spec.default_columns)
        if defaults.get("V", ("",))[0] == "V_oc_V" and "V_read_V" in header:
            defaults["V"] = ("V_read_V", "V")   # a run read through C_p: the model's V
        defaults = _read_defaults(defaults, spec.model_columns, header, what)
        columns = [Column(q, c, u, None) for q, (c, u) in defaults.items() if c in header]
        if not columns:
            raise SceneError(f"{what} has none of the columns "
                             f"{', '.join(c for c, _ in defaults.values())} on its header line "
                             f"{layout.header_line}: name the columns in [fit.columns] "
                             f"({header_described(header)})")
    columns = [_header_unit(c, layout, what) for c in columns]
    time_column = split_unit(spec.time_column)[0]
    wanted = [("[fit] time_column", time_column)] + \
             [(f"[fit.columns.{c.quantity}] column", c.column) for c in columns]
    for where, col in wanted:
        if col not in header:
            raise SceneError(f"{where} = {col!r} is not a column of {name!r}: expected it "
                             f"on the header line {layout.header_line} (with or without its "
                             "unit; give [fit] header_row = N when the header is elsewhere; "
                             f"{header_described(header)})" + same_name_in_file(col, header))
    if len(table.rows) < MIN_SAMPLES:
        raise SceneError(f"{what} has {len(table.rows)} data rows: at least "
                         f"{MIN_SAMPLES} are needed")

    def column(col: str) -> np.ndarray:
        out = table.column(col, allow_blank=True)
        bad = np.flatnonzero(~np.isfinite(out))
        if bad.size:
            raise SceneError(f"{what}: column {col!r} holds NaN, inf or a blank at "
                             f"data row {bad[0] + 1} ({bad.size} such rows); remove or fill them")
        return out

    time = column(time_column) * _time_factor(spec, layout, time_column, what)
    check_magnitude(time, MAX_TRACE_TIME, what, f"time column {spec.time_column!r}", "s")
    check_time_steps(time, what)
    values = {}
    for c in columns:
        values[c.quantity] = column(c.column) * c.factor
        check_magnitude(values[c.quantity], MAX_TRACE_VALUE[c.quantity], what,
                        f"column {c.column!r} (SI)", RUN_COLUMNS[c.quantity][1])
    return Trace(name, time, values, columns)


def _read_defaults(defaults: dict, model: dict, header, what: str) -> dict:
    """``defaults`` ({V|Q|I: (column, unit)}) with the column of what the model compares
    where the file has it (``model``: :func:`~.compared.model_columns`; a run's
    ``V_read_V``, ``Q_read_C``, ``I_read_A`` for a model read through an ``[instrument]``).
    A file with only the terminal's own column where the reading differs from it (the
    ideal V_OC against a voltage read through C_p: kV against ~1 V) is refused in one
    line: ``[fit.columns]`` names a column to compare anyway."""
    out = dict(defaults)
    for q, (want, same) in model.items():
        if q not in out or out[q][0] == want:
            continue
        column, unit = out[q]
        if want in header:
            out[q] = (want, unit)
        elif column in header and not same:
            raise SceneError(
                f"{what} has {column} but not {want}, the {describe(want, unit=False)} the "
                f"model compares: give a trace read by the same [instrument] (a run's "
                f"{want}), or name the column in [fit.columns.{q}] to compare it anyway")
    return out


def _disagree(what: str, column: str, header_unit: str, key: str) -> None:
    """The one refusal of a unit the scene gives that the trace's header contradicts (a
    header ``t [ms]`` read as seconds fitted nothing: "no signal at the start values")."""
    raise SceneError(f"{what}: the header gives {column} the unit {header_unit!r}, but "
                     f"{key}: they disagree; drop the key (the header's unit is used) or "
                     "write the header's")


def _time_factor(spec: FitSpec, layout, column: str, what: str) -> float:
    """Seconds per unit of the trace's time column: ``[fit] time_unit`` when given, else
    the header's (``TIME [ms]``), else s."""
    unit = layout.units.get(column, "")
    if spec.time_unit_given and unit in HEADER_TIME_UNITS \
            and HEADER_TIME_UNITS[unit] != TIME_UNITS[spec.time_unit]:
        _disagree(what, f"the time column {column!r}", unit, f"[fit] time_unit = "
                  f"{spec.time_unit!r}")
    if spec.time_unit_given or not unit:
        return TIME_UNITS[spec.time_unit]
    if unit not in HEADER_TIME_UNITS:
        raise SceneError(f"{what}: the header gives the time column {column!r} a unit "
                         f"tengfield does not know: expected one of {', '.join(HEADER_TIME_UNITS)}"
                         " (or give [fit] time_unit)")
    return HEADER_TIME_UNITS[unit]


def _header_unit(c: Column, layout, what: str) -> Column:
    """``c`` with the unit its header gives (``CH1(V)``, ``Q [nC]``) unless ``[fit.columns]``
    gave one."""
    unit = layout.units.get(c.column, "")
    unit = {"µV": "uV", "µC": "uC", "µA": "uA"}.get(unit, unit)
    if c.unit_given and unit in UNITS[c.quantity] and unit != c.unit:
        _disagree(what, f"column {c.column!r}", unit,
                  f"[fit.columns.{c.quantity}] unit = {c.unit!r}")
    if c.unit_given or not unit:
        return c
    if unit not in UNITS[c.quantity]:
        raise SceneError(f"{what}: the header gives column {c.column!r} a unit tengfield does "
                         f"not know for {c.quantity}: expected one of "
                         f"{', '.join(UNITS[c.quantity])} (or give [fit.columns.{c.quantity}] unit)")
    return Column(c.quantity, c.column, unit, c.noise, c.unit_given)


# ---------------------------------------------------------------------------
#: a target's name: {V,Q,I}_{pp,peak}_{unit}, the letters and infixes of the quantity table
_TARGET = re.compile(rf"^(?P<q>[{''.join(LETTERS)}])_(?P<kind>{'|'.join(INFIXES)})"
                     r"_(?P<unit>[A-Za-z]+)$")
#: examples of target names for the messages: the [reference] keys of the table
TARGET_EXAMPLES = ", ".join(dict.fromkeys(MEASURED_KEYS.values()))


@dataclass
class Target:
    """A scalar target: peak-to-peak (``pp``) or peak |x| (``peak``) of V, Q or I."""
    quantity: str
    kind: str
    unit: str
    value: float        # SI
    uncertainty: float  # SI, 1-sigma
    uncertainty_given: bool

    @property
    def key(self) -> str:
        return f"{self.quantity}_{self.kind}"

    @property
    def label(self) -> str:
        return f"{self.quantity}_{self.kind}_{self.unit}"

    @property
    def factor(self) -> float:
        return UNITS[self.quantity][self.unit]

    @property
    def statistic(self) -> str:
        """``peak_to_peak`` or ``peak`` (tengfield.quantities.STATISTICS)."""
        return INFIXES[self.kind]

    @property
    def measured_key(self) -> str:
        """The ``[reference]`` key of this measured value (``V_pp_mV`` -> ``V_pp_V``)."""
        return MEASURED_KEYS[(self.quantity, self.statistic)]


#: relative 1-sigma uncertainty of a target given without ``+-``
DEFAULT_TARGET_UNCERTAINTY = 0.05


def parse_targets(items) -> list[Target]:
    """``["V_pp_V=4.2", "Q_pp_nC=1.42+-0.05", "I_peak_uA=0.16"]`` -> targets (SI)."""
    targets = []
    for item in items:
        text = str(item).strip()
        name, _, value = text.partition("=")
        match = _TARGET.match(name.strip())
        if not match or not value:
            raise SceneError(f"--targets {text!r}: expected NAME=VALUE[+-SIGMA] with NAME like "
                             f"{TARGET_EXAMPLES} ({{{','.join(LETTERS)}}}_"
                             f"{{{','.join(INFIXES)}}}_{{unit}})")
        q, kind, unit = match["q"], match["kind"], match["unit"]
        if unit not in UNITS[q]:
            raise SceneError(f"--targets {text!r}: unit {unit!r} is not allowed for {q}: choose "
                             "one of " + ", ".join(map(repr, UNITS[q])) + _suggest(unit, UNITS[q]))
        value, _, sigma = value.partition("+-")
        try:
            number = float(value)
            spread = float(sigma) if sigma else abs(number) * DEFAULT_TARGET_UNCERTAINTY
        except ValueError:
            raise SceneError(f"--targets {text!r}: {value!r} or {sigma!r} is not a number") from None
        if not math.isfinite(number) or number <= 0:
            raise SceneError(f"--targets {text!r}: value {number!r} is out of range: allowed (0, inf)")
        if not math.isfinite(spread) or spread <= 0:
            raise SceneError(f"--targets {text!r}: uncertainty {spread!r} is out of range: "
                             "allowed (0, inf)")
        factor = UNITS[q][unit]
        if number * factor > MAX_TRACE_VALUE[q]:   # a unit slip, as in a measured trace
            raise SceneError(f"--targets {text!r}: {q}_{kind} = {number:g} {unit} is out of "
                             f"range: allowed (0, {MAX_TRACE_VALUE[q] / factor:g}] {unit}")
        if any(t.key == f"{q}_{kind}" for t in targets):
            raise SceneError(f"--targets {text!r}: {q}_{kind} is given twice")
        targets.append(Target(q, kind, unit, number * factor, spread * factor, bool(sigma)))
    if not targets:
        raise SceneError("--targets: give at least one NAME=VALUE")
    return targets
