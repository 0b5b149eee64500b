"""The single-electrode cell (``[device] electrodes = "lower"``, issue #51): the field of
any list of electrodes, here one. The terminals are the lower electrode and the ground
(``tengfield.terminals.LowerToGround``). Physics: the isolated disk's C = 8 ε0 a; Q = −q ψ
at the ball's centre; charge conservation between the electrode and the ground; the
single electrode transfers less than the pair (Niu et al., Adv. Funct. Mater. 24:3332,
2014); every shape lists its electrodes (the 3D and off-axis field:
tests/field/test_single_electrode_3d.py; the shell's: test_single_electrode_shell.py)."""
import json
import math

import pytest

pytest.importorskip("dolfinx")
pytest.importorskip("gmsh")

import numpy as np  # noqa: E402
from mpi4py import MPI  # noqa: E402

from helpers import single_and_pair_runs  # noqa: E402

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
    (["device.electrodes=3"], r"\[device\] electrodes = 3: expected a string"),
    (SINGLE + ["circuit.reference=grounded-lower"], r"has one topology"),
])
def test_bad_values_of_the_new_key_are_one_line(settings, needle):
    with pytest.raises(SceneError, match=needle) as info:
        with_settings(default_scene(), settings)
    assert "\n" not in str(info.value)


SMALL = ("[run]\nduration_s = 0.3\nsettle_periods = 2\nsample_rate_hz = 5000\n"
         "[field]\ndegree = 1\nmesh_size_mm = 1.5\ntolerance = 1e-2\n")


def test_a_run_of_the_single_electrode_cell_transfers_less_than_the_pairs(tmp_path, run_cli):
    """End to end with figures on: the single-electrode cell's run reports its topology,
    V_OC = Q_SC / C_T row by row, and moves less charge than the pair's run of the same
    scene (Niu et al. 2014: 0.68 x here)."""
    import csv

    single, pair, out, proc = single_and_pair_runs(
        run_cli, tmp_path, lambda extra: SMALL + (f"[device]\n{extra}\n" if extra else ""),
        timeout=300)
    assert "(lower-to-ground reference)" in proc.stdout
    assert (out / "waveforms.png").stat().st_size > 10_000
    assert (out / "surrogate.png").stat().st_size > 10_000
    q_single = single["peak_to_peak"]["Q_sc_C"]
    q_pair = pair["peak_to_peak"]["Q_sc_C"]
    assert 0.0 < q_single < 0.8 * q_pair, (q_single, q_pair)
    with open(out / "waveforms.csv", newline="") as f:
        rows = [r for r in csv.DictReader(f)]
    v = np.array([float(r["V_oc_V"]) for r in rows])
    q = np.array([float(r["Q_sc_C"]) for r in rows])
    c = np.array([float(r["C_T_F"]) for r in rows])
    np.testing.assert_allclose(v * c, q, rtol=1e-6, atol=1e-9 * np.max(np.abs(q)))


@pytest.mark.slow
def test_the_studies_run_the_single_electrode_cell_with_figures(tmp_path, run_cli):
    scene = tmp_path / "single.toml"
    scene.write_text(SMALL + '[device]\nelectrodes = "lower"\n')
    for command in (["sweep", "--frequency-hz", "20:30:2", "--amplitude-mm", "1.5"],
                    ["sweep", "--vary", "device.stroke_mm=2,3"],
                    ["design", "--candidates", "4", "--seed", "1"], ["uncertainty"],
                    ["precompute"], ["run", "--set", "circuit.kind=rectifier"],
                    ["run", "--spice"], ["run", "--set", "array.cells=3",
                                         "--set", "array.restitution_spread=0.05"]):
        out = tmp_path / "-".join(command[:2])
        proc = run_cli(command[0], scene, *command[1:], "-o", out, "--cache-dir",
                       tmp_path / "cache", timeout=600)
        assert proc.returncode == 0, (command, proc.stderr[-2000:])
        if out.is_dir():       # precompute -o names its surrogate file
            assert any(p.suffix == ".png" for p in out.iterdir()), (command, list(out.iterdir()))
        else:
            assert out.stat().st_size > 0


