"""tengfield.plotting.process: figures drawn by a second process are the figures drawn
here, errors come back as errors, and a child that is gone never loses a figure."""
import os
import signal
from pathlib import Path

import numpy as np
import pytest

import figure_jobs
from tengfield.dynamics import simulate
from tengfield.plotting.dynamics import draw_trajectory, trajectory_figure
from tengfield.plotting.process import FigureProcess
from tengfield.scene import default_scene

TESTS = Path(__file__).resolve().parents[1]   # the tests' root (figure_jobs, plate_model)


@pytest.fixture
def jobs_importable(monkeypatch):
    """The child finds tests/figure_jobs.py."""
    path = os.environ.get("PYTHONPATH")
    monkeypatch.setenv("PYTHONPATH", str(TESTS) + (os.pathsep + path if path else ""))
    monkeypatch.delenv("TENGFIELD_FIGURE_PROCESS", raising=False)


@pytest.mark.slow
def test_the_child_draws_the_same_figure(tmp_path, monkeypatch):
    import matplotlib.image

    monkeypatch.delenv("TENGFIELD_FIGURE_PROCESS", raising=False)
    scene = default_scene()
    result = simulate(scene, duration=12 * scene.run.settle_periods / scene.excitation.frequency)
    data = trajectory_figure(result, title="test")
    assert data.t.size > 100 and data.impact_time.size > 0
    with FigureProcess() as figures:
        assert figures.running
        drawing = figures.draw(draw_trajectory, data, tmp_path / "child.png")
        assert drawing.result() == tmp_path / "child.png"
    draw_trajectory(data, tmp_path / "here.png")
    child = matplotlib.image.imread(tmp_path / "child.png")
    here = matplotlib.image.imread(tmp_path / "here.png")
    assert child.shape == here.shape and np.array_equal(child, here)


def test_answers_in_order_and_output_kept_apart(tmp_path, jobs_importable, capfd):
    with FigureProcess() as figures:
        drawings = [figures.draw(figure_jobs.noisy, tmp_path / f"{k}.txt") for k in range(3)]
        pids = [d.result() for d in reversed(drawings)]     # any order of waiting
    assert len(set(pids)) == 1 and pids[0] != os.getpid()  # all drawn by the child
    assert sorted(p.name for p in tmp_path.iterdir()) == ["0.txt", "1.txt", "2.txt"]
    err = capfd.readouterr().err
    assert err.count("a warning") == 3 and err.count("drawing") == 3


def test_errors_come_back_with_their_type(tmp_path, jobs_importable):
    with FigureProcess() as figures:
        failing = figures.draw(figure_jobs.broken, 42)
        missing_dir = figures.draw(figure_jobs.noisy, tmp_path / "no" / "such" / "f.txt")
        odd = figures.draw(figure_jobs.unpicklable)
        fine = figures.draw(figure_jobs.noisy, tmp_path / "ok.txt")
        with pytest.raises(ValueError, match="cannot draw 42") as info:
            failing.result()
        assert "in the figure process" in "".join(getattr(info.value, "__notes__", []))
        with pytest.raises(FileNotFoundError):
            missing_dir.result()
        with pytest.raises(RuntimeError, match="figure process"):
            odd.result()
        assert fine.result() != os.getpid()     # the child goes on after errors
    assert (tmp_path / "ok.txt").read_text() == "figure"


def test_a_child_that_dies_loses_no_figure(tmp_path, jobs_importable):
    with FigureProcess() as figures:
        figures.draw(figure_jobs.die)                # its result() would re-run it here
        second = figures.draw(figure_jobs.noisy, tmp_path / "after.txt")
        assert second.result() == os.getpid()        # drawn here instead
        assert not figures.running
        third = figures.draw(figure_jobs.noisy, tmp_path / "later.txt")
        assert third.result() == os.getpid()
    assert (tmp_path / "after.txt").exists() and (tmp_path / "later.txt").exists()


def test_a_child_killed_from_outside(tmp_path, jobs_importable):
    """Also with SIGPIPE's default action (PETSc installs a handler that aborts): sending
    to a child that has gone must not kill this process."""
    previous = signal.signal(signal.SIGPIPE, signal.SIG_DFL)
    try:
        with FigureProcess() as figures:
            os.kill(figures._proc.pid, signal.SIGKILL)
            figures._proc.wait()
            drawing = figures.draw(figure_jobs.noisy, tmp_path / "f.txt")
            again = figures.draw(figure_jobs.noisy, tmp_path / "g.txt")
            assert drawing.result() == os.getpid() and again.result() == os.getpid()
    finally:
        signal.signal(signal.SIGPIPE, previous)
    assert (tmp_path / "f.txt").exists() and (tmp_path / "g.txt").exists()


def test_switched_off_draws_here(tmp_path, jobs_importable, monkeypatch):
    monkeypatch.setenv("TENGFIELD_FIGURE_PROCESS", "0")
    with FigureProcess() as figures:
        assert not figures.running and figures._proc is None
        assert figures.draw(figure_jobs.noisy, tmp_path / "f.txt").result() == os.getpid()


def test_an_exception_in_the_block_kills_the_child(jobs_importable):
    with pytest.raises(KeyboardInterrupt):
        with FigureProcess() as figures:
            child = figures._proc
            raise KeyboardInterrupt
    assert child.poll() == -signal.SIGKILL and not figures.running


