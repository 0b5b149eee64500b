"""Where a surrogate came from: the solver's fingerprint, the provenance record, the
cache keys and the file format versions.

:func:`solver_fingerprint` (a hash of the field solver's source) and the scene's
field hash (:meth:`tengfield.scene.Scene.field_hash`; for the (z, r) surrogate
:func:`radial_hash`, which adds the 3D settings)
decide whether a stored table may be reused; :func:`provenance` records versions,
scene text and command line with every table.
"""
from __future__ import annotations

import hashlib
import importlib.metadata
import json
import sys
import time

from .. import __version__
from .sampling import DEFAULT_DEGREE, DEFAULT_MESH_SIZE_MM, DEFAULT_TOLERANCE
from ..scene.schema import SURFACE_CHARGE_KEY

#: 2: per-array checksums (Fletcher-32 + SHA-256) and a checksum of the scalars;
#: 3: the breakdown lines' mesh check stored only where it was solved (no NaN in a file);
#: 4: per unit ball charge (``induced_fraction``, no ``ball_charge_C``)
FORMAT_VERSION = 4
#: the 1-D formats still read: 3 (charges in C at its ball charge, converted on read)
OLD_FORMAT_VERSIONS = (3,)
#: format of the (z, r) HDF5 file (2: per unit ball charge, as the 1-D format 4)
FORMAT_VERSION_ZR = 2
#: the (z, r) formats still read: 1 (charges in C at its ball charge, converted on read)
OLD_FORMAT_VERSIONS_ZR = (1,)
#: the format number in the (z, r) cache key (:func:`radial_hash`): 1, the format the key
#: was made with; a new format whose old files are converted on read keeps the key
ZR_KEY_FORMAT = 1


def solver_fingerprint() -> str:
    """SHA-256 (16 hex digits) of the field solver's source files
    (:func:`tengfield.field.solver_source_paths`: not the plotting or file-writing code).

    Part of the cache check on top of the scene's field hash, so that a
    changed solver (without a ``FIELD_SCHEMA`` bump) never reuses old solves.
    """
    from ..field import solver_source_paths

    digest = hashlib.sha256()
    for path in solver_source_paths():
        digest.update(path.name.encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


def provenance(scene, command_line: str = "") -> dict:
    """Versions, scene text and command line recorded with a surrogate."""
    versions = {"tengfield": __version__}
    for label, dist in (("dolfinx", "fenics-dolfinx"), ("petsc4py", "petsc4py"),
                        ("gmsh", "gmsh"), ("mpi4py", "mpi4py"), ("numpy", "numpy"),
                        ("scipy", "scipy")):   # h5py + HDF5: the file attribute "written_with"
        try:
            versions[label] = importlib.metadata.version(dist)
        except importlib.metadata.PackageNotFoundError:
            versions[label] = "missing"
    petsc = sys.modules.get("petsc4py.PETSc")  # only if a solve loaded it
    if petsc is not None:
        versions["PETSc"] = ".".join(str(v) for v in petsc.Sys.getVersion())
    text = scene.text or json.dumps(scene.to_dict(), indent=2, sort_keys=True)
    return {"versions": versions, "scene_text": text, "scene_source": scene.source,
            "field_inputs": scene.field_inputs(), "command_line": command_line,
            "created": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())}


def legacy_field_hash(scene) -> str:
    """The field hash an older tengfield (``FIELD_SCHEMA`` 1, σ part of the key) gave
    ``scene``: its cache file is still read (and scaled) rather than solved again."""
    inputs = scene.field_inputs()
    inputs["schema"] = 1
    inputs["device"] = {**inputs["device"],
                        SURFACE_CHARGE_KEY: scene.to_dict()["device"][
                            SURFACE_CHARGE_KEY]}
    blob = json.dumps(inputs, sort_keys=True, default=float).encode()
    return hashlib.sha256(blob).hexdigest()


def radial_hash(scene, *, mesh_size_mm: float = DEFAULT_MESH_SIZE_MM,
                degree: int = DEFAULT_DEGREE, tolerance: float = DEFAULT_TOLERANCE) -> str:
    """SHA-256 of the scene's field inputs plus the (z, r) surrogate's own settings
    (the cache key of :func:`obtain_radial_table`)."""
    inputs = {"field": scene.field_inputs(),
              "zr": {"format": ZR_KEY_FORMAT, "method": "3d",
                     "mesh_size_mm": float(mesh_size_mm), "degree": int(degree),
                     "tolerance": float(tolerance)}}
    return hashlib.sha256(json.dumps(inputs, sort_keys=True, default=float).encode()).hexdigest()
