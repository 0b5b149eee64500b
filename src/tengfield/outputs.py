"""Output directories that are checked first and written all-or-nothing.

Every CLI command with ``-o DIR`` writes through :class:`StagedOutput`
(``tengfield.cli`` does it for every command, the command modules need no
change):

1. before any computation, ``DIR`` is created or checked (a file, a path under
   a file, a read-only place: one :class:`OutputError` line, exit 2);
2. a lock (``DIR/.tengfield.lock``, ``flock``, released by the kernel when the
   process dies) refuses a second tengfield command writing to the same ``DIR``;
3. the command writes into a staging directory inside ``DIR``; only when it
   succeeds are its files moved into place one by one (``os.replace``, atomic
   per file on one file system). Files the previous command wrote there and this
   one did not are removed (``DIR/.tengfield-manifest.json`` lists them), so the
   directory always holds one complete set;
4. on any failure (exception, full disk, Ctrl-C) the staging directory is
   removed and the previous set stays as it was.

``-o FILE`` options (``tengfield precompute``) get the checks of step 1 on the
file's directory, and the file must be a regular file or a new path (a FIFO,
a device node, ``/dev/null``: refused, never replaced); the file itself is
written atomically by its writer.
"""
from __future__ import annotations

import errno
import json
import os
import shutil
import stat
import tempfile
from pathlib import Path

from .errors import TengfieldError

LOCK_NAME = ".tengfield.lock"
MANIFEST_NAME = ".tengfield-manifest.json"
STAGING_PREFIX = ".tengfield-staging-"


class OutputError(TengfieldError):
    """The output location cannot be used (not a directory, not writable, locked)."""


def _reason(exc: OSError) -> str:
    if exc.errno in (errno.EACCES, errno.EPERM, errno.EROFS):
        return "is not writable (read-only or no permission)"
    if exc.errno == errno.ENAMETOOLONG:
        return "is too long a name for the file system"
    return exc.strerror or str(exc)


_KINDS = {stat.S_IFIFO: "a named pipe (FIFO)", stat.S_IFCHR: "a character device",
          stat.S_IFBLK: "a block device", stat.S_IFSOCK: "a socket", stat.S_IFLNK: "a symlink",
          stat.S_IFDIR: "a directory", stat.S_IFREG: "a file"}


def _kind(mode: int) -> str:
    """``a named pipe (FIFO)``, ``a character device``, ... of an ``st_mode``."""
    return _KINDS.get(stat.S_IFMT(mode), "a special file")


def _not_empty(path, option: str, what: str) -> Path:
    """``Path(path)``, refusing "" (``Path("")`` is the current directory)."""
    if path is None or str(path) == "":
        raise OutputError(f"{option} '' is empty: give {what} (-o . for the current directory)"
                          if what == "a directory" else f"{option} '' is empty: give {what}")
    return Path(path)


def _first_file_above(path: Path) -> Path | None:
    """The nearest existing non-directory among ``path``'s ancestors, if any."""
    for parent in path.parents:
        if parent.exists():
            return None if parent.is_dir() else parent
    return None


def ensure_directory(path: str | Path, option: str = "-o") -> Path:
    """Create ``path`` (and its parents) or check the existing one; writable.

    Raises :class:`OutputError` with one line naming the option and the path
    (also for "", a FIFO or device, a name too long for the file system).
    """
    p = _not_empty(path, option, "a directory")
    where = f"{option} {str(p)!r}"
    try:
        st = os.stat(p)
    except FileNotFoundError:
        st = None
    except OSError as exc:     # ENAMETOOLONG, ELOOP, ENOTDIR (checked below), ...
        st = None
        if exc.errno != errno.ENOTDIR:
            raise OutputError(f"{where} {_reason(exc)}") from None
    if st is not None and not stat.S_ISDIR(st.st_mode):
        raise OutputError(f"{where} is {_kind(st.st_mode)}, not a directory")
    try:
        blocker = _first_file_above(p)
    except OSError as exc:
        raise OutputError(f"{where} {_reason(exc)}") from None
    if blocker is not None:
        raise OutputError(f"{where}: {str(blocker)!r} is a file, not a directory")
    try:
        p.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"{where} could not be created: {_reason(exc)}") from None
    try:   # a real write probe: os.access says yes to root on read-only mounts
        fd, probe = tempfile.mkstemp(dir=p, prefix=".tengfield-probe-")
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        raise OutputError(f"{where} {_reason(exc)}") from None
    return p


