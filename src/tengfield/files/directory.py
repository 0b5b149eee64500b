"""Output directories that are checked first and written all-or-nothing.

Every CLI command with ``-o DIR`` writes through :class:`StagedOutput`
(``tengfield.cli`` does it for every command, the command modules need no
change):

1. before any computation, ``DIR`` is created or checked (a file, a FIFO or device,
   a path under a file, a read-only place, "" or a name too long for the file
   system: one :class:`OutputError` line naming the option, exit 2);
2. a lock (``DIR/.tengfield.lock``, ``flock``, released by the kernel when the
   process dies; never opened through a symlink) refuses a second tengfield
   command writing to the same ``DIR``;
3. the command writes into a staging directory inside ``DIR``; only when it
   succeeds are its files moved into place, all or nothing: every destination is
   checked first (a directory, FIFO or device where a file goes: one error line,
   nothing replaced), the files they replace are moved aside into the staging
   directory under a journal, and a failure on the way (or a kill -9, undone by
   the next command writing to ``DIR``) puts them back. Files the previous command
   wrote there and this one did not are removed (``DIR/.tengfield-manifest.json``
   lists them; only plain names inside ``DIR``, regular files reached through real
   directories: never "../x", "/x" or a symlink's target), so the directory always
   holds one complete set. A file in ``DIR`` that tengfield did not write (not in the
   manifest: a user's own ``summary.json``) is never replaced silently: it is kept as
   ``NAME.orig`` (``NAME.orig.2``, ... when taken), one warning line naming both
   (:func:`foreign_files`). A file the command read (its scene, a recorded excitation,
   a PSD table, fit's measured trace: :func:`tengfield.files.atomic.note_input`) is never
   removed (it stays, no longer listed) nor replaced (one error line, nothing written);
4. on any failure (exception, full disk, Ctrl-C) the staging directory is
   removed and the previous set stays as it was; the lock file goes when the command
   ends (a command that finds it unlinked under its lock takes the lock again).

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
import warnings
from pathlib import Path

from ..errors import OutputError
from .atomic import file_kind as _kind
from .atomic import forget_inputs, input_named

LOCK_NAME = ".tengfield.lock"
MANIFEST_NAME = ".tengfield-manifest.json"
STAGING_PREFIX = ".tengfield-staging-"
#: inside a staging directory during a commit: the journal and the files being replaced
TX_NAME = ".tengfield-tx"
JOURNAL_NAME = "journal.json"
OLD_NAME = "old"


def _reason(exc: OSError) -> str:
    if exc.errno in (errno.EACCES, errno.EPERM, errno.EROFS):
        return "is not writable (read-only or no permission)"
    if exc.errno == errno.ENAMETOOLONG:
        return "is too long a name for the file system"
    return exc.strerror or str(exc)


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
    inner = [part for part in Path(os.path.abspath(p)).parts
             if part.startswith((STAGING_PREFIX, ".tengfield-probe-"))]
    if inner:   # another command's staging directory: removed when that command ends
        raise OutputError(f"{where} is inside {inner[0]!r}, a tengfield command's staging "
                          "directory (removed when that command ends): choose another directory")
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
    try:   # the temporary name files.atomic.write_bytes uses: 14 bytes longer
        fd, probe = tempfile.mkstemp(prefix=f".{p.name}.", suffix=".tmp", dir=parent)
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        raise OutputError(f"{where} {_reason(exc)}") from None
    return p


def _plain_name(name) -> str | None:
    """``name`` if it is a relative path inside a directory (no "..", ".", empty, absolute
    or reserved part), else None: what a manifest or journal may name."""
    if not isinstance(name, str) or not name or "\0" in name or name.startswith("/"):
        return None
    parts = name.split("/")
    if any(part in ("", ".", "..") for part in parts):
        return None
    if parts[0] in (LOCK_NAME, MANIFEST_NAME, MANIFEST_NAME + ".tmp") or \
            parts[0].startswith((STAGING_PREFIX, ".tengfield-probe-")):
        return None
    return name


def _lstat(path: Path) -> os.stat_result | None:
    try:
        return os.lstat(path)
    except FileNotFoundError:
        return None


def _parents_are_directories(target: Path, name: str) -> bool:
    """Every directory on the way from ``target`` to ``target/name`` exists and is a real
    directory (no symlink): nothing is reached outside ``target``."""
    here = target
    for part in name.split("/")[:-1]:
        here = here / part
        st = _lstat(here)
        if st is None or not stat.S_ISDIR(st.st_mode):
            return False
    return True


class StagedOutput:
    """``with StagedOutput(DIR) as staging: ...`` writes into ``staging`` and, when the
    block ends without an exception, moves the files into ``DIR``; see the module doc."""

    def __init__(self, target: str | Path, *, option: str = "-o", created: bool | None = None):
        """``created``: whether this command made DIR (default: DIR does not exist when
        :meth:`open` is called; under mpirun the ranks made it before)."""
        self._spelled = target
        self.target = Path(target)
        self.option = option
        self.staging: Path | None = None
        self._lock_fd: int | None = None
        self._created = False
        self._created_given = created

    # -- the three steps -----------------------------------------------------------
    def open(self) -> Path:
        self._created = (not os.path.lexists(self.target) if self._created_given is None
                         else self._created_given)
        forget_inputs()      # the command notes the files it reads from here on
        ensure_directory(self._spelled, self.option)
        self._lock()
        try:
            self._recover_leftovers()    # of a killed run; we hold the lock
            self.staging = Path(tempfile.mkdtemp(dir=self.target, prefix=STAGING_PREFIX))
        except OSError as exc:
            self._unlock()
            raise OutputError(f"{self.option} {str(self.target)!r} {_reason(exc)}") from None
        except BaseException:
            self._unlock()
            raise
        # the path as the user spelled it, so messages that name files read naturally
        self.staging = Path(os.path.join(str(self.target), self.staging.name))
        return self.staging

    def commit(self) -> list[Path]:
        """Move every staged file into place and the previous command's leftovers out,
        all or nothing: every destination is checked first (a directory or a special
        file where a file goes: :class:`OutputError`, nothing replaced); the files they
        replace are kept in the staging directory, listed in a journal, until the last
        one is in place, and put back on any failure (here, or by the next command
        after a kill)."""
        assert self.staging is not None
        keep = False
        try:
            staged = self._staged_names()
            previous = self._read_manifest()
            stale = sorted(previous - set(staged))
            moves = self._plan(staged, stale)
            kept = _keep_foreign(self.target, foreign_files(self.target, staged, previous))
            (self.staging / MANIFEST_NAME).write_text(
                json.dumps({"files": staged}, indent=1) + "\n")
            tx = self.staging / TX_NAME
            (tx / OLD_NAME).mkdir(parents=True)
            with open(tx / JOURNAL_NAME, "w") as fh:
                json.dump({"moves": [{"name": n, "staged": s} for n, s in moves]}, fh)
                fh.flush()
                os.fsync(fh.fileno())
            try:
                for name, is_staged in moves:
                    self._move(name, is_staged, tx / OLD_NAME)
            except BaseException:
                keep = not self._undo(self.staging)
                for _, copy in kept:          # the user's file is back in its place
                    copy.unlink(missing_ok=True)
                raise
            (tx / JOURNAL_NAME).unlink()     # the commit point: the new set is in place
            for name, copy in kept:
                warnings.warn(f"{self.option} {str(self.target)!r}: {name!r} there was not "
                              f"written by tengfield: kept it as {copy.name!r} (the new "
                              f"{name!r} is this command's)", UserWarning, stacklevel=2)
            return [self.target / name for name in staged]
        finally:
            self._cleanup(keep=keep)

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

    # -- the move into place ----------------------------------------------------------
    def _staged_names(self) -> list[str]:
        """The files (and symlinks) the command wrote, relative to the staging directory."""
        names = []
        for p in self.staging.rglob("*"):
            if not stat.S_ISDIR(p.lstat().st_mode):
                name = _plain_name(p.relative_to(self.staging).as_posix())
                if name is not None:
                    names.append(name)
        return sorted(names)

    def _plan(self, staged: list[str], stale: list[str]) -> list[tuple[str, bool]]:
        """``(name, staged)`` of every move, after checking every destination: a staged
        file may replace a file or a symlink (the link, never its target), never a
        directory or a special file; a stale file is removed only if it is a regular
        file reached through real directories of DIR."""
        moves = []
        for name in [*staged, MANIFEST_NAME]:
            here = self.target
            for part in name.split("/"):
                here = here / part
                st = _lstat(here)
                if st is None:
                    break
                last = here == self.target / name
                if stat.S_ISDIR(st.st_mode) and last:
                    raise OutputError(f"{self.option} {str(here)!r} is a directory where "
                                      "tengfield writes a file: nothing was replaced")
                if not last and not stat.S_ISDIR(st.st_mode):
                    raise OutputError(f"{self.option} {str(here)!r} is {_kind(st.st_mode)}, "
                                      "not a directory: nothing was replaced")
                if last and not (stat.S_ISREG(st.st_mode) or stat.S_ISLNK(st.st_mode)):
                    raise OutputError(f"{self.option} {str(here)!r} is {_kind(st.st_mode)}, "
                                      "not a regular file: nothing was replaced")
                read_as = input_named(here) if last else None
                if read_as is not None:
                    raise OutputError(f"{self.option} {str(self.target)!r}: {name!r} there is a "
                                      f"file this command read ({read_as!r}) and would be "
                                      "replaced by its output of that name: nothing was "
                                      f"written; choose another {self.option} directory")
            moves.append((name, True))
        for name in stale:
            if _parents_are_directories(self.target, name):
                st = _lstat(self.target / name)
                if st is not None and stat.S_ISREG(st.st_mode) \
                        and input_named(self.target / name) is None:   # an input stays
                    moves.append((name, False))
        return moves

    def _move(self, name: str, is_staged: bool, old: Path) -> None:
        """The file at ``DIR/name`` (if any) to ``old/name``, then the staged one in."""
        dest = self.target / name
        if is_staged and "/" in name:
            dest.parent.mkdir(parents=True, exist_ok=True)
        if _lstat(dest) is not None:
            (old / name).parent.mkdir(parents=True, exist_ok=True)
            os.replace(dest, old / name)
        if is_staged:
            os.replace(self.staging / name, dest)

    def _undo(self, staging: Path) -> bool:
        """Put back what the journal in ``staging`` says a commit moved (a commit that
        failed, or was killed, before its end); False if something could not be."""
        moves = _read_journal(staging)
        if moves is None:
            return True
        old = staging / TX_NAME / OLD_NAME
        st = _lstat(old)
        old_ok = st is not None and stat.S_ISDIR(st.st_mode)
        done = True
        for name, is_staged in reversed(moves):
            dest = self.target / name
            if not _parents_are_directories(self.target, name):
                continue
            try:
                if old_ok and _inside(old, name):
                    os.replace(old / name, dest)           # the previous file back
                elif is_staged and _parents_are_directories(staging, name) \
                        and _lstat(staging / name) is None:
                    st = _lstat(dest)                      # a new file where there was none
                    if st is not None and not stat.S_ISDIR(st.st_mode):
                        dest.unlink()
            except OSError:
                done = False
        if done:
            (staging / TX_NAME / JOURNAL_NAME).unlink()
        return done

    def _recover_leftovers(self) -> None:
        """Undo the move of a commit that was killed, then remove its staging directory."""
        for leftover in sorted(self.target.glob(STAGING_PREFIX + "*")):
            st = _lstat(leftover)
            if st is None or not stat.S_ISDIR(st.st_mode):
                continue
            if not self._undo(leftover):
                raise OutputError(f"{self.option} {str(self.target)!r}: an interrupted earlier "
                                  "write could not be undone; the files it replaced are in "
                                  f"{str(leftover / TX_NAME / OLD_NAME)!r}")
            shutil.rmtree(leftover, ignore_errors=True)

    # -- helpers --------------------------------------------------------------------
    def _lock(self, _retries: int = 20) -> None:
        import fcntl

        path = self.target / LOCK_NAME
        where = f"{self.option} {str(self.target)!r}"
        try:   # never through a symlink (it would truncate its target), nor a FIFO's wait
            fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_NONBLOCK, 0o644)
        except OSError as exc:
            if exc.errno == errno.ELOOP:
                raise OutputError(f"{where}: {LOCK_NAME} is a symlink, not a regular file: "
                                  "remove it") from None
            raise OutputError(f"{where} {_reason(exc)}") from None
        mode = os.fstat(fd).st_mode
        if not stat.S_ISREG(mode):
            os.close(fd)
            raise OutputError(f"{where}: {LOCK_NAME} is {_kind(mode)}, not a regular file: "
                              "remove it")
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            holder = os.pread(fd, 64, 0).decode("ascii", "replace").strip() or "?"
            os.close(fd)
            raise OutputError(f"{self.option} {str(self.target)!r} is being written by another "
                              f"tengfield command (pid {holder}); wait for it or choose another "
                              "directory") from None
        now = _lstat(path)
        if now is None or (now.st_ino, now.st_dev) != (os.fstat(fd).st_ino, os.fstat(fd).st_dev):
            # the command that held it removed the file as it ended: the lock is the
            # path's file, take it again
            os.close(fd)
            if _retries <= 0:
                raise OutputError(f"{where}: {LOCK_NAME} keeps being replaced: another "
                                  "process is writing there; choose another directory")
            return self._lock(_retries - 1)
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        self._lock_fd = fd

    def _unlock(self) -> None:
        """Remove the lock file (no ``.tengfield.lock`` stays after a command: a command
        that opened it meanwhile finds it unlinked and takes the new one, :meth:`_lock`)
        and release the lock."""
        if self._lock_fd is not None:
            path = self.target / LOCK_NAME
            try:
                now, mine = _lstat(path), os.fstat(self._lock_fd)
                if now is not None and (now.st_ino, now.st_dev) == (mine.st_ino, mine.st_dev):
                    path.unlink()
            except OSError:
                pass
            os.close(self._lock_fd)   # closing releases the flock
            self._lock_fd = None

    def _cleanup(self, keep: bool = False) -> None:
        """Remove the staging directory (``keep``: leave it, it holds files a failed
        commit could not put back; the next command tries again) and unlock."""
        if self.staging is not None:
            if not keep:
                shutil.rmtree(self.staging, ignore_errors=True)
            self.staging = None
        self._unlock()

    def _read_manifest(self) -> set[str]:
        """The names the previous command wrote: only plain names inside DIR (a planted
        manifest naming "../x", "/x" or reaching through a symlink is ignored)."""
        data = _read_json(self.target / MANIFEST_NAME)
        files = data.get("files") if isinstance(data, dict) else None
        if not isinstance(files, list):
            return set()
        return {name for name in files if _plain_name(name) is not None}


def foreign_files(target: Path, staged: list[str], previous: set[str]) -> list[str]:
    """The names among ``staged`` whose destination in ``target`` holds a file (or a
    symlink) tengfield did not write: not in the ``previous`` command's manifest."""
    foreign = []
    for name in staged:
        if name in previous or name.split("/")[0].startswith(".tengfield"):
            continue
        if not _parents_are_directories(target, name):
            continue
        st = _lstat(target / name)
        if st is not None and (stat.S_ISREG(st.st_mode) or stat.S_ISLNK(st.st_mode)):
            foreign.append(name)
    return foreign


