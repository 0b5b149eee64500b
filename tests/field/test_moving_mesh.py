"""One mesh per geometry moved with the ball (issue #40, ``[field] mesh_motion = "move"``):
the blending map moves the ball rigidly and nothing else that is fixed, a move that
would spoil the mesh is meshed instead, and the moved tables of the tube and the
spherical shell (axisymmetric) agree with the remeshed ones within each table's error
estimate at every position."""
import warnings

import numpy as np
import pytest
from helpers import assert_tables_agree_within_estimates

from tengfield.scene import default_scene

field = pytest.mark.field


def test_mesh_motion_enters_the_field_hash_only_when_moving():
    scene = default_scene()
    assert scene.with_values(field={"mesh_motion": "remesh"}).field_hash() == scene.field_hash()
    assert scene.with_values(field={"mesh_motion": "move"}).field_hash() != scene.field_hash()


def test_the_blending_weight_moves_the_ball_rigidly_and_holds_the_walls():
    from tengfield.field import geometry_axisymmetric as geometry
    from tengfield.field.moving import blending_weight

    lay = geometry.layout(default_scene(), 1.5e-3)
    rng = np.random.default_rng(3)
    angle = rng.uniform(0, np.pi, 50)
    radius = lay.ball_radius * np.sqrt(rng.uniform(0, 1, 50))
    ball = np.column_stack([radius * np.sin(angle), lay.ball_centre_z + radius * np.cos(angle)])
    assert np.allclose(blending_weight(ball, lay), 1.0)
    r = np.linspace(0.0, lay.electrode_radius, 20)
    for z in (lay.z_lower, lay.z_upper):   # the electrodes and the plates beyond
        assert np.all(blending_weight(np.column_stack([r, np.full_like(r, z)]), lay) == 0.0)
    bore = np.column_stack([np.full(20, lay.tube_inner_radius),
                            np.linspace(lay.z_lower, lay.z_upper, 20)])
    assert np.all(blending_weight(bore, lay) == 0.0)
    far = np.column_stack([np.full(5, 3 * lay.tube_outer_radius), np.linspace(-1e-2, 1e-2, 5)])
    assert np.all(blending_weight(far, lay) == 0.0)
    # between: 0 < w < 1, falling away from the ball
    gap = np.column_stack([np.zeros(5), np.linspace(lay.z_lower, lay.ball_centre_z
                                                    - lay.ball_radius, 7)[1:-1]])
    w = blending_weight(gap, lay)
    assert np.all((w > 0) & (w < 1)) and np.all(np.diff(w) > 0)


@field
def test_a_move_that_would_invert_or_crush_cells_is_refused():
    from mpi4py import MPI

    from tengfield.field import _dolfinx as dx_api
    from tengfield.field import moving
    from tengfield.field.axisymmetric import discretised, permittivities
    from tengfield.field import geometry_axisymmetric as geometry

    scene = default_scene().with_values(field={"mesh_size_mm": 1.0})
    lay = geometry.layout(scene, 1.5e-3)
    _, disc = discretised(dx_api, scene, 1.5e-3, MPI.COMM_SELF,
                          permittivities(scene.device, lay), moving=False)
    ref = moving._new_reference(dx_api, lay, disc)
    assert moving.quality_ok(ref, 0.0) and moving.quality_ok(ref, -0.3e-3)
    assert not moving.quality_ok(ref, -1.45e-3)   # the gap of 1.5 mm crushed to 0.05 mm
    assert not moving.quality_ok(ref, -1.6e-3)    # through the electrode: inverted


def _tube():
    return default_scene().with_values(field={"mesh_size_mm": 0.8})


def _shell():
    from shell_model import SHELL

    from tengfield.scene import Scene
    return Scene.from_dict({"device": SHELL, "field": {"mesh_size_mm": 2.0, "tolerance": 0.01}})


@field
@pytest.mark.slow
@pytest.mark.parametrize("make_scene", [_tube, _shell], ids=["tube", "spherical-shell"])
def test_the_moved_table_agrees_with_the_remeshed_one_within_its_error_estimate(make_scene):
    from tengfield import surrogate
    from tengfield.field import moving

    from tengfield.field import _dolfinx as dx_api

    scene = make_scene()
    moving.clear()
    set_up = []
    original = dx_api.create_ksp

    def create_ksp(*args, **kwargs):
        set_up.append(kwargs["prefix"])
        return original(*args, **kwargs)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        remeshed = surrogate.precompute(scene)
        dx_api.create_ksp = create_ksp
        try:
            moved = surrogate.precompute(scene.with_values(field={"mesh_motion": "move"}))
        finally:
            dx_api.create_ksp = original
    assert moving.COUNTS["moved"] >= 5 and moving.COUNTS["meshed"] >= 1
    # the solver is set up once per mesh (its own options prefix), refactored on a move
    assert len(set_up) == len(set(set_up)) == moving.COUNTS["meshed"]
    moving.clear()
    assert not any(key.startswith(tuple(set_up)) for key in dx_api.PETSc.Options().getAll())
    assert_tables_agree_within_estimates(moved, remeshed)


@field
def test_moved_numbers_do_not_depend_on_the_order_of_the_solves():
    """The reference of a position is a function of the position alone (a ladder of
    gaps), so a table's numbers are the same whatever order its solves ran in (and
    however they were spread over the ranks)."""
    from mpi4py import MPI

    from tengfield.field import moving, solve_position

    scene = default_scene().with_values(field={"mesh_size_mm": 1.0, "mesh_motion": "move"})
    positions = [0.3e-3, 1.2e-3, 0.6e-3, 2.1e-3]

    def solved(order):
        moving.clear()
        out = {z: solve_position(scene, z, comm=MPI.COMM_SELF, estimate_error=False)
               for z in order}
        return [out[z] for z in positions]
    forward, backward = solved(positions), solved(positions[::-1])
    assert moving.COUNTS["moved"] >= 2
    for a, b in zip(forward, backward):
        assert np.array_equal(a.capacitance, b.capacitance)
        assert np.array_equal(a.induced_charge, b.induced_charge)
    moving.clear()
