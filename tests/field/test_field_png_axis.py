"""field.png's vertical axis and its title use the same z (issue #29): the axis reads
the height above the lower electrode's face, so the ball's bottom sits at the gap z
the title names (the mesh's origin is the midplane, the axis used to read from it)."""
from __future__ import annotations

import pytest

from tengfield.field.geometry_axisymmetric import layout
from tengfield.field.plot import height_origin
from tengfield.scene import default_scene


@pytest.mark.parametrize("position_mm", [0.5, 1.5, 2.9])
@pytest.mark.parametrize("stroke_mm", [3.0, 5.0])
def test_ball_bottom_reads_the_gap_on_the_axis(position_mm, stroke_mm):
    scene = default_scene().with_values(device={"stroke_mm": stroke_mm})
    lay = layout(scene, position_mm * 1e-3)
    bottom = lay.ball_centre_z - lay.ball_radius - height_origin(lay)
    assert bottom == pytest.approx(position_mm * 1e-3, abs=1e-12)
    # the upper electrode's face is at the stroke + the ball's diameter (the spacing h)
    assert lay.z_upper - height_origin(lay) == pytest.approx(scene.device.plate_spacing)
