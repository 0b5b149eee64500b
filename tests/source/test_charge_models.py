"""Issue #51: the charge models as a registry (``tengfield.charge_models``): the scene's
choices are its names, every caller asks the entry (the breakdown limit, the contacts,
the keys it reads, the commands that run it), and a command that does not run a model
refuses it in one line naming those that do."""
from __future__ import annotations

import pytest

import tengfield as tf
from tengfield.air_breakdown import uses_breakdown_charge
from tengfield.charge_models import (CHARGE_MODELS, charge_model_of, check_command,
                                     models_reading)
from tengfield.scene.schema import SCHEMA

import plate_model as fx


def test_the_schema_offers_exactly_the_registrys_models():
    assert set(SCHEMA["charge"]["model"].check[1]) == set(CHARGE_MODELS)


def test_every_charge_key_is_read_by_some_model():
    for key in SCHEMA["charge"]:
        assert any(entry.reads(key) for entry in CHARGE_MODELS.values()), key
    assert models_reading("efficiency") == '"contact"'


@pytest.mark.parametrize("sections, name, limit, contacts", [
    ({}, "constant", False, False),
    ({"charge": {"model": "breakdown"}}, "breakdown", True, False),
    ({"device": {"surface_charge_uC_per_m2": "breakdown"}}, "breakdown", True, False),
    ({"charge": {"model": "contact"}}, "contact", False, True),
])
def test_the_scene_runs_with_its_entry(sections, name, limit, contacts):
    scene = fx.scene_with(**sections)
    entry = charge_model_of(scene)
    assert entry is CHARGE_MODELS[name]
    assert uses_breakdown_charge(scene) is limit
    assert scene.charge.from_contacts is contacts


@pytest.mark.parametrize("command", ["breakdown", "fit", "report"])
def test_a_command_that_does_not_run_a_model_names_those_that_do(command):
    scene = fx.scene_with(charge={"model": "contact"})
    with pytest.raises(tf.TengfieldError) as caught:
        check_command(scene, command)
    text = str(caught.value)
    assert text.startswith(f'[charge] model = "contact" is not supported by tengfield '
                           f'{command} yet')
    assert "`tengfield sweep`" in text and '"constant" or "breakdown"' in text
    for other in ("run", "sweep", "uncertainty", "design"):
        check_command(scene, other)                  # these run it: no error
    check_command(fx.scene_with(), command)          # a constant charge: every command