def _keep_foreign(target: Path, names: list[str]) -> list[tuple[str, Path]]:
    """A copy of each of ``names`` in ``target`` beside it as ``NAME.orig`` (a hard link,
    or a copy where the file system has none; a symlink as a symlink), so the commit's
    replacement loses nothing: ``[(name, copy)]``."""
    kept = []
    try:
        for name in names:
            src = target / name
            copy = src.with_name(src.name + ".orig")
            n = 2
            while _lstat(copy) is not None:
                copy = src.with_name(f"{src.name}.orig.{n}")
                n += 1
            if stat.S_ISLNK(os.lstat(src).st_mode):
                os.symlink(os.readlink(src), copy)
            else:
                try:
                    os.link(src, copy, follow_symlinks=False)
                except OSError:
                    shutil.copy2(src, copy, follow_symlinks=False)
            kept.append((name, copy))
    except OSError as exc:
        for _, copy in kept:
            copy.unlink(missing_ok=True)
        raise OutputError(f"-o {str(target)!r}: {name!r} there was not written by tengfield "
                          f"and could not be kept ({_reason(exc)}): nothing was replaced; "
                          "move it or choose another directory") from None
    return kept


def drop_staging(staging: str | Path, target: str | Path, created: bool) -> None:
    """Remove ``staging`` (and the lock and DIR when this command ``created`` DIR and
    nothing else is there): the clean-up of a rank that ends an MPI job whose rank 0
    (holding the :class:`StagedOutput`) is blocked and will be killed."""
    shutil.rmtree(staging, ignore_errors=True)
    if created:
        try:
            if {p.name for p in Path(target).iterdir()} <= {LOCK_NAME}:
                (Path(target) / LOCK_NAME).unlink(missing_ok=True)
        except OSError:
            pass


