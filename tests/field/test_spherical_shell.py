"""The spherical-shell cell (tengfield.field.cells): its geometry for every stage, and
the physics of its axisymmetric field solve (symmetry, charge conservation, mesh
convergence, a closed form of the closed-sphere limit)."""
import math

import numpy as np
import pytest

from tengfield.errors import FieldError
from tengfield.field.cells import CELLS, Cell, SphericalShell, cell_class

A = 10e-3   # cavity radius of the test cells [m]


def shell(**kw):
    values = dict(cavity_diameter=2 * A, shell_thickness=2e-3, electrode_band=2e-3,
                  ball_diameter=8e-3, wall_permittivity=3.0, ball_permittivity=2.1)
    values.update(kw)
    return SphericalShell(**values)


# -- geometry (pure, fast) -----------------------------------------------------------
def test_registry_and_protocol():
    cell = shell()
    assert CELLS["spherical-shell"] is SphericalShell
    assert cell_class("spherical-shell") is SphericalShell
    assert isinstance(cell, Cell)
    from tengfield.field.cells import Hexagonal, Tube
    from tengfield.scene import default_scene
    assert isinstance(Tube(default_scene()), Cell) and isinstance(Hexagonal(default_scene()), Cell)
    with pytest.raises(ValueError, match="allowed hexagonal, spherical-shell, tube"):
        cell_class("dodecahedron")


def test_stroke_and_centre():
    cell = shell()
    assert cell.stroke == pytest.approx(12e-3)          # cavity - ball diameter
    assert cell.ball_centre_z(0.0) == pytest.approx(-A + 4e-3)   # resting on the bottom
    assert cell.ball_centre_z(cell.stroke) == pytest.approx(A - 4e-3)   # touching the top
    assert cell.ball_centre_z(0.5 * cell.stroke) == pytest.approx(0.0)


def test_admissible_region_wall_distance_and_normal():
    cell = shell()
    free = A - 4e-3   # the centre's largest distance from the cavity centre
    rng = np.random.default_rng(3)
    for _ in range(50):
        direction = rng.normal(size=3)
        direction /= np.linalg.norm(direction)
        rho = rng.uniform(0.0, 1.3 * free)
        c = rho * direction
        assert cell.wall_distance(c) == pytest.approx(free - rho, abs=1e-15)
        assert cell.admissible(c) == (rho <= free)
        n = cell.wall_normal(c)
        assert np.linalg.norm(n) == pytest.approx(1.0)
        assert n == pytest.approx(direction)       # radial, outward
        # the nearest wall point is c + (wall_distance + r_b) n, on the cavity sphere
        touch = c + (cell.wall_distance(c) + cell.ball_radius) * n
        assert np.linalg.norm(touch) == pytest.approx(A)
    assert cell.wall_normal(np.zeros(3)) == pytest.approx([0.0, 0.0, -1.0])


def test_volume_longest_path_outline_and_features():
    cell = shell()
    assert cell.volume() == pytest.approx(4.0 / 3.0 * math.pi * 12e-3**3)
    assert cell.longest_path() == pytest.approx(2 * A)
    lower, upper, band, outer = cell.outline()
    for arc, radius in ((lower, A), (upper, A), (band, A), (outer, 12e-3)):
        assert np.hypot(arc[:, 0], arc[:, 1]) == pytest.approx(radius)
        assert np.all(arc[:, 0] >= -1e-15)
    assert lower[:, 1].max() == pytest.approx(-1e-3)   # the band's edges: z = ±w/2
    assert upper[:, 1].min() == pytest.approx(1e-3)
    assert lower[0] == pytest.approx([0.0, -A], abs=1e-15)
    assert cell.mesh_features() == {"ball_diameter_mm": 8e-3, "stroke_mm": 12e-3,
                                    "electrode_band_mm": 2e-3, "shell_thickness_mm": 2e-3}
    assert "shell_thickness_mm" not in shell(wall_permittivity=1.0).mesh_features()
    assert cell.electrode_at(-2e-3) == "lower" and cell.electrode_at(0.0) is None


