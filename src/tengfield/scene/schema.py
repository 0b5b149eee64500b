"""Every scene key, declared once: section, file key -> :class:`Key` (attribute, type,
default, SI factor, range or choices, and whether it changes a field solve).

Keys in the file carry their unit (``stroke_mm``, ``frequency_hz``); ``Key.factor`` turns
the file's number into SI. :data:`FIELD_KEYS` (the surrogate cache hash) is derived
from the ``field=True`` flags. :func:`convert` checks one file value,
:func:`check_attribute` one SI value of a dataclass built from Python.
"""
from __future__ import annotations

import datetime
import difflib
import math
import warnings
from numbers import Integral, Real
from typing import Any, NamedTuple

from .._mpi import launched_rank as _launched_rank
from ..errors import SceneError
from ..quantities import SURFACE_CHARGE_KEY   # σ's key, spelled once (base layer)
from ..quantities import stated_surface_charge  # noqa: F401 - read off a scene once
from ..terminals import REFERENCES   # the topologies' names (terminals.TOPOLOGIES)
from .limits import MAX_HARMONICS
from .shapes import SHAPES

#: Bumped whenever the field solver changes what it computes for the same
#: inputs; part of the surrogate cache hash. 2: the ball's surface charge left the
#: hash (a surrogate is scaled to the scene's sigma, issue #28)
FIELD_SCHEMA = 2


#: the same key as "section.key" (``--set``, ``[uncertainty.vary]``, ``[design.vary]``)
SURFACE_CHARGE_SETTING = f"device.{SURFACE_CHARGE_KEY}"


class Key(NamedTuple):
    """One scene key: ``attr`` of the dataclass, ``type`` (float, int, str, tuple of
    floats), file-level ``default``, ``factor`` (file unit -> SI; None for strings),
    ``check`` (:func:`_rng`, :func:`_choice` or None) and ``field`` (a change alters a
    field solve: the key is part of :meth:`Scene.field_hash`)."""
    attr: str
    type: type
    default: Any
    factor: float | None
    check: tuple | None
    field: bool = False


_INF = math.inf

#: ``[device] shape``: the cells a scene can name, the shape registry's (scene/shapes/;
#: ``tengfield.field.cells.CELLS`` holds their field models, tests/field/
#: test_shape_registry.py holds the two equal)
CELL_SHAPES = tuple(SHAPES)


def _rng(lo=-_INF, hi=_INF, lo_open=False, hi_open=False, why=""):
    """A range constraint; ``why`` names the numerical limit behind a bound (quoted in
    the error message)."""
    return ("range", lo, hi, lo_open, hi_open, why)


def _choice(*options):
    return ("choice", options)


_POS = _rng(0.0, _INF, lo_open=True)
_NONNEG = _rng(0.0)
_DEG = math.pi / 180.0

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
_ANGLE = _rng(-360.0, 360.0)
#: a measured magnitude of [reference] (0: not given)
_MEASURED = _rng(0.0, 1e30, why="a measured magnitude; 0: not given")

