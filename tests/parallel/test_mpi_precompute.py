"""MPI task farm of the surrogate: 2 ranks give the serial result; a failure aborts all ranks.

``make test-mpi`` runs the ``mpi``-marked tests under ``mpirun -n 2``; the
others start ``mpirun`` themselves (the serial suite).
"""
from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

import numpy as np
import pytest

from tengfield import surrogate

import plate_model as fx

ROOT = Path(__file__).resolve().parents[2]
COARSE_FIELD = {"mesh_size_mm": 1.5, "degree": 1, "tolerance": 0.05}


def mpi_env():
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1", MPLBACKEND="Agg")
    return env


def assert_same_table(a, b):
    np.testing.assert_array_equal(a.positions, b.positions)
    np.testing.assert_array_equal(a.capacitance, b.capacitance)
    np.testing.assert_array_equal(a.induced_fraction, b.induced_fraction)
    assert a.interpolation_error == b.interpolation_error
    assert a.error_history == b.error_history


@pytest.mark.mpi
def test_two_ranks_equal_serial_analytic_model():
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    scene = fx.scene_with(field={"tolerance": 1e-5})
    parallel = surrogate.precompute(scene, comm=comm, solve=fx.plate_model_solve)
    serial = surrogate.precompute(scene, comm=None, solve=fx.plate_model_solve)
    assert_same_table(parallel, serial)
    # every rank holds the same table
    others = comm.allgather(parallel.capacitance)
    for other in others:
        np.testing.assert_array_equal(other, parallel.capacitance)


@pytest.mark.mpi
@pytest.mark.parametrize("dynamic", [True, False])
def test_farm_runs_every_item_once_and_keeps_the_order(dynamic):
    from mpi4py import MPI

    from tengfield._mpi import farm

    comm = MPI.COMM_WORLD
    done = []

    def work(item):
        done.append(item)
        return item * item

    items = list(range(23))
    assert farm(comm, items, work, dynamic=dynamic) == [i * i for i in items]
    everywhere = sorted(i for part in comm.allgather(done) for i in part)
    assert everywhere == items                      # each item exactly once


@pytest.mark.mpi
@pytest.mark.field
@pytest.mark.filterwarnings("ignore:surrogate. field error estimate:RuntimeWarning")  # coarse
def test_two_ranks_equal_serial_field_solver():
    import pyvista  # noqa: F401 - before dolfinx
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    scene = fx.scene_with(field=COARSE_FIELD)
    parallel = surrogate.precompute(scene, comm=comm)
    # the serial reference: rank 0 alone, shared with the other rank
    serial = surrogate.precompute(scene, comm=None) if comm.rank == 0 else None
    serial = comm.bcast(serial, root=0)
    assert_same_table(parallel, serial)
    assert parallel.count >= 17


@pytest.mark.slow
def test_cli_precompute_under_mpirun_equals_serial(tmp_path, cli_command):
    """`mpirun -n 2 tengfield precompute` writes the same file content as a serial run."""
    if shutil.which("mpirun") is None:
        pytest.skip("mpirun not installed")
    scene_file = tmp_path / "coarse.toml"
    scene_file.write_text("[field]\n" + "".join(f"{k} = {v!r}\n".replace("'", '"')
                                                 for k, v in COARSE_FIELD.items()))
    cmd = cli_command("precompute", scene_file)
    serial = subprocess.run(cmd + ["-o", str(tmp_path / "serial.h5")], capture_output=True,
                            text=True, env=mpi_env(), timeout=300)
    assert serial.returncode == 0, serial.stderr
    parallel = subprocess.run(["mpirun", "-n", "2"] + cmd + ["-o", str(tmp_path / "mpi.h5")],
                              capture_output=True, text=True, env=mpi_env(), timeout=300)
    assert parallel.returncode == 0, parallel.stderr
    a = surrogate.read_table(tmp_path / "serial.h5")
    b = surrogate.read_table(tmp_path / "mpi.h5")
    assert_same_table(a, b)
    assert "mpirun" not in a.provenance["command_line"]
    assert a.provenance["command_line"].startswith("tengfield precompute")


