"""The Python API takes numpy scalars and scene dicts, and refuses what it cannot use
with a clear error (issue #30.21); an ensemble's work is bounded at load (#30.10)."""
import numpy as np
import pytest

import tengfield as tf
from tengfield.errors import SceneError


def test_with_values_accepts_numpy_scalars():
    scene = tf.default_scene()
    s = scene.with_values(excitation={"frequency_hz": np.float32(30)}, device={"cells": np.int64(3)})
    assert s.excitation.frequency == 30.0
    assert s.device.cells == 3 and isinstance(s.device.cells, int)


def test_with_values_refuses_a_section_that_is_not_a_dict():
    with pytest.raises(TypeError, match=r"with_values\(excitation=None\): expected a dict"):
        tf.default_scene().with_values(excitation=None)


def test_run_and_simulate_take_a_dict_or_say_what_to_pass():
    dyn = tf.simulate({"run": {"duration_s": np.float64(0.5), "settle_periods": 2}})
    assert dyn.t[-1] == pytest.approx(0.5, abs=1e-3)
    with pytest.raises(TypeError, match="expected a tengfield.Scene"):
        tf.run("scene.toml")
    with pytest.raises(TypeError, match="expected a tengfield.Scene"):
        tf.simulate(42)
    # a bad value in the dict is the scene's one-line error, not an AttributeError
    with pytest.raises(SceneError, match="frequency_hz"):
        tf.run({"excitation": {"frequency_hz": -1.0}})


def test_simulate_refuses_a_duration_that_is_not_a_number():
    scene = tf.default_scene()
    with pytest.raises(TypeError, match="duration = '1' must be a number"):
        tf.simulate(scene, duration="1")
    for bad in (0.0, -1.0, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="allowed \\(0, inf\\)"):
            tf.simulate(scene, duration=bad)
    dyn = tf.simulate(scene, duration=np.float32(0.75))
    assert dyn.t[-1] == pytest.approx(0.75, abs=1e-3)


def _random(**run):
    return tf.default_scene().with_values(
        excitation={"kind": "random", "band_hz": [10.0, 100.0], "rms_acceleration_m_per_s2": 10.0},
        run=run)


def test_ensemble_work_is_bounded_before_it_starts():
    with pytest.raises(SceneError) as err:
        _random(realisations=100000, duration_s=600.0)
    msg = str(err.value)
    assert "realisations x duration_s x sample_rate_hz" in msg and "1.2e+12" in msg
    assert "allowed <= 1e+10" in msg and "\n" not in msg
    # just inside the bound (and a single realisation of the longest run) pass
    assert _random(realisations=5000, duration_s=100.0).run.realisations == 5000   # 1e10
    with pytest.raises(SceneError, match="5001 x 100 x 20000"):
        _random(realisations=5001, duration_s=100.0)
    assert _random(realisations=1, duration_s=600.0).run.duration == 600.0


def test_a_figure_that_fails_to_write_leaves_no_file(tmp_path, monkeypatch):
    """A full disk while a figure is saved (simulated: savefig writes part, then ENOSPC)
    leaves no 0-byte waveforms.png: the figure is written atomically."""
    import errno

    from tengfield import io as tio

    def failing(*data):
        path = data[-1]
        with open(path, "wb") as fh:
            fh.write(b"")
        raise OSError(errno.ENOSPC, "No space left on device")

    with pytest.raises(OSError):
        tio._figure(None, failing, path=tmp_path / "waveforms.png")
    assert list(tmp_path.iterdir()) == []
