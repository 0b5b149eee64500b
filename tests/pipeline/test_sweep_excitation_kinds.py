"""`tengfield sweep` and `map` vary a sine's frequency and amplitude: a scene whose
excitation is not a sine (random, harmonics, recorded) is refused by sweep before any
work (its points would all be the same run, silently) and named by map (whose grid
points are sines whatever the scene says)."""
from __future__ import annotations

import pytest

from tengfield.errors import SceneError
from tengfield.scene import parse_scene
from tengfield.sweeps import check_grid

SCENES = {
    "random": '[excitation]\nkind = "random"\nband_hz = [10.0, 100.0]\n'
              'rms_acceleration_m_per_s2 = 10.0\n',
    "harmonics": '[excitation]\nkind = "harmonics"\nfrequency_hz = [20.0, 40.0]\n'
                 'amplitude_mm = [1.5, 0.1]\n',
}
RUN = "[run]\nduration_s = 0.5\nsettle_periods = 1\n"


@pytest.mark.parametrize("kind", sorted(SCENES))
def test_sweep_refuses_an_excitation_without_frequency_and_amplitude(kind):
    scene = parse_scene(SCENES[kind] + RUN)
    with pytest.raises(SceneError, match=rf"kind = '{kind}': a sweep varies a sine's"):
        check_grid(scene, [10.0, 20.0], [1e-3, 2e-3])
    check_grid(parse_scene(RUN), [10.0, 20.0], [1e-3, 2e-3])     # a sine: accepted


@pytest.mark.slow
def test_cli_sweep_refuses_and_map_names_it(tmp_path, run_cli):
    (tmp_path / "r.toml").write_text(SCENES["random"] + RUN)
    grid = ("--frequency-hz", "10:30:3", "--amplitude-mm", "1:2:2")
    sweep = run_cli("sweep", "r.toml", *grid, "-o", "sw", cwd=tmp_path, timeout=300)
    assert sweep.returncode == 2 and "Traceback" not in sweep.stderr
    assert sweep.stderr.startswith("tengfield: error: [excitation] kind = 'random'")
    assert not (tmp_path / "sw").exists()
    mapped = run_cli("map", "r.toml", *grid, "-o", "map", cwd=tmp_path, timeout=300)
    assert mapped.returncode == 0, mapped.stderr
    warnings = [ln for ln in mapped.stderr.splitlines() if ln.startswith("tengfield: warning:")]
    assert len(warnings) == 1 and "kind = 'random' is not used" in warnings[0]
    assert (tmp_path / "map" / "map.png").stat().st_size > 10_000
