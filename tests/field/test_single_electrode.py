"""The single-electrode cell (``[device] electrodes = "lower"``, issue #51): the field of
any list of electrodes, here one. The terminals are the lower electrode and the ground
(``tengfield.terminals.LowerToGround``). Physics: the isolated disk's C = 8 ε0 a; Q = −q ψ
at the ball's centre; charge conservation between the electrode and the ground; the
single electrode transfers less than the pair (Niu et al., Adv. Funct. Mater. 24:3332,
2014); every other command refuses it in one line."""
import json
import math

import pytest

pytest.importorskip("dolfinx")
pytest.importorskip("gmsh")

import numpy as np  # noqa: E402
from mpi4py import MPI  # noqa: E402

from tengfield import terminals  # noqa: E402
from tengfield.errors import SceneError  # noqa: E402
from tengfield.field import _dolfinx as dx_api  # noqa: E402
from tengfield.field import solve_position  # noqa: E402
from tengfield.scene import EPS0, default_scene, with_settings  # noqa: E402

COMM = MPI.COMM_SELF
SINGLE = ["device.electrodes=lower"]
#: εr = 1 everywhere: the ball and the walls are invisible to the electrode's field
VACUUM = ["device.ball_permittivity=1", "device.wall_permittivity=1"]


def solve(scene, z, **kw):
    opts = {"mesh_size_mm": 0.8, "degree": 2, "estimate_error": False, **kw}
    return solve_position(scene, z, comm=COMM, method="axisymmetric", **opts)


def test_an_isolated_disk_is_8_eps0_a():
    """One disk of radius a in free space (Kelvin far field), nothing else conducting:
    C = 8 ε0 a (the anchor of DESIGN §8), within the solve's own error estimate."""
    scene = with_settings(default_scene(), SINGLE + VACUUM)
    res = solve(scene, 1.5e-3, estimate_error=True)
    exact = 8.0 * EPS0 * scene.device.electrode_radius
    assert res.capacitance.shape == (1, 1) and res.electrodes == ("lower",)
    error = abs(res.C_ll - exact) / exact
    assert error <= max(res.relative_error_estimate, 2e-4), (error, res.relative_error_estimate)
    assert error < 3e-3


@pytest.mark.parametrize("settings", [SINGLE, []], ids=["single", "pair"])
def test_each_electrodes_charge_is_the_weighting_potential_at_the_centre(settings):
    """Shockley–Ramo with a vacuum ball (ψ_k harmonic inside): Q_k = −q ψ_k(centre), for
    the single electrode as for the pair: the surface integral of the solve against an
    independent evaluation of its weighting potential."""
    scene = with_settings(default_scene(), settings + ["device.ball_permittivity=1"])
    res = solve(scene, 0.9e-3, keep_solution=True)
    sol = res.solution
    assert len(sol.weighting) == len(res.electrodes) == (1 if settings else 2)
    for k, psi in enumerate(sol.weighting):
        centre = dx_api.point_values(sol.space, psi.x.array, [sol.ball_centre])[0]
        assert res.induced_charge[k] == pytest.approx(-res.ball_charge * centre, rel=2e-4)


def test_the_electrode_and_the_ground_share_the_balls_image():
    """q_lower + q_ground = −q_ball: the electrode's charge by reciprocity (the surface
    integral of ψ) equals the reaction of the source solve on its dofs, and the ground
    (the far field) takes the rest, of the same sign, more as the ball rises."""
    scene = with_settings(default_scene(), SINGLE)
    low, high = (solve(scene, z, source_solve=True) for z in (0.0, scene.device.stroke))
    for res in (low, high):
        reaction = res.info["source_electrode_charge_C"]
        assert np.ravel(reaction) == pytest.approx(res.induced_charge, rel=2e-3)
        fraction = res.induced_charge[0] / res.ball_charge
        assert -1.0 < fraction < 0.0          # the ground's share −1 − fraction in (−1, 0)
    assert abs(high.induced_charge[0]) < abs(low.induced_charge[0])


