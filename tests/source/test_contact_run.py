"""Issue 52: a run whose contacts make the ball's charge ([charge] model = "contact").

The wire's transfer against an independent closed form (Shockley–Ramo between wide
plates, the charge conserved electrode by electrode), the identities (a ball that starts
at sigma_eq and neither leaks nor is capped is the constant model, on every circuit), and
the CLI end to end with figures on."""
from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import tengfield as tf
from tengfield.field.result import PositionResult
from tengfield.scene import EPS0
from tengfield.source.charge import ContactCharging, charge_history
from tengfield.source.terminal import ContactTerminal
from tengfield.surrogate.table import table_from_results

import plate_model as fx
from helpers import serial_and_mpirun

RUN = {"duration_s": 0.4, "settle_periods": 3, "sample_rate_hz": 5000.0}


def _wide_plates(scene, position):
    """Pure Shockley–Ramo plates: the ball's induced charges -q z_c/h (upper) and
    -q (1 - z_c/h) (lower), and a capacitance matrix with strays to the environment."""
    dev = scene.device
    h = dev.plate_spacing
    c0 = EPS0 * math.pi * dev.electrode_radius ** 2 / h
    u = (position + dev.ball_radius) / h
    q = dev.ball_charge
    c_ll, c_lu, c_uu = 1.3 * c0, -c0, 1.2 * c0   # k = c_u/(c_l + c_u): exact in the splines
    return PositionResult(position=float(position), offset=0.0,
                          capacitance=[[c_ll, c_lu], [c_lu, c_uu]],
                          induced_charge=[-q * (1.0 - u), -q * u], ball_charge=q,
                          dofs=1, cells=1, method="axisymmetric", degree=1, wall_time=0.0,
                          relative_error_estimate=0.0, solve_time=0.0)


def _plates_table(scene):
    stroke = scene.device.stroke
    return table_from_results([_wide_plates(scene, z) for z in np.linspace(0.0, stroke, 9)],
                              stroke=stroke)


@settings(max_examples=40, deadline=None)
@given(st.integers(1, 40), st.floats(0.05, 1.0), st.floats(0.0, 2.0), st.integers(0, 2**31),
       st.sampled_from(["floating", "grounded-lower"]))
def test_the_wire_carries_what_the_electrodes_conserve_between_wide_plates(
        contacts, efficiency, leak, seed, reference):
    """Q_SC(t) = Q_u(t) - Q_u(0) + U(t) (the upper electrode's charge changes through the wire
    or by a contact), with Q_u = -q z_c/h + k (Q_e + q) between wide plates (k = c_u /
    (c_l + c_u) of the floating pair, 0 with the lower grounded) and Q_e + q = -(what the
    ball lost to the air): computed here from the electrodes, not from the module's formula."""
    scene = fx.scene_with(device={"surface_charge_uC_per_m2": -30.0})
    table = _plates_table(scene)
    rng = np.random.default_rng(seed)
    A = math.pi * scene.device.ball_diameter ** 2
    law = ContactCharging(equilibrium=-100e-6, efficiency=efficiency, ball_area=A,
                          initial=-5e-6, leakage_time=leak)
    times = np.sort(rng.uniform(0.0, 1.0, contacts))
    areas = rng.uniform(0.01, 0.3, contacts) * A
    upper = rng.random(contacts) < 0.5
    history = charge_history(law, times, areas)
    terminal = ContactTerminal(table, history, upper, reference)

    t = rng.uniform(0.0, 1.2, 50)
    z = rng.uniform(0.0, scene.device.stroke, 50)
    q_sc = terminal.evaluate(t, z, np.zeros_like(z))[0]

    dev = scene.device
    h, R = dev.plate_spacing, dev.ball_radius
    q = history.at(t)
    counted = np.searchsorted(times, t, side="right")
    gains = history.gains
    took = np.array([gains[:n].sum() for n in counted])             # D(t)
    took_upper = np.array([gains[:n][upper[:n]].sum() for n in counted])   # U(t)
    lost = history.start + took - q                                  # to the air
    if reference == "floating":
        c = np.array([_wide_plates(scene, zi).capacitance for zi in z])
        c_l, c_u = c[:, 0, 0] + c[:, 0, 1], c[:, 0, 1] + c[:, 1, 1]
        share = c_u / (c_l + c_u)
    else:
        share = 0.0
    upper_now = -q * (z + R) / h - share * lost
    upper_start = -history.start * R / h
    expected = upper_now - upper_start + took_upper
    scale = np.max(np.abs(expected)) + abs(law.equilibrium * A) * 1e-3
    assert np.max(np.abs(q_sc - expected)) <= 1e-12 * scale