SCHEMA: dict[str, dict[str, Key]] = {
    "device": {
        "ball_diameter_mm": Key("ball_diameter", float, 7.0, 1e-3, _LENGTH, field=True),
        # the free stroke dh = h - d (called gap_mm before issue #29: RENAMED_KEYS)
        "stroke_mm": Key("stroke", float, 3.0, 1e-3, _LENGTH, field=True),
        "electrode_radius_mm": Key("electrode_radius", float, 4.0, 1e-3, _LENGTH, field=True),
        "tube_inner_radius_mm": Key("tube_inner_radius", float, 4.0, 1e-3, _LENGTH, field=True),
        "tube_outer_radius_mm": Key("tube_outer_radius", float, 5.5, 1e-3, _LENGTH, field=True),
        "plate_thickness_mm": Key("plate_thickness", float, 2.0, 1e-3, _LENGTH, field=True),
        "ball_density_kg_per_m3": Key("ball_density", float, 2200.0, 1.0,
                                      _rng(1e-3, 1e5, why="aerogel to twice osmium, a finite "
                                           "ball mass")),
        "ball_permittivity": Key("ball_permittivity", float, 2.1, 1.0, _rng(1.0, 1e4), field=True),
        "wall_permittivity": Key("wall_permittivity", float, 2.6, 1.0, _rng(1.0, 1e4), field=True),
        # also the keyword "breakdown" (KEYWORD_VALUES). Not a field key: every charge of
        # the field is linear in sigma, so a cached surrogate is scaled to the scene's sigma
        # (tengfield.surrogate.at_surface_charge) and a sigma-only change solves nothing
        SURFACE_CHARGE_KEY: Key("surface_charge", float, -8.0, 1e-6, _rng(-1e4, 1e4)),
        "cells": Key("cells", int, 1, 1, _rng(1, 10**7)),
        # 3D motion (issue #13): gravity tilted by tilt from -z toward tilt_azimuth
        "tilt_deg": Key("tilt", float, 0.0, _DEG, _rng(0.0, 180.0)),
        "tilt_azimuth_deg": Key("tilt_azimuth", float, 0.0, _DEG, _ANGLE),
        # the cell's shape (issue #32; scene/shapes/, field/cells/): "hexagonal" reads the
        # tube's keys as the hexagon's apothems (3D solves). In the field hash only when
        # not "tube" (a tube's hash is the one before the key existed)
        "shape": Key("shape", str, "tube", None, _choice(*CELL_SHAPES), field=True),
        # shape = "spherical-shell": the cavity (its stroke is cavity - ball diameter), the
        # shell behind the electrodes (wall_permittivity), the insulating band at the
        # equator. In the field hash of a shell only (scene/shapes/ SHAPE_KEYS)
        "cavity_diameter_mm": Key("cavity_diameter", float, 20.0, 1e-3, _LENGTH),
        "shell_thickness_mm": Key("shell_thickness", float, 2.0, 1e-3, _LENGTH),
        "electrode_band_mm": Key("electrode_band", float, 2.0, 1e-3, _LENGTH),
        # the cell's electrodes (issue #51): "both" (the pair), "lower" (the single-electrode
        # cell: the upper plate bare, the terminals the lower electrode and the ground). In
        # the field hash only when not "both" (the pair's hash is the one before the key)
        "electrodes": Key("electrodes", str, "both", None, _choice("both", "lower"), field=True),
    },
    "excitation": {
        "kind": Key("kind", str, "sine", None, _choice("sine", "recorded", "random", "harmonics")),
        # kind = "harmonics": frequency_hz, amplitude_mm (or acceleration_m_per_s2) and
        # phase_deg are lists, one entry per component (HARMONIC_KEYS)
        "frequency_hz": Key("frequency", float, 20.0, 1.0, _FREQUENCY),
        "amplitude_mm": Key("amplitude", float, 1.5, 1e-3, _AMPLITUDE),
        "phase_deg": Key("phase", float, 0.0, _DEG, _ANGLE),
        # kind = "recorded": a CSV relative to the scene file
        "file": Key("file", str, "", None, None),
        "time_column": Key("time_column", str, "time_s", None, None),
        "signal_column": Key("signal_column", str, "displacement_m", None, None),
        "signal": Key("signal", str, "displacement", None, _choice("displacement", "acceleration")),
        # the header's line in the file (1-based); 0: the first line naming time_column
        # (an oscilloscope's metadata lines before it are skipped)
        "header_row": Key("header_row", int, 0, 1, _rng(0, 10**7)),
        "smoothing_hz": Key("smoothing", float, 0.0, 1.0, _rng(0.0, 1e9)),
        # random and harmonics (issue #25): a Gaussian table acceleration with a flat PSD
        # on band_hz and rms_acceleration_m_per_s2, or the PSD of psd_file; either may
        # be the noise on top of harmonics. seed picks the realisation.
        "acceleration_m_per_s2": Key("acceleration", float, 0.0, 1.0, _rng(0.0, 1e6)),
        "band_hz": Key("band", tuple, (), 1.0, _rng(0.0, 1e6, lo_open=True)),
        "rms_acceleration_m_per_s2": Key("rms_acceleration", float, 0.0, 1.0, _rng(0.0, 1e6)),
        "psd_file": Key("psd_file", str, "", None, None),
        "seed": Key("seed", int, 0, 1, _rng(0, 2**32 - 1)),
        # 3D motion: lateral sine x = A_x sin(w t + phase_x); recorded lateral columns
        "amplitude_x_mm": Key("amplitude_x", float, 0.0, 1e-3, _AMPLITUDE),
        "amplitude_y_mm": Key("amplitude_y", float, 0.0, 1e-3, _AMPLITUDE),
        "phase_x_deg": Key("phase_x", float, 0.0, _DEG, _ANGLE),
        "phase_y_deg": Key("phase_y", float, 0.0, _DEG, _ANGLE),
        "rms_acceleration_x_m_per_s2": Key("rms_acceleration_x", float, 0.0, 1.0, _rng(0.0, 1e6)),
        "rms_acceleration_y_m_per_s2": Key("rms_acceleration_y", float, 0.0, 1.0, _rng(0.0, 1e6)),
        "signal_x_column": Key("signal_x_column", str, "", None, None),
        "signal_y_column": Key("signal_y_column", str, "", None, None),
    },
    # 3D material defaults (handbook values, sources in docs/motion3d.md): PTFE ball E
    # 0.5 GPa, nu 0.46; copper electrodes E 120 GPa, nu 0.34; PMMA tube E 3.0 GPa,
    # nu 0.37; Coulomb friction static 0.1 / dynamic 0.05 (the reference paper's model).
    "contact": {
        "model": Key("model", str, "impact", None, _choice("impact", "soft", "3d")),
        "restitution": Key("restitution", float, 0.1, 1.0, _rng(0.0, 1.0)),
        "restitution_model": Key("restitution_model", str, "constant", None,
                                 _choice("constant", "power-law")),
        "restitution_reference_speed_m_per_s": Key("restitution_reference_speed", float, 0.1, 1.0,
                                                   _rng(1e-6, 1e3, why="1 um/s to 1 km/s")),
        "restitution_exponent": Key("restitution_exponent", float, 0.0, 1.0, _rng(0.0, 1.0)),
        "stiffness_N_per_m": Key("stiffness", float, 1.0e5, 1.0, _rng(1.0, 1e15)),
        "law": Key("law", str, "hertz", None, _choice("hertz", "power")),
        "damping_model": Key("damping_model", str, "calibrated", None,
                             _choice("calibrated", "chrono")),
        "exponent": Key("exponent", float, 1.0, 1.0, _rng(1.0, 3.0)),
        "damping_N_s_per_m": Key("damping", float, -1.0, 1.0, _rng(-1.0, 1e12)),
        "penetration_max_mm": Key("penetration_max", float, 0.0, 1e-3, _rng(0.0, 10.0)),
        "ball_youngs_modulus_GPa": Key("ball_youngs_modulus", float, 0.5, 1e9,
                                       _rng(1e-6, 1e4, lo_open=True)),
        "ball_poisson_ratio": Key("ball_poisson_ratio", float, 0.46, 1.0,
                                  _rng(-1.0, 0.5, lo_open=True)),
        "plate_youngs_modulus_GPa": Key("plate_youngs_modulus", float, 120.0, 1e9,
                                        _rng(1e-6, 1e4, lo_open=True)),
        "plate_poisson_ratio": Key("plate_poisson_ratio", float, 0.34, 1.0,
                                   _rng(-1.0, 0.5, lo_open=True)),
        "wall_youngs_modulus_GPa": Key("wall_youngs_modulus", float, 3.0, 1e9,
                                       _rng(1e-6, 1e4, lo_open=True)),
        "wall_poisson_ratio": Key("wall_poisson_ratio", float, 0.37, 1.0,
                                  _rng(-1.0, 0.5, lo_open=True)),
        "friction_static": Key("friction_static", float, 0.1, 1.0, _rng(0.0, 10.0)),
        "friction_dynamic": Key("friction_dynamic", float, 0.05, 1.0, _rng(0.0, 10.0)),
    },
    "initial": {
        "time_s": Key("time", float, 0.0, 1.0,
                      _rng(-1e12, 1e12, why="|t| <= 1e12 s: the start time is carried exactly")),
        "gap_mm": Key("gap", float, 0.0, 1e-3, _NONNEG),
        "velocity_m_per_s": Key("velocity", float, 0.0, 1.0, _rng(-1e3, 1e3)),
    },
    "run": {
        "duration_s": Key("duration", float, 1.0, 1.0, _rng(0.0, 1e6, lo_open=True)),
        "settle_periods": Key("settle_periods", int, 10, 1, _rng(0, 10**7)),
        "sample_rate_hz": Key("sample_rate", float, 20000.0, 1.0, _rng(0.0, 1e9, lo_open=True)),
        # independent realisations of a random excitation (issue #25; tengfield.ensemble)
        "realisations": Key("realisations", int, 1, 1, _rng(1, 100000)),
        # the tables of `tengfield run`: CSV files, or one HDF5 file (run.h5); a run past
        # the CSV bound (tengfield.files.hdf5.MAX_CSV_ROWS) writes HDF5 with a warning
        "output_format": Key("output_format", str, "csv", None, _choice("csv", "hdf5")),
    },
    # field-only: a bad value fails only where a field stage runs (check_field)
    "field": {
        "method": Key("method", str, "auto", None, _choice("auto", "axisymmetric", "3d"),
                      field=True),
        "degree": Key("degree", int, 2, 1, _rng(1, 3), field=True),
        "mesh_size_mm": Key("mesh_size", float, 0.5, 1e-3, _rng(0.0, 100.0, lo_open=True),
                            field=True),
        "tolerance": Key("tolerance", float, 1e-3, 1.0, _rng(1e-8, 0.5), field=True),
        # also "auto" (AUTO_KEYS)
        "domain_radius_mm": Key("domain_radius", float, "auto", 1e-3,
                                _rng(0.0, 1e6, lo_open=True), field=True),
        "environment": Key("environment", str, "free-space", None,
                           _choice("free-space", "grounded-table"), field=True),
        "far_field": Key("far_field", str, "kelvin", None,
                         _choice("kelvin", "robin", "dirichlet"), field=True),
        "ball_offset_mm": Key("ball_offset", float, 0.0, 1e-3, _rng(0.0, 1e4), field=True),
        # issue #40 (tengfield.field.cost): the estimated peak memory of one field solve
        # is refused past this many GB before any meshing; 0: 80 % of the machine's memory
        "max_memory_gb": Key("max_memory_gb", float, 0.0, 1.0, _rng(0.0, 1e6)),
        # the (z, r) surrogate's 3D solves (tengfield.surrogate.precompute_radial; its cache
        # key holds them, not the axis surrogate's): mesh size, degree, tolerance
        "radial_mesh_size_mm": Key("radial_mesh_size", float, 1.5, 1e-3,
                                   _rng(0.0, 100.0, lo_open=True)),
        "radial_degree": Key("radial_degree", int, 2, 1, _rng(1, 2)),
        "radial_tolerance": Key("radial_tolerance", float, 1e-2, 1.0, _rng(1e-8, 0.5)),
        # the axisymmetric tube's positions: each meshed by gmsh ("remesh"), or one
        # reference mesh moved with the ball ("move": tengfield.field.moving). In the
        # field hash only when "move" (Scene.field_inputs): "remesh" keeps today's keys
        "mesh_motion": Key("mesh_motion", str, "remesh", None, _choice("remesh", "move"),
                           field=True),
        # the 3D meshes (tengfield.field.geometry3d, issue #55): "uniform" keeps the base size
        # in the whole device; "graded" lets it grow away from the gaps, the electrode rims
        # and the ball. In the field hash only when "graded" (Scene.field_inputs)
        "mesh_grading": Key("mesh_grading", str, "uniform", None, _choice("uniform", "graded"),
                            field=True),
    },
    # kind = "rectifier": harvesting electronics (issue #11; tengfield.harvest); the
    # chip's defaults are the LTC3588-1's (docs/harvest.md)
    "circuit": {
        "kind": Key("kind", str, "open", None,
                    _choice("open", "short", "load", "rectifier", "series-rc")),
        "load_ohm": Key("load", float, 1.0e8, 1.0,
                        _rng(1e-3, 1e18, why="1 mohm to 1 Eohm: the load integrator's tested span")),
        "parallel_capacitance_pF": Key("parallel_capacitance", float, 0.0, 1e-12, _rng(0.0, 1e9)),
        # kind = "series-rc": C_s in series with load_ohm
        "series_capacitance_pF": Key("series_capacitance", float, 100.0, 1e-12,
                                     _rng(1e-6, 1e18, why="1 aF to 1 MF")),
        "reference": Key("reference", str, "floating", None, _choice(*REFERENCES)),
        "diode": Key("diode", str, "ideal", None, _choice("ideal", "shockley")),
        "diode_forward_voltage_V": Key("diode_forward_voltage", float, 0.0, 1.0, _rng(0.0, 100.0)),
        "diode_saturation_current_A": Key("diode_saturation_current", float, 1e-12, 1.0,
                                          _rng(1e-18, 1.0)),
        "diode_emission_coefficient": Key("diode_emission_coefficient", float, 1.0, 1.0,
                                          _rng(0.5, 10.0)),
        "diode_series_resistance_ohm": Key("diode_series_resistance", float, 0.0, 1.0,
                                           _rng(0.0, 1e12)),
        "storage_capacitance_uF": Key("storage_capacitance", float, 10.0, 1e-6,
                                      _rng(1e-6, 1e12, why="1 pF to 1 MF")),
        # 0: no leakage resistor across the store
        "storage_leakage_ohm": Key("storage_leakage", float, 0.0, 1.0, _rng(0.0, 1e30)),
        "pmic": Key("pmic", str, "none", None, _choice("none", "uvlo")),
        "uvlo_rising_V": Key("uvlo_rising", float, 5.05, 1.0, _rng(1e-3, 1e6)),
        "uvlo_falling_V": Key("uvlo_falling", float, 4.04, 1.0, _rng(1e-3, 1e6)),
        "pmic_output_V": Key("pmic_output", float, 3.3, 1.0, _rng(1e-3, 1e6)),
        "pmic_load_ohm": Key("pmic_load", float, 1e5, 1.0, _rng(1e-3, 1e18, why="1 mohm to 1 Eohm")),
        "pmic_efficiency": Key("pmic_efficiency", float, 0.9, 1.0, _rng(0.0, 1.0, lo_open=True)),
        "pmic_quiescent_current_A": Key("pmic_quiescent_current", float, 450e-9, 1.0,
                                        _rng(0.0, 1.0)),
        "pmic_shunt_V": Key("pmic_shunt", float, 20.0, 1.0, _rng(1e-3, 1e6)),
    },
    # cells that each run their own dynamics (cells = 0: no array; then [device] cells
    # identical copies). Spreads are full widths of uniform draws (tengfield.array).
    "array": {
        "cells": Key("cells", int, 0, 1, _rng(0, 10**6)),
        "connection": Key("connection", str, "parallel", None,
                          _choice("parallel", "rectified-per-cell", "rectified-parallel")),
        "initial_phase_spread_deg": Key("phase_spread", float, 0.0, _DEG, _rng(0.0, 360.0)),
        "restitution_spread": Key("restitution_spread", float, 0.0, 1.0, _rng(0.0, 1.0)),
        "initial_velocity_spread_m_per_s": Key("velocity_spread", float, 0.0, 1.0,
                                               _rng(0.0, 100.0)),
        "seed": Key("seed", int, 0, 1, _rng(0, 2**32 - 1)),
    },
    # air breakdown (issue #23; tengfield.air_breakdown, tengfield.paschen): Paschen constants
    # of air (Raizer 1991, Table 4.1) and the pressure. They change the breakdown check
    # made from the surrogate's lines, not the field solve.
    "breakdown": {
        "pressure_kPa": Key("pressure", float, 101.325, 1e3, _rng(0.0, 1e4, lo_open=True)),
        "paschen_A_per_Pa_m": Key("paschen_A", float, 11.25, 1.0, _rng(0.0, 1e4, lo_open=True)),
        "paschen_B_V_per_Pa_m": Key("paschen_B", float, 273.75, 1.0, _rng(0.0, 1e6, lo_open=True)),
        # secondary-emission coefficient γ of the cathode (the charged PTFE; issue #38:
        # called secondary_emission before, RENAMED_KEYS) and the range the band's edges
        # take it over (10^-4 ... 0.1: what is reported; docs/breakdown.md)
        "gamma": Key("gamma", float, 0.01, 1.0, _rng(0.0, 1.0, lo_open=True)),
        "gamma_range": Key("gamma_range", tuple, (1e-4, 0.1), 1.0, _rng(0.0, 1.0, lo_open=True)),
        # which breakdown curve: the Townsend formula (A, B, γ) or Dakin's measured air data
        "paschen": Key("paschen", str, "townsend", None, _choice("townsend", "empirical")),
        # the seed-limited estimate (issue #38): natural volume ionisation S_v (cosmic rays
        # and radon, ~10 pairs cm^-3 s^-1), small negative ions in air n_ion (10^2-10^3
        # cm^-3), and the breakdown rate that defines the estimate
        "seed_rate_per_cm3_s": Key("seed_rate", float, 10.0, 1e6, _rng(0.0, 1e12)),
        "ion_density_per_cm3": Key("ion_density", float, 500.0, 1e6, _rng(0.0, 1e12)),
        "breakdowns_per_s": Key("breakdowns_per_s", float, 1.0, 1.0,
                                _rng(0.0, 1e9, lo_open=True)),
    },
    # the ball's charge (issue #52; tengfield.source, docs/charge.md): "constant" is
    # [device]'s SURFACE_CHARGE_KEY (a number, or "breakdown": its air-breakdown
    # limit); "breakdown" the same as that key = "breakdown"; "contact"
    # makes it impact by impact (Hertz's area at each impact's speed with [contact]'s
    # moduli, the condenser law toward equilibrium_uC_per_m2, leakage, the air-breakdown
    # cap of discharge). Not field keys: the field is linear in the ball's charge.
    "charge": {
        "model": Key("model", str, "constant", None, _choice("constant", "breakdown", "contact")),
        "equilibrium_uC_per_m2": Key("equilibrium", float, -113.0, 1e-6, _rng(-1e4, 1e4)),
        "efficiency": Key("efficiency", float, 1.0, 1.0, _rng(0.0, 1.0, lo_open=True)),
        "initial_uC_per_m2": Key("initial", float, 0.0, 1e-6, _rng(-1e4, 1e4)),
        "leakage_time_s": Key("leakage_time", float, 0.0, 1.0,
                              _rng(0.0, 1e12, why="0: no leakage")),
        "discharge": Key("discharge", str, "estimate", None,
                         _choice("estimate", "lower", "upper", "static", "none")),
        # tengfield.humidity: an assumed law on sigma_eq, tau and Paschen's B (0: dry air,
        # the constants as given)
        "relative_humidity_percent": Key("relative_humidity", float, 0.0, 0.01,
                                         _rng(0.0, 100.0, why="0: dry air, the given "
                                              "constants")),
        # what the electrical stage covers (tengfield.contact_run.electrical_window): the
        # last settle_periods + window_periods periods ("steady"), the whole run from the
        # uncharged start ("start-up"), or "auto": "start-up" where a rectifier fills a
        # store (its charging is the run), "steady" otherwise
        "waveforms": Key("waveforms", str, "auto", None, _choice("auto", "steady", "start-up")),
        "window_periods": Key("window_periods", int, 50, 1, _rng(1, 10**7)),
    },
    # the bench's instrument (issue #39; tengfield.electrical.instrument, docs/outputs.md):
    # what an electrometer or a scope records. Optional: without the section nothing of a
    # run changes. 0 means "none" for each key (no input resistance: infinite, as an
    # electrometer's charge mode; no bandwidth limit; an instantaneous reading; a reading
    # at every output sample of the run).
    "instrument": {
        "capacitance_pF": Key("capacitance", float, 0.0, 1e-12, _rng(0.0, 1e9)),
        "input_resistance_ohm": Key("input_resistance", float, 0.0, 1.0,
                                    _rng(0.0, 1e30, why="0: infinite (charge mode)")),
        "bandwidth_hz": Key("bandwidth", float, 0.0, 1.0, _rng(0.0, 1e12, why="0: unlimited")),
        "aperture_s": Key("aperture", float, 0.0, 1.0, _rng(0.0, 1e4, why="0: instantaneous")),
        "sample_rate_hz": Key("sample_rate", float, 0.0, 1.0,
                              _rng(0.0, 1e12, why="0: a reading at every output sample")),
    },
    # measured values to compare the run with (tengfield run: summary.json ->
    # measured_comparison, the terminal's table). 0 (the default): not given. Which tool
    # quantity each is compared with: tengfield.quantities.MEASURED (docs/outputs.md).
    "reference": {
        "V_pp_V": Key("V_pp", float, 0.0, 1.0, _MEASURED),
        "V_peak_V": Key("V_peak", float, 0.0, 1.0, _MEASURED),
        "Q_pp_nC": Key("Q_pp", float, 0.0, 1e-9, _MEASURED),
        "Q_peak_nC": Key("Q_peak", float, 0.0, 1e-9, _MEASURED),
        "I_pp_uA": Key("I_pp", float, 0.0, 1e-6, _MEASURED),
        "I_peak_uA": Key("I_peak", float, 0.0, 1e-6, _MEASURED),
        "P_mean_uW": Key("P_mean", float, 0.0, 1e-6, _MEASURED),
    },
}

