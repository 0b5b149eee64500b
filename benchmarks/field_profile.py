"""Where the time of a field solve goes (issue #40): a cold and a warm process, axisymmetric
and 3D, split into imports, form compilation, gmsh, mesh conversion / distribution,
assembly, solve (factorisation or preconditioner set-up + substitution or iterations;
which solver, how many dofs), the rest (A P products, C and q, Python), and, for the
axisymmetric case, the whole default surrogate (the field stage of ``tengfield run``:
17 positions, 9 solved) with its fitting; beside it a bare PETSc solve of the same size
(the floor: a 5-point Laplacian with as many unknowns, factored and solved by the same
CHOLMOD Cholesky as the solver's serial direct solves, or CG + BoomerAMG for 3D).

Cold: a fresh form-compiler cache (``XDG_CACHE_HOME`` in a new directory) and a fresh
surrogate cache; warm: the same process run again on the caches the cold one filled.
Each case runs in its own process so that imports are counted.

    .venv/bin/python benchmarks/field_profile.py [--case axisymmetric|3d|all] [--repeat 3]
        [--mesh-motion remesh|move]    (shell-zr: the 10 mm shell's (z, r) solve, P2, 1.5 mm)

The machine may be shared (2 cores, other jobs): the load average is printed with
every table; whole-command figures for the README come from a process-timing tool
run from outside (medians of 3).
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PYTHON = sys.executable
#: the 3D case's mesh size [mm]: the issue's figure (~7 s, 155k dofs, P2); the scene's
#: default 0.5 mm gives 1.1M dofs in 3D (130-180 s, loaded machine)
MESH_SIZE_3D_MM = 2.0
PHASES = ("imports", "form compilation", "gmsh", "mesh conversion", "assembly",
          "solver set-up", "solve", "other")
#: the "shell-zr" case: the 10 mm shell (default scene, ``cavity_diameter_mm = 10``,
#: 7 mm ball) at the (z, r) table's default settings (P2, 1.5 mm), one off-axis position
#: (mid-stroke, half the admissible offset)
SHELL_ZR = {"shape": "spherical-shell", "cavity_diameter_mm": 10.0}


class Profile:
    """Wraps (in this process only) the functions of :mod:`tengfield.field._dolfinx` and
    the gmsh model builders: each call's wall time goes to its phase. Nested calls are
    counted once (the outermost phase wins)."""

    def __init__(self):
        self.seconds = {p: 0.0 for p in PHASES}
        self.depth = 0
        self.saved = []
        self.solver = {}

    def wrap(self, module, name, phase):
        original = getattr(module, name)
        self.saved.append((module, name, original))
        profile = self

        def wrapper(*args, **kwargs):
            if profile.depth:
                return original(*args, **kwargs)
            profile.depth += 1
            start = time.perf_counter()
            try:
                return original(*args, **kwargs)
            finally:
                profile.depth -= 1
                profile.seconds[phase] += time.perf_counter() - start
        setattr(module, name, wrapper)

    def __enter__(self):
        from tengfield.field import _dolfinx as dx, geometry_axisymmetric, solver3d
        from tengfield.field.cells import shell_model

        self.wrap(dx, "form", "form compilation")
        self.wrap(dx, "_function_space", "form compilation")
        self.wrap(dx, "mesh_from_gmsh", "mesh conversion")
        for name in ("assemble_matrix", "assemble_vector", "assemble_scalar", "matrix_from_csr",
                     "cellwise_constant"):
            self.wrap(dx, name, "assembly")
        self.wrap(geometry_axisymmetric, "build_model", "gmsh")
        self.wrap(shell_model, "build_model", "gmsh")
        self.wrap(solver3d, "build_model", "gmsh")
        original_ksp = dx.create_ksp
        profile = self

        def create_ksp(comm, A, *, kind="direct", **kw):
            profile.solver.setdefault(kind, []).append(A.getSize()[0])
            return original_ksp(comm, A, kind=kind, **kw)
        dx.create_ksp = create_ksp
        self.saved.append((dx, "create_ksp", original_ksp))
        self.wrap(dx, "create_ksp", "solver set-up")
        self.wrap(dx, "refactor", "solver set-up")
        self.wrap(dx, "solve", "solve")
        return self

    def __exit__(self, *exc):
        for module, name, original in reversed(self.saved):
            setattr(module, name, original)


def floor_seconds(unknowns: int, kind: str) -> float:
    """Wall time of a bare PETSc factor + 2 solves (kind "direct": the package of the
    solver's serial symmetric solves, ``_dolfinx.direct_solver``: CHOLMOD) or
    CG + BoomerAMG set-up + 2 solves of a Laplacian with ``unknowns`` unknowns
    (5-point stencil in 2D, 7-point in 3D): the floor of a solve of that size."""
    import numpy as np
    import scipy.sparse as sp
    from petsc4py import PETSc

    if kind == "direct":
        n = max(int(round(unknowns ** 0.5)), 2)
        one = sp.diags([-1, 2, -1], [-1, 0, 1], shape=(n, n))
        A = (sp.kron(sp.identity(n), one) + sp.kron(one, sp.identity(n))).tocsr()
    else:
        n = max(int(round(unknowns ** (1 / 3))), 2)
        one = sp.diags([-1, 2, -1], [-1, 0, 1], shape=(n, n))
        eye = sp.identity(n)
        A = (sp.kron(sp.kron(eye, eye), one) + sp.kron(sp.kron(eye, one), eye)
             + sp.kron(sp.kron(one, eye), eye)).tocsr()
    M = PETSc.Mat().createAIJ(size=A.shape, csr=(A.indptr.astype(PETSc.IntType),
                                                 A.indices.astype(PETSc.IntType), A.data),
                              comm=PETSc.COMM_SELF)
    M.assemble()
    from tengfield.field._dolfinx import direct_solver   # the solver's package (probed once)
    package = direct_solver(PETSc.COMM_SELF, symmetric=True)
    start = time.perf_counter()
    ksp = PETSc.KSP().create(PETSc.COMM_SELF)
    ksp.setOptionsPrefix("floor_")
    opts = PETSc.Options()
    if kind == "direct":
        M.setOption(PETSc.Mat.Option.SYMMETRIC, True)
        for k, v in {"ksp_type": "preonly", "pc_type": "cholesky",
                     "pc_factor_mat_solver_type": package, "mat_mumps_icntl_7": 0}.items():
            opts[f"floor_{k}"] = v
    else:
        for k, v in {"ksp_type": "cg", "pc_type": "hypre", "pc_hypre_type": "boomeramg",
                     "ksp_rtol": 1e-10}.items():
            opts[f"floor_{k}"] = v
    ksp.setOperators(M)
    ksp.setFromOptions()
    ksp.setUp()
    b, x = M.createVecLeft(), M.createVecRight()
    for seed in (1, 2):
        b.setArray(np.random.default_rng(seed).standard_normal(A.shape[0]))
        ksp.solve(b, x)
    return time.perf_counter() - start


def child(case: str) -> dict:
    """One process: import, then the case's solves, timed by phase (JSON on stdout)."""
    start = time.perf_counter()
    import tengfield.field._dolfinx  # noqa: F401 - dolfinx, petsc4py, ufl
    import gmsh  # noqa: F401
    from mpi4py import MPI

    from tengfield.scene import default_scene
    imports = time.perf_counter() - start
    scene = default_scene()
    if os.environ.get("FIELD_PROFILE_MESH_MOTION"):
        scene = scene.with_values(field={"mesh_motion": os.environ["FIELD_PROFILE_MESH_MOTION"]})
    out = {"case": case}
    with Profile() as profile:
        profile.seconds["imports"] = imports
        t0 = time.perf_counter()
        if case == "axisymmetric":
            from tengfield import surrogate
            table = surrogate.precompute(scene)
            out["positions"] = int(table.count)
            from tengfield.field import solve_position
            res = solve_position(scene, 0.5 * scene.device.stroke, comm=MPI.COMM_SELF,
                                 estimate_error=False)
        elif case == "shell-zr":
            from tengfield.field import solve_position
            from tengfield.surrogate.sampling import DEFAULT_DEGREE, DEFAULT_MESH_SIZE_MM
            scene = scene.with_values(device=SHELL_ZR)
            z = 0.5 * scene.device.stroke
            res = solve_position(scene, z, comm=MPI.COMM_SELF, method="3d",
                                 offset=0.25 * scene.device.stroke, estimate_error=False,
                                 mesh_size_mm=DEFAULT_MESH_SIZE_MM, degree=DEFAULT_DEGREE)
        else:
            from tengfield.field import solve_position
            res = solve_position(scene, 0.5 * scene.device.stroke, comm=MPI.COMM_SELF,
                                 method="3d", estimate_error=False,
                                 mesh_size_mm=MESH_SIZE_3D_MM)
        work = time.perf_counter() - t0
    named = sum(v for k, v in profile.seconds.items() if k not in ("imports", "other"))
    profile.seconds["other"] = work - named
    out.update(seconds=profile.seconds, total=imports + work, dofs=int(res.dofs),
               solvers=[f"{'CHOLMOD / MUMPS LDLT' if k == 'direct' else 'CG + BoomerAMG'} x {len(v)} "
                             f"({min(v)}-{max(v)} unknowns)" for k, v in profile.solver.items()], one_solve=res.wall_time)
    return out


def run_case(case: str, env: dict) -> dict:
    proc = subprocess.run([PYTHON, __file__, "--child", case], env=env, capture_output=True,
                          text=True, cwd=ROOT)
    if proc.returncode != 0:
        sys.exit(f"{case} failed:\n{proc.stderr[-3000:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", default="all", choices=("axisymmetric", "3d", "shell-zr", "all"))
    parser.add_argument("--repeat", type=int, default=1, help="cold/warm pairs (median)")
    parser.add_argument("--mesh-motion", default="remesh", choices=("remesh", "move"),
                        help="[field] mesh_motion of the axisymmetric surrogate")
    parser.add_argument("--child", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        print(json.dumps(child(args.child)))
        return
    cases = ("axisymmetric", "3d") if args.case == "all" else (args.case,)
    for case in cases:
        runs = {"cold": [], "warm": []}
        for _ in range(args.repeat):
            with tempfile.TemporaryDirectory() as tmp:
                env = dict(os.environ, XDG_CACHE_HOME=tmp, TENGFIELD_CACHE_DIR=f"{tmp}/surrogate",
                           PYTHONPATH=str(ROOT / "src"), MPLBACKEND="Agg",
                           FIELD_PROFILE_MESH_MOTION=args.mesh_motion)
                runs["cold"].append(run_case(case, env))
                runs["warm"].append(run_case(case, env))
        print(f"\n{case} (mesh_motion = {args.mesh_motion!r}): default scene, {runs['cold'][0]['dofs']} dofs per solve, solver "
              f"{', '.join(runs['cold'][0]['solvers'])}; load {os.getloadavg()[0]:.1f}")
        print(f"{'phase':18s} {'cold [s]':>9s} {'warm [s]':>9s}")
        for phase in PHASES:
            cold = statistics.median(r["seconds"][phase] for r in runs["cold"])
            warm = statistics.median(r["seconds"][phase] for r in runs["warm"])
            print(f"{phase:18s} {cold:9.3f} {warm:9.3f}")
        cold = statistics.median(r["total"] for r in runs["cold"])
        warm = statistics.median(r["total"] for r in runs["warm"])
        print(f"{'total':18s} {cold:9.3f} {warm:9.3f}")
        kind = "direct" if case == "axisymmetric" else "cg-amg"
        unknowns = int(runs["cold"][0]["dofs"])
        floor = floor_seconds(unknowns, kind)
        print(f"one warm solve {statistics.median(r['one_solve'] for r in runs['warm']):.3f} s; "
              f"floor (bare PETSc {kind}, {unknowns} unknowns, set-up + 2 solves): "
              f"{floor:.3f} s")


if __name__ == "__main__":
    main()
