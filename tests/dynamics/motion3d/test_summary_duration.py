"""Issue #21 item 9: a 3D run's summary reports the simulated duration (it said 0.0),
and the trajectory it returns is still the one it integrated, whatever [initial] time_s."""
import json

import numpy as np
import pytest

from tengfield.dynamics.soft import simulate_soft
from tengfield.dynamics.motion3d import simulate_3d
from tengfield.scene import default_scene

RUN = {"duration_s": 0.25, "settle_periods": 2, "sample_rate_hz": 4000.0}


@pytest.mark.parametrize("start", [0.0, 0.0375])
def test_3d_summary_duration_is_the_simulated_time_as_in_1d(start):
    scene = default_scene().with_values(run=RUN, initial={"time_s": start},
                                        contact={"model": "3d"},
                                        excitation={"amplitude_x_mm": 0.5})
    r3 = simulate_3d(scene)
    r1 = simulate_soft(scene.with_values(contact={"model": "soft"}))
    assert r1.summary["duration_s"] == pytest.approx(RUN["duration_s"], rel=1e-12)
    assert r3.summary["duration_s"] == pytest.approx(r1.summary["duration_s"], rel=1e-12)
    assert r3.summary["time_origin_s"] == pytest.approx(start)
    # the samples start at [initial] time_s and cover the duration
    assert r3.t[0] == pytest.approx(start) and r3.t[-1] - r3.t[0] == pytest.approx(0.25)
    # sample(t) at the sample times gives back the sampled trajectory (absolute times)
    z, v, y = r3.sample(r3.t)
    np.testing.assert_allclose(z, r3.gap, rtol=0, atol=1e-12)
    np.testing.assert_allclose(v, r3.gap_velocity, rtol=0, atol=1e-9)
    np.testing.assert_allclose(y, r3.table, rtol=0, atol=1e-12)
    # and sample_elapsed measures from [initial] time_s
    z_mid, _, _ = r3.sample_elapsed([0.1])
    z_abs, _, _ = r3.sample([start + 0.1])
    assert z_mid[0] == pytest.approx(z_abs[0], abs=1e-12)


@pytest.mark.slow
def test_cli_dynamics_3d_summary_json_duration(tmp_path, run_cli, cli_env):
    (tmp_path / "s.toml").write_text(
        '[contact]\nmodel = "3d"\n[excitation]\namplitude_x_mm = 0.5\n'
        "[run]\nduration_s = 0.2\nsettle_periods = 2\nsample_rate_hz = 4000.0\n")
    proc = run_cli("dynamics", "s.toml", "-o", "out", "--no-plots", cwd=tmp_path,
                   env=cli_env(MPLBACKEND="Agg"))
    assert proc.returncode == 0, proc.stderr
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["model"] == "3d"
    assert summary["duration_s"] == pytest.approx(0.2, rel=1e-12)
