"""A run refuses a bad field-only value before any dynamics work (#8 item 1)."""
import pytest

from tengfield import pipeline
from tengfield.errors import SceneError
from tengfield.scene import default_scene


def test_run_refuses_a_bad_field_value_before_the_dynamics():
    scene = default_scene().with_values(device={"stroke_mm": 0.01})   # too small to mesh
    assert scene.field_problems                                      # dynamics accept it

    def simulate(_):
        raise AssertionError("the dynamics ran before the field values were checked")

    with pytest.raises(SceneError, match="stroke_mm = 0.01"):
        pipeline.run(scene, simulate=simulate)


def test_uncharged_run_never_looks_at_field_values():
    scene = default_scene().with_values(device={"stroke_mm": 0.01, "surface_charge_uC_per_m2": 0.0},
                                        run={"duration_s": 0.2, "settle_periods": 1,
                                             "sample_rate_hz": 2000.0})
    result = pipeline.run(scene)
    assert result.stages["field"].status == "skipped"
