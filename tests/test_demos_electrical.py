"""Each electrical demo runs in --fast mode, writes its figure and prints its comparison.

The demos share one surrogate cache (a temporary directory for this module),
so the paper's device is solved once. Numbers asserted are physics the
demos exist to show, with margins for the coarse fast-mode fields.
"""
from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DEMOS = ROOT / "demos"
PYTHON = sys.executable
NAMES = ["electrical_waveforms", "electrical_frequency_amplitude", "electrical_geometry",
         "electrical_honeycomb"]


@pytest.fixture(scope="module")
def cache_dir(tmp_path_factory):
    return tmp_path_factory.mktemp("surrogates")


def run_demo(name, out, cache_dir):
    env = {**os.environ, "MPLBACKEND": "Agg"}
    proc = subprocess.run([PYTHON, str(DEMOS / f"{name}.py"), "--fast", "-o", str(out),
                           "--cache-dir", str(cache_dir)],
                          capture_output=True, text=True, env=env, timeout=600, cwd=ROOT)
    assert proc.returncode == 0, proc.stderr[-3000:]
    png = out / f"{name}.png"
    assert png.exists() and 10_000 < png.stat().st_size < 300_000
    return proc.stdout


def number(pattern, text):
    match = re.search(pattern, text)
    assert match, f"{pattern!r} not in output:\n{text}"
    return float(match.group(1))


def test_every_electrical_demo_is_tested():
    assert sorted(p.stem for p in DEMOS.glob("electrical_*.py")
                  if p.stem != "electrical_common") == sorted(NAMES)


def test_waveforms_demo_reconciles_the_electrometer(tmp_path, cache_dir):
    out = run_demo("electrical_waveforms", tmp_path, cache_dir)
    # the instrument that turns the ideal V_OC into the paper's 4.2 V adds hundreds of pF
    c_p = number(r"instrument capacitance C_p for 4\.2 V\s+hundreds of pF\s+([\d.]+) pF", out)
    assert 100 < c_p < 1000
    assert number(r"V read with that C_p\s+4\.2 V\s+([\d.]+) V", out) == pytest.approx(4.2, rel=0.02)
    ideal = number(r"V_OC at that sigma, ideal\s+-\s+([\d.]+) V", out)
    assert ideal > 100 * 4.2        # the ideal floating-pair V_OC is kV-scale


def test_frequency_demo_shows_lift_off_and_plateau(tmp_path, cache_dir):
    out = run_demo("electrical_frequency_amplitude", tmp_path, cache_dir)
    onset = number(r"lowest frequency with output\s+16-20 Hz \(none < 16\)\s+([\d.]+) Hz", out)
    assert 12 <= onset <= 20        # lift-off at 1.5 mm: A w^2 = g at 12.9 Hz
    rows = re.findall(r"^\s*([\d.]+)\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)$", out, re.M)
    volts = {float(f): float(v) for f, _, v, _ in rows}
    assert volts[5.0] == 0.0 and volts[10.0] == 0.0
    assert min(volts[f] for f in volts if f >= 20) > 3.5


def test_geometry_demo_trends(tmp_path, cache_dir):
    out = run_demo("electrical_geometry", tmp_path, cache_dir)
    assert out.count("tengfield: monotonic") == 2


def test_honeycomb_demo_load_optimum(tmp_path, cache_dir):
    out = run_demo("electrical_honeycomb", tmp_path, cache_dir)
    assert "455 cells in parallel" in out
    best = number(r"max mean power density\s+-\s+[\d.e+-]+ W/m\^3 at ([\d.]+) MOhm", out)
    matched = number(r"1/\(2 pi f \(C_T \+ C_p\)\)\s+-\s+([\d.]+) MOhm", out)
    assert best == pytest.approx(matched, rel=0.6)   # impedance matching, on the sweep's grid
