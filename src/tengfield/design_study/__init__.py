"""The design study: the device geometry that serves a given vibration best (``tengfield
design``, ``tf.design(scene)``).

``[design]`` (:mod:`tengfield.design_study.spec`) names the objective (power density into the
matched load, power, Q_SC, harvested power, or the stroke), the band of excitations it
is aggregated over (mean or worst case; or ``"p10"``: a percentile over the scene's
``[uncertainty.vary]`` at each band point, then the band's mean), the keys to vary and
the budget. Every candidate gets its own field surrogate (cached by field hash, coarse
stated settings),
its dynamics at every band point and its circuit; the search (Sobol' start, shrinking
boxes) runs its rounds over the MPI task farm or worker processes (docs/design.md).

* :func:`design` -> :class:`DesignResult` (``best``, ``ranking``, ``rows``, ``confidence()``);
* :func:`evaluate`, :func:`candidate_scene`, :func:`candidate_charge` - one candidate;
* :func:`check_optimum` - a narrower search around the best;
* :func:`design_answer`, :func:`design_warnings`, :func:`answer_lines` - the answer stated
  (plate spacing, what followed, σ, load, band table), the warnings, the terminal's text;
* :func:`write_design_outputs` - design.csv, design.json, best.toml, design.png.
"""
from __future__ import annotations

from .answer import answer_lines, chosen_band_point, design_answer, design_warnings
from .candidate import (candidate_charge, candidate_scene, design_field_settings, evaluate,
                        followed_geometry, matched_load)
from .output import design_summary, write_design_outputs
from .search import DesignResult, check_optimum, design, narrowed_scene
from .spec import OBJECTIVES, DesignSpec, parse_design_section

__all__ = ["design", "DesignResult", "DesignSpec", "parse_design_section", "evaluate",
           "candidate_scene", "candidate_charge", "design_field_settings", "followed_geometry",
           "matched_load", "check_optimum", "narrowed_scene", "write_design_outputs",
           "design_summary", "OBJECTIVES", "design_answer", "design_warnings", "answer_lines",
           "chosen_band_point"]

