"""breakdown.png (issue #53, Figures): ``plot()`` is the file's three panels; the band's
panel draws each edge once against the ball position (no two-branch loops), with V_b at
the edge's own γ, so that lower and upper reach 1 where they bind; a size a page holds."""
import numpy as np
from PIL import Image

from helpers import assert_labelled
import tengfield as tf
from tengfield.scene import default_scene

SMALL = {"field": {"degree": 1, "mesh_size_mm": 1.5, "tolerance": 0.5},
         "run": {"duration_s": 0.3, "settle_periods": 2, "sample_rate_hz": 5000}}


def test_breakdown_plot_is_the_files_figure_and_its_edges_touch_one(tmp_path):
    study = tf.breakdown(default_scene().with_values(**SMALL), cache_dir=tmp_path / "cache")
    fig = study.plot()
    drawn = [ax for ax in fig.axes if ax.get_lines()]
    assert len(drawn) == 3                        # as breakdown.png: not 2 panels
    assert_labelled(fig)
    (band_ax,) = [ax for ax in drawn if ax.get_xlabel().startswith("ball position z along")]
    band = study.band
    curves = {line.get_label().split(":")[0]: line for line in band_ax.get_lines()
              if ":" in line.get_label()}
    assert set(curves) == {"lower", "estimate", "upper"}
    for edge, line in curves.items():
        z = np.asarray(line.get_xdata())
        assert np.all(np.diff(z) > 0), f"{edge}: a curve drawn twice over z (two branches)"
    lower, upper = (np.asarray(curves[e].get_ydata()) for e in ("lower", "upper"))
    z = np.asarray(curves["lower"].get_xdata()) * 1e-3
    # lower binds where its ratio peaks at 1, upper at the widest gap where it is 1
    assert np.max(lower) == np.float64(lower[np.argmin(abs(z - band.lower_position))])
    assert abs(np.max(lower) - 1.0) < 1e-6
    assert abs(upper[np.argmin(abs(z - band.upper_position))] - 1.0) < 1e-6
    assert np.max(np.asarray(curves["estimate"].get_ydata())) >= 1.0 - 1e-9
    # the legend's dotted/dashed lines are the curves' styles, drawn on one branch each
    styles = {t.get_text().split(":")[0]: h.get_linestyle() for t, h in
              zip(band_ax.get_legend().get_texts(), band_ax.get_legend().legend_handles)}
    assert styles == {e: line.get_linestyle() for e, line in curves.items()}
    paths = study.write(tmp_path / "out")
    png = next(p for p in paths if p.name == "breakdown.png")
    with Image.open(png) as image:
        width, height = image.size
    assert width <= 1600 and height <= 1200, (width, height)
