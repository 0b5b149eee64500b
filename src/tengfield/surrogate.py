"""Surrogate of the terminal quantities against ball position (DESIGN §4).

Field solves (:func:`tengfield.field.solve_position`) at sampled gaps
``z ∈ [0, Δh]`` give per position the Maxwell capacitance matrix
``C_ll, C_lu, C_uu`` [F] and the induced charges ``q_l, q_u`` [C] (sign
conventions of :mod:`tengfield.terminals`). Cubic splines through the
derived ``Q_SC(z)`` [C] and ``C_T(z)`` [F] (for the chosen reference) give
``V_OC = Q_SC / C_T`` [V] and the exact derivatives ``dQ_SC/dz`` [C/m] and
``dC_T/dz`` [F/m] of the interpolant (never finite differences).

Sampling: nested Chebyshev–Lobatto sets ``z_j = Δh (1 - cos(π j / (n-1))) / 2``
with ``n = 2^k + 1`` (clustered at both ends of the stroke). Each refinement
solves the ``n - 1`` new positions (the angular midpoints of the current set)
first as *held-out* points: the largest relative deviation of the current
interpolant from those direct solves (over Q_SC, C_T and V_OC, both
references) is the error estimate. Refinement stops once it is below
``[field] tolerance``; the stored surrogate then includes the held-out
points, so the estimate is conservative (it belongs to the coarser set).

The table is stored in HDF5 (:func:`write_table`, atomic) with provenance and
a completeness flag; :func:`obtain_table` implements the cache keyed by
:meth:`tengfield.scene.Scene.field_hash`.
"""
from __future__ import annotations

import dataclasses
import importlib.metadata
import json
import math
import os
import sys
import tempfile
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np
from scipy.interpolate import CubicSpline

from . import __version__, terminals
from ._mpi import farm, rank_of
from .errors import TengfieldError

FORMAT_VERSION = 1
#: initial number of positions (a Chebyshev–Lobatto set, 2^k + 1)
INITIAL_POSITIONS = 9
#: the refinement stops here even if the tolerance is not met (then converged = False)
MAX_POSITIONS = 65


class SurrogateError(TengfieldError, RuntimeError):
    """A surrogate file is missing, partial, corrupt or for another scene."""


# ---------------------------------------------------------------------------
# sampling
def lobatto_positions(stroke: float, count: int) -> np.ndarray:
    """``count`` Chebyshev–Lobatto gaps [m] on [0, stroke], ascending, ends included,
    bitwise symmetric about the middle (so mirror images land on set members)."""
    if count < 2:
        raise ValueError(f"count = {count}: at least 2 positions are needed")
    j = np.arange(count)
    z = 0.5 * stroke * (1.0 - np.cos(np.pi * j / (count - 1)))
    upper = j >= count // 2 + count % 2
    z[upper] = stroke - z[count - 1 - j[upper]]   # exactly symmetric: z_(n-1-j) = Δh - z_j
    z[0], z[-1] = 0.0, stroke
    return z


def refinement_positions(stroke: float, count: int) -> np.ndarray:
    """The ``count - 1`` positions that refine a Lobatto set of ``count`` to ``2 count - 1``."""
    finer = lobatto_positions(stroke, 2 * count - 1)
    return finer[1::2]


def is_mirror_symmetric(scene) -> bool:
    """True when the device is symmetric under z -> Δh - z with lower <-> upper.

    Both plates are built alike (same thickness, electrode radius and
    material), so only the environment can break the mirror symmetry: a
    grounded table under the lower plate does, free space does not.
    """
    return scene.field.environment == "free-space"


def mirrored(result, stroke: float):
    """The solve at ``stroke - z`` implied by mirror symmetry: C_ll <-> C_uu, q_l <-> q_u
    (wall and solve times 0: nothing was solved)."""
    C = np.asarray(result.capacitance, dtype=float)
    q = np.asarray(result.induced_charge, dtype=float)
    return dataclasses.replace(result, position=stroke - result.position,
                               capacitance=C[::-1, ::-1].copy(), induced_charge=q[::-1].copy(),
                               wall_time=0.0, solve_time=0.0,   # no solve of its own
                               info={**getattr(result, "info", {}), "mirrored_from": result.position})


