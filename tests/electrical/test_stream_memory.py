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
import json, resource, sys, tracemalloc
def peak_kb():   # this process's own peak RSS [kB]: ru_maxrss of a child also counts
    # the parent's RSS at the fork (the copied address space), VmHWM does not
    return int(next(l for l in open('/proc/self/status') if l.startswith('VmHWM')).split()[1])
sys.path.insert(0, {tests!r})
import plate_model as fx
import tengfield as tf
from tengfield import io as tio
from tengfield.dynamics import simulate
from tengfield.electrical import stream

stream.STREAM_ROWS = {stream_rows}
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
scene = scene_of({duration})
dynamics = simulate(scene)
rss0 = peak_kb()
tracemalloc.start()
r = outputs(scene, dynamics, out)
peak = tracemalloc.get_traced_memory()[1]
rss1 = peak_kb()
print(json.dumps({{"traced_peak_MB": peak / 1e6, "rss_rise_MB": (rss1 - rss0) / 1e3,
                  "rows": len(r.t), "streamed": hasattr(r.waveforms, "chunks")}}))
"""


LOAD = {"kind": "load", "load_ohm": 1e8, "parallel_capacitance_pF": 338.0}
#: the plate model's cell charges this store through the chip's levels many times
UVLO = {"kind": "rectifier", "storage_capacitance_uF": 1e-4, "pmic": "uvlo",
        "pmic_quiescent_current_A": 0.0, "uvlo_rising_V": 20.0, "uvlo_falling_V": 10.0,
        "pmic_output_V": 3.3, "pmic_load_ohm": 1e7, "pmic_shunt_V": 100.0}


def _measure(python, env, tmp_path, duration, stream_rows, circuit):
    name = f"d{duration:g}-s{stream_rows}-{circuit['kind']}"
    code = CHILD.format(tests=str(TESTS), stream_rows=stream_rows, duration=duration,
                        cache=str(tmp_path / "cache"), out=str(tmp_path / name),
                        circuit=circuit)
    proc = subprocess.run([python, "-c", code], capture_output=True, text=True, env=env,
                          timeout=900)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


@pytest.mark.slow
@pytest.mark.parametrize("circuit", [LOAD, UVLO], ids=["load-Cp", "rectifier-uvlo"])
def test_a_run_4x_longer_streams_in_the_same_memory(tmp_path, python, cli_env, circuit):
    env = cli_env(MPLBACKEND="Agg")
    # 5 s and 20 s at the default 20 kHz: 1e5 and 4e5 rows, 6 and 24 chunks of STREAM_ROWS
    short = _measure(python, env, tmp_path, 5.0, 1 << 14, circuit)
    long = _measure(python, env, tmp_path, 20.0, 1 << 14, circuit)
    assert short["streamed"] and long["streamed"]
    assert long["rows"] > 3.9 * short["rows"] > 3.5e5
    assert long["traced_peak_MB"] < 1.3 * short["traced_peak_MB"], (short, long)
    assert long["rss_rise_MB"] < 1.3 * short["rss_rise_MB"] + 20.0, (short, long)
    print("streamed", circuit["kind"], short, long)
    if circuit is not LOAD:
        return
    # the control: the same outputs from whole-record arrays grow with the run (so the
    # bound above is one a proportional implementation would exceed)
    whole_short = _measure(python, env, tmp_path, 5.0, 1 << 40, circuit)
    whole_long = _measure(python, env, tmp_path, 20.0, 1 << 40, circuit)
    assert not whole_long["streamed"]
    assert whole_long["traced_peak_MB"] > 2.5 * whole_short["traced_peak_MB"], \
        (whole_short, whole_long)
    assert long["traced_peak_MB"] < 0.5 * whole_long["traced_peak_MB"]
    print("whole", whole_short, whole_long)


#: the whole process: the dynamics (its columns sampled on request past LAZY_ROWS), the
#: surrogate, the streamed electrical stage, run.h5 and the figures
WHOLE = """
import json, resource, sys
def peak_kb():   # this process's own peak RSS [kB]: ru_maxrss of a child also counts
    # the parent's RSS at the fork (the copied address space), VmHWM does not
    return int(next(l for l in open('/proc/self/status') if l.startswith('VmHWM')).split()[1])
sys.path.insert(0, {tests!r})
import plate_model as fx
import tengfield as tf
from tengfield import io as tio
from tengfield.dynamics import columns, simulate

columns.LAZY_ROWS = {lazy_rows}
scene = fx.scene_with(run={{"duration_s": {duration}, "settle_periods": 2,
                           "output_format": "hdf5"}}, circuit={circuit!r})
r = tf.run(scene, cache_dir={cache!r}, solve=fx.plate_model_solve)
tio.write_run_outputs(r, {out!r}, plots=True)
tio.write_dynamics_outputs(r, {out!r}, plots=True)
print(json.dumps({{"peak_rss_MB": peak_kb() / 1e3,
                  "rows": len(r.t), "streamed": hasattr(r.waveforms, "chunks"),
                  "sampled": type(r.dynamics.gap).__name__ == "SampledColumn"}}))
"""


def _whole(python, env, tmp_path, duration, lazy_rows, circuit):
    name = f"whole-d{duration:g}-l{lazy_rows}"
    code = WHOLE.format(tests=str(TESTS), lazy_rows=lazy_rows, duration=duration,
                        cache=str(tmp_path / "cache"), out=str(tmp_path / name),
                        circuit=circuit)
    proc = subprocess.run([python, "-c", code], capture_output=True, text=True, env=env,
                          timeout=1800)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


@pytest.mark.slow
def test_a_run_4x_longer_has_the_same_peak_memory_dynamics_included(tmp_path, python, cli_env):
    """Issue #28 / #30.11: the whole process's peak RSS (VmHWM of a child: the
    dynamics, surrogate, streamed circuit, run.h5, figures) of a run 4x longer is < 1.2x
    that of the shorter one, now that the dynamics' columns are sampled on request; the
    control (whole dynamics arrays, LAZY_ROWS out of reach) grows past that bound."""
    env = cli_env(MPLBACKEND="Agg")
    short = _whole(python, env, tmp_path, 60.0, 1 << 20, LOAD)
    long = _whole(python, env, tmp_path, 240.0, 1 << 20, LOAD)
    assert short["sampled"] and long["sampled"] and short["streamed"] and long["streamed"]
    assert long["rows"] > 3.9 * short["rows"] > 1.1e6
    assert long["peak_rss_MB"] < 1.2 * short["peak_rss_MB"], (short, long)
    print("sampled", short, long)
    whole_short = _whole(python, env, tmp_path, 60.0, 1 << 40, LOAD)
    whole_long = _whole(python, env, tmp_path, 240.0, 1 << 40, LOAD)
    assert not whole_long["sampled"] and whole_long["streamed"]
    assert whole_long["peak_rss_MB"] > 1.2 * whole_short["peak_rss_MB"], \
        (whole_short, whole_long)
    print("whole", whole_short, whole_long)
