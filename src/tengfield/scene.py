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
import io
import json
import math
import tomllib
import warnings
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
        "smoothing_hz": ("smoothing", float, 0.0, 1.0, _NONNEG),
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
        "domain_radius_mm": ("domain_radius", float, "auto", 1e-3, _POS),
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
#: the package that reads it: ``[fit]`` by :mod:`tengfield.fit`, ``[design]`` by
#: :mod:`tengfield.design`).
PASSTHROUGH_SECTIONS = ("fit", "design")

# ---------------------------------------------------------------------------
# 3D motion keys (issue #13, tengfield.motion3d; used only by [contact] model = "3d").
# Their defaults leave every impact/soft scene unchanged. Material defaults
# (handbook values, sources in docs/motion3d.md): PTFE ball E 0.5 GPa
# (0.4-0.8), nu 0.46; copper electrodes E 120 GPa (110-130), nu 0.34; PMMA
# tube E 3.0 GPa (2.4-3.3), nu 0.37; Coulomb friction static 0.1 / dynamic 0.05
# (the reference paper's multibody model).
SCHEMA["contact"]["model"] = ("model", str, "impact", None, _choice("impact", "soft", "3d"))
SCHEMA_3D: dict[str, dict[str, tuple]] = {
    "device": {
        "tilt_deg": ("tilt", float, 0.0, math.pi / 180.0, _rng(0.0, 180.0)),
        "tilt_azimuth_deg": ("tilt_azimuth", float, 0.0, math.pi / 180.0, _rng(-360.0, 360.0)),
    },
    "excitation": {
        "amplitude_x_mm": ("amplitude_x", float, 0.0, 1e-3, _NONNEG),
        "amplitude_y_mm": ("amplitude_y", float, 0.0, 1e-3, _NONNEG),
        "phase_x_deg": ("phase_x", float, 0.0, math.pi / 180.0, _rng(-360.0, 360.0)),
        "phase_y_deg": ("phase_y", float, 0.0, math.pi / 180.0, _rng(-360.0, 360.0)),
        "signal_x_column": ("signal_x_column", str, "", None, None),
        "signal_y_column": ("signal_y_column", str, "", None, None),
    },
    "contact": {
        "law": ("law", str, "hertz", None, _choice("hertz", "power")),
        "damping_model": ("damping_model", str, "calibrated", None,
                          _choice("calibrated", "chrono")),
        "exponent": ("exponent", float, 1.0, 1.0, _rng(1.0, 3.0)),
        "damping_N_s_per_m": ("damping", float, -1.0, 1.0, _rng(-1.0, 1e12)),
        "penetration_max_mm": ("penetration_max", float, 0.0, 1e-3, _rng(0.0, 10.0)),
        "ball_youngs_modulus_GPa": ("ball_youngs_modulus", float, 0.5, 1e9, _rng(1e-6, 1e4, lo_open=True)),
        "ball_poisson_ratio": ("ball_poisson_ratio", float, 0.46, 1.0, _rng(-1.0, 0.5, lo_open=True)),
        "plate_youngs_modulus_GPa": ("plate_youngs_modulus", float, 120.0, 1e9, _rng(1e-6, 1e4, lo_open=True)),
        "plate_poisson_ratio": ("plate_poisson_ratio", float, 0.34, 1.0, _rng(-1.0, 0.5, lo_open=True)),
        "wall_youngs_modulus_GPa": ("wall_youngs_modulus", float, 3.0, 1e9, _rng(1e-6, 1e4, lo_open=True)),
        "wall_poisson_ratio": ("wall_poisson_ratio", float, 0.37, 1.0, _rng(-1.0, 0.5, lo_open=True)),
        "friction_static": ("friction_static", float, 0.1, 1.0, _rng(0.0, 10.0)),
        "friction_dynamic": ("friction_dynamic", float, 0.05, 1.0, _rng(0.0, 10.0)),
    },
}
for _sec, _keys in SCHEMA_3D.items():
    SCHEMA[_sec].update(_keys)
# (the matching dataclass fields are the "3D motion" fields at the end of
# Device, Excitation and Contact below)
# ---------------------------------------------------------------------------

