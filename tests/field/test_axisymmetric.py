"""Physics of the axisymmetric field solver on coarse meshes (analytic limits,
invariants, convergence rates, far-field truncation, contact rule, reciprocity)."""
import math

import pytest

pytest.importorskip("dolfinx")
pytest.importorskip("gmsh")

import numpy as np  # noqa: E402
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402
from mpi4py import MPI  # noqa: E402

from tengfield.field import solve_position  # noqa: E402
from tengfield.field import _dolfinx as dx_api  # noqa: E402
from tengfield.field import contact  # noqa: E402
from tengfield.field import geometry_axisymmetric as geometry  # noqa: E402
from tengfield.scene import default_scene  # noqa: E402

COMM = MPI.COMM_SELF
COARSE = dict(mesh_size_mm=0.8, degree=2, estimate_error=False)


def solve(scene, z, **kw):
    opts = {**COARSE, **kw}
    return solve_position(scene, z, comm=COMM, method="axisymmetric", **opts)


def quantities(res):
    """The numbers a user reads: C_ll, C_lu, C_uu, q_lower, q_upper."""
    return np.array([res.C_ll, res.C_lu, res.C_uu, res.q_lower, res.q_upper])


def max_relative_difference(a, b):
    return float(np.max(np.abs(quantities(a) / quantities(b) - 1.0)))


# -- exact limits ---------------------------------------------------------------
@pytest.mark.parametrize("z", [0.4e-3, 2.2e-3])
def test_mean_value_property_for_a_vacuum_ball(z):
    """εr = 1 inside the ball: ψ_k is harmonic there, so ∮σψ_k = q_ball ψ_k(centre)
    (any electrode shape, any dielectric outside: the PMMA walls stay in)."""
    scene = default_scene().with_values(device={"ball_permittivity": 1.0})
    res = solve(scene, z, keep_solution=True)
    sol = res.solution
    assert sol.method == "axisymmetric" and sol.source is None
    centre = [sol.ball_centre]
    assert sol.ball_centre[1] == pytest.approx(geometry.layout(scene, z).ball_centre_z)
    for k, psi in enumerate(sol.weighting):
        psi_centre = dx_api.point_values(sol.space, psi.x.array, centre)[0]
        expected = -res.ball_charge * psi_centre
        assert res.induced_charge[k] == pytest.approx(expected, rel=2e-4)


def test_large_electrodes_follow_shockley_ramo():
    """Electrodes much wider than their spacing, εr = 1 everywhere:
    q_upper / q_ball = -(z + d/2) / h (parallel-plate weighting field)."""
    scene = default_scene().with_values(
        device={"electrode_radius_mm": 40.0, "tube_inner_radius_mm": 35.0,
                "tube_outer_radius_mm": 40.0, "ball_permittivity": 1.0,
                "wall_permittivity": 1.0},
        field={"domain_radius_mm": 60.0})
    dev = scene.device
    for z in (0.5e-3, 2.5e-3):
        res = solve(scene, z, mesh_size_mm=1.2)
        expected = -(z + dev.ball_radius) / dev.plate_spacing
        assert res.q_upper / res.ball_charge == pytest.approx(expected, rel=1e-3)
        assert res.q_lower / res.ball_charge == pytest.approx(-1.0 - expected, rel=1e-3)