#: Field-relevant inputs (the ``field=True`` keys): a change in any of these
#: invalidates a cached surrogate.
FIELD_KEYS: dict[str, list[str]] = {
    sec: [key for key, spec in keys.items() if spec.field]
    for sec, keys in SCHEMA.items() if any(spec.field for spec in keys.values())}

#: Renamed keys: (section, old name) -> new name. The old name is read for one release,
#: with one warning line saying what to write ([initial] gap_mm keeps its name: it is
#: the ball's gap, the stroke was the [device] gap_mm).
RENAMED_KEYS = {("device", "gap_mm"): "stroke_mm",
                ("breakdown", "secondary_emission"): "gamma"}
#: The name a renamed field key has in the surrogate cache hash (its name when the cache
#: was first keyed): renaming a key never invalidates a cached surrogate.
HASH_NAMES = {("device", "stroke_mm"): "gap_mm"}

#: Keys that also accept the string "auto", resolved to a number at load.
AUTO_KEYS = {("field", "domain_radius_mm")}
#: the stand-in sigma [uC/m^2] of SURFACE_CHARGE_KEY = "breakdown" before sigma_max is known
BREAKDOWN_PLACEHOLDER_UC = -1.0
#: keys that also take one keyword: (keyword, the number it stands for at load)
KEYWORD_VALUES = {("device", SURFACE_CHARGE_KEY): ("breakdown", BREAKDOWN_PLACEHOLDER_UC)}
#: keys of [excitation] that hold one entry per component with kind = "harmonics"
HARMONIC_KEYS = ("frequency_hz", "amplitude_mm", "acceleration_m_per_s2", "phase_deg")
#: Sections passed through unvalidated to ``scene.raw`` (each is validated by
#: the package that reads it: ``[fit]`` by :mod:`tengfield.fit`, ``[design]`` by
#: :mod:`tengfield.design_study`, ``[uncertainty]`` by :mod:`tengfield.uncertainty_study`).
PASSTHROUGH_SECTIONS = ("fit", "design", "uncertainty")


