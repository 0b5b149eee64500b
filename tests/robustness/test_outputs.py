"""#8.11, #8.12, #8.16, #8.10: output directories checked first, written all-or-nothing,
locked against a concurrent writer; Ctrl-C and --jobs at the CLI."""
import errno
import hashlib
import os
import signal
import subprocess
import time
from pathlib import Path

import pytest

from tengfield import _mpi, cli
from tengfield.plotting.process import Drawing, FigureProcess
from tengfield.files.directory import LOCK_NAME, MANIFEST_NAME, STAGING_PREFIX, OutputError, StagedOutput


def snapshot(directory: Path) -> dict[str, str]:
    """name -> sha256 of every visible file (the user's view of an output set)."""
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(directory.iterdir()) if p.is_file() and not p.name.startswith(".")}


def no_staging_left(directory: Path) -> bool:
    return not list(directory.glob(STAGING_PREFIX + "*"))


def run_main(argv, capsys):
    code = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


# -- #8.11: the output location is checked before any computation -------------------------
def test_output_that_is_a_file_fails_first(tmp_path, capsys, monkeypatch):
    import tengfield.dynamics as dynamics

    def never(*a, **k):
        raise AssertionError("the simulation ran before the output directory was checked")

    monkeypatch.setattr(dynamics, "simulate", never)
    target = tmp_path / "taken"
    target.write_text("not a directory")
    code, out, err = run_main(["dynamics", "-o", target], capsys)
    assert code == 2
    assert err == f"tengfield: error: -o {str(target)!r} is a file, not a directory\n"
    code, out, err = run_main(["dynamics", "-o", target / "below"], capsys)
    assert code == 2 and "is a file, not a directory" in err and err.count("\n") == 1
    assert target.read_text() == "not a directory"


def test_read_only_place_fails_first(tmp_path, capsys):
    # /sys refuses mkdir even to root (a chmod'ed directory would not stop root)
    code, out, err = run_main(["dynamics", "-o", "/sys/tengfield-out"], capsys)
    assert code == 2
    assert err == ("tengfield: error: -o '/sys/tengfield-out' could not be created: is not "
                   "writable (read-only or no permission)\n")


def test_precompute_output_file_checks_its_directory(tmp_path, capsys, monkeypatch):
    import tengfield.surrogate as surrogate

    def never(*a, **k):
        raise AssertionError("field solves ran before the output location was checked")

    monkeypatch.setattr(surrogate, "precompute", never)
    (tmp_path / "file").write_text("x")
    code, out, err = run_main(["precompute", "-o", tmp_path / "file" / "s.h5"], capsys)
    assert code == 2 and "'file' is a file, not a directory" in err.replace(str(tmp_path) + "/", "")
    code, out, err = run_main(["precompute", "-o", tmp_path], capsys)
    assert code == 2 and "is a directory: give a file name" in err


