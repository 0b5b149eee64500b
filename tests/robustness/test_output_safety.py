"""#21 items 10-12 (safety of files): a planted manifest never reaches outside -o DIR,
special files are never replaced, the final move of an output set is all-or-nothing,
and -o "" / over-long names are refused with a line naming -o."""
import json
import os
import stat
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from tengfield import cli
from tengfield.files.directory import LOCK_NAME, MANIFEST_NAME, STAGING_PREFIX, OutputError, StagedOutput


def run_main(argv, capsys):
    code = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def write_set(target: Path, files: dict[str, str]) -> None:
    """One committed output set ``name -> text`` in ``target``."""
    with StagedOutput(target) as staging:
        for name, text in files.items():
            (staging / name).parent.mkdir(parents=True, exist_ok=True)
            (staging / name).write_text(text)


def visible(directory: Path) -> dict[str, str]:
    return {p.name: p.read_text() for p in sorted(directory.iterdir())
            if p.is_file() and not p.is_symlink() and not p.name.startswith(".")}


def no_staging_left(directory: Path) -> bool:
    return not list(directory.glob(STAGING_PREFIX + "*"))


@pytest.fixture
def never_solve(monkeypatch):
    import tengfield.surrogate as surrogate

    def never(*a, **k):
        raise AssertionError("field solves ran before the output location was checked")

    monkeypatch.setattr(surrogate, "precompute", never)


# -- item 10: a planted manifest --------------------------------------------------------
def plant(tmp_path: Path) -> tuple[Path, dict[Path, str]]:
    """DIR with a planted manifest naming files outside it (relative, absolute, through
    symlinks, nested); returns DIR and the victims with their contents."""
    out = tmp_path / "out"
    out.mkdir()
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    victims = {tmp_path / "victim.txt": "relative victim",
               tmp_path / "abs-victim.txt": "absolute victim",
               elsewhere / "x.txt": "behind a symlinked directory",
               elsewhere / "linked.txt": "behind a symlinked file",
               elsewhere / "tmp-target.txt": "behind the manifest's temporary file",
               elsewhere / "new.txt": "behind a symlink a new file replaces"}
    for path, text in victims.items():
        path.write_text(text)
    (out / "linkdir").symlink_to(elsewhere)
    (out / "link.txt").symlink_to(elsewhere / "linked.txt")
    (out / "new.txt").symlink_to(elsewhere / "new.txt")
    (out / (MANIFEST_NAME + ".tmp")).symlink_to(elsewhere / "tmp-target.txt")
    (out / "sub").mkdir()
    (out / MANIFEST_NAME).write_text(json.dumps({"files": [
        "../victim.txt", str(tmp_path / "abs-victim.txt"), "link.txt", "linkdir/x.txt",
        "sub/../../victim.txt", "./../victim.txt", "sub/../../elsewhere/x.txt", "",
        "linkdir", "..", "/", 3, None, "linkdir/../victim.txt", "sub//x", LOCK_NAME]}))
    return out, victims


def test_planted_manifest_touches_nothing_outside_dir(tmp_path):
    out, victims = plant(tmp_path)
    with StagedOutput(out) as staging:
        (staging / "a.txt").write_text("new a")
        (staging / "new.txt").write_text("new file where a symlink was")
    for path, text in victims.items():
        assert path.read_text() == text, path
    assert (out / "a.txt").read_text() == "new a"
    assert (out / "new.txt").read_text() == "new file where a symlink was"
    assert not (out / "new.txt").is_symlink()                  # the link replaced, not its target
    assert (out / "link.txt").is_symlink() and (out / "linkdir").is_symlink()
    assert json.loads((out / MANIFEST_NAME).read_text()) == {"files": ["a.txt", "new.txt"]}
    assert no_staging_left(out)


