"""MPI task farm for independent jobs (e.g. one field solve per ball position).

Communicators are always passed in; only :func:`world_if_parallel` touches
``COMM_WORLD``, after :func:`launched_size`, the one test of whether mpirun started
this process (the CLI's and the commands' alike), says that it has company.
``comm`` may be any object with mpi4py's ``rank``, ``size``, ``allgather``
and ``Abort`` (``None`` means a serial run without MPI).
"""
from __future__ import annotations

import os
import sys
import time
import traceback
from typing import Any, Callable, Sequence


#: what an MPI launcher puts into each rank's environment: the number of ranks it
#: started (Open MPI, PMI: MPICH and Intel MPI, PMIx, MPICH's hydra), first found first
LAUNCHER_SIZE_VARIABLES = ("OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE", "MPI_LOCALNRANKS")


def launched_size() -> int:
    """How many ranks mpirun started this process among (1: started without it, or
    with ``-n 1``), read from the launcher's environment: MPI is not initialised."""
    for key in LAUNCHER_SIZE_VARIABLES:
        value = os.environ.get(key)
        if value and value.isdigit():
            return int(value)
    return 1


#: ... and this process's rank among them
LAUNCHER_RANK_VARIABLES = ("OMPI_COMM_WORLD_RANK", "PMI_RANK", "PMIX_RANK")


def launched_rank() -> int:
    """This process's rank among the ranks mpirun started (0 without mpirun), read from
    the launcher's environment: MPI is not initialised. A line every rank would print
    alike (a scene's warning) is printed where this is 0."""
    for key in LAUNCHER_RANK_VARIABLES:
        value = os.environ.get(key)
        if value and value.isdigit():
            return int(value)
    return 0


def world_if_parallel():
    """``MPI.COMM_WORLD`` when started by mpirun with several ranks, else None
    (a serial run never initialises MPI before it needs a field solve)."""
    if launched_size() <= 1:
        return None
    from mpi4py import MPI
    return MPI.COMM_WORLD if MPI.COMM_WORLD.size > 1 else None


def rank_of(comm) -> int:
    return 0 if comm is None else int(comm.rank)


def size_of(comm) -> int:
    return 1 if comm is None else int(comm.size)


#: At most this many worker processes per core (``--jobs``).
JOBS_PER_CORE_LIMIT = 4


def max_jobs() -> int:
    """Largest ``jobs`` accepted: ``JOBS_PER_CORE_LIMIT`` x the cores of this machine."""
    return JOBS_PER_CORE_LIMIT * (os.cpu_count() or 1)


def check_jobs(jobs: int | None, comm=None, option: str = "--jobs") -> None:
    """Refuse ``jobs`` worker processes outside ``[1, max_jobs()]`` (None = all cores), and
    more than one inside an MPI job: under ``mpirun -n N`` (N > 1) every rank is one worker."""
    from .errors import SceneError

    if jobs is None:
        return
    if not 1 <= jobs <= max_jobs():
        raise SceneError(f"{option} = {jobs} is out of range: allowed [1, {max_jobs()}] "
                         f"({JOBS_PER_CORE_LIMIT} x the {os.cpu_count() or 1} cores)")
    if jobs > 1 and size_of(comm) > 1:
        raise SceneError(f"{option} = {jobs} cannot be combined with mpirun -n {size_of(comm)}: "
                         f"allowed 1 or omitted (each MPI rank is one worker)")


def abort_with_message(comm, message: str, code: int = 2) -> None:
    """Print ``message`` (rank-tagged) to stderr and abort every rank of ``comm``.

    Only used when ``comm`` has more than one rank: the other ranks may be
    blocked in a collective call, so raising would leave them hanging.
    """
    sys.stderr.write(f"tengfield: error on rank {rank_of(comm)} of {size_of(comm)}: {message}\n")
    sys.stderr.flush()
    comm.Abort(code)


#: Seconds a rank that failed on its own waits for the others to reach the end of the
#: command (:func:`all_arrived`) before it aborts them: long enough for ranks that fail
#: alike (the same bad value) to agree on one message, short enough not to look hung.
FAILURE_GRACE_S = 5.0