# -- invariants -------------------------------------------------------------------
@settings(max_examples=4, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(z_fraction=st.floats(0.0, 1.0), ball_eps=st.floats(1.0, 6.0),
       wall_eps=st.sampled_from([1.0, 2.6]),
       far_field=st.sampled_from(["kelvin", "robin"]))
def test_capacitance_matrix_and_charge_invariants(z_fraction, ball_eps, wall_eps, far_field):
    scene = default_scene().with_values(device={"ball_permittivity": ball_eps,
                                                "wall_permittivity": wall_eps})
    res = solve(scene, z_fraction * scene.device.stroke, mesh_size_mm=1.0, far_field=far_field)
    C = res.capacitance
    assert C[0, 1] == C[1, 0]
    assert C[0, 0] > 0 and C[1, 1] > 0 and C[0, 1] < 0
    assert np.all(np.linalg.eigvalsh(C) > 0)          # field energy ½VᵀCV ≥ 0 for every V
    assert C.sum(axis=1).min() > 0                    # diagonal dominance (free space)
    fractions = res.induced_fractions()
    assert np.all(fractions >= -1.0) and np.all(fractions <= 0.0)
    assert -1.0 <= fractions.sum() <= 0.0
    assert res.info["ball_area_quadrature_m2"] == pytest.approx(math.pi * (2 * scene.device.ball_radius) ** 2, rel=1e-6)


def test_mirror_symmetry_of_the_device():
    """The device is symmetric about its mid-plane: z ↔ Δh - z swaps lower and upper."""
    scene = default_scene()
    a, b = solve(scene, 0.7e-3), solve(scene, scene.device.stroke - 0.7e-3)
    assert a.C_ll == pytest.approx(b.C_uu, rel=2e-3)
    assert a.q_lower == pytest.approx(b.q_upper, rel=2e-3)
    assert a.q_upper == pytest.approx(b.q_lower, rel=2e-3)


# -- convergence ------------------------------------------------------------------
@pytest.fixture(scope="module")
def convergence_reference():
    return solve(default_scene(), 1.5e-3, degree=3, mesh_size_mm=0.4)


@pytest.mark.parametrize("degree,expected_rate", [(1, 2.0), (2, 4.0)])
def test_convergence_rate_under_refinement(convergence_reference, degree, expected_rate):
    """C and q are energy-type functionals: error ~ h^(2p) with the radical rim grading."""
    sizes = np.array([1.6, 1.1, 0.8])
    errors = [max_relative_difference(solve(default_scene(), 1.5e-3, degree=degree,
                                            mesh_size_mm=h), convergence_reference)
              for h in sizes]
    slope = np.polyfit(np.log(sizes), np.log(errors), 1)[0]
    assert slope == pytest.approx(expected_rate, abs=0.45), (errors, slope)


# -- far field --------------------------------------------------------------------
@pytest.mark.parametrize("environment", ["free-space", "grounded-table"])
def test_kelvin_far_field_does_not_depend_on_the_domain_radius(environment):
    scene = default_scene().with_values(field={"environment": environment})
    small = solve(scene, 1.0e-3, domain_radius_mm=16.0)
    large = solve(scene, 1.0e-3, domain_radius_mm=32.0)
    assert max_relative_difference(small, large) < 0.2 * scene.field.tolerance


def test_dirichlet_truncation_is_not_stable():
    """The naive grounded sphere moves the results by far more than the tolerance."""
    scene = default_scene()
    small = solve(scene, 1.0e-3, domain_radius_mm=16.0, far_field="dirichlet")
    large = solve(scene, 1.0e-3, domain_radius_mm=32.0, far_field="dirichlet")
    assert max_relative_difference(small, large) > 10 * scene.field.tolerance


def test_grounded_table_takes_charge_from_the_electrodes():
    """A grounded plane below the device screens it: both induced charges shrink in
    magnitude and the lower electrode's self-capacitance grows."""
    scene = default_scene()
    free = solve(scene, 1.0e-3)
    table = solve(scene.with_values(field={"environment": "grounded-table"}), 1.0e-3)
    assert abs(table.q_lower) < abs(free.q_lower)
    assert abs(table.q_upper) < abs(free.q_upper)
    assert table.C_ll > free.C_ll


# -- contact rule -----------------------------------------------------------------
@pytest.mark.slow
def test_contact_rule_matches_a_directly_meshed_small_gap(monkeypatch):
    """Below min_gap the solver extrapolates from min_gap, 2 min_gap, 4 min_gap
    (a straight line for PTFE); meshing a 5 µm gap directly gives the same numbers."""
    scene = default_scene()
    z = 5e-6
    rule = solve(scene, z)
    assert "extrapolation" in rule.info["contact_rule"]
    monkeypatch.setattr(contact, "MIN_GAP_FRACTION", 1e-4)
    direct = solve(scene, z)
    assert "contact_rule" not in direct.info
    assert direct.info["meshed_gap_m"] == pytest.approx(z)
    assert max_relative_difference(rule, direct) < 2e-4
    assert rule.info["contact_extrapolation_error"] < 1e-3      # PTFE: linear near contact


def test_contact_rule_flags_a_nearly_conducting_ball():
    """εr = 100: the charge varies logarithmically near contact; the extrapolation
    error estimate must say the result is not within the 1e-3 tolerance."""
    scene = default_scene().with_values(device={"ball_permittivity": 100.0})
    res = solve(scene, 0.0)
    assert res.info["contact_extrapolation_error"] > 1e-2


@pytest.mark.slow
def test_contact_at_both_plates_is_symmetric():
    scene = default_scene()
    bottom, top = solve(scene, 0.0), solve(scene, scene.device.stroke)
    assert bottom.q_lower == pytest.approx(top.q_upper, rel=2e-3)
    assert bottom.q_upper == pytest.approx(top.q_lower, rel=2e-3)
    assert -1.0 < bottom.q_lower / bottom.ball_charge < -0.5   # mostly on the touched plate


# -- reciprocity and the error estimate -------------------------------------------
def test_reciprocity_direct_source_solve_gives_the_induced_charges():
    """Electrode charges from the direct solve with the σ source (electrodes grounded)
    equal -∮σψ_k from the weighting potentials."""
    res = solve(default_scene(), 1.2e-3, source_solve=True)
    direct = np.asarray(res.info["source_electrode_charge_C"])
    assert direct == pytest.approx(res.induced_charge, rel=1e-8)


def test_error_estimate_brackets_the_true_error(convergence_reference):
    res = solve(default_scene(), 1.5e-3, mesh_size_mm=1.1, estimate_error=True)
    true_error = max_relative_difference(res, convergence_reference)
    assert 0.5 * true_error < res.relative_error_estimate < 2.0 * true_error
