"""Starting gmsh (both solvers start it through :func:`initialize`).

The gmsh wheel carries its own PETSc, which checks at start-up whether the process
holds both Open MPI and MPICH: it looks for the symbols ``ompi_mpi_init`` and
``MPL_exit``. Open MPI 5 (Debian 13) exports both itself, so every ``gmsh.initialize``
after dolfinx is loaded printed "PETSc Error --- Application was linked against both
OpenMPI and MPICH based MPI libraries and will not run correctly": a false alarm (there
is one MPI, and the solves are right), written by C to file descriptor 2. That line is
dropped; anything else gmsh writes there passes through.
"""
from __future__ import annotations

import contextlib
import os
import sys
import tempfile

#: the false alarm of the PETSc inside the gmsh wheel under Open MPI 5
FALSE_ALARM = b"PETSc Error --- Application was linked against both OpenMPI and MPICH"


def initialize(argv=(), **kwargs) -> None:
    """``gmsh.initialize(list(argv), **kwargs)`` without the false alarm on stderr."""
    import gmsh

    with _without_line(FALSE_ALARM):
        gmsh.initialize(list(argv), **kwargs)


@contextlib.contextmanager
def _without_line(marker: bytes):
    """Capture what is written to file descriptor 2 meanwhile; pass on every line that
    does not contain ``marker``."""
    try:
        sys.stderr.flush()
    except (OSError, ValueError):
        pass
    saved = os.dup(2)
    with tempfile.TemporaryFile() as captured:
        os.dup2(captured.fileno(), 2)
        try:
            yield
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            captured.seek(0)
            kept = b"".join(line for line in captured.read().splitlines(keepends=True)
                            if marker not in line)
            if kept:
                os.write(2, kept)
