"""Scene files: a TOML description of one BB-TENG and how it is driven.

Keys in the file carry their unit (``gap_mm``, ``frequency_hz``); the
:class:`Scene` object holds SI values only (metres, seconds, coulombs...).
Every key is validated on load; a bad value raises :class:`SceneError`
naming the key, the value and the allowed range.
"""
from __future__ import annotations

import copy
import dataclasses
import datetime
import difflib
import os
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


def _rng(lo=-_INF, hi=_INF, lo_open=False, hi_open=False, why=""):
    """A range constraint; ``why`` names the numerical limit behind a bound (quoted in
    the error message)."""
    return ("range", lo, hi, lo_open, hi_open, why)


def _choice(*options):
    return ("choice", options)


_POS = _rng(0.0, _INF, lo_open=True)
_NONNEG = _rng(0.0)

# -- numerical bounds of the ranges (issue #21 item 7): every numeric key is bounded by
# what the numerics can represent, so a value that passes validation gives finite output.
#: lengths [mm]: 1 nm (1000 x the impact map's rest height, 1 pm) to 10 m; derived
#: volumes, masses and the "auto" domain radius stay finite and representable
_LENGTH = _rng(1e-6, 1e4, why="1 nm to 10 m: lengths the dynamics and the geometry resolve")
#: table amplitude [mm]: 1 km keeps A w^4 (the kernel's snap bound) finite at every
#: allowed frequency (1e3 m x (2 pi 1e9 Hz)^4 = 1.6e42)
_AMPLITUDE = _rng(0.0, 1e6, why="up to 1 km: the kernel's bounds A w^2 ... A w^4 stay finite")
#: excitation frequency [Hz]: 1 uHz to 1 GHz (A w^4 stays finite with the amplitude bound;
#: the period count is bounded separately by MAX_PERIODS)
_FREQUENCY = _rng(1e-6, 1e9, why="1 uHz to 1 GHz")

