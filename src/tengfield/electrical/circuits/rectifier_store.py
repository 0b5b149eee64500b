"""The bridge rectifier's store and chip settings and checks (``[circuit] kind =
"rectifier"``), shared by the whole-record path (:mod:`.rectifier`) and the streamed one
(:mod:`.rectifier_stream`): the harvester's options from the scene, the smallest store the
output step resolves, the numerical-dissipation warning, the first crossing of a level."""
from __future__ import annotations

import math

import numpy as np


def harvester_options(scene) -> dict:
    """Keyword arguments of :class:`tengfield.harvest.Harvester` from ``[circuit]``
    (SI): diode, store, leakage (0 in the file: none), the UVLO chip (``pmic``)."""
    from ...harvest import Diode, PowerChip

    c = scene.circuit
    diode = Diode(model=c.diode, forward_voltage=c.diode_forward_voltage,
                  saturation_current=c.diode_saturation_current,
                  emission_coefficient=c.diode_emission_coefficient,
                  series_resistance=c.diode_series_resistance)
    chip = None
    if c.pmic == "uvlo":
        chip = PowerChip(uvlo_rising=c.uvlo_rising, uvlo_falling=c.uvlo_falling,
                         output_voltage=c.pmic_output, load=c.pmic_load,
                         efficiency=c.pmic_efficiency, quiescent_current=c.pmic_quiescent_current,
                         shunt_voltage=c.pmic_shunt)
    return {"storage_capacitance": c.storage_capacitance, "diode": diode,
            "parallel_capacitance": c.parallel_capacitance,
            "leakage": c.storage_leakage if c.storage_leakage > 0 else math.inf, "chip": chip}


#: numerical_dissipation_J above this fraction of the energy delivered into the bridges
#: gets a warning (the backward-Euler step moved the store too far per step)
NUMERICAL_DISSIPATION_WARN = 0.01


def smallest_resolved_store(scene) -> float:
    """Smallest ``[circuit] storage_capacitance_uF`` [F] whose chip bursts the output
    step resolves (0 without a chip): the energy between the UVLO levels,
    ``C_L (uvlo_rising^2 - uvlo_falling^2) / 2``, must last at least one step
    ``1 / sample_rate_hz`` at the chip's largest draw (input power + quiescent current
    at the shunt voltage). Below it a burst (the chip on, then locked out again) fits
    inside one step: the store is at 0 at every grid point while the books show shunt
    and chip energy, and the step's own dissipation is half of what is delivered."""
    c = scene.circuit
    if c.kind != "rectifier" or c.pmic != "uvlo":
        return 0.0
    step = 1.0 / scene.run.sample_rate
    draw = c.pmic_output**2 / (c.pmic_load * c.pmic_efficiency) \
        + c.pmic_quiescent_current * c.pmic_shunt
    return 2.0 * step * draw / (c.uvlo_rising**2 - c.uvlo_falling**2)


def check_store_resolution(scene) -> None:
    """One-line SceneError when the store is too small for the output step to resolve
    its chip (:func:`smallest_resolved_store`)."""
    from ...errors import SceneError

    smallest = smallest_resolved_store(scene)
    c = scene.circuit
    if c.storage_capacitance < smallest:
        raise SceneError(
            f"[circuit] storage_capacitance_uF = {c.storage_capacitance * 1e6:g} is out of "
            f"range: with pmic = 'uvlo' at [run] sample_rate_hz = {scene.run.sample_rate:g} "
            f"allowed >= {smallest * 1e6:.3g} (a chip burst, C_L (uvlo_rising_V^2 - "
            f"uvlo_falling_V^2)/2 of energy, must last at least one output step; or raise "
            f"[run] sample_rate_hz)")


def warn_numerical_dissipation(books: dict) -> None:
    """One ``tengfield: warning:`` line when the backward-Euler step's own dissipation
    (``numerical_dissipation_J`` of ``HarvestResult.balance()``, or the same keys summed
    over stores) exceeds ``NUMERICAL_DISSIPATION_WARN`` of the delivered energy."""
    import warnings

    delivered = books.get("delivered_J", 0.0)
    lost = books.get("numerical_dissipation_J", 0.0)
    if delivered > 0 and lost > NUMERICAL_DISSIPATION_WARN * delivered:
        warnings.warn(
            f"rectifier: numerical_dissipation_J = {lost:.3g} J is {lost / delivered:.1%} of "
            f"the {delivered:.3g} J delivered into the bridges (> "
            f"{NUMERICAL_DISSIPATION_WARN:.0%}): the store moves too far per step; raise "
            f"[run] sample_rate_hz or [circuit] storage_capacitance_uF", RuntimeWarning,
            stacklevel=3)


def first_crossing(times, values, level: float) -> float:
    """First time [s] ``values`` reach ``level`` (linear between samples); NaN if never."""
    v = np.asarray(values, dtype=float)
    hit = np.flatnonzero(v >= level)
    if hit.size == 0:
        return math.nan
    k = int(hit[0])
    if k == 0:
        return float(times[0])
    v0, v1 = v[k - 1], v[k]
    return float(times[k - 1] + (level - v0) / (v1 - v0) * (times[k] - times[k - 1]))
