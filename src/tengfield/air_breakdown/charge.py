"""The charge a run uses: the scene's σ, or −σ_max for ``[device]
σ = "breakdown"`` (:func:`resolve_for_run`); the surrogate is per unit ball charge
(charges are linear in σ: no new field solve), the run's curves take the scene's charge
(:func:`tengfield.run_surrogate.surrogate_for_run`)."""
from __future__ import annotations

from ..paschen import Paschen
from .limit import BreakdownResult, evaluate, lines_from_table
from ..scene.schema import SURFACE_CHARGE_KEY, stated_surface_charge


def scene_states(scene) -> tuple[str, ...]:
    """The circuit states the scene implies: open circuit, short circuit, or all three
    for a load or a rectifier (its transferred charge lies between the two open ones).
    An open circuit read through an instrument (``parallel_capacitance_pF`` > 0) moves
    charge between 0 and Q_SC through it: open and short circuit bound it."""
    from ..electrical import circuit_for   # the entry's breakdown_states / states()
    return circuit_for(scene).states(scene)


def uses_breakdown_charge(scene) -> bool:
    """True when ``σ = "breakdown"`` or ``[charge] model = "breakdown"`` (the charge
    model's entry, :data:`tengfield.charge_models.CHARGE_MODELS`)."""
    from ..charge_models import charge_model_of
    return charge_model_of(scene).at_breakdown_limit


def scene_breakdown(scene, table, states=None) -> BreakdownResult:
    """:func:`evaluate` for a scene and its surrogate table (the scene's states,
    ``[circuit] reference``, ``[breakdown]`` Paschen constants and the scene's σ)."""
    sigma = None if uses_breakdown_charge(scene) else scene.device.surface_charge
    result = evaluate(lines_from_table(table, scene), Paschen.from_scene(scene),
                      scene_states(scene) if states is None else states,
                      scene.circuit.reference, sigma)
    result.scene = scene
    return result


def check_gap_lines(scene, needed_by: str, alternative: str = "") -> None:
    """Refuse, in one line before any work, a scene whose field solves give no breakdown
    gap lines when ``needed_by`` (what asks: "the breakdown check", σ = "breakdown", a
    breakdown-band draw) needs them: the one check of ``run`` (the scene's field
    problems), ``breakdown``, ``design`` and ``uncertainty``
    (:func:`tengfield.scene.shapes.gap_lines_problem`; ``alternative``: what else the
    asker can do, said after the fix)."""
    from ..errors import SceneError
    from ..scene.shapes import gap_lines_problem

    problem = gap_lines_problem(scene.device, scene.field, alternative)  # a refused [field]: its line
    if problem is not None:
        raise SceneError(f"{needed_by}: {problem}")


def obtain_breakdown_table(scene, *, cache_dir=None, comm=None, progress: bool = False,
                           command_line: str = "", write: bool = True, solve=None):
    """The scene's surrogate (:func:`tengfield.surrogate.obtain_table`, cached) with its
    breakdown lines. A cached table without them (written by an older tengfield or a
    custom solve) is recomputed once with a warning, the new one cached."""
    import dataclasses
    import time
    import warnings

    from ..surrogate import obtain_table, precompute, store_in_cache

    if solve is None:
        check_gap_lines(scene, "the breakdown check")   # before minutes of 3D solves
    if scene.device.surface_charge == 0.0:
        # the per-sigma gap voltages need the induced-charge fractions q / q_ball, which
        # an uncharged ball does not give: its table is the stand-in sigma's (everything
        # is linear in sigma; sigma_max does not depend on it)
        from ..surrogate.cache import solved_scene
        scene = solved_scene(scene)
    table, outcome = obtain_table(scene, cache_dir=cache_dir, comm=comm, solve=solve,
                                  progress=progress, command_line=command_line, write=write)
    if table.line_potential is None and solve is None:   # check_gap_lines (above)
        start = time.perf_counter()
        if comm is None or comm.rank == 0:
            warnings.warn(f"cached surrogate {outcome.path} has no breakdown lines, recomputing",
                          RuntimeWarning, stacklevel=2)
        table = precompute(scene, comm=comm, progress=progress, command_line=command_line)
        stored = store_in_cache(outcome.path, table, comm) if write else False
        outcome = dataclasses.replace(outcome, status="recomputed",
                                      reason="the cached surrogate had no breakdown lines",
                                      wall_time=outcome.wall_time + time.perf_counter() - start,
                                      stored=stored)
    return table, outcome