SCHEMA: dict[str, dict[str, tuple]] = {
    "device": {
        "ball_diameter_mm": ("ball_diameter", float, 7.0, 1e-3, _LENGTH),
        "gap_mm": ("stroke", float, 3.0, 1e-3, _LENGTH),
        "electrode_radius_mm": ("electrode_radius", float, 4.0, 1e-3, _LENGTH),
        "tube_inner_radius_mm": ("tube_inner_radius", float, 4.0, 1e-3, _LENGTH),
        "tube_outer_radius_mm": ("tube_outer_radius", float, 5.5, 1e-3, _LENGTH),
        "plate_thickness_mm": ("plate_thickness", float, 2.0, 1e-3, _LENGTH),
        "ball_density_kg_per_m3": ("ball_density", float, 2200.0, 1.0,
                                   _rng(1e-3, 1e5, why="aerogel to twice osmium, a finite ball mass")),
        "ball_permittivity": ("ball_permittivity", float, 2.1, 1.0, _rng(1.0, 1e4)),
        "wall_permittivity": ("wall_permittivity", float, 2.6, 1.0, _rng(1.0, 1e4)),
        "surface_charge_uC_per_m2": ("surface_charge", float, -8.0, 1e-6, _rng(-1e4, 1e4)),
        "cells": ("cells", int, 1, 1, _rng(1, 10**7)),
    },
    "excitation": {
        "kind": ("kind", str, "sine", None, _choice("sine", "recorded")),
        "frequency_hz": ("frequency", float, 20.0, 1.0, _FREQUENCY),
        "amplitude_mm": ("amplitude", float, 1.5, 1e-3, _AMPLITUDE),
        "phase_deg": ("phase", float, 0.0, math.pi / 180.0, _rng(-360.0, 360.0)),
        "file": ("file", str, "", None, None),
        "time_column": ("time_column", str, "time_s", None, None),
        "signal_column": ("signal_column", str, "displacement_m", None, None),
        "signal": ("signal", str, "displacement", None, _choice("displacement", "acceleration")),
        "smoothing_hz": ("smoothing", float, 0.0, 1.0, _rng(0.0, 1e9)),
    },
    "contact": {
        "model": ("model", str, "impact", None, _choice("impact", "soft")),
        "restitution": ("restitution", float, 0.1, 1.0, _rng(0.0, 1.0)),
        "restitution_model": ("restitution_model", str, "constant", None,
                              _choice("constant", "power-law")),
        "restitution_reference_speed_m_per_s": ("restitution_reference_speed", float, 0.1, 1.0,
                                                _rng(1e-6, 1e3, why="1 um/s to 1 km/s")),
        "restitution_exponent": ("restitution_exponent", float, 0.0, 1.0, _rng(0.0, 1.0)),
        "stiffness_N_per_m": ("stiffness", float, 1.0e5, 1.0, _rng(1.0, 1e15)),
    },
    "initial": {
        "time_s": ("time", float, 0.0, 1.0,
                   _rng(-1e12, 1e12, why="|t| <= 1e12 s: the start time is carried exactly")),
        "gap_mm": ("gap", float, 0.0, 1e-3, _NONNEG),
        "velocity_m_per_s": ("velocity", float, 0.0, 1.0, _rng(-1e3, 1e3)),
    },
    "run": {
        "duration_s": ("duration", float, 1.0, 1.0, _rng(0.0, 1e6, lo_open=True)),
        "settle_periods": ("settle_periods", int, 10, 1, _rng(0, 10**7)),
        "sample_rate_hz": ("sample_rate", float, 20000.0, 1.0, _rng(0.0, 1e9, lo_open=True)),
        # independent realisations of a random excitation (issue #25; tengfield.ensemble)
        "realisations": ("realisations", int, 1, 1, _rng(1, 100000)),
    },
    "field": {
        "method": ("method", str, "auto", None, _choice("auto", "axisymmetric", "3d")),
        "degree": ("degree", int, 2, 1, _rng(1, 3)),
        "mesh_size_mm": ("mesh_size", float, 0.5, 1e-3, _rng(0.0, 100.0, lo_open=True)),
        "tolerance": ("tolerance", float, 1e-3, 1.0, _rng(1e-8, 0.5)),
        "domain_radius_mm": ("domain_radius", float, "auto", 1e-3, _rng(0.0, 1e6, lo_open=True)),
        "environment": ("environment", str, "free-space", None,
                        _choice("free-space", "grounded-table")),
        "far_field": ("far_field", str, "kelvin", None, _choice("kelvin", "robin", "dirichlet")),
        "ball_offset_mm": ("ball_offset", float, 0.0, 1e-3, _rng(0.0, 1e4)),
    },
    "circuit": {
        "kind": ("kind", str, "open", None, _choice("open", "short", "load")),
        "load_ohm": ("load", float, 1.0e8, 1.0,
                     _rng(1e-3, 1e18, why="1 mohm to 1 Eohm: the load integrator's tested span")),
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
                               _rng(1e-6, 1e12, why="1 pF to 1 MF")),
    # 0: no leakage resistor across the store
    "storage_leakage_ohm": ("storage_leakage", float, 0.0, 1.0, _rng(0.0, 1e30)),
    "pmic": ("pmic", str, "none", None, _choice("none", "uvlo")),
    "uvlo_rising_V": ("uvlo_rising", float, 5.05, 1.0, _rng(1e-3, 1e6)),
    "uvlo_falling_V": ("uvlo_falling", float, 4.04, 1.0, _rng(1e-3, 1e6)),
    "pmic_output_V": ("pmic_output", float, 3.3, 1.0, _rng(1e-3, 1e6)),
    "pmic_load_ohm": ("pmic_load", float, 1e5, 1.0,
                      _rng(1e-3, 1e18, why="1 mohm to 1 Eohm")),
    "pmic_efficiency": ("pmic_efficiency", float, 0.9, 1.0, _rng(0.0, 1.0, lo_open=True)),
    "pmic_quiescent_current_A": ("pmic_quiescent_current", float, 450e-9, 1.0, _rng(0.0, 1.0)),
    "pmic_shunt_V": ("pmic_shunt", float, 20.0, 1.0, _rng(1e-3, 1e6)),
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


# ---------------------------------------------------------------------------
# air breakdown (issue #23, tengfield.breakdown, tengfield.paschen): Paschen constants
# of air (Raizer 1991, Table 4.1) and the pressure; [device] surface_charge_uC_per_m2
# also takes "breakdown" (the run uses sigma = -sigma_max; until resolved the scene
# holds BREAKDOWN_PLACEHOLDER_UC).
SCHEMA["breakdown"] = {
    "pressure_kPa": ("pressure", float, 101.325, 1e3, _rng(0.0, 1e4, lo_open=True)),
    "paschen_A_per_Pa_m": ("paschen_A", float, 11.25, 1.0, _rng(0.0, 1e4, lo_open=True)),
    "paschen_B_V_per_Pa_m": ("paschen_B", float, 273.75, 1.0, _rng(0.0, 1e6, lo_open=True)),
    "secondary_emission": ("secondary_emission", float, 0.01, 1.0, _rng(0.0, 1.0, lo_open=True)),
}
#: the stand-in sigma [uC/m^2] of surface_charge_uC_per_m2 = "breakdown" before sigma_max is known
BREAKDOWN_PLACEHOLDER_UC = -1.0
#: keys that also take one keyword: (keyword, the number it stands for at load)
KEYWORD_VALUES = {("device", "surface_charge_uC_per_m2"): ("breakdown", BREAKDOWN_PLACEHOLDER_UC)}


@dataclass(frozen=True)
class Breakdown:
    """``[breakdown]``: ``pressure`` [Pa], Paschen's ``paschen_A`` [1/(Pa m)],
    ``paschen_B`` [V/(Pa m)] and ``secondary_emission`` (γ)."""
    pressure: float = 101325.0
    paschen_A: float = 11.25
    paschen_B: float = 273.75
    secondary_emission: float = 0.01

    def __post_init__(self):
        from .paschen import STREAMER_PD   # the Townsend range must not be empty
        lowest = math.exp(1.0 + math.log(math.log1p(1.0 / self.secondary_emission))) / STREAMER_PD
        if self.paschen_A <= lowest:
            raise SceneError(f"[breakdown] paschen_A_per_Pa_m = {self.paschen_A:g} is out of range "
                             f"with secondary_emission = {self.secondary_emission:g}: allowed "
                             f"({lowest:.4g}, 10000] (Paschen's minimum must lie below the "
                             f"streamer regime, p d = {STREAMER_PD:.4g} Pa m)")


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

# ---------------------------------------------------------------------------
# Random and multi-harmonic excitation (issue #25; tengfield.dynamics.vibration).
# kind = "harmonics": frequency_hz, amplitude_mm (or acceleration_m_per_s2) and
# phase_deg are lists, one entry per component (a single number is a list of one);
# kind = "random": a Gaussian table acceleration with a flat PSD on band_hz and
# rms_acceleration_m_per_s2, or the PSD of psd_file; either may be the noise on
# top of harmonics. seed picks the realisation.
SCHEMA["excitation"]["kind"] = ("kind", str, "sine", None,
                                _choice("sine", "recorded", "random", "harmonics"))
SCHEMA["excitation"].update({
    "acceleration_m_per_s2": ("acceleration", float, 0.0, 1.0, _rng(0.0, 1e6)),
    "band_hz": ("band", tuple, (), 1.0, _rng(0.0, 1e6, lo_open=True)),
    "rms_acceleration_m_per_s2": ("rms_acceleration", float, 0.0, 1.0, _rng(0.0, 1e6)),
    "psd_file": ("psd_file", str, "", None, None),
    "seed": ("seed", int, 0, 1, _rng(0, 2**32 - 1)),
})
#: keys of [excitation] that hold one entry per component with kind = "harmonics"
HARMONIC_KEYS = ("frequency_hz", "amplitude_mm", "acceleration_m_per_s2", "phase_deg")
#: components of a harmonics excitation
MAX_HARMONICS = 1000
#: points of a PSD table (psd_file)
MAX_PSD_ROWS = 100000
#: samples per period of the highest frequency in a synthesised record
#: (tengfield.dynamics.vibration.SAMPLES_PER_PERIOD; bounds its size at load)
VIBRATION_SAMPLES_PER_PERIOD = 32
#: samples of a synthesised record (its quintic spline: about 1 kB of memory per sample
#: while it is built, so 2e6 samples are ~2 GB; 2 s of a 31 kHz band)
MAX_RECORD_SAMPLES = 2e6

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
        "amplitude_x_mm": ("amplitude_x", float, 0.0, 1e-3, _AMPLITUDE),
        "amplitude_y_mm": ("amplitude_y", float, 0.0, 1e-3, _AMPLITUDE),
        "phase_x_deg": ("phase_x", float, 0.0, math.pi / 180.0, _rng(-360.0, 360.0)),
        "phase_y_deg": ("phase_y", float, 0.0, math.pi / 180.0, _rng(-360.0, 360.0)),
        "rms_acceleration_x_m_per_s2": ("rms_acceleration_x", float, 0.0, 1.0, _rng(0.0, 1e6)),
        "rms_acceleration_y_m_per_s2": ("rms_acceleration_y", float, 0.0, 1.0, _rng(0.0, 1e6)),
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
#: ... and at least this many (a 1e-300 s run, or a 1e-300 Hz sample rate, had none).
MIN_SAMPLES = 2
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

#: Bytes of a scene file: the default scene is 5 kB; tomllib needs ~130 bytes of memory
#: per byte of text (a 50 MB file took 6.7 GB), so 1 MB bounds a parse at ~150 MB.
MAX_SCENE_BYTES = 1_000_000
#: Nesting of tables and arrays in a scene file ([fit.columns.V] is 3 deep, an inline
#: table of [fit.parameters] 3): deeper structures are refused (tomllib recurses).
MAX_TOML_DEPTH = 8

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
    # random and harmonics (issue #25): components (frequency [Hz], amplitude [m],
    # phase [rad]); noise PSD: a flat band [Hz] with rms_acceleration [m/s^2], or a
    # table (psd_frequencies [Hz], psd_values [(m/s^2)^2/Hz]); seed of the realisation
    acceleration: float = 0.0
    band: tuple = ()
    rms_acceleration: float = 0.0
    psd_file: str = ""
    seed: int = 0
    rms_acceleration_x: float = 0.0
    rms_acceleration_y: float = 0.0
    harmonics: tuple = ()
    psd_frequencies: np.ndarray | None = field(default=None, compare=False, repr=False)
    psd_values: np.ndarray | None = field(default=None, compare=False, repr=False)

    @property
    def has_noise(self) -> bool:
        """Random noise is part of the table motion (kind random, or harmonics + noise)."""
        return self.kind in ("random", "harmonics") and (bool(self.band) or bool(self.psd_file))

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
    realisations: int = 1  # independent seeds of a random excitation


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
    breakdown: Breakdown = Breakdown()
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
        size = p.stat().st_size
        if size > MAX_SCENE_BYTES + 4:   # before reading: a 50 MB file is refused at once
            raise SceneError(f"scene file {str(p)!r} has {size:,} bytes: allowed at most "
                             f"{MAX_SCENE_BYTES:,} (recorded data belong in a CSV file)")
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
    if len(text) > MAX_SCENE_BYTES:
        raise SceneError(f"{source}: {len(text):,} characters: a scene file is allowed at most "
                         f"{MAX_SCENE_BYTES:,} (recorded data belong in a CSV file)")
    if "\x00" in text:
        raise SceneError(f"{source}: holds NUL characters (binary data, not a TOML scene)")
    _check_nesting_text(text, source)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"{source}: malformed TOML: {exc}") from None
    except RecursionError:
        raise SceneError(f"{source}: nested too deeply: allowed {MAX_TOML_DEPTH} levels of "
                         "tables and arrays") from None
    except (ValueError, OverflowError) as exc:   # e.g. an integer of more than 4300 digits
        import re
        long = re.search(r"[0-9_]{4000,}", text)
        if long:
            line = text.count("\n", 0, long.start()) + 1
            key = text[text.rfind("\n", 0, long.start()) + 1:long.start()].split("=")[0].strip()
            raise SceneError(f"{source}: line {line}: {key} = an integer of "
                             f"{long.end() - long.start()} digits is out of range: numbers must "
                             "stay within the doubles (|x| < 1.8e308)") from None
        detail = str(exc).split(";")[0].strip()
        raise SceneError(f"{source}: malformed TOML: {detail}") from None
    _check_values(data, source)
    return _build(data, base_dir=base_dir, source=source, text=text)