def test_breakdown_feet():
    """Each line runs from a ball surface point to the nearest point of its side's
    electrode: checked against a brute-force minimum over the electrode's meridian."""
    cell = shell()
    zc = cell.ball_centre_z(1e-3)            # 1 mm above the bottom
    lines = cell.breakdown_feet(zc, range(0, 90, 5))
    assert lines["start"].shape == (2, 18, 3) and lines["length"].shape == (2, 18)
    assert lines["length"][0, 0] == pytest.approx(1e-3)     # the axial gap below
    feet, start = lines["foot"], lines["start"]
    assert np.hypot(feet[..., 0], feet[..., 1]) == pytest.approx(A)
    assert np.linalg.norm(feet - start, axis=-1) == pytest.approx(lines["length"])
    assert np.all(feet[0, :, 1] <= -1e-3 + 1e-15) and np.all(feet[1, :, 1] >= 1e-3 - 1e-15)
    assert np.all(lines["length"] <= cell.longest_path())
    # brute force: the electrode meridians, finely sampled
    phi0 = math.asin(1e-3 / A)
    for side, (lo, hi) in enumerate(((-0.5 * math.pi, -phi0), (phi0, 0.5 * math.pi))):
        phi = np.linspace(lo, hi, 200001)
        arc = np.column_stack([A * np.cos(phi), A * np.sin(phi)])
        for k in range(18):
            best = np.min(np.hypot(arc[:, 0] - start[side, k, 0], arc[:, 1] - start[side, k, 1]))
            assert lines["length"][side, k] == pytest.approx(best, rel=1e-6, abs=1e-9)
    # the low ball: its lower lines are radial; the top of the ball (below the band)
    # reaches the upper electrode at its rim
    assert lines["radial"][0].all()
    assert not lines["radial"][1, 0]
    assert feet[1, 0] == pytest.approx([math.sqrt(A * A - 1e-6), 1e-3, 0.0])


@pytest.mark.parametrize("kw, match", [
    (dict(ball_diameter=20e-3), "ball_diameter_mm = 20 is out of range"),
    (dict(electrode_band=25e-3), "electrode_band_mm = 25 is out of range"),
    (dict(shell_thickness=0.0), "shell_thickness_mm = 0 is out of range"),
    (dict(wall_permittivity=0.5), "wall_permittivity = 0.5 is out of range"),
    (dict(domain_radius=12e-3), "domain_radius_mm = 12 is too small"),
])
def test_bad_dimensions_one_line(kw, match):
    with pytest.raises(FieldError, match=match) as info:
        shell(**kw)
    assert "\n" not in str(info.value)


# -- field solves ---------------------------------------------------------------------
field = pytest.mark.field


def solve(cell, z, **kw):
    pytest.importorskip("dolfinx")
    pytest.importorskip("gmsh")
    from mpi4py import MPI

    from tengfield.field.cells.solve import solve_cell_position

    opts = dict(sigma=-1e-5, mesh_size=1e-3, estimate_error=False)
    opts.update(kw)
    return solve_cell_position(cell, z, comm=MPI.COMM_SELF, **opts)


@field
@pytest.mark.slow
def test_ball_at_the_centre_induces_equal_charges_and_mirror_symmetry():
    """Ball at the centre: the geometry is symmetric under z -> -z (which swaps the
    hemispheres), so q_lower = q_upper and C_ll = C_uu; off the centre, z and
    stroke - z are mirror images (q and C swap)."""
    cell = shell()
    centre = solve(cell, 0.5 * cell.stroke)
    assert centre.q_lower == pytest.approx(centre.q_upper, rel=1e-5)
    assert centre.C_ll == pytest.approx(centre.C_uu, rel=1e-5)
    assert centre.C_lu < 0 < centre.C_ll
    assert -0.5 < centre.induced_fraction[0] < -0.49   # nearly all of -Q, halved
    low, high = solve(cell, 2.5e-3), solve(cell, cell.stroke - 2.5e-3)
    assert low.induced_fraction == pytest.approx(high.induced_fraction[::-1], rel=1e-4)
    assert low.C_ll == pytest.approx(high.C_uu, rel=1e-4)
    # σ < 0: a negative ball; the induced charges are positive, more on the nearer side
    assert low.ball_charge < 0
    assert low.q_lower > centre.q_lower > low.q_upper > 0


