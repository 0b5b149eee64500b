"""The device as a SPICE subcircuit (issue #39), run by a real ngspice: on a resistor it
gives tengfield's own load voltage within 1 % over the steady window, and through a
full-wave bridge of Shockley diodes into a capacitor tengfield's rectifier's store
voltage within 2 %. The field is the analytic plate model (no dolfinx); ngspice is a
system package (scripts/install-system.sh)."""
from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

import tengfield as tf
from tengfield import spice

import plate_model as fx

NGSPICE = shutil.which("ngspice")
needs_ngspice = pytest.mark.skipif(NGSPICE is None, reason="ngspice is not installed "
                                   "(scripts/install-system.sh installs it)")
RUN = {"duration_s": 0.4, "settle_periods": 3, "sample_rate_hz": 20000.0}
EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("surrogates")


def _ngspice(folder: Path, netlist: str, output: str) -> np.ndarray:
    (folder / "top.cir").write_text(netlist)
    proc = subprocess.run([NGSPICE, "-b", "top.cir"], cwd=folder, capture_output=True,
                          text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    return np.loadtxt(folder / output)


def _steady_error(result, column, simulated) -> float:
    t = np.asarray(result.t) - result.t[0]
    mask = t >= result.scene.run.settle_periods * result.scene.excitation.period
    ours = np.asarray(result.waveforms[column])[mask]
    theirs = np.interp(t[mask], simulated[:, 0], simulated[:, 1])
    return float(np.max(np.abs(theirs - ours)) / np.max(np.abs(ours)))


def test_the_subcircuit_holds_the_runs_tables(cache, tmp_path):
    r = tf.run(fx.scene_with(run=RUN), cache_dir=cache, solve=fx.plate_model_solve)
    text = spice.export(r, tmp_path / "teng.lib").read_text()
    assert ".subckt teng p n" in text and ".ends teng" in text
    tab = spice.tables(r)
    assert tab["time_s"].size > len(r.t)                  # the impacts added
    assert np.all(np.diff(tab["time_s"]) > 0)
    # the table's C_T is the waveforms' C_T_F (in pF), V_OC = Q_SC / C_T
    np.testing.assert_allclose(r.waveforms["V_oc_V"],
                               r.waveforms["Q_sc_C"] / r.waveforms["C_T_F"], rtol=1e-12)
    first = text.split("Vct ct 0 PWL(")[1].split("\n")[1].split()
    assert float(first[2]) == pytest.approx(r.waveforms["C_T_F"][0] * 1e12, rel=1e-9)


@needs_ngspice
@pytest.mark.slow
def test_on_a_resistor_ngspice_gives_tengfields_load_voltage(cache, tmp_path):
    load = 1e8
    r = tf.run(fx.scene_with(run=RUN, circuit={"kind": "load", "load_ohm": load}),
               cache_dir=cache, solve=fx.plate_model_solve)
    spice.export(r, tmp_path / "teng.lib")
    step = float(r.t[1] - r.t[0])
    out = _ngspice(tmp_path, spice.load_netlist(load, float(r.t[-1] - r.t[0]), step,
                                                output="v.csv"), "v.csv")
    assert np.max(np.abs(r.waveforms["V_load_V"])) > 0.1     # a signal, not noise
    assert _steady_error(r, "V_load_V", out) < 0.01


BRIDGE = """* the TENG through a full-wave bridge into a store
.include teng.lib
X1 a b teng
D1 a out dteng
D2 b out dteng
D3 0 a dteng
D4 0 b dteng
Cstore out 0 {store}
.model dteng D(IS={i_s} N={n} RS=0)
.temp 26.85
.tran {step} {stop} 0 {step}
.control
run
wrdata store.csv v(out)
quit 0
.endc
.end
"""


@needs_ngspice
@pytest.mark.slow
def test_through_a_bridge_ngspice_gives_tengfields_store_voltage(cache, tmp_path):
    """tengfield's Shockley diodes (i = I_s (exp(v / (n V_T)) - 1), V_T = k 300 K / e)
    are SPICE's diode model at 300 K (26.85 °C) with the same I_s and n."""
    store = 1e-9
    circuit = {"kind": "rectifier", "diode": "shockley", "diode_saturation_current_A": 1e-12,
               "diode_emission_coefficient": 1.0, "storage_capacitance_uF": store * 1e6}
    r = tf.run(fx.scene_with(run=RUN, circuit=circuit), cache_dir=cache,
               solve=fx.plate_model_solve)
    spice.export(r, tmp_path / "teng.lib")
    step = float(r.t[1] - r.t[0])
    out = _ngspice(tmp_path, BRIDGE.format(store=store, i_s=1e-12, n=1.0, step=step,
                                           stop=float(r.t[-1] - r.t[0])), "store.csv")
    assert r.waveforms["V_store_V"][-1] > 0.1
    assert _steady_error(r, "V_store_V", out) < 0.02


@needs_ngspice
def test_the_shipped_example_runs_in_ngspice(tmp_path):
    """examples/teng_load.cir with examples/teng.lib (examples/make_bench_exports.py): run
    from examples/ as README says, V(out) across 100 Mohm is volts, both signs."""
    for name in ("teng_load.cir", "teng.lib"):
        shutil.copy(EXAMPLES / name, tmp_path / name)
    proc = subprocess.run([NGSPICE, "-b", "teng_load.cir"], cwd=tmp_path, capture_output=True,
                          text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    v = np.loadtxt(tmp_path / "teng_load.csv")[:, 1]
    assert 0.5 < np.max(v) < 100 and -100 < np.min(v) < -0.5


def test_a_streamed_run_exports_the_same_subcircuit(cache, monkeypatch):
    """A long run's columns come a chunk at a time (electrical/stream.py): the same text."""
    from tengfield.electrical import stream

    scene = fx.scene_with(run={**RUN, "duration_s": 0.3}, circuit={"kind": "load"})
    whole = tf.run(scene, cache_dir=cache, solve=fx.plate_model_solve)
    monkeypatch.setattr(stream, "STREAM_ROWS", 10)
    monkeypatch.setattr(stream, "CHUNK_ROWS", 97)
    streamed = tf.run(scene, cache_dir=cache, solve=fx.plate_model_solve)
    assert isinstance(streamed.waveforms, stream.StreamedWaveforms)
    assert spice.subcircuit(streamed) == spice.subcircuit(whole)
