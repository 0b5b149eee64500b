"""Rectifier, store and power chip (tengfield.harvest): physics checks on
synthetic periodic TENG drives (no field solve needed)."""
import math

import numpy as np
import pytest
from scipy.integrate import trapezoid
from hypothesis import given, settings, strategies as st

from tengfield.errors import SceneError
from tengfield.harvest import (Diode, PowerChip, harvest, max_energy_per_cycle,
                               saturation_voltage)

FREQ = 20.0
Q_MAX = 1.4e-9          # C, Q_SC peak of one cell
C_BOTTOM = 0.30e-12     # F, C_T with the ball on the lower plate
C_TOP = 0.25e-12        # F, C_T at the top of the stroke


def drive(periods=20, per_period=1000, phase=0.0, q_max=Q_MAX):
    """A smooth periodic cell: Q_SC = Q_max (1 - cos(ωt + φ))/2, C_T between its ends."""
    t = np.linspace(0.0, periods / FREQ, periods * per_period + 1)
    s = 0.5 * (1.0 - np.cos(2 * np.pi * FREQ * t + phase))
    return t, q_max * s, C_BOTTOM + (C_TOP - C_BOTTOM) * s


@pytest.mark.parametrize("forward", [0.0, 0.3])
def test_ideal_bridge_saturates_at_the_derived_voltage(forward):
    t, q, c = drive(periods=60)
    res = harvest(t, q, c, storage_capacitance=1e-12, diode=Diode(forward_voltage=forward))
    expected = saturation_voltage(Q_MAX, C_BOTTOM, C_TOP, forward)
    assert res.store_voltage[-1] == pytest.approx(expected, rel=1e-2)
    assert np.all(np.diff(res.store_voltage) >= -1e-9 * expected)   # never discharges


def test_saturation_follows_the_geometric_law():
    """U_k -> U_sat (1 - exp(-2k (C_max + C_min)/C_L)) for C_L >> C (Niu et al. 2014)."""
    t, q, c = drive(periods=40)
    c_store = 20e-12
    res = harvest(t, q, c, storage_capacitance=c_store)
    u_sat = saturation_voltage(Q_MAX, C_BOTTOM, C_TOP)
    k = np.arange(5, 40, 5)
    samples = res.store_voltage[(k * 1000)]
    law = u_sat * (1 - np.exp(-2 * k * (C_BOTTOM + C_TOP) / c_store))
    assert samples == pytest.approx(law, rel=0.05)


@pytest.mark.parametrize("cells", [1, 3])
def test_huge_store_charges_linearly_by_twice_q_max_per_cycle(cells):
    t, q, c = drive(periods=10)
    q = np.repeat(q[:, None], cells, axis=1)
    c = np.repeat(c[:, None], cells, axis=1)
    res = harvest(t, q, c, storage_capacitance=1e-3)
    assert res.store_voltage[-1] * 1e-3 == pytest.approx(2 * Q_MAX * 10 * cells, rel=1e-4)


def test_rectifier_into_a_shorted_store_carries_the_rectified_short_circuit_current():
    """C_L -> inf holds U = 0: the bridge shorts the cell, |I_b| = |I_SC|."""
    t, q, c = drive(periods=3)
    res = harvest(t, q, c, storage_capacitance=1e3)
    transferred = res.bridge_charge[:, 0]
    assert transferred == pytest.approx(q - q[0], abs=1e-6 * Q_MAX)
    assert np.max(np.abs(res.voltage)) < 1e-9
    assert res.store_voltage[-1] * 1e3 == pytest.approx(np.sum(np.abs(np.diff(q))), rel=1e-9)


@pytest.mark.slow
@pytest.mark.parametrize("diode", [Diode(), Diode(forward_voltage=0.5, series_resistance=1e8),
                                   Diode(model="shockley", saturation_current=1e-12,
                                         series_resistance=1e3)])