def _check_nesting_text(text: str, source: str) -> None:
    """Refuse brackets nested deeper than a scene can use before tomllib recurses into
    them (a cheap upper bound: brackets inside strings and comments count too, so the
    text limit is generous, 4 x MAX_TOML_DEPTH)."""
    depth = deepest = 0
    for ch in text:
        if ch in "[{":
            depth += 1
            if depth > deepest:
                deepest = depth
                if deepest > 4 * MAX_TOML_DEPTH:
                    raise SceneError(f"{source}: nested too deeply: allowed {MAX_TOML_DEPTH} "
                                     "levels of tables and arrays")
        elif ch in "]}":
            depth = max(0, depth - 1)


def _check_values(data, source: str, path: str = "", depth: int = 0) -> None:
    """Every value of a parsed scene: no TOML dates/times (no key takes one), nesting at
    most MAX_TOML_DEPTH, integers within the doubles."""
    if depth > MAX_TOML_DEPTH:
        raise SceneError(f"{source}: {path} is nested too deeply: allowed {MAX_TOML_DEPTH} "
                         "levels of tables and arrays")
    items = data.items() if isinstance(data, dict) else enumerate(data) \
        if isinstance(data, list) else ()
    for key, value in items:
        where = f"{path}.{key}" if isinstance(key, str) and path else \
            f"{path}[{key}]" if path else f"[{key}]"
        if isinstance(value, (datetime.date, datetime.time)):
            raise SceneError(f"{source}: {_where(where)} = {_show(value)}: no scene key takes a "
                             "date or time; write a number or a string")
        if isinstance(value, int) and not isinstance(value, bool) and abs(value) > 2**1023:
            raise SceneError(f"{source}: {_where(where)} = {_show(value)} is out of range: "
                             "integers must stay within the doubles (|x| < 1.8e308)")
        if isinstance(value, (dict, list)):
            _check_values(value, source, where, depth + 1)


