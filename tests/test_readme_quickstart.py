"""Smoke test of README's "Quick start": every command of the block, figures on (issue #21).

Each command runs as the README shows it, in a subprocess, on a small scene made
from ``tengfield scene --default`` (0.3 s, coarse field); the files README's
"Outputs" table lists must exist, be non-empty, and PNGs must decode. Sizes shrunk
against the README: ``map`` and ``sweep`` grids (the sweep from 10 Hz: two settling
periods must fit in the 0.3 s run); ``precompute`` serial (not under
``mpirun -n 2``); ``report --fast`` (its CI-sized plan: the full report is ~100x the
solves); ``fit --targets`` is given the small scene (the README's form without a
scene computes the default scene's fine surrogate). Beyond the block: a 3D run with a
lateral drive, a rectifier run and an ``[array]`` with spread, all figures on.

One surrogate cache serves the module: ``precompute`` fills it with the real field
solves, the rest find it. The 3D run's (z, r) surrogate (3D solves, minutes) is
pre-cached from the analytic (z, r) stand-in of ``tests/test_surrogate_zr.py``; its
axis part is the real cached one.
"""
from __future__ import annotations

import csv
import json
import re
from pathlib import Path

import numpy as np
import pytest

from test_run_3d_figures import assert_png

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[1]

#: [key] value -> small value: a 0.3 s run at 5 kHz, a coarse field
SMALL = {"duration_s": "0.3", "settle_periods": "2", "sample_rate_hz": "5000.0",
         "degree": "1", "mesh_size_mm": "1.5", "tolerance": "0.2"}


def quick_start_commands() -> list[str]:
    """The command lines of README's Quick start block (comments dropped)."""
    text = (ROOT / "README.md").read_text()
    block = re.search(r"## Quick start\s*```bash\n(.*?)```", text, re.S).group(1)
    return [line.split("#")[0].strip() for line in block.splitlines() if line.split("#")[0].strip()]


def subcommand(line: str) -> str:
    if line.startswith("make "):
        return line.split()[1]                         # make run = tengfield run
    words = line.split()
    return words[[i for i, w in enumerate(words) if w.endswith("tengfield")][0] + 1]


def edit(text: str, key: str, value: str) -> str:
    """``key = value`` in the scene file ``text`` (the key's one line; comments kept)."""
    new, count = re.subn(rf"^({re.escape(key)}\s*=\s*)[^#\s]+", rf"\g<1>{value}", text,
                         flags=re.M)
    if count == 0:   # a key the default scene leaves unset, shown commented out
        new, count = re.subn(rf"^#\s*({re.escape(key)}\s*=\s*)[^#\s]+", rf"\g<1>{value}",
                             text, flags=re.M)
    assert count == 1, (key, count)
    return new


def add_to_section(text: str, section: str, lines: str) -> str:
    head = f"[{section}]\n"
    assert text.count(head) == 1, section
    return text.replace(head, head + lines)


@pytest.fixture(scope="module")
def work(tmp_path_factory, run_cli, cli_env, cli_command):
    """(dir, cli): ``cli(*args)`` runs ``tengfield args`` in dir with the module's
    cache, checks exit code 0, no traceback, and that every warning or error on stderr
    is one of tengfield's ``tengfield: ...`` lines (none from Python, numba, PETSc);
    returns the CompletedProcess."""
    where = tmp_path_factory.mktemp("quickstart")
    env = cli_env(TENGFIELD_CACHE_DIR=where / "cache", XDG_CACHE_HOME=where / "xdg")

    def cli(*args, mpirun=None):
        if mpirun:   # as README writes it: mpirun -n N tengfield ...
            import subprocess
            proc = subprocess.run(
                ["mpirun", "-n", str(mpirun), *cli_command(*args)], cwd=where,
                env={**env, "OMPI_MCA_rmaps_base_oversubscribe": "1",
                     "PRTE_MCA_rmaps_default_mapping_policy": ":oversubscribe"},
                capture_output=True, text=True, timeout=900)
        else:
            proc = run_cli(*args, cwd=where, env=env, timeout=900)
        assert proc.returncode == 0, f"tengfield {' '.join(map(str, args))}:\n{proc.stderr}"
        assert "Traceback" not in proc.stderr, proc.stderr
        stray = [ln for ln in proc.stderr.splitlines() if not ln.startswith("tengfield: ")
                 and (re.search("warning", ln, re.I) or re.search(r"error:|Error\b|Exception", ln))]
        assert not stray, f"tengfield {' '.join(map(str, args))}: foreign messages {stray}"
        return proc
    return where, cli


