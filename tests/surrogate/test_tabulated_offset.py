"""A surrogate tabulates the whole stroke at ``[field] ball_offset_mm``: a spherical shell
holds only the axis at the ends of its stroke, so a shell's table at a lateral offset is
refused in one line before any field solve (it solved three 3D positions, ~20 s on one
core, before meeting the end of the stroke; issue #41)."""
from __future__ import annotations

import pytest
from shell_model import SHELL

import plate_model as fx
from tengfield.errors import FieldError
from tengfield.scene import Scene
from tengfield.surrogate import precompute


def _refusing_solve(calls):
    def solve(scene, position, *, comm=None, **_):
        calls.append(float(position))
        raise AssertionError("no field solve may run for a table the cavity cannot hold")
    return solve


@pytest.mark.parametrize("offset_mm", [1.0, 0.01])
def test_a_shells_table_at_a_lateral_offset_is_refused_before_any_solve(offset_mm):
    scene = Scene.from_dict({"device": SHELL,
                             "field": {"method": "3d", "ball_offset_mm": offset_mm}})
    calls: list = []
    with pytest.raises(FieldError, match=rf"^offset_mm = {offset_mm:g} is out of range at "
                                         r"position_mm = 0: allowed \[0, 0\] mm .*a shell's "
                                         r"run needs 0 there") as info:
        precompute(scene, solve=_refusing_solve(calls), solve_comm=object())
    assert calls == []
    assert "\n" not in str(info.value)


def test_on_the_axis_and_in_a_tube_the_table_is_solved():
    """Offset 0 in the shell, and a tube at a lateral offset (it holds it at every
    height): nothing refused, every position solved."""
    for scene in (Scene.from_dict({"device": SHELL, "field": {"method": "3d"}}),
                  fx.scene_with().with_values(field={"ball_offset_mm": 0.2})):
        calls: list = []

        def solve(scene, position, *, comm=None, **kw):
            calls.append(float(position))
            return fx.plate_model_solve(scene, position, comm=comm, **kw)

        table = precompute(scene, solve=solve, solve_comm=object())
        assert calls and table.count >= 17
        assert 0.0 in calls