# ---------------------------------------------------------------------------
def suggest(word: str, options) -> str:
    """`` (did you mean 'x'?)`` for the closest of ``options``, or ``""``."""
    close = difflib.get_close_matches(str(word), list(options), n=1, cutoff=0.6)
    return f" (did you mean {close[0]!r}?)" if close else ""


def fmt_range(c) -> str:
    _, lo, hi, lo_open, hi_open = c[:5]
    left = "(" if lo_open else "["
    right = ")" if hi_open else "]"
    why = c[5] if len(c) > 5 and c[5] else ""
    def bound(x):   # an integer bound exactly (a seed's 4294967295, not 4.29497e+09)
        return str(x) if isinstance(x, int) and not isinstance(x, bool) else f"{x:g}"
    return f"{left}{bound(lo)}, {bound(hi)}{right}" + (f" ({why})" if why else "")


def show(value) -> str:
    """A value for a message: repr, TOML dates as written, long integers shortened."""
    if isinstance(value, (datetime.date, datetime.time)):
        return f"{value.isoformat()} (a TOML date/time)"
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) >= 10**30:
        digits = len(str(abs(value))) if abs(value) < 10**4000 else "> 4000"
        return f"an integer of {digits} digits"
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def renamed_section(sec: str, values: dict) -> dict:
    """``values`` of section ``sec`` with renamed keys under their new names (a copy when
    one was renamed; the caller refuses a section that holds both names)."""
    if not isinstance(values, dict) or not any((sec, k) in RENAMED_KEYS for k in values):
        return values
    return {RENAMED_KEYS.get((sec, k), k): v for k, v in values.items()}


