"""Issue 52, studies: ``sweep`` (its points, ``--vary charge.*``) and ``uncertainty``
(``[uncertainty.vary]`` draws of ``charge.*``) with ``[charge] model = "contact"`` give,
at each point or draw, the numbers ``tengfield run`` gives at those values
(``tengfield.contact_run.contact_source``, one function for all three); a ``charge.*``
key that cannot act (a constant charge) is refused in one line; the CLI end to end with
figures on, and ``mpirun -n 2`` equal to serial."""
from __future__ import annotations

import csv
import json
import subprocess

import pytest

import tengfield as tf
from tengfield.sweeps import sweep_study

import plate_model as fx
from helpers import serial_and_mpirun

RUN = {"duration_s": 2.0, "settle_periods": 4, "sample_rate_hz": 2000.0}
CHARGE = {"model": "contact", "discharge": "none", "equilibrium_uC_per_m2": -100.0}
TERMINAL = [("V_oc_pp_V", "V_oc_V"), ("Q_sc_pp_C", "Q_sc_C"), ("I_sc_pp_A", "I_sc_A")]


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("surrogates")


def _run(scene, cache):
    return tf.run(scene, cache_dir=cache, solve=fx.plate_model_solve)


@pytest.mark.parametrize("circuit", [{"kind": "open"}, {"kind": "load", "load_ohm": 3e8}])
def test_a_sweep_row_is_the_run_at_its_values(cache, circuit):
    """Each row of ``--vary charge.efficiency`` (and of charge.leakage_time_s) holds the
    run's peak-to-peak values, its load's power, its steady charge and rise time (1e-12)."""
    base = fx.scene_with(run=RUN, charge=CHARGE, circuit=circuit)
    vary = {"charge.efficiency": [0.05, 0.4], "charge.leakage_time_s": [0.0, 0.5]}
    rows = sweep_study(base, vary=vary, cache_dir=cache, solve=fx.plate_model_solve)
    assert len(rows) == 4
    assert {"sigma_steady_uC_per_m2", "rise_time_90_s", "charge_binds"} <= set(rows.columns)
    for row in rows:
        run = _run(base.with_values(charge={"efficiency": row["charge.efficiency"],
                                            "leakage_time_s": row["charge.leakage_time_s"]}),
                   cache)
        for column, name in TERMINAL:
            assert row[column] == pytest.approx(run.summary["peak_to_peak"][name], rel=1e-12)
        block = run.summary["charge"]
        assert row["sigma_steady_uC_per_m2"] == pytest.approx(block["steady_uC_per_m2"],
                                                              rel=1e-12)
        assert row["charge_binds"] == block["binds"]
        if block["rise_time_90_s"] is None:
            assert row["rise_time_90_s"] is None
        else:
            assert row["rise_time_90_s"] == pytest.approx(block["rise_time_90_s"], rel=1e-12)
        if circuit["kind"] == "load":
            assert row["P_mean_W"] == pytest.approx(run.summary["load"]["mean_power_W"],
                                                    rel=1e-12)


def test_doubling_the_efficiency_halves_the_rise_time_where_the_contacts_are_small(cache):
    """S << A, no leakage, no cap: q_n = q_eq (1 - (1 - eta S/A)^n), so the contacts to 90 %
    scale as 1/eta (to O(eta S/A)); the steady charge is sigma_eq at every eta."""
    base = fx.scene_with(run=RUN, charge=CHARGE)
    rows = sweep_study(base, vary={"charge.efficiency": [0.02, 0.04, 0.08]}, cache_dir=cache,
                       solve=fx.plate_model_solve)
    rise = [row["rise_time_90_s"] for row in rows]
    assert rise[0] / rise[1] == pytest.approx(2.0, rel=0.01)
    assert rise[1] / rise[2] == pytest.approx(2.0, rel=0.01)
    for row in rows:
        assert row["sigma_steady_uC_per_m2"] == pytest.approx(-100.0, rel=1e-9)
    # the output grows with the charge the run has reached: eta doubles it while q << q_eq
    v = [row["V_oc_pp_V"] for row in rows]
    assert v[1] / v[0] == pytest.approx(2.0, rel=0.05) and v[2] > v[1]


