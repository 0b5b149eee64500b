"""Issue #54 item 17: the Python API's entry points check their arguments with one helper
(``tengfield._args``: ``names``, ``path``, ``flag``, ``number``): a str is one name, never
its characters; a wrong kind is one TypeError naming the function and the argument; no
raw pathlib error, no string taken as true, no temporary file's name in a message."""
from __future__ import annotations

import pytest

import tengfield as tf
from tengfield.errors import OutputError, SceneError

SHORT = "[run]\nduration_s = 0.3\nsettle_periods = 2\nsample_rate_hz = 2000\n"


def _never(*args, **kwargs):
    raise AssertionError("no work may start")


def test_a_string_of_states_is_one_state():
    from tengfield._args import names

    assert names("f", "open", "states") == ["open"]
    assert names("f", ("open", "short"), "states") == ["open", "short"]
    with pytest.raises(TypeError, match=r"^f\(states=5\): expected a name or a list of names"):
        names("f", 5, "states")
    with pytest.raises(TypeError, match=r"^f\(states=\['open', 3\]\): expected names \(str\), "
                                        r"got 3"):
        names("f", ["open", 3], "states")


def test_breakdown_takes_states_as_one_name_and_names_a_bad_cache_dir(monkeypatch):
    from tengfield import air_breakdown
    from tengfield.air_breakdown import output

    seen = {}
    monkeypatch.setattr(output, "obtain_breakdown_table",
                        lambda scene, **kw: (None, None))
    monkeypatch.setattr(output, "scene_breakdown",
                        lambda scene, table, states: seen.setdefault("states", states) and _never())
    with pytest.raises(AssertionError, match="no work may start"):
        tf.breakdown(tf.default_scene(), states="open")
    assert seen["states"] == ["open"]            # was iterated: "state = 'o'"
    with pytest.raises(TypeError, match=r"^tengfield\.breakdown\(cache_dir=5\): expected a "
                                        r"folder name \(str or pathlib.Path\)"):
        air_breakdown.study(tf.default_scene(), cache_dir=5)


def test_calibrate_takes_one_target_and_one_free_name(monkeypatch):
    from tengfield import fit

    seen = {}

    def reference(scene, **kw):
        raise AssertionError("no work may start")

    monkeypatch.setattr(fit, "_reference_table", reference)
    real = fit.parse_fit_section

    def spy(scene, free=None):
        seen.setdefault("free", free)
        return real(scene, free)

    monkeypatch.setattr(fit, "parse_fit_section", spy)
    with pytest.raises(AssertionError, match="no work may start"):
        tf.calibrate(tf.default_scene(), targets="Q_pp_nC=0.3",
                     free="surface_charge_uC_per_m2")
    assert seen["free"] == ["surface_charge_uC_per_m2"]
    with pytest.raises(TypeError, match=r"^tengfield\.calibrate\(cache_dir=5\): expected a "
                                        r"folder name"):
        tf.calibrate(tf.default_scene(), targets="Q_pp_nC=0.3", cache_dir=5)
    with pytest.raises(TypeError, match=r"^tengfield\.calibrate\(targets=3\.0\): expected a "
                                        r"name or a list of names"):
        tf.calibrate(tf.default_scene(), targets=3.0)


def test_run_names_a_bad_cache_dir_before_any_work():
    with pytest.raises(TypeError, match=r"^tengfield\.run\(cache_dir=5\): expected a folder "
                                        r"name \(str or pathlib.Path\) or None, got int"):
        tf.run(tf.default_scene(), cache_dir=5, simulate=_never)


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    """A short run on the parallel-plate stand-in for the field (no dolfinx)."""
    import plate_model
    return tf.run(tf.parse_scene(SHORT), solve=plate_model.plate_model_solve,
                  cache_dir=tmp_path_factory.mktemp("cache"), write_cache=False)


def test_write_refuses_a_bad_folder_and_a_plots_that_is_no_bool(result, tmp_path):
    with pytest.raises(TypeError, match=r"^tengfield\.RunResult\.write\(out_dir=123\): "
                                        r"expected a folder name \(str or pathlib.Path\)"):
        result.write(123)
    for bad in ("no", 0, None):
        with pytest.raises(TypeError, match=r"^tengfield\.RunResult\.write\(plots="
                                            + repr(bad).replace("(", r"\(") + r"\): expected "
                                            r"True or False"):
            result.write(tmp_path / "out", plots=bad)
    assert not (tmp_path / "out").exists()      # nothing drawn, nothing written


