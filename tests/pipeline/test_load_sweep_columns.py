"""Issue #53 item 5: `sweep --load-ohm` writes V, I and P against R (sweep.csv columns:
the load's peak-to-peak and rms voltage and current and the mean power, the numbers a
single `run --set circuit.kind="load"` reports) and draws them against R (log axis), not
single dots on a one-frequency axis."""
from __future__ import annotations

import csv
import json
import math

import pytest

from tengfield import cli, surrogate
from tengfield.plotting.waveforms import sweep_figure
from tengfield.scene import load_scene

import plate_model as fx

SCENE = "[run]\nduration_s = 0.6\nsettle_periods = 2\nsample_rate_hz = 5000.0\n"
LOADS = (1e8, 1e9, 1e10)


def prepared(tmp_path):
    scene_file = tmp_path / "short.toml"
    scene_file.write_text(SCENE)
    cache = tmp_path / "cache"
    scene = load_scene(scene_file)
    surrogate.write_table(surrogate.cache_path(scene, cache),
                          surrogate.precompute(scene, comm=None, solve=fx.plate_model_solve))
    return scene_file, cache


def main(capsys, *argv):
    code = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    assert code == 0, err
    return out, err


def test_a_one_frequency_load_sweep_writes_and_draws_v_i_p_against_r(tmp_path, capsys):
    scene_file, cache = prepared(tmp_path)
    out_dir = tmp_path / "sweep"
    main(capsys, "sweep", scene_file, "--cache-dir", cache, "--frequency-hz", "20",
         "--amplitude-mm", "1.5", "--load-ohm", "1e8:1e10:3", "--jobs", "1", "-o", out_dir)
    assert (out_dir / "sweep.png").is_file() and (out_dir / "sweep.png").stat().st_size > 0
    with open(out_dir / "sweep.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert [float(r["load_ohm"]) for r in rows] == pytest.approx(LOADS)
    for column in ("V_load_pp_V", "I_load_pp_A", "V_load_rms_V", "I_load_rms_A", "P_mean_W"):
        assert all(float(r[column]) > 0 for r in rows), column
    for row in rows:
        r = float(row["load_ohm"])
        run_dir = tmp_path / f"run{r:g}"
        main(capsys, "run", scene_file, "--cache-dir", cache, "--set", 'circuit.kind="load"',
             "--set", f"circuit.load_ohm={r!r}", "--no-plots", "-o", run_dir)
        block = json.loads((run_dir / "summary.json").read_text())["load"]
        assert float(row["P_mean_W"]) == pytest.approx(block["mean_power_W"], rel=1e-9)
        assert float(row["V_load_pp_V"]) == pytest.approx(block["V_load_peak_to_peak_V"],
                                                          rel=1e-9)
        assert float(row["I_load_pp_A"]) == pytest.approx(block["I_load_peak_to_peak_A"],
                                                          rel=1e-9)
        # rms from the energy integral: P = V_rms^2 / R = I_rms^2 R
        p = block["mean_power_W"]
        assert float(row["V_load_rms_V"]) == pytest.approx(math.sqrt(p * r), rel=1e-9)
        assert float(row["I_load_rms_A"]) == pytest.approx(math.sqrt(p / r), rel=1e-9)


def test_the_figure_of_one_frequency_is_against_r_only():
    rows = [{"frequency_hz": 20.0, "amplitude_mm": 1.5, "load_ohm": r, "V_oc_pp_V": 1.0,
             "Q_sc_pp_C": 1e-10, "I_sc_pp_A": 1e-8, "P_mean_W": 1e-6 * (1 + i),
             "V_load_pp_V": 10.0 * (1 + i), "I_load_pp_A": 1e-8 / (1 + i)}
            for i, r in enumerate(LOADS)]
    fig = sweep_figure(rows)
    fig.canvas.draw()
    axes = fig.axes
    assert [ax.get_xlabel() for ax in axes] == ["load R [Ω]"] * 3
    assert [ax.get_ylabel() for ax in axes] == ["V_load peak-to-peak [V]",
                                                "I_load peak-to-peak [nA]", "P_mean [µW]"]
    assert all(ax.get_xscale() == "log" for ax in axes)
    for ax in axes:                              # a line through the three loads, not dots
        (line,) = ax.get_lines()
        assert list(line.get_xdata()) == list(LOADS)
    # two frequencies: the terminal panels against frequency come first
    two = rows + [{**r, "frequency_hz": 30.0} for r in rows]
    labels = [ax.get_xlabel() for ax in sweep_figure(two).axes]
    assert labels == ["frequency [Hz]"] * 3 + ["load R [Ω]"] * 3
