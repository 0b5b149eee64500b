"""`sweep` and `report` under ``mpirun -n 2``: the MPI task farm gives the serial rows,
``--jobs`` is refused next to several ranks, and a failure on one rank ends every rank.

The ``mpi``-marked tests run under ``mpirun -n 2`` (``make test-mpi``); the others
start ``mpirun`` themselves (the serial suite). The surrogate comes from the
analytic plate model of ``plate_model`` (no dolfinx): what is tested
here is the farm, not the field.
"""
from __future__ import annotations

import csv
import math
import subprocess
import textwrap
from pathlib import Path

import pytest

from tengfield import surrogate
from tengfield import sweeps as sweep_module
from tengfield.errors import SceneError

import plate_model as fx
from helpers import mpi_env, needs_mpirun, same_rows

ROOT = Path(__file__).resolve().parents[2]
SHORT_RUN = {"duration_s": 2.0}
FREQUENCIES = [15.0, 20.0, 25.0]
AMPLITUDES = [1.0e-3, 1.5e-3]
LOADS = [1e6, 1e9]


def plate_table(scene):
    return surrogate.precompute(scene, comm=None, solve=fx.plate_model_solve)


# ---------------------------------------------------------------------------
# under mpirun -n 2 (make test-mpi)
@pytest.mark.mpi
def test_sweep_on_two_ranks_equals_the_serial_rows():
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    assert comm.size >= 2
    scene = fx.scene_with(run=SHORT_RUN)
    table = plate_table(scene)
    parallel = sweep_module.sweep(scene, table, FREQUENCIES, AMPLITUDES, LOADS, comm=comm)
    serial = sweep_module.sweep(scene, table, FREQUENCIES, AMPLITUDES, LOADS, jobs=1)
    assert len(serial) == len(FREQUENCIES) * len(AMPLITUDES) * len(LOADS)
    assert same_rows(parallel, serial)
    # every rank holds every row, in the serial order
    for other in comm.allgather(parallel):
        assert same_rows(other, serial)
    assert [(r["frequency_hz"], r["amplitude_mm"], r["load_ohm"]) for r in parallel] == \
        [(f, a * 1e3, x) for f in FREQUENCIES for a in AMPLITUDES for x in LOADS]


@pytest.mark.mpi
def test_run_tasks_farms_each_task_once_in_order():
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    done = []

    def work(task):
        done.append(task)
        return (task, task**2)

    tasks = list(range(31))
    assert sweep_module.run_tasks(work, tasks, comm=comm) == [(t, t**2) for t in tasks]
    everywhere = sorted(t for part in comm.allgather(done) for t in part)
    assert everywhere == tasks


@pytest.mark.mpi
def test_jobs_next_to_several_ranks_is_refused_on_every_rank():
    from mpi4py import MPI

    from tengfield._mpi import check_jobs

    comm = MPI.COMM_WORLD
    with pytest.raises(SceneError, match=r"--jobs = 2 cannot be combined with mpirun -n 2"):
        check_jobs(2, comm)
    with pytest.raises(SceneError, match="--jobs"):
        sweep_module.run_tasks(abs, [1, 2], comm=comm, jobs=3)
    check_jobs(1, comm)          # one worker per rank is fine
    check_jobs(None, comm)


