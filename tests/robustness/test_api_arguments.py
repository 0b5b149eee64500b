"""The Python API's arguments: one TypeError or ValueError naming the function and the
argument, never a raw Python error deep inside or a value silently ignored; the messages
say ``jobs``, not the CLI's ``--jobs`` (issue #43.19)."""
from __future__ import annotations

import math
from pathlib import Path

import pytest

import tengfield as tf
from tengfield.errors import SceneError


@pytest.mark.parametrize("path, error, text", [
    (5, TypeError, r"tengfield.load_scene\(path=5\): expected a file name \(str or pathlib.Path\)"),
    (b"scene.toml", TypeError, r"load_scene\(path=b'scene.toml'\): expected a file name"),
    ("", SceneError, r"load_scene\(path=''\): an empty file name"),
    ("  ", SceneError, r"an empty file name"),
])
def test_load_scene_names_a_bad_path(path, error, text):
    with pytest.raises(error, match=text):
        tf.load_scene(path)


def test_load_scene_still_takes_str_path_scene_and_none(tmp_path):
    f = tmp_path / "s.toml"
    f.write_text("[contact]\nrestitution = 0.3\n")
    assert tf.load_scene(str(f)) == tf.load_scene(Path(f))
    assert tf.load_scene(None) == tf.default_scene()


@pytest.mark.parametrize("jobs, error", [("2", TypeError), (2.5, TypeError), (True, TypeError),
                                         (0, SceneError), (-3, SceneError)])
def test_run_refuses_bad_jobs_before_any_work(jobs, error):
    def never(scene):
        raise AssertionError("no work may start")

    with pytest.raises(error) as err:
        tf.run(tf.default_scene(), jobs=jobs, simulate=never)
    text = str(err.value)
    assert "tengfield.run(jobs=" in text and "--jobs" not in text and "\n" not in text


def test_uncertainty_names_a_bad_spec_and_jobs():
    """Messages name the verb as the user calls it (``tf.uncertainty``)."""
    with pytest.raises(TypeError, match=r"^tengfield\.uncertainty\(spec='abc'\): expected an "
                                        r"UncertaintySpec"):
        tf.uncertainty(tf.default_scene(), spec="abc")
    with pytest.raises(TypeError, match=r"^tengfield\.uncertainty\(jobs='2'\): expected a "
                                        r"whole number"):
        tf.uncertainty(tf.default_scene(), jobs="2")


def test_design_entry_points_name_their_arguments():
    from tengfield.design_study import evaluate
    from tengfield.design_study.search import DesignResult, check_optimum

    with pytest.raises(TypeError, match=r"tengfield.design\(scene=None\): expected a "
                                        r"tengfield.Scene"):
        tf.design(None)
    with pytest.raises(TypeError, match=r"design_study\.evaluate\(spec=None\): expected a "
                                        r"DesignSpec"):
        evaluate(tf.default_scene(), None, {"stroke_mm": 2.0})
    with pytest.raises(TypeError, match=r"check_optimum\(result=None\)"):
        check_optimum(None)
    result = DesignResult.__new__(DesignResult)
    for bad in (math.nan, -1.0, 0.0, 2.0, math.inf):
        with pytest.raises(SceneError, match=r"check_optimum\(fraction=.*\) is out of range: "
                                             r"allowed \(0, 1\]"):
            check_optimum(result, fraction=bad)
    with pytest.raises(TypeError, match=r"check_optimum\(fraction='0.2'\): expected a number"):
        check_optimum(result, fraction="0.2")
