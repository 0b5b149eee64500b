"""The one place that knows the dolfinx API (supports dolfinx 0.5.2, Debian bookworm).

Both field solvers (axisymmetric and 3D) call dolfinx only through these
functions, so moving to a newer dolfinx touches this file alone. Importing
this module imports dolfinx, petsc4py and ufl: import it lazily.

PETSc conventions: every KSP gets its own options prefix (pass a unique
``prefix``) with ``ksp_error_if_not_converged``; matrices are assembled with
ε0 scaled out (ε0 inside made PETSc's LU zero-pivot test return NaN).
"""
from __future__ import annotations

import itertools

import numpy as np

import dolfinx
import dolfinx.fem.petsc
import ufl
from dolfinx import fem
from dolfinx.io import XDMFFile, gmshio
from petsc4py import PETSc

SUPPORTED_DOLFINX = "0.5.2"

_counter = itertools.count()


def check_version() -> None:
    """Warn-free guard: raise if the installed dolfinx is not the supported one."""
    if not dolfinx.__version__.startswith(SUPPORTED_DOLFINX.rsplit(".", 1)[0]):
        raise RuntimeError(f"tengfield.field supports dolfinx {SUPPORTED_DOLFINX}, "
                           f"found {dolfinx.__version__}")


# -- mesh -------------------------------------------------------------------
def mesh_from_gmsh(model, comm, *, rank: int = 0, gdim: int):
    """(mesh, cell_tags, facet_tags) from the current gmsh model (physical groups become tags).

    Only entities inside a physical group of the top dimension are kept; do not
    define point physical groups (they confuse gmshio in 0.5.2)."""
    return gmshio.model_to_mesh(model, comm, rank, gdim=gdim)


def num_cells(mesh) -> int:
    """Global number of cells."""
    tdim = mesh.topology.dim
    return int(mesh.topology.index_map(tdim).size_global)


# -- spaces and functions -----------------------------------------------------
def lagrange_space(mesh, degree: int):
    return fem.FunctionSpace(mesh, ("Lagrange", degree))


def cellwise_constant(mesh, cell_tags, values: dict[int, float], default: float = 1.0):
    """A DG0 function equal to ``values[tag]`` on the cells tagged ``tag``."""
    Q = fem.FunctionSpace(mesh, ("DG", 0))
    f = fem.Function(Q)
    f.x.array[:] = default
    for tag, value in values.items():
        cells = cell_tags.find(tag)
        f.x.array[cells] = value
    f.x.scatter_forward()
    return f


def function(V, values=None, name: str | None = None):
    """A finite element function on V, optionally filled from a local array."""
    f = fem.Function(V, name=name)
    if values is not None:
        f.x.array[:] = values
    return f


def num_dofs(V) -> int:
    """Global number of scalar degrees of freedom."""
    return int(V.dofmap.index_map.size_global * V.dofmap.index_map_bs)


def num_owned_dofs(V) -> int:
    return int(V.dofmap.index_map.size_local * V.dofmap.index_map_bs)


def dof_coordinates(V) -> np.ndarray:
    """Coordinates of the local dofs, shape (n, 3)."""
    return V.tabulate_dof_coordinates()


def facet_dofs(V, facet_tags, tag: int) -> np.ndarray:
    """Local dofs on the facets tagged ``tag``."""
    mesh = V.mesh
    fdim = mesh.topology.dim - 1
    mesh.topology.create_connectivity(fdim, mesh.topology.dim)
    return fem.locate_dofs_topological(V, fdim, facet_tags.find(tag))


def dirichlet_bc(V, value: float, dofs):
    return fem.dirichletbc(PETSc.ScalarType(value), dofs, V)


def measures(mesh, cell_tags, facet_tags):
    """(dx, ds, dS) carrying the cell and facet tags."""
    dx = ufl.Measure("dx", domain=mesh, subdomain_data=cell_tags)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags)
    dS = ufl.Measure("dS", domain=mesh, subdomain_data=facet_tags)
    return dx, ds, dS


# -- forms and assembly -------------------------------------------------------
def form(ufl_form):
    return fem.form(ufl_form)


def assemble_matrix(a, bcs=()):
    """PETSc matrix of the compiled bilinear form ``a`` (rows/cols of ``bcs`` get a unit diagonal)."""
    A = dolfinx.fem.petsc.assemble_matrix(a, bcs=list(bcs))
    A.assemble()
    return A


