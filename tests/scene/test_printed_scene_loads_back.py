"""Issue 54 item 7: ``tengfield scene i.toml > j.toml; tengfield scene j.toml`` loads back,
whatever i.toml gives: the printed scene never holds a deprecated key beside its new one."""
from __future__ import annotations

import pytest

from tengfield.scene import parse_scene
from tengfield.scene.schema import DEPRECATED_KEYS


@pytest.mark.parametrize("text", ["", "[instrument]\ncapacitance_pF = 338\n",
                                  "[circuit]\nparallel_capacitance_pF = 100\n",
                                  "[instrument]\ncapacitance_pF = 338\n[circuit]\nkind = 'load'\n"])
def test_a_printed_scene_loads_back_to_the_same_scene(text, recwarn):
    from tengfield.commands.scene import toml_text   # what `tengfield scene` prints

    def printed_of(scene):
        return toml_text(scene.to_dict(), "tengfield scene")

    first = parse_scene(text)
    printed = printed_of(first)
    second = parse_scene(printed)
    assert second == first
    assert parse_scene(printed_of(second)) == second
    for sec, key in DEPRECATED_KEYS:
        given = key in (first.raw.get(sec) or {})
        assert (f"\n{key} =" in "\n" + printed) == given, (sec, key)