def test_the_current_between_contacts_is_the_time_derivative_of_the_charge(cache):
    """I_SC = dQ_SC/dt along a path between contacts (motion, leakage and k(z) of the plate
    model all at work), against a central difference of Q_SC (relative 1e-6)."""
    from tengfield.surrogate import obtain_table

    scene = fx.scene_with(device={"surface_charge_uC_per_m2": -30.0})
    table, _ = obtain_table(scene, cache_dir=cache, solve=fx.plate_model_solve)
    A = math.pi * scene.device.ball_diameter ** 2
    law = ContactCharging(equilibrium=-100e-6, efficiency=0.5, ball_area=A, initial=-40e-6,
                          leakage_time=0.05)
    history = charge_history(law, np.array([0.01, 0.3]), np.array([0.02 * A, 0.03 * A]))
    terminal = ContactTerminal(table, history, np.array([False, True]))
    stroke = scene.device.stroke

    def path(t):
        return 0.5 * stroke * (1.0 + 0.8 * np.sin(40.0 * t)), 0.5 * stroke * 0.8 * 40.0 * np.cos(40.0 * t)

    t = np.linspace(0.05, 0.25, 41)
    z, v = path(t)
    i_sc = terminal.evaluate(t, z, v)[1]
    dt = 1e-6
    zp, vp = path(t + dt)
    zm, vm = path(t - dt)
    numeric = (terminal.evaluate(t + dt, zp, vp)[0] - terminal.evaluate(t - dt, zm, vm)[0]) / (2 * dt)
    assert np.max(np.abs(i_sc - numeric)) <= 1e-6 * np.max(np.abs(i_sc))


def test_a_lower_contact_moves_only_the_redistribution_through_the_wire():
    """Between wide plates a gain dq on the lower electrode (ball at z = 0) makes the wire
    carry dq psi_u = -dq R/h: only the change of what the ball induces on the upper one."""
    scene = fx.scene_with(device={"surface_charge_uC_per_m2": -30.0})
    table = _plates_table(scene)
    A = math.pi * scene.device.ball_diameter ** 2
    law = ContactCharging(equilibrium=-100e-6, efficiency=1.0, ball_area=A)
    history = charge_history(law, np.array([0.5]), np.array([0.01 * A]))
    terminal = ContactTerminal(table, history, np.array([False]))
    before, after = terminal.evaluate(np.array([0.499, 0.501]), np.zeros(2), np.zeros(2))[0]
    dq = history.gains[0]
    R, h = scene.device.ball_radius, scene.device.plate_spacing
    assert dq == pytest.approx(0.01 * law.equilibrium * A)
    assert after - before == pytest.approx(-dq * R / h, rel=1e-12)


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("surrogates")


@pytest.mark.parametrize("circuit", [{"kind": "open"}, {"kind": "load", "load_ohm": 1e8},
                                     {"kind": "series-rc", "load_ohm": 1e8,
                                      "series_capacitance_pF": 100.0},
                                     {"kind": "rectifier", "storage_capacitance_uF": 0.001}])
def test_a_ball_starting_at_equilibrium_is_the_constant_model(circuit, cache):
    """sigma_eq from the start, no leakage, no cap: every contact moves nothing, and every
    column and peak equals the constant model's at sigma_eq (1e-12)."""
    constant = tf.run(fx.scene_with(run=RUN, circuit=circuit,
                                    device={"surface_charge_uC_per_m2": -20.0}),
                      cache_dir=cache, solve=fx.plate_model_solve)
    contact = tf.run(fx.scene_with(run=RUN, circuit=circuit, charge={
        "model": "contact", "equilibrium_uC_per_m2": -20.0, "initial_uC_per_m2": -20.0,
        "discharge": "none"}), cache_dir=cache, solve=fx.plate_model_solve)
    assert contact.summary["charge"]["contacts"] > 5
    for column, a in constant.waveforms.items():
        b = np.asarray(contact.waveforms[column])
        a = np.asarray(a)
        assert np.max(np.abs(a - b)) <= 1e-12 * (np.max(np.abs(a)) or 1.0), column
    for name, value in constant.peaks.items():
        assert contact.peaks[name] == pytest.approx(value, rel=1e-12, abs=1e-300), name
    assert np.all(contact.waveforms["q_ball_C"] == pytest.approx(
        -20e-6 * math.pi * contact.scene.device.ball_diameter ** 2, rel=1e-12))


