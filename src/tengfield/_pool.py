"""How tengfield starts its worker-process pools (``--jobs N`` on one machine).

One place for the start method of every pool (``tengfield map``'s regime map, ``sweep``
and ``report``'s task lists, an ``[array]``'s cells), :func:`pool_context`:

* ``fork`` when it is safe (:func:`start_method`): the calling process has one thread
  and has not initialised MPI (a plain ``tengfield map`` or ``sweep`` with a cached
  surrogate; the CLI turns tqdm's monitor thread off for this). The workers start
  at once, with the compiled kernels the caller already loaded.
* ``forkserver`` otherwise. Forking a process that has other threads (MPI's progress
  threads, a progress bar's monitor, a test runner's) can deadlock the child: Python
  3.12+ warns "This process ... is multi-threaded, use of fork() may lead to deadlocks
  in the child". The fork server is a fresh single-threaded interpreter, started once
  per process, that never initialises MPI; it imports :data:`PRELOAD` (the tasks'
  modules, numpy, numba and the impact map's kernels) once, and every worker is forked
  from it with those loaded, instead of importing them again as ``spawn`` workers do.
"""
from __future__ import annotations

import contextlib
import multiprocessing
import os
import sys

#: Imported once by the fork server (see the module docstring); nothing in it
#: initialises MPI or dolfinx, or starts a thread.
PRELOAD = ["tengfield._pool_preload"]


def _threads() -> int:
    """Threads of this process as the OS counts them (Python's fork check does the
    same on Linux), else those the threading module knows."""
    try:
        return len(os.listdir("/proc/self/task"))
    except OSError:
        import threading

        return threading.active_count()


def _mpi_initialised() -> bool:
    mpi = sys.modules.get("mpi4py.MPI")
    try:
        return bool(mpi is not None and mpi.Is_initialized() and not mpi.Is_finalized())
    except Exception:  # noqa: BLE001 - an MPI that cannot say: assume it is running
        return True


def start_method() -> str:
    """``fork`` if forking this process now is safe, else ``forkserver``.

    Safe: no Python thread but this one, MPI not initialised and, on Python 3.12+,
    one thread as the OS counts them (Python's own test). Before 3.12 a BLAS library's
    native worker threads (a pip numpy's OpenBLAS, fork-safe through its own atfork
    handlers) do not count, as they never did for these pools."""
    import threading

    if threading.active_count() > 1 or _mpi_initialised():
        return "forkserver"
    if sys.version_info >= (3, 12) and _threads() > 1:
        return "forkserver"
    return "fork"


def pool_context(method: str | None = None):
    """The multiprocessing context a pool is created with: :func:`start_method` (or
    ``method``), a fork server preloading :data:`PRELOAD`."""
    context = multiprocessing.get_context(method or start_method())
    if context.get_start_method() == "forkserver":
        context.set_forkserver_preload(PRELOAD)
    return context


def start_early(jobs: int | None) -> None:
    """For a command about to run ``jobs`` workers (None: one per core) in a process
    that would get a fork server: start it now, so it loads its modules while the
    command reads its input rather than when the first pool opens."""
    if (jobs is not None and jobs <= 1) or (os.cpu_count() or 1) <= 1:
        return
    if start_method() == "forkserver":
        from multiprocessing import forkserver

        pool_context("forkserver")
        forkserver.ensure_running()


@contextlib.contextmanager
def process_pool(jobs: int, method: str | None = None, initializer=None):
    """A ``ProcessPoolExecutor`` of ``jobs`` workers on :func:`pool_context` (``method``:
    a start method instead of :func:`start_method`'s choice). When the
    block fails or is interrupted (Ctrl-C, SIGTERM through the CLI) its workers are
    terminated and the tasks not started are cancelled: no worker goes on computing,
    or outlives the command (``with ProcessPoolExecutor`` would wait for every task)."""
    from concurrent.futures import ProcessPoolExecutor

    pool = ProcessPoolExecutor(max_workers=jobs, mp_context=pool_context(method),
                               initializer=initializer)
    try:
        yield pool
    except BaseException:
        for process in list((getattr(pool, "_processes", None) or {}).values()):
            process.terminate()
        pool.shutdown(wait=True, cancel_futures=True)
        raise
    pool.shutdown(wait=True)
