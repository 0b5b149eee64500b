"""Scene files: a TOML description of one BB-TENG and how it is driven.

Keys in the file carry their unit (``gap_mm``, ``frequency_hz``); the
:class:`Scene` object holds SI values only (metres, seconds, coulombs...).
Every key is validated on load; a bad value raises :class:`SceneError`
naming the key, the value and the allowed range.
"""
from __future__ import annotations

import copy
import dataclasses
import difflib
import hashlib
import json
import math
import tomllib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from .errors import SceneError

G = 9.80665  # standard gravity [m/s^2]
EPS0 = 8.8541878128e-12  # vacuum permittivity [F/m]

#: Bumped whenever the field solver changes what it computes for the same
#: inputs; part of the surrogate cache hash.
FIELD_SCHEMA = 1

# ---------------------------------------------------------------------------
# key tables: file key -> (attribute, type, default, SI factor, constraint)
# constraint: ("range", lo, hi, lo_open, hi_open) or ("choice", (...)) or None
_INF = math.inf


def _rng(lo=-_INF, hi=_INF, lo_open=False, hi_open=False):
    return ("range", lo, hi, lo_open, hi_open)


def _choice(*options):
    return ("choice", options)


_POS = _rng(0.0, _INF, lo_open=True)
_NONNEG = _rng(0.0)

SCHEMA: dict[str, dict[str, tuple]] = {
    "device": {
        "ball_diameter_mm": ("ball_diameter", float, 7.0, 1e-3, _POS),
        "gap_mm": ("stroke", float, 3.0, 1e-3, _POS),
        "electrode_radius_mm": ("electrode_radius", float, 4.0, 1e-3, _POS),
        "tube_inner_radius_mm": ("tube_inner_radius", float, 4.0, 1e-3, _POS),
        "tube_outer_radius_mm": ("tube_outer_radius", float, 5.5, 1e-3, _POS),
        "plate_thickness_mm": ("plate_thickness", float, 2.0, 1e-3, _POS),
        "ball_density_kg_per_m3": ("ball_density", float, 2200.0, 1.0, _POS),
        "ball_permittivity": ("ball_permittivity", float, 2.1, 1.0, _rng(1.0, 1e4)),
        "wall_permittivity": ("wall_permittivity", float, 2.6, 1.0, _rng(1.0, 1e4)),
        "surface_charge_uC_per_m2": ("surface_charge", float, -8.0, 1e-6, _rng(-1e4, 1e4)),
        "cells": ("cells", int, 1, 1, _rng(1, 10**7)),
    },
    "excitation": {
        "kind": ("kind", str, "sine", None, _choice("sine", "recorded")),
        "frequency_hz": ("frequency", float, 20.0, 1.0, _POS),
        "amplitude_mm": ("amplitude", float, 1.5, 1e-3, _NONNEG),
        "phase_deg": ("phase", float, 0.0, math.pi / 180.0, _rng(-360.0, 360.0)),
        "file": ("file", str, "", None, None),
        "time_column": ("time_column", str, "time_s", None, None),
        "signal_column": ("signal_column", str, "displacement_m", None, None),
        "signal": ("signal", str, "displacement", None, _choice("displacement", "acceleration")),
    },
    "contact": {
        "model": ("model", str, "impact", None, _choice("impact", "soft")),
        "restitution": ("restitution", float, 0.1, 1.0, _rng(0.0, 1.0)),
        "restitution_model": ("restitution_model", str, "constant", None,
                              _choice("constant", "power-law")),
        "restitution_reference_speed_m_per_s": ("restitution_reference_speed", float, 0.1, 1.0, _POS),
        "restitution_exponent": ("restitution_exponent", float, 0.0, 1.0, _rng(0.0, 1.0)),
        "stiffness_N_per_m": ("stiffness", float, 1.0e5, 1.0, _rng(1.0, 1e15)),
    },
    "initial": {
        "time_s": ("time", float, 0.0, 1.0, _rng()),
        "gap_mm": ("gap", float, 0.0, 1e-3, _NONNEG),
        "velocity_m_per_s": ("velocity", float, 0.0, 1.0, _rng(-1e3, 1e3)),
    },
    "run": {
        "duration_s": ("duration", float, 1.0, 1.0, _rng(0.0, 1e6, lo_open=True)),
        "settle_periods": ("settle_periods", int, 10, 1, _rng(0, 10**7)),
        "sample_rate_hz": ("sample_rate", float, 20000.0, 1.0, _rng(0.0, 1e9, lo_open=True)),
    },
    "field": {
        "method": ("method", str, "auto", None, _choice("auto", "axisymmetric", "3d")),
        "degree": ("degree", int, 2, 1, _rng(1, 3)),
        "mesh_size_mm": ("mesh_size", float, 0.5, 1e-3, _rng(0.0, 100.0, lo_open=True)),
        "tolerance": ("tolerance", float, 1e-3, 1.0, _rng(1e-8, 0.5)),
        "domain_radius_mm": ("domain_radius", float, 20.0, 1e-3, _POS),
        "environment": ("environment", str, "free-space", None,
                        _choice("free-space", "grounded-table")),
        "far_field": ("far_field", str, "kelvin", None, _choice("kelvin", "robin", "dirichlet")),
        "ball_offset_mm": ("ball_offset", float, 0.0, 1e-3, _NONNEG),
    },
    "circuit": {
        "kind": ("kind", str, "open", None, _choice("open", "short", "load")),
        "load_ohm": ("load", float, 1.0e8, 1.0, _rng(0.0, 1e18, lo_open=True)),
        "parallel_capacitance_pF": ("parallel_capacitance", float, 0.0, 1e-12, _rng(0.0, 1e9)),
        "reference": ("reference", str, "floating", None, _choice("floating", "grounded-lower")),
    },
}


