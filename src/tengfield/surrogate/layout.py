"""The layout of a surrogate file: which table attribute goes to which HDF5 dataset
or attribute (on the axis, and over (z, r)), with the type of each scalar. Read by
:mod:`.store`, written by :mod:`.output`.

A file holds the induced fractions (``induced_fraction``: the charge per unit ball
charge, dimensionless) and no ball charge. The layout before it (1-D format 3, (z, r)
format 1: ``induced_charge_C`` [C] at the ball charge ``ball_charge_C`` [C] solved
with) is still read, converted (:data:`OLD_CHARGE_ARRAY`, :data:`OLD_BALL_CHARGE`)."""
from __future__ import annotations


#: table attribute -> HDF5 dataset name (unit-suffixed)
ARRAYS = {"positions": "positions_m", "capacitance": "capacitance_F",
          "induced_fraction": "induced_fraction", "dofs": "dofs", "cells": "cells",
          "wall_time": "wall_time_s", "solve_time": "solve_time_s",
          "field_error": "field_relative_error_estimate"}
#: table attribute -> HDF5 file attribute, covered by ``scalars_sha256``
SCALARS = {"stroke": "stroke_m",
           "interpolation_error": "interpolation_error_estimate", "tolerance": "tolerance",
           "converged": "converged", "field_hash": "field_hash", "method": "method",
           "degree": "degree"}
#: table attribute -> type of its value (the scalars' checksum is of the typed values)
SCALAR_TYPES = {"stroke": float, "interpolation_error": float,
                "tolerance": float, "converged": bool, "field_hash": str, "method": str,
                "degree": int}
#: optional arrays (table attribute -> dataset), written when present: the breakdown
#: lines' basis potentials (a file without them is still a valid surrogate)
OPTIONAL_ARRAYS = {"line_potential": "breakdown_line_potential",
                   "line_check": "breakdown_line_potential_check"}
#: the positions (indices into ``positions_m``) where the lines' mesh check was solved:
#: ``breakdown_line_potential_check`` holds only those rows, so every number in a file
#: is finite (in memory, ``SurrogateTable.line_check`` has NaN rows where it was not)
LINE_CHECK_INDEX = "breakdown_line_potential_check_index"
_SHAPES = {"positions": (), "capacitance": (2, 2), "induced_fraction": (2,), "dofs": (),
           "cells": (), "wall_time": (), "solve_time": (), "field_error": ()}

#: table attribute -> HDF5 dataset name
ARRAYS_ZR = {"positions": "positions_m", "offsets": "offsets_m",
             "capacitance": "capacitance_F", "induced_fraction": "induced_fraction",
             "dofs": "dofs", "cells": "cells", "wall_time": "wall_time_s",
             "solve_time": "solve_time_s", "field_error": "field_relative_error_estimate"}
#: table attribute -> HDF5 file attribute (covered by ``scalars_sha256``)
SCALARS_ZR = {"stroke": "stroke_m",
              "max_offset": "max_offset_m", "interpolation_error": "interpolation_error_estimate",
              "tolerance": "tolerance", "converged": "converged", "field_hash": "field_hash",
              "method": "method", "degree": "degree", "mesh_size": "mesh_size_m"}
#: table attribute -> type of its value: the 1-D surrogate's and the 3D ones
SCALAR_TYPES_ZR = {**SCALAR_TYPES, "max_offset": float, "mesh_size": float}
#: scalars written only when not at their default (a tube's file stays as it was):
#: table attribute -> (file attribute, type, default)
OPTIONAL_SCALARS_ZR = {"offset_coordinate": ("offset_coordinate", str, "radial")}


#: the old layout's charge array (table attribute -> dataset) in place of the fractions,
#: and its ball charge (attribute -> file attribute, type): the fractions are the
#: charges divided by it
OLD_CHARGE_ARRAY = {"induced_charge": "induced_charge_C"}
OLD_BALL_CHARGE = {"ball_charge": ("ball_charge_C", float)}


def old_layout(arrays: dict, scalars: dict, types: dict) -> tuple[dict, dict, dict]:
    """``(arrays, scalars, types)`` of the old layout from today's (:data:`ARRAYS`,
    :data:`SCALARS`, :data:`SCALAR_TYPES` or their (z, r) forms): the charges [C] in place
    of the fractions, and the ball charge [C] among the checksummed scalars."""
    old_arrays = {**{a: n for a, n in arrays.items() if a != "induced_fraction"},
                  **OLD_CHARGE_ARRAY}
    (attr, (name, kind)), = OLD_BALL_CHARGE.items()
    return old_arrays, {attr: name, **scalars}, {attr: kind, **types}


def typed_scalars(values, types: dict) -> dict:
    """``{attr: types[attr](values[attr])}``: the scalars as written, read and checksummed."""
    return {attr: kind(values[attr]) for attr, kind in types.items()}
