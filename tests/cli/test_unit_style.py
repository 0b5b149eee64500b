"""One unit style on the terminal, the quantity table's (issue #42 item 6): µ for micro
(µW, µC/m^2, µF, µA), powers with ^ (W/m^3, µW/cm^3); never "uW", "uC/m^2" nor "³"."""
from __future__ import annotations

import re

import pytest

from tengfield import quantities
from tengfield.design_study.answer import readable_unit

ASCII_MICRO = re.compile(r"(?<![A-Za-z_])u(W|C|F|A|V|m)\b")
SUPERSCRIPT = re.compile("[²³]")


def test_the_table_style_is_micro_sign_and_caret():
    units = {q.display_unit for q in quantities.QUANTITIES.values()}
    assert "µW" in units and "W/m^3" in units
    assert not [u for u in units if ASCII_MICRO.search(u) or SUPERSCRIPT.search(u)]


@pytest.mark.parametrize("magnitude", [1e-4, 1.0, 1e3, 1e6])
def test_design_power_density_units(magnitude):
    label, _ = readable_unit("W/m^3", magnitude)
    assert label.endswith("/cm^3") and not SUPERSCRIPT.search(label)


@pytest.mark.slow
def test_run_prints_the_table_style(tmp_path, capsys):
    from tengfield.cli import main

    assert main(["run", "--set", "circuit.kind=load", "--set", "run.duration_s=0.8",
                 "--set", "circuit.storage_capacitance_uF=1", "--no-plots",
                 "-o", str(tmp_path / "r")]) == 0
    out = capsys.readouterr().out
    assert "µW" in out and "W/m^3" in out
    assert not ASCII_MICRO.search(out), ASCII_MICRO.findall(out)
    assert not SUPERSCRIPT.search(out)