def test_a_longer_leakage_time_holds_the_steady_charge_nearer_sigma_eq(cache):
    """--vary charge.leakage_time_s: the steady share of sigma_eq grows with tau toward 1
    (the fixed point q_eq r / (r + 1/tau) for small contacts; its exact form is tested on
    the run in test_contact_run.py), each row the run's share (1e-12)."""
    base = fx.scene_with(run=RUN, charge={**CHARGE, "efficiency": 0.3})
    rows = sweep_study(base, vary={"charge.leakage_time_s": [0.05, 0.2, 1.0]},
                       cache_dir=cache, solve=fx.plate_model_solve)
    shares = [row["sigma_steady_uC_per_m2"] / -100.0 for row in rows]
    assert 0.0 < shares[0] < shares[1] < shares[2] < 1.0
    assert all("leakage" in row["charge_binds"] for row in rows)
    block = _run(base.with_values(charge={"leakage_time_s": 0.2}), cache).summary["charge"]
    assert block["contacts"] > 20
    assert shares[1] == pytest.approx(block["share_of_equilibrium"], rel=1e-12)


def test_a_charge_key_that_cannot_act_is_refused_in_one_line(cache):
    """A constant charge ignores [charge] efficiency, sigma_eq, tau: varying them would give
    identical rows, so ``sweep --vary`` and ``[uncertainty.vary]`` refuse them up front."""
    constant = fx.scene_with(run=RUN)
    with pytest.raises(tf.TengfieldError, match=r"--vary charge.efficiency: \[charge\] "
                       r"efficiency acts only with \[charge\] model = \"contact\""):
        sweep_study(constant, vary={"charge.efficiency": [0.1, 0.2]}, cache_dir=cache,
                    solve=fx.plate_model_solve)
    drawn = constant.with_values(uncertainty={"samples": 16, "vary": {
        "charge.efficiency": {"distribution": "uniform", "low": 0.1, "high": 0.3}}})
    with pytest.raises(tf.TengfieldError, match=r"acts only with \[charge\] model"):
        tf.uncertainty(drawn, cache_dir=cache, solve=fx.plate_model_solve)


def test_an_uncertainty_study_draws_the_charging_physics(cache):
    """[uncertainty.vary] draws eta and sigma_eq: the nominal evaluation and each draw are
    the run at those values (1e-12), the outputs include the steady charge and rise time,
    and the rise time depends on eta (its largest total index)."""
    scene = fx.scene_with(run=RUN, charge={**CHARGE, "efficiency": 0.2}, uncertainty={
        "samples": 16, "vary": {
            "charge.efficiency": {"distribution": "uniform", "low": 0.05, "high": 0.5},
            "charge.equilibrium_uC_per_m2": {"distribution": "uniform", "low": -150.0,
                                             "high": -50.0}}})
    study = tf.uncertainty(scene, cache_dir=cache, solve=fx.plate_model_solve)
    outputs = study.summary["outputs"]
    assert {"charge.steady_uC_per_m2", "charge.rise_time_90_s"} <= set(outputs)
    nominal = _run(scene, cache)
    assert outputs["peak_to_peak.V_oc_V"]["nominal"] == pytest.approx(
        nominal.summary["peak_to_peak"]["V_oc_V"], rel=1e-12)
    assert outputs["charge.steady_uC_per_m2"]["nominal"] == pytest.approx(
        nominal.summary["charge"]["steady_uC_per_m2"], rel=1e-12)
    keys = study.spec.keys
    for k in (0, 5):
        drawn = dict(zip(keys, study.values[k]))
        run = _run(scene.with_values(charge={"efficiency": drawn["charge.efficiency"],
                                             "equilibrium_uC_per_m2":
                                                 drawn["charge.equilibrium_uC_per_m2"]}), cache)
        row = study.evaluations.rows[k]
        assert row["peak_to_peak.Q_sc_C"] == pytest.approx(
            run.summary["peak_to_peak"]["Q_sc_C"], rel=1e-12)
        assert row["charge.steady_uC_per_m2"] == pytest.approx(
            drawn["charge.equilibrium_uC_per_m2"], rel=1e-9)      # no cap, no leakage
    sobol = outputs["charge.rise_time_90_s"]["sobol"]
    assert max(sobol, key=lambda name: sobol[name]["ST"]) == "charge.efficiency"