@pytest.fixture(scope="module")
def scene(work):
    """my.toml: ``tengfield scene --default`` made small (the fit and every run use it)."""
    where, cli = work
    text = cli("scene", "--default").stdout
    for key, value in SMALL.items():
        text = edit(text, key, value)
    (where / "my.toml").write_text(text)
    checked = json.loads(cli("scene", "my.toml").stdout)  # the file reads back, values kept
    assert checked["run"]["duration_s"] == 0.3 and checked["field"]["mesh_size_mm"] == 1.5
    return where / "my.toml"


@pytest.fixture(scope="module")
def precomputed(work, scene):
    where, cli = work
    cli("precompute", "my.toml")
    files = list((where / "cache").glob("surrogate-*.h5"))
    assert len(files) == 1 and files[0].stat().st_size > 0
    return files[0]


@pytest.fixture(scope="module")
def ran(work, precomputed):
    where, cli = work
    proc = cli("run", "my.toml", "-o", "out/my")
    return where / "out" / "my", proc


def check_outputs(out: Path, names) -> None:
    for name in names:
        path = out / name
        assert path.is_file() and path.stat().st_size > 0, path
        if name.endswith(".png"):
            assert_png(path)
        elif name.endswith(".json"):
            json.loads(path.read_text())
        elif name.endswith(".csv"):
            with open(path, newline="") as f:
                rows = list(csv.reader(f))
            assert len(rows) >= 2 and len(rows[0]) >= 1, path
            # a missing value is an empty cell (a contact still open at the end), not text
            assert not [c for r in rows for c in r if c.strip().lower() == "nan"], path


RUN_FILES = ("waveforms.csv", "summary.json", "waveforms.png", "surrogate.png",
             "trajectory.csv", "impacts.csv", "trajectory.png")

#: what each Quick start command is covered by in this file
COVERED = {"run", "scene", "dynamics", "map", "field", "precompute", "sweep", "report", "fit",
           "info", "breakdown", "design"}


def test_every_quick_start_command_is_covered():
    commands = quick_start_commands()
    assert len(commands) >= 10
    assert {subcommand(line) for line in commands} == COVERED


def test_run(ran):
    out, proc = ran
    check_outputs(out, RUN_FILES)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["stages"]["field"]["status"] == "cached"   # precompute filled the cache
    assert summary["peak_to_peak"]["V_oc_V"] > 0
    data = np.loadtxt(out / "waveforms.csv", delimiter=",", skiprows=1)
    assert data.shape[0] == round(0.3 * 5000) + 1
    assert "wrote " in proc.stdout


def test_dynamics(work, scene):
    where, cli = work
    cli("dynamics", "my.toml", "-o", "out/dyn")
    check_outputs(where / "out" / "dyn", ("trajectory.csv", "impacts.csv", "summary.json",
                                          "trajectory.png"))
    summary = json.loads((where / "out" / "dyn" / "summary.json").read_text())
    assert summary["duration_s"] == pytest.approx(0.3)


def test_map(work, scene):
    where, cli = work
    cli("map", "my.toml", "--frequency-hz", "5:70:6", "--amplitude-mm", "0.1:5:5",
        "-o", "out/map")
    check_outputs(where / "out" / "map", ("map.csv", "map.png"))
    with open(where / "out" / "map" / "map.csv", newline="") as f:
        assert len(list(csv.DictReader(f))) == 30