@pytest.mark.mpi
@pytest.mark.slow
def test_fast_report_on_two_ranks_equals_serial_where_deterministic():
    """Every row's setting, knobs and errors equal the serial report's; the wall times
    (and so the recommendations, which weigh them) are measurements and may differ."""
    from mpi4py import MPI

    from tengfield import accuracy_report

    comm = MPI.COMM_WORLD
    scene = fx.scene_with()
    parallel = accuracy_report.build_report(scene, fast=True, solve=fx.plate_model_solve, farm_comm=comm)
    serial = accuracy_report.build_report(scene, fast=True, solve=fx.plate_model_solve) \
        if comm.rank == 0 else None
    serial = comm.bcast(serial, root=0)
    assert len(parallel.rows) == len(serial.rows) > 20
    for a, b in zip(parallel.rows, serial.rows):
        assert (a.stage, a.setting, a.knobs, a.reference) == (b.stage, b.setting, b.knobs,
                                                              b.reference)
        assert same_rows([a.errors], [b.errors]), (a.setting, a.errors, b.errors)
        assert a.error_position == b.error_position or \
            (math.isnan(a.error_position) and math.isnan(b.error_position))
    assert parallel.references["overall_peaks"] == serial.references["overall_peaks"]
    # every rank took the same decisions (the same rows, hence the same recommendations)
    mine = [(r.stage, r.setting, r.wall_time_s) for r in parallel.rows]
    assert all(other == mine for other in comm.allgather(mine))
    picks = [(r.field, r.sample_rate_hz, r.positions) for r in parallel.recommendations]
    assert all(other == picks for other in comm.allgather(picks))


# ---------------------------------------------------------------------------
# started from the serial suite: the CLI under mpirun
def _cached_scene(tmp_path) -> tuple[Path, Path]:
    """A short scene file and a cache dir holding its (plate-model) surrogate."""
    from tengfield.scene import load_scene

    scene_file = tmp_path / "short.toml"
    scene_file.write_text("[run]\nduration_s = 2.0\n")
    cache = tmp_path / "cache"
    scene = load_scene(scene_file)
    surrogate.write_table(surrogate.cache_path(scene, cache), plate_table(scene))
    return scene_file, cache


@pytest.mark.slow
def test_cli_sweep_under_mpirun_writes_the_serial_file(tmp_path, cli_command):
    needs_mpirun()
    scene_file, cache = _cached_scene(tmp_path)
    args = cli_command("sweep", scene_file, "--cache-dir", cache, "--frequency-hz", "15:25:3",
                       "--amplitude-mm", "1:1.5:2", "--load-ohm", "1e6:1e9:2")
    serial = subprocess.run(args + ["--jobs", "1", "-o", str(tmp_path / "serial")],
                            capture_output=True, text=True, env=mpi_env(), timeout=300)
    assert serial.returncode == 0, serial.stderr
    parallel = subprocess.run(["timeout", "280", "mpirun", "-n", "2"] + args
                              + ["-o", str(tmp_path / "mpi")],
                              capture_output=True, text=True, env=mpi_env(), timeout=300)
    assert parallel.returncode == 0, parallel.stderr
    text = (tmp_path / "serial" / "sweep.csv").read_text()
    assert (tmp_path / "mpi" / "sweep.csv").read_text() == text
    rows = list(csv.DictReader(text.splitlines()))
    assert len(rows) == 12 and all(float(r["P_mean_W"]) >= 0 for r in rows)
    assert sum(float(r["P_mean_W"]) > 0 for r in rows) >= 6      # the bouncing points
    assert (tmp_path / "mpi" / "sweep.png").stat().st_size > 0
    assert parallel.stdout.count("12 rows; wrote") == 1          # rank 0 alone writes
    assert not list((tmp_path / "mpi").glob(".*tmp*"))           # no temporary files left


@pytest.mark.slow
def test_cli_sweep_jobs_under_mpirun_is_a_clear_error(tmp_path, cli_command):
    needs_mpirun()
    scene_file, cache = _cached_scene(tmp_path)
    proc = subprocess.run(["timeout", "120", "mpirun", "-n", "2",
                           *cli_command("sweep", scene_file, "--cache-dir", cache,
                                        "--frequency-hz", "20", "--amplitude-mm", "1",
                                        "--jobs", "2", "-o", tmp_path / "o")],
                          capture_output=True, text=True, env=mpi_env(), timeout=150)
    assert proc.returncode not in (0, 124), proc.stderr      # 124: timeout (a hang)
    assert "tengfield: error: --jobs = 2 cannot be combined with mpirun -n 2" in proc.stderr
    assert "Traceback" not in proc.stderr
    assert not (tmp_path / "o").exists()