def scene_surface_charge(scene, result: BreakdownResult) -> float:
    """The σ [C/m²] a scene runs with: its own, or −σ_max for ``"breakdown"``."""
    return -result.sigma_max if uses_breakdown_charge(scene) else scene.device.surface_charge


def charge_line(scene) -> str:
    """What ``sweep`` and ``field`` print for a scene resolved by
    :func:`tengfield.run_surrogate.surrogate_for_run`
    from ``"breakdown"``: the σ it runs with."""
    return (f"surface charge: -sigma_max = {scene.device.surface_charge * 1e6:.4g} µC/m^2 "
            f'(air-breakdown limit, [device] {SURFACE_CHARGE_KEY} = "breakdown")')


def resolve_for_run(scene, table, comm=None):
    """For :func:`tengfield.pipeline.run`: ``(scene, table, result)``. With ``[device]
    σ = "breakdown"`` the scene gets σ = −σ_max (the table, per unit ball charge, serves
    it as it is: no new field solve); otherwise both are returned as they are.
    ``result`` is None when the table has no breakdown lines. Rank 0 of ``comm`` warns
    once when |σ| exceeds σ_max."""
    import warnings

    if table.line_potential is None:
        if uses_breakdown_charge(scene):   # never run at the stand-in sigma
            from ..errors import TengfieldError
            raise TengfieldError(
                f'[device] {SURFACE_CHARGE_KEY} = "breakdown": the surrogate has no '
                "breakdown lines (made by the 3D solver or a custom solve), so sigma_max is "
                "unknown; give sigma in µC/m^2 or use [field] method = \"axisymmetric\"")
        return scene, table, None
    result = scene_breakdown(scene, table)
    if uses_breakdown_charge(scene):
        sigma = -result.sigma_max
        scene = scene.with_values(device={SURFACE_CHARGE_KEY: sigma * 1e6})
        if getattr(table, "scene", None) is not None:   # the scene its figure is drawn for
            import dataclasses
            table = dataclasses.replace(table, scene=scene)   # the arrays shared, not copied
    elif result.margin(scene.device.surface_charge) > 1.0 and (comm is None or comm.rank == 0):
        b = result.binding
        warnings.warn(
            f"[device] {SURFACE_CHARGE_KEY} = {scene.device.surface_charge * 1e6:g} exceeds "
            f"the air-breakdown limit sigma_max = {result.sigma_max * 1e6:.3g} µC/m^2 "
            f"({b.state}, {b.side} gap {b.gap * 1e3:.3g} mm at z = {b.position * 1e3:.3g} mm): "
            "the gap would discharge first (tengfield breakdown; \"breakdown\" runs at the limit)",
            RuntimeWarning, stacklevel=3)
    return scene, table, result


def summary_block(result: BreakdownResult | None, scene, given=None) -> dict:
    """``summary.json["breakdown"]``: σ_max, the margin |σ|/σ_max, where it binds
    (``given``: the scene as loaded, whose σ may be "breakdown")."""
    if result is None:
        return {"available": False,
                "reason": "the surrogate has no breakdown lines (3D solver or a custom solve)"}
    sigma = scene.device.surface_charge
    return {"available": True, "sigma_max_uC_per_m2": result.sigma_max * 1e6,
            "margin": result.margin(sigma), "margin_rule": "|sigma| / sigma_max (above 1: the "
            "air breaks down before this charge is reached)",
            "sigma_uC_per_m2": sigma * 1e6,
            "sigma_from": ("breakdown limit" if uses_breakdown_charge(given or scene)
                           else "scene"),
            "relative_error_estimate": result.relative_error_estimate,
            "binding": result.binding.to_json(), "states_checked": list(result.states),
            "pressure_Pa": result.paschen.pressure}

