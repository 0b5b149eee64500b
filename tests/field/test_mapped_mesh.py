"""Across geometries (issue #40, ``[field] mesh_motion = "move"``): a geometry places its
reference meshes by mapping the mesh of its canonical geometry (its lengths on a
logarithmic grid, field/moving.py: ``canonical_length``, ``map_nodes``). The mapped
nodes land on the new interfaces exactly, a map that would spoil the mesh is refused
(meshed instead, and counted), a candidate's numbers do not depend on which candidates
were solved before it, and the tables of mapped geometries agree with remeshed ones
within each table's error estimate (tube and spherical shell)."""
import warnings

import numpy as np
import pytest
from helpers import assert_tables_agree_within_estimates

from tengfield.scene import default_scene

field = pytest.mark.field


def _tube(**device):
    return default_scene().with_values(device=device, field={"mesh_size_mm": 1.0,
                                                             "tolerance": 0.01})


def _shell(**device):
    from shell_model import SHELL

    from tengfield.scene import Scene
    return Scene.from_dict({"device": {**SHELL, **device},
                            "field": {"mesh_size_mm": 2.0, "tolerance": 0.02}})


def test_a_mapping_puts_the_tubes_interfaces_and_ball_exactly_on_their_new_places():
    """Pure numpy: points on the reference's electrodes, plates, bore, tube and ball land
    on the new geometry's; the far field does not move; the axis stays the axis."""
    from tengfield.field import geometry_axisymmetric as geometry
    from tengfield.field.moving import map_nodes

    old = geometry.layout(_tube(), 0.4e-3)
    new = geometry.layout(_tube(ball_diameter_mm=8.5, stroke_mm=4.2, tube_inner_radius_mm=4.8,
                                electrode_radius_mm=4.8, tube_outer_radius_mm=6.0), 0.5e-3)
    s = np.linspace(0.0, 1.0, 41)
    for z_old, z_new in ((old.z_lower, new.z_lower), (old.z_upper, new.z_upper),
                         (old.z_table, new.z_table),
                         (old.z_upper + old.plate_thickness, new.z_upper + new.plate_thickness)):
        y = map_nodes(np.column_stack([s * old.tube_outer_radius, np.full_like(s, z_old)]),
                      old, new)
        np.testing.assert_allclose(y[:, 1], z_new, rtol=0, atol=1e-15)
        corners = map_nodes(np.array([[r, z_old] for r in (
            old.electrode_radius, old.tube_inner_radius, old.tube_outer_radius)]), old, new)
        np.testing.assert_allclose(corners[:, 0], [new.electrode_radius, new.tube_inner_radius,
                                                   new.tube_outer_radius], rtol=1e-12)
    electrode = map_nodes(np.column_stack([s * old.electrode_radius,
                                           np.full_like(s, old.z_lower)]), old, new)
    np.testing.assert_allclose(electrode[-1], [new.electrode_radius, new.z_lower], atol=1e-15)
    for r_old, r_new in ((old.tube_inner_radius, new.tube_inner_radius),
                         (old.tube_outer_radius, new.tube_outer_radius)):
        z = old.z_lower + s * old.plate_spacing
        y = map_nodes(np.column_stack([np.full_like(z, r_old), z]), old, new)
        np.testing.assert_allclose(y[:, 0], r_new, rtol=0, atol=1e-15)
        np.testing.assert_allclose(y[:, 1], new.z_lower + s * new.plate_spacing, atol=1e-15)
    angle = np.linspace(0.0, np.pi, 37)
    for fraction in (1.0, 0.5, 0.0):   # the ball's surface, inside, its centre: rigid
        ball = np.column_stack([fraction * old.ball_radius * np.sin(angle),
                                old.ball_centre_z + fraction * old.ball_radius * np.cos(angle)])
        y = map_nodes(ball, old, new)
        np.testing.assert_allclose(np.hypot(y[:, 0], y[:, 1] - new.ball_centre_z),
                                   fraction * new.ball_radius, rtol=1e-12, atol=1e-15)
    axis = map_nodes(np.column_stack([np.zeros(9), np.linspace(-9e-3, 9e-3, 9)]), old, new)
    assert np.all(axis[:, 0] == 0.0)
    theta = np.linspace(0.0, np.pi, 25)   # the far boundary and its Kelvin image: scaled
    ratio = new.domain_radius / old.domain_radius
    for centre_old, centre_new in ((0.0, 0.0), (old.shift, new.shift)):
        far = np.column_stack([old.domain_radius * np.sin(theta),
                               centre_old + old.domain_radius * np.cos(theta)])
        y = map_nodes(far, old, new)
        np.testing.assert_allclose(y[:, 0], ratio * far[:, 0], rtol=1e-12)
        np.testing.assert_allclose(y[:, 1] - centre_new, ratio * (far[:, 1] - centre_old),
                                   rtol=1e-12, atol=1e-15)


