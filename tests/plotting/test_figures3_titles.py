"""Run titles and terminal lines (issue #42, Figures): the device's numbers in the title, the
cell count only when there is more than one cell."""
from types import SimpleNamespace

from tengfield.commands.run import terminal_lines
from tengfield.plotting.waveforms import cells_phrase, run_title


def _result(cells):
    scene = SimpleNamespace(
        excitation=SimpleNamespace(frequency=20.0, amplitude=0.5e-3),
        device=SimpleNamespace(surface_charge=-8e-6, stroke=1.5e-3, cells=cells,
                               electrode_names=("lower", "upper")),
        circuit=SimpleNamespace(reference="floating"))
    return SimpleNamespace(scene=scene, summary={"cells": cells})


def test_run_title_names_the_device_and_counts_cells_only_above_one():
    one = run_title(_result(1))
    assert one.startswith("σ = −8 µC/m², Δh = 1.5 mm, 20 Hz")
    assert "cell" not in one
    assert "4 cells" in run_title(_result(4))
    assert "cell(s)" not in run_title(_result(4))


def test_cells_phrase():
    assert cells_phrase(1) == ""
    assert cells_phrase(4) == "4 cells"


def _summary(cells):
    return {"reference": "floating", "cells": cells,
            "peak": {"V_oc_V": 10.0}, "peak_to_peak": {"V_oc_V": 20.0}}


def test_terminal_lines_write_the_cell_count_only_above_one():
    one = terminal_lines(_summary(1))
    assert any(line.startswith("peak-to-peak (floating reference): ") for line in one)
    assert not any("cell" in line for line in one)
    four = terminal_lines(_summary(4))
    assert any(line.startswith("peak-to-peak (floating reference, 4 cells): ") for line in four)