def contact_first_order(positions: np.ndarray, stroke: float) -> np.ndarray:
    """Indices ordering positions by distance to the nearer plate, closest first.

    Solves close to contact are the dearest; the task farm hands out jobs in
    this order (longest first), which balances the ranks.
    """
    return np.argsort(np.minimum(positions, stroke - positions), kind="stable")


# ---------------------------------------------------------------------------
# the table of solves
_PER_POSITION = ("positions", "capacitance", "induced_charge", "dofs", "cells", "wall_time",
                 "solve_time", "field_error")


@dataclass
class SurrogateTable:
    """Field solves at sampled positions (one cell, SI) and their provenance.

    ``capacitance[i]`` = [[C_ll, C_lu], [C_lu, C_uu]] [F] and
    ``induced_charge[i]`` = [q_lower, q_upper] [C] at ``positions[i]`` [m]
    (ascending). ``interpolation_error`` is the held-out relative error
    estimate (see the module docstring), ``field_error`` the field solver's
    own per-position estimate.
    """
    positions: np.ndarray
    capacitance: np.ndarray
    induced_charge: np.ndarray
    ball_charge: float
    stroke: float
    dofs: np.ndarray
    cells: np.ndarray
    wall_time: np.ndarray
    solve_time: np.ndarray
    field_error: np.ndarray
    interpolation_error: float = math.nan
    tolerance: float = math.nan
    converged: bool = False
    error_history: list = field(default_factory=list)   # [(positions, estimate), ...]
    field_hash: str = ""
    method: str = ""
    degree: int = 0
    provenance: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        order = np.argsort(self.positions, kind="stable")
        self.positions = np.asarray(self.positions, dtype=float)[order]
        self.capacitance = np.asarray(self.capacitance, dtype=float).reshape(-1, 2, 2)[order]
        self.induced_charge = np.asarray(self.induced_charge, dtype=float).reshape(-1, 2)[order]
        for name in ("dofs", "cells"):
            setattr(self, name, np.asarray(getattr(self, name), dtype=np.int64)[order])
        for name in ("wall_time", "solve_time", "field_error"):
            setattr(self, name, np.asarray(getattr(self, name), dtype=float)[order])

    @property
    def count(self) -> int:
        return int(self.positions.size)

    @property
    def total_solve_wall_time(self) -> float:
        """Sum of the per-position wall times [s] over all ranks (mirror images cost 0)."""
        return float(np.sum(self.wall_time))

    def curves(self, reference: str = "floating") -> "TerminalCurves":
        return TerminalCurves(self, reference)

    def subset(self, mask) -> "SurrogateTable":
        """The positions selected by the boolean ``mask``."""
        return dataclasses.replace(self, **{name: getattr(self, name)[mask] for name in _PER_POSITION})

    def merged(self, other: "SurrogateTable") -> "SurrogateTable":
        """This table plus the positions of ``other`` (same scene)."""
        cat = {name: np.concatenate([getattr(self, name), getattr(other, name)])
               for name in _PER_POSITION}
        return dataclasses.replace(self, **cat)


def table_from_results(results: list, *, stroke: float) -> SurrogateTable:
    """A :class:`SurrogateTable` from :class:`~tengfield.field.PositionResult` s."""
    if not results:
        raise ValueError("no field results")
    return SurrogateTable(
        positions=[r.position for r in results],
        capacitance=[r.capacitance for r in results],
        induced_charge=[r.induced_charge for r in results],
        ball_charge=float(results[0].ball_charge),
        stroke=stroke,
        dofs=[r.dofs for r in results], cells=[r.cells for r in results],
        wall_time=[r.wall_time for r in results],
        solve_time=[getattr(r, "solve_time", math.nan) for r in results],
        field_error=[r.relative_error_estimate for r in results],
        method=str(results[0].method), degree=int(results[0].degree))