def assemble_vector(L, a=None, bcs=()):
    """PETSc vector of the compiled linear form ``L``; with ``a`` and ``bcs`` lifted and set."""
    b = dolfinx.fem.petsc.assemble_vector(L)
    if a is not None and bcs:
        dolfinx.fem.petsc.apply_lifting(b, [a], bcs=[list(bcs)])
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    if bcs:
        dolfinx.fem.petsc.set_bc(b, list(bcs))
    return b


def assemble_scalar(M, comm) -> float:
    """Global value of the compiled functional ``M``."""
    from mpi4py import MPI
    return comm.allreduce(fem.assemble_scalar(M), op=MPI.SUM)


def matrix_to_csr(A):
    """(indptr, indices, data) of a serial PETSc AIJ matrix."""
    return A.getValuesCSR()


def matrix_from_csr(comm, shape, indptr, indices, data):
    M = PETSc.Mat().createAIJ(size=shape, csr=(indptr.astype(PETSc.IntType),
                                               indices.astype(PETSc.IntType), data), comm=comm)
    M.assemble()
    return M


def vector(comm, values):
    v = PETSc.Vec().createWithArray(np.ascontiguousarray(values, dtype=PETSc.ScalarType),
                                    comm=comm)
    return v


# -- linear solvers -----------------------------------------------------------
def unique_prefix(stem: str) -> str:
    """A PETSc options prefix no other solve in this process uses."""
    return f"tengfield_{stem}_{next(_counter)}_"


def create_ksp(comm, A, *, prefix: str, kind: str = "direct", rtol: float = 1e-12):
    """A KSP on operator ``A`` under options prefix ``prefix``.

    kind = "direct": LU factorisation with MUMPS (factored once at setUp, then
    reused for every right-hand side); kind = "cg-amg": CG preconditioned by
    hypre BoomerAMG (set up once). ``ksp_error_if_not_converged`` is on.
    """
    opts = PETSc.Options()
    if kind == "direct":
        opts[f"{prefix}ksp_type"] = "preonly"
        opts[f"{prefix}pc_type"] = "lu"
        opts[f"{prefix}pc_factor_mat_solver_type"] = "mumps"
    elif kind == "cg-amg":
        opts[f"{prefix}ksp_type"] = "cg"
        opts[f"{prefix}pc_type"] = "hypre"
        opts[f"{prefix}pc_hypre_type"] = "boomeramg"
        opts[f"{prefix}ksp_rtol"] = rtol
        opts[f"{prefix}ksp_atol"] = 0.0
        opts[f"{prefix}ksp_max_it"] = 2000
    else:
        raise ValueError(f"kind = {kind!r}: choose 'direct' or 'cg-amg'")
    opts[f"{prefix}ksp_error_if_not_converged"] = True
    ksp = PETSc.KSP().create(comm)
    ksp.setOptionsPrefix(prefix)
    ksp.setOperators(A)
    ksp.setFromOptions()
    ksp.setUp()
    return ksp


def clear_options(prefix: str) -> None:
    """Remove the options set under ``prefix`` (keeps the global options table small)."""
    opts = PETSc.Options()
    for key in list(opts.getAll()):
        if key.startswith(prefix):
            opts.delValue(key)


def solve(ksp, b):
    """x with A x = b for the KSP's (already factored / preconditioned) operator."""
    x = b.duplicate()
    ksp.solve(b, x)
    return x


# -- output ---------------------------------------------------------------------
def write_xdmf(path, mesh, functions, comm) -> None:
    """Mesh and functions to XDMF/HDF5 for ParaView (functions must live on a
    Lagrange space of the mesh's geometry degree, or P1)."""
    with XDMFFile(comm, str(path), "w") as xdmf:
        xdmf.write_mesh(mesh)
        for f in functions:
            xdmf.write_function(f)


def interpolate(V, f):
    """Interpolate the function ``f`` (or a callable x -> values) into V."""
    g = fem.Function(V, name=getattr(f, "name", None))
    g.interpolate(f)
    return g


def point_values(V, values, points) -> np.ndarray:
    """Values of the dof vector ``values`` on V at ``points`` (shape (n, 3)), serial."""
    from dolfinx import geometry

    mesh = V.mesh
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    tree = geometry.BoundingBoxTree(mesh, mesh.topology.dim)
    candidates = geometry.compute_collisions(tree, points)
    colliding = geometry.compute_colliding_cells(mesh, candidates, points)
    cells = []
    for i in range(points.shape[0]):
        links = colliding.links(i)
        if len(links) == 0:
            raise ValueError(f"point {points[i]} is outside the mesh")
        cells.append(links[0])
    u = function(V, values)
    return u.eval(points, np.array(cells, dtype=np.int32)).ravel()