def update_section(data: dict, sec: str, values: dict) -> None:
    """``data[sec].update(values)`` with a renamed key written under its new name,
    replacing the value under either name (``data`` holds file-level sections)."""
    target = data.setdefault(sec, {})
    for key, value in values.items():
        new = RENAMED_KEYS.get((sec, key), key)
        for (rsec, old), renamed in RENAMED_KEYS.items():
            if rsec == sec and renamed == new:
                target.pop(old, None)
        target[new] = value


#: Sections that a scene without them does not hold at all (``to_dict``, the written
#: scenes and the provenance hashes stay those of a scene written before them)
OPTIONAL_SECTIONS = ("instrument",)
#: (old section, old key) -> (new section, new key): a key that moved to another section,
#: read for one release with one warning (the value is used as the new key's)
MOVED_KEYS = {("circuit", "parallel_capacitance_pF"): ("instrument", "capacitance_pF")}


def with_defaults(raw: dict) -> dict:
    """File-level values of every key of every section (defaults filled in; a renamed key
    under its new name; an optional section only when given)."""
    full = {}
    for sec, keys in SCHEMA.items():
        if sec in OPTIONAL_SECTIONS and sec not in raw:
            continue
        given = renamed_section(sec, raw.get(sec, {}))
        # a deprecated key only where the scene gives it: a printed scene loads back
        # (issue 54 item 7: [instrument] capacitance_pF beside the old key's default)
        full[sec] = {k: given.get(k, spec.default) for k, spec in keys.items()
                     if (sec, k) not in DEPRECATED_KEYS or k in given}
    return full


