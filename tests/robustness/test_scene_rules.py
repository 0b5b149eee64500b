"""#30 item 23: what a command refuses or leaves out later is said when the scene is read
(``tengfield scene`` included): [array] with model = "3d", ensemble seeds past 2^32 - 1,
penetration_max_mm with the Hertz law."""
import warnings

import pytest

from tengfield.errors import SceneError
from tengfield.scene import parse_scene

NOISE = '[excitation]\nkind = "random"\nband_hz = [10.0, 100.0]\nrms_acceleration_m_per_s2 = 5.0\n'


def test_an_array_with_the_3d_model_is_refused_when_read():
    with pytest.raises(SceneError, match=r"\[contact\] model = '3d': \[array\] runs need the "
                                         r"impact map"):
        parse_scene('[contact]\nmodel = "3d"\n[array]\ncells = 4\n')


@pytest.mark.parametrize("seed, runs, ok", [(4294967295, 3, False), (4294967293, 3, True),
                                            (4294967295, 1, True)])
def test_ensemble_seeds_never_wrap(seed, runs, ok):
    text = NOISE + f"seed = {seed}\n[run]\nrealisations = {runs}\n"
    if ok:
        parse_scene(text)
        return
    with pytest.raises(SceneError, match=r"\[excitation\] seed = 4294967295 with \[run\] "
                                         r"realisations = 3: .*allowed seed \+ realisations - 1 "
                                         r"<= 4294967295 \(seed <= 4294967293\)"):
        parse_scene(text)


def test_penetration_max_with_the_hertz_law_is_one_warning():
    with pytest.warns(RuntimeWarning, match=r"penetration_max_mm = 0.05 left out: .*law = "
                                            r"'power' only"):
        parse_scene('[contact]\nmodel = "3d"\npenetration_max_mm = 0.05\n')
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        parse_scene('[contact]\nmodel = "3d"\nlaw = "power"\npenetration_max_mm = 0.05\n')


def test_scene_command_refuses_what_run_refuses(tmp_path, capsys):
    from tengfield import cli

    (tmp_path / "s.toml").write_text('[contact]\nmodel = "3d"\n[array]\ncells = 4\n')
    assert cli.main(["scene", str(tmp_path / "s.toml")]) == 2
    assert "[array] runs need the impact map" in capsys.readouterr().err
