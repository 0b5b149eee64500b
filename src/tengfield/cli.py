"""Command-line interface: ``tengfield <command> ...``.

Each command lives in ``tengfield.commands.<name>`` with a ``register``
function; those modules import heavy dependencies only inside their
handlers, so ``tengfield dynamics`` never loads dolfinx or gmsh.

What every command gets from here, without code of its own:

* ``-o DIR`` is created/checked before any computation and written
  all-or-nothing through :class:`tengfield.files.directory.StagedOutput` (``-o FILE``:
  its directory is checked);
* ``--jobs`` is bounded to ``[1, 4 x cores]``;
* bad input (:class:`~tengfield.errors.TengfieldError`) is one line
  ``tengfield: error: ...`` and exit 2; an I/O fault (full disk, ...) one line
  and exit 1; Ctrl-C ``tengfield: interrupted`` and exit 130;
* under ``mpirun -n N`` (N > 1) the ranks agree on the input before any output
  directory exists and on the outcome at the end: rank 0 prints a bad input or an
  error once, every rank exits with the same code, and a failure on one rank alone
  ends every rank within seconds (:func:`_main_under_mpirun`);
* only tengfield's own lines on stderr: library logging (ffcx/setuptools JIT
  ``INFO:root:running build_ext`` and compiler lines) is silenced below
  warnings, and warnings print as ``tengfield: warning: ...``; VTK renders
  off screen (:func:`tengfield._console.configure_output`).
"""
from __future__ import annotations

import argparse
import contextlib
import importlib
import io
import os
import re
import sys
import traceback
from typing import NamedTuple

from . import __version__
from ._console import (CLOSED_PIPE_STATUS, PipeSafeStdout, configure_output,
                       python_only_stdout, set_quiet)
from ._mpi import launched_size
from ._threads import limit_blas_threads
from .errors import SceneError, TengfieldError

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
    "uncertainty",
]



def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="tengfield",
        description="Bouncing-ball TENG: impact dynamics, dolfinx electrostatics, "
                    "V_OC / Q_SC / I_SC waveforms. Without SCENE every command uses "
                    "the embedded default scene (the paper's device).")
    parser.add_argument("--version", action="version", version=f"tengfield {__version__}")
    parser.add_argument("--quiet", action="store_true",
                        help="no progress bars (anywhere on the line; warnings and errors "
                             "still print)")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMAND_MODULES:
        importlib.import_module(f"tengfield.commands.{name}").register(sub)
    for command in sub.choices.values():
        if any(a.dest in ("no_plots", "no_plot") for a in command._actions):  # noqa: SLF001
            command.add_argument(
                "--figure-format", default="png", metavar="png|pdf|svg",
                help="format of the figures written (default png; tengfield field, whose "
                     "field.png pyvista draws, offers png only)")
            command.add_argument(
                "--dpi", type=float, default=None, metavar="N",
                help="resolution of the figures written [dots per inch] (default: each "
                     "figure's own, 110-120; e.g. 300 for a paper); field.png scales with it")
        if any(a.dest == "scene" for a in command._actions):     # noqa: SLF001
            command.add_argument(
                "--set", action="append", default=[], metavar="SECTION.KEY=VALUE",
                dest="settings",
                help="set one scene key as in the file, e.g. --set excitation.frequency_hz=30 "
                     "--set circuit.kind=rectifier (repeatable; checked like the file)")
    return parser


def _apply_settings(args) -> None:
    """``--set section.key=value``: the command gets the scene (file or default) with
    them applied, checked as the same keys in the file (raises SceneError); ``--dpi``
    and ``--figure-format``: how every figure of the command is saved (checked here,
    before any output exists, also against a command's own ``figure_formats``; reset by
    every call)."""
    from .files import set_figure_dpi, set_figure_format

    try:
        set_figure_dpi(getattr(args, "dpi", None))
        set_figure_format(getattr(args, "figure_format", "png"))
    except ValueError as exc:
        raise SceneError(str(exc)) from None
    only = getattr(args, "figure_formats", None)     # a command whose figures have one format
    fmt = str(getattr(args, "figure_format", "png")).lower().lstrip(".")
    drawn = not (getattr(args, "no_plot", False) or getattr(args, "no_plots", False))
    if only and fmt not in only and drawn:
        raise SceneError(f"--figure-format {fmt!r} is not offered by tengfield {args.command}: "
                         f"its figures are drawn by pyvista as {', '.join(only)} only "
                         f"(omit --figure-format, or --no-plots)")
    settings = getattr(args, "settings", None)
    if settings:
        from .scene import load_scene, with_settings
        from .scene.limits import SteadyWindowError

        base = load_scene(args.scene)
        try:
            args.scene = with_settings(base, settings)
        except SteadyWindowError as exc:
            extend = getattr(args, "extend_settling", None)   # run: as sweep does (#53)
            if extend is None:
                raise
            args.scene, args.settling_extended = extend(base, settings, exc)