def test_planted_lock_symlink_truncates_nothing(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    victim = tmp_path / "victim.txt"
    victim.write_text("keep me")
    (out / LOCK_NAME).symlink_to(victim)
    with pytest.raises(OutputError, match=f"-o .*{LOCK_NAME} is a symlink, not a regular file"):
        StagedOutput(out).open()
    assert victim.read_text() == "keep me"


def test_planted_leftover_journal_touches_nothing_outside(tmp_path):
    """The journal a killed commit leaves is read by the next command: a planted one
    must not reach outside DIR either."""
    out, victims = plant(tmp_path)
    leftover = out / (STAGING_PREFIX + "planted")
    (leftover / ".tengfield-tx").mkdir(parents=True)
    names = ["../victim.txt", str(tmp_path / "abs-victim.txt"), "linkdir/x.txt", "link.txt"]
    (leftover / ".tengfield-tx" / "journal.json").write_text(json.dumps(
        {"moves": [{"name": n, "staged": True} for n in names]}))
    with StagedOutput(out) as staging:
        (staging / "a.txt").write_text("new a")
    for path, text in victims.items():
        assert path.read_text() == text, path
    assert no_staging_left(out)


@pytest.mark.slow
def test_planted_manifest_cli_run_succeeds(tmp_path, short_scene, capsys):
    out, victims = plant(tmp_path)
    code, stdout, err = run_main(["dynamics", short_scene, "--no-plots", "-o", out], capsys)
    assert code == 0, err
    for path, text in victims.items():
        assert path.read_text() == text, path
    assert set(visible(out)) == {"impacts.csv", "summary.json", "trajectory.csv"}


# -- item 11: special files -------------------------------------------------------------
def special_files(tmp_path: Path) -> dict[Path, str]:
    fifo = tmp_path / "fifo.h5"
    os.mkfifo(fifo)
    device = tmp_path / "null.h5"
    os.mknod(device, 0o666 | stat.S_IFCHR, os.makedev(1, 3))     # root: a /dev/null twin
    return {fifo: "a named pipe (FIFO)", device: "a character device",
            Path("/dev/null"): "a character device"}


def kind(path: Path) -> int:
    return stat.S_IFMT(os.lstat(path).st_mode)


@pytest.mark.skipif(os.geteuid() != 0, reason="device nodes need root")
def test_precompute_refuses_special_files(tmp_path, capsys, never_solve):
    for path, what in special_files(tmp_path).items():
        before = kind(path)
        code, out, err = run_main(["precompute", "-o", path], capsys)
        assert code == 2, err
        assert err == (f"tengfield: error: -o {str(path)!r} is {what}, not a regular file: "
                       "give a file name\n")
        assert "wrote" not in out and kind(path) == before


def test_precompute_checks_again_before_writing(tmp_path, capsys, monkeypatch):
    """A FIFO put at -o FILE while the field solves ran is not replaced either."""
    import tengfield.surrogate as surrogate

    target = tmp_path / "s.h5"

    def solves(*a, **k):
        os.mkfifo(target)
        return object()

    monkeypatch.setattr(surrogate, "precompute", solves)
    code, out, err = run_main(["precompute", "-o", target], capsys)
    assert code == 2 and "wrote" not in out
    assert err == (f"tengfield: error: -o {str(target)!r} is a named pipe (FIFO), not a "
                   "regular file: give a file name\n")
    assert stat.S_ISFIFO(os.lstat(target).st_mode)


@pytest.mark.skipif(os.geteuid() != 0, reason="device nodes need root")
def test_directory_commands_refuse_special_files(tmp_path, capsys):
    for path, what in special_files(tmp_path).items():
        code, out, err = run_main(["dynamics", "-o", path], capsys)
        assert code == 2, err
        assert err == f"tengfield: error: -o {str(path)!r} is {what}, not a directory\n"
        assert path.exists() and not path.is_dir()


def test_special_file_inside_dir_is_not_replaced(tmp_path):
    out = tmp_path / "out"
    write_set(out, {"a.txt": "old a", "c.txt": "old c"})
    os.mkfifo(out / "b.txt")
    with pytest.raises(OutputError, match=r"-o .*b\.txt.* is a named pipe \(FIFO\), not a "
                                          r"regular file"):
        write_set(out, {"a.txt": "new a", "b.txt": "new b", "c.txt": "new c"})
    assert stat.S_ISFIFO(os.lstat(out / "b.txt").st_mode)
    assert visible(out) == {"a.txt": "old a", "c.txt": "old c"} and no_staging_left(out)


# -- item 12: all-or-nothing, -o "", long names --------------------------------------------
def test_directory_where_a_file_goes_replaces_nothing(tmp_path):
    out = tmp_path / "out"
    write_set(out, {"a.txt": "old a", "c.txt": "old c", "gone.txt": "old stale"})
    (out / "b.txt").mkdir()
    (out / "b.txt" / "mine").write_text("user's")
    with pytest.raises(OutputError, match=r"-o .*b\.txt.* is a directory"):
        write_set(out, {"a.txt": "new a", "b.txt": "new b", "c.txt": "new c"})
    assert visible(out) == {"a.txt": "old a", "c.txt": "old c", "gone.txt": "old stale"}
    assert (out / "b.txt" / "mine").read_text() == "user's" and no_staging_left(out)
    assert json.loads((out / MANIFEST_NAME).read_text())["files"] == ["a.txt", "c.txt",
                                                                        "gone.txt"]


def test_a_move_failing_midway_rolls_back(tmp_path, monkeypatch):
    out = tmp_path / "out"
    write_set(out, {"a.txt": "old a", "c.txt": "old c", "gone.txt": "old stale"})
    real_replace = os.replace

    def flaky(src, dst, *a, **k):
        if Path(dst) == out / "c.txt" and "new" in Path(src).read_text():
            raise OSError(5, "Input/output error", str(dst))
        return real_replace(src, dst, *a, **k)

    monkeypatch.setattr(os, "replace", flaky)
    with pytest.raises(OSError, match="Input/output error"):
        write_set(out, {"a.txt": "new a", "b.txt": "new b", "c.txt": "new c"})
    monkeypatch.undo()
    assert visible(out) == {"a.txt": "old a", "c.txt": "old c", "gone.txt": "old stale"}
    assert json.loads((out / MANIFEST_NAME).read_text())["files"] == ["a.txt", "c.txt",
                                                                        "gone.txt"]
    assert no_staging_left(out)


def test_kill_9_in_the_middle_of_the_move_is_rolled_back_next_time(tmp_path, cli_env):
    out = tmp_path / "out"
    write_set(out, {"a.txt": "old a", "c.txt": "old c", "gone.txt": "old stale"})
    script = textwrap.dedent(f"""
        import os, signal
        from pathlib import Path
        from tengfield.files.directory import StagedOutput
        real = os.replace
        def dying(src, dst, *a, **k):   # killed as the last new file goes into place
            if Path(dst) == Path({str(out / "c.txt")!r}):
                os.kill(os.getpid(), signal.SIGKILL)
            return real(src, dst, *a, **k)
        os.replace = dying
        with StagedOutput({str(out)!r}) as staging:
            for name in ("a.txt", "b.txt", "c.txt"):
                (staging / name).write_text("new " + name[0])
    """)
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          env=cli_env())
    assert proc.returncode == -9, proc.stderr
    assert visible(out) != {"a.txt": "old a", "c.txt": "old c", "gone.txt": "old stale"}
    following = StagedOutput(out)     # the next command: the killed move is undone first
    following.open()
    following.abort()
    assert visible(out) == {"a.txt": "old a", "c.txt": "old c", "gone.txt": "old stale"}
    assert no_staging_left(out)