# ---------------------------------------------------------------------------
# terminal quantities and their interpolants
def terminal_samples(table: SurrogateTable, reference: str = "floating"):
    """``(Q_SC, C_T)`` [C], [F] at the table's positions, one cell.

    ``Q_SC(z) = Q_u0(z) - Q_u0(0)``: the table must contain z = 0.
    """
    C = table.capacitance
    q = table.induced_charge
    c_t = terminals.terminal_capacitance(C[:, 0, 0], C[:, 0, 1], C[:, 1, 1], reference)
    q_u0 = terminals.upper_short_circuit_charge(C[:, 0, 0], C[:, 0, 1], C[:, 1, 1],
                                                q[:, 0], q[:, 1], table.ball_charge, reference)
    if table.positions[0] != 0.0:
        raise SurrogateError("the surrogate table has no position z = 0 (the reference state)")
    return q_u0 - q_u0[0], np.asarray(c_t, dtype=float)


class TerminalCurves:
    """Smooth ``Q_SC(z)``, ``C_T(z)``, ``V_OC(z)`` of one cell for one reference.

    Cubic splines (not-a-knot) through the tabulated values; derivatives are
    those of the splines. ``z`` [m] outside [0, Δh] is clipped to the stroke.
    """

    def __init__(self, table: SurrogateTable, reference: str = "floating"):
        terminals._check_reference(reference)
        self.reference = reference
        self.stroke = float(table.stroke)
        self.positions = table.positions.copy()
        self.charge_samples, self.capacitance_samples = terminal_samples(table, reference)
        if self.positions.size < 2:
            raise SurrogateError("a surrogate needs at least 2 positions")
        kind = "not-a-knot" if self.positions.size >= 4 else "natural"
        self._q = CubicSpline(self.positions, self.charge_samples, bc_type=kind)
        self._c = CubicSpline(self.positions, self.capacitance_samples, bc_type=kind)
        self._dq = self._q.derivative()
        self._dc = self._c.derivative()

    def _z(self, z):
        return np.clip(np.asarray(z, dtype=float), 0.0, self.stroke)

    def charge(self, z):
        """Q_SC(z) [C]."""
        return self._q(self._z(z))

    def charge_derivative(self, z):
        """dQ_SC/dz [C/m] (exact derivative of the interpolant)."""
        return self._dq(self._z(z))

    def capacitance(self, z):
        """C_T(z) [F]."""
        return self._c(self._z(z))

    def capacitance_derivative(self, z):
        """dC_T/dz [F/m]."""
        return self._dc(self._z(z))

    def voltage(self, z):
        """V_OC(z) = Q_SC / C_T [V]."""
        return terminals.open_circuit_voltage(self.charge(z), self.capacitance(z))


def held_out_error(coarse: SurrogateTable, held_out: SurrogateTable) -> float:
    """Largest relative deviation of ``coarse``'s interpolants from direct solves.

    Over both references and the quantities Q_SC, C_T and V_OC, each relative
    to its largest magnitude on the union of both position sets.
    """
    union = coarse.merged(held_out)
    worst = 0.0
    for reference in terminals.REFERENCES:
        curves = TerminalCurves(coarse, reference)
        q_all, c_all = terminal_samples(union, reference)
        inside = np.isin(union.positions, held_out.positions)
        z = union.positions[inside]
        q_direct, c_direct = q_all[inside], c_all[inside]
        v_all = q_all / c_all
        pairs = [(curves.charge(z), q_direct, np.max(np.abs(q_all))),
                 (curves.capacitance(z), c_direct, np.max(np.abs(c_all))),
                 (curves.voltage(z), q_direct / c_direct, np.max(np.abs(v_all)))]
        for interpolated, direct, scale in pairs:
            if scale > 0.0:
                worst = max(worst, float(np.max(np.abs(interpolated - direct)) / scale))
    return worst


# ---------------------------------------------------------------------------
# precomputation
SolveFunction = Callable[..., Any]


def _default_solver() -> SolveFunction:
    from .field import solve_position  # dolfinx/gmsh only load inside the solve
    return solve_position