@field
@pytest.mark.slow
def test_charge_conservation_with_the_far_field():
    """Gauss's law: the ball charge Q, the electrode charges (the reactions of the σ
    source solve, electrodes grounded) and the charge the field carries to infinity
    (the flux through the far sphere, -ε0 ∮ ∂φ/∂n dA = ε0/R ∮ φ dA with the monopole
    Robin condition) add up: Q + q_lower + q_upper = q_far. The reactions equal the
    reciprocity charges -σ∮ψ_k dS. The charge escaping through the band goes to 0 as
    the band closes (a closed grounded conductor takes all of -Q), like w²."""
    leaks, widths = [], (2e-3, 1e-3, 0.5e-3)
    for w in widths:
        res = solve(shell(electrode_band=w), 2.5e-3, far_field="robin", source_solve=True)
        Q = res.ball_charge
        reaction = res.info["source_electrode_charge_C"]
        q_far = res.info["far_field_charge_C"]
        assert reaction == pytest.approx(res.induced_charge, rel=1e-8)
        # to 1e-6 of Q: the quadrature of the curved (P2) ball surface's area differs
        # from π d² by ~2e-7; the charge leaving through the band is ~1e-3 of Q
        assert Q + reaction.sum() - q_far == pytest.approx(0.0, abs=1e-6 * abs(Q))
        assert q_far / Q > 0    # the escaping part has the ball's sign
        leaks.append(q_far / Q)
    assert leaks[0] > leaks[1] > leaks[2]
    slope = np.polyfit(np.log(widths), np.log(leaks), 1)[0]
    assert slope > 1.5, (leaks, slope)


@field
@pytest.mark.slow
def test_mesh_convergence():
    """C and the induced fractions converge under uniform refinement of one mesh family
    (the same grading lengths), at the rate h^(2p) of the energy functionals (p = 2):
    the error against a 1/8-size mesh falls with a fitted log-log slope of at least 3,
    and the Richardson estimate of the default solve bounds the true error."""
    from tengfield.field import contact

    cell = shell()
    sizes = (2e-3, 1e-3, 0.5e-3)
    ref = solve(cell, 2.5e-3, mesh_size=0.25e-3, grading_size=2e-3)
    errors = [contact.relative_change(solve(cell, 2.5e-3, mesh_size=h, grading_size=2e-3), ref)
              for h in sizes]
    assert errors[0] > errors[1] > errors[2]
    rate = np.polyfit(np.log(sizes), np.log(errors), 1)[0]
    assert rate > 3.0, (errors, rate)
    estimated = solve(cell, 2.5e-3, mesh_size=1e-3, estimate_error=True)
    assert errors[1] <= 2.0 * estimated.relative_error_estimate


def hemisphere_fraction(s, a):
    """ψ_lower at height s on the axis of a closed sphere of radius a whose lower
    hemisphere is at 1 V and upper at 0 V (derivation in the test below)."""
    if abs(s) < 1e-12 * a:
        return 0.5
    return (a * a - s * s) / (2.0 * s * math.sqrt(a * a + s * s)) - (a - s) / (2.0 * s)


def hemisphere_series(r, z, a, terms=80):
    """ψ_lower at (r, z) inside the closed sphere of radius a, anywhere (not only on the
    axis): the Legendre series of the boundary values f(μ) = 1 for μ < 0, 0 for μ > 0,
    ψ = Σ_l c_l (ρ/a)^l P_l(cos θ), c_l = (2l + 1)/2 ∫_{-1}^{0} P_l(μ) dμ."""
    from numpy.polynomial import legendre

    rho = math.hypot(r, z)
    mu = z / rho if rho > 0 else 0.0
    total = 0.0
    for n in range(terms):
        unit = np.zeros(n + 1)
        unit[n] = 1.0
        c = 0.5 * (2 * n + 1) * legendre.legval(0.0, legendre.legint(unit, lbnd=-1.0))
        total += c * (rho / a) ** n * legendre.legval(mu, unit)
    return total


def test_the_two_closed_forms_agree_on_the_axis():
    for s in np.linspace(-0.6 * A, 0.6 * A, 13):
        assert hemisphere_series(0.0, s, A) == pytest.approx(hemisphere_fraction(s, A),
                                                             abs=1e-12)


