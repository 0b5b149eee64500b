"""Issue #53 item 4: `run` reports the matched load (summary.json `matched_load`
{load_ohm, mean_power_W}, one terminal line) from the run's own Q_SC(t), C_T(t): its
power is the most a resistor takes, checked against independent load runs at 0.5 R and
2 R, and is the power a load run at R itself reports."""
from __future__ import annotations

import json

import pytest

from tengfield import cli, surrogate
from tengfield.scene import load_scene

import plate_model as fx

SCENE = "[run]\nduration_s = 0.6\nsettle_periods = 2\nsample_rate_hz = 5000.0\n"


def prepared(tmp_path):
    """A short scene file and a cache holding its plate-model surrogate (no field solve)."""
    scene_file = tmp_path / "short.toml"
    scene_file.write_text(SCENE)
    cache = tmp_path / "cache"
    scene = load_scene(scene_file)
    surrogate.write_table(surrogate.cache_path(scene, cache),
                          surrogate.precompute(scene, comm=None, solve=fx.plate_model_solve))
    return scene_file, cache


def run(capsys, tmp_path, scene_file, cache, name, *settings):
    out = tmp_path / name
    code = cli.main(["run", str(scene_file), "--cache-dir", str(cache), *settings,
                     "-o", str(out)])
    stdout, err = capsys.readouterr()
    assert code == 0, err
    return json.loads((out / "summary.json").read_text()), stdout, out


def test_the_matched_load_takes_more_than_half_and_twice_its_resistance(tmp_path, capsys):
    scene_file, cache = prepared(tmp_path)
    summary, out, where = run(capsys, tmp_path, scene_file, cache, "open")
    matched = summary["matched_load"]
    r, p = matched["load_ohm"], matched["mean_power_W"]
    assert p > 0 and 1e6 < r < 1e13
    lines = [ln for ln in out.splitlines() if ln.startswith("matched load")]
    assert lines == [f"matched load {r:.3g} ohm: mean power {p * 1e6:.4g} µW, "
                     f"{matched['power_density_W_per_m3']:.4g} W/m^3 (the resistor taking "
                     "the most; from this run's Q_SC, C_T, no field solve)"]
    assert (where / "waveforms.png").is_file()           # figures on
    powers = {}
    for factor in (0.5, 1.0, 2.0):
        loaded, _, _ = run(capsys, tmp_path, scene_file, cache, f"load{factor}",
                           "--set", 'circuit.kind="load"', "--set",
                           f"circuit.load_ohm={r * factor!r}", "--no-plots")
        powers[factor] = loaded["load"]["mean_power_W"]
    assert powers[1.0] == pytest.approx(p, rel=1e-9)      # the same integrator, the same run
    assert p >= powers[0.5] and p >= powers[2.0]
    # and it is a real maximum, not a grid edge: both neighbours are measurably lower
    assert powers[0.5] < 0.99 * p and powers[2.0] < 0.99 * p


def test_a_run_at_rest_has_no_matched_load_and_says_why(tmp_path, capsys):
    scene_file, cache = prepared(tmp_path)
    summary, out, _ = run(capsys, tmp_path, scene_file, cache, "rest",
                          "--set", "excitation.amplitude_mm=0.3", "--no-plots")
    assert summary["matched_load"] is None
    assert "no load takes power" in summary["matched_load_reason"]
    assert "matched load" not in out