def ensure_file_parent(path: str | Path, option: str = "-o") -> Path:
    """Checks for an output FILE: a regular file or a new path (never a directory, FIFO,
    device node, ...: those are not replaced), its directory created and writable, and
    room in the directory for the writer's temporary file ``.NAME.XXXXXXXX.tmp``."""
    p = _not_empty(path, option, "a file name")
    where = f"{option} {str(p)!r}"
    try:
        st = os.stat(p)          # through a symlink: what a writer would reach
    except FileNotFoundError:
        st = None                # a new path (or a dangling symlink, replaced as such)
    except OSError as exc:
        st = None
        if exc.errno != errno.ENOTDIR:
            raise OutputError(f"{where} {_reason(exc)}") from None
    if st is not None and stat.S_ISDIR(st.st_mode):
        raise OutputError(f"{where} is a directory: give a file name")
    if st is not None and not stat.S_ISREG(st.st_mode):
        raise OutputError(f"{where} is {_kind(st.st_mode)}, not a regular file: give a file name")
    parent = p.parent if str(p.parent) else Path(".")
    ensure_directory(parent, option=f"{where}: directory")
    try:   # the temporary name surrogate.store.write_checked_file uses: 14 bytes longer
        fd, probe = tempfile.mkstemp(prefix=f".{p.name}.", suffix=".tmp", dir=parent)
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        raise OutputError(f"{where} {_reason(exc)}") from None
    return p


class StagedOutput:
    """``with StagedOutput(DIR) as staging: ...`` writes into ``staging`` and, when the
    block ends without an exception, moves the files into ``DIR``; see the module doc."""

    def __init__(self, target: str | Path, *, option: str = "-o"):
        self._spelled = target
        self.target = Path(target)
        self.option = option
        self.staging: Path | None = None
        self._lock_fd: int | None = None
        self._created = False

    # -- the three steps -----------------------------------------------------------
    def open(self) -> Path:
        self._created = not os.path.lexists(self.target)
        ensure_directory(self._spelled, self.option)
        self._lock()
        for leftover in self.target.glob(STAGING_PREFIX + "*"):   # of a killed run; we hold the lock
            shutil.rmtree(leftover, ignore_errors=True)
        try:
            self.staging = Path(tempfile.mkdtemp(dir=self.target, prefix=STAGING_PREFIX))
        except OSError as exc:
            self._unlock()
            raise OutputError(f"{self.option} {str(self.target)!r} {_reason(exc)}") from None
        # the path as the user spelled it, so messages that name files read naturally
        self.staging = Path(os.path.join(str(self.target), self.staging.name))
        return self.staging

    def commit(self) -> list[Path]:
        """Move every staged file into place; remove the previous command's leftovers."""
        assert self.staging is not None
        try:
            written = sorted(p.relative_to(self.staging) for p in self.staging.rglob("*")
                             if not p.is_dir())
            for rel in written:
                dest = self.target / rel
                dest.parent.mkdir(parents=True, exist_ok=True)
                os.replace(self.staging / rel, dest)
            previous = self._read_manifest()
            names = {str(rel) for rel in written}
            for stale in previous - names:
                stale_path = self.target / stale
                if stale_path.is_file() and not stale_path.is_symlink():
                    stale_path.unlink()
            self._write_manifest(names)
            return [self.target / rel for rel in written]
        finally:
            self._cleanup()

    def abort(self) -> None:
        """Drop everything staged; the previous set in DIR stays untouched (a DIR
        this command created is removed again)."""
        self._cleanup()
        if self._created:
            try:
                leftovers = {p.name for p in self.target.iterdir()}
                if leftovers <= {LOCK_NAME}:
                    (self.target / LOCK_NAME).unlink(missing_ok=True)
                    self.target.rmdir()
            except OSError:
                pass

    # -- context manager -----------------------------------------------------------
    def __enter__(self) -> Path:
        return self.open()

    def __exit__(self, exc_type, exc, tb) -> bool:
        if exc_type is None:
            self.commit()
        else:
            self.abort()
        return False

    # -- helpers --------------------------------------------------------------------
    def _lock(self) -> None:
        import fcntl

        path = self.target / LOCK_NAME
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as exc:
            raise OutputError(f"{self.option} {str(self.target)!r} {_reason(exc)}") from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            holder = os.pread(fd, 64, 0).decode("ascii", "replace").strip() or "?"
            os.close(fd)
            raise OutputError(f"{self.option} {str(self.target)!r} is being written by another "
                              f"tengfield command (pid {holder}); wait for it or choose another "
                              "directory") from None
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        self._lock_fd = fd

    def _unlock(self) -> None:
        if self._lock_fd is not None:
            os.close(self._lock_fd)   # closing releases the flock
            self._lock_fd = None

    def _cleanup(self) -> None:
        if self.staging is not None:
            shutil.rmtree(self.staging, ignore_errors=True)
            self.staging = None
        self._unlock()

    def _read_manifest(self) -> set[str]:
        try:
            return set(json.loads((self.target / MANIFEST_NAME).read_text())["files"])
        except (OSError, ValueError, KeyError, TypeError):
            return set()

    def _write_manifest(self, names: set[str]) -> None:
        tmp = self.target / (MANIFEST_NAME + ".tmp")
        tmp.write_text(json.dumps({"files": sorted(names)}, indent=1) + "\n")
        os.replace(tmp, self.target / MANIFEST_NAME)