def test_every_shape_lists_its_electrodes():
    """The tube, the honeycomb and the spherical shell each offer the pair and the lower
    electrode alone (the shell's: tests/field/test_single_electrode_shell.py)."""
    for shape in ("tube", "hexagonal", "spherical-shell"):
        scene = with_settings(default_scene(), [f"device.shape={shape}"] + SINGLE)
        assert scene.device.electrode_names == ("lower",)
        pair = with_settings(default_scene(), [f"device.shape={shape}"])
        assert pair.device.electrode_names == ("lower", "upper")


def test_the_pairs_field_hash_is_the_one_before_the_key():
    unchanged = default_scene()
    assert unchanged.field_hash() == with_settings(unchanged, ["device.electrodes=both"]).field_hash()
    assert unchanged.field_hash() != with_settings(unchanged, SINGLE).field_hash()


@pytest.mark.slow
def test_mpirun_runs_and_sweeps_the_single_electrode_cell_as_serial(tmp_path, cli_command,
                                                                   cli_env):
    """``mpirun -n 2`` of a run and of a ``--vary`` sweep of the single-electrode cell write
    the serial waveforms.csv and sweep.csv byte for byte (each from its own cold cache)."""
    import shutil
    import subprocess

    mpirun = shutil.which("mpirun")
    if mpirun is None:
        pytest.skip("mpirun not installed")
    scene = tmp_path / "single.toml"
    scene.write_text(SMALL + '[device]\nelectrodes = "lower"\n')
    for command, written in ((["run"], "waveforms.csv"),
                             (["sweep", "--vary", "device.stroke_mm=2,3"], "sweep.csv")):
        files = []
        for ranks in (1, 2):
            env = cli_env(OMPI_MCA_rmaps_base_oversubscribe="1", MPLBACKEND="Agg",
                          PRTE_MCA_rmaps_default_mapping_policy=":oversubscribe",
                          TENGFIELD_CACHE_DIR=tmp_path / f"cache-{command[0]}-{ranks}")
            env.pop("OMPI_COMM_WORLD_SIZE", None)
            out = tmp_path / f"{command[0]}-{ranks}"
            argv = cli_command(command[0], scene, *command[1:], "-o", out)
            if ranks > 1:
                argv = [mpirun, "-n", str(ranks), *argv]
            proc = subprocess.run(argv, capture_output=True, text=True, env=env, timeout=600)
            assert proc.returncode == 0, (command, ranks, proc.stderr[-3000:])
            files.append((out / written).read_bytes())
        assert files[0] == files[1], command


