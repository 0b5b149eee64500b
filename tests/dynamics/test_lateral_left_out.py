"""A lateral drive ([excitation] amplitude_x_mm, ..._y_, the lateral noise levels and
recorded columns) moves the ball only in the 3D model: with the 1-D impact or soft
model it was left out silently; now one warning line names the keys."""
from __future__ import annotations

import warnings

import pytest

from tengfield.dynamics import simulate
from tengfield.scene import parse_scene

RUN = "[run]\nduration_s = 0.2\nsettle_periods = 2\n"


@pytest.mark.parametrize("model", ["impact", "soft"])
def test_a_1d_model_names_the_lateral_drive_it_leaves_out(model):
    scene = parse_scene(f'[excitation]\namplitude_x_mm = 0.5\namplitude_y_mm = 0.25\n'
                        f'[contact]\nmodel = "{model}"\n' + RUN)
    with pytest.warns(RuntimeWarning, match=r"amplitude_x_mm = 0\.5, amplitude_y_mm = 0\.25 "
                                            rf"left out: \[contact\] model = '{model}'"):
        lateral = simulate(scene)
    # what it leaves out: the motion is the axial drive's alone
    axial = simulate(parse_scene(f'[contact]\nmodel = "{model}"\n' + RUN))
    assert (lateral.gap == axial.gap).all()


def test_no_warning_without_a_lateral_drive_or_in_3d():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        simulate(parse_scene(RUN))
        simulate(parse_scene('[excitation]\namplitude_x_mm = 0.5\n[contact]\nmodel = "3d"\n'
                             + RUN))


@pytest.mark.slow
def test_cli_prints_one_line(tmp_path, run_cli):
    (tmp_path / "lat.toml").write_text("[excitation]\namplitude_x_mm = 0.5\n" + RUN)
    done = run_cli("dynamics", "lat.toml", "-o", "out", cwd=tmp_path, timeout=300)
    assert done.returncode == 0, done.stderr
    lines = [ln for ln in done.stderr.splitlines() if ln.startswith("tengfield: warning:")]
    assert len(lines) == 1 and "amplitude_x_mm = 0.5 left out" in lines[0], done.stderr
