"""Every shipped shape (``scene/shapes/``' registry: the tube, the spherical shell, the
honeycomb) through ``run``, ``sweep``, ``design``, ``uncertainty`` and ``breakdown`` on
the command line with figures on (issue 54.18: the honeycomb could not run at all). The
field is the coarsest the schema allows (P1, mesh_size_mm = 100, tolerance = 0.5): what is
tested is that each command takes each shape, not the accuracy. ``run`` solves the
shape's surrogate once; the studies vary keys that are not field inputs, so they read it
from the cache. A shape that cannot do a command (the honeycomb has no breakdown gap
lines) is refused in one line before any work."""
from __future__ import annotations

import csv
import json

import pytest

from tengfield.scene import parse_scene
from tengfield.scene.shapes import SHAPES

pytestmark = [pytest.mark.slow, pytest.mark.field]

SCENE = """[device]
shape = "{shape}"

[field]
degree = 1
mesh_size_mm = 100
tolerance = 0.5

[run]
duration_s = 0.3
settle_periods = 2
sample_rate_hz = 5000

[design]
objective = "charge"
candidates = 4
initial_candidates = 4
field = "scene"
settle_periods = 2
window_periods = 2
[design.vary]
ball_density_kg_per_m3 = [1500.0, 2500.0]
[design.excitation]
frequency_hz = [20.0]
amplitude_mm = [1.5]

[uncertainty]
samples = 20
method = "monte-carlo"
seed = 1
[uncertainty.vary]
"contact.restitution" = {{ distribution = "uniform", low = 0.05, high = 0.2 }}
"""


def rows_of(path):
    with open(path) as fh:
        return list(csv.DictReader(fh))


@pytest.fixture(scope="module", params=sorted(SHAPES))
def shape_run(request, tmp_path_factory, run_cli, cli_env):
    """(directory, env, shape) after ``tengfield run`` of the shape (its surrogate cached)."""
    shape = request.param
    d = tmp_path_factory.mktemp(shape)
    (d / "scene.toml").write_text(SCENE.format(shape=shape))
    env = cli_env(TENGFIELD_CACHE_DIR=d / "cache", MPLBACKEND="Agg")
    proc = run_cli("run", "scene.toml", "-o", "run", cwd=d, env=env)
    assert proc.returncode == 0, proc.stderr
    summary = json.loads((d / "run" / "summary.json").read_text())
    assert summary["peak_to_peak"]["Q_sc_C"] > 0
    for figure in ("waveforms.png", "surrogate.png"):
        assert (d / "run" / figure).stat().st_size > 10_000
    return d, env, shape


def test_sweep(shape_run, run_cli):
    d, env, _ = shape_run
    proc = run_cli("sweep", "scene.toml", "--vary", "contact.restitution=0.1,0.2", "--jobs", "1",
                   "-o", "sweep", cwd=d, env=env)
    assert proc.returncode == 0, proc.stderr
    assert "(0 computed, 1 cached" in proc.stderr          # the run's surrogate
    rows = rows_of(d / "sweep" / "sweep.csv")
    assert [r["contact.restitution"] for r in rows] == ["0.1", "0.2"]
    assert all(float(r["Q_sc_pp_C"]) > 0 for r in rows)
    assert (d / "sweep" / "sweep_contact.restitution.png").stat().st_size > 10_000


def test_design(shape_run, run_cli):
    d, env, _ = shape_run
    proc = run_cli("design", "scene.toml", "--jobs", "1", "-o", "design", cwd=d, env=env)
    assert proc.returncode == 0, proc.stderr
    summary = json.loads((d / "design" / "design.json").read_text())
    assert summary["best"] is not None and summary["best"]["objective"] > 0
    assert (d / "design" / "design.png").stat().st_size > 10_000
    assert (d / "design" / "best.toml").is_file()


def test_uncertainty(shape_run, run_cli):
    d, env, _ = shape_run
    proc = run_cli("uncertainty", "scene.toml", "--jobs", "1", "-o", "uq", cwd=d, env=env)
    assert proc.returncode == 0, proc.stderr
    assert len(rows_of(d / "uq" / "uncertainty.csv")) == 20
    assert (d / "uq" / "uncertainty.png").stat().st_size > 10_000


def test_breakdown(shape_run, run_cli):
    """A shape with gap lines reports its limit and band; one without (its field solver
    has none) is refused in one line naming why, and nothing is written."""
    d, env, shape = shape_run
    proc = run_cli("breakdown", "scene.toml", "-o", "bd", cwd=d, env=env)
    if parse_scene(SCENE.format(shape=shape)).has_gap_lines:
        assert proc.returncode == 0, proc.stderr
        result = json.loads((d / "bd" / "breakdown.json").read_text())
        assert result["sigma_max_uC_per_m2"] > 0
        assert (d / "bd" / "breakdown.png").stat().st_size > 10_000
    else:
        assert proc.returncode == 2, proc.stderr
        assert "Traceback" not in proc.stderr and not (d / "bd").exists()
        ours = [ln for ln in proc.stderr.splitlines() if ln.startswith("tengfield")]
        assert len(ours) == 1 and ours[0].startswith("tengfield: error: the breakdown check: "
                                                     "the breakdown gap lines come from"), \
            proc.stderr
