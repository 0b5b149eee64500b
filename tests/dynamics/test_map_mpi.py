"""`regime_map` over MPI ranks (the task farm) equals the serial map (make test-mpi)."""
import numpy as np
import pytest

from tengfield.dynamics import regime_map
from tengfield.scene import default_scene


@pytest.mark.mpi
def test_map_on_two_ranks_equals_the_serial_map():
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    scene = default_scene()
    freqs, amps = np.linspace(10.0, 40.0, 5), np.linspace(0.5e-3, 3e-3, 4)
    farmed = regime_map(scene, freqs, amps, comm=comm, progress=False, periods=40)
    serial = regime_map(scene, freqs, amps, jobs=1, progress=False, periods=40)
    assert farmed.records() == serial.records()
    gathered = comm.allgather(farmed.records())           # every rank holds the whole map
    assert all(r == gathered[0] for r in gathered)
