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