def test_a_broken_matplotlib_is_one_clear_error(tmp_path, jobs_importable, monkeypatch, capfd):
    """The child's start-up imports fail quietly; the figure that needs them gets the
    ImportError, other jobs still run in the child."""
    fake = tmp_path / "site" / "matplotlib"
    fake.mkdir(parents=True)
    (fake / "__init__.py").write_text("raise ImportError('broken matplotlib')\n")
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([str(fake.parent), os.environ["PYTHONPATH"]]))
    data = trajectory_figure(simulate(default_scene(), duration=4.0), title="t")
    with FigureProcess() as figures:
        figure = figures.draw(draw_trajectory, data, tmp_path / "t.png")
        other = figures.draw(figure_jobs.noisy, tmp_path / "f.txt")
        with pytest.raises(ImportError, match="broken matplotlib"):
            figure.result()
        assert other.result() != os.getpid()
    assert not (tmp_path / "t.png").exists()
    assert "Traceback" not in capfd.readouterr().err


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["rectifier", "array"])
def test_run_figures_from_the_child_are_the_same(tmp_path, kind, monkeypatch):
    """Every figure of a `tengfield run` result (waveforms, surrogate, trajectory and the
    harvesting or array figures) drawn by the figure process equals the one drawn here;
    the tables are byte-identical."""
    import matplotlib.image
    import plate_model as fx

    import tengfield as tf
    from tengfield import io

    monkeypatch.delenv("TENGFIELD_FIGURE_PROCESS", raising=False)
    run = {"duration_s": 0.5, "settle_periods": 2, "sample_rate_hz": 5000.0}
    if kind == "rectifier":
        scene = fx.scene_with(run=run, circuit={"kind": "rectifier",
                                                "storage_capacitance_uF": 1e-4})
    else:
        scene = fx.scene_with(run=run, circuit={"kind": "load", "load_ohm": 3e9},
                              array={"cells": 4, "initial_velocity_spread_m_per_s": 0.3})
    result = tf.run(scene, cache_dir=tmp_path / "cache", solve=fx.plate_model_solve)
    here, child = tmp_path / "here", tmp_path / "child"
    names = [p.name for p in io.write_run_outputs(result, here)
             + io.write_dynamics_outputs(result, here, plots=True)]
    with FigureProcess() as figures:
        sent = [p.name for p in io.write_run_outputs(result, child, figures=figures)
                + io.write_dynamics_outputs(result, child, plots=True, figures=figures)]
        assert figures.running
        drawn = figures.finish()
    assert sent == names and len(drawn) == sum(n.endswith(".png") for n in names)
    assert {"charging.png" if kind == "rectifier" else "array.png"} < set(names)
    for name in names:
        if name.endswith(".png"):
            a = matplotlib.image.imread(here / name)
            b = matplotlib.image.imread(child / name)
            assert a.shape == b.shape and np.array_equal(a, b), name
        elif name != "summary.json":
            assert (here / name).read_bytes() == (child / name).read_bytes(), name


def test_nothing_sent_or_all_answered_ends_at_once(tmp_path, jobs_importable):
    """Leaving the block does not wait for a child still importing matplotlib: it is
    stopped, as it is once every figure has been answered."""
    with FigureProcess() as figures:
        child = figures._proc
    assert child.poll() == -signal.SIGKILL          # killed while importing
    with FigureProcess() as figures:
        figures.draw(figure_jobs.noisy, tmp_path / "f.txt").result()
        child = figures._proc
    assert child.poll() in (0, -signal.SIGKILL) and not figures.running
    assert (tmp_path / "f.txt").exists()


def test_the_child_speaks_as_the_command(jobs_importable, capfd):
    """stderr holds tengfield's own lines only: matplotlib's log (the font cache message
    of a fresh machine) is not shown, a warning is one tengfield line."""
    with FigureProcess() as figures:
        assert figures.draw(figure_jobs.chatty).result() != os.getpid()
    err = capfd.readouterr().err
    assert err == "tengfield: warning: odd axis limits\n", err


@pytest.mark.parametrize("value, expected", [("0", False), ("off", False), (" No ", False),
                                             ("1", True), ("yes", True), ("TRUE", True)])
def test_the_switch_reads_the_usual_spellings(monkeypatch, value, expected):
    from tengfield.plotting import process

    monkeypatch.setenv("TENGFIELD_FIGURE_PROCESS", value)
    assert process.enabled() is expected


def test_a_misspelt_switch_is_refused_before_any_output(tmp_path, monkeypatch, capsys):
    """`TENGFIELD_FIGURE_PROCESS=maybe`: one error line naming the variable, the value
    and the allowed spellings; exit 2 and no output directory."""
    from tengfield import cli

    monkeypatch.setenv("TENGFIELD_FIGURE_PROCESS", "maybe")
    out_dir = tmp_path / "out"
    assert cli.main(["dynamics", "-o", str(out_dir), "--duration-s", "2"]) == 2
    err = capsys.readouterr().err
    assert err == ("tengfield: error: TENGFIELD_FIGURE_PROCESS = 'maybe': allowed 1/0, "
                   "yes/no, true/false, on/off\n")
    assert not out_dir.exists()
