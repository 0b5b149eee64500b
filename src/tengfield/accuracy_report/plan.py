"""The report's settings and plan, its rows, and the error arithmetic (pure, no I/O).

:class:`FieldSetting` (one discretisation of the field solve), :class:`Row`
(one accuracy level of one stage), :class:`Plan` and :func:`make_plan` (what
:func:`tengfield.accuracy_report.build_report` measures), and the pure pieces every
stage uses: relative errors, Richardson extrapolation, the cheapest row.
All numbers are SI; errors are relative (|x − x_ref| / |x_ref|).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Iterable

import numpy as np

from ..quantities import TERMINAL, describe, quantity
from ..surrogate import FEWEST_POSITIONS

#: the waveform quantities whose errors the report measures (the terminal's: the keys of
#: ``electrical.terminal_peaks``, short names of the quantity table's ``TERMINAL``)
QUANTITIES = tuple(quantity(name).short for name in TERMINAL)
#: every error the report measures -> the dotted key of its quantity in the one table of
#: output quantities (tengfield.quantities): the terminal's peak-to-peak values and the
#: circuit stage's mean load power and peak-to-peak load voltage
ERROR_KEYS = {**{quantity(name).short: f"peak_to_peak.{name}" for name in TERMINAL},
              "P_load": "load.mean_power_W", "V_load": "peak_to_peak.V_load_V"}
#: the circuit stage's errors
CIRCUIT_ERRORS = ("P_load", "V_load")


def error_symbol(error: str) -> str:
    """The table's symbol of an error's quantity: ``"V_oc"`` -> ``"V_OC"``."""
    return quantity(ERROR_KEYS[error].rpartition(".")[2]).symbol


def error_symbols(errors=QUANTITIES) -> str:
    """``"V_OC, Q_SC, I_SC"``: the symbols of ``errors``."""
    return ", ".join(error_symbol(e) for e in errors)


#: the stages of a report and their titles (report.md's sections, the figures' titles)
STAGE_TITLES = {
    "field": "Field: mesh size, degree, axisymmetric vs 3D, far field",
    "surrogate": "Surrogate: number of positions",
    "dynamics": "Dynamics: output sampling and soft-contact stiffness",
    "circuit": "Circuit: load-integrator step for stiff to slow loads",
}


def stage_error_label(stage: str) -> str:
    """The y axis of a stage's figure: which errors it shows, by the table's symbols."""
    if stage == "circuit":
        return f"relative error ({error_symbols(CIRCUIT_ERRORS)})"
    return f"relative error (max of {error_symbols()} peak-to-peak)"


def error_words(errors=QUANTITIES) -> str:
    """The table's words for ``errors``: ``"open-circuit voltage V_OC, peak-to-peak; ..."``."""
    return "; ".join(describe(ERROR_KEYS[e], unit=False) for e in errors)
TARGETS = (1e-2, 1e-3)
#: the surrogate's ``[field] tolerance`` is at most this share of the target
BUDGET_SHARE = 1.0 / 3.0
#: fewest positions the adaptive surrogate ends with: its initial Lobatto set and the
#: positions held out between them (9 + 8 = 17), see :func:`tengfield.surrogate.precompute`
MIN_ADAPTIVE_POSITIONS = FEWEST_POSITIONS


# ---------------------------------------------------------------------------
# settings and rows
@dataclass(frozen=True)
class FieldSetting:
    """One discretisation of the field solve (file-level ``[field]`` units)."""
    method: str = "axisymmetric"
    degree: int = 2
    mesh_size_mm: float = 0.5
    far_field: str = "kelvin"
    domain_radius_mm: float = 20.0

    @property
    def label(self) -> str:
        text = f"{self.method} p{self.degree} h={self.mesh_size_mm:g}mm"
        if self.far_field != "kelvin" or self.domain_radius_mm != 20.0:
            text += f" {self.far_field} R={self.domain_radius_mm:g}mm"
        return text

    def overrides(self) -> dict:
        """Keyword arguments of :func:`tengfield.field.solve_position`."""
        return {"method": self.method, "degree": self.degree, "mesh_size_mm": self.mesh_size_mm,
                "far_field": self.far_field, "domain_radius_mm": self.domain_radius_mm}

    def field_block(self) -> dict:
        """The ``[field]`` keys of this setting."""
        return {"method": self.method, "degree": self.degree,
                "mesh_size_mm": self.mesh_size_mm, "far_field": self.far_field,
                "domain_radius_mm": self.domain_radius_mm}


@dataclass
class Row:
    """One accuracy level of one stage: its cost and its errors."""
    stage: str
    setting: str
    knobs: dict
    wall_time_s: float
    errors: dict                      # quantity -> relative error
    reference: str
    error_position: float = math.nan  # field only: max relative error of C, q
    note: str = ""

    @property
    def error(self) -> float:
        """Largest relative error over the waveform quantities (NaN if none)."""
        values = [v for v in self.errors.values() if v is not None and math.isfinite(v)]
        return max(values) if values else math.nan


