"""The one place that knows the dolfinx API: dolfinx 0.5.2 (Debian 12) and 0.9 (Debian 13).

Every dolfinx, petsc4py, ufl and basix import of tengfield happens here;
the solvers, writers and plots call these functions (and use the ``ufl``
and ``PETSc`` modules re-exported here). The version is read once, at
import, and the names are chosen then: no version check exists anywhere
else. Importing this module imports dolfinx, petsc4py and ufl: import it
lazily.

What differs between the two releases (checked against the 0.9.0 sources):

====================  =================================  =====================================
what                  0.5.2                              0.9
====================  =================================  =====================================
function space        ``fem.FunctionSpace(mesh, el)``    ``fem.functionspace(mesh, el)``
gmsh model import     ``model_to_mesh(m, comm, r, gdim)``  same, plus a shared-facet partitioner
                                                          under MPI (``dS`` integrals)
PETSc vector of f     ``f.vector``                       ``f.x.petsc_vec``
dofmap.list           AdjacencyList (``.array``)         2D ndarray
geometry.dofmap       AdjacencyList                      2D ndarray
bounding-box tree     ``geometry.BoundingBoxTree``       ``geometry.bb_tree``
point collisions      ``geometry.compute_collisions``    ``geometry.compute_collisions_points``
VTK arrays            ``plot.create_vtk_mesh``           ``plot.vtk_mesh``
form options          ``jit_params=``                    ``jit_options=``
====================  =================================  =====================================

PETSc conventions: every KSP gets its own options prefix (pass a unique
``prefix``) with ``ksp_error_if_not_converged``; matrices are assembled with
ε0 scaled out (ε0 inside made PETSc's LU zero-pivot test return NaN).
"""
from __future__ import annotations

import contextlib
import functools
import itertools
import logging
import os
import sys
import tempfile

import numpy as np

# VTK's core library before dolfinx's: in the reverse order VTK's first std::regex (its
# text rendering, a field.png drawn in the process of a solve) aborts the process on
# Debian 12 (libstdc++ symbols bound to the ones dolfinx's libraries brought). 0.1 s;
# nothing when pyvista/VTK is not installed.
with contextlib.suppress(ImportError):
    import vtkmodules.vtkCommonCore  # noqa: F401

import dolfinx
import dolfinx.fem.petsc
import dolfinx.geometry
import dolfinx.io
import dolfinx.mesh
import dolfinx.plot
import ufl
from dolfinx import fem
from dolfinx.io import XDMFFile, gmshio
from petsc4py import PETSc

__all__ = ["PETSc", "ufl", "VERSION", "LEGACY"]

#: (major, minor) of the installed dolfinx
VERSION = tuple(int(p) for p in dolfinx.__version__.split(".")[:2])
#: True on the 0.5 line (Debian 12), False on 0.7+ (Debian 13 ships 0.9)
LEGACY = VERSION < (0, 7)
SUPPORTED = ((0, 5), (0, 9))

_counter = itertools.count()


# -- the form compiler, quiet ------------------------------------------------------
class _BelowWarning(logging.Filter):
    def filter(self, record: logging.LogRecord) -> bool:
        return record.levelno >= logging.WARNING


def jit_cache_dir():
    """The form compiler's (dolfinx/FFCx JIT) cache directory: ``$XDG_CACHE_HOME/fenics``,
    by default ``~/.cache/fenics`` (read by dolfinx when it is imported)."""
    from pathlib import Path

    import dolfinx.jit
    options = dolfinx.jit.get_parameters() if LEGACY else dolfinx.jit.get_options()
    return Path(str(options["cache_dir"])).expanduser()


def _jit_cache_message(cache, reason: str) -> str:
    return (f"the form compiler's cache (dolfinx/FFCx JIT) {cache} cannot be written "
            f"({reason}): point XDG_CACHE_HOME at a writable directory (the cache is then "
            "$XDG_CACHE_HOME/fenics; tengfield's surrogate cache moves with it unless "
            "TENGFIELD_CACHE_DIR or --cache-dir is set), e.g. XDG_CACHE_HOME=/tmp/cache")