#: a staging directory's part of a path, left out of an error line (it names DIR)
_STAGING_IN_PATH = re.compile(r"/\.tengfield-staging-[^/]+")


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


#: a line that says files were written ("wrote DIR/run.h5, ...", "3 rows; wrote ...")
_WROTE = re.compile(r"(^|[\s;,(])wrote\s")


class _PathRewriter(io.TextIOBase):
    """Writes through to ``stream`` with the staging directory's path shown as DIR; a line
    saying "wrote DIR/..." is held until the set is in place (:meth:`release`) and
    dropped if it never is (#43 item 9: it named files that were not written)."""

    def __init__(self, stream, staging: str, target: str):
        self._stream, self._staging, self._target = stream, staging, target
        self._partial = ""      # the start of a line that says "wrote"
        self._held: list[str] = []

    def write(self, text):
        shown = text.replace(self._staging, self._target)
        pending = self._partial + shown
        self._partial = ""
        lines = pending.split("\n")
        for line in lines[:-1]:
            if _WROTE.search(line) and self._target in line:
                self._held.append(line + "\n")
            else:
                self._stream.write(line + "\n")
        if _WROTE.search(lines[-1]):
            self._partial = lines[-1]          # held until its line ends
        elif lines[-1]:
            self._stream.write(lines[-1])
        return len(text)

    def release(self, written: bool = True) -> None:
        """The held "wrote" lines, printed once the set is in place (``written``) or
        dropped."""
        held, self._held = self._held + ([self._partial] if self._partial else []), []
        self._partial = ""
        if written:
            for line in held:
                self._stream.write(line)
            self.flush()

    def flush(self):
        # also called when the rewriter is collected (IOBase.__del__ -> close), possibly
        # after the stream it wraps was closed (pytest's capture, Python 3.13)
        if not getattr(self._stream, "closed", False) and not sys.is_finalizing():
            self._stream.flush()

    def isatty(self):
        return self._stream.isatty()

    def fileno(self):
        return self._stream.fileno()

    @property
    def encoding(self):
        return getattr(self._stream, "encoding", "utf-8")


def _run_command(parser: argparse.ArgumentParser, args) -> int:
    """One process (under mpirun -n N > 1: :func:`_main_under_mpirun`)."""
    if hasattr(args, "jobs"):   # before any output directory is made
        from ._mpi import check_jobs, world_if_parallel
        from ._pool import start_early
        check_jobs(args.jobs, world_if_parallel())
        start_early(args.jobs)   # the worker pool's server loads while the input is read
    action = _output_option(parser, args.command)
    target = getattr(args, action.dest, None) if action is not None else None
    if target is None:
        return int(args.func(args) or 0)
    from .files.directory import StagedOutput, ensure_file_parent

    option = action.option_strings[0]
    if action.metavar == "FILE":
        ensure_file_parent(target, option)
        return int(args.func(args) or 0)
    from .files.directory import record_command, refuse_another_commands_directory

    refuse_another_commands_directory(target, args.command, option)
    staged = StagedOutput(target, option=option)
    staging = str(staged.open())
    try:
        record_command(staging, args.command)
    except BaseException:
        staged.abort()
        raise
    setattr(args, action.dest, staging)
    out, err = sys.stdout, sys.stderr
    rewriters = (_PathRewriter(out, staging, str(target)),
                 _PathRewriter(err, staging, str(target)))
    sys.stdout, sys.stderr = rewriters
    try:
        code = int(args.func(args) or 0)
    except OSError as exc:
        _release(rewriters, False)
        staged.abort()
        if exc.filename is None:     # e.g. a full disk while a PNG was flushed: the
            exc.filename = target    # directory written is the one to name
        raise
    except BaseException:
        _release(rewriters, False)
        staged.abort()
        raise
    finally:
        sys.stdout, sys.stderr = out, err
        setattr(args, action.dest, target)
    if code == 0:
        try:
            staged.commit()
        except BaseException:
            _release(rewriters, False)
            staged.abort()     # a new DIR goes again (the previous set was put back)
            raise
        _release(rewriters, True)     # "wrote ..." only now that the files are there
    else:
        _release(rewriters, False)    # nothing was moved into place
        staged.abort()
    return code


