"""#43 item 18: ``fit --measured out/run.h5``, the tool's own format, was refused as
"binary data"; its /waveforms table is read as a measured trace (the columns a run's CSV
has), so a fit to a run's own waveforms gives back the run's surface charge."""
from __future__ import annotations

import json

import h5py
import numpy as np
import pytest

from tengfield.cli import main

RUN = "[run]\nduration_s = 0.3\nsettle_periods = 2\nsample_rate_hz = 2000\n"


@pytest.mark.slow
def test_fit_to_a_runs_own_run_h5_gives_its_charge_back(tmp_path, capsys):
    measured = tmp_path / "measured.toml"
    measured.write_text(RUN + 'output_format = "hdf5"\n[device]\n'
                        "surface_charge_uC_per_m2 = -12.0\n")
    model = tmp_path / "model.toml"
    model.write_text(RUN)           # the default charge, -8 uC/m^2, as the fit's start
    assert main(["run", str(measured), "--no-plots", "-o", str(tmp_path / "run")]) == 0
    run_h5 = tmp_path / "run" / "run.h5"
    assert run_h5.is_file()
    assert main(["fit", str(model), "--measured", str(run_h5),
                 "-o", str(tmp_path / "fit")]) == 0
    fitted = json.loads((tmp_path / "fit" / "fit.json").read_text())["parameters"]
    assert fitted["surface_charge_uC_per_m2"]["value"] == pytest.approx(-12.0, rel=1e-4)
    assert (tmp_path / "fit" / "fit.png").is_file()


def test_an_hdf5_file_without_waveforms_is_one_line(tmp_path, capsys):
    other = tmp_path / "other.h5"
    with h5py.File(other, "w") as f:
        f["data"] = np.arange(10.0)
    assert main(["fit", "--measured", str(other), "-o", str(tmp_path / "fit")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "without a /waveforms table" in err, err
    assert not (tmp_path / "fit").exists()


# ---------------------------------------------------------------------------
# issue 54 item 1: the read columns of a run.h5 are what a model read through an
# [instrument] is compared with; a file with only the ideal ones is refused in one line
def test_a_model_read_through_an_instrument_reads_the_files_read_columns(tmp_path):
    import tengfield as tf
    from tengfield import io as tio
    from tengfield.fit.spec import parse_fit_section, read_trace

    import plate_model as fx

    scene = fx.scene_with(run={"duration_s": 0.4, "settle_periods": 2,
                               "output_format": "hdf5"},
                          instrument={"capacitance_pF": 338.0})
    result = tf.run(scene, cache_dir=tmp_path / "cache", solve=fx.plate_model_solve)
    tio.write_run_outputs(result, tmp_path / "run", plots=False)
    trace = read_trace(tmp_path / "run" / "run.h5", parse_fit_section(scene))
    assert {c.quantity: c.column for c in trace.columns} == {
        "V": "V_read_V", "Q": "Q_read_C", "I": "I_read_A"}
    np.testing.assert_array_equal(trace.values["V"], result.waveforms["V_read_V"])
    # kV of the ideal V_OC against ~1 V read through 338 pF: not what the model compares
    assert np.max(np.abs(result.waveforms["V_oc_V"])) > 100 * np.max(np.abs(trace.values["V"]))


def test_a_file_with_only_the_ideal_voltage_is_refused_for_a_read_model(tmp_path, capsys):
    """A run.h5 (or CSV) without V_read_V (the ideal V_oc_V alone, as run.h5 was written
    before) fitted with a model read through C_p: one line naming both columns, before any
    work (it paired kV with the read ~1 V: residual 150 % of the signal, no word)."""
    from tengfield.files.hdf5 import write_tables

    t = np.linspace(0.0, 0.1, 501)
    write_tables(tmp_path / "old.h5", {"waveforms": {
        "time_s": t, "V_oc_V": 1e3 * np.sin(60 * t), "Q_sc_C": 1e-10 * np.sin(60 * t),
        "I_sc_A": 6e-9 * np.cos(60 * t)}})
    model = tmp_path / "model.toml"
    model.write_text(RUN + "[instrument]\ncapacitance_pF = 338\n")
    assert main(["fit", str(model), "--measured", str(tmp_path / "old.h5"),
                 "-o", str(tmp_path / "fit")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "V_read_V" in err and "V_oc_V" in err, err
    assert "[fit.columns.V]" in err
    assert not (tmp_path / "fit").exists()
    # named in [fit.columns], the ideal column is the user's choice: read as asked
    from tengfield.fit.spec import parse_fit_section, read_trace
    import tengfield as tf
    scene = tf.load_scene(model).with_values(fit={"columns": {"V": {"column": "V_oc_V"}}})
    trace = read_trace(tmp_path / "old.h5", parse_fit_section(scene))
    assert [c.column for c in trace.columns] == ["V_oc_V"]


@pytest.mark.slow
def test_fit_of_the_issues_run_h5_through_the_instrument(tmp_path, capsys):
    """The issue's case end to end, figures on: `run --set run.output_format='"hdf5"'
    --set instrument.capacitance_pF=338` on the base scene, then `fit --measured run.h5`
    with the same scene: V is compared as V_read_V, the residual is small (150 % before)."""
    base = ("[run]\nduration_s = 0.3\nsettle_periods = 2\nsample_rate_hz = 5000\n"
            "[field]\ndegree = 1\nmesh_size_mm = 1.5\ntolerance = 1e-2\n"
            "[instrument]\ncapacitance_pF = 338\n")
    scene = tmp_path / "base.toml"
    scene.write_text(base)
    assert main(["run", str(scene), "--set", 'run.output_format="hdf5"',
                 "-o", str(tmp_path / "run")]) == 0
    with h5py.File(tmp_path / "run" / "run.h5", "r") as f:
        assert {"V_read_V", "Q_read_C", "I_read_A"} <= set(f["waveforms"])
    assert main(["fit", str(scene), "--measured", str(tmp_path / "run" / "run.h5"),
                 "-o", str(tmp_path / "fit")]) == 0
    fit = json.loads((tmp_path / "fit" / "fit.json").read_text())
    assert fit["residuals"]["V"]["tool_key"] == "V_read_V"
    assert fit["residuals"]["V"]["percent_of_signal_rms"] < 1.0
    assert (tmp_path / "fit" / "fit.png").is_file()
