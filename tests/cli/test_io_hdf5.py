"""run.h5 (issue #28, "big outputs"): ``[run] output_format = "hdf5"`` and, past the CSV
bound, automatically with one warning; one chunked, compressed file holding waveforms,
trajectory and impacts with units, readable by h5py and pandas; trajectory columns equal
to waveform columns are stored once (hard links)."""
import json
import warnings

import numpy as np
import pytest

import tengfield as tf
from tengfield import io as tio
from tengfield.files import hdf5 as io_hdf5
from tengfield.surrogate.store import _import_h5py

import plate_model as fx

h5py = _import_h5py()


def _result(tmp_path, **run):
    scene = fx.scene_with(run={"duration_s": 1.0, "settle_periods": 2, **run})
    return tf.run(scene, cache_dir=tmp_path / "cache", solve=fx.plate_model_solve)


def test_units_come_from_the_column_names():
    assert io_hdf5.unit_of("gap_velocity_m_per_s") == "m/s"
    assert io_hdf5.unit_of("V_oc_V") == "V" and io_hdf5.unit_of("Q_sc_C") == "C"
    assert io_hdf5.unit_of("I_sc_A") == "A" and io_hdf5.unit_of("time_s") == "s"
    assert io_hdf5.unit_of("table_m") == "m" and io_hdf5.unit_of("plate") == "1"
    assert io_hdf5.unit_of("spin_x_rad_per_s") == "rad/s"


def test_hdf5_holds_the_tables_of_the_csv_files(tmp_path):
    result = _result(tmp_path, output_format="hdf5")
    out = tmp_path / "out"
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)   # chosen: no warning
        written = tio.write_run_outputs(result, out, plots=False)
        written += tio.write_dynamics_outputs(result, out, plots=False)
    names = sorted(p.name for p in out.iterdir())
    assert names == ["run.h5", "summary.json"], names
    assert [p.name for p in written] == ["run.h5", "summary.json"]
    with h5py.File(out / "run.h5", "r") as f:
        assert set(f) == {"waveforms", "trajectory", "impacts"}
        wf = f["waveforms"]
        assert list(wf) == list(tio.WAVEFORM_COLUMNS)
        for name in wf:
            np.testing.assert_array_equal(wf[name][()], result.waveforms[name])
        assert wf["V_oc_V"].attrs["units"] == "V" and wf["I_sc_A"].attrs["units"] == "A"
        assert wf["time_s"].compression == "gzip" and wf["time_s"].chunks is not None
        # the trajectory's columns are the waveforms' ones, stored once
        for name in ("time_s", "gap_m", "gap_velocity_m_per_s", "table_m"):
            assert f["trajectory"][name].id == wf[name].id
        np.testing.assert_array_equal(f["trajectory/gap_m"][()], result.dynamics.gap)
        imp = f["impacts"]
        assert imp["plate"][()].astype(str).tolist() == result.dynamics.impacts.plate.tolist()
        np.testing.assert_array_equal(imp["speed_after_m_per_s"][()],
                                      result.dynamics.impacts.speed_after)
        assert imp["speed_after_m_per_s"].attrs["units"] == "m/s"
        summary = json.loads(f.attrs["summary_json"])
        assert summary["peak_to_peak"]["V_oc_V"] == pytest.approx(
            result.summary["peak_to_peak"]["V_oc_V"])


def test_pandas_reads_it_as_the_docs_say(tmp_path):
    pd = pytest.importorskip("pandas")
    result = _result(tmp_path, output_format="hdf5")
    path = tio.write_run_hdf5(tmp_path / "run.h5", result)
    with h5py.File(path, "r") as f:
        waveforms = pd.DataFrame({name: f["waveforms"][name][()] for name in f["waveforms"]})
    assert list(waveforms.columns) == list(tio.WAVEFORM_COLUMNS)
    assert len(waveforms) == len(result.waveforms["time_s"])
    assert waveforms["Q_sc_C"].iloc[-1] == result.waveforms["Q_sc_C"][-1]