def _release(rewriters, written: bool) -> None:
    for rewriter in rewriters:
        if isinstance(rewriter, _PathRewriter):
            rewriter.release(written)


@contextlib.contextmanager
def _sigterm_as_interrupt():
    """SIGTERM (``kill``, a batch system's time limit) ends a command as Ctrl-C does:
    ``tengfield: interrupted``, exit 130, -o DIR keeps its previous content, no staging
    directory left, worker pools stopped (:func:`tengfield._pool.process_pool`). Only in
    the main thread of a process that left SIGTERM at its default (a single process:
    under mpirun the launcher stops the ranks itself). A worker process forked while it
    is installed dies of SIGTERM quietly, as with the default."""
    import os
    import signal
    import threading

    if (threading.current_thread() is not threading.main_thread()
            or signal.getsignal(signal.SIGTERM) is not signal.SIG_DFL):
        yield
        return
    owner = os.getpid()

    def interrupt(signum, frame):
        if os.getpid() != owner:          # a forked worker: die as the default would
            signal.signal(signal.SIGTERM, signal.SIG_DFL)
            os.kill(os.getpid(), signal.SIGTERM)
            return
        from ._early_interrupt import note_interrupt
        note_interrupt()
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGTERM, interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def _take_quiet(argv) -> list[str]:
    """``argv`` without ``--quiet`` (accepted before or after the command; see
    :func:`tengfield._console.set_quiet`)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    end = argv.index("--") if "--" in argv else len(argv)
    if "--quiet" in argv[:end]:
        set_quiet(True)
        argv = [a for a in argv[:end] if a != "--quiet"] + argv[end:]
    return argv


def main(argv: list[str] | None = None) -> int:
    """Run one command; a stdout whose reader went away (``| head -1``) stops the
    printing, not the command: its files are written, and the exit status is
    :data:`~tengfield._console.CLOSED_PIPE_STATUS` with nothing on stderr."""
    stdout = sys.stdout
    split = None if isinstance(stdout, PipeSafeStdout) else python_only_stdout(stdout)
    safe = stdout if isinstance(stdout, PipeSafeStdout) else PipeSafeStdout(
        stdout if split is None else split[0])
    sys.stdout = safe
    try:
        code = _main(argv)
        safe.flush()
    finally:
        if sys.stdout is safe:
            sys.stdout = stdout
        if split is not None:
            split[1](safe.broken)
    return CLOSED_PIPE_STATUS if safe.broken and code == 0 else code


def _main(argv: list[str] | None = None) -> int:
    configure_output()
    limit_blas_threads()
    parser = build_parser()
    argv = _take_quiet(argv)
    if launched_size() > 1:
        from ._early_interrupt import hand_back
        hand_back()   # _mpi's own SIGINT/SIGTERM handling from here
        return _main_under_mpirun(parser, argv, _launched_world())
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        from ._early_interrupt import hand_back
        hand_back()   # from here an interrupt is caught here and cleaned up
        with _sigterm_as_interrupt():
            _apply_settings(args)
            return _run_command(parser, args)
    except TengfieldError as exc:
        print(f"tengfield: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return _interrupted()
    except OSError as exc:   # full disk, vanished directory...: a fault, not a bug report
        if _caused_by_interrupt(exc):
            return _interrupted()
        where = f": {_STAGING_IN_PATH.sub('', str(exc.filename))}" if exc.filename else ""
        print(f"tengfield: error: {exc.strerror or exc}{where}", file=sys.stderr)
        return 1
    except Exception as exc:
        if _caused_by_interrupt(exc):   # Ctrl-C/SIGTERM inside a C callback (numba's
            return _interrupted()       # unpickler): a SystemError wrapping the interrupt
        raise


def _interrupted() -> int:
    """Say ``tengfield: interrupted`` and give 130, the exit code of a handled Ctrl-C."""
    print("tengfield: interrupted", file=sys.stderr)
    forget_unhandled_interrupt()
    return 130


def forget_unhandled_interrupt() -> None:
    """Let a caught KeyboardInterrupt end the process with the exit code tengfield returns.

    CPython marks a KeyboardInterrupt that leaves code run by ``exec`` of a string (as
    :mod:`dataclasses` builds a class's methods while a module is imported) as unhandled,
    even when a caller catches it, and then ends the process by SIGINT (exit -2) instead
    of with ``sys.exit(130)``. Running a string again clears the mark."""
    exec("pass")   # noqa: S102 - a constant string: clears the interpreter's mark


def _caused_by_interrupt(exc: BaseException) -> bool:
    """True when ``exc`` was raised because of a KeyboardInterrupt (its cause or context),
    or after SIGINT arrived (a C extension's import turns it into an ImportError)."""
    from ._early_interrupt import received
    if received():
        return True
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, KeyboardInterrupt):
            return True
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return False


# -- under mpirun -n N (N > 1) -----------------------------------------------------------
# Every rank runs main(). The ranks agree (collectively, on a communicator of their own)
# on the outcome at three points: the input (arguments, --jobs, the scene file), the
# output location, and the end of the command. Rank 0 alone prints what went wrong, once,
# every rank exits with the same code only after rank 0 has written (Open MPI 5's
# launcher drops a rank's last lines if another rank exits first), and a bad input leaves
# no output directory. A rank that fails on its own while the others are blocked in the
# command's collective calls prints its error and aborts them all after
# _mpi.FAILURE_GRACE_S seconds (never a hang).
#: under mpirun: how SIGINT/SIGTERM end this rank (_mpi.SignalExit), None otherwise
_SIGNAL_EXIT = None


class _Outcome(NamedTuple):
    """How one rank ended a step: exit code and the text main() prints ('' = none)."""

    code: int
    text: str = ""
    stream: str = "stderr"


def _launched_world():
    """``MPI.COMM_WORLD`` (initialises MPI); tests put a stand-in here."""
    from mpi4py import MPI

    return MPI.COMM_WORLD


def _outcome_of(exc: BaseException) -> _Outcome:
    """What the one-process main() prints and returns for ``exc``."""
    from ._mpi import FailedOnAnotherRank

    if isinstance(exc, FailedOnAnotherRank):   # the failing rank says it: its exit code
        return _Outcome(1 if exc.original is None else _outcome_of(exc.original).code)
    if isinstance(exc, TengfieldError):
        return _Outcome(2, f"tengfield: error: {exc}")
    if isinstance(exc, KeyboardInterrupt):
        forget_unhandled_interrupt()
        return _Outcome(130, "tengfield: interrupted")
    if isinstance(exc, OSError):
        where = f": {_STAGING_IN_PATH.sub('', str(exc.filename))}" if exc.filename else ""
        return _Outcome(1, f"tengfield: error: {exc.strerror or exc}{where}")
    if isinstance(exc, SystemExit):
        if exc.code is None or isinstance(exc.code, int):
            return _Outcome(int(exc.code or 0))
        return _Outcome(1, str(exc.code))
    text = "".join(traceback.format_exception(type(exc), exc, exc.__traceback__)).rstrip()
    return _Outcome(1, text)


def _on_rank(text: str, rank: int, size: int) -> str:
    """``text`` said by rank ``rank`` (printed by rank 0)."""
    tag = f"on rank {rank} of {size}"
    for prefix in ("tengfield: error: ", "tengfield: interrupted"):
        if text.startswith(prefix):
            return f"{prefix.rstrip(': ')} {tag}: {text[len(prefix):]}".rstrip(": ")
    return f"tengfield: error {tag}:\n{text}"


def _parse_quietly(parser: argparse.ArgumentParser, argv):
    """``parser.parse_args(argv)``; what argparse prints and exits with (usage, --help)
    is kept as an :class:`_Outcome` for rank 0 to print, not printed by every rank."""
    import contextlib

    out, err = io.StringIO(), io.StringIO()
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            args = parser.parse_args(argv)
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 2)
        if out.getvalue():
            return None, _Outcome(code, out.getvalue().rstrip("\n"), "stdout")
        return None, _Outcome(code, err.getvalue().rstrip("\n"))
    if not getattr(args, "func", None):
        return None, _Outcome(2, parser.format_help().rstrip("\n"), "stdout")
    return args, None