def precompute(scene, *, comm=None, solve: SolveFunction | None = None, solve_comm=None,
               initial_positions: int = INITIAL_POSITIONS, max_positions: int = MAX_POSITIONS,
               progress: bool = False, command_line: str = "") -> SurrogateTable:
    """Adaptive table of field solves for ``scene`` (see the module docstring).

    ``comm`` spreads the positions of each refinement level over its ranks
    (a task farm, each solve on ``solve_comm``, by default ``COMM_SELF``);
    every rank returns the same table. ``solve(scene, position, comm=...)``
    defaults to :func:`tengfield.field.solve_position`. When the device is
    mirror-symmetric (:func:`is_mirror_symmetric`) only the positions
    ``z <= Δh/2`` are solved and the others are their mirror images.
    """
    if solve is None:
        solve = _default_solver()
    if solve_comm is None:
        from mpi4py import MPI
        solve_comm = MPI.COMM_SELF
    stroke = scene.device.stroke
    tolerance = scene.field.tolerance
    count = int(initial_positions)
    if count < 3 or (count - 1) & (count - 2):
        raise ValueError(f"initial_positions = {count}: must be 2^k + 1 >= 3")
    bar = None
    if progress and rank_of(comm) == 0:
        from tqdm import tqdm
        bar = tqdm(total=count, desc="field solves", unit="position", file=sys.stderr,
                   disable=not sys.stderr.isatty())

    symmetric = is_mirror_symmetric(scene)

    def work(z):
        return solve(scene, float(z), comm=solve_comm)

    def advance(n):
        if bar is not None:
            bar.update(min(n, bar.total - bar.n))

    def solve_level(positions: np.ndarray) -> SurrogateTable:
        """Solve ``positions`` (with mirror symmetry: only those in the lower half)."""
        todo = positions[positions <= 0.5 * stroke * (1 + 1e-12)] if symmetric else positions
        if bar is not None:
            bar.total += todo.size - positions.size
            bar.refresh()
        todo = todo[contact_first_order(todo, stroke)]
        results = farm(comm, list(todo), work, progress=advance)
        if symmetric:
            results += [mirrored(r, stroke) for r in results
                        if not math.isclose(r.position, 0.5 * stroke, rel_tol=1e-12)]
        return table_from_results(results, stroke=stroke)

    # the first refinement is always needed: solve it with the initial set in one
    # batch (better balance over the ranks), then split coarse / held-out
    initial = lobatto_positions(stroke, count)
    new = refinement_positions(stroke, count)
    if bar is not None:
        bar.total += new.size
    both = solve_level(np.concatenate([initial, new]))
    table, held_out = both.subset(np.isin(both.positions, initial)), \
        both.subset(np.isin(both.positions, new))
    history: list[tuple[int, float]] = []
    while True:
        estimate = held_out_error(table, held_out)
        history.append((count, estimate))
        table = table.merged(held_out)
        count = 2 * count - 1
        if estimate <= tolerance or 2 * count - 1 > max_positions:
            break
        new = refinement_positions(stroke, count)
        if bar is not None:
            bar.total += new.size
            bar.refresh()
        held_out = solve_level(new)
    if bar is not None:
        bar.n = bar.total
        bar.close()
    converged = estimate <= tolerance
    if not converged and rank_of(comm) == 0:
        warnings.warn(f"surrogate: interpolation error estimate {estimate:.3g} is above "
                      f"[field] tolerance = {tolerance:g} after {table.count} positions "
                      f"(max_positions = {max_positions})", RuntimeWarning, stacklevel=2)
    return dataclasses.replace(
        table, interpolation_error=estimate, tolerance=tolerance, converged=converged,
        error_history=history, field_hash=scene.field_hash(),
        provenance={**provenance(scene, command_line), "mirror_symmetry": symmetric,
                    "solver_fingerprint": solver_fingerprint()})


def solver_fingerprint() -> str:
    """SHA-256 (16 hex digits) of the field solver's source files.

    Part of the cache check on top of the scene's field hash, so that a
    changed solver (without a ``FIELD_SCHEMA`` bump) never reuses old solves.
    """
    import hashlib
    from importlib import resources

    digest = hashlib.sha256()
    package = resources.files("tengfield").joinpath("field")
    for entry in sorted(package.iterdir(), key=lambda e: e.name):
        if entry.name.endswith(".py"):
            digest.update(entry.name.encode())
            digest.update(entry.read_bytes())
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


