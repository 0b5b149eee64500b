"""Every demo as one test (issue #22, item 6), after scikit-fem's ``tests/test_examples.py``
and dolfinx's ``python/demo/test.py``.

* The demos are the ``demos/*.py`` with a ``main()``; the others (``electrical_common.py``,
  ``demo_mpi.py``) are their helper modules.
* Each demo has its pinned physics numbers in :data:`DEMO_CHECKS` (a new demo without an
  entry fails :func:`test_demo_has_pinned_numbers`): ``check(run)`` asserts on what
  ``main(["--fast", ...])`` returns (``run.numbers``), prints (``run.printed``) and writes
  (``run.out``), with margins for the coarse fast-mode fields.
* Every demo runs once in-process (``--fast -o TMP --cache-dir TMP/cache``, a fresh
  surrogate cache each), and the field demos (those that build surrogates: importing
  ``electrical_common``, calling ``obtain_table`` / ``surrogate_curves``, or marked
  ``field=True``) once more as a script under ``mpirun -n 2`` (exit code 0, figures
  written by rank 0); the heavy ones of :data:`MPIRUN_FROM_CACHE` from a copy of the
  surrogate cache of their in-process run (their fields solved once in this file).
"""
from __future__ import annotations

import contextlib
import importlib.util
import io
import math
import re
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import pytest

DEMOS = Path(__file__).resolve().parents[1] / "demos"


def is_demo(path: Path) -> bool:
    """A demo has a ``main()``; a helper module of the demos has none."""
    return re.search(r"^def main\(", path.read_text(), re.M) is not None


DEMO_PATHS = sorted(p for p in DEMOS.glob("*.py") if is_demo(p))
HELPERS = sorted(p.stem for p in DEMOS.glob("*.py") if not is_demo(p))


@dataclass
class DemoRun:
    """One in-process run of a demo: ``main(argv)``'s return value, its stdout, its
    output directory and its surrogate cache."""
    name: str
    numbers: dict
    printed: str
    out: Path
    cache_dir: Path


@dataclass
class Pins:
    check: Callable[[DemoRun], None]
    pngs: tuple[str, ...]            # the figures it writes (relative to -o)
    field: bool = False              # solves fields though its source does not say so


#: demo name -> its pinned numbers (:class:`Pins`); filled by :func:`pins`.
DEMO_CHECKS: dict[str, Pins] = {}


def pins(name: str, *pngs: str, field: bool = False):
    """Register the decorated ``check(run)`` for ``demos/name.py`` and the figures it
    writes (default: ``name.png``)."""
    def register(check):
        DEMO_CHECKS[name] = Pins(check, pngs or (f"{name}.png",), field)
        return check
    return register


def solves_fields(path: Path) -> bool:
    source = path.read_text()
    return (DEMO_CHECKS.get(path.stem, Pins(None, ())).field
            or re.search(r"^\s*(from electrical_common import|import electrical_common)",
                         source, re.M) is not None
            or "obtain_table" in source or "surrogate_curves" in source)


def takes_cache_dir(path: Path) -> bool:
    """The electrical demos' ``demo_arguments`` has ``--cache-dir``; the dynamics ones none."""
    source = path.read_text()
    return "--cache-dir" in source or "demo_arguments" in source


def demo_argv(path: Path, out: Path) -> list[str]:
    argv = ["--fast", "-o", str(out)]
    return argv + (["--cache-dir", str(out / "cache")] if takes_cache_dir(path) else [])


def numbers_in(value):
    """Every number in a (nested) dict of the demo's results."""
    if isinstance(value, dict):
        return [x for v in value.values() for x in numbers_in(v)]
    return [value] if isinstance(value, (int, float)) and not isinstance(value, bool) else []


def png_size(run: DemoRun, name: str) -> int:
    png = run.out / name
    assert png.exists(), f"{run.name} did not write {name}"
    return png.stat().st_size


# --- the dynamics demos (no fields) ------------------------------------------------------

def dynamics_common(run: DemoRun) -> None:
    """It prints its comparison with the paper, its figure and finite numbers."""
    assert "paper" in run.printed
    assert png_size(run, f"{run.name}.png") > 10_000
    values = numbers_in(run.numbers)
    assert values and all(math.isfinite(v) for v in values), run.numbers


