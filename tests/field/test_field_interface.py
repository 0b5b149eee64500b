"""The field package's pure-Python parts: result object, dispatch, input checks,
open-circuit potentials (no dolfinx needed)."""
import json
import math
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tengfield import terminals
from tengfield.errors import FieldError, SceneError
from tengfield.field import check_position, resolve_method, solve_position
from tengfield.field.contact import (contact_anchors, linear_extrapolation, minimum_gap,
                                    relative_change, relative_difference)
from tengfield.field.geometry_axisymmetric import layout
from tengfield.field.potential import open_circuit_potentials, reference_charges
from tengfield.field.result import PositionResult
from tengfield.scene import default_scene


def _result(**kw):
    base = dict(position=1.5e-3, offset=0.0,
                capacitance=[[4.3e-13, -1.4e-13], [-1.4e-13, 4.3e-13]],
                induced_charge=[4.7e-10, 4.7e-10], ball_charge=-1.23e-9, dofs=10, cells=5,
                method="axisymmetric", degree=2, wall_time=1.0, relative_error_estimate=1e-4)
    base.update(kw)
    return PositionResult(**base)


def test_import_does_not_load_dolfinx_or_gmsh():
    code = ("import sys, tengfield.field, tengfield.field.result, tengfield.commands.field; "
            "bad = [m for m in sys.modules if m.split('.')[0] in ('dolfinx', 'gmsh', 'pyvista', "
            "'petsc4py')]; print(bad); sys.exit(1 if bad else 0)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stdout + done.stderr


def test_to_json_has_the_documented_keys():
    res = _result()
    data = json.loads(json.dumps(res.to_json("floating")))
    assert data["capacitance_F"] == {"lower_lower": 4.3e-13, "lower_upper": -1.4e-13,
                                     "upper_upper": 4.3e-13}
    assert data["induced_charge_C"] == {"lower": 4.7e-10, "upper": 4.7e-10}
    assert data["ball_charge_C"] == -1.23e-9
    for key in ("C_T_F", "dofs", "cells", "method", "degree", "wall_time_s",
                "relative_error_estimate"):
        assert key in data
    assert data["C_T_F"] == pytest.approx(terminals.terminal_capacitance(
        4.3e-13, -1.4e-13, 4.3e-13, "floating"))
    assert res.to_json("grounded-lower")["C_T_F"] == pytest.approx(4.3e-13)


def test_result_rejects_unknown_method():
    with pytest.raises(ValueError, match="method"):
        _result(method="2d")


@pytest.mark.parametrize("position", [-1e-4, 3.0001e-3, float("nan")])
def test_position_outside_the_stroke_is_refused(position):
    with pytest.raises(FieldError, match=r"position_mm = .* allowed \[0, 3\] mm"):
        check_position(default_scene(), position)


def test_bad_position_fails_before_any_solve():
    with pytest.raises(FieldError, match="position_mm"):
        solve_position(default_scene(), 4e-3, comm=None)


def test_non_positive_mesh_size_is_refused_with_the_key():
    with pytest.raises(SceneError, match=r"mesh_size_mm = 0.* allowed \(0, 100\]"):
        solve_position(default_scene(), 1e-3, comm=None, mesh_size_mm=0.0)
    with pytest.raises(SceneError, match=r"mesh_size_mm = -0.2"):
        solve_position(default_scene(), 1e-3, comm=None, mesh_size_mm=-0.2)


def test_electrode_larger_than_the_plate_is_refused():
    with pytest.raises(SceneError, match=r"electrode_radius_mm = 6 .*allowed \(0, 5.5\] mm"):
        default_scene().with_values(device={"electrode_radius_mm": 6.0})


def test_method_resolution():
    scene = default_scene()
    assert resolve_method(scene, None, 0.0) == "axisymmetric"
    assert resolve_method(scene, "auto", 1e-4) == "3d"
    assert resolve_method(scene, "3d", 0.0) == "3d"
    with pytest.raises(FieldError, match="offset"):
        resolve_method(scene, "axisymmetric", 1e-4)


def test_contact_anchors_rule():
    dev = default_scene().device
    g = minimum_gap(dev.plate_spacing)
    assert g == pytest.approx(0.002 * dev.plate_spacing)

    def anchors(z):
        return contact_anchors(z, dev.stroke, dev.plate_spacing)
    assert anchors(0.0) == (g, 2 * g, 4 * g)
    assert anchors(dev.stroke) == pytest.approx((dev.stroke - g, dev.stroke - 2 * g,
                                                 dev.stroke - 4 * g))
    assert anchors(1.5e-3) is None
    assert anchors(g) is None
    assert layout(default_scene(), 0.0).effective_gap == pytest.approx(g)


def test_linear_extrapolation_is_exact_on_lines():
    values = [np.array([1.0, -2.0]), np.array([3.0, 0.0])]
    assert linear_extrapolation(0.0, (1.0, 2.0), values) == pytest.approx([-1.0, -4.0])
    assert linear_extrapolation(1.5, (1.0, 2.0), values) == pytest.approx([2.0, -1.0])


def test_domain_radius_too_small_for_the_table_centre():
    scene = default_scene().with_values(field={"domain_radius_mm": 12.0})
    with pytest.raises(FieldError, match="domain_radius_mm = 12"):
        layout(scene, 1e-3, environment="grounded-table")


matrices = st.tuples(st.floats(0.2, 2.0), st.floats(0.05, 0.9), st.floats(0.2, 2.0),
                     st.floats(-1.0, 0.0), st.floats(-1.0, 0.0),
                     st.floats(-1.0, 0.0), st.floats(-1.0, 0.0))


@settings(max_examples=60, deadline=None)
@given(values=matrices, reference=st.sampled_from(["floating", "grounded-lower"]))
def test_open_circuit_potentials_agree_with_the_terminal_reduction(values, reference):
    """V_lower - V_upper from the floating-electrode potentials equals Q_SC / C_T of
    tengfield.terminals for the same reference state."""
    cll, k, cuu, fl0, fu0, fl, fu = values
    clu = -k * min(cll, cuu)          # keeps C positive definite with C_lu < 0
    C = np.array([[cll, clu], [clu, cuu]]) * 1e-12
    C0 = C * 1.02
    qb = -1e-9
    q0 = np.array([fl0, fu0]) * 0.5 * -qb
    q = np.array([fl, fu]) * 0.5 * -qb
    V = open_circuit_potentials(C, q, C0, q0, qb, reference)
    q_sc = (terminals.upper_short_circuit_charge(*C[np.triu_indices(2)], *q, qb, reference)
            - terminals.upper_short_circuit_charge(*C0[np.triu_indices(2)], *q0, qb, reference))
    c_t = terminals.terminal_capacitance(*C[np.triu_indices(2)], reference)
    assert V[0] - V[1] == pytest.approx(q_sc / c_t, rel=1e-9, abs=1e-9 * abs(qb) / c_t)
    Q = C @ V + q
    Q_ref = reference_charges(C0, q0, qb, reference)
    if reference == "grounded-lower":   # the grounded lower electrode exchanges charge
        assert V[0] == 0.0
        assert Q[1] == pytest.approx(Q_ref[1], rel=1e-9, abs=1e-21)
    else:                               # both floating: each keeps its charge
        assert Q == pytest.approx(Q_ref, rel=1e-9, abs=1e-21)
        assert Q.sum() == pytest.approx(-qb, rel=1e-12)


def test_only_the_version_layer_imports_dolfinx_petsc_ufl_basix():
    """#10/#14: every dolfinx/petsc4py/ufl/basix import of the field stack (the field
    package, its CLI command, and the solver callers) is in field/_dolfinx.py
    (commands/info.py reads versions; it is not part of the field stack)."""
    import ast
    from pathlib import Path

    import tengfield
    root = Path(tengfield.__file__).parent
    offenders = []
    for path in [*root.joinpath("field").rglob("*.py"), root / "commands" / "field.py",
                 root / "surrogate.py", root / "pipeline.py"]:
        if not path.is_file():
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            names = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names = [node.module]
            for name in names:
                if name.split(".")[0] in ("dolfinx", "petsc4py", "ufl", "basix"):
                    offenders.append(f"{path.relative_to(root)}: {name}")
    assert offenders and all(o.startswith("field/_dolfinx.py") for o in offenders), offenders


def test_solver_sources_exclude_io_and_plots():
    """The surrogate's solver fingerprint hashes SOLVER_SOURCES: every file that
    decides the numbers is in it, the writers and plots are not."""
    from pathlib import Path

    import tengfield.field as field
    paths = field.solver_source_paths()
    assert all(p.is_file() for p in paths)
    root = Path(field.__file__).parent
    names = {p.relative_to(root).as_posix() for p in paths}
    assert {"axisymmetric.py", "solver3d.py", "_dolfinx.py", "contact.py"} <= names
    assert not names & {"io.py", "plot.py", "potential.py", "result.py"}
    # the cells (field/cells/: their meshes and solve decide the numbers) are all in, but
    # contact_surfaces.py: the walls the 3D dynamics touch, no field number depends on it
    cells = {p.relative_to(root).as_posix() for p in root.glob("cells/*.py")}
    assert cells - {"cells/contact_surfaces.py"} <= names
    assert "cells/contact_surfaces.py" not in names
    names = {name for name in names if "/" not in name}
    package = {p.name for p in root.glob("*.py")}
    assert names <= package
    # _gmsh.py starts gmsh with the arguments its callers give (stderr filtering only);
    # cost.py estimates and refuses before a solve, it computes no number of one
    assert package - names == {"io.py", "plot.py", "potential.py", "result.py", "_gmsh.py",
                               "cost.py"}, \
        "a new module in field/: add it to SOLVER_SOURCES if it changes the numbers"


def test_contact_relative_change_is_relative_to_the_reference_and_zero_safe():
    class S:
        def __init__(self, c, f):
            self.capacitance, self.induced_fraction = np.array(c), np.array(f)
    ref = S([[2.0, -1.0], [-1.0, 2.0]], [-0.5, -0.25])
    val = S([[2.2, -1.0], [-1.0, 2.0]], [-0.5, -0.25])
    assert relative_change(val, ref) == pytest.approx(0.1)
    assert relative_difference([0.0, 1.0], [0.0, 1.0]) == 0.0
    assert relative_difference([1e-3], [0.0]) == math.inf