@field
@pytest.mark.slow
@pytest.mark.parametrize("z", [0.0, 1e-3, 4e-3, 8e-3, 13e-3])
def test_closed_sphere_limit_matches_poissons_integral(z):
    """Closed form (band -> 0, ball permittivity 1, wall permittivity 1).

    Green's reciprocity gives q_k = -∮_ball σ ψ_k dS with ψ_k the weighting potential
    of electrode k. With ε = 1 in the whole cavity, ψ_k is harmonic inside it, so its
    mean over the ball's surface is its value at the ball centre c (mean-value
    property): q_k = -Q ψ_k(c), as for a point charge Q at c.

    As the band closes, the cavity wall is a closed sphere of radius a with ψ_lower =
    1 on the lower hemisphere and 0 on the upper one. Poisson's integral for the ball
    |x| < a, at x = s ẑ (|x - y|² = a² + s² - 2 a s cos θ, dS = a² sin θ dθ dφ):

        ψ_lower(s) = (a² - s²) a / 2 ∫_{π/2}^{π} sin θ dθ / (a² + s² - 2as cos θ)^(3/2)
                   = (a² - s²)/(2s) [1/√(a² + s²) - 1/(a + s)]

    (u = cos θ from -1 to 0), = 1/2 at s = 0, -> 1 as s -> -a, -> 0 as s -> a; and
    ψ_upper = 1 - ψ_lower. So q_lower/Q = -ψ_lower(s), q_upper/Q = -(1 - ψ_lower(s)).
    Nothing of the solver enters: the exterior, the shell and the band drop out.

    The solve with a band w = 0.1 mm (w/2a = 0.005) agrees within 1e-4 (absolute
    fraction), and the band of 0.4 mm deviates more (the limit is approached);
    z = 0 (ball on the bottom) goes through the contact rule's extrapolation.
    """
    closed = dict(ball_diameter=4e-3, ball_permittivity=1.0, wall_permittivity=1.0)
    narrow = shell(electrode_band=0.1e-3, **closed)
    s = narrow.ball_centre_z(z)
    psi = hemisphere_fraction(s, A)
    exact = np.array([-psi, -(1.0 - psi)])
    res = solve(narrow, z)
    assert res.induced_fraction == pytest.approx(exact, abs=1e-4)
    wide = solve(shell(electrode_band=0.4e-3, **closed), z)
    assert np.abs(wide.induced_fraction - exact).max() > np.abs(
        res.induced_fraction - exact).max()


def test_from_keys_reads_file_units():
    cell = SphericalShell.from_keys({"shape": "spherical-shell", "cavity_diameter_mm": 20,
                                     "shell_thickness_mm": 2, "electrode_band_mm": 2,
                                     "ball_diameter_mm": 8, "wall_permittivity": 3.0},
                                    domain_radius_mm=40)
    assert cell == shell(ball_permittivity=2.1, domain_radius=40e-3)
    with pytest.raises(FieldError, match=r"\[device\] electrode_band_mm is missing"):
        SphericalShell.from_keys({"cavity_diameter_mm": 20, "shell_thickness_mm": 2,
                                  "ball_diameter_mm": 8})


# -- the tube through the same protocol ---------------------------------------------------
def test_tube_cell_geometry_matches_the_scene():
    from tengfield.scene import default_scene
    from tengfield.scene.limits import mesh_features

    scene = default_scene()
    tube = CELLS["tube"].from_scene(scene)
    dev = scene.device
    assert isinstance(tube, Cell)
    assert tube.stroke == dev.stroke
    assert tube.longest_path() == dev.longest_path == math.hypot(dev.plate_spacing,
                                                                 2 * dev.tube_inner_radius)
    assert tube.volume() == dev.cell_volume
    assert tube.mesh_features() == mesh_features(dev, scene.field.environment)
    centre = np.array([0.0, 0.0, tube.ball_centre_z(0.3e-3)])
    assert tube.wall_distance(centre) == pytest.approx(0.3e-3)   # the gap to the lower plate
    assert tube.wall_normal(centre) == pytest.approx([0.0, 0.0, -1.0])
    side = np.array([dev.tube_inner_radius - dev.ball_radius - 0.1e-3, 0.0, 0.0])
    assert tube.wall_distance(side) == pytest.approx(0.1e-3)
    assert tube.wall_normal(side) == pytest.approx([1.0, 0.0, 0.0])
    assert not tube.admissible(side + np.array([0.2e-3, 0.0, 0.0]))


