"""Which quantity of the tool a fit compares each measured value with, named by the one
table of output quantities (:mod:`tengfield.quantities`: ``MEASURED``, ``tool_key``,
``describe``; issue #28).

A fit compares V, Q and I. Q is the short-circuit charge ``Q_sc_C``; I the
short-circuit current ``I_sc_A``; V what an instrument of capacitance C_p reads,
``V_read_V`` (C_p > 0) or the ideal ``V_oc_V`` (C_p = 0): the rule of
``[reference]``'s comparison (:func:`tengfield.quantities.tool_key`). With
``[circuit] kind = "load"`` V and I are the load's (``V_load_V``, ``I_load_A``:
the circuit entry's ``fit_columns``).

* :data:`MEASURED_KEYS`: ``(letter, statistic) -> [reference] key`` (``("V",
  "peak_to_peak") -> "V_pp_V"``), from ``MEASURED``;
* :data:`INFIXES`: a target name's infix -> its statistic (``"pp" ->
  "peak_to_peak"``), from ``STATISTICS``;
* :func:`compared_key`: the dotted key of the tool quantity (``peak_to_peak.V_read_V``);
* :func:`compared`: that key, its words and unit, as fit.json writes them;
* :func:`model_columns`: the column of a run's waveforms table (CSV or run.h5) that holds
  what the model compares, which a measured trace without ``[fit.columns]`` is read from.
"""
from __future__ import annotations

from ..electrical import circuit_for
from ..electrical.instrument import as_terminal
from ..quantities import MEASURED, STATISTICS, describe, quantity, tool_key


def _letter(name: str) -> str:
    """V, Q or I: the first letter of the quantity's symbol (``V_read`` -> ``V``)."""
    return quantity(name).symbol[0]


#: (V|Q|I, statistic) -> the [reference] key it is measured as (MEASURED's own)
MEASURED_KEYS: dict[tuple[str, str], str] = {
    (_letter(name), stat): key for key, (stat, name, _, _) in MEASURED.items()
    if stat in STATISTICS}
#: a scalar target's infix (``V_pp_V``: ``pp``) -> its statistic
INFIXES: dict[str, str] = {infix: stat for stat, (_, infix) in STATISTICS.items()}
#: the letters a fit compares
LETTERS: tuple[str, ...] = tuple(dict.fromkeys(letter for letter, _ in MEASURED_KEYS))


def compared_key(letter: str, statistic: str, scene, parallel_capacitance: float) -> str:
    """The dotted key of the tool quantity a measured ``letter`` (V, Q, I) is compared with
    (``statistic``: ``peak_to_peak``/``peak``; empty for a waveform: the bare name).
    ``parallel_capacitance`` [F] is the fit's C_p (fitted or the scene's)."""
    entry = circuit_for(scene)
    if entry.fit_load:
        name = entry.fit_columns[letter][0]
        return f"{statistic}.{name}" if statistic else name
    stat = statistic or "peak_to_peak"
    reads = {stat: {"V_read_V": True}} if parallel_capacitance > 0 else {}
    if scene.instrument.given:       # what the [instrument] records (issue #39)
        reads = {stat: {"V_read_V": True, "Q_read_C": True, "I_read_A": True}}
    key = tool_key(MEASURED_KEYS[(letter, stat)], reads)
    return key if statistic else key.rpartition(".")[2]


def compared(letter: str, statistic: str, scene, parallel_capacitance: float) -> dict:
    """``{"tool_key", "tool_label", "tool_unit"}`` of :func:`compared_key` (fit.json's
    names, as summary.json's ``measured_comparison``)."""
    key = compared_key(letter, statistic, scene, parallel_capacitance)
    name = key.rpartition(".")[2]
    return {"tool_key": key, "tool_label": describe(key, unit=False),
            "tool_unit": quantity(name).unit}


def model_columns(scene) -> dict[str, tuple[str, bool]]:
    """``{V|Q|I: (column, same)}``: the column of a tengfield run's waveforms (CSV or
    run.h5) holding what the model of ``scene`` compares (:func:`compared_key` at the
    scene's C_p: ``V_read_V``, ``Q_read_C``, ``I_read_A`` through an ``[instrument]``),
    and whether the circuit's own column (``fit_columns``: ``V_oc_V``, ``Q_sc_C``...)
    holds the same numbers (a quantity the instrument leaves as the terminal's,
    :func:`tengfield.electrical.instrument.as_terminal`: Q and I through C_p alone)."""
    entry = circuit_for(scene)
    same = as_terminal(scene)
    out = {}
    for letter, (own, _) in entry.fit_columns.items():
        column = compared_key(letter, "", scene, scene.circuit.parallel_capacitance)
        name = column.rpartition("_")[0]
        out[letter] = (column, column == own or same.get(name) == own.rpartition("_")[0])
    return out