def test_the_single_electrode_transfers_less_than_the_pair():
    """Niu et al. 2014: for the same ball and stroke the single-electrode cell moves less
    charge through its terminals than the pair (floating): Q_SC over the stroke and its
    open-circuit voltage's charge, positive for a PTFE ball rising (the pair's sign)."""
    single = with_settings(default_scene(), SINGLE)
    pair = default_scene()
    stroke = pair.device.stroke

    def transferred(scene):
        rest, top = solve(scene, 0.0), solve(scene, stroke)
        wiring = rest.wiring("floating")
        return float(wiring.terminal_charge(top.capacitance, top.induced_charge,
                                            top.ball_charge)
                     - wiring.terminal_charge(rest.capacitance, rest.induced_charge,
                                              rest.ball_charge))

    q_single, q_pair = transferred(single), transferred(pair)
    assert 0.0 < q_single < q_pair, (q_single, q_pair)


def test_the_topology_of_one_electrode_is_the_electrode_to_the_ground():
    """V_OC = Q_SC / C_T with C_T = C_ll: the open electrode's potential holding its
    reference charge, against the closed forms of LowerToGround."""
    wiring = terminals.wiring("floating", 1)
    C, q, q_ref = np.array([[0.4e-12]]), np.array([0.5e-9]), np.array([0.9e-9])
    V = wiring.open_potentials(C, q, wiring.reference_charges(C, q_ref, -1.2e-9))
    q_sc = wiring.terminal_charge(C, q, -1.2e-9) - wiring.terminal_charge(C, q_ref, -1.2e-9)
    assert terminals.terminal_voltage(V) == pytest.approx(q_sc / C[0, 0], rel=1e-14)
    assert q_sc > 0.0 and wiring.terminal_capacitance(C) == C[0, 0]
    assert terminals.wiring("grounded-lower", 2) is terminals.TOPOLOGIES["grounded-lower"]


def test_the_field_command_writes_the_single_electrode_with_figures(tmp_path, run_cli):
    scene = tmp_path / "single.toml"
    scene.write_text("[device]\nelectrodes = \"lower\"\n[field]\ndegree = 1\n"
                     "mesh_size_mm = 1.5\n")
    out = tmp_path / "out"
    proc = run_cli("field", scene, "--position-mm", "1.5", "-o", out, timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    data = json.loads((out / "field.json").read_text())
    assert list(data["capacitance_F"]) == ["lower_lower"]
    assert data["reference"] == "lower-to-ground"
    assert data["C_T_F"] == data["capacitance_F"]["lower_lower"]
    assert list(data["open_circuit_potential_V"]) == ["lower"]
    assert (out / "field.png").stat().st_size > 10_000
    assert "V_OC = V_lower (the ground at 0 V)" in proc.stdout


@pytest.mark.parametrize("settings, needle", [
    (["device.electrodes=upper"], r"\[device\] electrodes = 'upper' is not allowed"),
    (["device.shape=spherical-shell", "device.electrodes=lower"],
     r"not offered by shape = 'spherical-shell' yet: allowed 'both'"),
    (SINGLE + ["circuit.reference=grounded-lower"], r"has one topology"),
])
def test_bad_values_of_the_new_key_are_one_line(settings, needle):
    with pytest.raises(SceneError, match=needle) as info:
        with_settings(default_scene(), settings)
    assert "\n" not in str(info.value)


def test_the_commands_on_a_surrogate_refuse_it_before_the_work(tmp_path, run_cli):
    scene = tmp_path / "single.toml"
    scene.write_text("[device]\nelectrodes = \"lower\"\n")
    for command in (["run"], ["sweep", "--frequency-hz", "20:30:2", "--amplitude-mm", "1.5"],
                    ["design"], ["uncertainty"], ["breakdown"], ["precompute"]):
        out = tmp_path / command[0]
        proc = run_cli(command[0], scene, *command[1:], "-o", out, timeout=300)
        errors = [x for x in proc.stderr.splitlines() if x.startswith("tengfield: error")]
        assert proc.returncode == 2 and len(errors) == 1, (command, proc.stderr[-1500:])
        assert "electrodes = 'lower' (the single-electrode cell)" in errors[0]
        assert not out.exists()
    unchanged = default_scene()
    assert unchanged.field_hash() == with_settings(unchanged, ["device.electrodes=both"]).field_hash()