# ---------------------------------------------------------------------------
# harvesting electronics and arrays (issue #11; tengfield.harvest, tengfield.array).
# [circuit] kind gains "rectifier"; defaults of the chip are the LTC3588-1's
# (tengfield.harvest.LTC3588_*; docs/harvest.md).
SCHEMA["circuit"]["kind"] = ("kind", str, "open", None,
                             _choice("open", "short", "load", "rectifier"))
SCHEMA["circuit"].update({
    "diode": ("diode", str, "ideal", None, _choice("ideal", "shockley")),
    "diode_forward_voltage_V": ("diode_forward_voltage", float, 0.0, 1.0, _rng(0.0, 100.0)),
    "diode_saturation_current_A": ("diode_saturation_current", float, 1e-12, 1.0,
                                   _rng(1e-18, 1.0)),
    "diode_emission_coefficient": ("diode_emission_coefficient", float, 1.0, 1.0,
                                   _rng(0.5, 10.0)),
    "diode_series_resistance_ohm": ("diode_series_resistance", float, 0.0, 1.0, _rng(0.0, 1e12)),
    "storage_capacitance_uF": ("storage_capacitance", float, 10.0, 1e-6,
                               _rng(0.0, 1e12, lo_open=True)),
    # 0: no leakage resistor across the store
    "storage_leakage_ohm": ("storage_leakage", float, 0.0, 1.0, _rng(0.0, 1e30)),
    "pmic": ("pmic", str, "none", None, _choice("none", "uvlo")),
    "uvlo_rising_V": ("uvlo_rising", float, 5.05, 1.0, _rng(0.0, 1e6, lo_open=True)),
    "uvlo_falling_V": ("uvlo_falling", float, 4.04, 1.0, _rng(0.0, 1e6, lo_open=True)),
    "pmic_output_V": ("pmic_output", float, 3.3, 1.0, _rng(0.0, 1e6, lo_open=True)),
    "pmic_load_ohm": ("pmic_load", float, 1e5, 1.0, _rng(0.0, 1e18, lo_open=True)),
    "pmic_efficiency": ("pmic_efficiency", float, 0.9, 1.0, _rng(0.0, 1.0, lo_open=True)),
    "pmic_quiescent_current_A": ("pmic_quiescent_current", float, 450e-9, 1.0, _rng(0.0, 1.0)),
    "pmic_shunt_V": ("pmic_shunt", float, 20.0, 1.0, _rng(0.0, 1e6, lo_open=True)),
})
#: [array]: cells that each run their own dynamics (``cells = 0``: no array; then
#: ``[device] cells`` identical copies). Spreads are full widths of uniform draws.
SCHEMA["array"] = {
    "cells": ("cells", int, 0, 1, _rng(0, 10**6)),
    "connection": ("connection", str, "parallel", None,
                   _choice("parallel", "rectified-per-cell", "rectified-parallel")),
    "initial_phase_spread_deg": ("phase_spread", float, 0.0, math.pi / 180.0, _rng(0.0, 360.0)),
    "restitution_spread": ("restitution_spread", float, 0.0, 1.0, _rng(0.0, 1.0)),
    "initial_velocity_spread_m_per_s": ("velocity_spread", float, 0.0, 1.0, _rng(0.0, 100.0)),
    "seed": ("seed", int, 0, 1, _rng(0, 2**32 - 1)),
}