def test_an_uncharged_ball_charges_toward_sigma_eq_and_the_steady_state_is_the_fixed_point(
        cache):
    """From an uncharged ball the charge grows monotonically toward sigma_eq; with equal
    contacts (a period-1 bounce) and leakage the steady charge is the closed form
    k q_eq / (1 - (1 - k) e^(-T/tau)) of the contacts' own k and T."""
    from tengfield.source.charge import leaky_steady_charge
    from tengfield.source.contacts import contacts_of

    scene = fx.scene_with(run={"duration_s": 2.0, "settle_periods": 10,
                               "sample_rate_hz": 2000.0},
                          charge={"model": "contact", "equilibrium_uC_per_m2": -100.0,
                                  "efficiency": 1.0, "leakage_time_s": 0.5,
                                  "discharge": "none"})
    r = tf.run(scene, cache_dir=cache, solve=fx.plate_model_solve)
    q = np.asarray(r.waveforms["q_ball_C"])
    block = r.summary["charge"]
    assert block["contacts"] > 20 and q[0] == 0.0
    assert np.all(q <= 0.0) and block["share_of_equilibrium"] < 1.0
    # one excitation period's contacts (a big impact and its chatter) composed by hand
    from tengfield.source.charge import ContactCharging as Law
    d = r.dynamics
    times, areas, _ = contacts_of(r.scene, d.impacts, np.asarray(d.impacts.time))
    A = math.pi * r.scene.device.ball_diameter ** 2
    T = r.scene.excitation.period
    one = (times > 2.0 - T) & (times <= 2.0)
    assert np.count_nonzero(one) >= 2      # chatter: unequal contacts in a period
    P, Q, t_last = 1.0, 0.0, 2.0 - T
    for t, s in zip(times[one], areas[one]):
        k = s / A
        leak = math.exp(-(t - t_last) / 0.5)
        P, Q = (1 - k) * leak * P, (1 - k) * leak * Q + k * (-100e-6 * A)
        t_last = t
    leak = math.exp(-(2.0 - t_last) / 0.5)
    P, Q = P * leak, Q * leak
    q, t_last, after = Q / (1 - P), 2.0 - T, []
    for t, s in zip(times[one], areas[one]):
        q = q * math.exp(-(t - t_last) / 0.5)
        q += s / A * (-100e-6 * A - q)
        after.append(q)
        t_last = t
    assert block["steady_uC_per_m2"] * 1e-6 * A == pytest.approx(np.mean(after), rel=1e-9)
    # equal contacts, once a period: the closed form of docs/charge.md
    law = Law(equilibrium=-100e-6, efficiency=1.0, ball_area=A, leakage_time=0.5)
    n = 400
    h = charge_history(law, np.arange(1, n + 1) * T, np.full(n, 0.01 * A))
    from tengfield.source.contacts import steady_state
    state = steady_state(h, law, np.full(n, 0.01 * A), 0.5 * n * T, n * T + 0.5 * T, T)
    assert state["steady"] == pytest.approx(leaky_steady_charge(-100e-6 * A, 0.01, T, 0.5),
                                            rel=1e-9)


def test_what_contact_charging_does_not_run_yet_is_refused_before_the_work(cache):
    # an [array] runs (test_contact_array.py), the 3D ball too (test_contact_offaxis.py)
    with pytest.raises(tf.TengfieldError, match="contradict"):
        fx.scene_with(device={"surface_charge_uC_per_m2": "breakdown"},
                      charge={"model": "contact"})
    with pytest.raises(tf.TengfieldError, match=r"discharge = 'estimate' needs the air-breakdown"):
        tf.run(fx.scene_with(run=RUN, charge={"model": "contact"}), cache_dir=cache,
               solve=fx.plate_model_solve)   # the stand-in solver draws no breakdown lines
    with pytest.raises(tf.TengfieldError, match=r"\[charge\] efficiency = 0.*\(0, 1\]"):
        fx.scene_with(charge={"model": "contact", "efficiency": 0.0})


