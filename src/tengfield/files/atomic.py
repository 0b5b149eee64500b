"""How one file is written: never half a file, never into a pipe or through a symlink.

* :func:`atomic_path`: a temporary file next to the target, moved over it
  (``os.replace``) only when complete: a reader never sees half a file;
  :func:`write_bytes` the same for bytes built in memory (fsynced first);
* :func:`writable_target` refuses to write into a pipe or a device, or through a
  symlink;
* the files this process read as input (:func:`note_input`), which an output
  directory never removes or replaces (:mod:`tengfield.files.directory`).
"""
from __future__ import annotations

import os
import re
import stat
import tempfile
from contextlib import contextmanager
from pathlib import Path

from ..errors import OutputError

_KINDS = {stat.S_IFIFO: "a named pipe (FIFO)", stat.S_IFCHR: "a character device",
          stat.S_IFBLK: "a block device", stat.S_IFSOCK: "a socket", stat.S_IFLNK: "a symlink",
          stat.S_IFDIR: "a directory", stat.S_IFREG: "a file"}


#: the files this process read as input (scene files, recorded excitations, PSD tables,
#: measured traces) as (st_dev, st_ino): an output directory never removes or replaces
#: one of them (:class:`tengfield.files.directory.StagedOutput`)
_INPUTS: dict[tuple[int, int], str] = {}


def note_input(path: str | Path) -> None:
    """Record that this process reads ``path`` as an input (every reader of an input
    file calls it before reading)."""
    try:
        st = os.stat(path)
    except OSError:
        return
    _INPUTS[(st.st_dev, st.st_ino)] = str(path)


def input_named(path: str | Path) -> str | None:
    """The name an input was read under when ``path`` is the same file, else None."""
    try:
        st = os.stat(path)
    except OSError:
        return None
    return _INPUTS.get((st.st_dev, st.st_ino))


def forget_inputs() -> None:
    """Start a new command's list of inputs."""
    _INPUTS.clear()


def file_kind(mode: int) -> str:
    """``a named pipe (FIFO)``, ``a character device``, ... of an ``st_mode``."""
    return _KINDS.get(stat.S_IFMT(mode), "a special file")


def writable_target(path: str | Path) -> Path:
    """``path``, made safe to write a file at: a symlink there is removed (a file is
    written in its place, never through it to its target); a directory, FIFO or device
    node is refused (:class:`tengfield.errors.OutputError`: nothing is written into a
    pipe or a device). The staging directory of ``-o DIR`` (under mpirun too) holds none
    of these; the Python API writes where it is told. :func:`write_csv` writes where it is
    told (``/dev/full`` included); :func:`atomic_path` and the writers of an output
    set check."""
    path = Path(path)
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        return path
    if stat.S_ISLNK(st.st_mode):
        path.unlink()
    elif not stat.S_ISREG(st.st_mode):
        raise OutputError(f"{str(path)!r} is {file_kind(st.st_mode)}, not a regular file: "
                          "nothing was written there")
    return path


def target_name(path) -> str:
    """The file name a user asked for, of a path :func:`atomic_path` handed out
    (``.waveforms.tmp-123.png`` -> ``waveforms.png``) or of any other path; "the figure"
    for a file object (messages name the file, never a temporary one)."""
    if not isinstance(path, (str, os.PathLike)):
        return "the figure"
    name = os.path.basename(os.fspath(path))
    match = re.fullmatch(r"\.(.+)\.tmp-\d+(\.[^.]*)?", name)
    return match.group(1) + (match.group(2) or "") if match else name


@contextmanager
def atomic_path(path: str | Path):
    """Yield a temporary path next to ``path`` (same suffix, so plotting libraries
    pick the format); it replaces ``path`` (``os.replace``) when the block ends
    without an exception, else it is removed: a reader never sees half a file."""
    path = writable_target(path)
    tmp = path.with_name(f".{path.stem}.tmp-{os.getpid()}{path.suffix}")
    try:
        yield tmp
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


def write_bytes(path: str | Path, data) -> Path:
    """``data`` (bytes, or a buffer) to ``path`` atomically and durably: a temporary file
    next to it, fsynced, moved over it (``os.replace``). Raises ``OSError`` naming
    ``path`` if it cannot be written (nothing is left behind)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except OSError as exc:   # name the file (a bare "No space left on device" names none)
        Path(tmp).unlink(missing_ok=True)
        raise OSError(exc.errno, exc.strerror or str(exc), str(path)) from None
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path
