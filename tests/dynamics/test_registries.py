"""The dynamics' registries: one entry per contact model and per excitation kind,
the same names the scene file allows, and simulate dispatching through them."""
import re

from types import SimpleNamespace

import numpy as np
import pytest

from tengfield.dynamics import MODELS, simulate
from tengfield.dynamics.excitation import EXCITATIONS, table_from_scene
from tengfield.dynamics.models import ContactModel
from tengfield.errors import DynamicsError, SceneError
from tengfield.scene import default_scene, parse_scene


def _allowed(text: str) -> list[str]:
    with pytest.raises(SceneError) as info:
        parse_scene(text)
    return re.findall(r"'([^']+)'", str(info.value).split("choose one of", 1)[1])


def test_models_are_the_scene_files_choices():
    assert list(MODELS) == _allowed('[contact]\nmodel = "none"\n')


def test_excitation_kinds_are_the_scene_files_choices():
    assert list(EXCITATIONS) == _allowed('[excitation]\nkind = "none"\n')


def test_simulate_dispatches_through_models(monkeypatch):
    calls = []

    def fake(scene, *, duration=None):
        calls.append(duration)
        return SimpleNamespace(ran=True)

    import tengfield.dynamics as dynamics

    monkeypatch.setitem(MODELS, "impact", ContactModel(fake, event_map=True))
    # the settling check (which continues a real run) is not what is tested here
    monkeypatch.setattr(dynamics, "_settled", lambda scene, model, result, duration: result)
    scene = default_scene()
    result = simulate(scene, duration=0.5)
    assert result.ran and calls == [0.5]
    assert result.scene is scene          # the result keeps the scene it ran (#41)


def test_only_a_phased_kind_takes_another_phase():
    sine = default_scene()
    shifted = table_from_scene(sine, phase=sine.excitation.phase + 0.5)
    y0 = table_from_scene(sine).evaluate(np.array([0.0]))[0]
    assert shifted.evaluate(np.array([0.0]))[0] != y0
    harmonics = parse_scene('[excitation]\nkind = "harmonics"\nfrequency_hz = [30.0, 60.0]\n'
                            'amplitude_mm = [0.5, 0.1]\n[run]\nduration_s = 0.2\n'
                            'settle_periods = 2\n')
    same = harmonics.excitation.phase
    assert table_from_scene(harmonics, phase=same).kind == table_from_scene(harmonics).kind
    with pytest.raises(DynamicsError, match="only a sine"):
        table_from_scene(harmonics, phase=same + 0.5)