@dataclass(frozen=True)
class Plan:
    """What :func:`build_report` measures (``fast`` is the CI-sized plan)."""
    field_positions: int
    field_settings: tuple
    reference_pair: tuple               # (coarser, finer) degree-2 axisymmetric kelvin
    far_field_settings: tuple
    settings_3d: tuple
    surrogate_counts: tuple
    reference_count: int
    sample_rates: tuple
    reference_sample_rate: float
    stiffnesses: tuple
    loads: tuple
    circuit_rates: tuple
    circuit_refinement: int = 16


def _settings(levels, **keys) -> tuple:
    """FieldSettings of ``(degree, mesh_size_mm)`` pairs with the same other ``keys``."""
    return tuple(FieldSetting(degree=degree, mesh_size_mm=size, **keys) for degree, size in levels)


def make_plan(fast: bool = False) -> Plan:
    """The accuracy levels of the report; ``fast`` keeps it to about a minute."""
    if fast:
        ref = _settings([(2, 1.0), (2, 0.5)])
        return Plan(
            field_positions=5,
            field_settings=_settings([(1, 2.0), (1, 1.0), (2, 2.0), (2, 1.4)]) + ref,
            reference_pair=ref,
            far_field_settings=(_settings([(2, 1.0)], far_field="robin")
                                + _settings([(2, 1.0)], far_field="dirichlet")),
            settings_3d=_settings([(1, 2.5)], method="3d", far_field="robin"),
            surrogate_counts=(5, 9, 17), reference_count=33,
            sample_rates=(5000.0, 20000.0, 80000.0, 320000.0), reference_sample_rate=1.28e6,
            stiffnesses=(1e4, 1e5),
            loads=(1e4, 1e8), circuit_rates=(2500.0, 5000.0, 10000.0), circuit_refinement=8)
    ref = _settings([(2, 0.5), (2, 0.25)])
    return Plan(
        field_positions=9,
        field_settings=_settings([(1, 2.0), (1, 1.0), (1, 0.5), (1, 0.25),
                                      (2, 2.0), (2, 1.4), (2, 1.0), (2, 0.7)]) + ref,
        reference_pair=ref,
        far_field_settings=tuple(FieldSetting(degree=2, mesh_size_mm=0.5, far_field=far,
                                              domain_radius_mm=radius)
                                 for far in ("robin", "dirichlet") for radius in (20.0, 40.0)),
        settings_3d=(_settings([(1, 2.0), (1, 1.4)], method="3d", far_field="robin")
                     + _settings([(2, 2.0)], method="3d", far_field="kelvin")),
        surrogate_counts=(5, 9, 17, 33), reference_count=65,
        sample_rates=tuple(2500.0 * 2 ** k for k in range(9)),       # 2.5 kHz .. 640 kHz
        reference_sample_rate=2.56e6,
        stiffnesses=(1e4, 1e5, 1e6),
        loads=(1e4, 1e8, 1e11), circuit_rates=(2500.0, 5000.0, 10000.0, 20000.0, 40000.0))


# ---------------------------------------------------------------------------
# pure pieces
def relative_error(value: float, reference: float) -> float:
    """|value − reference| / |reference| (NaN when the reference is 0)."""
    return abs(value - reference) / abs(reference) if reference != 0.0 else math.nan


def peak_errors(peaks: dict, reference: dict) -> dict:
    """Relative error of each peak-to-peak value against the reference's."""
    return {k: relative_error(peaks[k], reference[k]) for k in peaks}


def richardson(coarse, fine, ratio: float, order: float):
    """Richardson extrapolation ``fine + (fine − coarse) / (ratio^order − 1)`` (elementwise)."""
    coarse, fine = np.asarray(coarse, dtype=float), np.asarray(fine, dtype=float)
    return fine + (fine - coarse) / (ratio**order - 1.0)


def max_relative_deviation(values, reference) -> float:
    """Largest |values − reference| / |reference| over the entries (C and q arrays)."""
    values, reference = np.asarray(values, dtype=float), np.asarray(reference, dtype=float)
    scale = np.abs(reference)
    ok = scale > 0
    return float(np.max(np.abs(values - reference)[ok] / scale[ok]))


def cheapest(rows: Iterable[Row], target: float, *, key: Callable[[Row], float] | None = None):
    """The row of least wall time whose error is at most ``target`` (None if none)."""
    key = key or (lambda r: r.error)
    good = [r for r in rows if math.isfinite(key(r)) and key(r) <= target]
    return min(good, key=lambda r: r.wall_time_s) if good else None


def solves_needed(count: int, symmetric: bool = True) -> int:
    """Field solves for a Lobatto set of ``count`` positions (mirror symmetry halves it)."""
    return (count + 1) // 2 if symmetric else count
