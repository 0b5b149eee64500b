"""σ is ``surface_charge`` in code (issue #41): the σ a scene runs with is
:func:`tengfield.air_breakdown.scene_surface_charge` [C/m²], and the stand-in σ of
``"breakdown"`` before σ_max is known is the schema's one value, not a second constant."""
from __future__ import annotations

from types import SimpleNamespace

import pytest

from tengfield import air_breakdown
from tengfield.scene import parse_scene
from tengfield.scene.schema import BREAKDOWN_PLACEHOLDER_UC
from tengfield.surrogate.cache import solved_scene


def test_the_surface_charge_a_scene_runs_with():
    limit = SimpleNamespace(sigma_max=25e-6)                 # σ_max [C/m²]
    numeric = parse_scene("[device]\nsurface_charge_uC_per_m2 = -40.0\n")
    assert air_breakdown.scene_surface_charge(numeric, limit) == pytest.approx(-40e-6)
    at_limit = parse_scene('[device]\nsurface_charge_uC_per_m2 = "breakdown"\n')
    assert air_breakdown.scene_surface_charge(at_limit, limit) == pytest.approx(-25e-6)
    assert not hasattr(air_breakdown, "scene_sigma")


def test_one_stand_in_charge_for_breakdown():
    assert not hasattr(air_breakdown, "PLACEHOLDER_SIGMA")
    uncharged = parse_scene("[device]\nsurface_charge_uC_per_m2 = 0.0\n")
    assert solved_scene(uncharged).device.surface_charge == pytest.approx(
        BREAKDOWN_PLACEHOLDER_UC * 1e-6)
