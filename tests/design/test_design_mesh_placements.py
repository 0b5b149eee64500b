"""design.json's ``cost_per_candidate_s.mesh_placements`` (issue #40): the moves, gmsh
meshings and maps of the candidates whose field this run computed, summed; candidates
whose table came from the cache or the memo add nothing."""
from types import SimpleNamespace

from tengfield.design_study.output import cost_split


def _row(status, placements):
    return {"status": "ok", "field_status": status, "mesh_placements": placements,
            "wall_s": {"field": 1.0, "dynamics": 0.0, "circuit": 0.0}}


def test_the_mesh_placements_of_computed_candidates_are_summed():
    rows = [_row("computed", {"moved": 11, "meshed": 7, "mapped": 0}),
            _row("computed", {"moved": 10, "meshed": 1, "mapped": 6}),
            _row("cached", {}), _row("memo", {}),
            {**_row("computed", {"moved": 3, "meshed": 3, "mapped": 3}), "status": "skipped"}]
    split = cost_split(SimpleNamespace(rows=rows, spec=SimpleNamespace(percentile=None)))
    assert split["mesh_placements"] == {"moved": 21, "meshed": 8, "mapped": 6}
    assert split["new_geometries"] == 2 and split["candidates"] == 4


def test_the_coarse_design_field_moves_and_maps_and_the_scene_field_is_kept():
    """``[design] field = "coarse"`` (the default) solves its candidates with meshes moved
    with the ball and mapped from their canonical geometries; ``field = "scene"`` keeps
    the scene's ``[field] mesh_motion``."""
    from tengfield.design_study import candidate_scene, design_field_settings
    from tengfield.design_study.spec import DesignSpec
    from tengfield.scene import default_scene

    assert design_field_settings(7.0)["mesh_motion"] == "move"
    base = default_scene()
    values = {"stroke_mm": 2.5, "ball_diameter_mm": 7.2}
    coarse = candidate_scene(base, DesignSpec(field="coarse"), values)
    assert coarse.field.mesh_motion == "move" and coarse.field.degree == 2
    kept = candidate_scene(base, DesignSpec(field="scene"), values)
    assert kept.field.mesh_motion == base.field.mesh_motion == "remesh"