# Field-relevant inputs: a change in any of these invalidates a cached surrogate.
FIELD_KEYS = {
    "device": ["ball_diameter_mm", "gap_mm", "electrode_radius_mm", "tube_inner_radius_mm",
               "tube_outer_radius_mm", "plate_thickness_mm", "ball_permittivity",
               "wall_permittivity", "surface_charge_uC_per_m2"],
    "field": ["method", "degree", "mesh_size_mm", "tolerance", "domain_radius_mm",
              "environment", "far_field", "ball_offset_mm"],
}


#: Keys that also accept the string "auto", resolved to a number at load.
AUTO_KEYS = {("field", "domain_radius_mm")}

# -- limits of work, checked at load (docs/stability.md, "bad input and faults") --
#: Output samples per run, ``duration_s x sample_rate_hz``: 2e7 is 1000 s at 20 kHz
#: (four float64 arrays of 0.64 GB; the CSV holds about 1 GB).
MAX_SAMPLES = 2e7
#: Excitation periods per run, ``duration_s x frequency_hz``: 1e6 is 14 h at 20 Hz.
MAX_PERIODS = 1e6
#: ``[array]`` cells with their own dynamics (a spread set) x excitation periods: the
#: run's peak memory is about 1.4 kB per cell-period (455 cells x 1000 periods: 642 MB,
#: benchmarks/harvest_array_speed.py; the segments are kept twice, per cell and in one
#: bundle), so 5e6 is about 7 GB.
MAX_ARRAY_CELL_PERIODS = 5e6
#: peak bytes per cell-period (the estimate in the message)
ARRAY_BYTES_PER_CELL_PERIOD = 1.4e3
#: Events per period the impact map provisions (its first allocation); with
#: MAX_PERIODS this bounds the first allocation at 1.6e7 events (1.3 GB).
EVENTS_PER_PERIOD_ESTIMATE = 16

#: Data rows a recorded excitation needs: the table motion is a quintic spline
#: (``tengfield.dynamics.table.recorded_table``).
MIN_RECORDED_ROWS = 6

# -- field-only ranges relative to the geometry (checked by check_field) --
#: ``domain_radius_mm = "auto"``: this factor x the device's bounding radius,
#: rounded up at two significant digits (the paper's device: 2.2 x 8.9 mm -> 20 mm).
DOMAIN_AUTO_FACTOR = 2.2
#: The far-field sphere must exceed 1.2 x (bounding radius + ball offset) ...
DOMAIN_MIN_FACTOR = 1.2
#: ... and stay below 50 x the bounding radius (gmsh/OpenCASCADE fail far beyond).
DOMAIN_MAX_FACTOR = 50.0
#: Every feature (ball, plates, tube wall, electrode) >= 1e-3 x the bounding radius.
FEATURE_MIN_FRACTION = 1e-3
#: Smallest base mesh size as a fraction of the device's smallest feature, per
#: solver (the mesh is graded finer still at rims and gaps). Measured, paper's
#: device, degree 2, one (r, z) solve: 0.5 mm 1.3e4 dofs; 0.15 mm 1.3e5 dofs,
#: 0.4 GB; the limit 0.075 mm 5.1e5 dofs, 78 s, 1.2 GB (dofs ~ h^-2).
MESH_MIN_FRACTION = {"axisymmetric": 1.0 / 20.0, "3d": 1.0 / 4.0}
#: The contact rule meshes ball-electrode gaps down to min_gap and extrapolates
#: from gaps g, 2g, 4g at both plates: the stroke must hold 8 of them.
CONTACT_GAPS_IN_STROKE = 8


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
    # 3D motion (SCHEMA_3D): gravity tilted by ``tilt`` from -z toward azimuth ``tilt_azimuth`` [rad]
    tilt: float = 0.0
    tilt_azimuth: float = 0.0

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
    def bounding_radius(self) -> float:
        """Radius of the smallest sphere about the device centre holding one cell [m]."""
        return math.hypot(self.tube_outer_radius, 0.5 * self.plate_spacing + self.plate_thickness)

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
    # 3D motion (SCHEMA_3D): lateral sine x = A_x sin(w t + phase_x) [m, rad]; recorded columns
    amplitude_x: float = 0.0
    amplitude_y: float = 0.0
    phase_x: float = 0.0
    phase_y: float = 0.0
    signal_x_column: str = ""
    signal_y_column: str = ""
    smoothing: float = 0.0      # [Hz] zero-phase low-pass of a recorded signal, 0 = off

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
    # 3D motion (SCHEMA_3D), SI: moduli [Pa], damping [N s/m] (< 0: from restitution),
    # penetration_max [m]
    law: str = "hertz"
    damping_model: str = "calibrated"   # Hertz: beta fitted to rebound with e, or Chrono's closed form
    exponent: float = 1.0
    damping: float = -1.0
    penetration_max: float = 0.0
    ball_youngs_modulus: float = 0.5e9
    ball_poisson_ratio: float = 0.46
    plate_youngs_modulus: float = 120e9
    plate_poisson_ratio: float = 0.34
    wall_youngs_modulus: float = 3.0e9
    wall_poisson_ratio: float = 0.37
    friction_static: float = 0.1
    friction_dynamic: float = 0.05

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


