"""``tengfield info``: versions to paste into a bug report."""
from __future__ import annotations

import importlib
import os
import platform
import subprocess
from pathlib import Path


def package_root() -> Path:
    """The directory two levels above the package (a checkout's root: src/tengfield)."""
    return Path(__file__).resolve().parents[3]


def git_commit() -> str:
    """The checkout's commit (12 hex digits) and ", modified" when tracked files differ
    from it; "not a git checkout" for an installed package (or without git)."""
    root = package_root()

    def git(*args) -> str | None:
        try:
            proc = subprocess.run(["git", "-C", str(root), *args], capture_output=True,
                                  text=True, timeout=10)
        except (OSError, subprocess.SubprocessError):
            return None
        return proc.stdout.strip() if proc.returncode == 0 else None

    top = git("rev-parse", "--show-toplevel")
    if not top or Path(top).resolve() != root or not (root / "src" / "tengfield").is_dir():
        return "not a git checkout"
    head = git("rev-parse", "HEAD")
    if not head:
        return "not a git checkout"
    changed = git("status", "--porcelain", "--untracked-files=no")
    return head[:12] + (", modified (uncommitted changes)" if changed else "")


def blas_libraries() -> str:
    """The BLAS libraries this process has loaded (numpy's; PETSc's, which CHOLMOD and
    MUMPS run on): each that threadpoolctl knows as ``api version, N thread(s) (file)``,
    any other ``libblas`` by its file (the reference BLAS: the factorisations ~8 %
    slower end to end, docs/field.md)."""
    parts, known = [], set()
    try:
        from threadpoolctl import threadpool_info
        for lib in threadpool_info():
            if lib.get("user_api") != "blas":
                continue
            path = os.path.realpath(lib["filepath"])
            known.add(os.path.dirname(path))
            threads = lib.get("num_threads")
            parts.append(f"{lib.get('internal_api')} {lib.get('version')}, {threads} "
                         f"thread{'s' if threads != 1 else ''} ({path})")
    except Exception:  # noqa: BLE001 - report, never fail
        pass
    try:
        with open("/proc/self/maps") as maps:
            mapped = {line.split()[-1] for line in maps if "/" in line}
    except OSError:
        mapped = set()
    for path in sorted(mapped):
        name = os.path.basename(path)
        if name.startswith("libblas.so") and os.path.dirname(os.path.realpath(path)) not in known:
            parts.append(f"{'reference BLAS' if '/blas/' in path else 'other'} ({path})")
    return "; ".join(parts) or "none loaded"


def versions() -> dict[str, str]:
    """Versions of tengfield and of every library it may use ('missing' if absent)."""
    from .. import __version__

    out = {"tengfield": __version__, "git commit": git_commit(),
           "python": platform.python_version(),
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
    out["BLAS"] = blas_libraries()
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