def _read_json(path: Path):
    """The JSON in the regular file ``path`` (never through a symlink), or None."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK)
    except OSError:
        return None
    with os.fdopen(fd, "rb") as fh:
        try:
            if not stat.S_ISREG(os.fstat(fd).st_mode):
                return None
            return json.loads(fh.read(1 << 24))
        except (OSError, ValueError):
            return None


def _inside(base: Path, name: str) -> bool:
    """``base/name`` exists and is reached through real directories from ``base``."""
    return _parents_are_directories(base, name) and _lstat(base / name) is not None


def _read_journal(staging: Path) -> list[tuple[str, bool]] | None:
    """The moves a commit into ``staging``'s DIR had begun (None: none under way)."""
    tx = staging / TX_NAME
    st = _lstat(tx)
    if st is None or not stat.S_ISDIR(st.st_mode):
        return None
    data = _read_json(tx / JOURNAL_NAME)
    if data is None:
        return None
    moves = data.get("moves") if isinstance(data, dict) else None
    if not isinstance(moves, list):
        return []
    plain = []
    for move in moves:
        if not isinstance(move, dict):
            continue
        name = move.get("name")
        if name == MANIFEST_NAME or _plain_name(name) is not None:
            plain.append((name, bool(move.get("staged"))))
    return plain