@pins("dynamics_amplitude_sweep")
def check_amplitude_sweep(run):
    dynamics_common(run)
    out = run.numbers
    # Fig. 5a, A = 0.5 mm: at rest at 5 Hz (A w^2 < g), 0.09 mm at 25 Hz (paper),
    # the full 3 mm stroke at 70 Hz (critical contact)
    assert out["regime"][5] == "rest" and out["max_gap_mm"][5] == 0.0
    assert out["max_gap_mm"][25] == pytest.approx(0.0989, rel=0.05)
    assert out["max_gap_mm"][70] == pytest.approx(3.0, abs=1e-6)


@pins("dynamics_critical_contact")
def check_critical_contact(run):
    dynamics_common(run)
    out = run.numbers
    # Fig. 6: contact onset at 10 Hz near the paper's 4.1 mm, Eq. 10's 0.205 m/s,
    # a flight of 41 ms (paper 37 ms) to the upper plate
    assert out["onset_amplitude_mm"][10.0] == pytest.approx(4.06, rel=0.02)
    assert out["launch_speed_m_per_s"] == pytest.approx(0.205, rel=0.01)
    assert out["flight_s"] == pytest.approx(0.0411, rel=0.05)
    assert out["regime"] == "critical-contact"


@pins("dynamics_jump_onset")
def check_jump_onset(run):
    dynamics_common(run)
    out = run.numbers
    # Fig. 4c, f: 10.4 mm at 5 Hz for a 0.1 mm jump (paper 10.5), 19.1 Hz at 1 mm for
    # a 0.5 mm jump (paper 19.5); a jump needs more than g (Fig. 4d, g)
    assert out["onset_amplitude_mm_at_5hz"][0.1] == pytest.approx(10.42, rel=0.02)
    assert out["onset_frequency_hz_0.5mm_jump"][1.0] == pytest.approx(19.14, rel=0.02)
    assert 9.81 < out["min_acceleration_over_frequency"] < 10.5
    assert 9.81 < out["min_acceleration_over_amplitude"] < 11.5


@pins("dynamics_regular_contact")
def check_regular_contact(run):
    dynamics_common(run)
    out = run.numbers
    # Fig. 7, 3 mm / 30 Hz: period-1 regular contact, once on the lower plate per
    # period, across the whole 3 mm stroke
    assert out["regime"] == "regular-contact" and out["period"] == 1
    assert out["lower_contacts_per_period"] == pytest.approx(1.0)
    assert out["upper_contacts_per_period"] >= 1.0
    assert out["max_gap_mm"] == pytest.approx(3.0, abs=1e-6)


@pins("motion3d_lateral", "motion3d_lateral.png", "motion3d_lateral_trajectory3d.png")
def check_motion3d_lateral(run):
    assert "paper" in run.printed
    for name in ("motion3d_lateral.png", "motion3d_lateral_trajectory3d.png"):
        assert png_size(run, name) > 10_000
    rows = run.numbers["rows"]
    assert [row["lateral_mm"] for row in rows] == [0.0, 0.5, 2.0]
    # on the axis the ball never touches the wall; shaken sideways it does, and the
    # 3 mm / 30 Hz regular contact survives (two upper impact episodes per period)
    assert rows[0]["wall_per_period"] == 0.0 and rows[0]["mean_r_mm"] == 0.0
    assert all(row["wall_per_period"] > 0 for row in rows[1:])
    assert all(row["regime"] == "regular-contact" for row in rows)
    assert rows[0]["upper_per_period"] == pytest.approx(2.0, abs=0.05)
    assert (run.out / "motion3d_lateral.csv").stat().st_size > 0


# --- the electrical demos (surrogates of dolfinx field solves) ----------------------------

def small_png(run: DemoRun) -> None:
    """``save_small_png``: a real figure under 300 kB."""
    assert 10_000 < png_size(run, f"{run.name}.png") < 300_000


@pins("electrical_waveforms")
def check_waveforms(run):
    small_png(run)
    out = run.numbers
    # the instrument that turns the ideal V_OC into the paper's 4.2 V adds hundreds of pF
    assert 100 < out["C_p_pF"] < 1000
    assert out["V_read_V"] == pytest.approx(4.2, rel=0.02)
    assert out["V_oc_ideal_V"] > 100 * 4.2        # the ideal floating-pair V_OC is kV-scale
    # sigma is fitted to the charge-mode reading: Q_SC is the paper's 1.42 nC
    assert out["Q_sc_nC"] == pytest.approx(1.42, rel=1e-6)