def test_plot_refuses_a_string_of_periods(result):
    with pytest.raises(TypeError, match=r"^tengfield\.RunResult\.plot\(last_periods='5'\): "
                                        r"expected a number or None"):
        result.plot(last_periods="5")
    with pytest.raises(SceneError, match=r"^tengfield\.RunResult\.plot\(last_periods=-1\) is "
                                         r"out of range: allowed \(0, inf\]"):
        result.plot(last_periods=-1)


def test_spice_export_names_its_arguments_and_the_missing_folder(result, tmp_path):
    from tengfield import spice
    from tengfield.dynamics import simulate

    with pytest.raises(TypeError, match=r"^tengfield\.spice\.export\(path=123\): expected a "
                                        r"file name"):
        spice.export(result, 123)
    with pytest.raises(TypeError, match=r"^tengfield\.spice\.export\(result=.*\): expected a "
                                        r"run's result \(tengfield.run\(scene\)\), got "
                                        r"DynamicsResult"):
        spice.export(simulate(tf.parse_scene(SHORT)), tmp_path / "teng.lib")
    missing = tmp_path / "nowhere" / "teng.lib"
    with pytest.raises(OutputError) as err:
        spice.export(result, missing)
    text = str(err.value)
    assert text.startswith("tengfield.spice.export(path=") and "nowhere" in text
    assert ".tmp" not in text and "\n" not in text
    spice.export(result, tmp_path / "teng.lib")
    assert (tmp_path / "teng.lib").read_text().startswith("*")


def test_solve_position_refuses_a_string_position():
    with pytest.raises(TypeError, match=r"^tengfield\.solve_position\(position='1\.5e-3'\): "
                                        r"expected a number, got str"):
        tf.solve_position(tf.default_scene(), "1.5e-3", comm=None)


def test_load_scene_takes_toml_text_as_the_readme_says(tmp_path):
    scene = tf.load_scene("[run]\nduration_s = 1.5\n")
    assert scene.run.duration == 1.5
    assert tf.load_scene('[excitation]\nfrequency_hz = 30.0').excitation.frequency == 30.0
    f = tmp_path / "s.toml"
    f.write_text("[contact]\nrestitution = 0.3\n")
    assert tf.load_scene(str(f)).contact.restitution == 0.3      # a file name is still a file
    with pytest.raises(SceneError, match=r"does not exist"):
        tf.load_scene(str(tmp_path / "missing.toml"))


def _result_classes():
    """Every class of tengfield's modules with a ``write(self, out_dir, ...)`` method
    (a result's face): found by walking the package, so a new result is checked too."""
    import importlib
    import inspect
    import pkgutil

    import tengfield

    skip = ("tengfield.cli", "tengfield._early_interrupt", "tengfield._warmup",
            "tengfield._pool_preload")
    found = {}
    for info in pkgutil.walk_packages(tengfield.__path__, "tengfield."):
        if info.name.startswith(skip) or ".commands" in info.name:
            continue
        module = importlib.import_module(info.name)
        for _, cls in inspect.getmembers(module, inspect.isclass):
            write = cls.__dict__.get("write")
            if cls.__module__ != info.name or write is None:
                continue
            params = list(inspect.signature(write).parameters)
            if params[:2] == ["self", "out_dir"]:
                found[f"{cls.__module__}.{cls.__qualname__}"] = cls
    return found


def test_every_results_write_is_checked():
    classes = _result_classes()
    assert len(classes) >= 14, sorted(classes)     # run, sweep, dynamics, map, field, ...
    unchecked = [name for name, cls in classes.items()
                 if not getattr(cls.__dict__["write"], "checks_arguments", False)]
    assert not unchecked, unchecked


@pytest.mark.parametrize("name", sorted(_result_classes()))
def test_each_results_write_names_a_bad_folder_and_a_plots_that_is_no_bool(name, tmp_path):
    cls = _result_classes()[name]
    result = cls.__new__(cls)        # no __init__: the check comes before the result is read
    short = cls.__name__
    with pytest.raises(TypeError, match=rf"^tengfield\.{short}\.write\(out_dir=123\): "
                                        r"expected a folder name \(str or pathlib\.Path\)"):
        result.write(123)
    with pytest.raises(TypeError, match=rf"^tengfield\.{short}\.write\(plots='no'\): "
                                        r"expected True or False"):
        result.write(tmp_path / "out", plots="no")
    assert not (tmp_path / "out").exists()     # nothing drawn, nothing written


def test_calibrate_names_a_measured_that_is_no_file_name(monkeypatch):
    from tengfield import fit

    monkeypatch.setattr(fit, "_reference_table", _never)
    with pytest.raises(TypeError, match=r"^tengfield\.calibrate\(measured=5\): expected a "
                                        r"measured trace's file name"):
        tf.calibrate(tf.default_scene(), measured=5)
