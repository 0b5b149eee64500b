"""One home per shape (issue #41): each shape is one module of scene/shapes/ (pure
geometry) plus its field models in field/cells/, both registries looked up through
``_registry.lookup``, ``[field] method`` resolved through the method table and the
shape's own ``field_methods``; no ``isinstance`` over shapes anywhere."""
import ast
import math
from pathlib import Path

import pytest

from tengfield.errors import SceneError
from tengfield.field import resolve_method
from tengfield.field.cells import CELLS, cell_of
from tengfield.field.cells._methods import solve_with
from tengfield.field.cells.contact_surfaces import contact_surfaces
from tengfield.field.cells.plate_model3d import cylindrical_cell
from tengfield.scene import Scene
from tengfield.scene.shapes import SHAPES, field_method, shape_of
from tengfield.scene.shapes.methods import FIELD_METHODS

SRC = Path(__file__).resolve().parents[2] / "src" / "tengfield"

SHELL = {"shape": "spherical-shell", "cavity_diameter_mm": 20.0, "shell_thickness_mm": 2.0,
         "electrode_band_mm": 2.0, "ball_diameter_mm": 8.0, "wall_permittivity": 3.0}
HEXAGONAL = {"shape": "hexagonal", "ball_diameter_mm": 5.0, "stroke_mm": 2.0,
             "tube_inner_radius_mm": 3.0, "tube_outer_radius_mm": 4.0,
             "plate_thickness_mm": 2.0, "wall_permittivity": 3.0}
SCENES = {"tube": {}, "spherical-shell": {"device": SHELL},
          "hexagonal": {"device": HEXAGONAL, "field": {"method": "3d"}}}


def test_the_two_registries_hold_the_same_shapes_and_methods():
    assert set(SHAPES) == set(CELLS) == set(SCENES)
    for name, shape in SHAPES.items():
        cell = CELLS[name]
        # the field models are exactly the methods the shape offers, all in the table
        assert tuple(cell.field_models) == shape.field_methods, name
        assert set(shape.field_methods) <= set(FIELD_METHODS)
        # the 3D contact's walls exist exactly where the scene allows [contact] model = "3d"
        assert (cell.contact_walls is not None) == shape.contact_3d, name


def test_an_unknown_shape_is_one_line_naming_the_key_and_the_allowed_shapes():
    with pytest.raises(SceneError) as info:
        shape_of("dodecahedron")
    message = str(info.value)
    assert "\n" not in message and "[device] shape = 'dodecahedron'" in message
    assert all(repr(name) in message for name in SHAPES)


@pytest.mark.parametrize("shape, offset, expected", [
    ("tube", 0.0, "axisymmetric"), ("tube", 1e-4, "3d"),
    ("spherical-shell", 0.0, "axisymmetric"), ("spherical-shell", 1e-4, "3d"),
    ("hexagonal", 0.0, "3d"), ("hexagonal", 1e-4, "3d")])
def test_auto_is_the_first_of_the_shapes_methods_that_takes_the_offset(shape, offset, expected):
    assert field_method(shape, "auto", offset) == expected
    scene = Scene.from_dict({**SCENES[shape], "field": {"method": "auto"}})
    assert resolve_method(scene, "auto", offset) == expected


def test_a_method_the_shape_does_not_offer_is_refused_by_its_table():
    with pytest.raises(SceneError, match=r"\[field\] method = 'axisymmetric': allowed '3d'"):
        field_method("hexagonal", "axisymmetric")
    # the field cell's table refuses it before any mesh is made (no dolfinx reached)
    scene = Scene.from_dict(SCENES["hexagonal"])
    with pytest.raises(SceneError, match=r"shape = 'hexagonal'\) = 'axisymmetric': "
                                         r"allowed '3d'"):
        solve_with(cell_of(scene), scene, 1e-3, comm=None, method="axisymmetric", offset=0.0)


def test_bounding_radius_is_the_shapes_one_formula_for_the_device_and_its_3d_cell():
    tube = Scene.from_dict({})
    dev = tube.device
    assert cylindrical_cell(dev).bounding_radius == dev.bounding_radius == math.hypot(
        dev.tube_outer_radius, 0.5 * dev.plate_spacing + dev.plate_thickness)
    hexagonal = Scene.from_dict(SCENES["hexagonal"])
    assert cell_of(hexagonal).cell.bounding_radius == hexagonal.device.bounding_radius \
        == pytest.approx(math.hypot(4e-3 / math.cos(math.pi / 6), 3.5e-3 + 2e-3), rel=1e-15)
    shell = Scene.from_dict(SCENES["spherical-shell"])
    assert cell_of(shell).bounding_radius == shell.device.bounding_radius == 12e-3
    # and the shell's field cell answers volume, longest path, mesh features as the shape
    cell, shape = cell_of(shell), SHAPES["spherical-shell"]
    assert cell.volume() == shape.volume(shell.device) == pytest.approx(
        4 / 3 * math.pi * 12e-3**3, rel=1e-15)
    assert cell.longest_path() == shell.device.longest_path == 20e-3
    assert cell.mesh_features() == shape.mesh_features(shell.device)


def test_contact_surfaces_come_from_the_shapes_entry():
    assert contact_surfaces(cell_of(Scene.from_dict({}))).names == ("lower", "upper", "wall")
    assert contact_surfaces(cell_of(Scene.from_dict(SCENES["spherical-shell"]))).spherical
    with pytest.raises(ValueError, match=r"shape = 'hexagonal': its walls are not described "
                                         r"for the 3D contact model yet; allowed 'tube', "
                                         r"'spherical-shell'"):
        contact_surfaces(cell_of(Scene.from_dict(SCENES["hexagonal"])))


def test_no_isinstance_over_shapes_in_the_package():
    shapes = {"Tube", "SphericalShell", "Hexagonal", "CylindricalCell", "HexagonalCell"}
    found = []
    for path in sorted(SRC.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Call) and getattr(node.func, "id", None) == "isinstance" \
                    and len(node.args) == 2:
                named = {getattr(n, "id", getattr(n, "attr", None))
                         for n in ast.walk(node.args[1])}
                if named & shapes:
                    found.append(f"{path.relative_to(SRC)}:{node.lineno}")
    assert not found, found