@dataclass(frozen=True)
class Array:
    """``[array]``: ``cells`` (0: none), ``connection``, spreads (full widths:
    ``phase_spread`` [rad], ``restitution_spread``, ``velocity_spread`` [m/s]), ``seed``."""
    cells: int = 0
    connection: str = "parallel"
    phase_spread: float = 0.0
    restitution_spread: float = 0.0
    velocity_spread: float = 0.0
    seed: int = 0


def _check_harvest(dev, circ, arr) -> None:
    """Cross-key rules of the harvesting/array block (one-line SceneErrors)."""
    if circ.uvlo_rising <= circ.uvlo_falling:
        raise SceneError(f"[circuit] uvlo_rising_V = {circ.uvlo_rising:g} must exceed "
                         f"uvlo_falling_V = {circ.uvlo_falling:g} (the lockout's hysteresis)")
    if circ.pmic_output >= circ.uvlo_falling:
        raise SceneError(f"[circuit] pmic_output_V = {circ.pmic_output:g} is out of range: "
                         f"allowed (0, {circ.uvlo_falling:g}) (below uvlo_falling_V)")
    if circ.pmic_shunt <= circ.uvlo_rising:
        raise SceneError(f"[circuit] pmic_shunt_V = {circ.pmic_shunt:g} must exceed "
                         f"uvlo_rising_V = {circ.uvlo_rising:g}")
    if arr.cells > 0 and dev.cells != 1:
        raise SceneError(f"[array] cells = {arr.cells} and [device] cells = {dev.cells}: set one "
                         "of them ([device] cells: identical copies; [array] cells: cells with "
                         "their own dynamics)")
    if arr.cells == 0 and (arr.phase_spread or arr.restitution_spread or arr.velocity_spread
                           or arr.connection != "parallel"):
        raise SceneError("[array] spreads and connection need [array] cells >= 1")
    if arr.connection != "parallel" and circ.kind != "rectifier":
        raise SceneError(f"[array] connection = {arr.connection!r} needs [circuit] kind = "
                         f"'rectifier' (it is {circ.kind!r})")
# ---------------------------------------------------------------------------

#: Sections passed through unvalidated to ``scene.raw`` (each is validated by
#: the package that reads it: ``[fit]`` by :mod:`tengfield.fit`).
PASSTHROUGH_SECTIONS = ("fit",)

# Field-relevant inputs: a change in any of these invalidates a cached surrogate.
FIELD_KEYS = {
    "device": ["ball_diameter_mm", "gap_mm", "electrode_radius_mm", "tube_inner_radius_mm",
               "tube_outer_radius_mm", "plate_thickness_mm", "ball_permittivity",
               "wall_permittivity", "surface_charge_uC_per_m2"],
    "field": ["method", "degree", "mesh_size_mm", "tolerance", "domain_radius_mm",
              "environment", "far_field", "ball_offset_mm"],
}


# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class Device:
    """Geometry and materials, SI. The z axis is the tube axis."""
    ball_diameter: float        # [m]
    stroke: float               # free stroke dh = h - d [m] (scene key gap_mm)
    electrode_radius: float     # [m]
    tube_inner_radius: float    # [m]
    tube_outer_radius: float    # [m] (= end-plate radius)
    plate_thickness: float      # [m]
    ball_density: float         # [kg/m^3]
    ball_permittivity: float    # relative
    wall_permittivity: float    # relative
    surface_charge: float       # [C/m^2], negative for PTFE
    cells: int

    @property
    def ball_radius(self) -> float:
        return 0.5 * self.ball_diameter

    @property
    def plate_spacing(self) -> float:
        """h = d + dh: distance between the electrode faces [m]."""
        return self.ball_diameter + self.stroke

    @property
    def ball_mass(self) -> float:
        return self.ball_density * math.pi * self.ball_diameter**3 / 6.0

    @property
    def ball_charge(self) -> float:
        """Total charge on the ball, sigma * pi d^2 [C]."""
        return self.surface_charge * math.pi * self.ball_diameter**2

    @property
    def cell_volume(self) -> float:
        """Outer volume of one cell, tube and both plates [m^3]."""
        return math.pi * self.tube_outer_radius**2 * (self.plate_spacing + 2 * self.plate_thickness)


@dataclass(frozen=True)
class Excitation:
    """Table motion y(t): ``A sin(2 pi f t + phase)`` or a recorded signal."""
    kind: str
    frequency: float            # [Hz]; for "recorded" used as the reference period
    amplitude: float            # [m]
    phase: float                # [rad]
    file: str
    time_column: str
    signal_column: str
    signal: str
    times: np.ndarray | None = field(default=None, compare=False, repr=False)   # [s]
    values: np.ndarray | None = field(default=None, compare=False, repr=False)  # [m] or [m/s^2]

    @property
    def omega(self) -> float:
        return 2.0 * math.pi * self.frequency

    @property
    def period(self) -> float:
        return 1.0 / self.frequency

    @property
    def gamma(self) -> float:
        """Dimensionless intensity A w^2 / g (sine only)."""
        return self.amplitude * self.omega**2 / G


@dataclass(frozen=True)
class Contact:
    model: str
    restitution: float
    restitution_model: str
    restitution_reference_speed: float   # [m/s]
    restitution_exponent: float
    stiffness: float                     # [N/m]

    def restitution_at(self, speed: float) -> float:
        """Restitution for an impact at relative speed ``speed`` [m/s].

        "constant": e. "power-law": ``min(1, e (v/v_ref)^-p)``, a common fit of
        velocity-dependent restitution of polymer balls (e falls with speed).
        """
        if self.restitution_model == "constant" or self.restitution_exponent == 0.0:
            return self.restitution
        v = max(abs(speed), 1e-12)
        return min(1.0, self.restitution * (v / self.restitution_reference_speed) ** (-self.restitution_exponent))


@dataclass(frozen=True)
class Initial:
    time: float       # [s]
    gap: float        # [m]
    velocity: float   # relative to the table [m/s]


@dataclass(frozen=True)
class Run:
    duration: float        # [s]
    settle_periods: int
    sample_rate: float     # [Hz]


@dataclass(frozen=True)
class Field:
    method: str
    degree: int
    mesh_size: float       # [m]
    tolerance: float
    domain_radius: float   # [m]
    environment: str
    far_field: str
    ball_offset: float     # [m]