CONTACT_SCENE = fx.SMALL_SCENE + '\n[charge]\nmodel = "contact"\nefficiency = 0.3\n'


def test_cli_sweep_and_uncertainty_of_the_contact_charge_with_figures(tmp_path, cli_command,
                                                                      cli_env):
    """The real field (coarse, the breakdown cap of the band's estimate): ``sweep --vary
    charge.efficiency`` writes the charge columns and a figure with the steady-charge panel,
    its rows equal to ``run``; ``uncertainty`` over eta writes its figure with the charge."""
    scene = tmp_path / "contact.toml"
    scene.write_text(CONTACT_SCENE + "[uncertainty]\nsamples = 16\n[uncertainty.vary]\n"
                     '"charge.efficiency" = { distribution = "uniform", low = 0.1, '
                     "high = 0.6 }\n")
    env = cli_env(TENGFIELD_CACHE_DIR=tmp_path / "cache")
    sweep = subprocess.run(cli_command("sweep", scene, "--vary", "charge.efficiency=0.1,0.6",
                                       "-o", tmp_path / "sweep"),
                           capture_output=True, text=True, env=env, timeout=600)
    assert sweep.returncode == 0, sweep.stderr
    with open(tmp_path / "sweep" / "sweep.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 2 and "sigma_steady_uC_per_m2" in rows[0]
    png = (tmp_path / "sweep" / "sweep_charge.efficiency.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 20_000
    run = subprocess.run(cli_command("run", scene, "--set", "charge.efficiency=0.6", "-o",
                                     tmp_path / "run"),
                         capture_output=True, text=True, env=env, timeout=600)
    assert run.returncode == 0, run.stderr
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert float(rows[1]["V_oc_pp_V"]) == pytest.approx(summary["peak_to_peak"]["V_oc_V"],
                                                        rel=1e-12)
    assert float(rows[1]["sigma_steady_uC_per_m2"]) == pytest.approx(
        summary["charge"]["steady_uC_per_m2"], rel=1e-12)
    unc = subprocess.run(cli_command("uncertainty", scene, "-o", tmp_path / "unc"),
                         capture_output=True, text=True, env=env, timeout=600)
    assert unc.returncode == 0, unc.stderr
    assert "steady ball charge σ [µC/m²]" in unc.stdout
    assert "exceeds the air-breakdown limit" not in unc.stderr   # sigma_eq: the cap holds
    png = (tmp_path / "unc" / "uncertainty.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 50_000


@pytest.mark.slow
def test_mpirun_sweeps_the_serial_rows(tmp_path, cli_command, cli_env):
    """``mpirun -n 2 tengfield sweep --vary charge.efficiency`` writes the serial sweep.csv
    byte for byte."""
    scene = tmp_path / "contact.toml"
    scene.write_text(CONTACT_SCENE)
    serial_and_mpirun(cli_command, cli_env, tmp_path, "sweep", scene, "--vary",
                      "charge.efficiency=0.1:0.9:3", "--no-plots", shared_cache=True)
    assert (tmp_path / "one" / "sweep.csv").read_bytes() == \
        (tmp_path / "two" / "sweep.csv").read_bytes()


def _design_scene(charge, **design_keys):
    section = {"objective": "power", "candidates": 4, "seed": 1, "settle_periods": 10,
               "window_periods": 10, "samples_per_period": 120,
               "vary": {"stroke_mm": [1.0, 4.0]},
               "excitation": {"frequency_hz": [20.0, 25.0], "amplitude_mm": [1.5]}}
    section.update(design_keys)
    return fx.scene_with(design=section, charge=charge)


def test_a_design_scores_each_band_point_at_the_steady_charge_its_contacts_make(cache):
    """``[charge] model = "contact"`` in ``design``: each candidate's band point is scored at
    the plateau its own impacts reach (the steady charge along its trajectory), i.e. the
    constant model at that sigma (1e-12); with leakage the plateau depends on the impacts,
    so it differs from stroke to stroke and from band point to band point."""
    from tengfield.design_study import evaluate, parse_design_section

    scene = _design_scene({**CHARGE, "efficiency": 0.3, "leakage_time_s": 0.3},
                          objective="charge")
    result = tf.design(scene, cache_dir=cache, solve=fx.plate_model_solve, jobs=1)
    ok = [row for row in result.rows if row["status"] == "ok"]
    assert len(ok) == 4
    steady = [tuple(row["charge"]["steady_uC_per_m2"]) for row in ok]
    assert len({s for band in steady for s in band}) == 8   # every point its own plateau
    for band in steady:
        assert all(-100.0 < s < 0.0 for s in band)          # leakage holds it below sigma_eq
    row = ok[0]
    spec = parse_design_section(scene)
    for k, (f, a) in enumerate(spec.band):
        constant = fx.scene_with(device={"surface_charge_uC_per_m2":
                                         row["charge"]["steady_uC_per_m2"][k]},
                                 design={**scene.raw["design"], "excitation": {
                                     "frequency_hz": [f * 1.0], "amplitude_mm": [a * 1e3]}})
        alone = evaluate(constant, parse_design_section(constant), row["values"],
                         cache_dir=cache, solve=fx.plate_model_solve)
        assert row["band_values"]["charge"][k] == pytest.approx(
            alone["band_values"]["charge"][0], rel=1e-12)


def test_a_contact_design_refuses_what_it_cannot_score_in_one_line(cache):
    with pytest.raises(tf.TengfieldError, match=r'aggregate = "p10" with \[charge\] model = '
                                                r'"contact": not supported yet'):
        tf.design(_design_scene(CHARGE, aggregate="p10").with_values(uncertainty={
            "samples": 16, "vary": {"contact.restitution": {"distribution": "uniform",
                                                            "low": 0.4, "high": 0.6}}}),
                  cache_dir=cache, solve=fx.plate_model_solve, jobs=1)
    # a cap needs the breakdown lines: a 3D field has none (refused before the first solve)
    with pytest.raises(tf.TengfieldError, match=r"\[charge\] discharge = 'estimate'"):
        tf.design(_design_scene({"model": "contact"}).with_values(field={"method": "3d"}),
                  cache_dir=cache, solve=fx.plate_model_solve, jobs=1)


def test_cli_design_with_the_contact_charge_and_figures(tmp_path, cli_command, cli_env):
    """``tengfield design`` end to end (the real field, coarse, the cap of the band's
    estimate): the terminal names the steady charge each candidate is scored at and its
    rise time, best.toml says how long a run takes to reach it, design.png is drawn."""
    scene = tmp_path / "design.toml"
    scene.write_text(CONTACT_SCENE.replace("efficiency = 0.3", "efficiency = 0.5\n"
                                           "leakage_time_s = 1.0")
                     + "[design]\nobjective = \"power\"\ncandidates = 4\nsettle_periods = 10\n"
                     "window_periods = 10\n[design.vary]\nstroke_mm = [1.0, 4.0]\n"
                     "[design.excitation]\nfrequency_hz = [20.0]\namplitude_mm = [1.5]\n")
    done = subprocess.run(cli_command("design", scene, "-o", tmp_path / "out"),
                          capture_output=True, text=True, timeout=900,
                          env=cli_env(TENGFIELD_CACHE_DIR=tmp_path / "cache"))
    assert done.returncode == 0, done.stderr
    assert "(the steady charge its contacts make, at the band point; 90 % of it after" \
        in done.stdout
    best = (tmp_path / "out" / "best.toml").read_text()
    assert "# [charge]: scored at the steady charge its contacts make there" in best
    tf.load_scene(tmp_path / "out" / "best.toml")          # loads back
    png = (tmp_path / "out" / "design.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 20_000
    best_block = json.loads((tmp_path / "out" / "design.json").read_text())["best"]
    charge = best_block["charge"]
    assert len(charge["steady_uC_per_m2"]) == 1 and charge["steady_uC_per_m2"][0] < 0
    assert best_block["surface_charge_uC_per_m2"] == pytest.approx(
        charge["steady_uC_per_m2"][0], rel=1e-12)


@pytest.mark.slow
def test_mpirun_uncertainty_writes_the_serial_csv_with_figures(tmp_path, cli_command,
                                                               cli_env):
    """``mpirun -n 2 tengfield uncertainty`` over the charging physics (eta, tau) with
    ``[charge] model = "contact"``, figures on: the serial uncertainty.csv byte for byte.
    The mpirun run starts from an empty cache: its field is solved in one rank's task
    (PETSc initialised on every rank first; it hung there before)."""
    scene = tmp_path / "contact.toml"
    scene.write_text(CONTACT_SCENE + "[uncertainty]\nsamples = 16\nseed = 3\n"
                     "[uncertainty.vary]\n"
                     '"charge.efficiency" = { distribution = "uniform", low = 0.1, '
                     "high = 0.6 }\n"
                     '"charge.leakage_time_s" = { distribution = "uniform", low = 0.05, '
                     "high = 1.0 }\n")
    serial_and_mpirun(cli_command, cli_env, tmp_path, "uncertainty", scene)
    one_csv = (tmp_path / "one" / "uncertainty.csv").read_bytes()
    assert one_csv == (tmp_path / "two" / "uncertainty.csv").read_bytes()
    with open(tmp_path / "one" / "uncertainty.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 16 * 4                       # Saltelli: N (k + 2), k = 2
    steady = [float(row["charge.steady_uC_per_m2"]) for row in rows]
    assert len(set(steady)) > 16 and all(s < 0.0 for s in steady)   # leakage: each its own
    for name in ("one", "two"):
        png = (tmp_path / name / "uncertainty.png").read_bytes()
        assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 50_000


#: design.csv's columns that depend on the machine and the cache, not on the result
#: (tests/design/test_design_mpi.py): whether the candidate's field was read or solved, and
#: the wall times
MACHINE_COLUMNS = ("field_status", "field_wall_s", "dynamics_wall_s", "circuit_wall_s")


@pytest.mark.slow
def test_mpirun_design_writes_the_serial_rows_with_figures(tmp_path, cli_command, cli_env):
    """``mpirun -n 2 tengfield design`` with ``[charge] model = "contact"``, figures on:
    design.csv equal to the serial one in every column but :data:`MACHINE_COLUMNS`
    (compared as text, exactly), the same best candidate in design.json."""
    scene = tmp_path / "design.toml"
    scene.write_text(CONTACT_SCENE.replace("efficiency = 0.3", "efficiency = 0.5\n"
                                           "leakage_time_s = 0.5")
                     + "[design]\nobjective = \"power\"\ncandidates = 4\nbatch = 2\nseed = 2\n"
                     "settle_periods = 10\nwindow_periods = 10\n[design.vary]\n"
                     "stroke_mm = [1.0, 4.0]\n[design.excitation]\nfrequency_hz = [20.0]\n"
                     "amplitude_mm = [1.5]\n")
    serial_and_mpirun(cli_command, cli_env, tmp_path, "design", scene, serial=("--jobs", "1"),
                      timeout=900)

    def rows_of(name):
        with open(tmp_path / name / "design.csv", newline="") as f:
            rows = list(csv.DictReader(f))
        return [{k: v for k, v in row.items() if k not in MACHINE_COLUMNS} for row in rows]

    one, two_rows = rows_of("one"), rows_of("two")
    assert len(one) == 4 and one == two_rows
    assert sum(row["status"] == "ok" for row in one) == 4
    # each stroke scored at its own plateau (leakage: the impacts set it), below sigma_eq
    steady = [float(row["surface_charge_uC_per_m2"]) for row in one]
    assert len(set(steady)) == 4 and all(-113.0 < s < 0.0 for s in steady)
    best = [json.loads((tmp_path / name / "design.json").read_text())["best"]
            for name in ("one", "two")]
    assert best[0] == best[1] and best[0]["charge"]["steady_uC_per_m2"][0] < 0.0
    for name in ("one", "two"):
        png = (tmp_path / name / "design.png").read_bytes()
        assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 20_000
