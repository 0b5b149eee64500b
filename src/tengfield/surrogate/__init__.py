"""Surrogate of the terminal quantities against ball position (DESIGN §4), on the axis
(z) and off it (z, r).

Field solves (:func:`tengfield.field.solve_position`) at sampled gaps
``z ∈ [0, Δh]`` give per position the Maxwell capacitance matrix and the
induced charges; cubic splines through the derived ``Q_SC(z)`` and ``C_T(z)``
give ``V_OC`` and exact derivatives; for an off-axis ball, 3D solves on a
(z, r) grid and tensor-product splines do the same. The package is split by
job, for both shapes alike:

* :mod:`.sampling`: nested Chebyshev–Lobatto positions and offsets, mirror
  symmetry, the sampling defaults;
* :mod:`.table`: :class:`SurrogateTable`, :class:`RadialTable` and the curves
  through them (:class:`Curves`: what every caller uses);
* :mod:`.refinement`: :func:`precompute`, :func:`precompute_radial` (adaptive
  refinement, task farm) and the accuracy checks;
* :mod:`.store`: the HDF5 files (checksums, structure checks);
* :mod:`.provenance`: solver fingerprint, provenance, cache keys, format versions;
* :mod:`.cache`: where tables live and whether one is reused
  (:func:`obtain_table`, :func:`obtain_radial_table`; rank 0 decides);
* :mod:`.offaxis`: whether a 3D trajectory leaves the axis, its r(t).
"""
from __future__ import annotations

import sys
import types

from .cache import (CacheOutcome, cache_path, default_cache_dir, load_cached,
                    obtain_radial_table, obtain_table, radial_cache_path, store_in_cache)
from .offaxis import AXIS_FRACTION, leaves_axis, radial_motion
from .provenance import (FORMAT_VERSION, FORMAT_VERSION_ZR, provenance, radial_hash,
                         solver_fingerprint)
from .refinement import (FIELD_ERROR_MODES, axis_check, error_sample_positions, held_out_error,
                         held_out_error_zr, precompute, precompute_radial,
                         radial_accuracy_problems)
from .sampling import (DEFAULT_DEGREE, DEFAULT_MESH_SIZE_MM, DEFAULT_TOLERANCE, FEWEST_POSITIONS,
                       INITIAL_LEVEL, INITIAL_OFFSETS, INITIAL_POSITIONS, MAX_OFFSETS,
                       MAX_POSITIONS, MAX_POSITIONS_ZR, contact_first_order, is_lobatto_count,
                       is_mirror_symmetric, lobatto_positions, max_offset, mirrored,
                       offset_positions, offset_refinement, refinement_positions)
from .store import (_import_h5py, check_radial_table, check_table, read_radial_table, read_table,
                    write_radial_table, write_table)
from .table import (AnchoredTerminalCurves, Curves, OffAxisCurves, OnAxisCurves, RadialTable,
                    RadialTerminalCurves, SurrogateError, SurrogateTable, TerminalCurves,
                    table_from_grid, table_from_results, terminal_grid, terminal_samples)

#: ``tengfield.surrogate.radial``: the (z, r) names under the module they were first
#: published in (now in the modules above; V_OC, Q_SC, I_SC along an off-axis
#: trajectory: :func:`tengfield.electrical.terminal_waveforms` with ``radial=``)
RADIAL_NAMES = (
    "AXIS_FRACTION", "AnchoredTerminalCurves", "DEFAULT_DEGREE", "DEFAULT_MESH_SIZE_MM",
    "DEFAULT_TOLERANCE", "FORMAT_VERSION_ZR", "INITIAL_OFFSETS", "MAX_OFFSETS",
    "MAX_POSITIONS_ZR", "RadialTable", "RadialTerminalCurves", "axis_check",
    "check_radial_table", "held_out_error_zr", "leaves_axis", "max_offset",
    "obtain_radial_table", "offset_positions", "offset_refinement", "precompute_radial",
    "radial_accuracy_problems", "radial_cache_path", "radial_hash", "radial_motion",
    "read_radial_table", "table_from_grid", "terminal_grid", "write_radial_table",
)
radial = types.ModuleType(f"{__name__}.radial", "The (z, r) surrogate (an off-axis ball).")
radial.__dict__.update({name: globals()[name] for name in RADIAL_NAMES})
sys.modules[radial.__name__] = radial

__all__ = [
    "FIELD_ERROR_MODES", "FEWEST_POSITIONS", "FORMAT_VERSION", "INITIAL_LEVEL",
    "INITIAL_POSITIONS", "MAX_POSITIONS", "CacheOutcome", "SurrogateError", "SurrogateTable",
    "TerminalCurves", "cache_path", "check_table", "contact_first_order", "default_cache_dir",
    "error_sample_positions", "held_out_error", "is_lobatto_count", "is_mirror_symmetric",
    "load_cached", "lobatto_positions", "mirrored", "obtain_table", "precompute", "provenance",
    "read_table", "refinement_positions", "solver_fingerprint", "store_in_cache",
    "table_from_results", "terminal_samples", "write_table", "Curves", "OnAxisCurves",
    "OffAxisCurves", "radial", *RADIAL_NAMES,
]