def test_past_the_csv_bound_the_tables_go_to_hdf5_with_one_warning(tmp_path, monkeypatch):
    result = _result(tmp_path)                  # output_format = "csv" (the default)
    rows = len(result.waveforms["time_s"])
    monkeypatch.setattr(io_hdf5, "MAX_CSV_ROWS", rows - 1)
    out = tmp_path / "out"
    with pytest.warns(RuntimeWarning, match=r"pass the CSV bound .*run\.h5") as caught:
        tio.write_run_outputs(result, out, plots=False)
        tio.write_dynamics_outputs(result, out, plots=False)
    assert len([w for w in caught if "CSV bound" in str(w.message)]) == 1
    assert sorted(p.name for p in out.iterdir()) == ["run.h5", "summary.json"]
    # at the bound: CSV as before
    monkeypatch.setattr(io_hdf5, "MAX_CSV_ROWS", rows)
    out2 = tmp_path / "out2"
    tio.write_run_outputs(result, out2, plots=False)
    tio.write_dynamics_outputs(result, out2, plots=False)
    assert sorted(p.name for p in out2.iterdir()) == ["impacts.csv", "summary.json",
                                                      "waveforms.csv"]


def test_columns_are_written_a_chunk_at_a_time(tmp_path, monkeypatch):
    """A column longer than a chunk is written in pieces (CHUNK_ROWS each) and reads back
    whole; a table that does not fit the disk is refused before HDF5 writes a byte."""
    monkeypatch.setattr(io_hdf5, "CHUNK_ROWS", 1000)
    x = np.linspace(0.0, 1.0, 4321)
    path = io_hdf5.write_tables(tmp_path / "t.h5", {"a": {"time_s": x, "V_oc_V": x ** 2}})
    with h5py.File(path, "r") as f:
        assert f["a/time_s"].chunks == (1000,)
        np.testing.assert_array_equal(f["a/V_oc_V"][()], x ** 2)
    import shutil
    from collections import namedtuple
    usage = namedtuple("usage", "total used free")
    monkeypatch.setattr(shutil, "disk_usage", lambda p: usage(10**6, 10**6 - 1000, 1000))
    with pytest.raises(OSError, match="No space left on device") as err:
        io_hdf5.write_tables(tmp_path / "u.h5", {"a": {"time_s": x}})
    assert err.value.filename == str(tmp_path / "u.h5")
    assert not (tmp_path / "u.h5").exists()


@pytest.mark.slow
def test_cli_run_in_hdf5_with_figures(tmp_path, run_cli):
    """End to end, figures on: run.h5 instead of the three CSV files."""
    scene = tmp_path / "s.toml"
    scene.write_text('[run]\nduration_s = 1.0\nsettle_periods = 2\noutput_format = "hdf5"\n')
    out = run_cli("run", scene, "-o", tmp_path / "out")
    assert out.returncode == 0, out.stderr
    names = sorted(p.name for p in (tmp_path / "out").iterdir() if not p.name.startswith("."))
    assert names == ["run.h5", "summary.json", "surrogate.png", "trajectory.png",
                     "waveforms.png"]
    with h5py.File(tmp_path / "out" / "run.h5", "r") as f:
        assert f["waveforms/V_oc_V"].shape == (20001,)
        assert f["trajectory/time_s"].id == f["waveforms/time_s"].id


