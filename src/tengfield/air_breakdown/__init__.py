"""Air breakdown (docs/breakdown.md), split by layer:

* :mod:`.limit` the physics (pure numpy): the gap lines, their voltages per unit σ in
  each circuit state, σ_max (:func:`evaluate`, :class:`BreakdownResult`), the energies
  at σ_max;
* :mod:`.charge` the charge a run uses (its σ, or −σ_max for ``"breakdown"``:
  :func:`resolve_for_run`; the run's surrogate at it is
  :func:`tengfield.run_surrogate.surrogate_for_run`'s);
* :mod:`.band` the charge a device holds as a band (lower, seed-limited estimate,
  upper) from the field and the trajectory (issue #38);
* :mod:`.output` what ``tengfield breakdown`` prints and writes.
"""
from __future__ import annotations

from .band import (Band, Seeds, Trajectory, band_summary, compute_band, scene_band,
                   trajectory_of)
from .charge import (charge_line, check_gap_lines, obtain_breakdown_table, resolve_for_run,
                     scene_breakdown, scene_states, scene_surface_charge,
                     summary_block, uses_breakdown_charge)
from .limit import (CHECK_MARGIN, CSV_COLUMNS, DENSE_POINTS, SIDES, STATE_TEXT,
                    STATES, Binding, BreakdownResult, Lines, electrode_potentials, evaluate,
                    gap_voltages, limited_energy, lines_from_table)
from .output import BreakdownStudy, study, summary_lines, write_outputs

__all__ = ["study", "Band", "Seeds", "Trajectory", "band_summary", "compute_band", "scene_band",
           "trajectory_of",
           "CHECK_MARGIN", "CSV_COLUMNS", "DENSE_POINTS", "SIDES",
           "STATE_TEXT", "STATES", "Binding", "BreakdownResult", "Lines", "charge_line",
           "electrode_potentials", "evaluate", "gap_voltages", "limited_energy",
           "lines_from_table", "obtain_breakdown_table", "check_gap_lines",
           "resolve_for_run", "scene_breakdown", "scene_surface_charge",
           "scene_states", "summary_block", "summary_lines", "uses_breakdown_charge",
           "write_outputs"]
