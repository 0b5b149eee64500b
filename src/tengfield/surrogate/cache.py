"""The surrogate cache: where a scene's table lives (on the axis and over (z, r)), and
whether it is trusted.

:func:`obtain_table` is the cache keyed by :meth:`tengfield.scene.Scene.field_hash`
(and the solver fingerprint): rank 0 decides hit or miss and broadcasts the
decision and the table, so the ranks never disagree. The ball's surface charge σ is
neither in the key nor in the table: every charge of the field is linear in σ, so a
table holds the charges per unit ball charge (the induced fractions), the curves take
the scene's ball charge (:class:`tengfield.surrogate.TerminalCurves`), and a σ-only
change (value or sign) solves nothing. A file that is not trusted
(:func:`tengfield.surrogate.store.read_table`) is recomputed (with a warning); a
cache that cannot be written costs a warning, never the run.
"""
from __future__ import annotations

import os
import time
import warnings
from dataclasses import dataclass
from pathlib import Path

from .._mpi import rank_of, size_of
from .provenance import legacy_field_hash, radial_hash, solver_fingerprint
from .refinement import (SolveFunction, precompute, precompute_radial, radial_accuracy_problems,
                         warn_accuracy, warn_problems)
from .sampling import DEFAULT_DEGREE, DEFAULT_MESH_SIZE_MM, DEFAULT_TOLERANCE
from .store import read_radial_table, read_table, write_radial_table, write_table
from .table import SurrogateError, SurrogateTable
from ..scene.schema import SURFACE_CHARGE_KEY


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
    "computed" (no file) or "recomputed" (an untrusted file was replaced);
    ``stored`` is False when the new table could not be written to the cache."""
    status: str
    reason: str
    path: str
    wall_time: float
    stored: bool = True


def _decide(path: Path, scene, read=None) -> tuple[SurrogateTable | None, str, str]:
    """(table or None, status, reason) for the cache file ``path`` (one process);
    ``read(path)`` (default: :func:`read_table` for ``scene``) reads and checks it."""
    if path.is_dir():
        return None, "computed", f"the cache path {path} is a directory"
    if not path.exists():
        return None, "computed", f"no cached surrogate at {path}"
    try:
        table = read(path) if read is not None else read_table(
            path, expected_hash=scene.field_hash(), expected_solver=solver_fingerprint())
    except SurrogateError as exc:
        return None, "recomputed", f"cached surrogate {path} not trusted ({exc.reason})"
    return table, "cached", f"complete surrogate with matching field hash at {path}"


def load_cached(path: str | Path, scene, comm=None, *,
                read=None) -> tuple[SurrogateTable | None, str, str]:
    """Rank 0 of ``comm`` reads and checks the cache file ``path``; every rank gets
    its decision ``(table or None, status, reason)`` (status "cached", "computed"
    or "recomputed"). An untrusted file gives one warning (rank 0). ``read(path)``
    replaces :func:`read_table` (e.g. the (z, r) surrogate's reader); it raises
    :class:`SurrogateError` for a file it does not trust."""
    decision: object = None
    if rank_of(comm) == 0:
        try:
            decision = _decide(Path(path), scene, read)
        except Exception as exc:  # noqa: BLE001 - raised on every rank below, never a hang
            decision = exc
    if size_of(comm) > 1:
        decision = comm.bcast(decision, root=0)
    if isinstance(decision, Exception):
        raise decision
    table, status, reason = decision
    if status == "recomputed" and rank_of(comm) == 0:
        warnings.warn(f"{reason}, recomputing", RuntimeWarning, stacklevel=3)
    return table, status, reason


def store_in_cache(path: str | Path, table: SurrogateTable, comm=None, *, write=None) -> bool:
    """Write ``table`` to the cache file ``path`` on rank 0 of ``comm``; if that fails
    (cache directory a file or read-only, cache path a directory...) warn once and
    return False on every rank, else True. ``write(path, table)`` replaces
    :func:`write_table` (it raises ``OSError`` when it cannot write)."""
    stored: object = True
    if rank_of(comm) == 0:
        try:
            (write or write_table)(path, table)
        except OSError as exc:
            why = exc.strerror or str(exc)
            warnings.warn(f"surrogate cache {path} could not be written ({why}); the table is "
                          "used for this run but not cached", RuntimeWarning, stacklevel=3)
            stored = False
    if size_of(comm) > 1:
        stored = comm.bcast(stored, root=0)
    return bool(stored)


def solved_scene(scene):
    """The scene a surrogate is solved for: ``scene`` itself, or (an uncharged ball) the
    same scene at the stand-in σ (``BREAKDOWN_PLACEHOLDER_UC``): a solver may give the
    fractions as charges divided by the ball's, which an uncharged ball has not. The
    table is per unit charge either way (its cache key has no σ)."""
    if scene.device.surface_charge != 0.0:
        return scene
    from ..scene.schema import BREAKDOWN_PLACEHOLDER_UC
    return scene.with_values(device={SURFACE_CHARGE_KEY: BREAKDOWN_PLACEHOLDER_UC})


def _legacy(scene, path: Path, comm, write: bool):
    """A trusted surrogate cached by an older tengfield under the key with σ
    (:func:`legacy_field_hash`): read, copied to ``path`` under today's key (when
    ``write``), and used. ``(None, "computed", reason)`` when there is none."""
    import dataclasses

    legacy = legacy_field_hash(scene)
    old = path.parent / f"surrogate-{legacy[:24]}.h5"
    missing = (None, "computed", f"no cached surrogate at {path}")
    if old == path or not old.is_file():
        return missing
    table, status, reason = load_cached(
        old, scene, comm, read=lambda p: read_table(p, expected_hash=legacy,
                                                    expected_solver=solver_fingerprint()))
    if table is None:   # an untrusted old file was warned of; solve for today's key
        return None, "recomputed", reason
    table = dataclasses.replace(table, field_hash=scene.field_hash())
    if write:
        store_in_cache(path, table, comm)
    return table, "cached", (f"surrogate of an older tengfield (sigma in its key) at {old}"
                             + (f", copied to {path}" if write else ""))


def obtain_table(scene, *, cache_dir: str | Path | None = None, comm=None,
                 solve: SolveFunction | None = None, progress: bool = False,
                 command_line: str = "", write: bool = True) -> tuple[SurrogateTable, CacheOutcome]:
    """The cached surrogate of ``scene`` if trusted (:func:`read_table`), else a new one.

    Rank 0 of ``comm`` decides hit or miss and broadcasts the decision and the
    table (:func:`load_cached`). A partial, corrupt or mismatching file triggers
    a warning and a recomputation (it is never trusted). The new table is
    written by rank 0 unless ``write`` is false; a cache that cannot be
    written gives a warning (:func:`store_in_cache`). Every rank returns the table.
    """
    start = time.perf_counter()
    path = cache_path(scene, cache_dir)
    table, status, reason = load_cached(path, scene, comm)
    if table is None and status == "computed":
        table, status, reason = _legacy(scene, path, comm, write)
    if table is not None:
        warn_accuracy(table, comm)      # as when it was computed: a cache hit is no excuse
        table.scene = scene
        return table, CacheOutcome(status, reason, str(path), time.perf_counter() - start)
    table = precompute(solved_scene(scene), comm=comm, solve=solve, progress=progress,
                       command_line=command_line)
    stored = store_in_cache(path, table, comm) if write else False
    table.scene = scene
    return table, CacheOutcome(status, reason, str(path), time.perf_counter() - start, stored)


def radial_cache_path(scene, cache_dir=None, **settings) -> Path:
    """Where the (z, r) surrogate of ``scene`` lives in the cache."""
    directory = Path(cache_dir).expanduser() if cache_dir is not None else default_cache_dir()
    return directory / f"surrogate-zr-{radial_hash(scene, **settings)[:24]}.h5"


def obtain_radial_table(scene, *, cache_dir=None, comm=None, solve=None, progress: bool = False,
                        command_line: str = "", write: bool = True,
                        mesh_size_mm: float = DEFAULT_MESH_SIZE_MM, degree: int = DEFAULT_DEGREE,
                        tolerance: float = DEFAULT_TOLERANCE, **refinement):
    """The cached (z, r) surrogate of ``scene`` if trusted, else a new one:
    ``(RadialTable, CacheOutcome)``, the rules of
    :func:`tengfield.surrogate.obtain_table` (rank 0 decides and broadcasts;
    an untrusted file is recomputed with a warning; an unwritable cache costs a
    warning). ``refinement``: further keywords of :func:`precompute_radial` (which refuses
    the single-electrode cell before any work)."""
    start = time.perf_counter()
    settings = {"mesh_size_mm": mesh_size_mm, "degree": degree, "tolerance": tolerance}
    path = radial_cache_path(scene, cache_dir, **settings)
    key = radial_hash(scene, **settings)
    table, status, reason = load_cached(
        path, scene, comm,
        read=lambda p: read_radial_table(p, expected_hash=key,
                                         expected_solver=solver_fingerprint()))
    if table is not None:
        warn_problems(radial_accuracy_problems(table), comm, stacklevel=2)
        return table, CacheOutcome(status, reason, str(path), time.perf_counter() - start)
    table = precompute_radial(solved_scene(scene), comm=comm, solve=solve, progress=progress,
                              command_line=command_line, **settings, **refinement)
    stored = store_in_cache(path, table, comm, write=write_radial_table) if write else False
    return table, CacheOutcome(status, reason, str(path), time.perf_counter() - start, stored)