def test_energy_books_balance(diode):
    t, q, c = drive(periods=8, per_period=2000)
    res = harvest(t, q, c, storage_capacitance=1e-9, diode=diode, leakage=1e11,
                  chip=PowerChip(uvlo_rising=5.05, uvlo_falling=4.04, load=1e6,
                                 quiescent_current=0.0))
    books = res.balance()
    assert books["terminal_residual"] < 1e-9
    assert books["bridge_residual"] < 1e-6
    assert books["store_residual"] < 1e-9
    assert books["numerical_dissipation_J"] < 1e-3 * books["delivered_J"]
    assert books["diode_loss_J"] >= 0.0


def test_numerical_dissipation_is_first_order_in_the_step():
    """The backward-Euler store step dissipates C_L ΔU²/2 per step: O(h) in total."""
    ratios = []
    for per_period in (500, 1000, 2000):
        t, q, c = drive(periods=4, per_period=per_period)
        books = harvest(t, q, c, storage_capacitance=1e-9).balance()
        ratios.append(books["numerical_dissipation_J"] / books["delivered_J"])
    slope = np.polyfit(np.log([500, 1000, 2000]), np.log(ratios), 1)[0]
    assert slope == pytest.approx(-1.0, abs=0.15)


def test_mechanical_work_matches_the_power_integral():
    """Σ work = ∫ (V I_SC - V² dC/dt / 2) dt on the solution, converging with the step."""
    errors = []
    for per_period in (500, 1000, 2000, 4000):
        t, q, c = drive(periods=4, per_period=per_period)
        res = harvest(t, q, c, storage_capacitance=5e-12)
        v = res.voltage[:, 0]
        power = v * np.gradient(q, t) - 0.5 * v * v * np.gradient(c, t)
        integral = trapezoid(power, t)
        errors.append(abs(res.mechanical_work[-1] - integral) / abs(integral))
    slope = np.polyfit(np.log([500, 1000, 2000, 4000]), np.log(errors), 1)[0]
    assert errors[-1] < 2e-3
    assert slope < -0.8


def test_forward_drop_loss_is_its_charge_times_two_drops():
    t, q, c = drive(periods=6)
    res = harvest(t, q, c, storage_capacitance=1e-6, diode=Diode(forward_voltage=0.4))
    moved = np.sum(np.abs(np.diff(res.bridge_charge[:, 0])))
    assert res.diode_loss[-1] == pytest.approx(2 * 0.4 * moved, rel=1e-12)


def test_uvlo_switches_with_the_hysteresis_it_is_given():
    """Constant charging current I into C_L, chip power P > U I: each burst drains
    C_L (V_r² - V_f²)/2 and recharging takes C_L (V_r - V_f) / I."""
    c_store, rising, falling = 10e-6, 5.05, 4.04
    current = 2e-6                                    # A into the store
    t = np.linspace(0.0, 200.0, 400001)
    ramp = current * t                                # a "cell" that is a current source:
    cap = np.full_like(t, 1e-12)                      # tiny C_T: the bridge passes I_SC
    chip = PowerChip(uvlo_rising=rising, uvlo_falling=falling, load=1e3, quiescent_current=0.0)
    res = harvest(t, ramp, cap, storage_capacitance=c_store, chip=chip)
    first_on = c_store * rising / current
    assert res.threshold_times["uvlo_rising_s"] == pytest.approx(first_on, rel=1e-3)
    on = res.chip_on.astype(int)
    bursts = np.count_nonzero(np.diff(on) == 1) + on[0]
    period = c_store * (rising - falling) / current   # burst time is negligible (P >> U I)
    expected = 1 + math.floor((t[-1] - first_on) / period)
    assert abs(bursts - expected) <= 1
    assert res.store_voltage.max() <= rising + 1e-3
    assert res.store_voltage[t > first_on + 1].min() >= falling - 1e-3


