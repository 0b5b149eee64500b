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


# -- 54.11: every figure's pixels are bounded; --dpi is refused past it before the work --
def _commands_with_dpi():
    from tengfield import cli

    parser = cli.build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")   # noqa: SLF001
    for name, command in sub.choices.items():
        actions = command._actions                                   # noqa: SLF001
        if any(a.option_strings == ["--dpi"] for a in actions):
            required = [arg for a in actions if a.required and a.option_strings
                        for arg in (a.option_strings[0], "1")]
            positional = [a for a in actions if not a.option_strings and a.required
                          and a.nargs not in ("?", "*")]
            groups = [g for g in command._mutually_exclusive_groups if g.required]  # noqa: SLF001
            required += [arg for g in groups for arg in (g._group_actions[0].option_strings[0],  # noqa: SLF001
                                                         "x")]
            yield name, required + ["x"] * len(positional)


def test_several_commands_take_dpi():
    names = {name for name, _ in _commands_with_dpi()}
    assert {"run", "field", "sweep", "dynamics", "design", "uncertainty"} <= names


@pytest.mark.parametrize("name, extra", list(_commands_with_dpi()))
def test_every_command_refuses_a_dpi_past_the_pixel_bound_before_the_work(name, extra,
                                                                          tmp_path, capsys):
    from tengfield import cli
    from tengfield.files.figures import DPI_RANGE, MAX_FIGURE_PIXELS

    assert MAX_FIGURE_PIXELS == 50e6 and DPI_RANGE == (20.0, 683.0)
    out = tmp_path / "out"
    code = cli.main([name, *extra, "-o", str(out), "--dpi", "1200"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, err
    assert err[0] == ("tengfield: error: --dpi 1200 is out of range: allowed [20, 683] dots "
                      "per inch (a figure is at most 50 megapixels; the largest, field.png, "
                      "would be 14000 x 11000 px here)")
    assert not out.exists()


def test_field_png_at_the_highest_dpi_stays_within_the_bound():
    from tengfield.field.io import figure_window
    from tengfield.files import set_figure_dpi

    try:
        set_figure_dpi(683)
        w, h = figure_window((1400, 1100))
    finally:
        set_figure_dpi(None)
    assert w * h <= 50e6 and (w, h) == (7968, 6261)
    with pytest.raises(ValueError, match=r"^--dpi 684 is out of range: allowed \[20, 683\]"):
        set_figure_dpi(684)     # one more dot per inch: field.png past 50 megapixels


def test_a_figure_grown_past_the_bound_is_drawn_within_it_with_one_warning(tmp_path):
    from PIL import Image

    from tengfield import plotting

    fig = plotting.new_figure((40.0, 10.0))
    fig.subplots().plot([0, 1], [0, 1])
    with pytest.warns(RuntimeWarning, match=r"^wide.png: 40 x 10 in at 600 dpi would be 24000 x "
                                            r"6000 px \(144 megapixels\): drawn at 353 dpi "
                                            r"\(allowed <= 50 megapixels per figure\)"):
        plotting.save_figure(fig, tmp_path / ".wide.tmp-77.png", 600)
    with Image.open(tmp_path / ".wide.tmp-77.png") as image:
        assert image.size[0] * image.size[1] <= 50e6


# -- 54.16: messages name what the user wrote -------------------------------------------
def test_a_toml_date_in_set_names_the_key():
    from tengfield.scene.parse import parse_setting

    with pytest.raises(SceneError, match=r"^--set: \[run\] duration_s = 1979-05-27 \(a TOML "
                                         r"date/time\): no scene key takes a date"):
        parse_setting("run.duration_s=1979-05-27")


def test_set_on_an_absent_uncertainty_entry_says_it_has_no_distribution():
    from tengfield.scene import default_scene, with_settings
    from tengfield.uncertainty_study.spec import uncertainty_spec

    scene = with_settings(default_scene(), ['uncertainty.vary."contact.restitution".low=0.1'])
    with pytest.raises(SceneError) as err:
        uncertainty_spec(scene)
    text = str(err.value)
    assert text.startswith("[uncertainty.vary] 'contact.restitution': no distribution given "
                           "(only low = 0.1;"), text
    assert "None" not in text and "'uniform'" in text


@pytest.mark.parametrize("fit, text", [
    ("[fit.parameters]\nsurface_charge_uC_per_m2 = {min = nan}\n",
     "[fit.parameters] surface_charge_uC_per_m2.min = nan: expected a finite number"),
    ("[fit.parameters]\nrestitution = {max = inf}\n",
     "[fit.parameters] restitution.max = inf: expected a finite number in [0, 1]"),
    ("[fit.columns.V]\nnoise = nan\n",
     "[fit.columns.V] noise = nan: expected a finite number in (0, inf)"),
    ("[fit.parameters]\nload_ohm = {min = -inf}\n",
     "[fit.parameters] load_ohm.min = -inf: expected a finite number in (0, inf)"),
])
def test_nan_and_inf_in_fit_are_finite_numbers_with_the_keys_own_range(fit, text):
    from tengfield.fit.spec import parse_fit_section

    with pytest.raises(SceneError) as err:
        parse_fit_section(parse_scene(fit))
    assert str(err.value) == text and "[-inf, inf]" not in str(err.value)


def test_a_list_of_lists_in_vary_is_a_list_of_values_and_errors_name_vary():
    from tengfield.sweeps import parse_vary

    assert parse_vary("device.stroke_mm=[[2, 3], [4]]") == ("device.stroke_mm", [[2, 3], [4]])
    assert parse_vary("device.stroke_mm=1,2,4") == ("device.stroke_mm", [1, 2, 4])
    assert parse_vary("circuit.kind=load,open") == ("circuit.kind", ["load", "open"])
    with pytest.raises(SceneError, match=r"^--vary 'device.stroke_mm=\[1, 2': '\[1, 2' is no "
                                         r"TOML value"):
        parse_vary("device.stroke_mm=[1, 2")


def test_a_time_unit_the_header_contradicts_is_one_line(run_cli, tmp_path):
    import math

    rows = "\n".join(f"{i * 0.2:.3f},{100 * math.sin(2 * math.pi * 20 * i * 0.2e-3):.5f}"
                     for i in range(400))
    (tmp_path / "tr.csv").write_text("t [ms],V_oc_V\n" + rows + "\n")
    (tmp_path / "s.toml").write_text('[fit]\ntime_column = "t"\ntime_unit = "s"\n' + BASE)
    proc = run_cli("fit", "s.toml", "-o", tmp_path / "out", "--measured", "tr.csv",
                   cwd=tmp_path, timeout=300)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert lines == ["tengfield: error: --measured 'tr.csv': the header gives the time column "
                     "'t' the unit 'ms', but [fit] time_unit = 's': they disagree; drop the "
                     "key (the header's unit is used) or write the header's"], proc.stderr
    assert not (tmp_path / "out").exists()


def test_the_deprecated_capacitance_warns_via_set_as_in_a_file():
    from tengfield.scene import default_scene, with_settings

    with pytest.warns(FutureWarning, match=r"^--set circuit.parallel_capacitance_pF: \[circuit\] "
                                           r"parallel_capacitance_pF is now \[instrument\] "
                                           r"capacitance_pF: write --set "
                                           r"instrument.capacitance_pF=338 "):
        scene = with_settings(default_scene(), ["circuit.parallel_capacitance_pF=338"])
    assert scene.instrument.capacitance == pytest.approx(338e-12)
    with pytest.warns(FutureWarning, match=r"^<string>: \[circuit\] parallel_capacitance_pF is "
                                           r"now \[instrument\] capacitance_pF: write "
                                           r"\[instrument\] capacitance_pF = 338 "):
        parse_scene("[circuit]\nparallel_capacitance_pF = 338\n")


# -- 54.16: a reader slower than the steady window is one line, before the work --------
@pytest.mark.parametrize("rate, count", [("2", 0), ("5", 1)])
def test_a_reader_with_fewer_than_two_readings_in_the_window_is_one_line(rate, count,
                                                                         run_cli, tmp_path):
    scene = tmp_path / "base.toml"
    scene.write_text(BASE)
    out = tmp_path / "out"
    proc = run_cli("run", scene, "-o", out, "--set", f"instrument.sample_rate_hz={rate}",
                   timeout=120)
    assert proc.returncode == 2, proc.stderr[-2000:]     # was exit 0 with "Q_read peak 0 nC"
    errors = [line for line in proc.stderr.splitlines() if "error" in line]
    assert len(errors) == 1 and "Traceback" not in proc.stderr, proc.stderr[-2000:]
    assert errors[0].startswith(f"tengfield: error: [instrument] sample_rate_hz = {rate}: "
                                f"{count} reading(s) in the steady window t = 0.1 to 0.3 s")
    assert "allowed sample_rate_hz >= 10 for this window" in errors[0]
    assert not out.exists()


def test_the_window_count_is_the_readers_own():
    """:func:`window_readings` counts the instants :class:`SampleHold` reads at: fed its
    own time axis, the distinct readings at or after the window's start are the count."""
    import numpy as np
    from hypothesis import given, settings, strategies as st

    from tengfield.electrical.instrument import SampleHold
    from tengfield.scene.limits import window_readings

    @settings(max_examples=60, deadline=None)
    @given(st.floats(0.5, 400.0), st.floats(0.0, 0.8), st.floats(0.05, 1.0))
    def check(rate, start_fraction, duration):
        t = np.linspace(0.0, duration, 4001)
        held = SampleHold(rate)(t, t)           # each reading holds its own instant
        start = start_fraction * duration
        read = np.unique(held[t >= start])
        inside = read[read >= start - 1e-9 / rate]
        assert window_readings(start, duration, rate) == inside.size

    check()


def test_exactly_two_readings_in_the_window_run():
    with pytest.warns(RuntimeWarning, match="Nyquist"):     # 0.1333 and 0.2667 s
        scene = parse_scene(BASE + "[instrument]\nsample_rate_hz = 7.5\n")
    assert scene.instrument.sample_rate == 7.5


def test_a_reader_below_nyquist_warns_once():
    import warnings

    from tengfield.scene import with_settings

    with pytest.warns(RuntimeWarning, match=r"^\[instrument\] sample_rate_hz = 13 takes 0\.65 "
                                            r"reading\(s\) per period of \[excitation\] "
                                            r"frequency_hz = 20, fewer than 2 \(Nyquist\)"):
        scene = parse_scene(BASE + "[instrument]\nsample_rate_hz = 13\n")
    with warnings.catch_warnings(record=True) as caught:   # --set on it: said once already
        warnings.simplefilter("always")
        with_settings(scene, ["run.duration_s=0.4"])
        parse_scene(BASE + "[instrument]\nsample_rate_hz = 40\n")   # 2 per period: no word
    assert not [w for w in caught if "Nyquist" in str(w.message)]
