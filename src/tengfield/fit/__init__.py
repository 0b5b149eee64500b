"""Calibration: fit a scene's unknowns to a measured waveform or to scalar targets.

``tengfield fit [SCENE] --measured FILE.csv`` (or ``--targets V_pp_V=4.2 ...``)
fits the free parameters of the scene's ``[fit]`` section (σ, C_p, the
restitution, the load, a time shift, an amplitude scale) by bounded least
squares, reusing one field surrogate for every iteration (σ scales the charge
linearly), and reports standard errors, correlations and which parameters the
data cannot determine (docs/fit.md).

* :func:`calibrate` - the whole chain from a scene (surrogate obtained once);
* :func:`fit_trace`, :func:`fit_targets` - the fits given a surrogate;
* :func:`parse_fit_section`, :func:`read_trace`, :func:`parse_targets` - input;
* :func:`write_fit_outputs` - fit.json, fit.png, fitted.toml.
"""
from __future__ import annotations

from .output import fitted_scene_dict, write_fit_outputs
from .solve import FitError, FitResult, fit_targets, fit_trace
from .spec import (PARAMETERS, FitSpec, Target, Trace, parse_fit_section, parse_targets,
                   read_trace)
from ..scene.schema import SURFACE_CHARGE_KEY

__all__ = ["calibrate", "reference_surrogate", "fit_trace", "fit_targets", "FitResult",
           "FitError", "FitSpec", "Trace", "Target", "PARAMETERS", "parse_fit_section",
           "read_trace", "parse_targets", "write_fit_outputs", "fitted_scene_dict"]

#: σ [µC/m²] of the surrogate when the scene's own σ is zero: the one stand-in σ
#: (:func:`tengfield.surrogate.cache.solved_scene`, breakdown's, uncertainty's)
from ..scene.schema import BREAKDOWN_PLACEHOLDER_UC as FALLBACK_SIGMA_UC  # noqa: E402


def reference_surrogate(scene, *, cache_dir=None, solve=None, comm=None, progress=False):
    """``(curves, sigma_ref [C/m²], outcome)``: the surrogate of ``scene`` at its own σ
    (at -1 µC/m² when that is zero), obtained once (cached by the field hash)."""
    from ..surrogate import TerminalCurves

    table, sigma_ref, outcome = _reference_table(scene, cache_dir=cache_dir, solve=solve,
                                                 comm=comm, progress=progress)
    return (TerminalCurves(table, scene.circuit.reference, _ball_charge(scene, sigma_ref)),
            sigma_ref, outcome)


def _ball_charge(scene, sigma: float) -> float:
    """σ π d² [C]: the ball's charge at the surface charge ``sigma`` [C/m²] (the curves'
    reference charge; the table is per unit ball charge)."""
    import math
    return sigma * math.pi * scene.device.ball_diameter**2


def _reference_table(scene, *, cache_dir=None, solve=None, comm=None, progress=False):
    """``(table, sigma_ref [C/m²], outcome)`` of :func:`reference_surrogate`."""
    from ..surrogate import obtain_table
    from ..surrogate.cache import solved_scene

    scene = solved_scene(scene)   # an uncharged ball: the stand-in σ, as every surrogate
    table, outcome = obtain_table(scene, cache_dir=cache_dir, comm=comm, solve=solve,
                                  progress=progress)
    return table, scene.device.surface_charge, outcome


def breakdown_check(scene, table, result: FitResult) -> None:
    """A fitted σ beyond the scene's air-breakdown limit σ_max (from the same surrogate's
    gap lines, :func:`tengfield.air_breakdown.scene_breakdown`): one warning naming both, a
    note, and ``result.breakdown``. Nothing when σ is not fitted or the surrogate has no
    gap lines (3D solver, a custom solve)."""
    import warnings

    name = SURFACE_CHARGE_KEY
    if name not in result.values or table.line_potential is None:
        return
    from ..air_breakdown import scene_breakdown

    limit = scene_breakdown(scene, table)
    sigma = result.values[name] * 1e-6
    margin = limit.margin(sigma)
    result.breakdown = {"sigma_max_uC_per_m2": limit.sigma_max * 1e6, "margin": margin,
                        "fitted_sigma_uC_per_m2": result.values[name],
                        "binding": limit.binding.state, "rule": "|fitted sigma| / sigma_max "
                        "(above 1: the gap would discharge before the ball holds that charge)"}
    if margin > 1.0:
        b = limit.binding
        text = (f"fitted {name} = {result.values[name]:.4g} exceeds the scene's air-breakdown "
                f"limit sigma_max = {limit.sigma_max * 1e6:.3g} µC/m^2 ({b.state}, {b.side} "
                f"gap {b.gap * 1e3:.3g} mm): the gap would discharge first, so the data "
                "need another explanation (geometry, C_p, the instrument) or the charge is "
                "not the ball's alone")
        result.notes.append(text)
        warnings.warn(f"fit: {text}", RuntimeWarning, stacklevel=2)


def calibrate(scene, *, measured=None, targets=None, free=None, cache_dir=None, solve=None,
              simulate=None, comm=None, progress=False, overrides: dict | None = None) -> FitResult:
    """Fit ``scene`` to a measured CSV (path) or to target strings (``["V_pp_V=4.2", ...]``).

    ``free`` (names) overrides the free parameters of ``[fit.parameters]``;
    ``overrides`` sets ``[fit]`` keys (e.g. ``{"loss": "huber", "profile": True}``).
    ``solve``/``simulate`` replace the field solver and the dynamics (tests).
    """
    from .._args import names, path
    from ..charge_models import check_command
    check_command(scene, "fit")   # a charge model it runs
    targets = names("tengfield.calibrate", targets, "targets")   # "Q_pp_nC=0.3": one target
    free = names("tengfield.calibrate", free, "free")            # one name, not its letters
    cache_dir = path("tengfield.calibrate", cache_dir, "cache_dir", allow_none=True,
                     what="a folder name")
    measured = path("tengfield.calibrate", measured, "measured", allow_none=True,
                    what="a measured trace's file name (CSV, or a run's run.h5)")
    if (measured is None) == (targets is None):
        raise FitError("give either a measured trace or targets, not both")
    if overrides:
        raw = dict(scene.raw.get("fit", {}) or {})
        raw.update(overrides)
        scene = scene.with_values(fit=raw)
    spec = parse_fit_section(scene, free)
    if targets is not None:
        goal = parse_targets(targets)
        if free is None and "parameters" not in (scene.raw.get("fit") or {}):
            spec = parse_fit_section(scene, _default_target_parameters(goal))
    else:
        goal = read_trace(measured, spec)
    from ..surrogate import TerminalCurves

    table, sigma_ref, _ = _reference_table(scene, cache_dir=cache_dir, solve=solve, comm=comm,
                                           progress=progress)
    curves = TerminalCurves(table, scene.circuit.reference, _ball_charge(scene, sigma_ref))
    if targets is not None:
        result = fit_targets(scene, curves, sigma_ref, goal, spec, simulate=simulate)
    else:
        result = fit_trace(scene, curves, sigma_ref, goal, spec, simulate=simulate,
                           progress=progress)
    breakdown_check(scene, table, result)
    result.scene = scene
    return result


def _default_target_parameters(targets) -> list[str]:
    """σ, and C_p when a voltage is among the targets."""
    names = [SURFACE_CHARGE_KEY]
    if any(t.quantity == "V" for t in targets):
        names.append("parallel_capacitance_pF")
    return names
