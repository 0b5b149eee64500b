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


# -- #30 item 20: messages -------------------------------------------------------------
def test_the_sample_limit_itself_is_allowed_and_past_it_the_numbers_differ():
    from tengfield.scene.limits import MAX_SAMPLES

    parse_scene(f"[run]\nduration_s = {MAX_SAMPLES / 20000:.17g}\nsample_rate_hz = 20000\n"
                "settle_periods = 0\n")
    with pytest.raises(SceneError, match=r"= 20000000\.02 samples: allowed <= 2e\+07 "):
        parse_scene(f"[run]\nduration_s = 1000.000001\nsample_rate_hz = 20000\n")


@pytest.mark.parametrize("noise", ["0", "-1"])
def test_fit_noise_zero_and_negative_say_the_same_range(noise):
    from tengfield.fit import parse_fit_section

    scene = parse_scene(f'[fit.columns.V]\ncolumn = "v"\nnoise = {noise}\n')
    with pytest.raises(SceneError, match=r"noise = -?[01] is out of range: allowed \(0, inf\)"):
        parse_fit_section(scene)


def test_a_psd_table_with_both_columns_says_so(tmp_path):
    (tmp_path / "psd.csv").write_text("frequency_hz,psd_g2_per_hz,psd_m2_per_s4_per_hz\n"
                                      "10,1e-3,0.1\n100,1e-3,0.1\n")
    (tmp_path / "s.toml").write_text('[excitation]\nkind = "random"\npsd_file = "psd.csv"\n')
    from tengfield.scene import load_scene
    with pytest.raises(SceneError, match="has both psd_g2_per_hz and psd_m2_per_s4_per_hz: "
                                         "keep exactly one"):
        load_scene(tmp_path / "s.toml")


def test_a_fifo_as_scene_file_is_named(tmp_path):
    import os

    from tengfield.scene import load_scene
    os.mkfifo(tmp_path / "s.toml")
    with pytest.raises(SceneError, match=r"is a named pipe \(FIFO\), not a regular file"):
        load_scene(tmp_path / "s.toml")


@pytest.mark.parametrize("value", ["x" * 500_000, "sine\u200b"])
def test_a_long_or_invisible_choice_is_shown_short_and_escaped(value):
    with pytest.raises(SceneError) as err:
        parse_scene(f'[excitation]\nkind = "{value}"\n')
    text = str(err.value)
    assert len(text) < 300 and "\u200b" not in text and "is not allowed: choose one of" in text
    if value.startswith("sine"):
        assert "'sine\\u200b'" in text


def test_a_failing_sweep_point_is_named(monkeypatch):
    """#30 item 20: an error inside one point of a sweep names the point."""
    import tengfield.sweeps as sweep_module
    from tengfield.errors import DynamicsError
    from tengfield.scene import default_scene

    def point(scene, table, frequency, amplitude, loads):
        if frequency > 25:
            raise DynamicsError("the impact map diverged")
        return [{"frequency_hz": frequency}]

    monkeypatch.setattr(sweep_module, "sweep_point", point)
    with pytest.raises(DynamicsError, match=r"^sweep point frequency_hz = 30, amplitude_mm = 1\.5: "
                                            r"the impact map diverged$"):
        sweep_module.sweep(default_scene(), None, [20.0, 30.0], [1.5e-3], jobs=1)


def test_fit_names_its_own_window_when_the_record_is_too_short(tmp_path):
    """#30 item 20: fit runs the dynamics for settle + trace + one period (1.65 s here),
    not for [run] duration_s = 1; a 1 s record is refused naming that window."""
    import numpy as np

    from tengfield.fit._model import ForwardModel
    from tengfield.scene import load_scene

    t = np.arange(10_000) * 1e-4
    (tmp_path / "t.csv").write_text("time_s,z_m\n" + "".join(
        f"{float(a)!r},{float(1.5e-3 * np.sin(2 * np.pi * 20 * a))!r}\n" for a in t))
    (tmp_path / "s.toml").write_text('[excitation]\nkind = "recorded"\nfile = "t.csv"\n'
                                     'time_column = "time_s"\nsignal_column = "z_m"\n'
                                     'frequency_hz = 20\n[run]\nduration_s = 1\n'
                                     'settle_periods = 10\n')
    scene = load_scene(tmp_path / "s.toml")
    with pytest.raises(SceneError, match=r"^fit: the model runs 1\.65 s \(0\.5 s of "
                                         r"settle_periods / frequency_hz, 1\.1 s of the measured "
                                         r"trace.*\[0, 0\.9999\] s is shorter"):
        ForwardModel(scene, None, 1.0, span=1.1, simulate=lambda s: None)
    ForwardModel(scene, None, 1.0, span=0.3, simulate=lambda s: None)   # fits: accepted
