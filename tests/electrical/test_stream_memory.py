"""Memory of a streamed run does not grow with the run (issue #28 last item, #30.11):
everything after the dynamics (surrogate, circuit, summary, run.h5, figures) peaks at
the same memory for a run 4x longer, where the whole-record stage (the control, streaming
switched off) grows with it. Measured in a child process: tracemalloc's peak of what is
allocated after the dynamics (numpy's arrays included), and the peak RSS's (VmHWM) rise over the
dynamics' level. The dynamics' own columns are not the electrical stage's: past
LAZY_ROWS they are sampled on request (tengfield/dynamics/columns.py); the last test
measures the whole process, dynamics included (docs/long_runs.md)."""
from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest

TESTS = Path(__file__).resolve().parents[1]

CHILD = """
import gc, json, os, sys, tracemalloc
def peak_kb():   # this process's own peak RSS [kB]: VmHWM (a forked child's starts at
    # its RSS at the fork: the parent's pages it shares count, its rise is its own)
    return int(next(l for l in open('/proc/self/status') if l.startswith('VmHWM')).split()[1])
sys.path.insert(0, {tests!r})
import plate_model as fx
import tengfield as tf
from tengfield import io as tio
from tengfield.dynamics import simulate
from tengfield.electrical import stream

stream.CHUNK_ROWS = 1 << 14
cache, out = {cache!r}, {out!r}

def scene_of(duration):
    return fx.scene_with(run={{"duration_s": duration, "settle_periods": 2,
                               "output_format": "hdf5"}}, circuit={circuit!r})

def outputs(scene, dynamics, directory):
    r = tf.run(scene, simulate=lambda s: dynamics, cache_dir=cache,
               solve=fx.plate_model_solve)
    tio.write_run_outputs(r, directory, plots=True)
    tio.write_dynamics_outputs(r, directory, plots=True)
    return r

warm = scene_of(0.5)                  # the surrogate, imports, matplotlib: not measured
outputs(warm, simulate(warm), out + "-warm")
del warm
gc.collect()
for duration, stream_rows in {runs!r}:    # each in a fresh fork of this warmed process
    sys.stdout.flush()
    pid = os.fork()
    if pid == 0:
        stream.STREAM_ROWS = stream_rows
        scene = scene_of(duration)
        dynamics = simulate(scene)
        rss0 = peak_kb()
        tracemalloc.start()
        r = outputs(scene, dynamics, f"{{out}}-d{{duration:g}}-s{{stream_rows}}")
        peak = tracemalloc.get_traced_memory()[1]
        rss1 = peak_kb()
        print(json.dumps({{"duration_s": duration, "stream_rows": stream_rows,
                          "traced_peak_MB": peak / 1e6, "rss_rise_MB": (rss1 - rss0) / 1e3,
                          "rows": len(r.t), "streamed": hasattr(r.waveforms, "chunks")}}))
        sys.stdout.flush()
        os._exit(0)
    _, status = os.waitpid(pid, 0)
    assert status == 0, (duration, stream_rows, status)
"""


LOAD = {"kind": "load", "load_ohm": 1e8, "parallel_capacitance_pF": 338.0}
#: the plate model's cell charges this store through the chip's levels many times
UVLO = {"kind": "rectifier", "storage_capacitance_uF": 1e-4, "pmic": "uvlo",
        "pmic_quiescent_current_A": 0.0, "uvlo_rising_V": 20.0, "uvlo_falling_V": 10.0,
        "pmic_output_V": 3.3, "pmic_load_ohm": 1e7, "pmic_shunt_V": 100.0}


def _measure(python, env, tmp_path, circuit, runs):
    """One child process, warmed once, measures each (duration [s], STREAM_ROWS) of
    ``runs`` in a fork of its own: a dict per run, in order."""
    code = CHILD.format(tests=str(TESTS), runs=list(runs), cache=str(tmp_path / "cache"),
                        out=str(tmp_path / circuit["kind"]), circuit=circuit)
    proc = subprocess.run([python, "-c", code], capture_output=True, text=True, env=env,
                          timeout=900)
    assert proc.returncode == 0, proc.stderr[-3000:]
    measured = [json.loads(line) for line in proc.stdout.splitlines() if line.startswith("{")]
    assert [(m["duration_s"], m["stream_rows"]) for m in measured] == list(runs), proc.stdout
    return measured


#: 4 s and 16 s at the default 20 kHz: 8e4 and 3.2e5 rows, 5 and 20 chunks of STREAM_ROWS;
#: the whole-record control grows by ~235 bytes a row (19 MB and 75 MB traced), far past
#: the streamed stage's ~20 MB at either length
SHORT_S, LONG_S = 4.0, 16.0
STREAMED, WHOLE_RECORD = 1 << 14, 1 << 40