@pytest.mark.parametrize("command", [["dynamics"], ["precompute"]])
def test_empty_output_is_refused(command, tmp_path, capsys, monkeypatch, never_solve):
    monkeypatch.chdir(tmp_path)
    code, out, err = run_main(command + ["-o", ""], capsys)
    assert code == 2
    assert err.startswith("tengfield: error: -o '' is empty") and err.count("\n") == 1
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("length", [300, 250])
def test_long_names_name_the_option(length, tmp_path, capsys, never_solve):
    """300 characters: longer than a name may be; 250 (+ ".h5"): the file's name fits
    but its temporary file's would not, found before any solve."""
    long = tmp_path / ("a" * length)
    for command, target in ((["dynamics"], long), (["precompute"], f"{long}.h5")):
        if command == ["dynamics"] and length < 255:
            continue
        code, out, err = run_main(command + ["-o", target], capsys)
        assert code == 2, err
        assert err.startswith(f"tengfield: error: -o {str(target)!r}") and "too long" in err
        assert err.count("\n") == 1
    assert list(tmp_path.iterdir()) == []


# -- under mpirun the commands write into DIR itself: the writers' own guard ---------------
def test_writers_never_write_through_a_symlink_or_into_a_pipe(tmp_path):
    from types import SimpleNamespace

    from tengfield import io as writers

    out = tmp_path / "out"
    out.mkdir()
    victim = tmp_path / "victim.csv"
    victim.write_text("keep me")
    three = np.arange(3.0)
    dynamics = SimpleNamespace(lateral=False, t=three, gap=three, gap_velocity=three, table=three,
                               impacts=SimpleNamespace(time=three, plate=np.array(["upper"] * 3),
                                                       speed_before=three, speed_after=three))
    scene = SimpleNamespace(contact=SimpleNamespace(model="impact"))
    writes = {"trajectory.csv": lambda: writers.write_dynamics_files(dynamics, scene, out,
                                                                     plots=False),
              "summary.json": lambda: writers.write_json(out / "summary.json", {"a": 1})}
    for name, write in writes.items():
        (out / name).symlink_to(victim)
        write()
        assert victim.read_text() == "keep me", name
        assert (out / name).is_file() and not (out / name).is_symlink()
        (out / name).unlink()
        os.mkfifo(out / name)
        reader = os.open(out / name, os.O_RDONLY | os.O_NONBLOCK)   # no hang before the fix
        try:
            with pytest.raises(OutputError, match=r"is a named pipe \(FIFO\), not a regular file"):
                write()
        finally:
            os.close(reader)
        assert stat.S_ISFIFO(os.lstat(out / name).st_mode)
        (out / name).unlink()
