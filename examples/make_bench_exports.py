"""Write three example exports of a bench, as instruments save them (issue #39), for
`tengfield fit --measured` (README, "Compare with your bench"):

* ``tek_scope.csv``: an oscilloscope's CSV (Tektronix style): 12 metadata lines, then the
  header ``TIME,CH1``; CH1 is the voltage across the device read through a scope and
  cable of 338 pF;
* ``electrometer_log.tsv``: an electrometer's charge log: two title lines, tab separated,
  units in the header (``Time (ms)``, ``Charge (nC)``);
* ``scope_semicolon.csv``: a European spreadsheet's export: ``;`` separated, decimal
  commas, units in brackets (``TIME [s];CH1 [V];CH2 [nC]``).

All three hold the same 0.2 s of one trace: a ``tengfield run`` of the embedded default
scene (σ = -8 µC/m², 20 Hz, 1.5 mm) read through the front end of examples/bench.toml's
``[instrument]`` (338 pF, a 1.667 ms aperture; exported at 5 kHz, the trace's own readings),
its steady part from t = 0.5 s, without noise, so a test can hold the three readings equal
and ``tengfield fit examples/bench.toml --measured ...`` gives σ = -8 back. It also writes ``teng.lib`` (the device as a SPICE subcircuit, ``tengfield run
--spice``) and ``teng_load.cir`` (it on a 100 Mohm resistor; ``cd examples && ngspice -b
teng_load.cir`` writes V(out) to teng_load.csv).

    python examples/make_bench_exports.py        # rewrites the five files
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

import tengfield as tf

HERE = Path(__file__).resolve().parent
START_S, SPAN_S, RATE_HZ, C_P_PF, APERTURE_S = 0.5, 0.2, 5000.0, 338.0, 1.667e-3


def trace():
    """(t [s] from the first sample, V read [V], Q read [C])."""
    scene = tf.default_scene().with_values(instrument={"capacitance_pF": C_P_PF,
                                                       "aperture_s": APERTURE_S})
    r = tf.run(scene)
    step = int(round(1.0 / (RATE_HZ * (r.t[1] - r.t[0]))))
    keep = np.flatnonzero((r.t >= START_S - 1e-12) & (r.t < START_S + SPAN_S - 1e-9))[::step]
    return r.t[keep] - r.t[keep[0]], r.waveforms["V_read_V"][keep], r.waveforms["Q_read_C"][keep]


def write_tek(path: Path, t, v) -> None:
    meta = [("Model", "MSO44"), ("Firmware Version", "1.30.3.15"), ("", ""),
            ("Waveform Type", "ANALOG"), ("Point Format", "Y"), ("Horizontal Units", "s"),
            ("Horizontal Scale", "0.02"), ("Sample Interval", f"{1 / RATE_HZ:g}"),
            ("Record Length", str(t.size)), ("Gating", "0.0% to 100.0%"),
            ("Vertical Units", "V"), ("Label", "TENG")]
    with open(path, "w", newline="") as f:
        for key, value in meta:
            f.write(f"{key},{value}\n")
        f.write("TIME,CH1\n")
        for ti, vi in zip(t, v):
            f.write(f"{ti:.6e},{vi:.6e}\n")


def write_electrometer(path: Path, t, q) -> None:
    with open(path, "w", newline="") as f:
        f.write("Keithley 6514 electrometer, charge mode, 2 nC range\n")
        f.write("Logged by a bench PC\n\n")
        f.write("Time (ms)\tCharge (nC)\n")
        for ti, qi in zip(t, q):
            f.write(f"{ti * 1e3:.4f}\t{qi * 1e9:.6f}\n")


def write_semicolon(path: Path, t, v, q) -> None:
    with open(path, "w", newline="") as f:
        f.write("TIME [s];CH1 [V];CH2 [nC]\n")
        for ti, vi, qi in zip(t, v, q):
            f.write(f"{ti:.6f};{vi:.6f};{qi * 1e9:.6f}\n".replace(".", ","))


#: the SPICE example: the default scene on this load, this long, sampled at this rate
SPICE_LOAD_OHM, SPICE_DURATION_S, SPICE_RATE_HZ = 1e8, 0.5, 10000.0


def write_spice(lib: Path, netlist: Path) -> None:
    """examples/teng.lib (the default scene's device: its 0.2 s start-up, then its period
    repeated) and examples/teng_load.cir
    (it on a 100 Mohm resistor: ``cd examples && ngspice -b teng_load.cir``)."""
    from tengfield import spice

    scene = tf.default_scene().with_values(
        circuit={"kind": "load", "load_ohm": SPICE_LOAD_OHM},
        run={"duration_s": SPICE_DURATION_S, "settle_periods": 4,
             "sample_rate_hz": SPICE_RATE_HZ})
    r = tf.run(scene)
    spice.export(r, lib, start_up=True)     # from rest, as the run: then its period repeated
    netlist.write_text(spice.load_netlist(SPICE_LOAD_OHM, float(r.t[-1] - r.t[0]),
                                          float(r.t[1] - r.t[0])))


def main() -> list[Path]:
    t, v, q = trace()
    paths = [HERE / "tek_scope.csv", HERE / "electrometer_log.tsv", HERE / "scope_semicolon.csv",
             HERE / "teng.lib", HERE / "teng_load.cir"]
    write_tek(paths[0], t, v)
    write_electrometer(paths[1], t, q)
    write_semicolon(paths[2], t, v, q)
    write_spice(paths[3], paths[4])
    return paths


if __name__ == "__main__":
    for p in main():
        print(f"wrote {p}")