def test_cli_run_with_contact_charging_writes_the_charge_and_its_figure(tmp_path):
    """End to end with figures on (the real field, coarse): q_ball_C, summary.json's charge
    block, ball_charge.png, and the terminal's one line on the steady charge and its limit."""
    scene = tmp_path / "contact.toml"
    scene.write_text(fx.SMALL_SCENE + '\n[charge]\nmodel = "contact"\n')
    out = tmp_path / "out"
    proc = subprocess.run([sys.executable, "-m", "tengfield.cli", "run", str(scene), "-o",
                           str(out), "--cache-dir", str(tmp_path / "cache")],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    line = [x for x in proc.stdout.splitlines() if x.startswith("ball charge (contacts)")]
    assert len(line) == 1 and "limited by the air-breakdown cap" in line[0], proc.stdout
    summary = json.loads((out / "summary.json").read_text())
    block = summary["charge"]
    for key in ("steady_uC_per_m2", "rise_time_90_s", "contacts", "mean_delta_per_contact_C",
                "share_of_equilibrium", "share_of_cap", "binds"):
        assert key in block
    assert block["cap_level"] == "estimate"
    assert block["steady_uC_per_m2"] == pytest.approx(
        -summary["breakdown"]["band"]["estimate_uC_per_m2"], rel=1e-9)
    header = (out / "waveforms.csv").read_text().splitlines()[0].split(",")
    assert header[-1] == "q_ball_C"
    png = (out / "ball_charge.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 20_000


def test_the_rise_time_extrapolated_past_a_short_run_is_the_long_runs(cache):
    """A run too short to charge the ball says when it would reach 90 % of its steady
    charge; a run long enough to get there finds the same time (within 2 %)."""
    charge = {"model": "contact", "equilibrium_uC_per_m2": -100.0, "efficiency": 1.0,
              "leakage_time_s": 3.0, "discharge": "none"}
    short = tf.run(fx.scene_with(run={"duration_s": 1.0, "settle_periods": 10,
                                      "sample_rate_hz": 1000.0}, charge=charge),
                   cache_dir=cache, solve=fx.plate_model_solve).summary["charge"]
    long = tf.run(fx.scene_with(run={"duration_s": 12.0, "settle_periods": 10,
                                     "sample_rate_hz": 1000.0}, charge=charge),
                  cache_dir=cache, solve=fx.plate_model_solve).summary["charge"]
    assert short["rise_time_extrapolated"] and not long["rise_time_extrapolated"]
    assert short["share_of_steady_at_end"] < 0.8
    assert short["steady_uC_per_m2"] == pytest.approx(long["steady_uC_per_m2"], rel=1e-6)
    assert short["rise_time_90_s"] == pytest.approx(long["rise_time_90_s"], rel=0.02)


@pytest.mark.slow
def test_a_ten_minute_run_streams_the_charge_and_equals_the_constant_model_at_equilibrium(cache):
    """600 s at 20 Hz with the start-up (1.2 M samples: the streamed electrical stage): the
    charge column is in every chunk, and a ball at sigma_eq gives the constant model's
    peaks (1e-12)."""
    run = {"duration_s": 600.0, "settle_periods": 10, "sample_rate_hz": 2000.0}
    constant = tf.run(fx.scene_with(run=run, device={"surface_charge_uC_per_m2": -20.0}),
                      cache_dir=cache, solve=fx.plate_model_solve)
    contact = tf.run(fx.scene_with(run=run, charge={
        "model": "contact", "equilibrium_uC_per_m2": -20.0, "initial_uC_per_m2": -20.0,
        "discharge": "none", "waveforms": "start-up"}), cache_dir=cache,
        solve=fx.plate_model_solve)
    assert hasattr(contact.waveforms, "chunks")
    for name, value in constant.peaks.items():
        assert contact.peaks[name] == pytest.approx(value, rel=1e-12), name
    q = -20e-6 * math.pi * contact.scene.device.ball_diameter ** 2
    for chunk in contact.waveforms.chunks():
        assert np.all(chunk["q_ball_C"] == pytest.approx(q, rel=1e-12))
    assert contact.summary["charge"]["contacts"] > 10_000


@pytest.mark.slow
def test_mpirun_writes_the_serial_runs_files(tmp_path, cli_command, cli_env):
    """``mpirun -n 2 tengfield run`` of a contact-charged scene: waveforms.csv and the charge
    block byte for byte / number for number the serial run's."""
    scene = tmp_path / "contact.toml"
    scene.write_text(fx.SMALL_SCENE + '\n[charge]\nmodel = "contact"\n')
    serial_and_mpirun(cli_command, cli_env, tmp_path, "run", scene, shared_cache=True)
    assert (tmp_path / "one" / "waveforms.csv").read_bytes() == \
        (tmp_path / "two" / "waveforms.csv").read_bytes()
    one_block = json.loads((tmp_path / "one" / "summary.json").read_text())["charge"]
    two_block = json.loads((tmp_path / "two" / "summary.json").read_text())["charge"]
    assert one_block == two_block


@pytest.mark.parametrize("study", ["breakdown", "fit", "report"])
def test_the_studies_that_would_hold_the_charge_constant_refuse_it_in_one_line(study, tmp_path):
    """Until each study runs the contacts' charge it refuses ``[charge] model = "contact"``
    before any work, rather than running at a constant charge without saying so."""
    scene = tmp_path / "contact.toml"
    scene.write_text(fx.SMALL_SCENE + '\n[charge]\nmodel = "contact"\n')
    extra = {"sweep": ["--frequency-hz", "18:20:2", "--amplitude-mm", "1.5"],
             "fit": ["--target", "V_pp_V=4.2"]}.get(study, [])
    proc = subprocess.run([sys.executable, "-m", "tengfield.cli", study, str(scene), *extra,
                           "-o", str(tmp_path / "out")], capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode != 0
    assert 'model = "contact" is not supported by tengfield ' + study in proc.stderr, proc.stderr
    assert "Traceback" not in proc.stderr
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())