def _where(path: str) -> str:
    """``[run].duration_s`` -> ``[run] duration_s`` (how messages name scene keys)."""
    sec, dot, rest = path.partition("].")
    return f"{sec}] {rest}" if dot else path


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
    _, lo, hi, lo_open, hi_open = c[:5]
    left = "(" if lo_open else "["
    right = ")" if hi_open else "]"
    why = c[5] if len(c) > 5 and c[5] else ""
    return f"{left}{lo:g}, {hi:g}{right}" + (f" ({why})" if why else "")


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
    keyword = KEYWORD_VALUES.get((sec, key))
    if keyword and isinstance(value, str):
        if value != keyword[0]:
            raise SceneError(f"{where} = {value!r}: expected a number or {keyword[0]!r}"
                             + _suggest(value, [keyword[0]]))
        value = keyword[1]
    if (sec, key) in AUTO_KEYS and isinstance(value, str):
        if value != "auto":
            raise SceneError(f"{where} = {_show(value)}: expected a number or 'auto'")
        return None   # resolved by _build
    if typ is str:
        if not isinstance(value, str):
            raise SceneError(f"{where} = {_show(value)}: expected a string")
        if constraint and constraint[0] == "choice" and value not in constraint[1]:
            allowed = ", ".join(repr(o) for o in constraint[1])
            raise SceneError(f"{where} = {value!r} is not allowed: choose one of {allowed}"
                             + _suggest(value, constraint[1]))
        return value
    if typ is tuple:
        if not isinstance(value, (list, tuple)) or isinstance(value, str):
            raise SceneError(f"{where} = {value!r}: expected a list of numbers, e.g. [20.0, 200.0]")
        if len(value) > MAX_HARMONICS:
            raise SceneError(f"{where}: {len(value)} entries; allowed at most {MAX_HARMONICS}")
        return tuple(_convert(sec, key, v, (attr, float, None, factor, constraint))
                     for v in value)
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        hint = (" (a list is allowed only with [excitation] kind = 'harmonics')"
                if isinstance(value, list) and sec == "excitation" and key in HARMONIC_KEYS else "")
        raise SceneError(f"{where} = {_show(value)}: expected a number{hint}")
    if typ is int:
        if isinstance(value, float) and not value.is_integer():
            raise SceneError(f"{where} = {value!r}: expected a whole number")
        value = int(value)
    elif isinstance(value, int):
        try:   # a TOML integer beyond the doubles (1e309 written out) is out of range
            value = float(value)
        except OverflowError:
            raise SceneError(f"{where} = {_show(value)} is out of range: allowed "
                             f"{_fmt_range(constraint)}") from None
    if isinstance(value, float) and not math.isfinite(value):
        raise SceneError(f"{where} = {value!r} is not finite: allowed range {_fmt_range(constraint)}")
    if constraint and constraint[0] == "range":
        _, lo, hi, lo_open, hi_open = constraint[:5]
        bad = (value < lo or value > hi or (lo_open and value == lo) or (hi_open and value == hi))
        if bad:
            raise SceneError(f"{where} = {_show(value)} is out of range: allowed "
                             f"{_fmt_range(constraint)}")
    return value * factor if typ is float else value


