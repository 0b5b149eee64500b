"""``tengfield run --spice`` from the command line (issue #54): a scene named with
newlines and control characters writes no live line into teng.lib (ngspice reads the
device, not a 1 kohm leak the name held) and no invalid TOML comment (item 2: one
escaping, :func:`tengfield.files.one_line`); sigma = 0 is one error line before the work
(item 13); a long (streamed) run's export reads only the start-up's and the period's
rows, never a whole column (item 10). The field is the analytic plate model, put into
the cache before the CLI runs (the cache key is the field's inputs, not the name)."""
from __future__ import annotations

import shutil
import subprocess
import tomllib

import numpy as np
import pytest

import tengfield as tf
from tengfield import spice
from tengfield.electrical import stream
from tengfield.scene import load_scene

import plate_model as fx

NGSPICE = shutil.which("ngspice")
#: a name that, unescaped, put a resistor and a .control block into teng.lib, and a
#: control character (invalid in a TOML comment) into the scene's printed header
NAME = "run\nRleak out 0 1k\n.control\nquit\n.endc\n\x01*.toml"


def _scene(tmp_path, name: str):
    path = tmp_path / name
    path.write_text(fx.SMALL_SCENE + '\n[circuit]\nkind = "load"\nload_ohm = 1e8\n')
    return path


def test_a_scene_name_with_newlines_puts_no_live_line_into_teng_lib(tmp_path, run_cli):
    path = _scene(tmp_path, NAME)
    cache = tmp_path / "cache"
    tf.run(load_scene(path), cache_dir=cache, solve=fx.plate_model_solve)   # the field
    out = tmp_path / "out"
    proc = run_cli("run", path, "--set", "run.sample_rate_hz=20000", "--spice",
                   "-o", out, "--cache-dir", cache)
    assert proc.returncode == 0, proc.stderr[-3000:]
    text = (out / "teng.lib").read_text()
    head = text.split(".subckt")[0].splitlines()
    assert all(line.startswith("*") or line.startswith(".options") for line in head), head
    assert not any(line.startswith(("Rleak", ".control", "quit", ".endc"))
                   for line in text.splitlines())
    assert "* scene: " + spice_name(path) + " with --set" in text
    assert "* --set run.sample_rate_hz=20000" in text
    out_start = tmp_path / "out-start-up"
    proc = run_cli("run", path, "--set", "run.sample_rate_hz=20000", "--spice-start-up",
                   "--no-plots", "-o", out_start, "--cache-dir", cache)
    assert proc.returncode == 0, proc.stderr[-3000:]
    settle = load_scene(path).run.settle_periods * load_scene(path).excitation.period
    start_text = (out_start / "teng.lib").read_text()
    assert f"* start-up: t = 0 .. {settle:.9g} s is the run's own start" in start_text
    assert f"+ ) r={settle:.12g}" in start_text
    if NGSPICE is None:
        return
    waveforms = np.genfromtxt(out / "waveforms.csv", delimiter=",", names=True)
    t = waveforms["time_s"] - waveforms["time_s"][0]
    step = float(t[1] - t[0])
    (out / "top.cir").write_text(spice.load_netlist(1e8, float(t[-1]), step, output="v.csv"))
    proc = subprocess.run([NGSPICE, "-b", "top.cir"], cwd=out, capture_output=True, text=True,
                          timeout=600)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    simulated = np.loadtxt(out / "v.csv")
    scene = load_scene(path)
    steady = t >= scene.run.settle_periods * scene.excitation.period
    ours = waveforms["V_load_V"][steady]
    theirs = np.interp(t[steady], simulated[:, 0], simulated[:, 1])
    assert np.max(np.abs(ours)) > 0.1              # volts, not the 1 kohm leak's 1e-5 V
    assert np.max(np.abs(theirs)) == pytest.approx(np.max(np.abs(ours)), rel=0.05)


def spice_name(path) -> str:
    """The scene's path as teng.lib's header quotes it: Python's escapes."""
    return (str(path).replace("\\", "\\\\").replace("\n", "\\n")
            .replace("\x01", "\\x01"))


def test_the_printed_scene_of_such_a_file_is_valid_toml(tmp_path, run_cli):
    path = _scene(tmp_path, NAME)
    proc = run_cli("scene", path)
    assert proc.returncode == 0, proc.stderr[-2000:]
    data = tomllib.loads(proc.stdout)        # a control character in a comment: invalid
    assert data["circuit"]["kind"] == "load"
    assert not any(line.startswith("Rleak") for line in proc.stdout.splitlines())


def test_sigma_zero_with_spice_is_one_line_before_the_work(tmp_path, run_cli):
    path = _scene(tmp_path, "base.toml")
    out = tmp_path / "out"
    proc = run_cli("run", path, "--set", "device.surface_charge_uC_per_m2=0", "--spice",
                   "-o", out, "--cache-dir", tmp_path / "cache")
    assert proc.returncode == 2, proc.stderr[-3000:]
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("tengfield: error: --spice with [device] "
                                                   "surface_charge_uC_per_m2 = 0"), lines
    assert not out.exists() and "Traceback" not in proc.stderr


def test_a_streamed_runs_export_reads_no_whole_column(tmp_path, monkeypatch):
    """Item 10: asking a streamed run for a whole column (what the export did: 2.17 GB at
    400 s against 0.40 GB without --spice) raises here; the export still comes out, with
    the same text as the whole-array run's."""
    scene = fx.scene_with(run={"duration_s": 0.6, "settle_periods": 3,
                               "sample_rate_hz": 20000.0}, circuit={"kind": "load"})
    whole = tf.run(scene, cache_dir=tmp_path, solve=fx.plate_model_solve)
    monkeypatch.setattr(stream, "STREAM_ROWS", 10)
    monkeypatch.setattr(stream, "CHUNK_ROWS", 997)
    streamed = tf.run(scene, cache_dir=tmp_path, solve=fx.plate_model_solve)
    assert isinstance(streamed.waveforms, stream.StreamedWaveforms)

    def whole_column(self, name):
        raise AssertionError(f"the whole column {name!r} was built")
    monkeypatch.setattr(stream.StreamedWaveforms, "__getitem__", whole_column)
    monkeypatch.setattr(stream.StreamedWaveforms, "chunks", whole_column)
    for options in ({}, {"start_up": True}):
        assert spice.subcircuit(streamed, **options) == spice.subcircuit(whole, **options)


def test_a_ball_at_rest_with_spice_is_one_line(tmp_path, run_cli):
    """No lift-off, no field solved: C_T(t) is unknown; one line after the run (its
    regime is known only then), no traceback and no -o."""
    path = _scene(tmp_path, "base.toml")
    out = tmp_path / "out"
    proc = run_cli("run", path, "--set", "excitation.amplitude_mm=0.05", "--spice", "-o", out,
                   "--cache-dir", tmp_path / "cache")
    assert proc.returncode == 2, proc.stderr[-3000:]
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("tengfield: error: --spice: the run has "
                                                   "no C_T(t)"), lines
    assert not out.exists()