#: keys still read under a newer spelling elsewhere (a warning says which): left out of a
#: scene printed with its defaults unless the scene gives them
DEPRECATED_KEYS = frozenset({("circuit", "parallel_capacitance_pF")})


def convert(sec: str, key: str, value, spec: Key):
    """A file-level value checked and turned into SI (None for "auto"); a bad one
    raises a one-line SceneError naming the key, the value and the allowed range."""
    attr, typ, default, factor, constraint = spec[:5]
    where = f"[{sec}] {key}"
    keyword = KEYWORD_VALUES.get((sec, key))
    if keyword and isinstance(value, str):
        if value != keyword[0]:
            raise SceneError(f"{where} = {value!r}: expected a number or {keyword[0]!r}"
                             + suggest(value, [keyword[0]]))
        value = keyword[1]
    if (sec, key) in AUTO_KEYS and isinstance(value, str):
        if value != "auto":
            raise SceneError(f"{where} = {show(value)}: expected a number or 'auto'")
        return None   # resolved when the scene is built
    if typ is str:
        if not isinstance(value, str):
            raise SceneError(f"{where} = {show(value)}: expected a string")
        if constraint and constraint[0] == "choice" and value not in constraint[1]:
            allowed = ", ".join(repr(o) for o in constraint[1])
            raise SceneError(f"{where} = {show(value)} is not allowed: choose one of {allowed}"
                             + suggest(value, constraint[1]))
        return value
    if typ is tuple:
        if not isinstance(value, (list, tuple)) or isinstance(value, str):
            raise SceneError(f"{where} = {value!r}: expected a list of numbers, e.g. [20.0, 200.0]")
        if len(value) > MAX_HARMONICS:
            raise SceneError(f"{where}: {len(value)} entries; allowed at most {MAX_HARMONICS}")
        return tuple(convert_entries(sec, key, value, Key(attr, float, None, factor, constraint)))
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        hint = (" (a list is allowed only with [excitation] kind = 'harmonics')"
                if isinstance(value, list) and sec == "excitation" and key in HARMONIC_KEYS else "")
        raise SceneError(f"{where} = {show(value)}: expected a number{hint}")
    if typ is int:
        if isinstance(value, float) and not value.is_integer():
            raise SceneError(f"{where} = {value!r}: expected a whole number")
        value = int(value)
    elif isinstance(value, int):
        try:   # a TOML integer beyond the doubles (1e309 written out) is out of range
            value = float(value)
        except OverflowError:
            raise SceneError(f"{where} = {show(value)} is out of range: allowed "
                             f"{fmt_range(constraint)}") from None
    if isinstance(value, float) and not math.isfinite(value):
        raise SceneError(f"{where} = {value!r} is not finite: allowed range {fmt_range(constraint)}")
    if constraint and constraint[0] == "range":
        _, lo, hi, lo_open, hi_open = constraint[:5]
        bad = (value < lo or value > hi or (lo_open and value == lo) or (hi_open and value == hi))
        if bad:
            raise SceneError(f"{where} = {show(value)} is out of range: allowed "
                             f"{fmt_range(constraint)}")
    return value * factor if typ is float else value


