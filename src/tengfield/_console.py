"""What tengfield prints on stderr: its own lines only.

:func:`configure_output` (called by :func:`tengfield.cli.main` before any command
module runs, and by the processes tengfield starts: the figure process, the design
workers) silences library logging below warnings (ffcx/setuptools JIT
``INFO:root:running build_ext`` and compiler lines), prints warnings and logged
errors as one line each (``tengfield: warning: ...``, :func:`warning_text`) and
makes VTK render off screen.

:func:`progress_bar` is the one progress bar of every long command (sweep, map,
report, precompute, ensembles, fit's scans, design): ``done/total`` and an ETA on
stderr, only on a terminal, on MPI rank 0 and without ``--quiet``
(:func:`set_quiet`, or ``TENGFIELD_QUIET=1``).
"""
from __future__ import annotations

import logging
import os
import re
import sys
import warnings

_WARNING_LINE = re.compile(r"^.*?:\d+: (\w+): (.*)$")


def warning_text(message) -> str:
    """One line for a warning: its first non-empty line, file/line prefixes dropped."""
    lines = [ln.strip() for ln in str(message).splitlines() if ln.strip()]
    text = lines[0] if lines else str(message).strip()
    match = _WARNING_LINE.match(text)
    return match.group(2) if match else text


class _TengfieldFormatter(logging.Formatter):
    def format(self, record: logging.LogRecord) -> str:
        kind = "error" if record.levelno >= logging.ERROR else "warning"
        return f"tengfield: {kind}: {warning_text(record.getMessage())}"


class _QuietHandler(logging.StreamHandler):
    """Root handler: warnings and errors only, one tengfield line each.

    It follows ``sys.stderr`` at emit time (so redirections and tests see it)."""

    def __init__(self):
        super().__init__()
        self.setLevel(logging.WARNING)
        self.setFormatter(_TengfieldFormatter())

    @property
    def stream(self):
        return sys.stderr

    @stream.setter
    def stream(self, value):  # logging.StreamHandler.__init__ assigns it
        pass


def _showwarning(message, category, filename, lineno, file=None, line=None):
    stream = file if file is not None else sys.stderr
    try:
        stream.write(f"tengfield: warning: {warning_text(message)}\n")
    except (OSError, ValueError):  # a closed stream: nothing to tell
        pass


def headless_vtk() -> None:
    """Without a display, ask VTK for its headless EGL window first: VTK (>= 9.4
    wheels) would try X first and print "bad X server connection" on stderr before
    falling back. Called by :func:`configure_output` (the CLI) and by ``import
    tengfield`` (scripts, notebooks: their field.png renders quietly too); VTK reads it
    when a render window is made. A display, or the user's own setting, is left alone."""
    if not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")


def configure_output() -> None:
    """Quiet stderr: only tengfield's own lines (see the module docstring).

    Idempotent; called by :func:`tengfield.cli.main` before any command module runs, i.e.
    before ffcx, setuptools, pyvista or VTK are imported.
    """
    # the CLI only renders PNG files: never ask for an X server (VTK's
    # "bad X server connection"); pyvista reads this at import
    os.environ["PYVISTA_OFF_SCREEN"] = "true"
    headless_vtk()
    root = logging.getLogger()
    if not any(isinstance(h, _QuietHandler) for h in root.handlers):
        # a handler on the root first: ffcx's logging.basicConfig() then adds none,
        # and setuptools' set_threshold (root level INFO during JIT builds) stays
        # invisible because this handler passes WARNING and above only
        for handler in list(root.handlers):
            if type(handler) is logging.StreamHandler:   # a basicConfig() of a library
                root.removeHandler(handler)
        root.addHandler(_QuietHandler())
    for noisy in ("distutils", "setuptools", "ffcx", "UFL", "ufl", "FFCX", "numba", "matplotlib",
                  "PIL", "h5py"):
        logging.getLogger(noisy).setLevel(logging.ERROR)
    logging.captureWarnings(False)
    warnings.showwarning = _showwarning
    try:   # no progress-bar monitor thread: a worker pool may fork this process
        import tqdm   # (tengfield._pool forks only a process with one thread)
        tqdm.tqdm.monitor_interval = 0
    except ImportError:   # pragma: no cover - a dependency
        pass


# -- progress --------------------------------------------------------------------------
_quiet = False


def set_quiet(quiet: bool = True) -> None:
    """``--quiet``: no progress bar in this process (warnings and errors still print)."""
    global _quiet
    _quiet = bool(quiet)


def progress_shown(enabled: bool = True, comm=None) -> bool:
    """Whether a progress bar prints: ``enabled``, stderr a terminal, rank 0 of ``comm``,
    not ``--quiet`` / ``TENGFIELD_QUIET``."""
    if not enabled or _quiet or os.environ.get("TENGFIELD_QUIET", "") not in ("", "0"):
        return False
    if comm is not None and comm.Get_rank() != 0:
        return False
    try:
        if sys.stderr.isatty():
            return True
        # under mpirun a rank's stderr is a pipe to the launcher even on a terminal: the
        # (z, r) table's minutes of 3D solves were silent under `mpirun -n 2` (issue #40)
        return _launcher_on_a_terminal()
    except (AttributeError, ValueError):   # a closed or replaced stream
        return False


#: process names of MPI launchers (their daemons are looked through to the launcher)
_LAUNCHERS = ("mpirun", "mpiexec", "orterun", "prterun", "mpiexec.hydra")
_DAEMONS = ("orted", "prted", "hydra_pmi_proxy")