def test_field(work, scene):
    where, cli = work
    cli("field", "my.toml", "--position-mm", "1.5", "-o", "out/field")
    check_outputs(where / "out" / "field", ("field.json", "potential.xdmf", "field.png"))


def test_breakdown(work, precomputed):
    """sigma_max from the cached surrogate's gap lines: a positive limit with its binding
    state and gap, the table and the figure."""
    where, cli = work
    cli("breakdown", "my.toml", "-o", "out/bd")
    out = where / "out" / "bd"
    check_outputs(out, ("breakdown.json", "breakdown.csv", "breakdown.png"))
    result = json.loads((out / "breakdown.json").read_text())
    assert 0 < result["sigma_max_uC_per_m2"] < 1e3


def test_design(work, scene):
    """A small [design] study over the stroke (4 candidates, one band point) under
    mpirun -n 2 as README shows it: every output, and best.toml runs."""
    import shutil
    where, cli = work
    text = (where / "my.toml").read_text() + (
        '\n[design]\nobjective = "charge"\ncandidates = 4\nseed = 1\nsettle_periods = 4\n'
        'window_periods = 4\n[design.vary]\ngap_mm = [2.0, 4.0]\n'
        '[design.excitation]\nfrequency_hz = [20.0]\namplitude_mm = [1.5]\n')
    (where / "design.toml").write_text(text)
    if shutil.which("mpirun"):
        cli("design", "design.toml", "-o", "out/design", mpirun=2)
    else:
        cli("design", "design.toml", "-o", "out/design")
    out = where / "out" / "design"
    check_outputs(out, ("design.csv", "design.json", "design.png", "best.toml"))
    best = json.loads((out / "design.json").read_text())["best"]
    assert 2.0 <= best["gap_mm"] <= 4.0 and best["objective"] > 0
    cli("run", "out/design/best.toml", "-o", "out/best", "--no-plots")


def test_sweep(work, precomputed):
    where, cli = work
    cli("sweep", "my.toml", "--frequency-hz", "10:50:3", "--amplitude-mm", "0.5:3:2",
        "-o", "out/sweep")
    check_outputs(where / "out" / "sweep", ("sweep.csv", "sweep.png"))
    with open(where / "out" / "sweep" / "sweep.csv", newline="") as f:
        assert len(list(csv.DictReader(f))) == 6


def test_report_fast(work, scene):
    where, cli = work
    cli("report", "my.toml", "--fast", "-o", "out/report")
    check_outputs(where / "out" / "report",
                  ("report.md", "report.csv", "report.json", "field.png", "surrogate.png",
                   "dynamics.png", "circuit.png", "recommended-0.01.toml",
                   "recommended-0.001.toml"))