def convert_entries(sec: str, key: str, values, spec) -> list:
    """:func:`convert` of each entry of a list key; a bad entry's message shows the whole
    list and the entry's position ("band_hz = [0.0, 10.0]: entry 1 = 0.0 is out of range")."""
    out = []
    for i, v in enumerate(values):
        try:
            out.append(convert(sec, key, v, spec))
        except SceneError as exc:
            text, prefix = str(exc), f"[{sec}] {key} = "
            detail = text[len(prefix):] if text.startswith(prefix) else text
            raise SceneError(f"{prefix}{show(list(values))}: entry {i + 1} = {detail}") from None
    return out


def check_attribute(sec: str, key: str, spec: Key, value, owner: str) -> None:
    """An SI value of a scene dataclass built from Python (``owner``, e.g. "Device"),
    checked against its key: SceneError naming the attribute, the key in file units and
    the allowed range. Bounds are compared in SI (``bound x factor``, as :func:`convert`
    scales a file value), so every value :func:`convert` returns passes."""
    def where() -> str:   # only for a message: a valid value is checked without it
        return f"{owner}.{spec.attr} = {show(value)}"

    if spec.type is str:
        if not isinstance(value, str):
            raise SceneError(f"{where()}: expected a string ([{sec}] {key})")
        if spec.check and value not in spec.check[1]:
            allowed = ", ".join(repr(o) for o in spec.check[1])
            raise SceneError(f"{where()} ([{sec}] {key}) is not allowed: choose one of {allowed}"
                             + suggest(value, spec.check[1]))
        return
    items = value if spec.type is tuple else (value,)
    if spec.type is tuple and not isinstance(value, tuple):
        raise SceneError(f"{where()}: expected a tuple of numbers ([{sec}] {key})")
    for x in items:
        number = Integral if spec.type is int else Real
        if isinstance(x, bool) or not isinstance(x, number):
            kind = "a whole number" if spec.type is int else "a number"
            raise SceneError(f"{where()}: expected {kind} ([{sec}] {key})")
        if not math.isfinite(x):
            raise SceneError(f"{where()} is not finite ([{sec}] {key}: allowed "
                             f"{fmt_range(spec.check)})")
        _, lo, hi, lo_open, hi_open = spec.check[:5]
        f = spec.factor if spec.type is not int else 1
        lo, hi = lo * f, hi * f
        if x < lo or x > hi or (lo_open and x == lo) or (hi_open and x == hi):
            raise SceneError(f"{where()} is out of range: [{sec}] {key} = {x / f:g} is allowed "
                             f"{fmt_range(spec.check)}")


