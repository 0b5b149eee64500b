"""``tengfield run``: dynamics -> surrogate (cached) -> circuit, end to end.

Writes DIR/waveforms.csv (the motion's columns too), DIR/summary.json, DIR/waveforms.png,
DIR/surrogate.png (charging.png and vq.png for a rectifier, vq.png for a
load, array.png for an [array]; ensemble.csv and ensemble.png for [run]
realisations > 1, farmed over the ranks or --jobs workers) and the dynamics'
impacts.csv and trajectory.png ([contact] model = "3d": also contacts.csv and
trajectory3d.png). Under ``mpirun -n N`` the field solves (if the surrogate
is not cached) are spread over the ranks; rank 0 writes every file.
"""
from __future__ import annotations

from .._mpi import world_if_parallel
from ._common import add_cache_argument, add_jobs_argument, command_line, scene_command


def register(sub) -> None:
    p = scene_command(sub, "run", output="out", description=__doc__,
                      help="V_OC, Q_SC, I_SC (and load) waveforms of a scene, end to end")
    add_cache_argument(p)
    add_jobs_argument(p)
    p.add_argument("--no-plots", "--no-plot", dest="no_plots", action="store_true",
                   help="skip the PNG files")
    p.add_argument("--reference", nargs="+", metavar="KEY=VALUE", default=None,
                   help="measured values to compare with, as in a [reference] section "
                        "(e.g. V_pp_V=4.2 Q_pp_nC=1.42 I_peak_uA=0.16): the tool's values, "
                        "the measured ones and the %% difference (docs/outputs.md)")
    p.add_argument("--spice", action="store_true",
                   help="also write DIR/teng.lib: the device as a SPICE subcircuit 'teng' "
                        "(two pins; V_OC(t) and C_T(t) tables of the steady period, "
                        "repeated for ever: PWL r=) for ngspice "
                        "(README, 'Simulate your own circuit'; docs/outputs.md)")
    p.add_argument("--spice-start-up", action="store_true",
                   help="as --spice, with the run's start-up (t = 0 .. settle_periods "
                        "periods, from rest) before the repeated period")
    p.set_defaults(func=_run, extend_settling=_extend_settling)


def _extend_settling(base, settings, error):
    """A ``--set`` frequency whose settle_periods fill duration_s: the run extended as a
    sweep point is (:func:`tengfield.sweeps.extend_for_settling`; the CLI calls it)."""
    from ..sweeps import extend_for_settling
    return extend_for_settling(base, settings, error)


def _run(args) -> int:
    from contextlib import nullcontext

    from ..plotting.process import FigureProcess

    comm = world_if_parallel()
    # one process: matplotlib loads in a second process while this one computes, and
    # draws the figures while the tables are written (not under mpirun: no fork there)
    separate = not args.no_plots and comm is None
    with FigureProcess() if separate else nullcontext() as figures:
        return _run_scene(args, comm, figures)


def _run_scene(args, comm, figures) -> int:
    from ..pipeline import run
    from ..scene import load_scene

    scene = with_measured(load_scene(args.scene), getattr(args, "reference", None))
    spice = getattr(args, "spice", False) or getattr(args, "spice_start_up", False)
    if spice:
        from ..spice import check_exportable
        check_exportable(scene)           # before the work (issue #54.13)
    extended = getattr(args, "settling_extended", None)
    if extended and (comm is None or comm.rank == 0):
        import sys
        print(extended["reason"], file=sys.stderr, flush=True)   # as sweep's line
    # [run] realisations > 1: the library runs the ensemble (result.ensemble, ensemble_rows)
    result = run(scene, comm=comm, cache_dir=args.cache_dir, progress=True,
                 command_line=command_line(), jobs=args.jobs)
    if extended:
        result.summary["run_extended"] = extended
    if comm is None or comm.rank == 0:
        written = result.write(args.output, plots=not args.no_plots,
                               spice=spice,
                               spice_start_up=getattr(args, "spice_start_up", False),
                               figures=figures)
        if figures is not None:
            figures.finish()
        print_summary(result.summary)
        print("wrote " + ", ".join(str(p) for p in written))
    return 0


def with_measured(scene, items):
    """``scene`` with ``--reference KEY=VALUE ...`` merged into its ``[reference]``
    (checked as keys in the file; a bad item is a one-line SceneError)."""
    if not items:
        return scene
    from ..errors import SceneError
    from ..quantities import parse_measured

    try:
        values = parse_measured(items)
    except ValueError as exc:
        raise SceneError(str(exc)) from None
    return scene.with_values(reference=values)


