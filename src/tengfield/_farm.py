"""The one task farm of every study (sweep, uncertainty, design, the ensemble):
:func:`run_tasks` spreads independent tasks over MPI ranks or worker processes."""
from __future__ import annotations

from typing import Callable, Sequence


def run_tasks(work: Callable, tasks: Sequence, *, comm=None, jobs: int | None = None,
              progress: Callable[[int], None] | None = None, mp_context: str | None = None) -> list:
    """``[work(task) for task in tasks]``, in order, spread over the workers at hand.

    * ``comm`` with more than one rank (``mpirun -n N``): the MPI task farm
      :func:`tengfield._mpi.farm` (dynamic schedule, every rank returns the
      whole list, an exception on any rank aborts all ranks with its message);
      ``jobs`` must be None or 1 (:func:`tengfield._mpi.check_jobs`).
    * otherwise ``jobs`` worker processes (default: all cores; ``work`` and
      the tasks must be picklable; ``mp_context``: a start method, default
      tengfield's one, :func:`tengfield._pool.pool_context`), or a plain loop for
      one job or one task.

    ``progress(n)``: called with the number of further tasks done (rank 0 only
    under MPI). Used by :func:`tengfield.sweeps.sweep`, the uncertainty and design studies and
    the ensemble.
    """
    import os

    from ._mpi import check_jobs, farm, size_of

    check_jobs(jobs, comm)
    tasks = list(tasks)
    if size_of(comm) > 1:
        return farm(comm, tasks, work, progress=progress)
    jobs = max(1, min(jobs or os.cpu_count() or 1, len(tasks)))
    results = []
    if jobs == 1:
        for task in tasks:
            results.append(work(task))
            if progress is not None:
                progress(1)
        return results
    from ._pool import process_pool
    with process_pool(jobs, mp_context) as pool:
        for result in pool.map(work, tasks):
            results.append(result)
            if progress is not None:
                progress(1)
    return results
