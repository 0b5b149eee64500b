"""Surrogate of the terminal quantities against ball position (DESIGN §4).

Field solves (:func:`tengfield.field.solve_position`) at sampled gaps
``z ∈ [0, Δh]`` give per position the Maxwell capacitance matrix and the
induced charges; cubic splines through the derived ``Q_SC(z)`` and ``C_T(z)``
give ``V_OC`` and exact derivatives. The package is split by job:

* :mod:`.sampling`: nested Chebyshev–Lobatto positions, mirror symmetry;
* :mod:`.table`: :class:`SurrogateTable`, :class:`TerminalCurves`, the
  held-out error estimate;
* :mod:`.refinement`: :func:`precompute` (adaptive refinement, task farm);
* :mod:`.store`: HDF5 file (checksums, provenance) and the cache
  (:func:`obtain_table`).
"""
from __future__ import annotations

from .refinement import FIELD_ERROR_MODES, error_sample_positions, precompute
from .sampling import (FEWEST_POSITIONS, INITIAL_LEVEL, INITIAL_POSITIONS, MAX_POSITIONS,
                       contact_first_order, is_lobatto_count, is_mirror_symmetric,
                       lobatto_positions, mirrored, refinement_positions)
from .cache import (CacheOutcome, cache_path, default_cache_dir, load_cached, obtain_table,
                    store_in_cache)
from .provenance import FORMAT_VERSION, provenance, solver_fingerprint
from .store import _import_h5py, check_table, read_table, write_table
from .table import (SurrogateError, SurrogateTable, TerminalCurves, held_out_error,
                    table_from_results, terminal_samples)

__all__ = [
    "FIELD_ERROR_MODES", "FEWEST_POSITIONS", "FORMAT_VERSION", "INITIAL_LEVEL",
    "INITIAL_POSITIONS", "MAX_POSITIONS", "CacheOutcome", "SurrogateError", "SurrogateTable",
    "TerminalCurves", "cache_path", "check_table", "contact_first_order", "default_cache_dir",
    "error_sample_positions", "held_out_error", "is_lobatto_count", "is_mirror_symmetric",
    "load_cached", "lobatto_positions", "mirrored", "obtain_table", "precompute", "provenance",
    "read_table", "refinement_positions", "solver_fingerprint", "store_in_cache",
    "table_from_results", "terminal_samples", "write_table",
]


def __getattr__(name: str):
    """``tengfield.surrogate.radial`` (the (z, r) surrogate) is imported on first use."""
    if name == "radial":
        import importlib
        return importlib.import_module(f"{__name__}.radial")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
