"""A run's own figures (issue #53), end to end on a small scene with a load and an
instrument: waveforms (title with R and C_p, the terminal's units, no offsets, legends off
the data) and the trajectory (restitution spelled out), as ``tengfield run`` draws them."""
import pytest

from helpers import assert_labelled, assert_units_as_terminal
import tengfield as tf
from tengfield.commands.run import terminal_lines
from tengfield.scene import default_scene

SMALL = {"field": {"degree": 1, "mesh_size_mm": 1.5, "tolerance": 0.5},
         "run": {"duration_s": 0.3, "settle_periods": 2, "sample_rate_hz": 5000},
         "circuit": {"kind": "load", "load_ohm": 1e7}, "instrument": {"capacitance_pF": 338}}


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    return tf.run(default_scene().with_values(**SMALL),
                  cache_dir=tmp_path_factory.mktemp("cache"))


def test_waveforms_name_r_and_c_p_in_the_terminals_units(run):
    fig = run.plot()
    title = fig._suptitle.get_text().replace("\n", " ")
    assert "R = 10 MΩ" in title and "C_p = 338 pF" in title
    assert_labelled(fig)
    assert_units_as_terminal(fig, terminal_lines(run.summary))


def test_the_trajectory_spells_the_restitution(run):
    from tengfield.plotting.dynamics import motion_words, trajectory_figure

    data = trajectory_figure(run.dynamics, title=motion_words(run.scene))
    assert "restitution 0.1" in data.title and "e = " not in data.title
    fig = run.dynamics.plot()
    assert_labelled(fig)