def _launcher_on_a_terminal() -> bool:
    """Whether this process was started by an MPI launcher (an ancestor named in
    :data:`_LAUNCHERS`, through its daemons) whose own stderr is a terminal (Linux
    ``/proc``; False wherever that cannot be read)."""
    if not any(name in os.environ for name in ("OMPI_COMM_WORLD_SIZE", "PMI_SIZE",
                                               "PMIX_RANK")):
        return False
    pid = os.getpid()
    try:
        for _ in range(6):
            with open(f"/proc/{pid}/stat") as stat:
                pid = int(stat.read().rsplit(")", 1)[1].split()[1])
            if pid <= 1:
                return False
            with open(f"/proc/{pid}/comm") as comm:
                name = comm.read().strip()
            if name in _LAUNCHERS:
                target = os.path.realpath(f"/proc/{pid}/fd/2")
                return target.startswith(("/dev/pts/", "/dev/tty"))
            if name not in _DAEMONS:
                return False
    except (OSError, ValueError, IndexError):
        return False
    return False


def progress_bar(total: int | None, what: str, enabled: bool = True, *, unit: str = "task",
                 comm=None, initial: int = 0):
    """A progress bar on stderr: ``what: 40%|####  | done/total [elapsed<ETA, rate]``.

    Shown only when :func:`progress_shown` (else every call on it does nothing).
    Use as ``bar.update(n)`` (callable as the ``progress`` argument of
    :func:`tengfield._mpi.farm` / ``run_tasks``), ``bar.total = n`` to grow it,
    ``bar.close()`` (or ``with progress_bar(...) as bar:``).
    """
    from tqdm import tqdm

    shown = progress_shown(enabled, comm)
    width = _terminal_width() if shown else 0
    return tqdm(total=total, desc=what, unit=unit, initial=initial, file=sys.stderr,
                disable=not shown, dynamic_ncols=width > 0, ncols=None if width > 0 else 80,
                nrows=None if width > 0 else 24)


def _terminal_width() -> int:
    """Columns of the terminal on stderr; 0 when it does not say (a bare pseudo-terminal:
    tqdm would then draw an empty line)."""
    try:
        return os.get_terminal_size(sys.stderr.fileno()).columns
    except (AttributeError, OSError, ValueError):
        return 0


# -- a closed stdout -------------------------------------------------------------------
#: exit status of a command whose stdout reader went away (128 + SIGPIPE, as a Unix tool
#: killed by SIGPIPE reports it)
CLOSED_PIPE_STATUS = 141


class PipeSafeStdout:
    """stdout that survives its reader going away (``tengfield run ... | head -1``).

    The first write or flush that fails with EPIPE (BrokenPipeError) marks the stream
    :attr:`broken` and drops that and every later text: the command goes on and writes
    its files; :func:`tengfield.cli.main` then exits with :data:`CLOSED_PIPE_STATUS` and
    nothing on stderr. Every other error of the stream is raised as before."""

    def __init__(self, stream):
        self._stream = stream
        self.broken = False

    def _guard(self, call, *args):
        if self.broken:
            return None
        _ignore_sigpipe()
        try:
            return call(*args)
        except BrokenPipeError:
            self.broken = True
            _silence_fd(self._stream)
            return None

    def write(self, text):
        self._guard(self._stream.write, text)
        return len(text)

    def flush(self):
        if not getattr(self._stream, "closed", False):
            self._guard(self._stream.flush)

    def __getattr__(self, name):      # isatty, fileno, encoding, buffer, ...
        return getattr(self._stream, name)


def _ignore_sigpipe() -> None:
    """SIGPIPE ignored again (as Python starts): PETSc, once initialised, installs its own
    handler, which turns the EPIPE of a write to a closed pipe into an MPI abort or a
    crash instead of a BrokenPipeError. Only the main thread may set a handler. Nothing
    while Python shuts down (a wrapper collected then flushes: Python 3.13 refuses
    imports by that time)."""
    if sys.is_finalizing():
        return
    import signal
    import threading

    if threading.current_thread() is threading.main_thread() and hasattr(signal, "SIGPIPE"):
        try:
            signal.signal(signal.SIGPIPE, signal.SIG_IGN)
        except (OSError, ValueError):
            pass


def _silence_fd(stream) -> None:
    """Point the stream's file descriptor at /dev/null: what its buffer still holds (and
    the interpreter's flush at exit) goes nowhere instead of raising again."""
    try:
        fd = stream.fileno()
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, fd)
        os.close(null)
    except (OSError, ValueError, AttributeError):
        pass


def python_only_stdout(stream):
    """When ``stream`` writes to file descriptor 1 and that is a pipe (``| head -1``):
    give the C libraries (gmsh, PETSc: they abort or die of SIGPIPE when a write to a
    closed pipe fails, and tengfield shows none of their lines) /dev/null as fd 1, and
    return a text stream for Python's own lines on a duplicate of the pipe, plus the
    function that puts fd 1 back; ``None`` otherwise (a terminal, a file, a capture, or a
    process started by mpirun, whose launcher owns fd 1)."""
    import io
    import stat

    from ._mpi import launched_size

    try:
        if stream.fileno() != 1 or not stat.S_ISFIFO(os.fstat(1).st_mode):
            return None
    except (AttributeError, OSError, ValueError, io.UnsupportedOperation):
        return None
    if launched_size() > 1:
        return None
    stream.flush()
    keep = os.dup(1)
    null = os.open(os.devnull, os.O_WRONLY)
    os.dup2(null, 1)
    os.close(null)
    text = io.TextIOWrapper(io.FileIO(keep, "w", closefd=False),
                            encoding=getattr(stream, "encoding", None) or "utf-8",
                            errors=getattr(stream, "errors", None) or "strict")

    def restore(broken: bool) -> None:
        try:
            text.flush()
        except (OSError, ValueError):
            pass
        if not broken:          # the pipe back on fd 1 (an in-process caller goes on)
            os.dup2(keep, 1)
        os.close(keep)

    return text, restore