class _RefusedField:
    """Stands in for :class:`Field` when ``[field]`` values are bad: a dynamics-only
    run never looks at them, and any use of one raises the :class:`SceneError`."""
    __slots__ = ("problems",)

    def __init__(self, problems: tuple[str, ...]):
        object.__setattr__(self, "problems", tuple(problems))

    def __getattr__(self, name):
        if name.startswith("__"):
            raise AttributeError(name)
        raise SceneError("; ".join(self.problems))

    def __setattr__(self, name, value):
        raise AttributeError("a scene's field settings are read-only")

    def __reduce__(self):   # pickled for worker processes (map, sweep)
        return (_RefusedField, (self.problems,))

    def __eq__(self, other):
        return isinstance(other, _RefusedField) and other.problems == self.problems

    def __hash__(self):
        return hash(self.problems)

    def __repr__(self):
        return f"_RefusedField({self.problems!r})"


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
        scene = _build(data, base_dir=base, source=self.source, text=self.text)
        if "field" in sections:   # explicit field settings: refuse bad ones at once
            check_field(scene)
        return scene

    # -- provenance -------------------------------------------------------
    def field_inputs(self) -> dict:
        """Every input the field solution depends on, as file-level values
        ("auto" resolved). Raises :class:`SceneError` if a field value is bad."""
        check_field(self)
        full = _with_defaults(self.raw)
        out: dict[str, Any] = {"schema": FIELD_SCHEMA}
        for sec, keys in FIELD_KEYS.items():
            out[sec] = {k: full[sec][k] for k in keys}
        for sec, key in AUTO_KEYS:
            if out[sec][key] == "auto":
                out[sec][key] = _auto_mm(getattr(getattr(self, sec), SCHEMA[sec][key][0]))
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
    def field_problems(self) -> tuple[str, ...]:
        """Every bad field-only value (empty when a field stage may run)."""
        return self.field.problems if isinstance(self.field, _RefusedField) else ()

    @property
    def is_axisymmetric(self) -> bool:
        """On-axis ball in a body of revolution: the field is 2D (r, z)."""
        return self.field.ball_offset == 0.0


# ---------------------------------------------------------------------------
def default_text() -> str:
    """The embedded default scene, with its comments."""
    return resources.files("tengfield").joinpath("data/default.toml").read_text()


def check_field(scene: Scene) -> None:
    """Raise :class:`SceneError` naming every bad field-only value of ``scene``.

    Call it where a field stage starts (field solve, surrogate, ``tengfield
    field``/``run``/``precompute``/``sweep``): field-only values (``[field]``
    keys and the geometry ranges a mesh needs) never fail a dynamics-only run.
    """
    if scene.field_problems:
        raise SceneError("; ".join(scene.field_problems))


def default_scene() -> Scene:
    return parse_scene(default_text(), source="<default>")


def load_scene(path: str | Path | None) -> Scene:
    """Read a scene file; ``None`` gives the embedded default scene."""
    if path is None:
        return default_scene()
    p = Path(path)
    if p.is_dir():
        raise SceneError(f"scene file {str(p)!r} is a directory: give a .toml file")
    if not p.is_file():
        raise SceneError(f"scene file {str(p)!r} does not exist")
    try:
        blob = p.read_bytes()
    except OSError as exc:
        raise SceneError(f"scene file {str(p)!r} could not be read: {exc.strerror or exc}") from None
    return parse_scene(decode_utf8(blob, f"scene file {str(p)!r}"), source=str(p),
                       base_dir=p.parent)