@pytest.mark.slow
@pytest.mark.parametrize("circuit", [LOAD, UVLO], ids=["load-Cp", "rectifier-uvlo"])
def test_a_run_4x_longer_streams_in_the_same_memory(tmp_path, python, cli_env, circuit):
    env = cli_env(MPLBACKEND="Agg")
    runs = [(SHORT_S, STREAMED), (LONG_S, STREAMED)]
    if circuit is LOAD:
        # the control: the same outputs from whole-record arrays grow with the run (so the
        # bound below is one a proportional implementation would exceed)
        runs += [(SHORT_S, WHOLE_RECORD), (LONG_S, WHOLE_RECORD)]
    measured = _measure(python, env, tmp_path, circuit, runs)
    short, long = measured[:2]
    assert short["streamed"] and long["streamed"]
    assert long["rows"] > 3.9 * short["rows"] > 3e5
    assert long["traced_peak_MB"] < 1.3 * short["traced_peak_MB"], (short, long)
    assert long["rss_rise_MB"] < 1.3 * short["rss_rise_MB"] + 20.0, (short, long)
    print("streamed", circuit["kind"], short, long)
    if circuit is not LOAD:
        return
    whole_short, whole_long = measured[2:]
    assert not whole_long["streamed"]
    assert whole_long["traced_peak_MB"] > 2.5 * whole_short["traced_peak_MB"], \
        (whole_short, whole_long)
    assert long["traced_peak_MB"] < 0.5 * whole_long["traced_peak_MB"]
    print("whole", whole_short, whole_long)


#: the whole process: the dynamics (its columns sampled on request past LAZY_ROWS), the
#: surrogate, the streamed electrical stage, run.h5 and the figures
WHOLE = """
import json, os, sys
def peak_kb():   # this process's own peak RSS [kB]: VmHWM (a forked child's starts at its
    # RSS at the fork, the imports' pages it shares with this process: a fresh process's)
    return int(next(l for l in open('/proc/self/status') if l.startswith('VmHWM')).split()[1])
sys.path.insert(0, {tests!r})
import plate_model as fx
import tengfield as tf
from tengfield import io as tio
from tengfield.dynamics import columns, simulate

for duration, lazy_rows in {runs!r}:   # each in a fresh fork of this imported process
    sys.stdout.flush()
    pid = os.fork()
    if pid == 0:
        columns.LAZY_ROWS = lazy_rows
        scene = fx.scene_with(run={{"duration_s": duration, "settle_periods": 2,
                                   "output_format": "hdf5"}}, circuit={circuit!r})
        r = tf.run(scene, cache_dir={cache!r}, solve=fx.plate_model_solve)
        out = f"{{{out!r}}}-d{{duration:g}}-l{{lazy_rows}}"
        tio.write_run_outputs(r, out, plots=True)
        tio.write_dynamics_outputs(r, out, plots=True)
        print(json.dumps({{"duration_s": duration, "lazy_rows": lazy_rows,
                          "peak_rss_MB": peak_kb() / 1e3,
                          "rows": len(r.t), "streamed": hasattr(r.waveforms, "chunks"),
                          "sampled": type(r.dynamics.gap).__name__ == "SampledColumn"}}))
        sys.stdout.flush()
        os._exit(0)
    _, status = os.waitpid(pid, 0)
    assert status == 0, (duration, lazy_rows, status)
"""


def _whole(python, env, tmp_path, circuit, runs):
    """One child process imports once and runs each (duration [s], LAZY_ROWS) of ``runs``
    in a fork of its own (the whole run, from an interpreter that has imported
    tengfield, as a fresh process would): a dict per run, in order."""
    code = WHOLE.format(tests=str(TESTS), runs=list(runs), cache=str(tmp_path / "cache"),
                        out=str(tmp_path / "whole"), circuit=circuit)
    proc = subprocess.run([python, "-c", code], capture_output=True, text=True, env=env,
                          timeout=1800)
    assert proc.returncode == 0, proc.stderr[-3000:]
    measured = [json.loads(line) for line in proc.stdout.splitlines() if line.startswith("{")]
    assert [(m["duration_s"], m["lazy_rows"]) for m in measured] == list(runs), proc.stdout
    return measured


@pytest.mark.slow
def test_a_run_4x_longer_has_the_same_peak_memory_dynamics_included(tmp_path, python, cli_env):
    """Issue #28 / #30.11: the whole process's peak RSS (VmHWM of a child: the
    dynamics, surrogate, streamed circuit, run.h5, figures) of a run 4x longer is < 1.2x
    that of the shorter one, now that the dynamics' columns are sampled on request; the
    control (whole dynamics arrays, LAZY_ROWS out of reach) grows past that bound."""
    env = cli_env(MPLBACKEND="Agg")
    short, long, whole_short, whole_long = _whole(
        python, env, tmp_path, LOAD, [(60.0, 1 << 20), (240.0, 1 << 20),
                                      (60.0, 1 << 40), (240.0, 1 << 40)])
    assert short["sampled"] and long["sampled"] and short["streamed"] and long["streamed"]
    assert long["rows"] > 3.9 * short["rows"] > 1.1e6
    assert long["peak_rss_MB"] < 1.2 * short["peak_rss_MB"], (short, long)
    print("sampled", short, long)
    assert not whole_long["sampled"] and whole_long["streamed"]
    assert whole_long["peak_rss_MB"] > 1.2 * whole_short["peak_rss_MB"], \
        (whole_short, whole_long)
    print("whole", whole_short, whole_long)