@dataclass(frozen=True)
class Circuit:
    kind: str
    load: float                   # [ohm]
    parallel_capacitance: float   # [F]
    reference: str
    # harvesting (kind = "rectifier"; block "harvesting electronics" above), SI
    diode: str = "ideal"
    diode_forward_voltage: float = 0.0         # [V] per diode (ideal model)
    diode_saturation_current: float = 1e-12    # [A] (shockley)
    diode_emission_coefficient: float = 1.0    # (shockley)
    diode_series_resistance: float = 0.0       # [ohm] per diode
    storage_capacitance: float = 10e-6         # [F]
    storage_leakage: float = 0.0               # [ohm], 0: none
    pmic: str = "none"
    uvlo_rising: float = 5.05                  # [V]
    uvlo_falling: float = 4.04                 # [V]
    pmic_output: float = 3.3                   # [V]
    pmic_load: float = 1e5                     # [ohm]
    pmic_efficiency: float = 0.9
    pmic_quiescent_current: float = 450e-9     # [A]
    pmic_shunt: float = 20.0                   # [V]


@dataclass(frozen=True)
class Scene:
    device: Device
    excitation: Excitation
    contact: Contact
    initial: Initial
    run: Run
    field: Field
    circuit: Circuit
    array: Array = Array()
    raw: dict = dataclasses.field(compare=False, repr=False, default_factory=dict)
    source: str = dataclasses.field(compare=False, repr=False, default="<default>")
    text: str = dataclasses.field(compare=False, repr=False, default="")

    # -- construction -----------------------------------------------------
    @classmethod
    def from_dict(cls, data: dict, *, base_dir: Path | None = None, source: str = "<dict>",
                  text: str = "") -> "Scene":
        return _build(data, base_dir=base_dir, source=source, text=text)

    def with_values(self, **sections: dict) -> "Scene":
        """A copy with some file-level keys changed, validated again.

        ``scene.with_values(excitation={"frequency_hz": 30.0})``
        """
        data = copy.deepcopy(self.raw)
        for sec, values in sections.items():
            data.setdefault(sec, {}).update(values)
        base = Path(self.source).parent if self.source not in ("<default>", "<dict>") else None
        return _build(data, base_dir=base, source=self.source, text=self.text)

    # -- provenance -------------------------------------------------------
    def field_inputs(self) -> dict:
        """Every input the field solution depends on, as file-level values."""
        full = _with_defaults(self.raw)
        out: dict[str, Any] = {"schema": FIELD_SCHEMA}
        for sec, keys in FIELD_KEYS.items():
            out[sec] = {k: full[sec][k] for k in keys}
        return out

    def field_hash(self) -> str:
        """SHA-256 of :meth:`field_inputs` (the surrogate cache key)."""
        blob = json.dumps(self.field_inputs(), sort_keys=True, default=float).encode()
        return hashlib.sha256(blob).hexdigest()

    def to_dict(self) -> dict:
        """File-level values of every key (defaults filled in)."""
        return _with_defaults(self.raw)

    # -- derived ----------------------------------------------------------
    @property
    def is_axisymmetric(self) -> bool:
        """On-axis ball in a body of revolution: the field is 2D (r, z)."""
        return self.field.ball_offset == 0.0


# ---------------------------------------------------------------------------
def default_text() -> str:
    """The embedded default scene, with its comments."""
    return resources.files("tengfield").joinpath("data/default.toml").read_text()


def default_scene() -> Scene:
    return parse_scene(default_text(), source="<default>")


def load_scene(path: str | Path | None) -> Scene:
    """Read a scene file; ``None`` gives the embedded default scene."""
    if path is None:
        return default_scene()
    p = Path(path)
    if not p.is_file():
        raise SceneError(f"scene file {str(p)!r} does not exist")
    return parse_scene(p.read_text(), source=str(p), base_dir=p.parent)


def parse_scene(text: str, *, source: str = "<string>", base_dir: Path | None = None) -> Scene:
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"{source}: malformed TOML: {exc}") from None
    return _build(data, base_dir=base_dir, source=source, text=text)


# ---------------------------------------------------------------------------
def _suggest(word: str, options) -> str:
    close = difflib.get_close_matches(word, list(options), n=1, cutoff=0.6)
    return f" (did you mean {close[0]!r}?)" if close else ""


def _with_defaults(raw: dict) -> dict:
    full = {}
    for sec, keys in SCHEMA.items():
        given = raw.get(sec, {})
        full[sec] = {k: given.get(k, spec[2]) for k, spec in keys.items()}
    return full


