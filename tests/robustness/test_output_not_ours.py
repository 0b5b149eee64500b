"""Issue #53: a file in ``-o DIR`` that tengfield did not write is never replaced silently
(it is kept as NAME.orig, one warning line naming both), and no ``.tengfield.lock`` stays
after a command."""
import json
import warnings

import pytest

from tengfield import cli
from tengfield.files.directory import LOCK_NAME, MANIFEST_NAME, StagedOutput


def run_main(argv, capsys):
    code = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_a_users_file_is_kept_beside_the_new_one(tmp_path):
    target = tmp_path / "out"
    target.mkdir()
    (target / "summary.json").write_text('{"mine": 1}\n')
    (target / "notes.txt").write_text("my notes\n")            # not written: untouched
    with pytest.warns(UserWarning, match=r"'summary.json' there was not written by tengfield: "
                                         r"kept it as 'summary.json.orig'"):
        with StagedOutput(target) as staging:
            (staging / "summary.json").write_text('{"tool": 1}\n')
    assert json.loads((target / "summary.json").read_text()) == {"tool": 1}
    assert json.loads((target / "summary.json.orig").read_text()) == {"mine": 1}
    assert (target / "notes.txt").read_text() == "my notes\n"
    # the next command's summary.json replaces tengfield's own, with no copy and no word
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with StagedOutput(target) as staging:
            (staging / "summary.json").write_text('{"tool": 2}\n')
    assert json.loads((target / "summary.json").read_text()) == {"tool": 2}
    assert sorted(p.name for p in target.iterdir() if not p.name.startswith(".")) == \
        ["notes.txt", "summary.json", "summary.json.orig"]
    # a second foreign file of that name gets the next free name
    (target / "a.csv").write_text("x\n")
    (target / "a.csv.orig").write_text("older\n")
    with pytest.warns(UserWarning, match="kept it as 'a.csv.orig.2'"):
        with StagedOutput(target) as staging:
            (staging / "a.csv").write_text("tool\n")
    assert (target / "a.csv.orig.2").read_text() == "x\n"
    assert (target / "a.csv.orig").read_text() == "older\n"


def test_a_failed_commit_leaves_the_users_file_and_no_copy(tmp_path, monkeypatch):
    target = tmp_path / "out"
    target.mkdir()
    (target / "summary.json").write_text("mine\n")
    import os
    real = os.replace
    calls = {"n": 0}

    def failing(src, dst):
        calls["n"] += 1
        if calls["n"] == 2:
            raise OSError(28, "No space left on device")
        return real(src, dst)

    staged = StagedOutput(target)
    staging = staged.open()
    (staging / "summary.json").write_text("tool\n")
    monkeypatch.setattr(os, "replace", failing)
    with pytest.raises(OSError):
        staged.commit()
    monkeypatch.setattr(os, "replace", real)
    assert (target / "summary.json").read_text() == "mine\n"
    assert not (target / "summary.json.orig").exists()


def test_no_lock_file_stays_after_success_or_failure(tmp_path):
    target = tmp_path / "out"
    with StagedOutput(target) as staging:
        (staging / "a.txt").write_text("1")
    assert not (target / LOCK_NAME).exists() and (target / MANIFEST_NAME).is_file()
    with pytest.raises(ValueError):
        with StagedOutput(target) as staging:
            raise ValueError
    assert not (target / LOCK_NAME).exists() and (target / "a.txt").read_text() == "1"


def test_a_lock_unlinked_by_its_holder_is_taken_again(tmp_path, monkeypatch):
    """A command that opened the lock file just before its holder removed it locks the
    removed file: it must notice and lock the path's new file, so two commands never
    both hold DIR."""
    import fcntl
    import os

    from tengfield.errors import OutputError

    target = tmp_path / "out"
    target.mkdir()
    (target / LOCK_NAME).write_text("")
    real_flock, other = fcntl.flock, []

    def race(fd, op):
        if not other:   # between our open and our flock: the holder ends, a third starts
            os.unlink(target / LOCK_NAME)
            third = os.open(target / LOCK_NAME, os.O_RDWR | os.O_CREAT)
            real_flock(third, fcntl.LOCK_EX)
            other.append(third)
        return real_flock(fd, op)

    monkeypatch.setattr(fcntl, "flock", race)
    try:
        with pytest.raises(OutputError, match="being written by another"):
            StagedOutput(target).open()
    finally:
        os.close(other[0])


def test_the_cli_keeps_a_users_summary_json_and_leaves_no_lock(tmp_path, short_scene,
                                                                capsys):
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    (out_dir / "summary.json").write_text('{"my": "own"}\n')
    code, out, err = run_main(["dynamics", short_scene, "-o", out_dir], capsys)
    assert code == 0, err
    assert json.loads((out_dir / "summary.json.orig").read_text()) == {"my": "own"}
    assert "regime" in json.loads((out_dir / "summary.json").read_text())
    lines = [ln for ln in err.splitlines() if "not written by tengfield" in ln]
    assert len(lines) == 1 and lines[0].startswith("tengfield: warning: -o ")
    assert "'summary.json'" in lines[0] and "'summary.json.orig'" in lines[0]
    assert not (out_dir / LOCK_NAME).exists()
    code, out, err = run_main(["dynamics", short_scene, "-o", out_dir], capsys)
    assert code == 0 and "not written by tengfield" not in err
    assert not (out_dir / LOCK_NAME).exists()
    assert not (out_dir / "summary.json.orig.2").exists()