@functools.lru_cache(maxsize=None)
def jit_cache_problem() -> str | None:
    """One line when the form compiler's cache directory cannot be created (a read-only
    ``$HOME``: dolfinx said ``Read-only file system: .../.cache``), else None. Checked
    the same way on every rank before a compile (a failure inside dolfinx's MPI compile
    is a bare RuntimeError on the other ranks). An existing cache that is read-only is
    not refused: its compiled modules are read from it."""
    cache = jit_cache_dir()
    try:
        cache.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        return _jit_cache_message(cache, f"{exc.strerror or exc}: {exc.filename or cache}")
    return None


@contextlib.contextmanager
def _cache_errors_named():
    """An OSError of the compiler on a file of its cache (a new module in a read-only
    cache) as the one line of :func:`jit_cache_problem` (a FieldError)."""
    from pathlib import Path

    try:
        yield
    except OSError as exc:
        cache = jit_cache_dir()
        name = Path(str(exc.filename)) if exc.filename else None
        if name is None or not (name == cache or cache in name.parents):
            raise
        from ..errors import FieldError
        raise FieldError(_jit_cache_message(cache, f"{exc.strerror or exc}: {name}")) from None


@contextlib.contextmanager
def quiet_compiler():
    """:func:`_quiet_output` of a compile, its cache checked first and its cache errors
    named (:func:`jit_cache_problem`: a :class:`~tengfield.errors.FieldError`)."""
    problem = jit_cache_problem()
    if problem is not None:
        from ..errors import FieldError
        raise FieldError(problem)
    with _cache_errors_named(), _quiet_output():
        yield


@contextlib.contextmanager
def _quiet_output():
    """The form compiler (ffcx -> cffi -> setuptools -> the C compiler) says nothing on
    stderr meanwhile: setuptools logs ``running build_ext`` and the compiler's command
    lines at INFO on the root logger (raising its level to INFO, with ffcx's
    ``logging.basicConfig()`` handler on stderr), and the compiler itself may write to
    file descriptor 2. Both are dropped, unless logging asks for INFO (the root logger's
    level at INFO or below before the compile, or ``TENGFIELD_VERBOSE=1``); what was
    written to descriptor 2 is passed on when the compile fails, and tengfield's own
    lines always are. The root logger's level is restored after."""
    root = logging.getLogger()
    if root.getEffectiveLevel() <= logging.INFO or \
            os.environ.get("TENGFIELD_VERBOSE", "") not in ("", "0"):
        yield
        return
    level = root.level
    quiet = _BelowWarning()
    filtered = [root, *root.handlers]
    for item in filtered:
        item.addFilter(quiet)
    try:
        sys.stderr.flush()
    except (AttributeError, OSError, ValueError):
        pass
    try:
        saved = os.dup(2)
    except OSError:    # no descriptor 2 (a daemon): nothing can reach it anyway
        saved = None
    captured = tempfile.TemporaryFile() if saved is not None else None
    failed = True
    try:
        if captured is not None:
            os.dup2(captured.fileno(), 2)
        yield
        failed = False
    finally:
        if captured is not None:
            os.dup2(saved, 2)
            os.close(saved)
            captured.seek(0)
            text = captured.read()
            captured.close()
            kept = text if failed else b"".join(
                line for line in text.splitlines(keepends=True) if line.startswith(b"tengfield: "))
            if kept:
                os.write(2, kept)
        for item in filtered:
            item.removeFilter(quiet)
        root.setLevel(level)


def _quietly(compile_function):
    @functools.wraps(compile_function)
    def call(*args, **kwargs):
        with quiet_compiler():
            return compile_function(*args, **kwargs)
    return call


# -- names chosen by version (the only version switch) ------------------------
_function_space = _quietly(fem.FunctionSpace if LEGACY else fem.functionspace)
_bb_tree = dolfinx.geometry.BoundingBoxTree if LEGACY else dolfinx.geometry.bb_tree
_collisions = (dolfinx.geometry.compute_collisions if LEGACY
               else dolfinx.geometry.compute_collisions_points)
_vtk_mesh = dolfinx.plot.create_vtk_mesh if LEGACY else dolfinx.plot.vtk_mesh
_JIT_KEY = "jit_params" if LEGACY else "jit_options"

if LEGACY:
    def _rows(adjacency, cells) -> np.ndarray:
        # one cell type: every row has the same length
        width = int(adjacency.offsets[1] - adjacency.offsets[0]) if adjacency.num_nodes else 0
        return adjacency.array.reshape(-1, max(width, 1))[cells]

    def _partition_options(comm) -> dict:
        return {}