def decode_utf8(blob: bytes, what: str) -> str:
    """UTF-8 text (a leading byte-order mark is dropped), or one-line SceneError naming
    ``what`` (every text file tengfield reads: scenes, recorded excitations, measured
    traces)."""
    if blob.startswith((b"\xff\xfe", b"\xfe\xff")):
        raise SceneError(f"{what} is UTF-16 text: save it as UTF-8")
    try:
        return blob.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        kind = "binary data" if b"\x00" in blob[:4096] else "not UTF-8 text"
        raise SceneError(f"{what} is {kind} (byte 0x{blob[exc.start]:02x} at offset "
                         f"{exc.start}): save it as UTF-8") from None


def parse_scene(text: str, *, source: str = "<string>", base_dir: Path | None = None) -> Scene:
    text = text.removeprefix("\ufeff")   # a UTF-8 byte-order mark is not TOML
    if "\x00" in text:
        raise SceneError(f"{source}: holds NUL characters (binary data, not a TOML scene)")
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


def _auto_mm(value_si: float) -> float:
    """An SI length as the file-level millimetre number."""
    return float(f"{value_si * 1e3:.12g}")


def _round_up_2(x: float) -> float:
    """``x`` > 0 rounded up at two significant digits (19.58 -> 20, 0.0213 -> 0.022)."""
    exp = math.floor(math.log10(x)) - 1
    return float(f"{math.ceil(x / 10.0**exp - 1e-9)}e{exp}")


def auto_domain_radius(device: Device, offset: float = 0.0) -> float:
    """``[field] domain_radius_mm = "auto"`` [m]: ``DOMAIN_AUTO_FACTOR`` x the
    device's bounding radius (at least 1.3 x (bounding radius + ball offset)),
    rounded up at two significant digits in mm; 20 mm for the paper's device."""
    b = device.bounding_radius
    return 1e-3 * _round_up_2(1e3 * max(DOMAIN_AUTO_FACTOR * b, 1.3 * (b + offset)))


def _convert(sec: str, key: str, value, spec):
    attr, typ, default, factor, constraint = spec
    where = f"[{sec}] {key}"
    if (sec, key) in AUTO_KEYS and isinstance(value, str):
        if value != "auto":
            raise SceneError(f"{where} = {value!r}: expected a number or 'auto'")
        return None   # resolved by _build
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
    field_problems: list[str] = []
    for sec, keys in SCHEMA.items():
        given = data.get(sec, {})
        values[sec] = {}
        for key, spec in keys.items():
            raw = given.get(key, spec[2])
            if sec != "field":
                values[sec][spec[0]] = _convert(sec, key, raw, spec)
                continue
            try:   # field-only: kept for check_field, never fails a dynamics run
                values[sec][spec[0]] = _convert(sec, key, raw, spec)
            except SceneError as exc:
                field_problems.append(str(exc))
                values[sec][spec[0]] = _convert(sec, key, spec[2], spec)

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
    check_steady_window(exc, run.settle_periods, run.duration)
    _check_work(exc, run)
    fvals = values["field"]
    if fvals["domain_radius"] is None:
        fvals["domain_radius"] = auto_domain_radius(dev, fvals["ball_offset"])
    fld = Field(**fvals)
    field_problems += _field_problems(dev, fld, explicit=set(data.get("field", {})))
    field_value: Field | _RefusedField = _RefusedField(field_problems) if field_problems else fld
    circ = Circuit(**values["circuit"])
    arr = Array(**values["array"])
    _check_harvest(dev, circ, arr)
    _check_array_work(arr, exc, run)
    return Scene(device=dev, excitation=exc, contact=Contact(**values["contact"]), initial=ini,
                 run=run, field=field_value, circuit=circ, array=arr,
                 raw=copy.deepcopy(data), source=source, text=text)