def _fmt_range(c) -> str:
    _, lo, hi, lo_open, hi_open = c
    left = "(" if lo_open else "["
    right = ")" if hi_open else "]"
    return f"{left}{lo:g}, {hi:g}{right}"


def _convert(sec: str, key: str, value, spec):
    attr, typ, default, factor, constraint = spec
    where = f"[{sec}] {key}"
    if typ is str:
        if not isinstance(value, str):
            raise SceneError(f"{where} = {value!r}: expected a string")
        if constraint and constraint[0] == "choice" and value not in constraint[1]:
            allowed = ", ".join(repr(o) for o in constraint[1])
            raise SceneError(f"{where} = {value!r} is not allowed: choose one of {allowed}"
                             + _suggest(value, constraint[1]))
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise SceneError(f"{where} = {value!r}: expected a number")
    if typ is int:
        if isinstance(value, float) and not value.is_integer():
            raise SceneError(f"{where} = {value!r}: expected a whole number")
        value = int(value)
    if not math.isfinite(value):
        raise SceneError(f"{where} = {value!r} is not finite: allowed range {_fmt_range(constraint)}")
    if constraint and constraint[0] == "range":
        _, lo, hi, lo_open, hi_open = constraint
        bad = (value < lo or value > hi or (lo_open and value == lo) or (hi_open and value == hi))
        if bad:
            raise SceneError(f"{where} = {value!r} is out of range: allowed {_fmt_range(constraint)}")
    return value * factor if typ is float else value


def _build(data: dict, *, base_dir: Path | None, source: str, text: str) -> Scene:
    if not isinstance(data, dict):
        raise SceneError(f"{source}: a scene is a TOML table")
    for sec in data:
        if sec in PASSTHROUGH_SECTIONS:   # kept in scene.raw, validated by their own package
            if not isinstance(data[sec], dict):
                raise SceneError(f"{source}: [{sec}] must be a table")
            continue
        if sec not in SCHEMA:
            raise SceneError(f"{source}: unknown section [{sec}]" + _suggest(sec, SCHEMA)
                             + f"; sections are {', '.join('[' + s + ']' for s in SCHEMA)}")
        if not isinstance(data[sec], dict):
            raise SceneError(f"{source}: [{sec}] must be a table")
        for key in data[sec]:
            if key not in SCHEMA[sec]:
                raise SceneError(f"{source}: unknown key [{sec}] {key}" + _suggest(key, SCHEMA[sec]))
    values: dict[str, dict[str, Any]] = {}
    for sec, keys in SCHEMA.items():
        given = data.get(sec, {})
        values[sec] = {}
        for key, spec in keys.items():
            raw = given.get(key, spec[2])
            values[sec][spec[0]] = _convert(sec, key, raw, spec)

    dev = Device(**values["device"])
    if dev.tube_outer_radius <= dev.tube_inner_radius:
        raise SceneError(
            f"[device] tube_outer_radius_mm = {dev.tube_outer_radius * 1e3:g} must exceed "
            f"tube_inner_radius_mm = {dev.tube_inner_radius * 1e3:g}")
    if dev.ball_diameter >= 2.0 * dev.tube_inner_radius:
        raise SceneError(
            f"[device] ball_diameter_mm = {dev.ball_diameter * 1e3:g}: the ball does not fit the tube; "
            f"allowed (0, {2e3 * dev.tube_inner_radius:g}) mm (twice tube_inner_radius_mm)")
    if dev.electrode_radius > dev.tube_outer_radius:
        raise SceneError(
            f"[device] electrode_radius_mm = {dev.electrode_radius * 1e3:g} is larger than the plate: "
            f"allowed (0, {dev.tube_outer_radius * 1e3:g}] mm (tube_outer_radius_mm)")

    exc_vals = values["excitation"]
    times = vals = None
    if exc_vals["kind"] == "recorded":
        times, vals = _read_recorded(exc_vals, base_dir)
    exc = Excitation(**exc_vals, times=times, values=vals)

    ini = Initial(**values["initial"])
    if ini.gap > dev.stroke:
        raise SceneError(f"[initial] gap_mm = {ini.gap * 1e3:g} is out of range: "
                         f"allowed [0, {dev.stroke * 1e3:g}] (the free stroke [device] gap_mm)")
    run = Run(**values["run"])
    if exc.kind == "sine" and run.settle_periods * exc.period >= run.duration:
        raise SceneError(
            f"[run] settle_periods = {run.settle_periods} leaves no steady window: "
            f"settle_periods / frequency_hz = {run.settle_periods * exc.period:g} s must be "
            f"< duration_s = {run.duration:g}")
    fld = Field(**values["field"])
    extent = math.hypot(dev.tube_outer_radius + fld.ball_offset,
                        0.5 * dev.plate_spacing + dev.plate_thickness)
    if fld.domain_radius <= 1.2 * extent:
        raise SceneError(
            f"[field] domain_radius_mm = {fld.domain_radius * 1e3:g} is too small: it must exceed "
            f"{1.2e3 * extent:.3g} mm (1.2 x the device's bounding radius)")
    max_offset = dev.tube_inner_radius - dev.ball_radius
    if fld.ball_offset > max_offset + 1e-15:
        raise SceneError(
            f"[field] ball_offset_mm = {fld.ball_offset * 1e3:g} is out of range: allowed "
            f"[0, {max_offset * 1e3:g}] mm (the ball must stay inside the tube)")
    if fld.ball_offset > 0 and fld.method == "axisymmetric":
        raise SceneError("[field] method = 'axisymmetric' needs ball_offset_mm = 0; "
                         "use method = '3d' or 'auto' for an off-axis ball")
    circ = Circuit(**values["circuit"])
    arr = Array(**values["array"])
    _check_harvest(dev, circ, arr)
    return Scene(device=dev, excitation=exc, contact=Contact(**values["contact"]), initial=ini,
                 run=run, field=fld, circuit=circ, array=arr,
                 raw=copy.deepcopy(data), source=source, text=text)


