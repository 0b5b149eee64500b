"""The layout of a surrogate file: which table attribute goes to which HDF5 dataset
or attribute (on the axis, and over (z, r)), with the type of each scalar. Read by
:mod:`.store`, written by :mod:`.output`."""
from __future__ import annotations


#: table attribute -> HDF5 dataset name (unit-suffixed)
ARRAYS = {"positions": "positions_m", "capacitance": "capacitance_F",
          "induced_charge": "induced_charge_C", "dofs": "dofs", "cells": "cells",
          "wall_time": "wall_time_s", "solve_time": "solve_time_s",
          "field_error": "field_relative_error_estimate"}
#: table attribute -> HDF5 file attribute, covered by ``scalars_sha256``
SCALARS = {"ball_charge": "ball_charge_C", "stroke": "stroke_m",
           "interpolation_error": "interpolation_error_estimate", "tolerance": "tolerance",
           "converged": "converged", "field_hash": "field_hash", "method": "method",
           "degree": "degree"}
#: table attribute -> type of its value (the scalars' checksum is of the typed values)
SCALAR_TYPES = {"ball_charge": float, "stroke": float, "interpolation_error": float,
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
_SHAPES = {"positions": (), "capacitance": (2, 2), "induced_charge": (2,), "dofs": (),
           "cells": (), "wall_time": (), "solve_time": (), "field_error": ()}

#: table attribute -> HDF5 dataset name
ARRAYS_ZR = {"positions": "positions_m", "offsets": "offsets_m",
             "capacitance": "capacitance_F", "induced_charge": "induced_charge_C",
             "dofs": "dofs", "cells": "cells", "wall_time": "wall_time_s",
             "solve_time": "solve_time_s", "field_error": "field_relative_error_estimate"}
#: table attribute -> HDF5 file attribute (covered by ``scalars_sha256``)
SCALARS_ZR = {"ball_charge": "ball_charge_C", "stroke": "stroke_m",
              "max_offset": "max_offset_m", "interpolation_error": "interpolation_error_estimate",
              "tolerance": "tolerance", "converged": "converged", "field_hash": "field_hash",
              "method": "method", "degree": "degree", "mesh_size": "mesh_size_m"}
#: table attribute -> type of its value: the 1-D surrogate's and the 3D ones
SCALAR_TYPES_ZR = {**SCALAR_TYPES, "max_offset": float, "mesh_size": float}
#: scalars written only when not at their default (a tube's file stays as it was):
#: table attribute -> (file attribute, type, default)
OPTIONAL_SCALARS_ZR = {"offset_coordinate": ("offset_coordinate", str, "radial")}


def typed_scalars(values, types: dict) -> dict:
    """``{attr: types[attr](values[attr])}``: the scalars as written, read and checksummed."""
    return {attr: kind(values[attr]) for attr, kind in types.items()}