def check_steady_window(exc: Excitation, settle_periods: int, duration: float,
                        name: str = "duration_s") -> None:
    """Refuse a run of ``duration`` [s] that ends before its regime window starts (after
    ``settle_periods`` excitation periods): the same rule for every excitation kind
    ("recorded": frequency_hz is the reference period of the analysis). ``name`` is how
    the message names the duration (a scene key, an option)."""
    settle = settle_periods * exc.period
    if settle >= duration:
        raise SceneError(
            f"[run] settle_periods = {settle_periods} leaves no steady window: "
            f"settle_periods / frequency_hz = {settle:g} s must be < {name} = {duration:g}")


def _check_array_work(arr: Array, exc: Excitation, run: Run) -> None:
    """Refuse an ``[array]`` whose cells' trajectories would not fit in memory: every cell
    of a spread set has its own dynamics, kept for the electrical stage (identical cells
    share one)."""
    spread = arr.phase_spread > 0 or arr.restitution_spread > 0 or arr.velocity_spread > 0
    if arr.cells == 0 or not spread:
        return
    cell_periods = arr.cells * run.duration * exc.frequency
    if cell_periods > MAX_ARRAY_CELL_PERIODS:
        raise SceneError(
            f"[array] cells x [run] duration_s x [excitation] frequency_hz = {arr.cells} x "
            f"{run.duration:g} x {exc.frequency:g} = {cell_periods:.3g} cell-periods: allowed "
            f"<= {MAX_ARRAY_CELL_PERIODS:.0e} (each cell keeps its trajectory: about "
            f"{cell_periods * ARRAY_BYTES_PER_CELL_PERIOD / 1e9:.3g} GB here; fewer cells or "
            "a shorter run)")


def _check_work(exc: Excitation, run: Run) -> None:
    """Refuse runs whose sample or event count would exhaust memory (product named)."""
    samples = run.duration * run.sample_rate
    if samples > MAX_SAMPLES:
        raise SceneError(
            f"[run] duration_s x sample_rate_hz = {run.duration:g} x {run.sample_rate:g} = "
            f"{samples:.3g} samples: allowed <= {MAX_SAMPLES:.3g} (lower sample_rate_hz or "
            "split the run)")
    periods = run.duration * exc.frequency
    if periods > MAX_PERIODS:
        raise SceneError(
            f"[run] duration_s x [excitation] frequency_hz = {run.duration:g} x "
            f"{exc.frequency:g} = {periods:.3g} excitation periods (about "
            f"{EVENTS_PER_PERIOD_ESTIMATE * periods:.3g} impact-map events at "
            f"{EVENTS_PER_PERIOD_ESTIMATE} per period): allowed <= {MAX_PERIODS:.3g} periods")