def _check_input(args, world) -> None:
    """Everything a rank can check before any output exists (raises TengfieldError)."""
    from ._mpi import check_jobs

    if getattr(args, "one_process", None):
        # one process's work: N ranks would each do it and write the same files at once
        raise TengfieldError(f"tengfield {args.command} runs on one process "
                             f"({args.one_process}): start it without mpirun")
    if hasattr(args, "jobs"):
        check_jobs(args.jobs, world)
    _apply_settings(args)
    if getattr(args, "scene", None) is not None:
        from .scene import load_scene

        load_scene(args.scene)    # every command's first step: a missing or bad file


def _missing_directories(path) -> list:
    """``path`` and those of its parents that do not exist yet, deepest first."""
    p, missing = os.path.abspath(path), []
    while not os.path.lexists(p) and os.path.dirname(p) != p:
        missing.append(p)
        p = os.path.dirname(p)
    return missing


def _remove_if_empty(directories) -> None:
    """Remove the directories this run created (deepest first) while they are empty."""
    for d in directories:
        try:
            os.rmdir(d)
        except FileNotFoundError:   # removed already (by the staged output's abort)
            continue
        except OSError:
            return


def _agree(control, mine: _Outcome | None) -> _Outcome | None:
    """Collective on ``control``: the first failing rank's outcome on every rank, after
    rank 0 printed every rank's text (once: a text shared by all ranks untagged, one
    of some ranks tagged with the first of them); None if every rank is fine."""
    # plain tuples: a rank started as `python -m tengfield.cli` has the class in __main__
    everyone = [None if o is None else _Outcome(*o)
                for o in control.allgather(None if mine is None else tuple(mine))]
    failed = [(r, o) for r, o in enumerate(everyone) if o is not None and (o.code or o.text)]
    if control.rank == 0:
        said = set()
        for r, o in failed:
            if not o.text or o.text in said:
                continue
            said.add(o.text)
            alike = all(x is not None and x.text == o.text for x in everyone)
            text = o.text if r == 0 or alike else _on_rank(o.text, r, control.size)
            print(text, file=sys.stdout if o.stream == "stdout" else sys.stderr)
    sys.stdout.flush()
    sys.stderr.flush()
    control.Barrier()     # nobody exits before rank 0 has written
    return failed[0][1] if failed else None