def _read_recorded(exc: dict, base_dir: Path | None):
    name = exc["file"]
    if not name:
        raise SceneError("[excitation] kind = 'recorded' needs file = 'name.csv'")
    path = Path(name)
    if not path.is_absolute() and base_dir is not None:
        path = base_dir / path
    if not path.is_file():
        raise SceneError(f"[excitation] file = {name!r}: no such file ({path})")
    try:
        table = np.genfromtxt(path, delimiter=",", names=True, dtype=float, encoding="utf-8")
    except Exception as exc_:  # noqa: BLE001 - reported with the file name
        raise SceneError(f"[excitation] file = {name!r} could not be read as CSV: {exc_}") from None
    names = table.dtype.names or ()
    for col_key in ("time_column", "signal_column"):
        col = exc[col_key]
        if col not in names:
            raise SceneError(f"[excitation] {col_key} = {col!r} is not a column of {name!r}; "
                             f"columns are {', '.join(names)}" + _suggest(col, names))
    t = np.atleast_1d(np.asarray(table[exc["time_column"]], dtype=float))
    v = np.atleast_1d(np.asarray(table[exc["signal_column"]], dtype=float))
    if t.size < 4:
        raise SceneError(f"[excitation] file = {name!r} has {t.size} rows: at least 4 are needed")
    for label, arr in (("time", t), ("signal", v)):
        bad = np.flatnonzero(~np.isfinite(arr))
        if bad.size:
            raise SceneError(f"[excitation] file = {name!r}: {label} column holds NaN or inf "
                             f"at data row {bad[0] + 1}")
    step = np.diff(t)
    if np.any(step <= 0):
        i = int(np.flatnonzero(step <= 0)[0])
        raise SceneError(f"[excitation] file = {name!r}: time is not strictly increasing "
                         f"at data row {i + 2} ({t[i]:g} s then {t[i + 1]:g} s)")
    return t, v