def _show(value) -> str:
    """A value for a message: repr, TOML dates as written, long integers shortened."""
    if isinstance(value, (datetime.date, datetime.time)):
        return f"{value.isoformat()} (a TOML date/time)"
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) >= 10**30:
        digits = len(str(abs(value))) if abs(value) < 10**4000 else "> 4000"
        return f"an integer of {digits} digits"
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


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
    components = None
    given_data = data
    if isinstance(data.get("excitation"), dict) and data["excitation"].get("kind") == "harmonics":
        # the lists stay in scene.raw (with_values, to_dict, the written scene); the
        # build below sees the fundamental's scalar values
        given_data, (data, components) = data, _harmonic_components(data)
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
    psd = _vibration_inputs(exc_vals, components, base_dir)
    exc = Excitation(**exc_vals, times=times, values=vals, harmonics=components or (),
                     psd_frequencies=psd[0], psd_values=psd[1])

    ini = Initial(**values["initial"])
    if ini.gap > dev.stroke:
        raise SceneError(f"[initial] gap_mm = {ini.gap * 1e3:g} is out of range: "
                         f"allowed [0, {dev.stroke * 1e3:g}] (the free stroke [device] gap_mm)")
    run = Run(**values["run"])
    check_steady_window(exc, run.settle_periods, run.duration)
    _check_work(exc, run)
    _check_vibration_work(exc, run)
    if run.realisations > 1 and not exc.has_noise:
        raise SceneError(f"[run] realisations = {run.realisations} needs a random excitation "
                         "([excitation] kind = 'random', or 'harmonics' with band_hz or "
                         f"psd_file): with kind = {exc.kind!r} every realisation is the same")
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
                 breakdown=Breakdown(**values["breakdown"]), raw=copy.deepcopy(given_data), source=source, text=text)


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
    if samples < MIN_SAMPLES:
        raise SceneError(
            f"[run] duration_s x sample_rate_hz = {run.duration:g} x {run.sample_rate:g} = "
            f"{samples:.3g} samples: allowed >= {MIN_SAMPLES:g} (the run's output needs "
            "samples to report)")
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


#: The default ``[field] mesh_size_mm`` (0.5 mm) resolves the paper's device, whose
#: smallest features are these [m]. Without ``mesh_size_mm`` in the scene, the default
#: size is scaled by ``max(1, min over the features of size / paper's size)``
#: (:func:`default_mesh_scale`): a device whose features are all k >= 1 times the
#: paper's gets the paper's mesh scaled by k (same cost, same relative error); a device
#: with one feature as small as the paper's keeps the default. A ``mesh_size_mm``
#: written in the scene (or passed as an override) is never scaled.
PAPER_FEATURES = {"ball_diameter_mm": 7.0e-3, "electrode_radius_mm": 4.0e-3, "gap_mm": 3.0e-3}
#: ... and, with dielectric walls (``wall_permittivity != 1``), the walls and the
#: ball's clearance to the tube (plate thickness also under a grounded table)
PAPER_WALL_FEATURES = {"tube_outer_radius_mm - tube_inner_radius_mm": 1.5e-3,
                       "plate_thickness_mm": 2.0e-3,
                       "tube_inner_radius_mm - ball_diameter_mm / 2": 0.5e-3}


def mesh_features(device, environment: str = "free-space") -> dict[str, float]:
    """The features [m] a mesh of ``device`` must resolve, by scene key (see
    :data:`PAPER_FEATURES`)."""
    features = {"ball_diameter_mm": device.ball_diameter,
                "electrode_radius_mm": device.electrode_radius, "gap_mm": device.stroke}
    walls = device.wall_permittivity != 1.0
    if walls:
        features["tube_outer_radius_mm - tube_inner_radius_mm"] = \
            device.tube_outer_radius - device.tube_inner_radius
        features["tube_inner_radius_mm - ball_diameter_mm / 2"] = \
            device.tube_inner_radius - device.ball_radius
    if walls or environment == "grounded-table":
        features["plate_thickness_mm"] = device.plate_thickness
    return features