@pytest.mark.slow
def test_failure_on_one_rank_aborts_every_rank(tmp_path, python):
    """An exception on one rank ends the whole job with its message (no hang).

    The failing job is a position, not a rank: with the dynamic schedule a rank
    that starts late (a loaded machine) may get no job at all."""
    if shutil.which("mpirun") is None:
        pytest.skip("mpirun not installed")
    script = tmp_path / "fail.py"
    script.write_text(textwrap.dedent(f"""
        import sys
        sys.path.insert(0, {str(Path(__file__).resolve().parents[1])!r})   # plate_model
        sys.path.insert(0, {str(Path(__file__).resolve().parent)!r})       # this file
        from mpi4py import MPI
        import plate_model as fx
        from tengfield import surrogate

        def solve(scene, z, comm=None):
            if z == 0.0:
                raise RuntimeError(f"mesh generation failed at z = {{z:.3g}}")
            return fx.plate_model_solve(scene, z)

        surrogate.precompute(fx.scene_with(), comm=MPI.COMM_WORLD, solve=solve)
        print("finished")
    """))
    proc = subprocess.run(["mpirun", "-n", "2", python, str(script)], capture_output=True,
                          text=True, env=mpi_env(), timeout=120)
    assert proc.returncode != 0
    assert re.search(r"error on rank [01] of 2", proc.stderr)
    assert "mesh generation failed" in proc.stderr
    assert "finished" not in proc.stdout


def _disagreeing_caches(comm, case: str):
    """Each rank its own cache directory (node-local caches); ``case`` says what they hold:
    "rank 0 holds it", "rank 1 holds it", "rank 0 corrupt". Returns (statuses, calls, tables)."""
    base = comm.bcast(tempfile.mkdtemp(prefix="tengfield-mpi-cache-") if comm.rank == 0
                      else None, root=0)
    mine = Path(base) / f"rank{comm.rank}"
    scene = fx.scene_with()
    holder = 0 if case == "rank 0 holds it" else 1
    try:
        if comm.rank == holder:       # written alone, as a serial run would
            surrogate.obtain_table(scene, cache_dir=mine, solve=fx.plate_model_solve)
        if case == "rank 0 corrupt" and comm.rank == 0:
            path = surrogate.cache_path(scene, mine)
            path.parent.mkdir(parents=True)
            path.write_bytes(b"not an HDF5 file")
        comm.Barrier()
        solver = fx.CountingSolver()
        table, outcome = surrogate.obtain_table(scene, cache_dir=mine, comm=comm, solve=solver)
        return (comm.allgather(outcome.status), sum(comm.allgather(solver.calls)),
                comm.allgather(table))
    finally:
        comm.Barrier()
        if comm.rank == 0:
            shutil.rmtree(base, ignore_errors=True)


@pytest.mark.mpi
@pytest.mark.parametrize("case, status", [("rank 0 holds it", "cached"),
                                          ("rank 1 holds it", "computed"),
                                          ("rank 0 corrupt", "recomputed")])
def test_ranks_with_different_caches_follow_rank_0(case, status):
    """Rank 0 decides hit or miss and broadcasts it with the table: the ranks never
    disagree (before, a rank that missed entered the solves alone and hung)."""
    import warnings

    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)   # "not trusted" on rank 0
        statuses, calls, tables = _disagreeing_caches(comm, case)
    assert statuses == [status] * comm.size
    assert (calls == 0) == (status == "cached")
    for other in tables[1:]:
        assert_same_table(other, tables[0])


@pytest.mark.slow
def test_ranks_with_different_caches_finish_under_mpirun(tmp_path, python):
    """The same three cases as a script under ``mpirun -n 2`` in the serial suite,
    under a timeout (a disagreement used to spin forever)."""
    if shutil.which("mpirun") is None:
        pytest.skip("mpirun not installed")
    script = tmp_path / "caches.py"
    script.write_text(textwrap.dedent(f"""
        import sys, warnings
        sys.path.insert(0, {str(Path(__file__).resolve().parents[1])!r})   # plate_model
        sys.path.insert(0, {str(Path(__file__).resolve().parent)!r})       # this file
        from mpi4py import MPI
        from test_mpi_precompute import _disagreeing_caches
        warnings.simplefilter("ignore", RuntimeWarning)
        comm = MPI.COMM_WORLD
        for case in ("rank 0 holds it", "rank 1 holds it", "rank 0 corrupt"):
            statuses, calls, _ = _disagreeing_caches(comm, case)
            if comm.rank == 0:
                print(case, "->", ",".join(statuses), calls, flush=True)
    """))
    proc = subprocess.run(["mpirun", "-n", "2", python, str(script)], capture_output=True,
                          text=True, env=mpi_env(), timeout=120)
    assert proc.returncode == 0, proc.stderr[-2000:]
    lines = proc.stdout.strip().splitlines()
    assert lines[0] == "rank 0 holds it -> cached,cached 0"
    assert lines[1].startswith("rank 1 holds it -> computed,computed ")
    assert lines[2].startswith("rank 0 corrupt -> recomputed,recomputed ")