def all_arrived(comm, timeout: float | None = None) -> bool:
    """Wait until every rank of ``comm`` calls this (a non-blocking barrier, polled
    with short sleeps, so a waiting rank leaves its core to the others).

    True once all have arrived; False if ``timeout`` seconds passed first (the
    caller then aborts: a rank that never comes is blocked elsewhere, e.g. in a
    collective call of the command on another communicator).
    """
    request = comm.Ibarrier()
    deadline = None if timeout is None else time.monotonic() + timeout
    pause = 1e-3
    while not request.Test():
        if deadline is not None and time.monotonic() >= deadline:
            return False
        time.sleep(pause)
        pause = min(2 * pause, 0.05)
    return True


class FailedOnAnotherRank(RuntimeError):
    """Raised by :func:`farm` on the ranks whose items went well when another rank's
    ``work`` raised (``original``: that exception, when it could be sent; ``rank``: where):
    the CLI's agreement prints the failing rank's own line once, every rank ends with its
    exit code, and -o DIR is cleaned up as in one process (#43 item 8)."""

    def __init__(self, rank: int, size: int, original: BaseException | None, detail: str):
        super().__init__(f"tengfield: error on rank {rank} of {size}: {detail}")
        self.rank, self.original = rank, original


def farm(comm, items: Sequence[Any], work: Callable[[Any], Any], *,
         progress: Callable[[int], None] | None = None, dynamic: bool = True) -> list:
    """``[work(item) for item in items]`` with the items spread over the ranks.

    Each job must be serial (e.g. a field solve on ``COMM_SELF``). With
    ``dynamic`` (default) the ranks take the next unstarted item from a
    shared counter (an MPI window on rank 0, atomic ``Fetch_and_op``), so a
    rank that drew a dear job simply takes fewer: pass the dearest items
    first. Without it (or if the MPI library offers no RMA window) rank ``r``
    runs items ``r, r + size, ...``. Every rank returns the full result list
    in the order of ``items`` (``allgather``), so all ranks can take the same
    next decision; results must be picklable, and do not depend on which
    rank computed them.

    An exception in ``work`` on a multi-rank communicator stops the farm on every rank
    (never a hang, no ``MPI_Abort``): the failing rank moves the shared counter past the
    end (the others start no further item), every rank meets at the final ``allgather``,
    the failing rank raises its exception and the others :class:`FailedOnAnotherRank`
    (with it); on one rank it is simply raised.

    ``progress(n)`` is called on rank 0 with the number of further jobs
    started on all ranks (dynamic) or an estimate (static).
    """
    size = size_of(comm)
    if size == 1:
        results = []
        for item in items:
            results.append(work(item))
            if progress is not None:
                progress(1)
        return results
    counter = _shared_counter(comm) if dynamic else None
    results: dict[int, Any] = {}
    started_seen = 0
    failure = None
    if counter is None:
        indices = iter(range(comm.rank, len(items), size))
    else:
        indices = iter(lambda: counter.fetch_next(), None)
    for index in indices:
        if index >= len(items):
            break
        try:
            results[index] = work(items[index])
        except BaseException as exc:  # noqa: BLE001 - every rank must reach the allgather
            failure = exc
            if counter is not None:
                counter.stop(len(items))
            break
        if progress is not None and comm.rank == 0:
            started = min(counter.peek(), len(items)) if counter is not None \
                else min(started_seen + size, len(items))
            progress(started - started_seen)
            started_seen = started
    if counter is not None:
        counter.free()
    gathered = comm.allgather((results if failure is None else {}, _sendable(failure)))
    failed = [(rank, sent) for rank, (_, sent) in enumerate(gathered) if sent is not None]
    if failure is not None:
        raise failure
    if failed:
        rank, (original, detail) = failed[0]
        raise FailedOnAnotherRank(rank, size, original, detail)
    merged: dict[int, Any] = {}
    for part, _ in gathered:
        merged.update(part)
    return [merged[i] for i in range(len(items))]


def _sendable(exc: BaseException | None):
    """(``exc`` if it pickles, else None; its one-line text) for the other ranks."""
    if exc is None:
        return None
    import pickle

    detail = "".join(traceback.format_exception_only(type(exc), exc)).strip()
    if not isinstance(exc, Exception):
        detail = f"interrupted ({type(exc).__name__})"
    try:
        pickle.loads(pickle.dumps(exc))
    except Exception:  # noqa: BLE001 - an exception that does not travel: its text does
        return None, detail
    return exc, detail