def default_mesh_scale(device, fld) -> float:
    """Factor on the default ``mesh_size_mm``: ``max(1, min_i feature_i / paper_i)`` over
    :func:`mesh_features` (1.0 exactly for the paper's device)."""
    paper = {**PAPER_FEATURES, **PAPER_WALL_FEATURES}
    ratios = [size / paper[key] for key, size in mesh_features(device, fld.environment).items()]
    return max(1.0, min(ratios))


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
    # the size the mesher uses: as written, or the default scaled by the smallest feature
    mesh_size = fld.mesh_size if "mesh_size_mm" in explicit \
        else fld.mesh_size * default_mesh_scale(dev, fld)
    if mesh_size < finest * (1 - 1e-12):
        problems.append(
            f"[field] mesh_size_mm = {mesh_size * 1e3:g} is too fine for this device: "
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
    what = f"[excitation] file = {name!r}"
    try:
        check_file_size(path, what, MAX_RECORDED_BYTES)
        blob = path.read_bytes()
    except OSError as exc_:
        raise SceneError(f"{what} could not be read: {exc_.strerror or exc_}") from None
    text = decode_utf8(blob, what)   # BOM dropped here
    if not text.strip():
        raise SceneError(f"{what} is empty: expected a header line "
                         f"({exc['time_column']},{exc['signal_column']}) and at least "
                         f"{MIN_RECORDED_ROWS} data rows")
    header, rows = read_csv_rows(text, what, MAX_RECORDED_ROWS)
    for col_key in ("time_column", "signal_column"):
        col = exc[col_key]
        if col not in header:
            raise SceneError(f"[excitation] {col_key} = {col!r} is not a column of {name!r}; "
                             f"columns are {', '.join(header)}" + _suggest(col, header))
    if len(rows) < MIN_RECORDED_ROWS:
        raise SceneError(f"{what} has {len(rows)} data rows: at least "
                         f"{MIN_RECORDED_ROWS} are needed (the quintic spline of the table motion)")
    t = csv_column(header, rows, exc["time_column"], what, allow_blank=True)
    v = csv_column(header, rows, exc["signal_column"], what, allow_blank=True)
    for label, arr in (("time", t), ("signal", v)):
        bad = np.flatnonzero(~np.isfinite(arr))
        if bad.size:
            raise SceneError(f"{what}: {label} column holds NaN or inf "
                             f"at data row {bad[0] + 1}")
    limit, unit = ((MAX_RECORDED_DISPLACEMENT, "m") if exc["signal"] == "displacement"
                   else (MAX_RECORDED_ACCELERATION, "m/s^2"))
    check_magnitude(v, limit, what, f"{exc['signal']} column {exc['signal_column']!r}", unit)
    check_magnitude(t, MAX_RECORDED_TIME, what, f"time column {exc['time_column']!r}", "s")
    check_time_steps(t, what)
    return t, v


# -- CSV input shared by the recorded excitation and fit's measured trace ---------------
#: Bytes and data rows of a recorded excitation (checked before reading): 2e6 rows is
#: 100 s at 20 kHz; the quintic spline and its bounds take ~0.5 kB per row (1 GB), and
#: Python's CSV reader ~2 s per million rows. A 30M-row file exhausted memory after 49 s.
MAX_RECORDED_ROWS = 2_000_000
MAX_RECORDED_BYTES = 200_000_000
#: |displacement| [m] (1 km, the amplitude_mm bound) and |acceleration| [m/s^2] (1e8 g)
#: of a record: the spline's bounds (up to the 4th derivative) stay finite
MAX_RECORDED_DISPLACEMENT = 1e3
MAX_RECORDED_ACCELERATION = 1e9
#: |time| [s] of a record, the [initial] time_s bound (1e12 s: doubles keep 0.1 ms)
MAX_RECORDED_TIME = 1e12
#: a time step below this fraction of the record's median step is refused: far below the
#: data's resolution (a near-duplicate stamp 1e-15 s apart made the spline ring)
MIN_STEP_FRACTION = 1e-3


def check_file_size(path: Path, what: str, limit: int) -> None:
    """SceneError before reading when ``path`` has more than ``limit`` bytes."""
    size = path.stat().st_size
    if size > limit:
        raise SceneError(f"{what} has {size:,} bytes: allowed at most {limit:,} "
                         f"({limit / 1e6:g} MB, checked before reading; decimate or split it)")


def read_csv_rows(text: str, what: str, max_rows: int) -> tuple[list[str], list[tuple]]:
    """(header, [(line number, fields), ...]) of a comma-separated text: blank lines and
    ``#`` comments skipped; a row whose field count differs from the header's is refused
    naming its line; more than ``max_rows`` data rows are refused as soon as seen."""
    import csv

    header: list[str] | None = None
    rows: list[tuple] = []
    for number, line in enumerate(text.splitlines(), start=1):
        line = line.split("#", 1)[0]
        if not line.strip():
            continue
        fields = next(csv.reader([line]))
        if header is None:
            header = [f.strip() for f in fields]
            continue
        if len(fields) != len(header):
            raise SceneError(f"{what}: line {number} (data row {len(rows) + 1}) has "
                             f"{len(fields)} field(s): expected {len(header)} "
                             f"({','.join(header)}): {line.strip()[:60]!r}")
        rows.append((number, fields))
        if len(rows) > max_rows:
            raise SceneError(f"{what} has more than {max_rows:,} data rows: allowed at most "
                             f"{max_rows:,} (checked while reading; decimate or split it)")
    return header or [], rows


def csv_column(header, rows, col: str, what: str, *, allow_blank: bool = False) -> np.ndarray:
    """One column of :func:`read_csv_rows` as floats; a cell that is not a number is
    refused naming its line, data row and text (blank: NaN with ``allow_blank``)."""
    j = header.index(col)
    out = np.empty(len(rows))
    for i, (number, fields) in enumerate(rows):
        cell = fields[j].strip()
        if not cell and allow_blank:
            out[i] = math.nan
            continue
        try:
            out[i] = float(cell)
        except ValueError:
            raise SceneError(f"{what}: column {col!r} holds {cell[:40]!r} at line {number} "
                             f"(data row {i + 1}): expected a number") from None
    return out


def check_magnitude(x: np.ndarray, limit: float, what: str, label: str, unit: str) -> None:
    """Refuse |x| > ``limit`` naming the first such data row and its value."""
    bad = np.flatnonzero(np.abs(x) > limit)
    if bad.size:
        raise SceneError(f"{what}: {label} holds {x[bad[0]]:g} {unit} at data row {bad[0] + 1}: "
                         f"allowed |x| <= {limit:g} {unit} (beyond it the numerics overflow; "
                         "check the column's unit)")


def check_time_steps(t: np.ndarray, what: str, *, row_offset: int = 0) -> None:
    """Times must increase, by steps of at least MIN_STEP_FRACTION x the median step (and
    more than 4 ulp of the times): the message names the data row and both values."""
    step = np.diff(t)
    if np.any(step <= 0):
        i = int(np.flatnonzero(step <= 0)[0])
        raise SceneError(f"{what}: time is not strictly increasing at data row "
                         f"{i + 2 + row_offset} ({t[i]!r} s then {t[i + 1]!r} s)")
    if step.size == 0:
        return
    median = float(np.median(step))
    ulp = 4.0 * np.spacing(np.maximum(np.abs(t[:-1]), np.abs(t[1:])))
    small = np.flatnonzero((step < MIN_STEP_FRACTION * median) | (step <= ulp))
    if small.size:
        i = int(small[0])
        raise SceneError(f"{what}: time step at data row {i + 2 + row_offset} is {step[i]:.3g} s "
                         f"({t[i]!r} s then {t[i + 1]!r} s), far below the data's resolution: "
                         f"allowed >= {MIN_STEP_FRACTION:g} x the median step "
                         f"{median:.3g} s (a duplicated or mistyped stamp?)")


# ---------------------------------------------------------------------------
# random and harmonics excitation (issue #25)
def _harmonic_components(data: dict) -> tuple[dict, tuple]:
    """``kind = "harmonics"``: the components ((frequency [Hz], amplitude [m], phase
    [rad]), ...) from the list keys, each entry validated as its scalar key is; the data
    returned carries the fundamental's (lowest frequency's) scalar values, which set the
    analysis period (settle_periods, the regime window) as frequency_hz does for a sine."""
    exc = dict(data["excitation"])
    spec = SCHEMA["excitation"]

    def entries(key):
        if key not in exc:
            return None
        raw = exc[key]
        items = raw if isinstance(raw, list) else [raw]
        if not items:
            raise SceneError(f"[excitation] {key} = []: give one entry per component")
        if len(items) > MAX_HARMONICS:
            raise SceneError(f"[excitation] {key}: {len(items)} components; allowed at most "
                             f"{MAX_HARMONICS}")
        return [_convert("excitation", key, v, spec[key]) for v in items]

    freqs = entries("frequency_hz")
    if freqs is None:
        raise SceneError("[excitation] kind = 'harmonics' needs frequency_hz = [f1, f2, ...]")
    amps = entries("amplitude_mm")
    accs = entries("acceleration_m_per_s2")
    if (amps is None) == (accs is None):
        raise SceneError("[excitation] kind = 'harmonics' needs exactly one of amplitude_mm = "
                         "[...] and acceleration_m_per_s2 = [...], one entry per frequency")
    phases = entries("phase_deg") or [0.0] * len(freqs)
    given = amps if amps is not None else accs
    for key, got in (("amplitude_mm" if amps is not None else "acceleration_m_per_s2", given),
                     ("phase_deg", phases)):
        if len(got) != len(freqs):
            raise SceneError(f"[excitation] {key} has {len(got)} entries but frequency_hz has "
                             f"{len(freqs)}: give one per component")
    if amps is None:   # acceleration amplitude a -> displacement a / (2 pi f)^2
        amps = [a / (2.0 * math.pi * f) ** 2 for a, f in zip(accs, freqs)]
    components = tuple((float(f), float(a), float(p)) for f, a, p in zip(freqs, amps, phases))
    k = min(range(len(components)), key=lambda i: components[i][0])
    f0, a0, p0 = components[k]
    exc.update({"frequency_hz": f0, "amplitude_mm": a0 * 1e3, "phase_deg": p0 * 180.0 / math.pi})
    exc.pop("acceleration_m_per_s2", None)
    out = dict(data)
    out["excitation"] = exc
    return out, components


def _vibration_inputs(exc: dict, components, base_dir: Path | None):
    """Check the noise keys of a random or harmonics excitation; (psd frequencies [Hz],
    psd values [(m/s^2)^2/Hz]) of psd_file, or (None, None)."""
    kind = exc["kind"]
    band, rms, psd_file = exc["band"], exc["rms_acceleration"], exc["psd_file"]
    if kind not in ("random", "harmonics"):
        for key, given in (("band_hz", band), ("psd_file", psd_file)):
            if given:
                raise SceneError(f"[excitation] {key} needs kind = 'random' or 'harmonics' "
                                 f"(kind = {kind!r})")
        return None, None
    if band and psd_file:
        raise SceneError("[excitation] band_hz and psd_file: give one of them (a flat band "
                         "or a PSD table)")
    if band:
        if len(band) != 2 or not band[0] < band[1]:
            shown = ", ".join(f"{b:g}" for b in band)
            raise SceneError(f"[excitation] band_hz = [{shown}]: expected [f1, f2] with "
                             "0 < f1 < f2 [Hz]")
        if rms <= 0.0:
            raise SceneError("[excitation] band_hz needs rms_acceleration_m_per_s2 > 0 "
                             f"(it is {rms:g})")
    elif psd_file:
        freqs, vals = _read_psd(psd_file, base_dir)
        if not np.any(vals > 0.0):
            raise SceneError(f"[excitation] psd_file = {psd_file!r} holds no power (every "
                             "PSD value is 0)")
        return freqs, vals   # rms_acceleration_m_per_s2 > 0 rescales it (dynamics.vibration)
    elif kind == "random":
        raise SceneError("[excitation] kind = 'random' needs band_hz = [f1, f2] with "
                         "rms_acceleration_m_per_s2, or psd_file = 'name.csv'")
    return None, None


def _read_psd(name: str, base_dir: Path | None) -> tuple[np.ndarray, np.ndarray]:
    """A PSD table: header ``frequency_hz`` and one of ``psd_g2_per_hz`` or
    ``psd_m2_per_s4_per_hz`` (the CSV reader of recorded excitations,
    :func:`read_csv_rows`); returns (frequencies [Hz], values [(m/s^2)^2/Hz])."""
    where = f"[excitation] psd_file = {name!r}"
    path = Path(name)
    if not path.is_absolute() and base_dir is not None:
        path = base_dir / path
    if not path.is_file():
        raise SceneError(f"{where}: no such file ({path})")
    try:
        check_file_size(path, where, MAX_RECORDED_BYTES)
        blob = path.read_bytes()
    except OSError as exc_:
        raise SceneError(f"{where} could not be read: {exc_.strerror or exc_}") from None
    header, rows = read_csv_rows(decode_utf8(blob, where), where, MAX_PSD_ROWS)
    units = {"psd_g2_per_hz": G**2, "psd_m2_per_s4_per_hz": 1.0}
    value_cols = [h for h in header if h in units]
    if "frequency_hz" not in header or len(value_cols) != 1:
        raise SceneError(f"{where}: header {','.join(header)!r} needs the columns frequency_hz "
                         "and one of psd_g2_per_hz, psd_m2_per_s4_per_hz")
    freqs = csv_column(header, rows, "frequency_hz", where)
    vals = csv_column(header, rows, value_cols[0], where)
    if freqs.size < 2:
        raise SceneError(f"{where} has {freqs.size} data rows: at least 2 are needed")
    for i, (f, v) in enumerate(zip(freqs, vals)):
        if not (math.isfinite(f) and math.isfinite(v)) or not 0.0 < f <= 1e6 or not 0.0 <= v <= 1e12:
            raise SceneError(f"{where}: data row {i + 1}: frequency_hz = {f:g}, "
                             f"{value_cols[0]} = {v:g}; allowed frequency in (0, 1e6] Hz, "
                             "PSD in [0, 1e12]")
        if i and f <= freqs[i - 1]:
            raise SceneError(f"{where}: data row {i + 1}: frequency {f:g} Hz is not above the "
                             f"previous row's {freqs[i - 1]:g} Hz")
    return freqs, vals * units[value_cols[0]]


def _vibration_max_frequency(exc: Excitation) -> float:
    freqs = [c[0] for c in exc.harmonics]
    if exc.band:
        freqs.append(exc.band[1])
    if exc.psd_frequencies is not None:
        freqs.append(float(exc.psd_frequencies[-1]))
    return max(freqs) if freqs else 0.0


def _check_vibration_work(exc: Excitation, run: Run) -> None:
    """Refuse a synthesised record that would not fit: duration x 32 samples per period
    of the highest frequency must stay below MAX_SAMPLES."""
    if exc.kind not in ("random", "harmonics") or (exc.kind == "harmonics" and len(exc.harmonics) == 1
                                                    and not exc.has_noise):
        return
    fmax = _vibration_max_frequency(exc)
    count = run.duration * VIBRATION_SAMPLES_PER_PERIOD * fmax
    if not count < MAX_RECORD_SAMPLES:
        raise SceneError(
            f"[run] duration_s x {VIBRATION_SAMPLES_PER_PERIOD} x the highest excitation "
            f"frequency = {run.duration:g} x {VIBRATION_SAMPLES_PER_PERIOD} x {fmax:g} Hz = "
            f"{count:.3g} record samples: allowed < {MAX_RECORD_SAMPLES:.0e} (a shorter run "
            "or a lower band)")

