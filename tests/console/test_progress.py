"""#29 progress: long commands show ``done/total`` and an ETA on a terminal (stderr a
pseudo-terminal here), and print no bar when stderr is piped or with ``--quiet``
(``tengfield._console.progress_bar``, the one helper)."""
from __future__ import annotations

import os
import pty
import re
import subprocess

import pytest

COARSE = ("[field]\ndegree = 1\nmesh_size_mm = 1.5\ntolerance = 0.5\n"
          "[run]\nduration_s = 0.3\nsettle_periods = 2\nsample_rate_hz = 2000\n")

#: what a tqdm bar shows: "3/3 [00:01<00:00, ...]" (done/total, elapsed<ETA)
BAR = re.compile(r"(\d+)/(\d+) \[[0-9:]+<[0-9:?]+")


def _on_terminal(command, env, cwd, timeout=900) -> tuple[int, str, str]:
    """Run ``command`` with stderr on a pseudo-terminal; (exit code, stdout, terminal text)."""
    master, slave = pty.openpty()
    proc = subprocess.Popen(command, cwd=cwd, env=env, stdin=subprocess.DEVNULL,
                            stdout=subprocess.PIPE, stderr=slave)
    os.close(slave)
    chunks = []
    while True:
        try:
            data = os.read(master, 65536)
        except OSError:          # EIO: the last writer closed the terminal
            break
        if not data:
            break
        chunks.append(data)
    os.close(master)
    out = proc.stdout.read().decode()
    proc.wait(timeout=timeout)
    return proc.returncode, out, b"".join(chunks).decode(errors="replace")


def _counts(text: str) -> list[tuple[int, int]]:
    return [(int(a), int(b)) for a, b in BAR.findall(text)]


@pytest.mark.slow
def test_map_shows_done_over_total_on_a_terminal_and_nothing_when_piped(tmp_path, cli_command,
                                                                        cli_env, run_cli):
    args = ("map", "--frequency-hz", "15:25:3", "--amplitude-mm", "1:2:2", "--periods", "20",
            "--jobs", "1", "--no-plots")
    code, _, tty = _on_terminal(cli_command(*args, "-o", "a"), cli_env(), tmp_path)
    assert code == 0, tty
    counts = _counts(tty)
    assert counts and counts[-1] == (6, 6), tty          # 3 x 2 points, all done
    assert "regime map" in tty
    piped = run_cli(*args, "-o", "b", cwd=tmp_path)
    assert piped.returncode == 0, piped.stderr
    assert not _counts(piped.stderr) and "regime map" not in piped.stderr, piped.stderr
    code, _, quiet = _on_terminal(cli_command("--quiet", *args, "-o", "c"), cli_env(), tmp_path)
    assert code == 0, quiet
    assert not _counts(quiet), quiet
    code, _, quiet = _on_terminal(cli_command(*args, "-o", "d", "--quiet"), cli_env(), tmp_path)
    assert code == 0, quiet
    assert not _counts(quiet), quiet


@pytest.mark.slow
@pytest.mark.field
def test_sweep_shows_done_over_total_on_a_terminal_and_nothing_when_piped(tmp_path, cli_command,
                                                                          cli_env, run_cli):
    scene = tmp_path / "coarse.toml"
    scene.write_text(COARSE)
    env = cli_env(TENGFIELD_CACHE_DIR=str(tmp_path / "cache"))
    args = ("sweep", scene, "--frequency-hz", "20:30:2", "--amplitude-mm", "1.5", "--jobs", "1")
    code, out, tty = _on_terminal(cli_command(*args, "-o", "a"), env, tmp_path)
    assert code == 0, tty
    assert (2, 2) in _counts(tty), tty                   # the sweep's two points
    assert "sweep" in tty
    piped = run_cli(*args, "-o", "b", cwd=tmp_path, env=env)
    assert piped.returncode == 0, piped.stderr
    assert not _counts(piped.stderr), piped.stderr
    assert "\r" not in piped.stderr


def test_the_helper_is_silent_off_a_terminal_and_with_quiet(monkeypatch, capsys):
    from tengfield import _console

    class Terminal:
        def __init__(self):
            self.text = []

        def isatty(self):
            return True

        def write(self, s):
            self.text.append(s)

        def flush(self):
            pass

    term = Terminal()
    monkeypatch.setattr("sys.stderr", term)
    monkeypatch.delenv("TENGFIELD_QUIET", raising=False)
    bar = _console.progress_bar(4, "things")
    bar.update(4)
    bar.close()
    assert "4/4" in "".join(term.text)
    term.text.clear()
    monkeypatch.setattr(_console, "_quiet", True)
    bar = _console.progress_bar(4, "things")
    bar.update(4)
    bar.close()
    assert "".join(term.text) == ""
    monkeypatch.setattr(_console, "_quiet", False)
    assert not _console.progress_shown(False)

    class Rank1:
        def Get_rank(self):
            return 1
    assert not _console.progress_shown(True, Rank1())
    monkeypatch.setattr("sys.stderr", capsys)       # no isatty: not a terminal
    assert not _console.progress_shown(True)