def _main_under_mpirun(parser: argparse.ArgumentParser, argv, world) -> int:
    from ._mpi import SignalExit

    out, err = sys.stdout, sys.stderr      # _open_staging rewrites the staging path
    global _SIGNAL_EXIT
    _SIGNAL_EXIT = SignalExit(world.rank).install()   # Ctrl-C/SIGTERM: clean, prompt
    try:
        return _agreed_run(parser, argv, world)
    except BaseException as exc:      # noqa: BLE001 - a fault of the agreement itself:
        text = _outcome_of(exc).text or f"tengfield: error: {type(exc).__name__}"
        print(_on_rank(text, world.rank, world.size), file=sys.stderr)
        sys.stderr.flush()            # the others may wait for this rank: end them all
        world.Abort(1)
        raise
    finally:
        sys.stdout, sys.stderr = out, err
        _SIGNAL_EXIT.uninstall()       # the process's handlers as they were (a test's)
        _SIGNAL_EXIT = None


def _agreed_run(parser: argparse.ArgumentParser, argv, world) -> int:
    from ._mpi import FAILURE_GRACE_S, all_arrived

    control = world.Dup()   # the agreement's own: it never meets a command's collectives
    created: list = []
    staged = None
    args, mine = None, None
    try:
        args, mine = _parse_quietly(parser, argv)
        if mine is None:
            _check_input(args, world)
    except BaseException as exc:      # noqa: BLE001 - every rank must reach _agree
        mine = _outcome_of(exc)
    action = _output_option(parser, args.command) if args is not None else None
    target = getattr(args, action.dest, None) if action is not None else None
    if target is not None:     # before any rank creates it (that follows the agreement)
        file = action.metavar == "FILE"
        created = _missing_directories((os.path.dirname(str(target)) or ".") if file
                                       else target)
    failed = _agree(control, mine)
    if failed is not None:
        return failed.code
    if target is not None:
        from .files.directory import ensure_directory, ensure_file_parent

        option = action.option_strings[0]
        try:   # every rank: a node-local path must exist where each rank looks
            (ensure_file_parent if action.metavar == "FILE" else ensure_directory)(target,
                                                                                   option)
        except BaseException as exc:  # noqa: BLE001
            mine = _outcome_of(exc)
        failed = _agree(control, mine)
        if failed is not None:
            _remove_if_empty(created)
            return failed.code
        if _SIGNAL_EXIT is not None and control.rank == 0:
            _SIGNAL_EXIT.clean_up(created=created)     # a signal: no new -o left
        if action.metavar != "FILE":   # all or nothing, as a single process (#30 item 2)
            staged, failed = _open_staging(control, args, action, bool(created))
            if failed is not None:
                _remove_if_empty(created)
                return failed.code
    if _SIGNAL_EXIT is not None and control.rank == 0:   # what a signal removes at once
        _SIGNAL_EXIT.clean_up(staging=getattr(staged, "staging", None), created=created)
    try:
        code = int(args.func(args) or 0)
        mine = _Outcome(code) if code else None
    except BaseException as exc:      # noqa: BLE001
        mine = _outcome_of(exc)
    if staged is not None:
        setattr(args, action.dest, target)
    if not all_arrived(control, None if mine is None else FAILURE_GRACE_S):
        # the others are blocked in the command (waiting for this rank): say why, end all
        if isinstance(staged, _OnAnotherRank):   # rank 0, blocked, is killed
            from .files.directory import drop_staging
            drop_staging(staged.staging, target, bool(created))
        elif staged is not None:
            staged.abort()
        _remove_if_empty(created)
        if mine.text:
            print(_on_rank(mine.text, world.rank, world.size), file=sys.stderr)
        sys.stdout.flush()
        sys.stderr.flush()
        world.Abort(mine.code or 1)
    if staged is not None:     # every rank succeeded: rank 0 moves the set into place
        anyone_failed = any(control.allgather(mine is not None))
        try:
            if control.rank == 0:
                with _SIGNAL_EXIT.moving() if _SIGNAL_EXIT else contextlib.nullcontext():
                    staged.abort() if anyone_failed else staged.commit()
        except BaseException as exc:  # noqa: BLE001
            mine = _outcome_of(exc)
            staged.abort()     # a new DIR goes again (the previous set was put back)
        # "wrote ..." (any rank's) only if rank 0 moved the set into place
        moved = control.bcast(mine is None and not anyone_failed if control.rank == 0
                              else None, root=0)
        _release((sys.stdout, sys.stderr), bool(moved) and mine is None)
    failed = _agree(control, mine)
    if failed is not None:
        _remove_if_empty(created)
        return failed.code
    return 0


