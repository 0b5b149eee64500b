"""The spherical shell's single-electrode cell (``[device] electrodes = "lower"`` with
``shape = "spherical-shell"``, issue #51): the lower cap alone, the upper cap bare cavity
wall (the shell's dielectric behind it), the terminals the lower cap and the ground.
Physics: Q = −q ψ(centre) for the one cap; removing the upper cap gives the lower one more
of the ball's image and a smaller self-capacitance; the 3D solve on the axis is the
axisymmetric one within its estimate; a run moves less charge than the pair's (Niu et al.
2014), with figures on."""

import numpy as np
import pytest

pytest.importorskip("dolfinx")
pytest.importorskip("gmsh")

from mpi4py import MPI  # noqa: E402

from helpers import single_and_pair_runs  # noqa: E402
from shell_model import shell_device_toml  # noqa: E402
from tengfield.field import _dolfinx as dx_api  # noqa: E402
from tengfield.field import solve_position  # noqa: E402
from tengfield.scene import load_scene  # noqa: E402

COMM = MPI.COMM_SELF
pytestmark = pytest.mark.field


def shell(**device):
    """The shared shell's scene (tests/shell_model.py) with ``device`` keys changed."""
    extra = "".join(f"{k} = {v!r}\n".replace("'", '"') for k, v in device.items())
    return load_scene(shell_device_toml(extra=extra))


def solve(scene, z=6e-3, **kw):
    opts = {"mesh_size_mm": 1.0, "degree": 2, "estimate_error": False,
            "method": "axisymmetric", **kw}
    return solve_position(scene, z, comm=COMM, **opts)


def test_the_single_cap_takes_more_of_the_image_than_the_pairs_lower_cap():
    single, pair = solve(shell(electrodes="lower")), solve(shell())
    assert single.electrodes == ("lower",) and single.capacitance.shape == (1, 1)
    f_single, f_pair = -single.induced_fraction[0], -pair.induced_fraction[0]
    assert 0.0 < f_pair < f_single < 1.0, (f_pair, f_single)
    assert 0.0 < single.C_ll < pair.C_ll


def test_the_single_caps_charge_is_the_weighting_potential_at_the_centre():
    """Shockley–Ramo with a vacuum ball: Q = −q ψ_lower(centre)."""
    res = solve(shell(electrodes="lower", ball_permittivity=1.0), keep_solution=True)
    sol = res.solution
    assert len(sol.weighting) == 1
    centre = dx_api.point_values(sol.space, sol.weighting[0].x.array, [sol.ball_centre])[0]
    assert res.induced_charge[0] == pytest.approx(-res.ball_charge * centre, rel=2e-4)


def test_the_single_caps_3d_solve_on_the_axis_is_the_axisymmetric_one():
    """P1 at 2 mm in 3D (with its estimate) against P2 at 0.5 mm axisymmetric."""
    scene = shell(electrodes="lower")
    axi = solve(scene, mesh_size_mm=0.5, estimate_error=True)
    three = solve(scene, method="3d", mesh_size_mm=2.0, degree=1, estimate_error=True)
    assert three.electrodes == ("lower",) and axi.relative_error_estimate < 1e-3
    for ours, ref in ((three.C_ll, axi.C_ll), (three.induced_fraction[0],
                                                axi.induced_fraction[0])):
        assert abs(ours - ref) / abs(ref) <= three.relative_error_estimate, (ours, ref)


SMALL = ("[run]\nduration_s = 0.3\nsettle_periods = 2\nsample_rate_hz = 5000\n"
         "[field]\ndegree = 1\nmesh_size_mm = 1.5\ntolerance = 5e-2\n")


@pytest.mark.slow
def test_a_run_of_the_single_electrode_shell_moves_less_than_the_pairs(tmp_path, run_cli):
    """End to end with figures on: the single-electrode shell's run names its topology and
    moves less charge than the pair's (0.32 x measured), V_OC = Q_SC / C_T row by row."""
    import csv

    single, pair, out, _ = single_and_pair_runs(
        run_cli, tmp_path, lambda extra: shell_device_toml(extra=extra) + SMALL, timeout=600)
    for name in ("waveforms.png", "surrogate.png"):
        assert (out / name).stat().st_size > 10_000, name
    q_single, q_pair = single["peak_to_peak"]["Q_sc_C"], pair["peak_to_peak"]["Q_sc_C"]
    assert 0.0 < q_single < 0.8 * q_pair, (q_single, q_pair)
    with open(out / "waveforms.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    q, v, c = (np.array([float(r[k]) for r in rows]) for k in ("Q_sc_C", "V_oc_V", "C_T_F"))
    np.testing.assert_allclose(v * c, q, rtol=1e-6, atol=1e-9 * np.max(np.abs(q)))