# ---------------------------------------------------------------------------
# HDF5 file
def _import_h5py():
    """``h5py``, which must be the distribution's build (Debian's python3-h5py).

    A pip wheel of h5py bundles its own HDF5; imported after dolfinx has loaded
    the system HDF5 it fails ("Not a datatype") or corrupts files. ``make setup``
    removes such a wheel from the venv; this names the problem if one is back.
    """
    import h5py

    bundled = Path(h5py.__file__).resolve().parents[1] / "h5py.libs"
    if bundled.exists() and any(name.startswith("dolfinx") for name in sys.modules):
        raise SurrogateError(
            f"the h5py at {Path(h5py.__file__).parent} is a pip wheel with its own HDF5, "
            "which clashes with the HDF5 dolfinx loads: `pip uninstall h5py` in the venv "
            "(Debian's python3-h5py is used), e.g. by running `make setup`")
    return h5py


_ARRAYS = {"positions": "positions_m", "capacitance": "capacitance_F",
           "induced_charge": "induced_charge_C", "dofs": "dofs", "cells": "cells",
           "wall_time": "wall_time_s", "solve_time": "solve_time_s",
           "field_error": "field_relative_error_estimate"}


def write_table(path: str | Path, table: SurrogateTable) -> Path:
    """Write ``table`` to HDF5 atomically (temporary file + ``os.replace``)."""
    h5py = _import_h5py()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        with h5py.File(tmp, "w") as f:
            f.attrs["complete"] = False
            for attr, name in _ARRAYS.items():
                f.create_dataset(name, data=getattr(table, attr))
            f.create_dataset("error_history", data=np.asarray(table.error_history, dtype=float)
                             .reshape(-1, 2))
            f.attrs["format_version"] = FORMAT_VERSION
            f.attrs["ball_charge_C"] = table.ball_charge
            f.attrs["stroke_m"] = table.stroke
            f.attrs["interpolation_error_estimate"] = table.interpolation_error
            f.attrs["tolerance"] = table.tolerance
            f.attrs["converged"] = bool(table.converged)
            f.attrs["field_hash"] = table.field_hash
            f.attrs["method"] = table.method
            f.attrs["degree"] = int(table.degree)
            f.attrs["provenance"] = json.dumps(table.provenance, default=str)
            f.attrs["scene_text"] = table.provenance.get("scene_text", "")
            f.attrs["command_line"] = table.provenance.get("command_line", "")
            f.attrs["written_with"] = f"h5py {h5py.__version__}, HDF5 {h5py.version.hdf5_version}"
            f.flush()
            f.attrs["complete"] = True
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def read_table(path: str | Path, expected_hash: str | None = None,
               expected_solver: str | None = None) -> SurrogateTable:
    """Read a surrogate file; raise :class:`SurrogateError` unless it is complete,
    readable and (if given) made for ``expected_hash`` by the solver with
    fingerprint ``expected_solver`` (:func:`solver_fingerprint`)."""
    h5py = _import_h5py()
    path = Path(path)
    if not path.is_file():
        raise SurrogateError(f"surrogate file {str(path)!r} does not exist")
    try:
        with h5py.File(path, "r") as f:
            if not bool(f.attrs.get("complete", False)):
                raise SurrogateError(f"surrogate file {str(path)!r} is partial (complete flag unset)")
            if int(f.attrs.get("format_version", -1)) != FORMAT_VERSION:
                raise SurrogateError(f"surrogate file {str(path)!r} has format version "
                                     f"{f.attrs.get('format_version')!r}, expected {FORMAT_VERSION}")
            stored_hash = str(f.attrs["field_hash"])
            if expected_hash is not None and stored_hash != expected_hash:
                raise SurrogateError(f"surrogate file {str(path)!r} was made for field hash "
                                     f"{stored_hash[:12]}..., the scene has {expected_hash[:12]}...")
            arrays = {attr: f[name][()] for attr, name in _ARRAYS.items()}
            history = [tuple(row) for row in f["error_history"][()].tolist()]
            history = [(int(n), float(e)) for n, e in history]
            table = SurrogateTable(
                **arrays, ball_charge=float(f.attrs["ball_charge_C"]),
                stroke=float(f.attrs["stroke_m"]),
                interpolation_error=float(f.attrs["interpolation_error_estimate"]),
                tolerance=float(f.attrs["tolerance"]), converged=bool(f.attrs["converged"]),
                error_history=history, field_hash=stored_hash, method=str(f.attrs["method"]),
                degree=int(f.attrs["degree"]), provenance=json.loads(str(f.attrs["provenance"])))
    except SurrogateError:
        raise
    except Exception as exc:  # noqa: BLE001 - any read failure means "corrupt"
        raise SurrogateError(f"surrogate file {str(path)!r} is corrupt or unreadable: "
                             f"{type(exc).__name__}: {exc}") from None
    stored_solver = table.provenance.get("solver_fingerprint")
    if expected_solver is not None and stored_solver != expected_solver:
        raise SurrogateError(f"surrogate file {str(path)!r} was made by another version of the "
                             f"field solver (fingerprint {stored_solver}, now {expected_solver})")
    if table.count < 2 or not np.all(np.isfinite(table.capacitance)) \
            or not np.all(np.isfinite(table.induced_charge)):
        raise SurrogateError(f"surrogate file {str(path)!r} holds non-finite or too few values")
    return table