@pytest.mark.slow
def test_the_papers_15_minute_record_runs_in_hdf5_with_bounded_memory(tmp_path, cli_env, python):
    """duration_s = 900 at the default 20 kHz (1.8e7 samples), figures on: one warning,
    run.h5 instead of 3.1 GB of CSV, and the main process peaks well below the 4.7 GB
    it took with CSV, the 2.0 GB of whole-record arrays in run.h5 and the 0.94 GB of the
    streamed electrical stage with whole dynamics arrays (0.72 GB of them): with the
    dynamics sampled on request 0.26 GB measured, as for 100 s (benchmarks/long_run.py)."""
    import subprocess

    scene = tmp_path / "s.toml"
    env = cli_env()
    # VmHWM: this process's own peak (a child's ru_maxrss also counts the pytest process's
    # RSS at the fork). The field's surrogate first (its solves, dolfinx and gmsh are not what is measured:
    # a cold cache adds them to the peak), then the 15 minutes from the cached surrogate. The
    # user's cache (as test_cli_run_in_hdf5_with_figures, the same default field): usually
    # a hit, no field solve at all; a cold cache computes it here as before
    scene.write_text("[run]\nduration_s = 1\n")
    warm = subprocess.run([python, "-m", "tengfield.cli", "run", str(scene), "--no-plots",
                           "-o", str(tmp_path / "warm")], capture_output=True, text=True,
                          env=env, timeout=1800)
    assert warm.returncode == 0, warm.stderr[-3000:]
    scene.write_text("[run]\nduration_s = 900\n")
    code = ("import resource, runpy, sys\n"
            f"sys.argv = ['tengfield', 'run', {str(scene)!r}, '-o', {str(tmp_path / 'out')!r}]\n"
            "try:\n    runpy.run_module('tengfield.cli', run_name='__main__')\n"
            "finally:\n    print('PEAK_KB', next(line for line in open('/proc/self/status')"
            " if line.startswith('VmHWM')).split()[1], file=sys.stderr)\n")
    out = subprocess.run([python, "-c", code], capture_output=True, text=True, env=env,
                         timeout=1800)
    assert out.returncode == 0, out.stderr[-3000:]
    said = [line for line in out.stderr.splitlines() if line.startswith("tengfield:")]
    assert len([s for s in said if "CSV bound" in s]) == 1, said
    peak_gb = int(out.stderr.split("PEAK_KB")[1].split()[0]) / 1e6
    assert peak_gb < 0.5, peak_gb
    files = {p.name: p.stat().st_size for p in (tmp_path / "out").iterdir()
             if not p.name.startswith(".")}
    assert "waveforms.csv" not in files and "trajectory.csv" not in files
    assert files["run.h5"] < 0.5e9 and "waveforms.png" in files and "record.png" in files
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["stages"]["circuit"]["details"]["streamed_chunks"] == 69
    with h5py.File(tmp_path / "out" / "run.h5", "r") as f:
        t = f["waveforms/time_s"]
        assert t.shape == (18_000_001,)
        assert t[-1] == pytest.approx(900.0)


