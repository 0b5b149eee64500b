"""record.png (issue #42, Figures): no empty secondary axis; the gap's band on a panel of
its own, every axis with data on it."""
import numpy as np

from tengfield.plotting.record import record_figure


def _envelope(read=False):
    t = np.linspace(0.0, 10.0, 2000)
    band = lambda a: (-a * np.ones_like(t), a * np.ones_like(t))    # noqa: E731
    env = {"time_s": t, "V_oc_V": band(100.0), "Q_sc_C": band(1e-9), "I_sc_A": band(1e-7),
           "gap_m": (np.zeros_like(t), 1.5e-3 * np.ones_like(t))}
    if read:
        env["V_read_V"] = band(50.0)
    return env


def test_every_axis_of_record_png_holds_data_and_none_is_a_twin():
    fig = record_figure(_envelope(read=True), parallel_capacitance_pF=47.0)
    axes = fig.get_axes()
    assert [ax.get_ylabel() for ax in axes] == ["V_OC (ideal) [V]", "V_read [V]", "Q_SC [nC]",
                                                "I_SC [nA]", "gap z [mm]"]
    boxes = [tuple(np.round(ax.get_position().bounds, 6)) for ax in axes]
    assert len(set(boxes)) == len(boxes)          # no twin axes sharing a panel
    for ax in axes:
        assert ax.collections, ax.get_ylabel()    # each holds its band
    gap = axes[-1]
    assert np.isclose(gap.get_ylim()[1], 1.5, rtol=0.2)
    v_read = axes[1]
    assert any("C_p = 47 pF" in t.get_text() for t in v_read.get_legend().get_texts())