def test_shunt_holds_the_store_at_its_voltage():
    t, q, c = drive(periods=20)
    chip = PowerChip(uvlo_rising=1e3, uvlo_falling=900.0, load=1e12, shunt_voltage=1500.0,
                     quiescent_current=0.0)
    res = harvest(t, q, c, storage_capacitance=1e-12, chip=chip)
    assert res.store_voltage.max() <= 1500.0 + 1e-9
    assert res.shunt_loss[-1] > 0


@settings(max_examples=15, deadline=None)
@given(phases=st.lists(st.floats(0.0, 2 * np.pi), min_size=2, max_size=5),
       c_store_pf=st.floats(1.0, 1e4), forward=st.sampled_from([0.0, 0.2]))
def test_per_cell_rectification_never_delivers_less_than_a_shared_bridge(phases, c_store_pf,
                                                                        forward):
    cols = [drive(periods=5, per_period=400, phase=p) for p in phases]
    t = cols[0][0]
    q = np.column_stack([col[1] for col in cols])
    c = np.column_stack([col[2] for col in cols])
    diode = Diode(forward_voltage=forward)
    per_cell = harvest(t, q, c, storage_capacitance=c_store_pf * 1e-12, diode=diode)
    shared = harvest(t, q.sum(axis=1), c.sum(axis=1), storage_capacitance=c_store_pf * 1e-12,
                     diode=diode)
    assert per_cell.stored_energy[-1] >= shared.stored_energy[-1] * (1 - 1e-9) - 1e-30


def test_identical_cells_per_cell_equal_one_bridge_on_the_parallel_sum():
    t, q, c = drive(periods=5, per_period=500)
    n = 4
    per_cell = harvest(t, np.repeat(q[:, None], n, 1), np.repeat(c[:, None], n, 1),
                       storage_capacitance=1e-10)
    shared = harvest(t, n * q, n * c, storage_capacitance=1e-10)
    assert per_cell.store_voltage == pytest.approx(shared.store_voltage, rel=1e-9, abs=1e-12)


@pytest.mark.slow
@pytest.mark.parametrize("c_store", [1e-9, 1e-6, 1e-3, 1.0])
@pytest.mark.parametrize("i_sat", [1e-15, 1e-9, 1e-6])
def test_stable_from_nanofarads_to_farads_and_any_saturation_current(c_store, i_sat):
    t, q, c = drive(periods=3, per_period=400)
    res = harvest(t, q, c, storage_capacitance=c_store,
                  diode=Diode(model="shockley", saturation_current=i_sat))
    assert np.all(np.isfinite(res.store_voltage)) and np.all(np.isfinite(res.voltage))
    u_sat = saturation_voltage(Q_MAX, C_BOTTOM, C_TOP)
    assert res.store_voltage.max() <= u_sat * 1.001
    assert res.store_voltage[-1] >= 0.0
    books = res.balance()
    assert books["store_residual"] < 1e-6 and books["terminal_residual"] < 1e-9


def test_cmeo_energy_is_the_area_of_the_cycle():
    """E_m = Q_max (V_OC,max + |V'|)/2: trace the CMEO cycle's four legs."""
    e_m = max_energy_per_cycle(Q_MAX, C_TOP, C_BOTTOM)
    v_oc_max, v_back = Q_MAX / C_TOP, Q_MAX / C_BOTTOM
    # legs at constant charge do no V dQ work; shorts move Q_max at V falling linearly
    # to 0 with C fixed: the area is the two triangles
    assert e_m == pytest.approx(0.5 * Q_MAX * v_oc_max + 0.5 * Q_MAX * v_back)


@pytest.mark.parametrize("kwargs, key", [
    ({"diode": "x"}, "diode"),
])
def test_bad_values_name_their_key(kwargs, key):
    with pytest.raises(SceneError, match=key):
        Diode(model=kwargs["diode"])
    with pytest.raises(SceneError, match="uvlo_rising_V"):
        PowerChip(uvlo_rising=3.0, uvlo_falling=4.0)
    with pytest.raises(SceneError, match="storage_capacitance_uF"):
        t, q, c = drive(periods=1, per_period=10)
        harvest(t, q, c, storage_capacitance=-1.0)
