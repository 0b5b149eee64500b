"""The run's surrogate: the field surrogate a run uses, at the charge it runs with, decided
in one place for ``run``, ``sweep``, ``field``, the ensemble and ``uncertainty``
(:func:`surrogate_for_run`).

A numeric σ runs with the scene's own surrogate (cached by field hash, or solved), checked
against the air-breakdown limit when the table has gap lines; ``[device]
σ = "breakdown"`` takes the surrogate with its gap lines and runs at
σ = −σ_max, the table scaled to it (charges are linear in σ: no new field solve;
:mod:`tengfield.air_breakdown` holds the physics).
"""
from __future__ import annotations

from .air_breakdown import obtain_breakdown_table, resolve_for_run, uses_breakdown_charge


def surrogate_for_run(scene, *, cache_dir=None, comm=None, solve=None, progress: bool = False,
                      command_line: str = "", write: bool = True):
    """``(scene, table, outcome, limit)``: the scene at the charge it runs with (σ [C/m²]
    = −σ_max for ``"breakdown"``, else itself), its surrogate table at that charge, how
    the table was obtained (:class:`tengfield.surrogate.Outcome`: cached or computed) and
    the breakdown limit (:class:`tengfield.air_breakdown.BreakdownResult`; None when the
    table has no gap lines). ``solve`` replaces the field solver; ``write`` False keeps a
    computed table out of the cache."""
    from .surrogate import obtain_table

    obtain = obtain_breakdown_table if uses_breakdown_charge(scene) else obtain_table
    table, outcome = obtain(scene, cache_dir=cache_dir, comm=comm, solve=solve,
                            progress=progress, command_line=command_line, write=write)
    scene, table, limit = resolve_for_run(scene, table, comm)
    return scene, table, outcome, limit
