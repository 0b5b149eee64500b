"""Figures drawn by a second Python process, so that a command's figures cost no time
of its own.

Importing matplotlib takes about 0.3 s and drawing a figure 0.2-0.3 s, all under the
GIL. :class:`FigureProcess` starts ``python -m tengfield.plotting.process`` when a
command begins: the child imports matplotlib on another core while the command
computes, then draws each figure it is sent (the arguments are pickled: send small
plot data, such as :class:`tengfield.plotting.dynamics.TrajectoryFigure`, not whole
results) while the command writes its tables.

The child runs in a process group of its own, so Ctrl-C at a terminal reaches only
this process, which kills the child on its way out (a child whose parent is gone
ends when its input does). Replies come back in order; :meth:`Drawing.result`
re-raises the child's exception (with the child's traceback as a note). If the
child cannot be started, or dies before it answers, or the arguments cannot be
pickled, the figure is drawn in this process instead, so a figure never goes
missing because of this shortcut. ``TENGFIELD_FIGURE_PROCESS=0`` draws every figure
in this process.
"""
from __future__ import annotations

import os
import pickle
import socket
import struct
import subprocess
import sys
from pathlib import Path

_LENGTH = struct.Struct("<Q")
_PRELOAD = ("matplotlib.figure", "matplotlib.backends.backend_agg", "tengfield.plotting.dynamics",
            "tengfield.plotting.waveforms", "tengfield.plotting.harvest")


_SWITCH = {"1": True, "yes": True, "true": True, "on": True,
           "0": False, "no": False, "false": False, "off": False}


def enabled() -> bool:
    """``TENGFIELD_FIGURE_PROCESS`` (unset: on); any other value than those of
    ``_SWITCH`` is a :class:`tengfield.errors.SceneError` naming it."""
    raw = os.environ.get("TENGFIELD_FIGURE_PROCESS", "1")
    value = _SWITCH.get(raw.strip().lower())
    if value is None:
        from ..errors import SceneError
        raise SceneError(f"TENGFIELD_FIGURE_PROCESS = {raw!r}: allowed 1/0, yes/no, "
                         "true/false, on/off")
    return value


def _pack(obj) -> bytes:
    data = pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL)
    return _LENGTH.pack(len(data)) + data


def _send(stream, obj) -> None:
    stream.write(_pack(obj))
    stream.flush()


def _receive(stream):
    """The next pickled object of ``stream``, or None at its end."""
    head = stream.read(_LENGTH.size)
    if len(head) < _LENGTH.size:
        return None
    size = _LENGTH.unpack(head)[0]
    data = stream.read(size)
    if len(data) < size:
        return None
    return pickle.loads(data)


class Drawing:
    """One figure sent to a :class:`FigureProcess`; :meth:`result` waits for it."""

    def __init__(self, owner: FigureProcess, index: int, job):
        self._owner, self._index, self._job = owner, index, job
        self._done = False
        self._value = None

    def result(self):
        """The drawing function's return value (re-raises its exception)."""
        if not self._done:
            self._value = self._owner._result(self._index, self._job)
            self._done = True
        return self._value