else:
    def _rows(array, cells) -> np.ndarray:
        return np.asarray(array)[cells]

    def _partition_options(comm) -> dict:
        # interior-facet (dS) integrals need shared-facet ghosts across processes
        if comm.size == 1:
            return {"partitioner": None}
        return {"partitioner": dolfinx.mesh.create_cell_partitioner(
            dolfinx.mesh.GhostMode.shared_facet)}


def petsc_vector(f):
    """The PETSc vector holding the dofs of the Function ``f`` (shares memory)."""
    return f.vector if LEGACY else f.x.petsc_vec


def mesh_from_gmsh(model, comm, *, rank: int = 0, gdim: int):
    """(mesh, cell_tags, facet_tags) from the gmsh model on ``rank`` of ``comm``."""
    with quiet_compiler():    # the coordinate element is compiled on first use
        out = gmshio.model_to_mesh(model, comm, rank, gdim=gdim, **_partition_options(comm))
    return out[0], out[1], out[2]


def describe() -> str:
    """"dolfinx X.Y.Z (0.5 names)" or "(0.9 names)": which branch of this layer is active."""
    return f"dolfinx {dolfinx.__version__} ({'0.5' if LEGACY else '0.9'} names)"


def petsc_version() -> str:
    """The PETSc library version petsc4py runs on, "X.Y.Z"."""
    return ".".join(str(v) for v in PETSc.Sys.getVersion())


# -- mesh -------------------------------------------------------------------
def num_cells(mesh) -> int:
    """Global number of cells."""
    return int(mesh.topology.index_map(mesh.topology.dim).size_global)


def num_local_cells(mesh) -> int:
    """Cells owned by this process."""
    return int(mesh.topology.index_map(mesh.topology.dim).size_local)


def geometry_degree(mesh) -> int:
    """Polynomial degree of the mesh geometry (2 for curved meshes)."""
    return int(mesh.geometry.cmap.degree)


def cell_vertex_nodes(mesh, vertices: int = 3) -> np.ndarray:
    """(local cells, ``vertices``) rows of ``mesh.geometry.x`` holding each cell's vertices
    (3: triangles, 4: tetrahedra; a curved cell's geometry nodes list its vertices first)."""
    cells = np.arange(num_local_cells(mesh), dtype=np.int32)
    return np.ascontiguousarray(_rows(mesh.geometry.dofmap, cells)[:, :vertices])


def submesh(mesh, cells) -> object:
    """A new serial mesh of the local ``cells`` of ``mesh`` (same coordinate
    element, so the same curved geometry)."""
    from mpi4py import MPI

    rows = _rows(mesh.geometry.dofmap, np.asarray(cells, dtype=np.int32))
    used, local = np.unique(rows, return_inverse=True)
    local = local.reshape(rows.shape).astype(np.int64)
    gdim = mesh.geometry.dim
    x = np.ascontiguousarray(mesh.geometry.x[used, :gdim])
    domain = ufl.Mesh(mesh.ufl_domain().ufl_coordinate_element())
    return dolfinx.mesh.create_mesh(MPI.COMM_SELF, local, x, domain)


# -- spaces and functions -----------------------------------------------------
def lagrange_space(mesh, degree: int):
    """Continuous Lagrange space of ``degree`` on ``mesh``."""
    return _function_space(mesh, ("Lagrange", degree))


def cell_dofs(V, cells) -> np.ndarray:
    """Dofs of the local ``cells`` in V, one row per cell."""
    return _rows(V.dofmap.list, np.asarray(cells, dtype=np.int32))


def cellwise_constant(mesh, cell_tags, values: dict[int, float], default: float = 1.0,
                      name: str | None = None):
    """A DG0 function equal to ``values[tag]`` on the cells tagged ``tag``."""
    Q = _function_space(mesh, ("DG", 0))
    f = fem.Function(Q, name=name)
    f.x.array[:] = default
    for tag, value in values.items():
        cells = cell_tags.find(tag)
        f.x.array[cell_dofs(Q, cells).ravel()] = value
    f.x.scatter_forward()
    return f


