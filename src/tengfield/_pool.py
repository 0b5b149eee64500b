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

Workers never run the caller's ``__main__`` (:func:`_without_main`): multiprocessing's
``spawn`` and ``forkserver`` workers re-import the main script (its
``init_main_from_path``) or module (``init_main_from_name``) before they unpickle
their task, which re-runs a script without an ``if __name__ == "__main__":`` guard
(its ``tf.map`` then starts workers from a worker: "An attempt has been made to start
a new process before the current process has finished its bootstrapping phase", over
and over), fails on ``python -`` (``runpy.run_path('<stdin>')``) and re-runs
``ipykernel_launcher`` in a notebook. The pools' tasks are tengfield's own functions,
so a worker needs tengfield only. A worker that cannot start, or dies, ends the pool
with one :class:`PoolError` line instead of a pool that waits or starts workers again.
"""
from __future__ import annotations

import contextlib
import multiprocessing
import multiprocessing.context
import multiprocessing.spawn
import os
import sys
import threading

from .errors import TengfieldError

#: Imported once by the fork server (see the module docstring); nothing in it
#: initialises MPI or dolfinx, or starts a thread.
PRELOAD = ["tengfield._pool_preload"]


class PoolError(TengfieldError, RuntimeError):
    """A worker process of a pool could not start or stopped (one line for the CLI)."""


_launching = threading.local()   # set while this thread starts one of our workers
_prepare = multiprocessing.spawn.get_preparation_data


def _preparation_data(name):
    """multiprocessing's preparation data of a new ``spawn``/``forkserver`` process,
    without the caller's main script or module while one of our workers starts."""
    data = _prepare(name)
    if getattr(_launching, "active", False):
        data.pop("init_main_from_path", None)
        data.pop("init_main_from_name", None)
    return data


def _without_main() -> None:
    """Install :func:`_preparation_data` (once): it drops the ``__main__`` entries only
    for the processes our contexts start (a thread-local flag set by their ``start``),
    so the caller's own multiprocessing is left as it was."""
    if multiprocessing.spawn.get_preparation_data is not _preparation_data:
        multiprocessing.spawn.get_preparation_data = _preparation_data


class _WorkerStart:
    """Mixin of our workers' Process classes: the start (the preparation data is made
    synchronously in ``start`` by the thread starting the worker) runs flagged."""

    def start(self):
        previous = getattr(_launching, "active", False)
        _launching.active = True
        try:
            super().start()
        finally:
            _launching.active = previous


class _ForkServerProcess(_WorkerStart, multiprocessing.context.ForkServerProcess):
    pass


class _SpawnProcess(_WorkerStart, multiprocessing.context.SpawnProcess):
    pass


class _ForkServerContext(multiprocessing.context.ForkServerContext):
    Process = _ForkServerProcess


class _SpawnContext(multiprocessing.context.SpawnContext):
    Process = _SpawnProcess


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
    method = method or start_method()
    if method == "fork":
        return multiprocessing.get_context("fork")
    _without_main()
    context = {"forkserver": _ForkServerContext, "spawn": _SpawnContext}[method]()
    if method == "forkserver":
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


def _drain_tasks(pool) -> None:
    """Read, and drop, the tasks still in the pipe to a broken pool's dead workers.

    Python 3.11's executor, once a worker died, joins the thread that feeds the tasks to
    the workers, which blocks for ever on a full pipe nobody reads (a sweep's tasks carry
    their scene): the caller would wait in ``shutdown`` for good. A daemon thread here
    empties that pipe until the executor closes it."""
    reader = getattr(getattr(pool, "_call_queue", None), "_reader", None)
    if reader is None:
        return

    def drain():
        try:
            while True:
                reader.recv_bytes()
        except (EOFError, OSError, ValueError):
            pass

    threading.Thread(target=drain, name="tengfield-pool-drain", daemon=True).start()


@contextlib.contextmanager
def process_pool(jobs: int, method: str | None = None, initializer=None):
    """A ``ProcessPoolExecutor`` of ``jobs`` workers on :func:`pool_context` (``method``:
    a start method instead of :func:`start_method`'s choice). When the
    block fails or is interrupted (Ctrl-C, SIGTERM through the CLI) its workers are
    terminated and the tasks not started are cancelled: no worker goes on computing,
    or outlives the command (``with ProcessPoolExecutor`` would wait for every task)."""
    from concurrent.futures import ProcessPoolExecutor
    from concurrent.futures.process import BrokenProcessPool

    pool = ProcessPoolExecutor(max_workers=jobs, mp_context=pool_context(method),
                               initializer=initializer)
    try:
        try:
            yield pool
        except BrokenProcessPool as exc:
            _drain_tasks(pool)
            raise PoolError(f"a worker process of the {jobs}-worker pool could not start "
                            f"or stopped ({exc}); run with jobs=1 (--jobs 1) to see "
                            "its error") from exc
    except BaseException:
        for process in list((getattr(pool, "_processes", None) or {}).values()):
            process.terminate()
        pool.shutdown(wait=True, cancel_futures=True)
        raise
    pool.shutdown(wait=True)
