"""Starting gmsh (both solvers start it through :func:`initialize`).

The gmsh wheel carries its own PETSc, which checks at start-up whether the process
holds both Open MPI and MPICH: it looks for the symbols ``ompi_mpi_init`` and
``MPL_exit``. Open MPI 5 (Debian 13) exports both itself, so every ``gmsh.initialize``
after dolfinx is loaded printed "PETSc Error --- Application was linked against both
OpenMPI and MPICH based MPI libraries and will not run correctly": a false alarm (there
is one MPI, and the solves are right), written by C to file descriptor 2. That line is
dropped; anything else gmsh writes there passes through.

Two more side effects of ``gmsh.initialize`` are undone here (issue #30, items 12, 13):

* it sets the C-level handlers of SIGTERM and SIGPIPE back to the default, under
  Python's: after any gmsh solve a SIGTERM killed the process (exit 143, no
  ``tengfield: interrupted``, a staging directory left) and a closed pipe killed it
  silently. Every signal's disposition is saved before and restored after
  (:func:`_kept_signal_handlers`);
* the FLTK inside the gmsh wheel writes ``~/.fltk/fltk.org/fltk.prefs`` at the first
  initialisation of a process: that one runs with ``HOME`` pointed at a temporary
  directory, removed after (:func:`_home_elsewhere`).
"""
from __future__ import annotations

import contextlib
import ctypes
import os
import shutil
import sys
import tempfile

#: the false alarm of the PETSc inside the gmsh wheel under Open MPI 5
FALSE_ALARM = b"PETSc Error --- Application was linked against both OpenMPI and MPICH"


def initialize(argv=(), **kwargs) -> None:
    """``gmsh.initialize(list(argv), **kwargs)`` without the false alarm on stderr."""
    import gmsh

    with _without_line(FALSE_ALARM), _kept_signal_handlers(), _home_elsewhere():
        gmsh.initialize(list(argv), **kwargs)


#: room for one ``struct sigaction`` (152 bytes on x86-64 and aarch64 glibc)
_SIGACTION_BYTES = 512


@contextlib.contextmanager
def _kept_signal_handlers():
    """Every signal's C-level disposition (``sigaction``) as it was before, afterwards."""
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        sigaction = libc.sigaction
    except (OSError, AttributeError):   # pragma: no cover - not a POSIX C library
        yield
        return
    saved = {}
    for signum in range(1, 32):
        buffer = ctypes.create_string_buffer(_SIGACTION_BYTES)
        if sigaction(signum, None, buffer) == 0:
            saved[signum] = buffer
    try:
        yield
    finally:
        for signum, buffer in saved.items():
            sigaction(signum, buffer, None)


_fltk_home_done = False


@contextlib.contextmanager
def _home_elsewhere():
    """``HOME`` a temporary directory meanwhile, at the first initialisation of this
    process only (FLTK's preferences file is written then; later ones write nothing)."""
    global _fltk_home_done
    if _fltk_home_done:
        yield
        return
    _fltk_home_done = True
    previous = os.environ.get("HOME")
    home = tempfile.mkdtemp(prefix="tengfield-gmsh-")
    os.environ["HOME"] = home
    try:
        yield
    finally:
        if previous is None:
            os.environ.pop("HOME", None)
        else:
            os.environ["HOME"] = previous
        shutil.rmtree(home, ignore_errors=True)


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