def test_a_mapping_puts_the_shells_cavity_band_and_ball_on_their_new_places():
    from tengfield.field.cells import cell_of
    from tengfield.field.moving import map_nodes

    def layout(scene, z):
        return cell_of(scene).axisymmetric_layout(z, mesh_size=2e-3)

    old = layout(_shell(), 1e-3)
    new = layout(_shell(cavity_diameter_mm=24.0, electrode_band_mm=3.0, ball_diameter_mm=9.0,
                        shell_thickness_mm=2.5), 2e-3)
    for radius_old, radius_new in ((old.cavity_radius, new.cavity_radius),
                                   (old.outer_radius, new.outer_radius)):
        phi = np.linspace(-np.pi / 2, np.pi / 2, 61)
        y = map_nodes(np.column_stack([radius_old * np.cos(phi), radius_old * np.sin(phi)]),
                      old, new)
        np.testing.assert_allclose(np.hypot(y[:, 0], y[:, 1]), radius_new, rtol=1e-12)
    edge = np.arcsin(0.5 * old.band / old.cavity_radius)
    rim = map_nodes(np.array([[old.cavity_radius * np.cos(edge),
                               old.cavity_radius * np.sin(edge)]]), old, new)
    np.testing.assert_allclose(rim[0, 1], 0.5 * new.band, rtol=1e-12)
    angle = np.linspace(0.0, np.pi, 37)
    ball = np.column_stack([old.ball_radius * np.sin(angle),
                            old.ball_centre_z + old.ball_radius * np.cos(angle)])
    y = map_nodes(ball, old, new)
    np.testing.assert_allclose(np.hypot(y[:, 0], y[:, 1] - new.ball_centre_z), new.ball_radius,
                               rtol=1e-12)


def test_the_canonical_grid_is_within_five_percent_and_a_function_of_the_value_alone():
    """Random lengths from 10 µm to 1 m: the canonical length is a power of the grid's
    ratio in mm, within sqrt(ratio) of the value, the same for any value of its cell,
    and the tube's and the shell's canonical geometries keep their shapes' rules."""
    from tengfield.field.axisymmetric import canonical_device
    from tengfield.field.cells.spherical_shell import SphericalShell
    from tengfield.field.moving import CANONICAL_RATIO, canonical_length

    rng = np.random.default_rng(40)
    for value in 10.0 ** rng.uniform(-5.0, 0.0, 400):
        c = canonical_length(value)
        k = np.log(c * 1e3) / np.log(CANONICAL_RATIO)
        assert abs(k - round(k)) < 1e-4   # 6 significant digits
        assert 1.0 / np.sqrt(CANONICAL_RATIO) - 1e-6 <= c / value <= np.sqrt(CANONICAL_RATIO) + 1e-6
        assert canonical_length(c) == c
        assert canonical_length(-value) == -c
    assert canonical_length(0.0) == 0.0
    device = default_scene().device
    a = canonical_device(device)
    b = canonical_device(_tube(ball_diameter_mm=7.05, tube_inner_radius_mm=4.02,
                               electrode_radius_mm=4.02, tube_outer_radius_mm=5.52).device)
    assert a == b                                  # one cell: one canonical geometry
    assert a.electrode_radius == a.tube_inner_radius   # the inset 0 stays 0
    assert a.tube_inner_radius > a.ball_radius
    shell = SphericalShell(cavity_diameter=20e-3, shell_thickness=2e-3, electrode_band=2e-3,
                           ball_diameter=17e-3, domain_radius=0.1).canonical()
    assert shell.domain_radius is None
    assert abs(shell.stroke / 3e-3 - 1.0) < 0.05   # the stroke is snapped, not the ball


@field
@pytest.mark.slow
def test_a_candidates_numbers_do_not_depend_on_the_candidates_solved_before_it():
    """Three tubes, two of them in one canonical cell (they share its template): solved
    in either order, in one process, every number is the same to the bit; the shared
    template is meshed once."""
    from mpi4py import MPI

    from tengfield.field import moving, solve_position

    scenes = {"a": _tube(), "b": _tube(ball_diameter_mm=7.6, stroke_mm=3.4,
                                       tube_inner_radius_mm=4.3, electrode_radius_mm=4.3,
                                       tube_outer_radius_mm=5.8),
              "c": _tube(ball_diameter_mm=7.5, stroke_mm=3.35, tube_inner_radius_mm=4.25,
                         electrode_radius_mm=4.25, tube_outer_radius_mm=5.75)}

    def run(order):
        moving.clear()
        numbers = {}
        for name in order:
            scene = scenes[name].with_values(field={"mesh_motion": "move"})
            results = [solve_position(scene, z, comm=MPI.COMM_SELF, estimate_error=False)
                       for z in (0.4e-3, 1.5e-3)]
            moving.release_references()
            numbers[name] = [(r.capacitance.tolist(), r.induced_fraction.tolist())
                             for r in results]
        return numbers, dict(moving.COUNTS)

    forward, counts = run("abc")
    backward, _ = run("cba")
    moving.clear()
    assert forward == backward
    assert counts["mapped"] == 6 and counts["map_refused"] == 0
    assert counts["meshed"] == 4    # the templates: a's cell and b's = c's, 2 rungs each
    assert forward["b"] != forward["c"]