def function(V, values=None, name: str | None = None):
    """A finite element function on V, optionally filled from a local array."""
    f = fem.Function(V, name=name)
    if values is not None:
        f.x.array[:] = values
    return f


def constant(mesh, value: float):
    return fem.Constant(mesh, PETSc.ScalarType(value))


def num_dofs(V) -> int:
    """Global number of scalar degrees of freedom."""
    return int(V.dofmap.index_map.size_global * V.dofmap.index_map_bs)


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


def interpolate(V, f):
    """Interpolate the Function ``f`` (or a callable x -> values) into V."""
    g = fem.Function(V, name=getattr(f, "name", None))
    g.interpolate(f)
    return g


# -- forms and assembly -------------------------------------------------------
def form(ufl_form, jit_options: dict | None = None):
    """Compiled form (``jit_options`` go to ffcx/cffi under the version's keyword)."""
    with quiet_compiler():
        if jit_options:
            return fem.form(ufl_form, **{_JIT_KEY: jit_options})
        return fem.form(ufl_form)


def assemble_matrix(a, bcs=()):
    """PETSc matrix of the compiled bilinear form ``a`` (rows/cols of ``bcs`` get a unit diagonal)."""
    A = dolfinx.fem.petsc.assemble_matrix(a, bcs=list(bcs))
    A.assemble()
    return A


def assemble_matrix_into(A, a, bcs=()) -> None:
    """Assemble the compiled bilinear form ``a`` into the existing matrix ``A`` (the same
    sparsity: a moved mesh), its entries zeroed first (``assemble_matrix``'s
    ``PETSc.Mat`` overload, the same in 0.5 and 0.9); rows/cols of ``bcs`` get a unit
    diagonal, as :func:`assemble_matrix`."""
    A.zeroEntries()
    if bcs:
        dolfinx.fem.petsc.assemble_matrix(A, a, bcs=list(bcs))
    else:
        dolfinx.fem.petsc.assemble_matrix(A, a)
    A.assemble()


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
    return float(comm.allreduce(fem.assemble_scalar(M), op=MPI.SUM))


def matrix_from_csr(comm, shape, indptr, indices, data):
    M = PETSc.Mat().createAIJ(size=shape, csr=(indptr.astype(PETSc.IntType),
                                               indices.astype(PETSc.IntType), data), comm=comm)
    M.assemble()
    return M


def vector(comm, values):
    return PETSc.Vec().createWithArray(np.ascontiguousarray(values, dtype=PETSc.ScalarType),
                                       comm=comm)


def python_matrix(comm, sizes, context):
    """A PETSc shell matrix whose ``mult(mat, x, y)`` is ``context.mult``."""
    M = PETSc.Mat().createPython(sizes, comm=comm)
    M.setPythonContext(context)
    M.setUp()
    return M


# -- linear solvers -----------------------------------------------------------
def unique_prefix(stem: str) -> str:
    """A PETSc options prefix no other solve in this process uses."""
    return f"tengfield_{stem}_{next(_counter)}_"