def test_run_trajectory_csv_does_not_repeat_the_waveform_columns(tmp_path):
    """`tengfield run` of a 1-D model writes no trajectory.csv: its columns (time, gap,
    velocity, table) are all in waveforms.csv, which gives the dynamics back."""
    pd = pytest.importorskip("pandas")
    result = _result(tmp_path)
    out = tmp_path / "out"
    tio.write_run_outputs(result, out, plots=False)
    tio.write_dynamics_outputs(result, out, plots=False)
    assert not (out / "trajectory.csv").exists() and (out / "impacts.csv").exists()
    waveforms = pd.read_csv(out / "waveforms.csv", float_precision="round_trip")
    np.testing.assert_array_equal(waveforms["time_s"].to_numpy(), result.dynamics.t)
    # waveforms.csv writes the motion with 10 significant digits (trajectory.csv of
    # `tengfield dynamics` and run.h5 hold every double)
    np.testing.assert_allclose(waveforms["gap_m"].to_numpy(), result.dynamics.gap, rtol=1e-9,
                               atol=1e-9 * result.dynamics.gap.max())
    # tengfield dynamics keeps its full table
    (tmp_path / "dyn").mkdir()
    tio.write_dynamics_files(result.dynamics, result.scene, tmp_path / "dyn", plots=False)
    assert list(pd.read_csv(tmp_path / "dyn" / "trajectory.csv").columns) == [
        "time_s", "gap_m", "gap_velocity_m_per_s", "table_m"]


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["open", "load", "rectifier"])
def test_a_streamed_run_writes_the_same_run_h5(tmp_path, monkeypatch, kind):
    """A long run's electrical stage streams (tengfield.electrical.stream: forced here with
    tiny chunks): run.h5 holds the same numbers as the whole-record run's, bit for bit,
    written a chunk at a time (the trajectory columns still hard links), and its
    figures (the last 5 periods, the V-Q loop) are drawn from what the stream kept. The
    dynamics' columns are sampled on request, as a long run's (dynamics/columns.py)."""
    from tengfield.dynamics import columns
    from tengfield.electrical import stream

    scene = fx.scene_with(run={"duration_s": 1.0, "settle_periods": 2,
                               "output_format": "hdf5"},
                          circuit={"kind": kind, "load_ohm": 1e8})
    whole = tf.run(scene, cache_dir=tmp_path / "cache", solve=fx.plate_model_solve)
    tio.write_run_outputs(whole, tmp_path / "whole", plots=True)
    tio.write_dynamics_outputs(whole, tmp_path / "whole", plots=True)
    monkeypatch.setattr(stream, "STREAM_ROWS", 100)
    monkeypatch.setattr(stream, "CHUNK_ROWS", 3000)
    monkeypatch.setattr(io_hdf5, "CHUNK_ROWS", 1000)
    monkeypatch.setattr(columns, "LAZY_ROWS", 100)
    streamed = tf.run(scene, cache_dir=tmp_path / "cache", solve=fx.plate_model_solve)
    assert isinstance(streamed.waveforms, stream.StreamedWaveforms)
    assert isinstance(streamed.dynamics.gap, columns.SampledColumn)
    written = tio.write_run_outputs(streamed, tmp_path / "streamed", plots=True)
    written += tio.write_dynamics_outputs(streamed, tmp_path / "streamed", plots=True)
    names = {p.name for p in written}
    assert {"run.h5", "waveforms.png", "summary.json"} <= names
    if kind != "open":
        assert "vq.png" in names
    if kind == "rectifier":
        assert "charging.png" in names
    a = io_hdf5.read_tables(tmp_path / "whole" / "run.h5")
    b = io_hdf5.read_tables(tmp_path / "streamed" / "run.h5")
    assert list(a["waveforms"]) == list(b["waveforms"])
    for group in ("trajectory", "impacts"):
        assert list(a[group]) == list(b[group])
        for column, values in a[group].items():
            np.testing.assert_array_equal(b[group][column], values, err_msg=column)
    for column, values in a["waveforms"].items():
        if kind == "rectifier":      # the bridge charge summed per chunk: 1e-12
            np.testing.assert_allclose(b["waveforms"][column], values, rtol=1e-12,
                                       atol=1e-12 * np.max(np.abs(values)), err_msg=column)
        else:
            np.testing.assert_array_equal(b["waveforms"][column], values, err_msg=column)
    with h5py.File(tmp_path / "streamed" / "run.h5", "r") as f:
        assert f["trajectory/time_s"].id == f["waveforms/time_s"].id
        assert f["waveforms/V_oc_V"].chunks == (1000,)
        assert f["waveforms"].attrs["rows"] == len(whole.t)
        summary = json.loads(f.attrs["summary_json"])
    assert summary["peak_to_peak"] == whole.summary["peak_to_peak"]
    # the same figures, and record.png: the whole run as a min/max envelope
    assert sorted(p.name for p in (tmp_path / "streamed").iterdir() if p.suffix == ".png") \
        == sorted(["record.png"] + [p.name for p in (tmp_path / "whole").iterdir()
                                    if p.suffix == ".png"])