@pins("electrical_frequency_amplitude")
def check_frequency_amplitude(run):
    small_png(run)
    out = run.numbers
    assert 12 <= out["onset_hz"] <= 20        # lift-off at 1.5 mm: A w^2 = g at 12.9 Hz
    volts = out["V_pp_read_V"]
    assert volts[5.0] < 5e-4 and volts[10.0] < 5e-4     # "0.000" V as printed
    assert min(volts[f] for f in volts if f >= 20) > 3.5


@pins("electrical_geometry")
def check_geometry(run):
    small_png(run)
    out = run.numbers
    assert out["monotonic_in_gap"] and out["monotonic_in_diameter"]


@pins("electrical_honeycomb")
def check_honeycomb(run):
    small_png(run)
    out = run.numbers
    assert out["cells"] == 455
    # impedance matching, on the sweep's grid
    assert out["mean_power_load_MOhm"] == pytest.approx(out["matched_load_MOhm"], rel=0.6)


@pins("breakdown_limit")
def check_breakdown_limit(run):
    small_png(run)
    numbers = run.numbers
    for name in ("device", "honeycomb"):
        res = numbers[name]
        # tens of uC/m^2, the range air breakdown allows contact-electrified devices
        assert 10e-6 < res["sigma_max"] < 80e-6
        assert res["Q_sc"] > 0 and res["V_oc"] > 0
    # the output at the limit scales with sigma_max: Q_SC / sigma_max is geometry only
    strokes = numbers["sweep"]["stroke"]
    assert [v for v, _ in strokes] == [1.0, 3.0, 5.0]
    assert all(r["sigma_max"] > 0 for _, r in strokes)


@pins("spherical_shell")
def check_spherical_shell(run):
    small_png(run)
    tube, shell, rolling = (run.numbers[k] for k in ("tube", "shell", "shell-3axis"))
    # the same ball, stroke and drive: the 1-D dynamics are the same to the bit
    assert shell["max_gap_mm"] == tube["max_gap_mm"] and shell["regime"] == tube["regime"]
    # the shell couples more charge (its electrodes wrap the ball: 0.52 nC against the
    # tube's 0.32 nC at sigma = -8 uC/m^2, fast fields) and has the larger C_T
    assert shell["peak_to_peak"]["Q_sc"] == pytest.approx(0.521e-9, rel=0.05)
    assert tube["peak_to_peak"]["Q_sc"] == pytest.approx(0.321e-9, rel=0.05)
    assert shell["C_T_pF"][0] > 3 * tube["C_T_pF"][1]
    # 3-axis drive: the ball rolls and bounces around the cavity, off the axis up to the
    # wall (a - R = 1.5 mm), through the shell's (z, r) surrogate; it couples less charge
    # than the vertical drive's bounce (0.42 against 0.52 nC, fast fields; the motion is
    # chaotic, so the pin is a range, not a number)
    assert 0.5 < rolling["max_radial_offset_mm"] <= 1.5 + 1e-3
    assert rolling["zr_grid"][1] >= 3
    assert 0.3 * shell["peak_to_peak"]["Q_sc"] < rolling["peak_to_peak"]["Q_sc"] \
        < shell["peak_to_peak"]["Q_sc"] * 1.2
    assert rolling["C_T_pF"] == shell["C_T_pF"]              # the same axis surrogate
    assert rolling["sigma_max_uC_per_m2"] == shell["sigma_max_uC_per_m2"]
    for res in (tube, shell, rolling):
        # Q_SC never exceeds the full stroke's; the peaks at sigma_max are sigma-linear
        assert res["peak_to_peak"]["Q_sc"] <= res["Q_sc_full_stroke_nC"] * 1e-9 * (1 + 1e-9)
        assert 10 < res["sigma_max_uC_per_m2"] < 80
        scale = res["sigma_max_uC_per_m2"] / 8.0
        for key in ("V_oc", "Q_sc", "I_sc"):
            assert res["at_sigma_max_peak_to_peak"][key] == pytest.approx(
                scale * res["peak_to_peak"][key], rel=1e-6)
    assert shell["sigma_max_uC_per_m2"] == pytest.approx(44.1, rel=0.15)