class _SharedCounter:
    """An integer on rank 0 that every rank can fetch-and-increment (MPI RMA)."""

    def __init__(self, comm, window):
        import numpy as np

        self._np = np
        self.comm = comm
        self.window = window
        if comm.rank == 0:
            from mpi4py import MPI
            window.Lock(0, MPI.LOCK_EXCLUSIVE)
            window.Put(np.zeros(1, dtype="i8"), 0)
            window.Unlock(0)
        comm.Barrier()

    def _fetch(self, increment: int) -> int:
        from mpi4py import MPI

        np = self._np
        result = np.zeros(1, dtype="i8")
        op = MPI.SUM if increment else MPI.NO_OP
        self.window.Lock(0, MPI.LOCK_SHARED)
        self.window.Fetch_and_op(np.array([increment], dtype="i8"), result, 0, 0, op)
        self.window.Unlock(0)
        return int(result[0])

    def fetch_next(self) -> int:
        """The next unstarted index (each index is handed out once)."""
        return self._fetch(1)

    def stop(self, past: int) -> None:
        """Move the counter past ``past``: no rank starts another item."""
        self._fetch(past + 1)

    def peek(self) -> int:
        """How many indices have been handed out so far."""
        return self._fetch(0)

    def free(self) -> None:
        self.window.Free()   # collective: every rank gets here before the allgather


def _shared_counter(comm):
    """A :class:`_SharedCounter` on ``comm``, or None if RMA windows are unavailable."""
    try:
        from mpi4py import MPI
        window = MPI.Win.Allocate(8 if comm.rank == 0 else 0, 8, comm=comm)
    except Exception:  # noqa: BLE001 - fall back to the static schedule
        return None
    return _SharedCounter(comm, window)


# -- Ctrl-C / SIGTERM under mpirun (#43 item 7) -------------------------------------------
#: rank 0's janitor: a small process (no tengfield, no MPI) that receives the signal's
#: byte straight from the interpreter's C-level handler (signal.set_wakeup_fd), so it
#: acts even while rank 0 holds the GIL (an import, a compiled kernel) or waits in an
#: MPI call; it removes what rank 0 told it (the staging directory, unless a move into
#: place is under way: its journal is undone by the next command; the lock and the
#: directories this command created, when empty) and prints the one line. Rank 0 ending
#: without a signal closes its pipe: the janitor leaves quietly.
_JANITOR = r"""
import json, os, select, shutil, sys, time
signals, commands, state, pending = int(sys.argv[1]), 0, {}, b""
while True:
    ready = select.select([signals, commands], [], [])[0]
    received = os.read(signals, 64) if signals in ready else b""
    if received:
        break
    if commands in ready:
        chunk = os.read(commands, 1 << 16)
        if not chunk:
            sys.exit(0)
        pending += chunk
        while b"\n" in pending:
            line, pending = pending.split(b"\n", 1)
            state = json.loads(line)
staging, target = state.get("staging"), state.get("target")
if staging and not os.path.lexists(os.path.join(staging, ".tengfield-tx")):
    for attempt in range(20):
        shutil.rmtree(staging, ignore_errors=True)
        if not os.path.lexists(staging):
            break
        time.sleep(0.01)
for d in state.get("created", []):
    try:
        if set(os.listdir(d)) <= {".tengfield.lock"}:
            if os.path.lexists(os.path.join(d, ".tengfield.lock")):
                os.unlink(os.path.join(d, ".tengfield.lock"))
            os.rmdir(d)
    except OSError:
        break
os.write(2, b"tengfield: interrupted\n")
sys.exit(received[0])     # rank 0 exits with 128 + this (_follow_janitor)
"""