def terminal_lines(summary: dict) -> list[str]:
    """The ``peak:`` and ``peak-to-peak:`` lines of a run's summary (names and units from
    :mod:`tengfield.quantities`), and the instrument's reading when there is one."""
    from ..plotting.waveforms import cells_phrase
    from ..quantities import QUANTITIES, TERMINAL, display

    lines = []
    for stat, words in (("peak", "peak (max |x|)"), ("peak_to_peak", "peak-to-peak")):
        values = summary.get(stat)
        if not values:
            continue
        names = [n for n in TERMINAL if n in values]
        where = ", ".join(p for p in (f"{summary['reference']} reference",
                                       cells_phrase(summary["cells"])) if p)
        lines.append(f"{words} ({where}): "
                     + ", ".join(f"{QUANTITIES[n].symbol} = {display(n, values[n])}"
                                 for n in names))
    if "V_read_V" in (summary.get("peak") or {}):
        c_p = summary["circuit"]["parallel_capacitance_F"] * 1e12
        lines.append(f"V read through C_p = {c_p:g} pF: peak {display('V_read_V', summary['peak']['V_read_V'])}, "
                     f"peak-to-peak {display('V_read_V', summary['peak_to_peak']['V_read_V'])} "
                     "(V_OC above is the ideal open-circuit voltage)")
    read = [n for n in ("Q_read_C", "I_read_A") if n in (summary.get("peak") or {})]
    if read:
        lines.append("read by the [instrument] (bandwidth, aperture, sample rate): "
                     + ", ".join(f"{QUANTITIES[n].symbol} peak {display(n, summary['peak'][n])}, "
                                 f"peak-to-peak {display(n, summary['peak_to_peak'][n])}"
                                 for n in read))
    return lines


def band_lines(summary: dict) -> list[str]:
    """The band of the charge the device holds (docs/breakdown.md), the trajectory's
    |V_gap|/V_b at the run's σ and, for σ = "breakdown", each main output as its band."""
    from ..quantities import describe, display

    bd = summary.get("breakdown") or {}
    band, path = bd.get("band"), bd.get("trajectory")
    if not band:
        return []
    lines = [f"  band: lower {band['lower_uC_per_m2']:.4g}, estimate "
             f"{band['estimate_uC_per_m2']:.4g}, upper {band['upper_uC_per_m2']:.4g} µC/m^2"
             + (f"; over the {path.get('over_s', 0.0):.3g} s steady window of the trajectory "
                f"max |V_gap|/V_b = {path['peak_gap_voltage_over_breakdown']:.3g} at this "
                f"sigma, above 1 for {path['time_above_breakdown_s']:.3g} s of it"
                if path else "")]
    lines += [f"    {text}" for text in band.get("assumptions", {}).values()]
    outputs = summary.get("breakdown_band") or {}
    for key, edges in outputs.items():
        if not isinstance(edges, dict):
            continue
        name = key.rpartition(".")[2]
        lines.append(f"  {describe(key, unit=False)}: " + " / ".join(
            display(name, edges[e]) for e in ("lower", "estimate", "upper"))
            + " (lower / estimate / upper)")
    if outputs.get("available") is False:
        lines.append(f"  outputs at the band: {outputs['reason']}")
    return lines


def comparison_lines(summary: dict) -> list[str]:
    """The table of ``summary["measured_comparison"]``: tool value, measured value and %
    difference per measured figure, naming the tool quantity each is compared with."""
    from ..quantities import percent_text

    block = summary.get("measured_comparison")
    if not block:
        return []
    lines = ["measured comparison (tool vs measured, difference = (tool - measured) / measured):"]
    for name, row in block["quantities"].items():
        diff_text = percent_text(row["difference_percent"])
        tool = "n/a" if row["tool_value"] is None else f"{row['tool_value']:.4g}"
        if row["tool_key"] is None:
            lines.append(f"  {name:16s} measured {row['measured_value']:.4g} {row['unit']}: "
                         f"{row['tool_label']}")
            continue
        lines.append(f"  {name:16s} tool {tool} vs measured {row['measured_value']:.4g} "
                     f"{row['unit']}: {diff_text}  [{row['tool_key']}: {row['tool_label']}]")
    return lines


def _level(level: float, x, length: float | None) -> str:
    """"reaches 4.04 V at 0.81 s", or "4.04 V not reached in 5 s" for ``x`` None."""
    if x is not None:
        return f"reaches {level:g} V at {x:.4g} s"
    return f"{level:g} V not reached" + ("" if length is None else f" in {length:.4g} s")


def ensemble_line(ens: dict) -> str:
    """The terminal line of ``summary -> ensemble``: each output's mean +- 95 % CI (peak-
    to-peak V_OC, Q_SC, I_SC; power), in the quantity table's units; an output whose
    spread is round-off (:data:`tengfield.ensemble.ROUNDOFF_RELATIVE`) is said to be the
    same in every realisation, without a +-."""
    from ..ensemble import ROUNDOFF_RELATIVE
    from ..quantities import quantity

    stats = ens["quantities"]
    parts, same = [], False
    for key, name, label in (("V_oc_pp_V", "V_oc_V", "V_OC"), ("Q_sc_pp_C", "Q_sc_C", "Q_SC"),
                             ("I_sc_pp_A", "I_sc_A", "I_SC"),
                             ("mean_power_W", "mean_power_W", "P"),
                             ("average_harvested_power_W", "average_harvested_power_W",
                              "harvested")):
        s = stats.get(key)
        if not s or s["mean"] is None:
            continue
        q = quantity(name)
        scale, unit = q.display_scale, q.display_unit
        if s.get("equal_within_round_off"):
            same = True
            parts.append(f"{label} {s['mean'] * scale:.4g} {unit} (same in every realisation)")
            continue
        half = s["ci95_half_width"]
        spread = "" if half is None else f" +- {half * scale:.3g}"
        parts.append(f"{label} {s['mean'] * scale:.4g}{spread} {unit}")
    note = (f"; same = spread below {ROUNDOFF_RELATIVE:g} of the value (round-off)"
            if same else "")
    return (f"ensemble of {ens['realisations']} realisations (mean +- 95 % CI, peak-to-peak): "
            + ", ".join(parts) + note)