def test_the_single_electrodes_breakdown_limit_has_its_own_gap_lines(tmp_path, run_cli):
    """The gap lines of one electrode: only the lower side is a gap (the upper faces the
    bare plate); a run at σ = "breakdown" peaks at |V_gap| / V_b = 1 there (within the
    trajectory's sampling), the limit binds on the lower gap, and `tengfield breakdown`
    writes its files with figures."""
    scene = tmp_path / "single.toml"
    scene.write_text(SMALL + '[device]\nelectrodes = "lower"\nsurface_charge_uC_per_m2 = '
                     '"breakdown"\n')
    out = tmp_path / "run"
    proc = run_cli("run", scene, "-o", out, "--cache-dir", tmp_path / "cache", timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    block = json.loads((out / "summary.json").read_text())["breakdown"]
    assert block["binding"]["gap"] == "lower"
    assert -block["sigma_uC_per_m2"] == pytest.approx(block["sigma_max_uC_per_m2"], rel=1e-12)
    ratio = block["trajectory"]["peak_gap_voltage_over_breakdown"]
    assert 0.99 < ratio <= 1.0 + 1e-9, ratio
    binding = block["binding"]
    assert binding["gap_voltage_at_sigma_max_V"] == pytest.approx(binding["breakdown_voltage_V"],
                                                                  rel=1e-9)
    out = tmp_path / "breakdown"
    proc = run_cli("breakdown", scene, "-o", out, "--cache-dir", tmp_path / "cache",
                   timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert (out / "breakdown.png").stat().st_size > 10_000
    assert "upper gap" not in proc.stdout


CONTACT = {"model": "contact", "equilibrium_uC_per_m2": -20.0, "efficiency": 0.3,
           "discharge": "none"}


def _small(**sections):
    import tomllib

    base = tomllib.loads(SMALL)
    scene = default_scene().with_values(**{**base, **sections})
    return with_settings(scene, SINGLE)


def test_a_contact_charged_single_electrode_at_equilibrium_is_the_constant_run(tmp_path):
    import tengfield as tf

    constant = tf.run(_small(device={"surface_charge_uC_per_m2": -20.0}), cache_dir=tmp_path)
    contact = tf.run(_small(charge={**CONTACT, "initial_uC_per_m2": -20.0}),
                     cache_dir=tmp_path)
    assert contact.summary["reference"] == "lower-to-ground"
    for key in ("Q_sc_C", "I_sc_A", "V_oc_V"):
        ours, theirs = contact.waveforms[key], constant.waveforms[key]
        assert np.max(np.abs(ours - theirs)) <= 1e-12 * np.max(np.abs(theirs)), key


def test_the_single_electrodes_wire_carries_what_the_electrode_gives_up(tmp_path):
    """Bookkeeping of one electrode: shorted it holds q f_l(z) and it gives every contact's
    gain to the ball, so the wire has carried Q_SC = f_l(0) q0 − f_l(z) q(t) − D(t) to the
    ground (D: the gains); checked at the table's own positions against its fractions
    (exact there), with leakage; the bare upper plate's impacts charge nothing; and I_SC is
    dQ_SC/dt between contacts."""
    import tengfield as tf
    from tengfield.contact_run import contact_source, field_scene
    from tengfield.surrogate import obtain_table

    scene = _small(charge={**CONTACT, "leakage_time_s": 0.05, "initial_uC_per_m2": -5.0},
                   excitation={"frequency_hz": 30.0, "amplitude_mm": 1.0})
    out = tf.run(scene, cache_dir=tmp_path)
    plates = np.asarray(out.dynamics.impacts.plate)
    assert np.any(plates == "upper")                    # the ball does hit the bare plate
    assert out.summary["charge"]["contacts"] == int(np.sum(plates == "lower"))
    table, _ = obtain_table(field_scene(scene), cache_dir=tmp_path)
    run = contact_source(scene, out.dynamics, table)
    terminal, history = run.curves.terminal, run.history
    fractions = table.induced_fraction[:, 0]
    t = np.linspace(0.0, scene.run.duration, table.positions.size)
    q = history.at(t)
    gained = np.array([np.sum(history.gains[history.times <= x]) for x in t])
    expected = fractions[0] * history.start - fractions * q - gained
    got = terminal.evaluate(t, table.positions, np.zeros_like(t))[0]
    np.testing.assert_allclose(got, expected, rtol=1e-10, atol=1e-12 * np.max(np.abs(expected)))
    time, charge, current = (out.waveforms[k] for k in ("time_s", "Q_sc_C", "I_sc_A"))
    impacts = np.asarray(out.dynamics.impacts.time) - float(out.dynamics.t[0]) + float(time[0])
    near = np.zeros_like(time, dtype=bool)
    for c in impacts:
        near |= np.abs(time - c) < 1.5 * (time[1] - time[0])
    slope = np.gradient(charge, time)
    assert np.median(np.abs(slope - current)[~near]) < 1e-3 * np.abs(current).max()


def test_a_pairs_mesh_is_never_mapped_onto_one_electrode():
    """The mesh-mapping family (``[field] mesh_motion = "move"``: a canonical geometry's
    template mapped onto another's) names the conductors: the pair's and the single
    electrode's layouts of one geometry are of different families, the tube's and the
    shell's."""
    from tengfield.field import geometry_axisymmetric as geometry
    from tengfield.field import moving
    from tengfield.field.cells import cell_of

    pair, single = default_scene(), with_settings(default_scene(), SINGLE)
    families = [moving.geometry_family(geometry.layout(s, 1e-3)) for s in (pair, single)]
    assert families[0] != families[1]
    shell = ["device.shape=spherical-shell", "device.cavity_diameter_mm=20",
             "device.ball_diameter_mm=8", "device.stroke_mm=12", "device.electrode_band_mm=2",
             "device.shell_thickness_mm=2"]
    layouts = [cell_of(with_settings(default_scene(), shell + extra)).axisymmetric_layout(
        3e-3, mesh_size=1e-3) for extra in ([], SINGLE)]
    assert layouts[1].electrodes == ("lower",)
    assert moving.geometry_family(layouts[0]) != moving.geometry_family(layouts[1])