@pytest.mark.slow
def test_failure_on_one_rank_of_a_sweep_aborts_every_rank(tmp_path, python):
    """An exception in one grid point on rank 1 ends the whole job with its message (no hang)."""
    needs_mpirun()
    script = tmp_path / "fail.py"
    script.write_text(textwrap.dedent(f"""
        import sys
        sys.path.insert(0, {str(Path(__file__).resolve().parents[1])!r})   # plate_model
        sys.path.insert(0, {str(Path(__file__).resolve().parent)!r})       # this file
        from mpi4py import MPI
        import plate_model as fx
        from tengfield import surrogate, sweeps as sweep

        comm = MPI.COMM_WORLD
        scene = fx.scene_with(run={{"duration_s": 1.0}})
        table = surrogate.precompute(scene, comm=None, solve=fx.plate_model_solve)
        real = sweep.sweep_point

        def point(scene, table, frequency, amplitude, loads=()):
            if comm.rank == 1:
                raise RuntimeError(f"impact map diverged at {{frequency:g}} Hz")
            return real(scene, table, frequency, amplitude, loads)

        sweep.sweep_point = point
        sweep.sweep(scene, table, [15.0, 20.0, 25.0, 30.0], [1e-3, 1.5e-3], comm=comm)
        print("finished")
    """))
    proc = subprocess.run(["timeout", "100", "mpirun", "-n", "2", python, str(script)],
                          capture_output=True, text=True, env=mpi_env(), timeout=120)
    assert proc.returncode not in (0, 124), proc.stderr
    assert "error on rank 1 of 2" in proc.stderr
    assert "impact map diverged at" in proc.stderr
    assert "finished" not in proc.stdout


@pytest.mark.slow
def test_one_process_commands_under_mpirun_are_refused_once(tmp_path, cli_command):
    """`tengfield dynamics` (one trajectory) under mpirun -n 2 used to run on both ranks,
    writing the same files at once: now one error line (from rank 0), a non-zero exit and
    no output directory."""
    needs_mpirun()
    out = tmp_path / "out"
    proc = subprocess.run(["timeout", "100", "mpirun", "-n", "2"]
                          + cli_command("dynamics", "--duration-s", "2", "-o", str(out)),
                          capture_output=True, text=True, env=mpi_env(), timeout=120)
    assert proc.returncode != 0
    ours = [line for line in proc.stderr.splitlines() if line.startswith("tengfield")]
    assert ours == ["tengfield: error: tengfield dynamics runs on one process (one trajectory; "
                    "`tengfield map` spreads many over the ranks): start it without mpirun"]
    assert not out.exists()


class _TwinWorld:
    """A stand-in for ``MPI.COMM_WORLD`` of rank ``rank`` out of two whose other rank
    does exactly the same (its allgather repeats this rank's value)."""

    size = 2

    def __init__(self, rank: int):
        self.rank = rank
        self.barriers = 0

    def Dup(self):
        return self

    def allgather(self, value):
        return [value] * self.size

    def Barrier(self):
        self.barriers += 1

    def Abort(self, code):
        raise AssertionError(f"Abort({code})")


@pytest.mark.parametrize("rank, lines", [(0, 1), (1, 0)])
@pytest.mark.parametrize("command", [["dynamics"], ["fit", "--targets", "V_pp_V=4.2"]])
def test_one_process_commands_see_the_launcher(tmp_path, monkeypatch, capsys, rank, lines,
                                               command):
    """The check reads the launcher's environment: rank 0 alone says why, after a barrier
    every rank exits 2 before any output directory exists."""
    from tengfield import cli

    world = _TwinWorld(rank)
    monkeypatch.setattr(cli, "_launched_world", lambda: world)
    monkeypatch.setenv("OMPI_COMM_WORLD_SIZE", "2")
    out = tmp_path / "out"
    assert cli.main([*command, "-o", str(out)]) == 2
    assert world.barriers == 1      # nobody exits before rank 0 has written
    err = capsys.readouterr().err.splitlines()
    assert len(err) == lines and all("start it without mpirun" in e for e in err)
    assert not out.exists()
