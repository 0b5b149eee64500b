"""vq.png (issue #42, Figures): the run's V-Q loop, far smaller than the CMEO triangle,
gets a panel of its own zoomed on it (both panels labelled)."""
import numpy as np

from tengfield.plotting.harvest import vq_figure


def _loops():
    phase = np.linspace(0.0, 2 * np.pi, 200)
    q = 0.5e-9 * (1 - np.cos(phase))          # 0 .. 1 nC
    v = 8.0 * np.sin(phase)                   # ±8 V
    return {"rectifier": (q, v, 1.2e-8)}


ENERGY = {"max_energy_per_cycle_J": 2.5e-4, "Q_sc_max_C": 100e-9, "V_oc_max_V": 5000.0,
          "V_return_max_V": 4000.0}


def test_the_loop_has_its_own_zoomed_panel_beside_the_cmeo_bound():
    fig = vq_figure(_loops(), ENERGY, title="a run")
    assert len(fig.axes) == 2
    whole, zoom = fig.axes
    for ax in (whole, zoom):
        assert ax.get_xlabel() == "charge through the circuit Q [nC]"
        assert ax.get_ylabel() == "terminal voltage V [V]"
        assert ax.get_title()
    assert "CMEO" in " ".join(t.get_text() for t in whole.get_legend().get_texts())
    # the zoomed panel: the loop fills most of it (its limits are the loop's, not the triangle's)
    (x0, x1), (y0, y1) = zoom.get_xlim(), zoom.get_ylim()
    assert (1.0 - 0.0) / (x1 - x0) > 0.6 and (16.0) / (y1 - y0) > 0.6
    loop = zoom.get_lines()[0]
    assert np.allclose(loop.get_xdata(), _loops()["rectifier"][0] * 1e9)


def test_without_a_cmeo_bound_one_panel_suffices():
    fig = vq_figure(_loops(), {}, title="a run")
    assert len(fig.axes) == 1
