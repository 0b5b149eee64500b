"""``tengfield fit``: calibrate a scene's unknowns to a measured trace or to scalar targets.

Writes DIR/fit.json (values, standard errors, correlations, residuals,
identifiability notes, iterations, wall time), DIR/fit.png (measured vs fitted
with residuals) and DIR/fitted.toml (the scene with the fitted values).
"""
from __future__ import annotations

from pathlib import Path  # a scene argument is a file name, never TOML text

from ..scene.schema import SURFACE_CHARGE_KEY


def register(sub) -> None:
    p = sub.add_parser(
        "fit", help="fit sigma, C_p, restitution, load, time shift to a measured trace",
        description="Least-squares calibration of the scene's [fit] parameters to a measured "
                    "CSV (--measured) or to scalar peak values (--targets), reusing one field "
                    "surrogate. Writes fit.json, fit.png and fitted.toml to DIR.")
    p.add_argument("scene", nargs="?", type=Path,
                   help="scene file with a [fit] section (default: the "
                        "embedded default scene)")
    source = p.add_mutually_exclusive_group(required=True)
    source.add_argument("--measured", metavar="FILE.csv",
                        help="measured trace: a header row, a time column and V / Q / I columns "
                             "([fit.columns]; default the columns of a `tengfield run` "
                             "waveforms.csv)")
    source.add_argument("--targets", nargs="+", metavar="NAME=VALUE[+-SIGMA]",
                        help="scalar targets instead of a trace, e.g. V_pp_V=4.2 Q_pp_nC=1.42 "
                             "I_peak_uA=0.16 (pp = peak-to-peak, peak = max |x| over the steady "
                             "window; default uncertainty 5 %%). V is compared with the voltage "
                             "read through C_p (the ideal V_OC when C_p = 0), Q with Q_SC, I "
                             "with I_SC (with a load: the load's V and I); fit.json and the "
                             "terminal name each tool quantity")
    p.add_argument("--free", metavar="NAME[,NAME...]", default=None,
                   help="free parameters (overrides [fit.parameters]; bounds and starts from "
                        f"there or the defaults): {SURFACE_CHARGE_KEY}, "
                        "parallel_capacitance_pF, restitution, load_ohm, time_shift_s, "
                        "amplitude_scale")
    p.add_argument("--loss", default=None,
                   choices=["linear", "soft_l1", "huber", "cauchy", "arctan"],
                   help="residual loss (overrides [fit] loss; robust losses resist outliers)")
    p.add_argument("--profile", action="store_true",
                   help="profile the poorly determined parameters (Δχ² ≤ 1 intervals)")
    p.add_argument("--bootstrap", type=int, default=None, metavar="N",
                   help="N moving-block bootstrap refits of a trace fit (overrides [fit] "
                        "bootstrap)")
    p.add_argument("-o", "--output", default="out", metavar="DIR",
                   help="output directory (created; default ./out)")
    p.add_argument("--cache-dir", default=None, metavar="DIR",
                   help="surrogate cache (default $TENGFIELD_CACHE_DIR, else "
                        "$XDG_CACHE_HOME/tengfield or ~/.cache/tengfield)")
    p.add_argument("--no-plots", "--no-plot", dest="no_plots", action="store_true",
                   help="skip fit.png")
    p.set_defaults(func=_run, one_process="the least-squares fit; compute its surrogate under "
                                          "mpirun with `tengfield precompute` first")


def _run(args) -> int:
    from ..fit import calibrate
    from ..scene import load_scene

    scene = load_scene(args.scene)
    overrides = {}
    if args.loss:
        overrides["loss"] = args.loss
    if args.profile:
        overrides["profile"] = True
    if args.bootstrap is not None:
        overrides["bootstrap"] = args.bootstrap
    free = [n.strip() for n in args.free.split(",") if n.strip()] if args.free else None
    result = calibrate(scene, measured=args.measured, targets=args.targets, free=free,
                       cache_dir=args.cache_dir, progress=True, overrides=overrides or None)
    written = result.write(args.output, plots=not args.no_plots)
    print_result(result)
    print("wrote " + ", ".join(str(p) for p in written))
    return 0


def print_result(result) -> None:
    from ..fit import PARAMETERS

    print(f"fit ({result.mode}): {result.message} ({result.evaluations} evaluations, "
          f"{result.dynamics_runs} dynamics runs, {result.wall_time:.2f} s)")
    for name in result.names:
        unit = PARAMETERS[name][2]
        flag = "" if result.identifiable[name] else "   NOT identifiable"
        print(f"  {name:26s} = {result.values[name]:12.6g} +- "
              f"{result.standard_errors[name]:.3g} {unit}{flag}")
    from ..fit._residuals import residual_lines

    for line in statistics_lines(result):
        print(f"  {line}")
    print("  residuals:")
    for line in residual_lines(result.mode, result.residuals):
        print(f"    {line}")
    if result.breakdown:
        b = result.breakdown
        print(f"  air breakdown: sigma_max = {b['sigma_max_uC_per_m2']:.3g} µC/m^2 of the scene, "
              f"|fitted sigma| / sigma_max = {b['margin']:.3g}")
    for note in result.notes:
        print(f"  note: {note}")


def statistics_lines(result) -> list[str]:
    """What the fit's chi^2 and standard errors rest on, in the data's units: the noise
    levels (given, or estimated from the residuals, when the reduced chi^2 is 1 by
    construction), a targets fit's assumed 1-sigma uncertainties (5 % by default)."""
    from ..fit._residuals import UNITS

    chi2 = result.chi2_reduced
    if result.mode == "targets":
        parts = []
        for label, noise in result.noise.items():
            r = result.residuals.get(label, {})
            text = f"{label} +- {r.get('uncertainty', float('nan')):.3g} {r.get('unit', '')}"
            if noise.get("how", "").startswith("given"):
                parts.append(text + " (given)")
            else:
                parts.append(text + f" ({100 * noise.get('relative', 0.0):.3g} %, the default: "
                                    "write NAME=VALUE+-SIGMA)")
        lines = ["assumed 1-sigma uncertainty of each target (weights of the fit and its "
                 "standard errors): " + ", ".join(parts)]
        free = len(result.residuals) - len(result.names)
        lines.append(f"reduced chi^2 = {chi2:.3g}" if free > 0 else
                     "reduced chi^2: none (no degrees of freedom: as many targets as "
                     "parameters)")
        return lines
    levels, estimated = [], []
    for q, noise in result.noise.items():
        r = result.residuals.get(q, {})
        unit = r.get("unit", "")
        factor = UNITS.get(q, {}).get(unit, 1.0)
        levels.append(f"{q} {noise['value_SI'] / factor:.3g} {unit}")
        if noise.get("how", "").startswith("estimated"):
            estimated.append(q)
    if estimated and len(estimated) == len(result.noise):
        return [f"reduced chi^2 = {chi2:.3g}: 1 by construction (the noise of every column is "
                f"estimated from the residuals: {', '.join(levels)}); standard errors assume "
                "that noise, independent between samples; give [fit.columns] noise levels "
                "for a test of the model"]
    how = ", ".join(f"{lv} ({result.noise[q]['how']})" for lv, q in zip(levels, result.noise))
    return [f"reduced chi^2 = {chi2:.3g} with the noise levels {how}"]
