"""MPI task farm for independent jobs (e.g. one field solve per ball position).

Communicators are always passed in; nothing here touches ``COMM_WORLD``.
``comm`` may be any object with mpi4py's ``rank``, ``size``, ``allgather``
and ``Abort`` (``None`` means a serial run without MPI).
"""
from __future__ import annotations

import sys
import traceback
from typing import Any, Callable, Sequence


def rank_of(comm) -> int:
    return 0 if comm is None else int(comm.rank)


def size_of(comm) -> int:
    return 1 if comm is None else int(comm.size)


def abort_with_message(comm, message: str, code: int = 2) -> None:
    """Print ``message`` (rank-tagged) to stderr and abort every rank of ``comm``.

    Only used when ``comm`` has more than one rank: the other ranks may be
    blocked in a collective call, so raising would leave them hanging.
    """
    sys.stderr.write(f"tengfield: error on rank {rank_of(comm)} of {size_of(comm)}: {message}\n")
    sys.stderr.flush()
    comm.Abort(code)


def farm(comm, items: Sequence[Any], work: Callable[[Any], Any], *,
         progress: Callable[[int], None] | None = None) -> list:
    """``[work(item) for item in items]`` with the items spread over the ranks.

    Rank ``r`` runs items ``r, r + size, ...`` (each job must be serial, e.g.
    a field solve on ``COMM_SELF``); every rank returns the full result list
    in the order of ``items`` (``allgather``), so all ranks can take the same
    next decision. Results must be picklable.

    An exception in ``work`` on a multi-rank communicator prints the message
    with its rank and calls ``comm.Abort`` (never a hang); on one rank it is
    simply raised.

    ``progress(n)`` is called on rank 0 after each of its own jobs with the
    estimated number of jobs finished on all ranks since the last call.
    """
    size = size_of(comm)
    rank = rank_of(comm)
    mine = list(range(rank, len(items), size))
    results: dict[int, Any] = {}
    for index in mine:
        if size == 1:
            results[index] = work(items[index])
        else:
            try:
                results[index] = work(items[index])
            except BaseException as exc:  # noqa: BLE001 - every failure must abort all ranks
                detail = "".join(traceback.format_exception_only(type(exc), exc)).strip()
                if not isinstance(exc, Exception):
                    detail = f"interrupted ({type(exc).__name__})"
                abort_with_message(comm, detail)
                raise  # only reached with a fake communicator whose Abort returns
        if progress is not None and rank == 0:
            progress(size)
    if size == 1:
        return [results[i] for i in range(len(items))]
    gathered = comm.allgather(results)
    merged: dict[int, Any] = {}
    for part in gathered:
        merged.update(part)
    return [merged[i] for i in range(len(items))]