def check_section(sec: str, obj, owner: str) -> None:
    """Every attribute of the dataclass ``obj`` that is a key of section ``sec``."""
    for key, spec in SCHEMA[sec].items():
        check_attribute(sec, key, spec, getattr(obj, spec.attr), owner)


def harmonic_components(data: dict) -> tuple[dict, tuple]:
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
        return convert_entries("excitation", key, items, spec[key])

    freqs = entries("frequency_hz")
    if freqs is None:
        raise SceneError("[excitation] kind = 'harmonics' needs frequency_hz = [f1, f2, ...]")
    amps = entries("amplitude_mm")
    accs = entries("acceleration_m_per_s2")
    if (amps is None) == (accs is None):
        raise SceneError("[excitation] kind = 'harmonics' needs exactly one of amplitude_mm = "
                         "[...] and acceleration_m_per_s2 = [...], one entry per frequency")
    phases = entries("phase_deg") or [0.0] * len(freqs)
    # a single number (not a list) applies to every component
    if amps is not None and not isinstance(exc["amplitude_mm"], list):
        amps = amps * len(freqs)
    if accs is not None and not isinstance(exc["acceleration_m_per_s2"], list):
        accs = accs * len(freqs)
    if "phase_deg" in exc and not isinstance(exc["phase_deg"], list):
        phases = phases * len(freqs)
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


def renamed(data: dict, source: str, warn: bool) -> dict:
    """``data`` with renamed keys under their new names (a copy if any was renamed); a
    section with both names is refused, an old name warned about once."""
    out = data
    for (sec, old), new in RENAMED_KEYS.items():
        section = data.get(sec)
        if not isinstance(section, dict) or old not in section:
            continue
        if new in section:
            raise SceneError(f"{source}: [{sec}] {old} and {new} are the same key ({old} is "
                             f"its old name): give {new} only")
        if warn and _launched_rank() == 0:   # under mpirun: one line, not one per rank
            warnings.warn(f"{source}: [{sec}] {old} is now called {new}: write "
                          f"{new} = {show(section[old])} ({old} is read until the "
                          f"next release)", FutureWarning, stacklevel=4)
        if out is data:
            out = dict(data)
        out[sec] = renamed_section(sec, section)
    return out
