"""Each electrical demo runs in --fast mode, writes its figure and returns its comparison.

The demos share one surrogate cache (a temporary directory for this module),
so the paper's device is solved once. Numbers asserted (those ``main()`` returns)
are physics the demos exist to show, with margins for the coarse fast-mode fields.
"""
from __future__ import annotations

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DEMOS = ROOT / "demos"
NAMES = ["electrical_waveforms", "electrical_frequency_amplitude", "electrical_geometry",
         "electrical_honeycomb"]

@pytest.fixture(scope="module")
def cache_dir(tmp_path_factory):
    return tmp_path_factory.mktemp("surrogates")


@pytest.fixture
def run_demo(load_demo, cache_dir, tmp_path):
    """``run_demo(name)`` -> the numbers of ``demos/name.py --fast`` (figure checked)."""
    def run(name):
        numbers = load_demo(name).main(["--fast", "-o", str(tmp_path),
                                        "--cache-dir", str(cache_dir)])
        png = tmp_path / f"{name}.png"
        assert png.exists() and 10_000 < png.stat().st_size < 300_000
        return numbers
    return run


def test_every_electrical_demo_is_tested():
    assert sorted(p.stem for p in DEMOS.glob("electrical_*.py")
                  if p.stem != "electrical_common") == sorted(NAMES)


@pytest.mark.slow   # dolfinx surrogate and impact-map runs
def test_waveforms_demo_reconciles_the_electrometer(run_demo):
    out = run_demo("electrical_waveforms")
    # the instrument that turns the ideal V_OC into the paper's 4.2 V adds hundreds of pF
    assert 100 < out["C_p_pF"] < 1000
    assert out["V_read_V"] == pytest.approx(4.2, rel=0.02)
    assert out["V_oc_ideal_V"] > 100 * 4.2        # the ideal floating-pair V_OC is kV-scale


@pytest.mark.slow   # dolfinx surrogate and impact-map runs
def test_frequency_demo_shows_lift_off_and_plateau(run_demo):
    out = run_demo("electrical_frequency_amplitude")
    assert 12 <= out["onset_hz"] <= 20        # lift-off at 1.5 mm: A w^2 = g at 12.9 Hz
    volts = out["V_pp_read_V"]
    assert volts[5.0] < 5e-4 and volts[10.0] < 5e-4     # "0.000" V as printed
    assert min(volts[f] for f in volts if f >= 20) > 3.5


@pytest.mark.slow   # dolfinx surrogate and impact-map runs
def test_geometry_demo_trends(run_demo):
    out = run_demo("electrical_geometry")
    assert out["monotonic_in_gap"] and out["monotonic_in_diameter"]


@pytest.mark.slow   # dolfinx surrogate and impact-map runs
def test_honeycomb_demo_load_optimum(run_demo):
    out = run_demo("electrical_honeycomb")
    assert out["cells"] == 455
    # impedance matching, on the sweep's grid
    assert out["mean_power_load_MOhm"] == pytest.approx(out["matched_load_MOhm"], rel=0.6)