def test_fit_measured_recovers_the_runs_own_charge(work, ran):
    """The run's own steady V_OC and Q_SC as the "scope" trace: σ comes back."""
    where, cli = work
    out, _ = ran
    with open(out / "waveforms.csv", newline="") as f:
        rows = [r for r in csv.DictReader(f) if float(r["time_s"]) >= 0.1]
    with open(where / "scope.csv", "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["time_s", "V_oc_V", "Q_sc_C"])
        writer.writerows([r["time_s"], r["V_oc_V"], r["Q_sc_C"]] for r in rows)
    cli("fit", "my.toml", "--measured", "scope.csv", "-o", "out/fit")
    check_outputs(where / "out" / "fit", ("fit.json", "fit.png", "fitted.toml"))
    fit = json.loads((where / "out" / "fit" / "fit.json").read_text())
    assert fit["parameters"]["surface_charge_uC_per_m2"]["value"] == pytest.approx(-8.0,
                                                                                  rel=1e-3)


def test_fit_targets(work, precomputed):
    where, cli = work
    cli("fit", "my.toml", "--targets", "V_pp_V=4.2", "Q_pp_nC=1.42", "-o", "out/fit-targets")
    check_outputs(where / "out" / "fit-targets", ("fit.json", "fit.png", "fitted.toml"))
    fit = json.loads((where / "out" / "fit-targets" / "fit.json").read_text())
    assert fit["parameters"]["surface_charge_uC_per_m2"]["value"] < 0   # as the PTFE ball's


def test_info(work):
    _, cli = work
    proc = cli("info")
    assert "tengfield" in proc.stdout.lower() and "numpy" in proc.stdout.lower()


def test_run_3d_lateral(work, scene, precomputed):
    import test_surrogate_zr as tz
    from tengfield.scene import load_scene
    from tengfield.surrogate import obtain_radial_table

    where, cli = work
    text = scene.read_text()
    text = edit(text, "model", '"3d"')
    text = add_to_section(text, "excitation", "amplitude_x_mm = 0.5\nphase_x_deg = 30.0\n")
    (where / "lateral.toml").write_text(text)
    obtain_radial_table(load_scene(where / "lateral.toml"), cache_dir=where / "cache",
                        solve=tz.zr_model_solve)
    cli("run", "lateral.toml", "-o", "out/lateral")
    out = where / "out" / "lateral"
    check_outputs(out, RUN_FILES + ("contacts.csv", "trajectory3d.png"))
    summary = json.loads((out / "summary.json").read_text())
    assert summary["stages"]["field"]["status"] == "cached"
    assert summary["stages"]["field_zr"]["status"] == "cached"


def rectifier_scene(scene_path: Path) -> str:
    text = scene_path.read_text()
    assert text.count('kind = "open"') == 1              # [circuit] kind ([excitation]: "sine")
    text = text.replace('kind = "open"', 'kind = "rectifier"')
    return add_to_section(text, "circuit", "storage_capacitance_uF = 1e-4\n")


def test_run_rectifier(work, scene, precomputed):
    where, cli = work
    (where / "rect.toml").write_text(rectifier_scene(scene))
    cli("run", "rect.toml", "-o", "out/rect")
    out = where / "out" / "rect"
    check_outputs(out, RUN_FILES + ("charging.png", "vq.png"))
    summary = json.loads((out / "summary.json").read_text())
    assert summary["rectifier"]["storage_capacitance_F"] == pytest.approx(1e-10)
    header = (out / "waveforms.csv").read_text().splitlines()[0]
    assert "V_store_V" in header


def test_run_array_with_spread(work, scene, precomputed):
    where, cli = work
    text = rectifier_scene(scene) + ("\n[array]\ncells = 4\nconnection = \"rectified-per-cell\"\n"
                                     "initial_phase_spread_deg = 90.0\nrestitution_spread = 0.02\n")
    (where / "array.toml").write_text(text)
    cli("run", "array.toml", "-o", "out/array")
    out = where / "out" / "array"
    # a store per cell: no charging.png, which draws one store (docs/harvest.md)
    check_outputs(out, RUN_FILES + ("array.png",))
    summary = json.loads((out / "summary.json").read_text())
    assert summary["cells"] == 4 and summary["array"]["distinct_dynamics"] == 4


def test_container_checks(work, ran, precomputed):
    """Last in the module: what ``scripts/test-container`` asserts of these files inside
    each image (``scripts/container/check_outputs.py``): every number in every surrogate
    file of the cache (the axis and, after the 3D run, the (z, r) one) is finite and
    tengfield reads it back; every run's files are complete and finite."""
    import subprocess
    import sys

    where, _ = work
    script = ROOT / "scripts" / "container" / "check_outputs.py"
    runs = sorted(p.parent for p in (where / "out").glob("*/waveforms.csv")
                  if (p.parent / "summary.json").is_file())
    assert ran[0] in runs
    for what, directory in [("precompute", precomputed.parent)] + [("run", d) for d in runs]:
        proc = subprocess.run([sys.executable, str(script), what, str(directory)],
                              capture_output=True, text=True, timeout=300)
        assert proc.returncode == 0, f"check_outputs.py {what} {directory}:\n{proc.stdout}{proc.stderr}"