@pins("fit_paper", *(f"fit_paper_{case}/fit.png" for case in "ABC"))
def check_fit_paper(run):
    import electrical_common      # on sys.path (the demos put it there), as fit_paper used it

    numbers = run.numbers
    # the hand computation of docs/demos.md on the same surrogate
    _, curves = electrical_common.surrogate_curves(electrical_common.paper_scene(True),
                                                   str(run.cache_dir))
    scale, c_p = electrical_common.reconcile(curves, True)
    a = numbers["A"]
    assert a["values"]["surface_charge_uC_per_m2"] == pytest.approx(-8.0 * scale, rel=0.01)
    assert a["values"]["parallel_capacitance_pF"] == pytest.approx(c_p * 1e12, rel=0.01)
    # 5 % readings -> about 5 % standard error on sigma
    assert 0.02 < a["standard_errors"]["surface_charge_uC_per_m2"] / 35.8 < 0.1
    # the current reading does not fit with the other two: chi^2 says so
    assert numbers["B"]["chi2_reduced"] > 4.0
    assert any("not consistent" in n for n in numbers["B"]["notes"])
    # in the bouncing regime the ball sticks and lifts off at a fixed phase: e has no effect
    assert not numbers["C"]["identifiable"]["restitution"]
    for case in "ABC":
        assert (run.out / f"fit_paper_{case}" / "fit.png").exists()


@pins("harvest_ship", "harvest_ship.png", "harvest_ship_array.png")
def check_harvest_ship(run):
    out = run.numbers
    # the store reaches the falling level before the rising one, the chip then cycles
    assert 0 < out["time_to_uvlo_falling_level_s"] < out["time_to_first_uvlo_rising_s"]
    assert out["chip_bursts"] >= 1
    # the load draws more than is harvested: the chip cannot stay on
    assert 0 < out["duty_cycle_after_first_on"] < 1
    assert out["duty_cycle_after_first_on"] == pytest.approx(out["expected_duty_cycle"], rel=0.5)
    assert out["energy_residual_max"] < 1e-6
    assert png_size(run, "harvest_ship.png") > 0


@pins("ship_engine")
def check_ship_engine(run):
    out = run.numbers
    # the pure sine bounces periodically, as the paper's ship case (harvested power
    # pinned to the value of this coarse field at its breakdown charge, 7.777 uW)
    assert out["sine_regime"] == "bounce"
    assert out["sine_harvested_power_W"] == pytest.approx(7.777e-6, rel=0.05)
    # the engine's realisations are a distribution: a finite positive mean inside its CI
    low, high = out["engine_harvested_power_ci95_W"]
    assert out["realisations"] == 4
    assert 0 < low < out["engine_harvested_power_W"] < high
    assert math.isclose(sum(out["engine_regime_fractions"].values()), 1.0)
    assert png_size(run, "ship_engine.png") > 10_000


@pins("design_ship", "design_ship.png", "ship_power/design.png")
def check_design_ship(run):
    out = run.numbers
    # contact needs a shorter stroke at a smaller amplitude; the band's answer is the smallest
    by_amplitude = out["full_contact_stroke_by_amplitude_mm"]
    assert by_amplitude[0.5] < by_amplitude[0.75] < by_amplitude[1.0]
    assert out["full_contact_stroke_mm"] == pytest.approx(by_amplitude[0.5], abs=0.1)
    # the power-density optimum lies inside the range, near the paper's hand-chosen 2 mm
    assert 1.0 < out["power_density_stroke_mm"] < 4.0
    assert out["power_density_W_per_m3"] >= out["paper_stroke_power_density_W_per_m3"] \
        - out["power_density_error_W_per_m3"]
    assert out["optimum_check"]["narrow_objective"] is not None
    # Fig. 9g: the voltage rises with the stroke; Fig. 9h: with the ball
    assert out["fig9g_voltage_rises"] and out["fig9h_voltage_rises"]
    for name in ("design_ship.png", "ship_power/design.png", "ship_power/best.toml",
                 "fig9g/design.csv"):
        assert (run.out / name).stat().st_size > 0


# --- the tests ----------------------------------------------------------------------------

def demo_params(paths):
    """``pytest.param`` per demo: slow (each runs for seconds), and field if it solves one."""
    return [pytest.param(p, id=p.stem, marks=[pytest.mark.slow]
                         + ([pytest.mark.field] if solves_fields(p) else []))
            for p in paths]


def test_the_demos_are_collected():
    """The glob finds the demos (four of dynamics among them) and leaves out only helper
    modules; no pinned numbers are left for a demo that is gone."""
    names = [p.stem for p in DEMO_PATHS]
    assert len([n for n in names if n.startswith("dynamics_")]) >= 4
    assert "electrical_common" in HELPERS and "electrical_common" not in names
    assert sorted(set(DEMO_CHECKS) - set(names)) == []


@pytest.mark.parametrize("demo", DEMO_PATHS, ids=lambda p: p.stem)
def test_demo_has_pinned_numbers(demo):
    assert demo.stem in DEMO_CHECKS, (
        f"demos/{demo.name} has no pinned numbers: add a @pins({demo.stem!r}) check to "
        "tests/test_demos.py asserting one or two of the physics numbers its main() returns")


