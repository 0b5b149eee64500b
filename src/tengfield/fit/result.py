"""The outcome of a fit (:class:`FitResult`, fit.json's summary) and :class:`FitError`."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._args import checked_write
from ..errors import TengfieldError
from .spec import PARAMETERS


class FitError(TengfieldError, RuntimeError):
    """The fit could not be carried out (e.g. the model gives no signal)."""


@dataclass
class FitResult:
    """Outcome of :func:`fit_trace` / :func:`fit_targets` (file units for parameters)."""
    mode: str                                   # "trace" or "targets"
    names: list[str]
    values: dict[str, float]
    start: dict[str, float]
    bounds: dict[str, tuple[float, float]]
    standard_errors: dict[str, float]
    correlation: np.ndarray
    identifiable: dict[str, bool]
    notes: list[str]
    residual_rms: dict[str, float]              # per column / target, SI, >= 0
    chi2_reduced: float
    noise: dict[str, dict]                      # per column: value [SI] and "given"/"estimated"
    evaluations: int
    jacobian_evaluations: int
    dynamics_runs: int
    status: int
    message: str
    wall_time: float
    alignment: dict = field(default_factory=dict)
    profiles: dict = field(default_factory=dict)
    bootstrap: dict = field(default_factory=dict)
    measured: dict = field(default_factory=dict)    # plotting: time, values
    fitted: dict = field(default_factory=dict)
    loss: str = "linear"
    #: per column / target in its own unit and as a % (tengfield.fit._residuals)
    residuals: dict = field(default_factory=dict)
    #: σ_max of the scene's surrogate and the fitted σ's margin (when σ is fitted and the
    #: surrogate has breakdown lines)
    breakdown: dict = field(default_factory=dict)

    def plot(self):
        """The fit figure (a matplotlib Figure; ``tengfield fit`` saves it as fit.png):
        measured against fitted with the residuals (a trace), or fitted / target (targets)."""
        from ..plotting.fit import fit_figure   # the edge, imported on use

        return fit_figure(self)

    scene: Any = field(default=None, repr=False, compare=False)   # the scene fitted

    @property
    def summary(self) -> dict:
        """JSON-ready: what fit.json holds (``as_dict()``, the older spelling)."""
        return self.as_dict()

    @property
    def t(self):
        """The measured trace's times [s] (a trace fit), else None."""
        return self.measured.get("time")

    @checked_write
    def write(self, out_dir, plots: bool = True) -> list:
        """Write what ``tengfield fit -o out_dir`` writes; returns the paths."""
        from .output import write_fit_outputs

        return write_fit_outputs(self.scene, self, out_dir, plots=plots)

    def as_dict(self) -> dict:
        """JSON-ready summary (fit.json)."""
        def finite(x):
            return None if x is None or not math.isfinite(x) else float(x)
        return {
            "mode": self.mode,
            "parameters": {n: {"value": self.values[n], "standard_error": finite(
                self.standard_errors[n]), "start": self.start[n], "min": self.bounds[n][0],
                "max": self.bounds[n][1], "identifiable": self.identifiable[n],
                "unit": PARAMETERS[n][2], "meaning": PARAMETERS[n][3]} for n in self.names},
            "correlation": {"names": self.names,
                            "matrix": [[finite(v) for v in row] for row in self.correlation]},
            "identifiability_notes": self.notes,
            "residual_rms": self.residual_rms,
            "residual_rms_rule": "SI: a column's RMS of fitted - measured, a target's "
                                 "|fitted - measured|; 'residuals' has them in the data's units "
                                 "and as %",
            "residuals": self.residuals,
            "breakdown": self.breakdown,
            "chi2_reduced": finite(self.chi2_reduced),
            "noise": self.noise,
            "loss": self.loss,
            "iterations": {"function_evaluations": self.evaluations,
                           "jacobian_evaluations": self.jacobian_evaluations,
                           "dynamics_runs": self.dynamics_runs},
            "status": self.status, "message": self.message,
            "wall_time_s": self.wall_time,
            "alignment": self.alignment,
            "profiles": self.profiles,
            "bootstrap": self.bootstrap,
            "uncertainty_rule": "covariance s^2 (J^T J)^-1 at the optimum, J the Jacobian of the "
                                "weighted residuals; s^2 = reduced chi^2 when the noise is "
                                "estimated, max(1, reduced chi^2) when it is given; assumes "
                                "independent noise between samples",
        }
