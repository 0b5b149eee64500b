"""``[uncertainty.vary] "device.surface_charge_uC_per_m2" = { distribution =
"breakdown-band" }`` (issue #38): σ log-uniform between the edges of each geometry's
breakdown band."""
import math

import pytest
from band_scene import band_scene

from tengfield.errors import SceneError
from tengfield.pipeline import run
from tengfield.scene import load_scene
from tengfield.uncertainty_study import run_study
from tengfield.uncertainty_study.spec import uncertainty_spec

STUDY = """[uncertainty]
samples = 20
method = "monte-carlo"
seed = 3
[uncertainty.vary]
{vary}
"""
BAND = '"device.surface_charge_uC_per_m2" = { distribution = "breakdown-band" }'


def scene_file(tmp_path, sigma="-8", vary=BAND):
    path = tmp_path / "scene.toml"
    path.write_text(band_scene(sigma, STUDY.format(vary=vary)))
    return load_scene(path)


def test_band_draws_are_for_sigma_only_and_take_no_parameters(tmp_path):
    spec = uncertainty_spec(scene_file(tmp_path))
    assert spec.inputs[0].kind == "breakdown-band"
    with pytest.raises(SceneError, match="is for 'device.surface_charge_uC_per_m2' only"):
        uncertainty_spec(scene_file(tmp_path, vary='"contact.restitution" = { distribution = '
                                                   '"breakdown-band" }'))
    with pytest.raises(SceneError, match="unknown parameter 'low'") as err:
        uncertainty_spec(scene_file(tmp_path, vary=BAND.replace("}", ", low = 1 }")))
    assert str(err.value).endswith("; it takes no parameters (each geometry's band gives the "
                                   "range)"), str(err.value)


@pytest.mark.slow
@pytest.mark.field
@pytest.mark.filterwarnings("ignore::RuntimeWarning")   # the coarse mesh's field error
def test_sigma_is_drawn_log_uniformly_in_the_band(tmp_path):
    scene = scene_file(tmp_path)
    study = run_study(scene, cache_dir=tmp_path / "cache", jobs=1)
    at_limit = run(scene_file(tmp_path, sigma='"breakdown"'), cache_dir=tmp_path / "cache")
    edges = at_limit.summary["breakdown_band"]["peak_to_peak.Q_sc_C"]
    places = study.values[:, 0]
    assert 0.0 < places.min() < 0.3 and 0.7 < places.max() < 1.0
    for u, row in zip(places, study.evaluations.rows):
        expected = edges["lower"] * (edges["upper"] / edges["lower"]) ** u
        assert row["peak_to_peak.Q_sc_C"] == pytest.approx(expected, rel=1e-9)
    assert study.evaluations.beyond_breakdown is None   # the band is the point of the draws
    assert math.isfinite(study.summary["outputs"]["peak_to_peak.Q_sc_C"]["mean"])