#: the field demos whose ``mpirun`` run starts from a copy of the surrogate cache their
#: in-process run filled (:func:`in_process_runs`), so their fields are solved once in this
#: file, not twice: under mpirun they still run every stage on both ranks (the cache read
#: on rank 0 and broadcast, the design's candidates and the runs farmed over the ranks,
#: rank 0 writing), and the parallel field solves they would repeat are held elsewhere:
#: the design's by ``tests/design/test_design_mpi.py`` (real solves, ``mpirun -n 2`` gives
#: the serial files), the (z, r) table's by ``tests/surrogate/test_surrogate_zr.py``
#: (2 ranks equal serial) and the 3D solve's by ``tests/field/test_field_3d_mpi.py``;
#: breakdown_limit's five axisymmetric tables are the farm (``surrogate.precompute`` over
#: the ranks) that the electrical demos' mpirun runs below solve afresh.
#: The other field demos' fields cost about a second: they solve them again.
MPIRUN_FROM_CACHE = ("breakdown_limit", "design_ship", "spherical_shell")


@pytest.fixture(scope="module")
def in_process_runs(tmp_path_factory):
    """``run(demo) -> DemoRun``: ``main(["--fast", "-o", DIR, "--cache-dir", DIR/cache])``
    in-process (``demos/`` on ``sys.path``, stdout captured), once per demo in this module."""
    runs: dict[str, DemoRun] = {}

    def run(demo: Path) -> DemoRun:
        if demo.stem not in runs:
            out = tmp_path_factory.mktemp(f"demo_{demo.stem}")
            printed = io.StringIO()
            with pytest.MonkeyPatch.context() as mp, contextlib.redirect_stdout(printed):
                mp.syspath_prepend(str(DEMOS))
                mp.setattr(sys, "argv", [demo.name])
                spec = importlib.util.spec_from_file_location(f"demo_{demo.stem}", demo)
                module = importlib.util.module_from_spec(spec)
                spec.loader.exec_module(module)
                numbers = module.main(demo_argv(demo, out))
            runs[demo.stem] = DemoRun(demo.stem, numbers, printed.getvalue(), out, out / "cache")
        return runs[demo.stem]
    return run


@pytest.mark.parametrize("demo", demo_params(DEMO_PATHS))
def test_demo(demo, in_process_runs):
    """``main(["--fast", "-o", TMP, "--cache-dir", TMP/cache])`` in-process, then its pins."""
    if demo.stem not in DEMO_CHECKS:
        pytest.fail(f"demos/{demo.name} has no pinned numbers (test_demo_has_pinned_numbers)")
    pinned = DEMO_CHECKS[demo.stem]
    run = in_process_runs(demo)
    for png in pinned.pngs:
        assert png_size(run, png) > 0
    pinned.check(run)


def mpirun_env(cli_env) -> dict:
    """The CLI's environment (this checkout's src first, root allowed) that may put 2 ranks
    on fewer cores (Open MPI 4 and 5)."""
    return cli_env(OMPI_MCA_rmaps_base_oversubscribe="1", MPLBACKEND="Agg",
                   PRTE_MCA_rmaps_default_mapping_policy=":oversubscribe")


@pytest.mark.parametrize("demo", demo_params([p for p in DEMO_PATHS if solves_fields(p)]))
def test_field_demo_under_mpirun(demo, tmp_path, python, cli_env, in_process_runs):
    """``mpirun -n 2 python demos/NAME.py --fast ...`` (the field solves spread over the two
    ranks, rank 0 writes): exit code 0 and every figure written. The demos of
    :data:`MPIRUN_FROM_CACHE` start from their in-process run's surrogates."""
    if shutil.which("mpirun") is None:
        pytest.skip("mpirun not installed")
    if demo.stem in MPIRUN_FROM_CACHE:
        shutil.copytree(in_process_runs(demo).cache_dir, tmp_path / "cache")
    proc = subprocess.run(["timeout", "890", "mpirun", "-n", "2", python, str(demo),
                           *demo_argv(demo, tmp_path)], cwd=tmp_path, env=mpirun_env(cli_env),
                          capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr[-3000:]
    for png in DEMO_CHECKS.get(demo.stem, Pins(None, (f"{demo.stem}.png",))).pngs:
        assert (tmp_path / png).stat().st_size > 0, png