@field
@pytest.mark.slow
def test_a_map_that_would_spoil_the_mesh_is_refused_meshed_and_counted(monkeypatch):
    """A quality bound no map can meet: the reference is meshed by gmsh for the
    candidate itself (after its canonical template), and ``map_refused`` says so; with
    the bound as shipped the same candidate is mapped, and a second candidate of the
    same canonical cell meshes nothing."""
    from mpi4py import MPI

    from tengfield.field import moving, solve_position

    settings = dict(comm=MPI.COMM_SELF, estimate_error=False)

    def move(scene):
        return scene.with_values(field={"mesh_motion": "move"})
    moving.clear()
    monkeypatch.setattr(moving, "MAP_QUALITY_BOUND", 1.0 + 1e-9)
    refused = solve_position(move(_tube(ball_diameter_mm=7.4)), 1.5e-3, **settings)
    assert refused.info["mesh_placements"] == {"moved": 0, "meshed": 2, "mapped": 0}
    assert moving.COUNTS["map_refused"] == 1
    monkeypatch.undo()
    moving.clear()
    first = solve_position(move(_tube(ball_diameter_mm=7.4)), 1.5e-3, **settings)
    moving.release_references()          # the table is done: its template is kept
    assert first.info["mesh_placements"] == {"moved": 0, "meshed": 1, "mapped": 1}
    near = solve_position(move(_tube(ball_diameter_mm=7.41)), 1.5e-3, **settings)
    assert near.info["mesh_placements"] == {"moved": 0, "meshed": 0, "mapped": 1}
    assert moving.COUNTS == {"moved": 0, "meshed": 1, "mapped": 2, "map_refused": 0}
    np.testing.assert_allclose(near.capacitance, refused.capacitance, rtol=2e-2)
    moving.clear()


@field
@pytest.mark.slow
def test_mapped_tube_tables_agree_with_remeshed_ones_within_their_error_estimates():
    """Stroke and ball diameter (the design's keys) changed: the second geometry's table
    comes from its canonical geometry's meshes mapped, and agrees with its own remeshed
    table."""
    from tengfield import surrogate
    from tengfield.field import moving

    moving.clear()
    first = _tube().with_values(field={"mesh_motion": "move"})
    second = _tube(ball_diameter_mm=7.6, stroke_mm=3.4, tube_inner_radius_mm=4.3,
                   electrode_radius_mm=4.3, tube_outer_radius_mm=5.8)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        surrogate.precompute(first)
        meshed_before, mapped_before = moving.COUNTS["meshed"], moving.COUNTS["mapped"]
        mapped = surrogate.precompute(second.with_values(field={"mesh_motion": "move"}))
        remeshed = surrogate.precompute(second)
    assert moving.COUNTS["mapped"] - mapped_before >= 4
    assert mapped.provenance["mesh_placements"]["mapped"] == (moving.COUNTS["mapped"]
                                                              - mapped_before)
    assert moving.COUNTS["meshed"] - meshed_before <= mapped.provenance["mesh_placements"][
        "meshed"]
    assert_tables_agree_within_estimates(mapped, remeshed)
    moving.clear()


@field
@pytest.mark.slow
def test_mapped_shell_tables_agree_with_remeshed_ones_within_their_error_estimates():
    from tengfield import surrogate
    from tengfield.field import moving

    moving.clear()
    second = _shell(cavity_diameter_mm=22.0, ball_diameter_mm=8.8)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        surrogate.precompute(_shell().with_values(field={"mesh_motion": "move"}))
        mapped = surrogate.precompute(second.with_values(field={"mesh_motion": "move"}))
        remeshed = surrogate.precompute(second)
    assert mapped.provenance["mesh_placements"]["mapped"] >= 4
    assert_tables_agree_within_estimates(mapped, remeshed)
    moving.clear()


def test_the_solvers_kept_alive_fit_in_petscs_options_database():
    """PETSc's options database holds at most 512 entries and every live solver keeps
    its own (a design of 200 candidates failed with "Number of options 512" when every
    canonical template kept its solver, tried and reverted): the axisymmetric and the
    3D references' kept solvers take at most half of it."""
    from petsc4py import PETSc

    from tengfield.field import _dolfinx, moving, moving3d

    def options_per_solver(kind):
        A = PETSc.Mat().createAIJ([2, 2], nnz=1, comm=PETSc.COMM_SELF)
        for i in range(2):
            A.setValue(i, i, 1.0)
        A.assemble()
        prefix = _dolfinx.unique_prefix("options_count")
        ksp = _dolfinx.create_ksp(PETSc.COMM_SELF, A, prefix=prefix, kind=kind, symmetric=True)
        count = sum(key.startswith(prefix) for key in PETSc.Options().getAll())
        ksp.destroy()
        A.destroy()
        _dolfinx.clear_options(prefix)
        return count

    direct, amg = options_per_solver("direct"), options_per_solver("cg-amg")
    assert direct >= 3 and amg >= 3
    kept = moving.MAX_REFERENCES * moving.MAX_KEYS * direct + moving3d.MAX_REFERENCES * amg
    assert kept <= 256, kept
