"""Command-line interface: ``tengfield <command> ...``.

Each command lives in ``tengfield.commands.<name>`` with a ``register``
function; those modules import heavy dependencies only inside their
handlers, so ``tengfield dynamics`` never loads dolfinx or gmsh.

What every command gets from here, without code of its own:

* ``-o DIR`` is created/checked before any computation and written
  all-or-nothing through :class:`tengfield.outputs.StagedOutput` (``-o FILE``:
  its directory is checked);
* ``--jobs`` is bounded to ``[1, 4 x cores]``;
* bad input (:class:`~tengfield.errors.TengfieldError`) is one line
  ``tengfield: error: ...`` and exit 2; an I/O fault (full disk, ...) one line
  and exit 1; Ctrl-C ``tengfield: interrupted`` and exit 130;
* only tengfield's own lines on stderr: library logging (ffcx/setuptools JIT
  ``INFO:root:running build_ext`` and compiler lines) is silenced below
  warnings, and warnings print as ``tengfield: warning: ...``; VTK renders
  off screen.
"""
from __future__ import annotations

import argparse
import importlib
import io
import logging
import os
import re
import sys
import warnings

from . import __version__
from .errors import TengfieldError

# command modules, in the order `tengfield --help` lists them
COMMAND_MODULES = [
    "scene",
    "info",
    "dynamics",
    "field",
    "run",
    "breakdown",
    "precompute",
    "sweep",
    "report",
    "fit",
    "design",
]



def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="tengfield",
        description="Bouncing-ball TENG: impact dynamics, dolfinx electrostatics, "
                    "V_OC / Q_SC / I_SC waveforms. Without SCENE every command uses "
                    "the embedded default scene (the paper's device).")
    parser.add_argument("--version", action="version", version=f"tengfield {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMAND_MODULES:
        importlib.import_module(f"tengfield.commands.{name}").register(sub)
    return parser


# -- quiet, readable output --------------------------------------------------------------
_WARNING_LINE = re.compile(r"^.*?:\d+: (\w+): (.*)$")
_STAGING_IN_PATH = re.compile(r"/\.tengfield-staging-[^/]+")


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


def configure_output() -> None:
    """Quiet stderr: only tengfield's own lines (see the module docstring).

    Idempotent; called by :func:`main` before any command module runs, i.e.
    before ffcx, setuptools, pyvista or VTK are imported.
    """
    # the CLI only renders PNG files: never ask for an X server (VTK's
    # "bad X server connection"); pyvista reads this at import
    os.environ["PYVISTA_OFF_SCREEN"] = "true"
    if not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        # no display: VTK (>= 9.4 wheels) would try X first and print "bad X server
        # connection" before falling back; ask for the headless EGL window first
        os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
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


# -- output locations ------------------------------------------------------------------
def _output_option(parser: argparse.ArgumentParser, command: str):
    """The ``-o`` action of ``command``'s subparser, or None."""
    for action in parser._subparsers._group_actions:          # noqa: SLF001 - argparse API
        sub = getattr(action, "choices", {}).get(command)
        if sub is None:
            continue
        for a in sub._actions:                                    # noqa: SLF001
            if "-o" in a.option_strings:
                return a
    return None


def _mpi_size() -> int:
    for key in ("OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE", "MPI_LOCALNRANKS"):
        value = os.environ.get(key)
        if value and value.isdigit():
            return int(value)
    return 1


def _mpi_rank() -> int:
    for key in ("OMPI_COMM_WORLD_RANK", "PMI_RANK", "PMIX_RANK"):
        value = os.environ.get(key)
        if value and value.isdigit():
            return int(value)
    return 0


class _PathRewriter(io.TextIOBase):
    """Writes through to ``stream`` with the staging directory's path shown as DIR."""

    def __init__(self, stream, staging: str, target: str):
        self._stream, self._staging, self._target = stream, staging, target

    def write(self, text):
        return self._stream.write(text.replace(self._staging, self._target))

    def flush(self):
        # also called when the rewriter is collected (IOBase.__del__ -> close), possibly
        # after the stream it wraps was closed (pytest's capture, Python 3.13)
        if not getattr(self._stream, "closed", False):
            self._stream.flush()

    def isatty(self):
        return self._stream.isatty()

    def fileno(self):
        return self._stream.fileno()

    @property
    def encoding(self):
        return getattr(self._stream, "encoding", "utf-8")


def _run_command(parser: argparse.ArgumentParser, args) -> int:
    if _mpi_size() > 1 and getattr(args, "one_process", None):
        # one process's work: N ranks would each do it and write the same files at once
        if _mpi_rank() == 0:
            print(f"tengfield: error: tengfield {args.command} runs on one process "
                  f"({args.one_process}): start it without mpirun", file=sys.stderr)
        return 2
    if hasattr(args, "jobs"):   # before any output directory is made
        from ._mpi import check_jobs
        from .commands._common import world_if_parallel
        check_jobs(args.jobs, world_if_parallel())
    action = _output_option(parser, args.command)
    target = getattr(args, action.dest, None) if action is not None else None
    if target is None:
        return int(args.func(args) or 0)
    from .outputs import StagedOutput, ensure_directory, ensure_file_parent

    option = action.option_strings[0]
    if action.metavar == "FILE":
        ensure_file_parent(target, option)
        return int(args.func(args) or 0)
    if _mpi_size() > 1:
        # under mpirun every rank runs this: check/create only, the command's
        # rank 0 writes (no staging across ranks)
        ensure_directory(target, option)
        return int(args.func(args) or 0)
    staged = StagedOutput(target, option=option)
    staging = str(staged.open())
    setattr(args, action.dest, staging)
    out, err = sys.stdout, sys.stderr
    sys.stdout = _PathRewriter(out, staging, str(target))
    sys.stderr = _PathRewriter(err, staging, str(target))
    try:
        code = int(args.func(args) or 0)
    except OSError as exc:
        staged.abort()
        if exc.filename is None:     # e.g. a full disk while a PNG was flushed: the
            exc.filename = target    # directory written is the one to name
        raise
    except BaseException:
        staged.abort()
        raise
    finally:
        sys.stdout, sys.stderr = out, err
        setattr(args, action.dest, target)
    if code == 0:
        staged.commit()
    else:
        staged.abort()
    return code


def main(argv: list[str] | None = None) -> int:
    configure_output()
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        return _run_command(parser, args)
    except TengfieldError as exc:
        print(f"tengfield: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("tengfield: interrupted", file=sys.stderr)
        return 130
    except OSError as exc:   # full disk, vanished directory...: a fault, not a bug report
        where = f": {_STAGING_IN_PATH.sub('', str(exc.filename))}" if exc.filename else ""
        print(f"tengfield: error: {exc.strerror or exc}{where}", file=sys.stderr)
        return 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
