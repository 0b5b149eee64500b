"""Ctrl-C before the command line has set itself up (issue 54 item 14): while ``tengfield``
(or ``python -m tengfield.cli``) is still importing, SIGINT prints the one line a later
interrupt prints and exits 130, instead of a KeyboardInterrupt traceback from the middle
of an import. A library user (a script, a notebook) keeps Python's own KeyboardInterrupt:
the handler is put in place only when this process is the command line, and
:func:`tengfield.cli.main` hands SIGINT back to Python once it can clean up."""
from __future__ import annotations

import os
import signal
import sys


def _is_command_line() -> bool:
    argv = list(getattr(sys, "orig_argv", ()) or ())
    if "-m" in argv[:-1]:
        return argv[argv.index("-m") + 1] in ("tengfield", "tengfield.cli")
    return bool(sys.argv) and os.path.basename(sys.argv[0]) == "tengfield"


def _interrupted(signum, frame):   # noqa: ARG001 - the signal handler's signature
    os.write(2, b"tengfield: interrupted\n")
    os._exit(130)


def install() -> None:
    """The quick exit on SIGINT, for the command line's start-up only."""
    if _is_command_line() and signal.getsignal(signal.SIGINT) is signal.default_int_handler:
        try:
            signal.signal(signal.SIGINT, _interrupted)
        except ValueError:     # not the main thread: leave it
            pass


#: SIGINT has arrived since :func:`hand_back` (the command line's own handling)
_received = False


def note_interrupt() -> None:
    """Remember that an interrupt (SIGINT, or SIGTERM through the command line) came: a C
    extension being imported (numba's, numpy's C API) turns its KeyboardInterrupt into an
    ImportError with no cause to follow."""
    global _received
    _received = True


def _recorded(signum, frame):   # noqa: ARG001 - the signal handler's signature
    """Python's KeyboardInterrupt, remembered (:func:`note_interrupt`)."""
    note_interrupt()
    raise KeyboardInterrupt


def received() -> bool:
    """Whether an interrupt has arrived since :func:`hand_back`."""
    return _received


def hand_back() -> None:
    """KeyboardInterrupt on SIGINT again, as Python's own handler raises it (the command
    line's own handling takes over), remembered for :func:`received` (from now: each
    command starts with none received)."""
    global _received
    _received = False
    try:
        if signal.getsignal(signal.SIGINT) in (_interrupted, signal.default_int_handler):
            signal.signal(signal.SIGINT, _recorded)
    except ValueError:
        pass


install()
