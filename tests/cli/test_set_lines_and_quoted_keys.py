"""#43 item 14: ``--set`` refuses a value with a line break (TOML read its first line and
dropped the rest silently) and addresses one ``[uncertainty.vary]`` entry by a quoted
dotted key (``uncertainty.vary."contact.restitution"=...``)."""
from __future__ import annotations

import pytest

from tengfield.cli import main
from tengfield.errors import SceneError
from tengfield.scene import parse_scene, with_settings

VARY = ('[uncertainty]\nsamples = 64\n[uncertainty.vary]\n'
        '"contact.restitution" = { distribution = "uniform", low = 0.1, high = 0.5 }\n')


@pytest.mark.parametrize("setting", ["excitation.frequency_hz=30\nrun.duration_s=99",
                                     "excitation.frequency_hz=30\r\n",
                                     'circuit.kind="load"\nload_ohm = 1'])
def test_a_value_with_a_line_break_is_refused(setting):
    with pytest.raises(SceneError, match="line break"):
        with_settings(parse_scene(""), [setting])


def test_the_cli_refuses_a_line_break_in_one_line(capsys):
    assert main(["scene", "--set", "excitation.frequency_hz=30\nrun.duration_s=99"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "line break" in err, err


def test_a_quoted_dotted_key_sets_one_vary_entry():
    scene = with_settings(parse_scene(VARY),
                          ['uncertainty.vary."contact.restitution".high=0.7'])
    entry = scene.raw["uncertainty"]["vary"]["contact.restitution"]
    assert entry == {"distribution": "uniform", "low": 0.1, "high": 0.7}
    whole = with_settings(parse_scene(VARY), [
        'uncertainty.vary."excitation.amplitude_mm"='
        '{ distribution = "uniform", low = 1.0, high = 2.0 }'])
    assert set(whole.raw["uncertainty"]["vary"]) == {"contact.restitution",
                                                     "excitation.amplitude_mm"}
    assert whole == parse_scene(VARY + '"excitation.amplitude_mm" = { distribution = '
                                '"uniform", low = 1.0, high = 2.0 }\n')


def test_an_unclosed_quote_in_the_key_is_refused():
    with pytest.raises(SceneError, match="section.key=value"):
        with_settings(parse_scene(VARY), ['uncertainty.vary."contact.restitution=0.3'])
