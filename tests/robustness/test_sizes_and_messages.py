"""Issue #54 items 9, 11, 16: every size the user sets is bounded by one rule before the
work, and the messages name the key (or option) the user wrote, its value and the range."""
from __future__ import annotations

import pytest

from tengfield.errors import SceneError
from tengfield.scene import parse_scene

BASE = ("[run]\nduration_s = 0.3\nsettle_periods = 2\nsample_rate_hz = 5000\n"
        "[field]\ndegree = 1\nmesh_size_mm = 1.5\ntolerance = 1e-2\n")


# -- 54.9: the instrument's readings are bounded as the run's samples -------------------
@pytest.mark.parametrize("rate", ["1e12", "1e9", "6.7e7"])
def test_an_instrument_sample_rate_past_what_the_run_holds_is_one_line(rate, run_cli, tmp_path):
    scene = tmp_path / "base.toml"
    scene.write_text(BASE)
    out = tmp_path / "out"
    proc = run_cli("run", scene, "-o", out, "--set", f"instrument.sample_rate_hz={rate}",
                   timeout=120)
    assert proc.returncode == 2, proc.stderr[-2000:]
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in proc.stderr, proc.stderr[-2000:]
    line = lines[0]
    assert line.startswith(f"tengfield: error: [instrument] sample_rate_hz = {float(rate):g}: ")
    assert "readings: allowed <= 2e+07" in line and "sample_rate_hz <= 6.67e+07" in line
    assert not out.exists()     # before any field solve: nothing written


def test_an_instrument_sample_rate_the_run_holds_is_taken():
    scene = parse_scene(BASE + "[instrument]\nsample_rate_hz = 6.6e7\n")
    assert scene.instrument.sample_rate == 6.6e7
    with pytest.raises(SceneError, match=r"^\[instrument\] sample_rate_hz = 1e\+06: \[run\] "
                                         r"duration_s x \[instrument\] sample_rate_hz = 100 x "
                                         r"1e\+06 = 1e\+08 readings: allowed <= 2e\+07"):
        parse_scene("[run]\nduration_s = 100\n[instrument]\nsample_rate_hz = 1e6\n")


# -- 54.16: the sample limit is the same inclusive bound everywhere ---------------------
def test_the_sample_limit_is_allowed_by_the_scene_and_by_the_run():
    from tengfield.dynamics.run import check_samples

    scene = parse_scene("[run]\nduration_s = 1000\nsample_rate_hz = 20000\nsettle_periods = 0\n")
    check_samples(scene, 1000.0)      # 2e7 samples: the limit itself (refused here before)
    with pytest.raises(SceneError, match=r"= 20000020 samples: allowed <= 2e\+07 "):
        check_samples(scene, 1000.001)
