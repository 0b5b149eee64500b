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