def print_summary(summary: dict) -> None:
    regime = summary.get("regime") or {}
    from ..dynamics.regime import regime_label

    label = regime_label(regime.get("regime", "?"), regime.get("period", 0),
                         settled_by_s=regime.get("settled_by_s"),
                         checked_to_s=regime.get("regime_checked_to_s") or 0.0,
                         duration_s=regime.get("regime_run_s") or None)
    print(f"regime: {label} "
          f"(max gap {1e3 * (regime.get('max_gap_m') or 0):.3g} mm)"
          + (f": {regime['reason']}" if regime.get("reason") else ""))
    if summary.get("charge"):
        from ..contact_run import waveform_line
        from ..source.contacts import charge_line
        print(charge_line(summary["charge"]))
        window = waveform_line(summary["charge"])
        if window:
            print(window)
    for line in terminal_lines(summary):
        print(line)
    if summary.get("load"):
        load = summary["load"]
        print(f"load {summary['circuit']['load_ohm']:.3g} ohm: mean power "
              f"{load['mean_power_W'] * 1e6:.4g} µW, {load['power_density_W_per_m3']:.4g} W/m^3")
    matched = summary.get("matched_load")
    if matched:
        print(f"matched load {matched['load_ohm']:.3g} ohm: mean power "
              f"{matched['mean_power_W'] * 1e6:.4g} µW, "
              f"{matched['power_density_W_per_m3']:.4g} W/m^3 (the resistor taking the most; "
              "from this run's Q_SC, C_T, no field solve)")
    energy = summary.get("energy_per_cycle")
    if energy:
        line = (f"energy per cycle: CMEO bound (the device's most) "
                f"{energy['max_energy_per_cycle_J']:.4g} J")
        if "load_loop_area_J" in energy:
            line += (f"; V-Q loop area, load {energy['load_ohm']:.3g} ohm: "
                     f"{energy['load_loop_area_J']:.4g} J")
        if "rectifier_loop_area_J" in energy:
            line += (f"; V-Q loop area of the last period through the rectifier: "
                     f"{energy['rectifier_loop_area_J']:.4g} J")
        print(line + f" (FOM_S = {energy['figure_of_merit_structural']:.4g})")
    bd = summary.get("breakdown")
    if bd and bd.get("available"):
        print(f"air breakdown: static limit sigma_max = {bd['sigma_max_uC_per_m2']:.4g} µC/m^2, "
              f"|sigma| / sigma_max = {bd['margin']:.3g} (sigma = {bd['sigma_uC_per_m2']:.4g} "
              f"µC/m^2, from the {bd['sigma_from']})")
        for line in band_lines(summary):
            print(line)
    rect = summary.get("rectifier")
    if rect:
        length = rect.get("record_length_s")
        line = (f"store {rect['storage_capacitance_F'] * 1e6:.4g} µF: U = "
                f"{rect['final_store_voltage_V']:.4g} V at the end")
        if rect["pmic"] != "none":    # the UVLO levels are the chip's
            falling, rising = rect["uvlo_levels_V"]
            line += (f"; {_level(falling, rect['time_to_uvlo_falling_V_s'], length)}, "
                     f"{_level(rising, rect['time_to_uvlo_rising_V_s'], length)}")
        print(line + f"; harvested {rect['average_harvested_power_W'] * 1e6:.4g} µW, "
              f"into the store {rect['energy_per_cycle_J']:.4g} J per excitation period "
              "(averaged over the steady window)")
        if rect["pmic"] != "none":
            print(f"chip: on {rect['chip_switch_on_count']} time(s), duty cycle "
                  f"{rect['chip_duty_cycle']:.4g}")
        res = rect["energy_residuals"]
        print("energy books residuals: " + ", ".join(f"{k} {v:.2g}" for k, v in res.items()))
    arr = summary.get("array")
    if arr:
        print(f"array: {arr['cells']} cells ({arr['connection']}), {arr['compared']}: array / "
              f"(N x one cell) = {arr['array_over_N_cells']:.4g}, phase std "
              f"{arr['phase_std_deg']:.3g} deg, coherence {arr['phase_coherence']:.3g}")
    ens = summary.get("ensemble")
    if ens:
        print(ensemble_line(ens))
    for line in comparison_lines(summary):
        print(line)
    for name, stage in summary["stages"].items():
        print(f"  {name:9s} {stage['status']:8s} {stage['wall_time_s']:7.2f} s  {stage['reason']}")