def _field_problems(dev: Device, fld: Field, *, explicit: set[str]) -> list[str]:
    """Field-only problems: ranges relative to the geometry that a mesh needs."""
    from .field.contact import MIN_GAP_FRACTION

    problems = []
    b = dev.bounding_radius
    b_mm = b * 1e3
    max_offset = dev.tube_inner_radius - dev.ball_radius
    if fld.ball_offset > max_offset + 1e-15:
        problems.append(
            f"[field] ball_offset_mm = {fld.ball_offset * 1e3:g} is out of range: allowed "
            f"[0, {max_offset * 1e3:g}] mm (the ball must stay inside the tube)")
    if fld.ball_offset > 0 and fld.method == "axisymmetric":
        problems.append("[field] method = 'axisymmetric' needs ball_offset_mm = 0; "
                        "use method = '3d' or 'auto' for an off-axis ball")
    how = "" if "domain_radius_mm" in explicit else " ('auto')"
    lowest = DOMAIN_MIN_FACTOR * (b + fld.ball_offset)
    if fld.domain_radius <= lowest:
        problems.append(
            f"[field] domain_radius_mm = {fld.domain_radius * 1e3:g}{how} is too small: it must "
            f"exceed {lowest * 1e3:.3g} mm ({DOMAIN_MIN_FACTOR:g} x the device's bounding radius "
            "+ ball offset)")
    if fld.domain_radius > DOMAIN_MAX_FACTOR * b:
        problems.append(
            f"[field] domain_radius_mm = {fld.domain_radius * 1e3:g} is too large for this "
            f"device: allowed <= {DOMAIN_MAX_FACTOR * b_mm:.3g} mm ({DOMAIN_MAX_FACTOR:g} x the "
            f"bounding radius {b_mm:.3g} mm); 'auto' picks one")
    smallest = FEATURE_MIN_FRACTION * b
    features = [("ball_diameter_mm", dev.ball_diameter),
                ("plate_thickness_mm", dev.plate_thickness),
                ("electrode_radius_mm", dev.electrode_radius),
                ("tube_outer_radius_mm - tube_inner_radius_mm",
                 dev.tube_outer_radius - dev.tube_inner_radius)]
    feature_key, feature = min(features + [("gap_mm", dev.stroke)], key=lambda kv: kv[1])
    for key, size in features:
        if size < smallest:
            problems.append(
                f"[device] {key} = {size * 1e3:.3g} is too small for a field mesh: allowed >= "
                f"{smallest * 1e3:.3g} mm ({FEATURE_MIN_FRACTION:g} x the device's bounding "
                f"radius {b_mm:.3g} mm)")
    gaps = CONTACT_GAPS_IN_STROKE * MIN_GAP_FRACTION * dev.plate_spacing
    if dev.stroke < gaps * (1 - 1e-12):
        # stroke >= n f (d + stroke)  <=>  stroke >= n f d / (1 - n f)
        nf = CONTACT_GAPS_IN_STROKE * MIN_GAP_FRACTION
        need = nf * dev.ball_diameter / (1.0 - nf)
        problems.append(
            f"[device] gap_mm = {dev.stroke * 1e3:g} is too small for a field solve: allowed >= "
            f"{need * 1e3:.3g} mm ({CONTACT_GAPS_IN_STROKE} x the smallest meshed gap, "
            f"{MIN_GAP_FRACTION:g} x the plate spacing); dynamics-only runs accept it")
    method = fld.method
    if method == "auto":
        method = "axisymmetric" if fld.ball_offset == 0.0 else "3d"
    finest = MESH_MIN_FRACTION[method] * feature
    if fld.mesh_size < finest * (1 - 1e-12):
        problems.append(
            f"[field] mesh_size_mm = {fld.mesh_size * 1e3:g} is too fine for this device: "
            f"allowed >= {finest * 1e3:.3g} mm (1/{1 / MESH_MIN_FRACTION[method]:g} of the "
            f"smallest feature, [device] {feature_key} = {feature * 1e3:.3g} mm, for the "
            f"{method} solver; finer meshes exceed memory)")
    return problems


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
        blob = path.read_bytes()
    except OSError as exc_:
        raise SceneError(f"[excitation] file = {name!r} could not be read: "
                         f"{exc_.strerror or exc_}") from None
    text = decode_utf8(blob, f"[excitation] file = {name!r}")   # BOM dropped here
    if not text.strip():
        raise SceneError(f"[excitation] file = {name!r} is empty: expected a header line "
                         f"({exc['time_column']},{exc['signal_column']}) and at least "
                         f"{MIN_RECORDED_ROWS} data rows")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")   # numpy's warnings become one-line errors
            table = np.genfromtxt(io.StringIO(text), delimiter=",", names=True, dtype=float)
    except Exception as exc_:  # noqa: BLE001 - reported with the file name
        detail = str(exc_).strip().splitlines()[0] if str(exc_).strip() else type(exc_).__name__
        raise SceneError(f"[excitation] file = {name!r} could not be read as CSV: {detail}") from None
    names = table.dtype.names or ()
    for col_key in ("time_column", "signal_column"):
        col = exc[col_key]
        if col not in names:
            raise SceneError(f"[excitation] {col_key} = {col!r} is not a column of {name!r}; "
                             f"columns are {', '.join(names)}" + _suggest(col, names))
    t = np.atleast_1d(np.asarray(table[exc["time_column"]], dtype=float))
    v = np.atleast_1d(np.asarray(table[exc["signal_column"]], dtype=float))
    if t.size < MIN_RECORDED_ROWS:
        raise SceneError(f"[excitation] file = {name!r} has {t.size} data rows: at least "
                         f"{MIN_RECORDED_ROWS} are needed (the quintic spline of the table motion)")
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