class FigureProcess:
    """A child process that draws figures; use it as a context manager (leaving the
    block stops the child; an exception inside kills it at once). :meth:`draw` sends a
    figure and returns at once; :meth:`finish` waits for all of them."""

    def __init__(self):
        self._proc: subprocess.Popen | None = None
        self._replies: list = []
        self._sent = 0
        self._drawings: list[Drawing] = []
        if not enabled() or not sys.executable:
            return
        src = str(Path(__file__).resolve().parents[2])   # tengfield importable as here
        path = os.environ.get("PYTHONPATH")
        env = dict(os.environ, PYTHONPATH=src + (os.pathsep + path if path else ""),
                   MPLBACKEND="Agg")
        # a socket, not a pipe: sent with MSG_NOSIGNAL, a child that has gone is an
        # error here, never a SIGPIPE (which PETSc, once imported, turns into an abort)
        self._sock, theirs = socket.socketpair()
        try:
            self._proc = subprocess.Popen([sys.executable, "-m", "tengfield.plotting.process"],
                                          stdin=theirs, stdout=theirs, env=env, close_fds=True,
                                          process_group=0)
        except OSError:
            self._proc = None
            self._sock.close()
        finally:
            theirs.close()
        if self._proc is not None:
            self._answers = self._sock.makefile("rb")

    @property
    def running(self) -> bool:
        return self._proc is not None and self._proc.poll() is None

    def draw(self, function, *args, **kwargs) -> Drawing:
        """Draw ``function(*args, **kwargs)`` (a module-level function) in the child,
        or here if the child is gone. Returns at once."""
        job = (function, args, kwargs)
        index = -1
        message = None
        if self._proc is not None:
            try:
                from ..files.figures import _FIGURE_OUTPUT   # --dpi, for the child too
                message = _pack((function.__module__, function.__qualname__, args, kwargs,
                                 _FIGURE_OUTPUT["dpi"]))
            except Exception:  # noqa: BLE001 - not picklable: drawn here
                message = None
        if message is not None:
            try:
                self._sock.sendall(message, socket.MSG_NOSIGNAL)
                index, self._sent = self._sent, self._sent + 1
            except (OSError, ValueError):   # the child has gone: draw here
                self._stop(kill=True)
        drawing = Drawing(self, index, job)
        self._drawings.append(drawing)
        return drawing

    def finish(self) -> list:
        """Wait for every figure sent so far; their return values, in order (the first
        error is raised)."""
        drawings, self._drawings = self._drawings, []
        return [drawing.result() for drawing in drawings]

    def _result(self, index: int, job):
        function, args, kwargs = job
        while index >= 0 and len(self._replies) <= index and self._proc is not None:
            reply = _receive(self._answers)
            if reply is None:            # the child died before answering
                self._stop(kill=True)
                break
            self._replies.append(reply)
        if index < 0 or index >= len(self._replies):
            return function(*args, **kwargs)
        ok, value, trace = self._replies[index]
        if ok:
            return value
        if trace and hasattr(value, "add_note"):
            value.add_note("in the figure process:\n" + trace.rstrip())
        raise value

    def _stop(self, *, kill: bool) -> None:
        proc, self._proc = self._proc, None
        if proc is None:
            return
        if kill:         # before its input ends: a child that reads the end exits by itself
            proc.kill()
        try:
            self._sock.shutdown(socket.SHUT_WR)      # the child's input ends
        except OSError:
            pass
        try:
            proc.wait(timeout=None if not kill else 10)
        finally:
            self._answers.close()
            self._sock.close()

    def close(self) -> None:
        """Let the child finish the figures it was sent and end (at once if every
        figure has been answered: it may still be importing matplotlib)."""
        self._stop(kill=len(self._replies) >= self._sent)

    def __enter__(self) -> FigureProcess:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is not None:
            self._stop(kill=True)
        else:
            self.close()


def _warm_up() -> None:
    """Draw a tiny figure to memory: fonts, mathtext and the PNG encoder load now, while
    the parent computes, not in the first real figure (0.04 s of 0.3 s)."""
    import io

    from . import new_figure

    fig = new_figure((2, 2))
    ax = fig.subplots()
    ax.plot([0, 1], [0, 1], "v", label="$y + z$")
    ax.fill_between([0, 1], [0, 1], alpha=0.1)
    ax.legend(fontsize=8)
    ax.set_title("warm-up", fontsize=10)
    ax.set_xlabel("time [s]")
    fig.tight_layout()
    fig.savefig(io.BytesIO(), dpi=30)


def _serve(stdin, stdout) -> int:
    """The child: draw each job of ``stdin`` and answer (ok, value or exception,
    traceback text) on ``stdout``, in order, until ``stdin`` ends."""
    import importlib
    import traceback

    try:                        # while the parent computes; a failure here comes
        for name in _PRELOAD:   # back as the first figure's error
            importlib.import_module(name)
        _warm_up()
    except Exception:  # noqa: BLE001
        pass
    while True:
        job = _receive(stdin)
        if job is None:
            return 0
        module, qualname, args, kwargs, dpi = job
        try:
            from ..files import set_figure_dpi
            set_figure_dpi(dpi)
            function = importlib.import_module(module)
            for part in qualname.split("."):
                function = getattr(function, part)
            reply = (True, function(*args, **kwargs), "")
        except Exception as exc:  # noqa: BLE001 - sent to the parent, which raises it
            reply = (False, exc, traceback.format_exc())
        try:
            pickle.dumps(reply[1])
        except Exception:  # noqa: BLE001 - an unpicklable value or exception
            reply = (False, RuntimeError(f"figure process: {reply[1]!r}"), reply[2])
        _send(stdout, reply)


def _main() -> int:
    from .._console import configure_output

    replies = os.fdopen(os.dup(1), "wb")    # the answers; what the figures print goes
    os.dup2(2, 1)                           # to stderr, not into the answers
    sys.stdout = sys.stderr
    configure_output()      # stderr as the command's: tengfield's own lines only
    code = _serve(sys.stdin.buffer, replies)
    sys.stderr.flush()
    os._exit(code)      # every figure is written and closed: skip the interpreter's teardown


if __name__ == "__main__":
    try:
        sys.exit(_main())
    except (KeyboardInterrupt, BrokenPipeError):   # Ctrl-C or the parent gone: quietly
        sys.exit(130)