# ---------------------------------------------------------------------------
# cache
def default_cache_dir() -> Path:
    """``$TENGFIELD_CACHE_DIR``, else ``$XDG_CACHE_HOME/tengfield``, else ``~/.cache/tengfield``."""
    env = os.environ.get("TENGFIELD_CACHE_DIR")
    if env:
        return Path(env).expanduser()
    xdg = os.environ.get("XDG_CACHE_HOME")
    base = Path(xdg).expanduser() if xdg else Path.home() / ".cache"
    return base / "tengfield"


def cache_path(scene, cache_dir: str | Path | None = None) -> Path:
    """Where the surrogate of ``scene`` lives in the cache (named by its field hash)."""
    directory = Path(cache_dir).expanduser() if cache_dir is not None else default_cache_dir()
    return directory / f"surrogate-{scene.field_hash()[:24]}.h5"


@dataclass
class CacheOutcome:
    """How :func:`obtain_table` got its table: ``status`` is "cached",
    "computed" (no file) or "recomputed" (an untrusted file was replaced)."""
    status: str
    reason: str
    path: str
    wall_time: float


def obtain_table(scene, *, cache_dir: str | Path | None = None, comm=None,
                 solve: SolveFunction | None = None, progress: bool = False,
                 command_line: str = "", write: bool = True) -> tuple[SurrogateTable, CacheOutcome]:
    """The cached surrogate of ``scene`` if complete and matching, else a new one.

    A partial, corrupt or mismatching file triggers a warning and a
    recomputation (it is never trusted). The new table is written (rank 0
    of ``comm``) unless ``write`` is false. Every rank returns the table.
    """
    start = time.perf_counter()
    path = cache_path(scene, cache_dir)
    status, reason = "computed", f"no cached surrogate at {path}"
    if path.exists():
        try:
            table = read_table(path, expected_hash=scene.field_hash(),
                               expected_solver=solver_fingerprint())
            return table, CacheOutcome("cached", f"complete surrogate with matching field hash "
                                       f"at {path}", str(path), time.perf_counter() - start)
        except SurrogateError as exc:
            status, reason = "recomputed", f"cached file not trusted: {exc}"
            if rank_of(comm) == 0:
                warnings.warn(f"{reason}; recomputing", RuntimeWarning, stacklevel=2)
    table = precompute(scene, comm=comm, solve=solve, progress=progress,
                       command_line=command_line)
    if write and rank_of(comm) == 0:
        write_table(path, table)
    return table, CacheOutcome(status, reason, str(path), time.perf_counter() - start)
