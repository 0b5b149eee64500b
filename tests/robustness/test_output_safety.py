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

import pytest

from tengfield import cli
from tengfield.outputs import LOCK_NAME, MANIFEST_NAME, STAGING_PREFIX, OutputError, StagedOutput


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


# -- item 12: all-or-nothing, -o "", long names --------------------------------------------
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
