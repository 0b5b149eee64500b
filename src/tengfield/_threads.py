"""One BLAS thread per process for the command line (issue #40).

tengfield runs in parallel by processes: MPI ranks, its process pools and the figure
process. numpy's bundled OpenBLAS starts a thread per core for a vector of more than a
few thousand entries, and on a machine whose cores those processes already keep busy
the threads wait for each other: on the 2-core machine a dot product of 20k entries
measured 5 µs alone, 84 µs beside one busy process and up to 5.7 ms beside two; a
60-candidate design under ``mpirun -n 2`` ran 0.97x as long with one BLAS thread
(paired runs, docs/design.md).
The library itself leaves the threads alone: a notebook keeps its own setting.
"""
from __future__ import annotations

import os

#: variables by which a user sets the BLAS threads; any of them set: left as it is
BLAS_THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS",
                         "BLIS_NUM_THREADS")


def limit_blas_threads(environ=os.environ) -> bool:
    """One BLAS thread in this process and in the processes it starts, unless the user
    set one of :data:`BLAS_THREAD_VARIABLES`; whether the limit was set (without
    threadpoolctl, in a venv made before it was a dependency: the children's only)."""
    if any(name in environ for name in BLAS_THREAD_VARIABLES):
        return False
    environ["OPENBLAS_NUM_THREADS"] = "1"      # what pools and the figure process inherit
    try:   # this process: numpy's BLAS is loaded already (a dependency since issue #40;
        from threadpoolctl import threadpool_limits   # a venv made before lacks it)
    except ImportError:
        return True
    threadpool_limits(1, user_api="blas")
    return True