def test_a_streamed_run_writes_the_same_waveforms_csv(tmp_path, monkeypatch):
    """Under the CSV bound a streamed run writes waveforms.csv a chunk at a time (no
    whole column held, the dynamics' columns sampled on request): the same bytes as the
    whole-record run's."""
    from tengfield.dynamics import columns
    from tengfield.electrical import stream

    scene = fx.scene_with(run={"duration_s": 1.0, "settle_periods": 2},
                          circuit={"kind": "load", "load_ohm": 1e8,
                                   "parallel_capacitance_pF": 338.0})
    whole = tf.run(scene, cache_dir=tmp_path / "cache", solve=fx.plate_model_solve)
    tio.write_run_outputs(whole, tmp_path / "whole", plots=False)
    monkeypatch.setattr(stream, "STREAM_ROWS", 100)
    monkeypatch.setattr(stream, "CHUNK_ROWS", 3000)
    monkeypatch.setattr(columns, "LAZY_ROWS", 100)
    streamed = tf.run(scene, cache_dir=tmp_path / "cache", solve=fx.plate_model_solve)
    assert isinstance(streamed.waveforms, stream.StreamedWaveforms)
    assert isinstance(streamed.dynamics.t, columns.SampledColumn)
    tio.write_run_outputs(streamed, tmp_path / "streamed", plots=False)
    assert streamed.waveforms._whole is None          # never held whole
    text = (tmp_path / "streamed" / "waveforms.csv").read_bytes()
    assert text == (tmp_path / "whole" / "waveforms.csv").read_bytes()
    assert text.count(b"time_s") == 1 and text.count(b"\n") == len(whole.t) + 1


@pytest.mark.parametrize("streamed", [False, True], ids=["whole", "streamed"])
def test_run_h5_holds_the_read_columns_of_the_csv(tmp_path, monkeypatch, streamed):
    """Issue 54 item 1: run.h5 holds the columns waveforms.csv holds, the instrument's read
    ones included (V_read_V, Q_read_C, I_read_A were dropped; also by the streamed run.h5
    of a long run)."""
    import csv

    from tengfield.dynamics import columns
    from tengfield.electrical import stream

    scene = fx.scene_with(run={"duration_s": 1.0, "settle_periods": 2},
                          instrument={"capacitance_pF": 338.0, "bandwidth_hz": 300.0})
    whole = tf.run(scene, cache_dir=tmp_path / "cache", solve=fx.plate_model_solve)
    tio.write_run_outputs(whole, tmp_path / "csv", plots=False)
    with open(tmp_path / "csv" / "waveforms.csv") as fh:
        header = next(csv.reader(fh))
    assert {"V_read_V", "Q_read_C", "I_read_A"} <= set(header)
    if streamed:
        monkeypatch.setattr(stream, "STREAM_ROWS", 100)
        monkeypatch.setattr(stream, "CHUNK_ROWS", 3000)
        monkeypatch.setattr(columns, "LAZY_ROWS", 100)
    result = tf.run(scene.with_values(run={"output_format": "hdf5"}),
                    cache_dir=tmp_path / "cache", solve=fx.plate_model_solve)
    assert isinstance(result.waveforms, stream.StreamedWaveforms) == streamed
    tio.write_run_outputs(result, tmp_path / "h5", plots=False)
    tables = io_hdf5.read_tables(tmp_path / "h5" / "run.h5")
    assert list(tables["waveforms"]) == header
    for column in ("V_read_V", "Q_read_C", "I_read_A"):
        np.testing.assert_allclose(tables["waveforms"][column], whole.waveforms[column],
                                   rtol=0, atol=1e-9 * np.max(np.abs(whole.waveforms[column])))
    with h5py.File(tmp_path / "h5" / "run.h5", "r") as f:
        assert f["waveforms/V_read_V"].attrs["units"] == "V"
        assert f["waveforms/Q_read_C"].attrs["units"] == "C"
