"""σ has one name in code (issue #41): the scene key ``[device] surface_charge_uC_per_m2`` is
spelled once in src, in the base layer's ``quantities.py`` (:data:`SURFACE_CHARGE_KEY`, which
the scene's schema hands on, and :data:`SURFACE_CHARGE_SETTING` as "section.key"); the
file's stated value is read in one place (``scene.schema.stated_surface_charge``); code
names the quantity ``surface_charge`` (SI, C/m²). Tests keep the literal: it is what a user
types."""
from __future__ import annotations

from pathlib import Path

import pytest

from tengfield.scene import default_scene, parse_scene
from tengfield.scene.schema import (KEYWORD_VALUES, SCHEMA, SURFACE_CHARGE_KEY,
                                    SURFACE_CHARGE_SETTING, stated_surface_charge)

SRC = Path(__file__).resolve().parents[2] / "src" / "tengfield"
LITERAL = "surface_charge_uC_per_m2"
HOME = "quantities.py"


def test_the_key_is_spelled_once_in_src():
    spelled = {path.relative_to(SRC).as_posix(): path.read_text().count(LITERAL)
               for path in sorted(SRC.rglob("*.py")) if LITERAL in path.read_text()}
    assert spelled.pop(HOME, 0) == 1, f"{HOME} spells {LITERAL!r} once: SURFACE_CHARGE_KEY"
    assert "import SURFACE_CHARGE_KEY" in (SRC / "scene" / "schema.py").read_text()
    stray = sorted(spelled)
    assert not stray, f"{LITERAL!r} spelled outside {HOME} (use SURFACE_CHARGE_KEY): {stray}"


def test_the_constant_names_the_schema_key_of_the_surface_charge():
    assert SURFACE_CHARGE_KEY == LITERAL
    assert SURFACE_CHARGE_SETTING == f"device.{LITERAL}"
    key = SCHEMA["device"][SURFACE_CHARGE_KEY]
    assert key.attr == "surface_charge" and key.factor == pytest.approx(1e-6)   # µC/m² -> C/m²
    assert KEYWORD_VALUES[("device", SURFACE_CHARGE_KEY)][0] == "breakdown"


@pytest.mark.parametrize("text, stated, si", [
    ("[device]\nsurface_charge_uC_per_m2 = -30.0\n", -30.0, -30e-6),
    ('[device]\nsurface_charge_uC_per_m2 = "breakdown"\n', "breakdown", None),
    ("[device]\nstroke_mm = 2.0\n", None, None),
])
def test_the_stated_value_is_what_the_file_says(text, stated, si):
    scene = parse_scene(text)
    assert stated_surface_charge(scene) == stated
    if si is not None:
        assert scene.device.surface_charge == pytest.approx(si)   # SI inside


def test_a_scene_built_from_python_states_what_it_was_given():
    scene = default_scene().with_values(device={LITERAL: "breakdown"})
    assert stated_surface_charge(scene) == "breakdown"