def create_ksp(comm, A, *, prefix: str, kind: str = "direct", rtol: float = 1e-12,
               preconditioner_matrix=None, options: dict | None = None,
               symmetric: bool = False):
    """A KSP on operator ``A`` under options prefix ``prefix``.

    kind = "direct": LU factorisation with MUMPS (factored once at setUp, then
    reused for every right-hand side); with ``symmetric=True`` (``A`` must be
    symmetric; it is marked so) a Cholesky / LDLᵀ factorisation instead: on one
    process SuiteSparse's CHOLMOD (:func:`direct_solver`), simplicial (LDLᵀ column by
    column, no supernodes: on the axisymmetric solver's 2D P2 operators of 13k-23k
    unknowns its set-up and two solves took 24-40 ms against 34-58 ms for the
    supernodal factorisation CHOLMOD chose by itself, and it factors a moved mesh's
    values ~40 % faster; its back-substitution is 3-5x faster than MUMPS', which has a
    fixed cost per solve at this size), else MUMPS LDLᵀ, on one
    process with the approximate-minimum-degree ordering (2.2-3x faster than
    MUMPS's default METIS ordering at 13k-80k dofs).
    kind = "cg-amg": CG preconditioned by hypre BoomerAMG (set up once, on
    ``preconditioner_matrix`` if given).
    ``options`` adds or overrides PETSc options (without the prefix).
    ``ksp_error_if_not_converged`` is on.
    """
    opts = PETSc.Options()
    if kind == "direct":
        values = {"ksp_type": "preonly", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps"}
        if symmetric:
            A.setOption(PETSc.Mat.Option.SYMMETRIC, True)
            values["pc_type"] = "cholesky"
            values["pc_factor_mat_solver_type"] = direct_solver(comm, symmetric=True)
            if comm.size == 1 and values["pc_factor_mat_solver_type"] == "mumps":
                values["mat_mumps_icntl_7"] = 0   # AMD ordering
            if values["pc_factor_mat_solver_type"] == "cholmod":
                values["mat_cholmod_factor"] = "simplicial"   # see above
    elif kind == "cg-amg":
        values = {"ksp_type": "cg", "pc_type": "hypre", "pc_hypre_type": "boomeramg",
                  "ksp_rtol": rtol, "ksp_atol": 0.0, "ksp_max_it": 2000}
    else:
        raise ValueError(f"kind = {kind!r}: choose 'direct' or 'cg-amg'")
    values.update(options or {})
    values["ksp_error_if_not_converged"] = True
    for key, value in values.items():
        opts[f"{prefix}{key}"] = value
    ksp = PETSc.KSP().create(comm)
    ksp.setOptionsPrefix(prefix)
    ksp.setOperators(A, A if preconditioner_matrix is None else preconditioner_matrix)
    ksp.setFromOptions()
    try:
        ksp.setUp()
    except PETSc.Error as exc:
        ksp.destroy()
        clear_options(prefix)
        from ..errors import FieldError
        raise FieldError(solver_failure(exc, kind, A.getSize()[0], symmetric,
                                        solver=values.get("pc_factor_mat_solver_type"))
                         ) from None
    return ksp


_CHOLMOD: list = []   # [bool] once probed


def direct_solver(comm, *, symmetric: bool) -> str:
    """The factorisation package of a direct solve: ``"cholmod"`` for a symmetric
    operator on one process when this PETSc has SuiteSparse (probed once on a 2 x 2
    matrix: Debian 12's and 13's do), else ``"mumps"``."""
    if not symmetric or comm.size != 1:
        return "mumps"
    if not _CHOLMOD:
        A = PETSc.Mat().createAIJ([2, 2], nnz=1, comm=PETSc.COMM_SELF)
        for i in range(2):
            A.setValue(i, i, 1.0)
        A.assemble()
        A.setOption(PETSc.Mat.Option.SYMMETRIC, True)
        ksp = PETSc.KSP().create(PETSc.COMM_SELF)
        try:
            ksp.setOperators(A, A)
            ksp.setType("preonly")
            pc = ksp.getPC()
            pc.setType("cholesky")
            pc.setFactorSolverType("cholmod")
            ksp.setUp()
            _CHOLMOD.append(True)
        except PETSc.Error:
            _CHOLMOD.append(False)
        finally:
            ksp.destroy()
            A.destroy()
    return "cholmod" if _CHOLMOD[0] else "mumps"


def factor_description(ksp) -> str:
    """PETSc's own description of the factorisation ``ksp`` holds (its factor matrix
    viewed with the ASCII info format: the package and, for CHOLMOD, its run parameters)."""
    import os
    import tempfile

    factor = ksp.getPC().getFactorMatrix()
    with tempfile.TemporaryDirectory(prefix="tengfield-factor-") as scratch:
        path = os.path.join(scratch, "factor.txt")   # PETSc's viewer writes, we read
        viewer = PETSc.Viewer().createASCII(path, comm=factor.getComm())
        viewer.pushFormat(PETSc.Viewer.Format.ASCII_INFO)
        factor.view(viewer)
        viewer.destroy()
        with open(path) as text:
            return text.read()


def refactor(ksp, K, *, kind: str = "direct", symmetric: bool = False) -> None:
    """Set ``ksp`` up again on ``K`` (the same matrix object, new values): a direct
    solver keeps its symbolic analysis (ordering) and factors the values again."""
    if symmetric:
        K.setOption(PETSc.Mat.Option.SYMMETRIC, True)
    ksp.setOperators(K, K)
    try:
        ksp.setUp()
    except PETSc.Error as exc:
        from ..errors import FieldError
        raise FieldError(solver_failure(exc, kind, K.getSize()[0], symmetric,
                                        solver=ksp.getPC().getFactorSolverType())) from None


#: MUMPS INFOG(1) codes of a failed allocation or too small a workspace (its manual, §8)
MUMPS_MEMORY_CODES = (-8, -9, -11, -13, -14, -15, -17, -19, -20, -27)


def solver_failure(exc, kind: str, unknowns: int, symmetric: bool = False,
                   solver: str | None = "mumps") -> str:
    """One line for a PETSc failure while factoring / setting up the preconditioner of a
    field solve (issue #43 item 4: MUMPS' ``INFOG(1)=-13`` was a raw traceback).
    ``solver``: the factorisation package of a direct solve."""
    import re

    text = str(exc)
    for line in (getattr(exc, "args", None) or ()):
        text += f" {line}"
    code = re.search(r"INFOG\(1\)\s*=\s*(-?\d+)", text)
    if kind != "direct":
        solver = "CG + BoomerAMG"
    elif solver == "cholmod":
        solver = "CHOLMOD Cholesky"
    else:
        solver = "MUMPS LDLT" if symmetric else "MUMPS LU"
    memory = getattr(exc, "ierr", None) == 55 or (
        code is not None and int(code.group(1)) in MUMPS_MEMORY_CODES)
    what = (f"ran out of memory (MUMPS INFOG(1) = {code.group(1)})" if code and memory
            else "ran out of memory" if memory
            else f"failed (MUMPS INFOG(1) = {code.group(1)})" if code
            else f"failed (PETSc error {getattr(exc, 'ierr', '?')})")
    return (f"the field's linear solver ({solver}, {unknowns} unknowns) {what}: coarsen "
            "[field] mesh_size_mm, lower degree, or run where more memory is free")


def release_garbage(comm) -> None:
    """Destroy the PETSc objects Python has collected on ``comm`` (collective on it: a
    mesh's own communicator, which dolfinx duplicates). petsc4py (3.18 on Debian 12,
    3.22 on 13) defers their destruction to ``garbage_cleanup``, so a process that
    solves position after position without it keeps every vector and matrix it ever
    made (measured: 1.1 MB per 13k-dof solve)."""
    PETSc.garbage_cleanup(comm)


def clear_options(prefix: str) -> None:
    """Remove the options set under ``prefix`` (keeps the global options table small)."""
    opts = PETSc.Options()
    for key in list(opts.getAll()):
        if key.startswith(prefix):
            opts.delValue(key)


def solve(ksp, b, x=None):
    """x with A x = b for the KSP's (already factored / preconditioned) operator."""
    x = b.duplicate() if x is None else x
    ksp.solve(b, x)
    return x


# -- points, output, plots ------------------------------------------------------
def colliding_cells(mesh, points) -> np.ndarray:
    """For each point (shape (n, 3)) one local cell containing it, or -1."""
    points = np.ascontiguousarray(np.asarray(points, dtype=float).reshape(-1, 3))
    tree = _bb_tree(mesh, mesh.topology.dim)
    candidates = _collisions(tree, points)
    colliding = dolfinx.geometry.compute_colliding_cells(mesh, candidates, points)
    out = np.full(points.shape[0], -1, dtype=np.int32)
    for i in range(points.shape[0]):
        links = colliding.links(i)
        if len(links):
            out[i] = links[0]
    return out


def point_values(V, values, points) -> np.ndarray:
    """Values of the dof vector ``values`` on V at ``points`` (shape (n, 3)), serial."""
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    cells = colliding_cells(V.mesh, points)
    if np.any(cells < 0):
        raise ValueError(f"point {points[np.argmin(cells)]} is outside the mesh")
    return function(V, values).eval(points, cells).ravel()


def vtk_arrays(V):
    """(topology, cell_types, points) of V's dof layout for pyvista.UnstructuredGrid."""
    return _vtk_mesh(V)


def write_xdmf(path, mesh, functions, comm) -> None:
    """Mesh and functions to XDMF/HDF5 for ParaView (functions must live on a
    Lagrange space of the mesh's geometry degree, or P1)."""
    with XDMFFile(comm, str(path), "w") as xdmf:
        xdmf.write_mesh(mesh)
        for f in functions:
            xdmf.write_function(f)
