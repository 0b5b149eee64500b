"""Paschen's law (tengfield.paschen) against tabulated values."""
import math

import numpy as np
import pytest

from tengfield.paschen import ATMOSPHERE, Paschen, breakdown_voltage


@pytest.mark.parametrize("d, expected", [
    (10e-6, 307.0), (0.1e-3, 865.0), (1e-3, 5030.0)])
def test_townsend_formula_at_one_atmosphere(d, expected):
    # DESIGN §8 / docs/breakdown.md: the Townsend formula with Raizer's constants
    assert float(Paschen().townsend(d)) == pytest.approx(expected, rel=3e-3)


def test_minimum_of_the_curve():
    p = Paschen()
    assert p.v_min == pytest.approx(305.0, rel=2e-3)
    assert p.d_min == pytest.approx(11.0e-6, rel=1e-2)
    # the minimum of the bare formula is where the analytic one says
    d = np.linspace(5e-6, 50e-6, 20001)
    v = p.townsend(d)
    assert float(np.nanmin(v)) == pytest.approx(p.v_min, rel=1e-6)
    assert d[np.nanargmin(v)] == pytest.approx(p.d_min, rel=2e-3)


@pytest.mark.parametrize("d, measured", [
    # uniform-field breakdown of air at 1 atm, 20 C: the values tabulated by Dakin et al.
    # (Electra 32, 1974; V = 24.36 x + 6.72 sqrt(x) kV, x in bar cm) and the classical
    # 31.6 kV at 1 cm (the textbook value for 1 atm, 20 C)
    (0.5e-3, 2.91e3), (1e-3, 4.61e3), (2e-3, 7.97e3), (10e-3, 31.6e3)])
def test_curve_against_measured_air_values(d, measured):
    assert breakdown_voltage(d) == pytest.approx(measured, rel=0.15)


def test_curve_is_continuous_and_non_decreasing():
    p = Paschen()
    d = np.geomspace(1e-8, 5e-2, 200001)
    v = p.voltage(d)
    assert np.all(np.isfinite(v))
    assert np.all(np.diff(v) >= -1e-9 * v[1:])
    # no jumps at the regime boundaries
    for edge in (p.d_field_emission, p.d_min, p.d_streamer):
        lo, hi = p.voltage(edge * (1 - 1e-9)), p.voltage(edge * (1 + 1e-9))
        assert hi == pytest.approx(lo, rel=1e-6)
    assert p.voltage(0.0) == 0.0
    assert set(p.regime([1e-7, 5e-6, 1e-4, 1e-2])) == {"field-emission", "plateau", "townsend",
                                                      "streamer"}


def test_pressure_enters_through_p_times_d():
    low = Paschen(pressure=0.5 * ATMOSPHERE)
    assert low.voltage(2e-4) == pytest.approx(Paschen().voltage(1e-4), rel=1e-12)
    # at mm gaps a lower pressure breaks down at a lower voltage
    assert low.voltage(1e-3) < Paschen().voltage(1e-3)


def test_bad_constants_are_refused():
    with pytest.raises(ValueError, match="gamma"):
        Paschen(gamma=0.0)
    with pytest.raises(ValueError, match="pressure"):
        Paschen(pressure=-1.0)
    assert math.isnan(Paschen().voltage(-1e-3))


# -- the left branch at low pressure: the device's longest path ----------------------
#: the default device's longest path: hypot(plate spacing 10 mm, inner diameter 8 mm)
DEVICE_PATH = math.hypot(10e-3, 8e-3)


def test_a_long_enough_device_changes_nothing_at_one_atmosphere():
    d = np.geomspace(1e-8, 5e-2, 400)
    np.testing.assert_array_equal(Paschen(longest_path=DEVICE_PATH).voltage(d),
                                  Paschen().voltage(d))


def test_low_pressure_raises_the_breakdown_voltage_again():
    """Paschen's curve in pressure for a fixed 1 mm gap: down the right branch to V_min,
    then up again once the longest path is shorter than the minimum's p d (the discharge
    cannot find a longer path), and no avalanche at all at a few Pa: vacuum."""
    pressures = np.geomspace(ATMOSPHERE, 1.0, 60)
    v = np.array([Paschen(pressure=p, longest_path=DEVICE_PATH).voltage(1e-3)
                  for p in pressures])
    lowest = int(np.argmin(v))
    assert v[lowest] == pytest.approx(Paschen().v_min, rel=1e-9)
    assert np.all(np.diff(v[:lowest + 1]) <= 1e-9 * v[0])        # falls to the minimum
    assert v[-1] > 100 * v[lowest]                                # and rises far beyond it
    p_left = Paschen().pd_min / DEVICE_PATH                       # where the branch turns
    for p in (0.7 * p_left, 0.5 * p_left):
        paschen = Paschen(pressure=p, longest_path=DEVICE_PATH)
        assert paschen.v_left == pytest.approx(float(paschen.townsend(DEVICE_PATH)), rel=1e-12)
        assert paschen.v_left > paschen.v_min
        assert paschen.regime(1e-3)[0] == "long-path"
    vacuum = Paschen(pressure=1.0, longest_path=DEVICE_PATH)
    assert vacuum.v_left == math.inf and vacuum.regime(1e-3)[0] == "vacuum"
    assert vacuum.voltage(1e-3) == pytest.approx(vacuum.field_emission * 1e-3)


@pytest.mark.parametrize("pressure", [ATMOSPHERE, 1e3, 80.0, 50.0, 20.0, 1.0])
def test_curve_never_falls_within_the_device(pressure):
    paschen = Paschen(pressure=pressure, longest_path=DEVICE_PATH)
    v = paschen.voltage(np.linspace(0.0, DEVICE_PATH, 2001))
    assert np.all(np.isfinite(v)) and np.all(np.diff(v) >= -1e-9 * v.max())


def test_from_scene_takes_the_devices_longest_path():
    from tengfield.scene import parse_scene
    scene = parse_scene("[breakdown]\npressure_kPa = 0.05\n")
    paschen = Paschen.from_scene(scene)
    dev = scene.device
    assert paschen.longest_path == pytest.approx(math.hypot(dev.plate_spacing,
                                                            2 * dev.tube_inner_radius))
    assert paschen.to_json()["longest_path_m"] == pytest.approx(paschen.longest_path)
