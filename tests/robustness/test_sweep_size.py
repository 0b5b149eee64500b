"""Issue #21 item 17: ``tengfield sweep`` bounds its size before any work (a 1e10-point
grid ran silently at 100 % CPU), naming the limit."""
from __future__ import annotations

import time

import pytest

from tengfield.errors import SceneError
from tengfield.scene import default_scene
from tengfield.sweeps import check_grid


def _one_line(proc, *needles):
    assert proc.returncode == 2, (proc.returncode, proc.stderr)
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("tengfield: error: "), proc.stderr
    for n in needles:
        assert n in lines[0], (n, lines[0])


def test_a_1e10_point_sweep_is_refused_at_once(run_cli, tmp_path):
    start = time.perf_counter()
    proc = run_cli("sweep", "--frequency-hz", "5:50:100000", "--amplitude-mm", "0.5:3:100000",
                   "-o", tmp_path / "out", "--no-plots", timeout=120)
    _one_line(proc, "sweep points = 100000 frequencies x 100000 amplitudes = 1e+10",
              "allowed <= 1e+05")
    assert time.perf_counter() - start < 60
    assert not (tmp_path / "out" / "sweep.csv").exists()


def test_too_many_loads_are_refused(run_cli, tmp_path):
    proc = run_cli("sweep", "--frequency-hz", "20:40:100", "--amplitude-mm", "1:2:100",
                   "--load-ohm", "1e3:1e9:1000", "-o", tmp_path / "out", timeout=120)
    _one_line(proc, "sweep rows = 10000 points x 1000 loads", "allowed <= 1e+06")


def test_sweep_work_in_samples_is_bounded():
    from tengfield.sweeps import check_sweep_size

    scene = default_scene().with_values(run={"duration_s": 100.0, "sample_rate_hz": 20000.0})
    with pytest.raises(SceneError, match=r"sweep work = 10000 points .* allowed <= 1e\+10"):
        check_sweep_size(scene, 100, 100, 0)


def test_grid_check_of_a_large_grid_is_quick_and_still_names_a_bad_point():
    import numpy as np

    scene = default_scene()
    start = time.perf_counter()
    check_grid(scene, np.linspace(20, 50, 300), np.linspace(0.5e-3, 3e-3, 300))
    assert time.perf_counter() - start < 5
    check_grid(scene, np.linspace(5, 50, 300), np.linspace(0.5e-3, 3e-3, 300))  # run longer
    with pytest.raises(SceneError, match="sweep point frequency_hz = 0.0001"):
        check_grid(scene, np.linspace(1e-4, 50, 300), np.linspace(0.5e-3, 3e-3, 300))
