"""The top-level verbs (issue #41): ``tf.design``, ``tf.uncertainty``, ``tf.breakdown``,
``tf.report`` and ``tf.sweep`` are plain functions taking a scene and returning their result; the packages
that hold the studies carry nouns (``design_study``, ``uncertainty_study``,
``air_breakdown``, ``accuracy_report``, ``sweeps``), so importing one never replaces a verb. The face
of each result (``.scene``, ``.summary``, ``.plot()``, ``.write()``) is
``tests/test_public_api.py``'s."""
from __future__ import annotations

import ast
import importlib
import inspect
import os
import subprocess
import sys
from pathlib import Path

import pytest

import tengfield as tf

ROOT = Path(__file__).resolve().parents[1]

#: verb -> the package that holds its study
VERBS = {"design": "tengfield.design_study", "uncertainty": "tengfield.uncertainty_study",
         "breakdown": "tengfield.air_breakdown", "report": "tengfield.accuracy_report",
         "sweep": "tengfield.sweeps"}


@pytest.mark.parametrize("verb", sorted(VERBS))
def test_each_verb_is_a_plain_function_whose_first_argument_is_the_scene(verb):
    function = getattr(tf, verb)
    assert inspect.isfunction(function), f"tf.{verb} is {type(function).__name__}"
    assert next(iter(inspect.signature(function).parameters)) == "scene"
    module = function.__module__
    assert module == VERBS[verb] or module.startswith(VERBS[verb] + ".")
    assert verb in tf.__all__ and verb in dir(tf)


@pytest.mark.parametrize("verb", sorted(VERBS))
def test_importing_a_study_package_leaves_its_verb_in_place(verb):
    """``import tengfield.<package>`` sets an attribute of ``tengfield``: a subpackage
    named like the verb would replace the function with a module."""
    importlib.import_module(VERBS[verb])
    assert inspect.isfunction(getattr(tf, verb))
    with pytest.raises(ModuleNotFoundError):
        importlib.import_module(f"tengfield.{verb}")


@pytest.mark.parametrize("verb", sorted(VERBS))
def test_a_verb_given_no_scene_names_itself_and_the_argument(verb):
    """One TypeError line naming the verb as the user called it, before any work."""
    with pytest.raises(TypeError, match=rf"^tengfield\.{verb}\(scene=42\): expected a "
                                        r"tengfield\.Scene") as info:
        getattr(tf, verb)(42)
    assert "\n" not in str(info.value)


def test_importing_tengfield_imports_no_study_until_a_verb_is_used():
    code = ("import sys, tengfield as tf; tf.default_scene(); "
            f"packages = {sorted(VERBS.values())!r}; "
            "print(sorted(m for m in packages if m in sys.modules)); tf.design; tf.report; "
            "print(sorted(m for m in packages if m in sys.modules))")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=ROOT, env={**os.environ, "PYTHONPATH": str(ROOT / "src")})
    assert proc.returncode == 0, proc.stderr
    before, after = map(ast.literal_eval, proc.stdout.split("\n")[:2])
    assert before == []
    assert {"tengfield.accuracy_report", "tengfield.design_study"} <= set(after)