def _open_staging(control, args, action, created: bool):
    """Under mpirun: rank 0 opens -o DIR's staging directory (lock, recovery) and every
    rank writes into it (``args``' -o is set to it; rank 0 moves the set into place when
    every rank succeeded). Returns (rank 0's StagedOutput or None, the failed outcome)."""
    from .files.directory import StagedOutput

    staged, mine, where = None, None, None
    if control.rank == 0:
        try:
            from .files.directory import record_command, refuse_another_commands_directory

            refuse_another_commands_directory(getattr(args, action.dest), args.command,
                                              action.option_strings[0])
            staged = StagedOutput(getattr(args, action.dest), option=action.option_strings[0],
                                  created=created)
            where = str(staged.open())
            try:
                record_command(where, args.command)
            except BaseException:
                staged.abort()
                raise
        except BaseException as exc:  # noqa: BLE001
            staged, mine = None, _outcome_of(exc)
    where = control.bcast(where)
    failed = _agree(control, mine)
    if failed is not None:
        return None, failed
    target = str(getattr(args, action.dest))
    setattr(args, action.dest, where)
    sys.stdout = _PathRewriter(sys.stdout, where, target)
    sys.stderr = _PathRewriter(sys.stderr, where, target)
    return (staged if control.rank == 0 else _OnAnotherRank(where)), None


class _OnAnotherRank(NamedTuple):
    """What _open_staging returns on the ranks other than 0 (rank 0 holds the
    StagedOutput): the staging directory every rank writes into."""

    staging: str


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
