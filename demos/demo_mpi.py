"""MPI for the demos (not a demo itself).

Under ``mpirun -n N`` every rank runs the whole demo: the field solves are spread
over the ranks (:func:`world`, passed as ``comm`` to tengfield), every rank gets
the same numbers, and rank 0 alone writes files (:func:`is_root`). A serial run
(no mpirun) never imports mpi4py.

    mpirun -n 2 .venv/bin/python demos/electrical_waveforms.py --fast
"""
from __future__ import annotations

import os


def world_size() -> int:
    """Ranks of the ``mpirun`` this process belongs to (1 outside mpirun)."""
    return int(os.environ.get("OMPI_COMM_WORLD_SIZE") or os.environ.get("PMI_SIZE") or 1)


def world():
    """``MPI.COMM_WORLD`` under ``mpirun -n N`` with N > 1, else None (a serial run)."""
    if world_size() <= 1:
        return None
    from mpi4py import MPI
    return MPI.COMM_WORLD


def is_root() -> bool:
    """True on the rank that writes files (rank 0; the only one outside mpirun)."""
    comm = world()
    return comm is None or comm.rank == 0
