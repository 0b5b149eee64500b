"""``tengfield info``: versions to paste into a bug report."""
from __future__ import annotations

import importlib
import platform


def versions() -> dict[str, str]:
    """Versions of tengfield and of every library it may use ('missing' if absent)."""
    from .. import __version__

    out = {"tengfield": __version__, "python": platform.python_version(),
           "platform": platform.platform()}
    # pyvista before dolfinx: the reverse order breaks VTK text rendering here
    for name in ["numpy", "scipy", "matplotlib", "numba", "h5py", "pyvista", "vtk", "gmsh",
                 "dolfinx", "ufl", "basix", "petsc4py", "mpi4py"]:
        try:
            mod = importlib.import_module(name)
            out[name] = str(getattr(mod, "__version__", getattr(mod, "VERSION", "?")))
        except Exception as exc:  # noqa: BLE001 - report, never fail
            out[name] = f"missing ({type(exc).__name__})"
    try:   # the field package's dolfinx layer: which names it uses, and PETSc
        from ..field._dolfinx import describe, petsc_version
        out["field layer"] = describe()
        out["PETSc"] = petsc_version()
    except Exception:  # noqa: BLE001
        pass
    try:
        from mpi4py import MPI
        out["MPI library"] = MPI.Get_library_version().replace("\x00", "").splitlines()[0].strip()
    except Exception:  # noqa: BLE001
        pass
    return out


def register(sub) -> None:
    p = sub.add_parser("info", help="versions of tengfield and its stack (for bug reports)")
    p.set_defaults(func=_run)


def _run(args) -> int:
    for k, v in versions().items():
        print(f"{k:12s} {v}")
    return 0