@field
@pytest.mark.slow
@pytest.mark.parametrize("z", [0.0, 1.5e-3])
def test_the_cell_route_reproduces_the_tube_solver_to_the_bit(z):
    """solve_cell_position on the tube cell builds the same mesh and runs the same
    assembly and solves as solve_position: the same numbers to the bit (also through
    the contact rule at z = 0)."""
    pytest.importorskip("dolfinx")
    from mpi4py import MPI

    from tengfield.field import solve_position
    from tengfield.scene import default_scene

    scene = default_scene().with_values(field={"mesh_size_mm": 0.8})
    direct = solve_position(scene, z, comm=MPI.COMM_SELF, method="axisymmetric",
                            estimate_error=False)
    via = solve(CELLS["tube"].from_scene(scene), z, sigma=scene.device.surface_charge,
                mesh_size=0.8e-3, degree=scene.field.degree, far_field=scene.field.far_field,
                domain_radius=scene.field.domain_radius)
    assert np.array_equal(via.capacitance, direct.capacitance)
    assert np.array_equal(via.induced_fraction, direct.induced_fraction)
    assert np.array_equal(via.induced_charge, direct.induced_charge)
    assert via.dofs == direct.dofs


@field
def test_the_cell_route_maps_the_tubes_canonical_mesh_as_the_tube_solver_does():
    """With ``mesh_motion = "move"`` the tube cell's route maps its reference from the
    same canonical tube (``Tube.canonical``) as solve_position: the same numbers to the
    bit, and one map each; every cell declares the hooks (``canonical``,
    ``check_tabulated_offset``)."""
    from mpi4py import MPI

    from tengfield.field import moving, solve_position
    from tengfield.field.cells import Cell, Hexagonal, Tube
    from tengfield.scene import default_scene

    scene = default_scene().with_values(field={"mesh_size_mm": 2.0, "mesh_motion": "move"})
    moving.clear()
    direct = solve_position(scene, 1.5e-3, comm=MPI.COMM_SELF, method="axisymmetric",
                            estimate_error=False)
    moving.clear()
    via = solve(Tube(scene), 1.5e-3, sigma=scene.device.surface_charge, mesh_size=2e-3,
                degree=scene.field.degree, far_field=scene.field.far_field,
                domain_radius=scene.field.domain_radius, mesh_motion="move")
    moving.clear()
    assert direct.info["mesh_placements"]["mapped"] == via.info["mesh_placements"]["mapped"] == 1
    assert np.array_equal(via.capacitance, direct.capacitance)
    assert np.array_equal(via.induced_fraction, direct.induced_fraction)
    canon = Tube(scene).canonical()
    assert canon.device.ball_diameter == pytest.approx(6.7275e-3, rel=1e-9)
    assert Hexagonal(default_scene()).canonical() is None
    assert isinstance(canon, Cell)


@field
@pytest.mark.slow
@pytest.mark.parametrize("ball_permittivity", [1.0, 2.1])
def test_concentric_ball_potential_and_lines(ball_permittivity):
    """Closed form of the breakdown lines' source potential (band -> 0): a ball of
    radius r_b with uniform surface charge σ at the centre of a closed grounded sphere
    of radius a. By symmetry the field is radial, zero inside the ball (whatever its
    permittivity: no free charge inside, and a radial field there would need one) and
    Q/(4πε0 ρ²) between the ball and the wall, Q = 4π r_b² σ; integrating from the
    grounded wall, φ(r_b) = Q/(4πε0) (1/r_b - 1/a) = σ r_b (1 - r_b/a)/ε0 at every
    surface point. The weighting potentials there (ε_ball = 1: harmonic in the
    cavity) are the closed sphere's, the Legendre series of its boundary values
    (:func:`hemisphere_series`), and ψ_lower + ψ_upper = 1. Band 0.1 mm: within 3e-4 (observed 5e-5)."""
    from tengfield.field.breakdown import LINE_ANGLES_DEG
    from tengfield.scene.constants import EPS0

    cell = shell(electrode_band=0.1e-3, ball_permittivity=ball_permittivity)
    res = solve(cell, 0.5 * cell.stroke, breakdown_lines=True)
    lines = res.info["breakdown_lines"]          # (sides, lines, [φ_1, ψ_lower, ψ_upper])
    assert lines.shape == (2, len(LINE_ANGLES_DEG), 3)
    rb = cell.ball_radius
    assert lines[..., 0] == pytest.approx(rb * (1.0 - rb / A) / EPS0, rel=3e-4)
    assert lines[..., 1] + lines[..., 2] == pytest.approx(1.0, abs=3e-4)
    # mirror symmetry (the axial lines too, since line_basis reads the top node at
    # r = -1.7e-21: test_upper_axial_line_reads_the_axis_node), and Poisson's integral
    assert lines[0, :, 1] == pytest.approx(lines[1, :, 2], abs=1e-5)
    if ball_permittivity == 1.0:   # the lower side's points (r, z) on the ball surface
        theta = np.radians(LINE_ANGLES_DEG)
        expected = [hemisphere_series(rb * math.sin(t), -rb * math.cos(t), A) for t in theta]
        assert lines[0, :, 1] == pytest.approx(expected, abs=3e-4)


