"""The worker pools (``--jobs``) never fork a multi-threaded process (issue #21, item
16): the start method is chosen in one place, :mod:`tengfield._pool` (fork when the
caller has one thread and no MPI, a fork server preloading the tasks' modules
otherwise). Python 3.12+ says so with a DeprecationWarning ("multi-threaded, use of
fork() may lead to deadlocks"): each pool runs here next to a second thread, as in a
test run or after MPI started its threads, and must raise none; its results equal the
one-process ones."""
from __future__ import annotations

import threading
import warnings

import numpy as np
import pytest

from tengfield import _pool, array
from tengfield import sweeps as sweep_module
from tengfield.dynamics import regime_map

import plate_model as fx


@pytest.fixture
def second_thread():
    stop = threading.Event()
    thread = threading.Thread(target=stop.wait, name="second-thread", daemon=True)
    thread.start()
    yield thread
    stop.set()
    thread.join()


@pytest.fixture
def no_fork_warning():
    """Every warning recorded (none filtered away); a fork() one fails the test."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        yield
    bad = [str(w.message) for w in caught if "fork" in str(w.message)]
    assert not bad, bad


def test_a_threaded_process_gets_the_fork_server(second_thread):
    assert _pool.start_method() == "forkserver"
    assert _pool.pool_context().get_start_method() == "forkserver"


@pytest.mark.slow
def test_regime_map_pool_next_to_a_thread(second_thread, no_fork_warning):
    scene = fx.scene_with()
    freqs, amps = np.array([15.0, 20.0, 25.0, 30.0]), np.array([1e-3, 1.5e-3, 2e-3])
    pooled = regime_map(scene, freqs, amps, jobs=2, periods=20, progress=False)
    serial = regime_map(scene, freqs, amps, jobs=1, periods=20, progress=False)
    np.testing.assert_array_equal(pooled.regime, serial.regime)
    np.testing.assert_array_equal(pooled.max_gap, serial.max_gap)


def test_run_tasks_pool_next_to_a_thread(second_thread, no_fork_warning):
    assert sweep_module.run_tasks(abs, [-1, -2, -3, -4], jobs=2) == [1, 2, 3, 4]


@pytest.mark.slow
def test_array_pool_next_to_a_thread(second_thread, no_fork_warning):
    scene = fx.scene_with(run={"duration_s": 0.5, "settle_periods": 2, "sample_rate_hz": 4000.0},
                          array={"cells": 8, "restitution_spread": 0.1,
                                 "initial_phase_spread_deg": 30.0})
    draws = array.draw_cells(scene)
    pooled = array.simulate_cells(scene, draws, jobs=2)
    serial = array.simulate_cells(scene, draws, jobs=1)
    t = np.linspace(0, 0.5, 51)
    for (a, na), (b, nb) in zip(pooled, serial):
        assert na == nb
        np.testing.assert_array_equal(a(t)[0], b(t)[0])