def test_bad_scene_leaves_no_new_directory(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text("[contact]\nrestitution = 2\n")
    code, out, err = run_main(["dynamics", bad, "-o", tmp_path / "new"], capsys)
    assert code == 2 and "restitution" in err
    assert not (tmp_path / "new").exists()


# -- #8.12: all-or-nothing outputs --------------------------------------------------------
@pytest.mark.slow
def test_success_replaces_the_set_and_prints_the_real_directory(tmp_path, short_scene, capsys):
    out_dir = tmp_path / "out"
    code, out, err = run_main(["dynamics", short_scene, "-o", out_dir], capsys)
    assert code == 0, err
    assert f"-> {out_dir}/" in out and STAGING_PREFIX not in out + err
    assert set(snapshot(out_dir)) == {"impacts.csv", "summary.json", "trajectory.csv",
                                      "trajectory.png"}
    assert no_staging_left(out_dir) and (out_dir / MANIFEST_NAME).is_file()


@pytest.mark.slow
def test_failing_command_keeps_the_previous_set(tmp_path, short_scene, capsys, monkeypatch):
    import tengfield.dynamics.output as writers   # the dynamics command's table writers

    out_dir = tmp_path / "out"
    assert run_main(["dynamics", short_scene, "-o", out_dir], capsys)[0] == 0
    before = snapshot(out_dir)
    written = []

    def full_disk(result, path):   # half a file written, then the disk is full
        Path(path).write_text("time_s,plate\n0.0123,lo")
        written.extend(p.name for p in Path(path).parent.iterdir())
        raise OSError(errno.ENOSPC, "No space left on device", str(path))

    monkeypatch.setattr(writers, "write_impacts_csv", full_disk)
    longer = short_scene.with_name("longer.toml")
    longer.write_text(short_scene.read_text().replace("0.3", "0.5"))
    code, out, err = run_main(["dynamics", longer, "-o", out_dir], capsys)
    assert "impacts.csv" in written                     # the failure left a partial file
    assert code == 1
    assert err == f"tengfield: error: No space left on device: {out_dir / 'impacts.csv'}\n"
    assert snapshot(out_dir) == before                         # old set intact, nothing partial
    assert no_staging_left(out_dir)


@pytest.mark.slow
def test_a_full_disk_without_a_file_name_names_the_directory(tmp_path, short_scene, capsys,
                                                             monkeypatch):
    """A write error that carries no file name (a PNG or JSON flushed onto a full disk:
    OSError(28) only) names the output directory, not nothing."""
    import tengfield.files as writers       # the one home of write_json (issue #41)

    out_dir = tmp_path / "out"
    assert run_main(["dynamics", short_scene, "-o", out_dir], capsys)[0] == 0
    before = snapshot(out_dir)

    def full_disk(path, data):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(writers, "write_json", full_disk)
    code, out, err = run_main(["dynamics", short_scene, "-o", out_dir], capsys)
    assert code == 1
    assert err == f"tengfield: error: No space left on device: {out_dir}\n"
    assert snapshot(out_dir) == before and no_staging_left(out_dir)


@pytest.mark.slow
@pytest.mark.parametrize("figure_process", ["1", "0"])
def test_exception_and_interrupt_keep_the_previous_set(tmp_path, short_scene, capsys,
                                                       monkeypatch, figure_process):
    """A fault while the figure is drawn, here (TENGFIELD_FIGURE_PROCESS=0) or while this
    process waits for the figure process: the previous set stays, nothing is left."""
    monkeypatch.setenv("TENGFIELD_FIGURE_PROCESS", figure_process)
    out_dir = tmp_path / "out"
    assert run_main(["dynamics", short_scene, "-o", out_dir], capsys)[0] == 0
    before = snapshot(out_dir)
    started = []
    real_init = FigureProcess.__init__

    def init(self):
        real_init(self)
        started.append(self._proc)

    monkeypatch.setattr(FigureProcess, "__init__", init)
    for fault, code_expected, line in ((KeyboardInterrupt, 130, "tengfield: interrupted\n"),
                                       (RuntimeError("bug"), None, None)):
        def plot(*a, _fault=fault, **k):
            raise _fault

        if figure_process == "0":
            monkeypatch.setattr("tengfield.plotting.dynamics.draw_trajectory", plot)
        else:
            monkeypatch.setattr(Drawing, "result", plot)
        if code_expected is None:
            with pytest.raises(RuntimeError, match="bug"):   # a bug keeps its traceback
                cli.main(["dynamics", str(short_scene), "-o", str(out_dir)])
            capsys.readouterr()
        else:
            code, out, err = run_main(["dynamics", short_scene, "-o", out_dir], capsys)
            assert code == code_expected and err == line
        assert snapshot(out_dir) == before and no_staging_left(out_dir)
    assert len(started) == 2
    for child in started:               # no figure process outlives its command
        if figure_process == "0":
            assert child is None
        else:
            assert child.poll() == -signal.SIGKILL     # killed at once by the fault


@pytest.mark.slow
def test_stale_files_of_the_previous_command_are_removed(tmp_path, short_scene, capsys):
    out_dir = tmp_path / "out"
    assert run_main(["dynamics", short_scene, "-o", out_dir], capsys)[0] == 0
    (out_dir / "notes.txt").write_text("mine")                 # not written by tengfield
    # the same command again without figures: its PNGs of the first set are stale
    # (another command's -o is refused: tests/robustness/test_output_of_another_command.py)
    code, out, err = run_main(["dynamics", short_scene, "--no-plots", "-o", out_dir], capsys)
    assert code == 0, err
    assert set(snapshot(out_dir)) == {"trajectory.csv", "impacts.csv", "summary.json",
                                      "notes.txt"}


def test_staged_output_unit(tmp_path):
    target = tmp_path / "out"
    with StagedOutput(target) as staging:
        (staging / "a.txt").write_text("1")
        (staging / "sub").mkdir()
        (staging / "sub" / "b.txt").write_text("2")
        assert not (target / "a.txt").exists()                 # nothing visible before the end
    assert (target / "a.txt").read_text() == "1" and (target / "sub" / "b.txt").read_text() == "2"
    with pytest.raises(ValueError):
        with StagedOutput(target) as staging:
            (staging / "a.txt").write_text("half")
            raise ValueError
    assert (target / "a.txt").read_text() == "1" and no_staging_left(target)


# -- #8.12: a lock for concurrent writers -------------------------------------------------
@pytest.mark.slow
def test_concurrent_writer_gets_a_clear_error(tmp_path, short_scene, capsys):
    out_dir = tmp_path / "out"
    holder = StagedOutput(out_dir)
    holder.open()
    try:
        code, out, err = run_main(["dynamics", short_scene, "-o", out_dir], capsys)
        assert code == 2
        assert err == (f"tengfield: error: -o {str(out_dir)!r} is being written by another "
                       f"tengfield command (pid {os.getpid()}); wait for it or choose another "
                       "directory\n")
        with pytest.raises(OutputError, match="being written"):
            StagedOutput(out_dir).open()
    finally:
        holder.abort()
    assert run_main(["dynamics", short_scene, "-o", out_dir], capsys)[0] == 0   # lock released
    assert not (out_dir / LOCK_NAME).exists()     # and removed (issue #53)


# -- #8.16 CLI side and #8.12 with real processes: Ctrl-C while writing, a second writer ---
def start_writing_a_long_run(tmp_path, out_dir, cli_command, cli_env, **popen):
    """A `tengfield dynamics` of 300 s (6e6 samples: seconds of CSV) into ``out_dir``,
    returned once it is writing trajectory.csv into its staging directory."""
    long_scene = tmp_path / "long.toml"
    long_scene.write_text("[run]\nduration_s = 300\n")
    proc = subprocess.Popen(cli_command("dynamics", long_scene, "-o", out_dir), cwd=tmp_path,
                            env=cli_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, **popen)
    deadline = time.monotonic() + 300
    while not list(out_dir.glob(STAGING_PREFIX + "*/trajectory.csv")):
        if proc.poll() is not None or time.monotonic() > deadline:
            proc.kill()
            pytest.fail(f"the long run never wrote trajectory.csv: {proc.communicate()}")
        time.sleep(0.05)
    return proc


@pytest.mark.slow
def test_ctrl_c_while_writing_and_a_concurrent_run(tmp_path, short_scene, run_cli, cli_command,
                                                   cli_env, capsys):
    out_dir = tmp_path / "out"
    # the previous set, written in this process (the behaviour here is the interrupted
    # and the concurrent CLI processes below; a CLI process of its own costs an import)
    code, out, err = run_main(["dynamics", short_scene, "-o", out_dir], capsys)
    assert code == 0, err
    before = snapshot(out_dir)
    proc = start_writing_a_long_run(tmp_path, out_dir, cli_command, cli_env)
    try:
        second = run_cli("dynamics", short_scene, "-o", out_dir, cwd=tmp_path)
        assert second.returncode == 2
        assert "is being written by another tengfield command" in second.stderr
        assert second.stderr.count("\n") == 1
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 130
    assert err.endswith("tengfield: interrupted\n") and "Traceback" not in err
    assert snapshot(out_dir) == before and no_staging_left(out_dir)


@pytest.mark.slow
def test_ctrl_c_at_the_terminal_stops_the_figure_process_too(tmp_path, short_scene,
                                                            cli_command, cli_env, capsys):
    """Ctrl-C at a terminal signals the whole process group. Exit 130 with one line, no
    traceback, the old set kept, and neither the command nor its figure process (which
    has a group of its own) left behind. The old set is written in this process."""
    out_dir = tmp_path / "out"
    assert run_main(["dynamics", short_scene, "-o", out_dir], capsys)[0] == 0
    before = snapshot(out_dir)
    proc = start_writing_a_long_run(tmp_path, out_dir, cli_command, cli_env,
                                    start_new_session=True)
    try:
        children = child_pids(proc.pid)
        assert len(children) == 1                 # the figure process
        os.killpg(proc.pid, signal.SIGINT)
        out, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert proc.returncode == 130
    assert err == "tengfield: interrupted\n", err
    assert snapshot(out_dir) == before and no_staging_left(out_dir)
    deadline = time.monotonic() + 10
    while Path(f"/proc/{children[0]}").exists():
        assert time.monotonic() < deadline, "the figure process outlived the command"
        time.sleep(0.05)


def child_pids(pid: int) -> list[int]:
    """The processes whose parent is ``pid`` (Linux /proc)."""
    found = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == pid:
            found.append(int(stat.parent.name))
    return found


# -- #8.10: --jobs bounds -----------------------------------------------------------------
@pytest.mark.parametrize("jobs", [0, -1, 1000])
def test_jobs_out_of_range_is_refused(jobs, capsys):
    limit = _mpi.JOBS_PER_CORE_LIMIT * (os.cpu_count() or 1)
    for command in (["map", "--frequency-hz", "20", "--amplitude-mm", "1"],
                    ["sweep", "--frequency-hz", "20", "--amplitude-mm", "1"]):
        code, out, err = run_main(command + ["--jobs", str(jobs)], capsys)
        assert code == 2
        assert err == (f"tengfield: error: --jobs = {jobs} is out of range: allowed [1, {limit}] "
                       f"({_mpi.JOBS_PER_CORE_LIMIT} x the {os.cpu_count()} cores)\n")