class SignalExit:
    """Under ``mpirun -n N``: SIGINT or SIGTERM (Open MPI 4's mpirun forwards both to every
    rank as SIGTERM, and SIGKILLs them a second later) ends every rank at once, also one
    blocked in an MPI call that waits for another rank, with nothing left behind:

    * rank 0 hands the signal to its janitor (:data:`_JANITOR`, told what to remove by
      :meth:`clean_up`), which removes the staging directory, the lock and a new -o and
      prints ``tengfield: interrupted`` once, whatever rank 0 is doing;
    * every rank's main thread, when it next runs Python, stops writing and exits with
      128 + the signal (130 for SIGINT, 143 for SIGTERM; rank 0 after its janitor is
      through), except while :meth:`moving` the set into place, which completes first;
      a watcher thread ends a rank blocked in an MPI call (the signal's byte through
      :func:`signal.set_wakeup_fd`) the same way.
    """

    SIGNALS = ("SIGINT", "SIGTERM")

    def __init__(self, rank: int):
        import threading

        self.rank = rank
        self._moving = threading.Lock()
        self._janitor = None
        self._installed = False

    def clean_up(self, *, staging=None, created=()) -> None:
        """What a signal removes (rank 0): ``staging``, and the directories in
        ``created`` (deepest first) when they hold nothing but the lock."""
        if self._janitor is None:
            return
        import json

        try:
            self._janitor.stdin.write((json.dumps(
                {"staging": None if staging is None else str(staging),
                 "created": [str(d) for d in created]}) + "\n").encode())
            self._janitor.stdin.flush()
        except OSError:
            pass

    def moving(self):
        """``with exit.moving(): commit()``: a signal lets the move into place finish."""
        return self._moving

    def install(self) -> "SignalExit":
        import signal
        import threading

        if threading.current_thread() is not threading.main_thread():
            return self
        read_end, write_end = os.pipe()
        os.set_blocking(write_end, False)
        if self.rank == 0:
            self._janitor = _start_janitor(read_end)
        if self._janitor is None:    # the ranks > 0 (and rank 0 without a janitor)
            threading.Thread(target=self._watch, args=(read_end,), daemon=True,
                             name="tengfield-signal-exit").start()
        else:                        # rank 0 ends when its janitor is through
            os.close(read_end)
            threading.Thread(target=self._follow_janitor, daemon=True,
                             name="tengfield-signal-exit").start()
        self._previous = {name: signal.signal(getattr(signal, name), self._exit_in_main)
                          for name in self.SIGNALS}
        self._previous_fd = signal.set_wakeup_fd(write_end, warn_on_full_buffer=False)
        self._write_end = write_end
        self._installed = True
        return self

    def uninstall(self) -> None:
        """The handlers as they were; the janitor leaves (its pipe closes)."""
        import signal

        if not self._installed:
            return
        signal.set_wakeup_fd(self._previous_fd)
        for name, previous in self._previous.items():
            signal.signal(getattr(signal, name), previous)
        os.close(self._write_end)
        if self._janitor is not None:
            try:
                self._janitor.stdin.close()
                self._janitor.wait(timeout=5.0)
            except Exception:  # noqa: BLE001 - it leaves by itself on the closed pipe
                pass
        self._installed = False

    def _exit_in_main(self, signum, frame) -> None:
        """The main thread's handler: exit (rank 0: once its janitor is through), unless
        the set is being moved into place (the janitor, or the next signal, ends it)."""
        if self._moving.locked():
            return
        self._finish(signum)

    def _watch(self, read_end: int) -> None:
        """Blocks until a signal's byte arrives, or the pipe's end (:meth:`uninstall`
        closed its write end): then it leaves (it used to read EOF again and again, a
        core spun for the rest of the process after every in-process use)."""
        data = os.read(read_end, 1)            # b"" only at the end of the pipe
        if not data:
            os.close(read_end)
            return
        self._moving.acquire(timeout=2.0)      # a move into place under way ends first
        self._finish(data[0])

    def _follow_janitor(self) -> None:
        """Rank 0, also while blocked in an MPI call: exit once the janitor has cleaned
        up after a signal (its exit code: the signal; 0: rank 0 ended by itself)."""
        import signal

        code = self._janitor.wait()
        if code in (signal.SIGINT, signal.SIGTERM) and self._installed:
            self._moving.acquire(timeout=2.0)
            os._exit(128 + code)

    def _finish(self, signum: int) -> None:
        if self._janitor is not None:
            try:
                self._janitor.wait(timeout=5.0)
            except Exception:  # noqa: BLE001 - the exit must happen
                pass
        elif self.rank == 0:   # straight to the descriptor: the main thread may hold sys.stderr
            os.write(2, b"tengfield: interrupted\n")
        os._exit(128 + signum)


def _start_janitor(signals: int):
    """Rank 0's janitor process (:data:`_JANITOR`) reading ``signals``, or None."""
    import subprocess

    try:
        return subprocess.Popen([sys.executable, "-I", "-S", "-c", _JANITOR, str(signals)],
                                stdin=subprocess.PIPE, pass_fds=(signals,),
                                start_new_session=True)   # not in the launcher's kill
    except OSError:
        return None