def test_upper_axial_line_reads_the_axis_node():
    """line_basis on ball-surface nodes like those of the shell's mesh (found there: the
    top node at r = -1.7e-21): the upper side's axial value is the top node's value
    (before the fix, arctan2 gave that node -π and the value was read 0.4 h away)."""
    from types import SimpleNamespace

    from tengfield.field.breakdown import line_basis

    polar = np.linspace(0.0, math.pi, 65)
    xy = np.column_stack([4e-3 * np.sin(polar), -4e-3 * np.cos(polar), np.zeros(65)])
    xy[-1, 0] = -1.7e-21            # the top node, a rounding below the axis
    values = np.cos(polar)          # +1 at the bottom, -1 at the top
    fake = SimpleNamespace(facet_dofs=lambda V, tags, tag: np.arange(65),
                           dof_coordinates=lambda V: xy)
    disc = SimpleNamespace(V=None, facet_tags=None)
    lines = line_basis(fake, disc, values, (values, values), SimpleNamespace(ball_centre_z=0.0),
                       angles_deg=(0.0, 45.0))
    assert lines[0, 0, 0] == pytest.approx(1.0)
    assert lines[1, 0, 0] == pytest.approx(-1.0)


@field
@pytest.mark.slow
def test_kept_potentials_match_the_closed_sphere_everywhere_in_the_cavity():
    """The potentials themselves (``keep_solution``), band -> 0, ball (ε = 1) at the
    centre: ψ_lower at points all over the cavity equals the Legendre series of the
    closed sphere (:func:`hemisphere_series`), and the ball's source potential
    (electrodes grounded) is φ_σ(ρ) = σ r_b²/ε0 (1/ρ - 1/a) between the ball and the
    wall (Gauss, radial field), constant σ r_b (1 - r_b/a)/ε0 inside the ball.
    Mesh 1 mm, band 0.1 mm: observed 6e-5 (ψ, absolute) and 5e-4 (φ_σ, relative,
    largest near the wall where φ_σ -> 0)."""
    from tengfield.field import _dolfinx as dx_api
    from tengfield.scene.constants import EPS0

    sigma = -1e-5
    cell = shell(electrode_band=0.1e-3, ball_permittivity=1.0, wall_permittivity=1.0)
    res = solve(cell, 0.5 * cell.stroke, sigma=sigma, source_solve=True, keep_solution=True)
    sol = res.solution
    rng = np.random.default_rng(7)
    rho = rng.uniform(0.05 * A, 0.8 * A, 40)
    angle = rng.uniform(0.0, math.pi, 40)
    points = np.column_stack([rho * np.sin(angle), -rho * np.cos(angle), np.zeros(40)])
    psi = dx_api.point_values(sol.space, sol.weighting[0].x.array, points)
    expected = [hemisphere_series(r, z, A) for r, z, _ in points]
    assert psi == pytest.approx(expected, abs=3e-4)
    rb = cell.ball_radius
    phi = dx_api.point_values(sol.space, sol.source.x.array, points)
    outside = sigma * rb * rb / EPS0 * (1.0 / np.maximum(rho, rb) - 1.0 / A)
    assert phi == pytest.approx(outside, rel=1e-3)
