"""waveforms.png (issue #42, Figures): the gap has its own panel, titles carry the device's
numbers, the V_read label fits its panel."""
import numpy as np

from tengfield.plotting.waveforms import waveforms_figure


def _waveforms(read=False):
    t = np.linspace(0.0, 0.1, 400)
    gap = 1.5e-3 * 0.5 * (1 - np.cos(2 * np.pi * 20 * t))
    w = {"time_s": t, "gap_m": gap, "V_oc_V": 100.0 * gap / 1.5e-3,
         "Q_sc_C": 1e-9 * gap / 1.5e-3, "I_sc_A": np.gradient(1e-9 * gap / 1.5e-3, t)}
    if read:
        w["V_read_V"] = 0.5 * w["V_oc_V"]
    return w


def test_gap_is_drawn_on_its_own_panel_not_over_the_terminal_curves():
    w = _waveforms()
    fig = waveforms_figure(w)
    axes = fig.get_axes()
    gap_axes = [ax for ax in axes if ax.get_ylabel() == "gap z [mm]"]
    assert len(gap_axes) == 1                     # one gap panel, no twin on every panel
    assert len(axes) == 4                         # V_OC, Q_SC, I_SC, gap: no twins
    (line,) = gap_axes[0].get_lines()
    assert np.allclose(line.get_ydata(), w["gap_m"] * 1e3)
    terminal = [ax for ax in axes if ax is not gap_axes[0]]
    for ax in terminal:                           # no grey gap line on a terminal panel
        for ln in ax.get_lines():
            assert not np.allclose(ln.get_ydata(), w["gap_m"] * 1e3)
    # panels do not overlap: the gap panel lies below the others
    gap_box = gap_axes[0].get_position()
    for ax in terminal:
        assert ax.get_position().y0 >= gap_box.y1 - 1e-9


def test_v_read_label_is_short_and_fits_its_panel_the_instrument_in_the_legend():
    w = _waveforms(read=True)
    fig = waveforms_figure(w, parallel_capacitance_pF=338.0)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    (ax,) = [ax for ax in fig.get_axes() if ax.get_ylabel().startswith("V_read")]
    assert ax.get_ylabel() == "V_read [V]"
    legend = ax.get_legend()
    assert legend is not None
    assert any("C_p = 338 pF" in t.get_text() for t in legend.get_texts())
    for each in fig.get_axes():                   # every y label within its panel's height
        label_box = each.yaxis.label.get_window_extent(renderer)
        assert label_box.height <= each.get_window_extent(renderer).height + 1e-6, each.get_ylabel()