# ---------------------------------------------------------------------------
# whose files an output directory holds (issue #42)
#: in -o DIR: the name of the tengfield command whose files DIR holds (written with them)
COMMAND_RECORD = ".tengfield-command"


def record_command(staging: str | Path, command: str) -> None:
    """Note in the staging directory of ``-o DIR`` which command writes its files (moved
    into DIR with them, listed in its manifest)."""
    Path(staging, COMMAND_RECORD).write_text(command + "\n")


def refuse_another_commands_directory(target: str | Path, command: str,
                                      option: str = "-o") -> None:
    """Raise :class:`~tengfield.errors.OutputError` (one line) when ``-o DIR`` holds the
    files of a different tengfield command: writing there would remove them (a
    directory keeps one command's complete set). Nothing is checked for a DIR with no
    record (new, or not written by tengfield)."""
    record = Path(target, COMMAND_RECORD)
    try:
        owner = record.read_text().strip() if record.is_file() else ""
    except OSError:
        return
    if not owner or owner == command:
        return
    manifest = Path(target, ".tengfield-manifest.json")
    try:
        names = [n for n in json.loads(manifest.read_text()).get("files", [])
                 if n != COMMAND_RECORD and Path(target, n).is_file()]
    except (OSError, ValueError, AttributeError):
        names = []
    shown = ", ".join(names[:3]) + (", ..." if len(names) > 3 else "")
    raise OutputError(f"{option} {str(target)!r} holds the files of `tengfield {owner}`"
                      + (f" ({shown})" if shown else "")
                      + f"; `tengfield {command}` would replace them: nothing was written; "
                        f"choose another {option} directory")
