"""The one table of output quantities: name, unit, label, how each is computed.

Every place that shows an output takes its name and unit from here:
``summary.json`` keys (``peak_to_peak.Q_sc_C``, ``peak.I_sc_A``,
``load.mean_power_W``), the terminal summary of ``tengfield run``, the columns of
``waveforms.csv``, ``sweep.csv`` and ``ensemble.csv``, the axis labels of the
figures and the ``[reference]`` comparison with measured values.

* :data:`QUANTITIES`: ``name -> Quantity`` (``QUANTITIES["V_oc_V"].unit == "V"``,
  ``.label == "open-circuit voltage V_OC"``);
* :data:`STATISTICS`: how a waveform becomes one number (``peak`` = max |x|,
  ``peak_to_peak`` = max x - min x, over the steady window's samples and just
  before and after every impact: :func:`tengfield.electrical.terminal_extremes`);
* :func:`summary_keys` (``"peak_to_peak.Q_sc_C"``, ...), :func:`summary_value`
  (the number of such a key in a summary dict), :func:`column_name` (the
  ``sweep.csv`` / ``ensemble.csv`` column: ``V_oc_pp_V``, ``I_sc_peak_A``),
  :func:`axis_label` (``"V_OC [V]"``, ``"Q_SC [nC]"``).

A new output quantity is one :class:`Quantity` entry here plus its computation
(a waveform column in :mod:`tengfield.electrical`, or a number in a summary
block); docs/architecture.md has the recipe. This module is base layer: it
imports nothing of tengfield.
"""
from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Quantity:
    """One output quantity. ``name``: its key and CSV column, SI unit suffixed
    (``V_oc_V``); ``unit``: the SI unit; ``symbol``: the short name printed and
    drawn (``V_OC``); ``label``: words for a person; ``computed``: how it is
    obtained; ``display_unit``/``display_scale``: what the terminal and the figures
    show (``Q_SC`` in nC: ``display_scale`` 1e9); ``waveform``: a column of
    ``waveforms.csv`` (True) or a number of a summary block (False);
    ``block``: the summary block of such a number (``load``, ``rectifier``,
    ``energy_per_cycle``); ``when``: when it is present (empty: always)."""
    name: str
    unit: str
    symbol: str
    label: str
    computed: str
    display_unit: str = ""
    display_scale: float = 1.0
    waveform: bool = True
    block: str = ""
    when: str = ""

    @property
    def short(self) -> str:
        """The name without its unit suffix (``V_oc`` of ``V_oc_V``)."""
        return self.name[: -(len(self.unit.replace("/", "_per_")) + 1)] \
            if self.name.endswith("_" + self.unit.replace("/", "_per_")) else self.name


def _q(name, unit, symbol, label, computed, display_unit="", display_scale=1.0, **kw):
    return name, Quantity(name, unit, symbol, label, computed, display_unit or unit,
                          display_scale, **kw)


#: every output quantity, by name
QUANTITIES: dict[str, Quantity] = dict([
    _q("time_s", "s", "t", "time", "the output samples, [run] sample_rate_hz"),
    _q("gap_m", "m", "z", "ball-electrode gap z", "the dynamics", "mm", 1e3),
    _q("gap_velocity_m_per_s", "m/s", "dz/dt", "gap velocity", "the dynamics"),
    _q("table_m", "m", "table", "table displacement", "the excitation", "mm", 1e3),
    _q("V_oc_V", "V", "V_OC", "open-circuit voltage V_OC",
       "Q_SC / C_T: the ideal open-circuit voltage (no instrument), cells in parallel"),
    _q("Q_sc_C", "C", "Q_SC", "short-circuit charge Q_SC",
       "Q_SC(z) of the surrogate x cells, zero in the reference state", "nC", 1e9),
    _q("I_sc_A", "A", "I_SC", "short-circuit current I_SC",
       "dQ_SC/dz dz/dt (+ dQ_SC/dr dr/dt off the axis), cells in parallel", "nA", 1e9),
    _q("V_read_V", "V", "V_read", "voltage read through C_p",
       "what an instrument of capacitance C_p reads: Q_SC / (C_T + C_p); with "
       "[circuit] kind = \"load\" the voltage across R || C_p (= V_load_V)",
       when="[instrument] (or [circuit] parallel_capacitance_pF > 0)"),
    _q("Q_read_C", "C", "Q_read", "charge read by the instrument",
       "Q_SC through [instrument]'s bandwidth, aperture and sample rate (charge mode: a "
       "virtual-ground input)", "nC", 1e9, when="[instrument]"),
    _q("I_read_A", "A", "I_read", "current read by the instrument",
       "I_SC through [instrument]'s bandwidth, aperture and sample rate (ammeter: a "
       "virtual-ground input)", "nA", 1e9, when="[instrument]"),
    _q("C_T_F", "F", "C_T", "device capacitance C_T",
       "C_T(z) of the surrogate x cells (V = V_OC - Q / C_T; the SPICE model's table)",
       "pF", 1e12),
    _q("q_ball_C", "C", "q_ball", "ball charge q",
       "the charge the contacts make (Hertz area x the condenser law, leakage, the "
       "air-breakdown cap), after a contact at its instant", "nC", 1e9,
       when="[charge] model = \"contact\""),
    _q("V_load_V", "V", "V_load", "load voltage", "the load ODE, R || C_p",
       when="[circuit] kind = \"load\" or \"series-rc\""),
    _q("I_load_A", "A", "I_load", "load current", "V_load / R", "nA", 1e9,
       when="[circuit] kind = \"load\" or \"series-rc\""),
    _q("P_load_W", "W", "P_load", "load power", "V_load^2 / R", "µW", 1e6,
       when="[circuit] kind = \"load\" or \"series-rc\""),
    _q("mean_power_W", "W", "P_mean", "mean load power",
       "energy dissipated in R over the steady window / its length", "µW", 1e6,
       waveform=False, block="load", when="a load"),
    _q("power_density_W_per_m3", "W/m^3", "P/V", "mean power per device volume",
       "mean_power_W / the cells' volume", waveform=False, block="load", when="a load"),
    _q("average_harvested_power_W", "W", "P_harvest", "power into the store",
       "energy into the store over the steady window / its length", "µW", 1e6,
       waveform=False, block="rectifier", when="[circuit] kind = \"rectifier\""),
    _q("final_stored_energy_J", "J", "E_store", "energy in the store at the end",
       "C_store U^2 / 2 at the last instant", waveform=False, block="rectifier",
       when="[circuit] kind = \"rectifier\""),
    _q("max_energy_per_cycle_J", "J", "E_CMEO", "CMEO energy per cycle (the device's own)",
       "Q_max (V_OC,max + |V'_max|) / 2 without the instrument (Zi et al. 2015)",
       waveform=False, block="energy_per_cycle"),
    _q("figure_of_merit_structural", "1", "FOM_S", "structural figure of merit",
       "2 eps0 E_CMEO / (sigma^2 A x_max), the device's own (no C_p)",
       waveform=False, block="energy_per_cycle"),
])

#: how a waveform becomes one number: summary block -> (words, CSV column infix)
STATISTICS: dict[str, tuple[str, str]] = {
    "peak_to_peak": ("max x - min x over the steady window's samples and just before and "
                     "after every impact", "pp"),
    "peak": ("max |x| over the same instants as peak_to_peak", "peak"),
}

#: the terminal quantities every run reports with both statistics
TERMINAL = ("V_oc_V", "Q_sc_C", "I_sc_A")


#: the scene key of the ball's surface charge density σ in [device] (µC/m², or the keyword
#: "breakdown"); code names the quantity ``surface_charge`` [C/m²]. Its one spelling in src
#: (tests/scene/test_surface_charge_key.py), here in the base layer so that this table and
#: the scene's schema (:data:`tengfield.scene.schema.SURFACE_CHARGE_KEY`) share it.
SURFACE_CHARGE_KEY = "surface_charge_uC_per_m2"


def stated_surface_charge(scene):
    """``[device]`` :data:`SURFACE_CHARGE_KEY` as the scene states it (``scene.raw``, file
    units): a number [µC/m²], the keyword ``"breakdown"``, or None when it is left to the
    default. The one place that reads the key off a scene (its SI value is
    ``scene.device.surface_charge`` [C/m²])."""
    raw = getattr(scene, "raw", None) if isinstance(getattr(scene, "raw", None), dict) else {}
    device = raw.get("device")
    return device.get(SURFACE_CHARGE_KEY) if isinstance(device, dict) else None


#: scene/fit parameter key (its section's prefix, ``device.``, dropped) -> (symbol, shown
#: unit, words for a unitless one). Figures label a scene key with these (issue #42).
SCENE_SYMBOLS: dict[str, tuple[str, str, str]] = {
    SURFACE_CHARGE_KEY: ("σ", "µC/m²", ""),
    "stroke_mm": ("Δh", "mm", ""),
    "gap_mm": ("Δh", "mm", ""),
    "ball_diameter_mm": ("d", "mm", ""),
    "electrode_radius_mm": ("r_e", "mm", ""),
    "ball_density_kg_per_m3": ("ρ", "kg/m³", ""),
    "restitution": ("e", "", "restitution"),
    "parallel_capacitance_pF": ("C_p", "pF", ""),
    "capacitance_pF": ("C_p", "pF", ""),
    "load_ohm": ("R", "Ω", ""),
    "frequency_hz": ("f", "Hz", ""),
    "amplitude_mm": ("A", "mm", ""),
    "time_shift_s": ("t_0", "s", ""),
    "amplitude_scale": ("A/A_scene", "", "amplitude scale"),
    "duration_s": ("T_run", "s", ""),
}


def scene_symbol(key: str) -> tuple[str, str, str] | None:
    """(symbol, unit, words) of scene key ``key`` (``"device.restitution"`` or
    ``"restitution"``), None when the table has none."""
    return SCENE_SYMBOLS.get(key.rpartition(".")[2])


def scene_label(key: str) -> str:
    """An axis label of scene key ``key``: ``"σ [µC/m²]"``, ``"e (restitution)"``; a key
    the table lacks: its name with underscores as spaces."""
    entry = scene_symbol(key)
    if entry is None:
        return key.rpartition(".")[2].replace("_", " ")
    symbol, unit, words = entry
    return f"{symbol} [{unit}]" if unit else f"{symbol} ({words})" if words else symbol


def scene_value_text(key: str, value: float, digits: int = 3) -> str:
    """``"σ = −35.8 µC/m²"``: scene key ``key`` at ``value`` (its file unit), typographic
    minus; a key the table lacks: ``"name = value"``."""
    number = f"{value:.{digits}g}".replace("-", "\u2212")
    entry = scene_symbol(key)
    if entry is None:
        return f"{key.rpartition('.')[2]} = {number}"
    symbol, unit, _ = entry
    return f"{symbol} = {number}" + (f" {unit}" if unit else "")


def quantity(name: str) -> Quantity:
    """The entry of ``name`` (KeyError naming the known ones)."""
    try:
        return QUANTITIES[name]
    except KeyError:
        raise KeyError(f"unknown output quantity {name!r}; known: "
                       + ", ".join(QUANTITIES)) from None


def summary_keys(*, instrument: bool = False) -> list[str]:
    """The dotted summary.json keys of the numbers a run reports: ``peak_to_peak.<name>``
    and ``peak.<name>`` of the terminal quantities (and ``V_read_V`` with an
    ``instrument``, C_p > 0), then the block numbers (``load.mean_power_W``, ...)."""
    names = list(TERMINAL) + (["V_read_V"] if instrument else [])
    keys = [f"{stat}.{n}" for stat in STATISTICS for n in names]
    keys += [f"{q.block}.{q.name}" for q in QUANTITIES.values() if not q.waveform]
    return keys


def summary_value(summary: dict, key: str):
    """The number at dotted ``key`` of a summary dict (``"peak.I_sc_A"``), or None when
    the run has no such number (no load, no instrument)."""
    node = summary
    for part in key.split("."):
        if not isinstance(node, dict) or node.get(part) is None:
            return None
        node = node[part]
    return node


def column_name(name: str, statistic: str) -> str:
    """The ``sweep.csv`` / ``ensemble.csv`` column of ``statistic`` of quantity ``name``:
    ``column_name("V_oc_V", "peak_to_peak") == "V_oc_pp_V"``."""
    q = quantity(name)
    suffix = name[len(q.short):]
    return f"{q.short}_{STATISTICS[statistic][1]}{suffix}"


_POWERS = {"^2": "²", "^3": "³", "^-1": "⁻¹", "^-2": "⁻²", "^-3": "⁻³"}


def figure_unit(unit: str) -> str:
    """A unit as a figure writes it: the terminal's carets as superscripts
    (``"µW/cm^3"`` -> ``"µW/cm³"``, ``"W/m^3"`` -> ``"W/m³"``); the terminal keeps ^."""
    for caret, superscript in sorted(_POWERS.items(), key=lambda kv: -len(kv[0])):
        unit = unit.replace(caret, superscript)
    return unit


def axis_label(name: str, *, statistic: str = "") -> str:
    """A figure's axis label: ``"Q_SC [nC]"`` (``statistic``: ``"Q_SC peak-to-peak [nC]"``),
    the unit in figure style (:func:`figure_unit`: ``"P/V [W/m³]"``)."""
    q = quantity(name)
    words = {"peak_to_peak": " peak-to-peak", "peak": " peak"}.get(statistic, "")
    return f"{q.symbol}{words} [{figure_unit(q.display_unit)}]"


def display(name: str, value) -> str:
    """``value`` [SI] of ``name`` as the terminal prints it: ``"0.3174 nC"``."""
    q = quantity(name)
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "n/a"
    return f"{value * q.display_scale:.4g} {q.display_unit}"


def describe(key: str, *, unit: bool = True) -> str:
    """Words for a dotted summary key: ``"peak.I_sc_A"`` -> ``"short-circuit current
    I_SC, peak [A]"`` (without ``[A]`` when not ``unit``)."""
    stat, _, name = key.rpartition(".")
    q = quantity(name)
    words = {"peak_to_peak": ", peak-to-peak", "peak": ", peak"}.get(stat, "")
    return f"{q.label}{words}" + (f" [{q.unit}]" if unit else "")


# ---------------------------------------------------------------------------
# measured values ([reference], tengfield run --reference)

#: ``[reference]`` key -> (statistic, tool quantity, the measured unit, its SI factor).
#: A measured voltage is compared with what the instrument reads: ``V_read_V`` when the
#: run has one (``[circuit] parallel_capacitance_pF`` > 0), else the ideal ``V_oc_V``.
MEASURED: dict[str, tuple[str, str, str, float]] = {
    "V_pp_V": ("peak_to_peak", "V_read_V", "V", 1.0),
    "V_peak_V": ("peak", "V_read_V", "V", 1.0),
    "Q_pp_nC": ("peak_to_peak", "Q_sc_C", "nC", 1e-9),
    "Q_peak_nC": ("peak", "Q_sc_C", "nC", 1e-9),
    "I_pp_uA": ("peak_to_peak", "I_sc_A", "uA", 1e-6),
    "I_peak_uA": ("peak", "I_sc_A", "uA", 1e-6),
    "P_mean_uW": ("load", "mean_power_W", "uW", 1e-6),
}


#: the quantity an ``[instrument]`` records in place of a terminal one
READ_OF = {"Q_sc_C": "Q_read_C", "I_sc_A": "I_read_A"}


def tool_key(measured_key: str, summary: dict) -> str:
    """The dotted summary key a ``[reference]`` value is compared with in ``summary``
    (``"I_peak_uA"`` -> ``"peak.I_sc_A"``, ``"peak.I_read_A"`` with an ``[instrument]``;
    a voltage -> ``V_read_V`` with an instrument, ``V_oc_V`` without: a fit's model V)."""
    stat, name, _, _ = MEASURED[measured_key]
    if name == "V_read_V" and "V_read_V" not in (summary.get(stat) or {}):
        name = "V_oc_V"
    if READ_OF.get(name) in (summary.get(stat) or {}):
        name = READ_OF[name]
    return f"{stat}.{name}"


def reference_key(measured_key: str, summary: dict) -> tuple[str | None, str]:
    """The dotted summary key a bench's ``[reference]`` value is compared with, and why
    (None: nothing of the run can be compared). A measured voltage is what the instrument
    reads (``V_read_V``); with a load and no instrument, the load's voltage (what a meter
    across it reads: ``load.V_load_peak_to_peak_V``); with neither, nothing: the ideal
    V_OC of an unloaded cell is kilovolts, no bench reads it (give ``[instrument]
    capacitance_pF``). A charge or current: the read one with an ``[instrument]``."""
    stat, name, _, _ = MEASURED[measured_key]
    if name != "V_read_V" or "V_read_V" in (summary.get(stat) or {}):
        key = tool_key(measured_key, summary)
        read = key.rpartition(".")[2] in READ_OF.values() or key.endswith("V_read_V")
        return key, ("what the instrument records" if read else "the terminal's own")
    if stat == "peak_to_peak" and summary_value(summary, "load.V_load_peak_to_peak_V") is not None:
        return "load.V_load_peak_to_peak_V", "the load's voltage (what a meter across it reads)"
    if summary_value(summary, "load.V_load_peak_to_peak_V") is not None:
        return None, ("not compared: of the load's voltage the run reports the peak-to-peak "
                      "(give V_pp_V), or give [instrument] capacitance_pF for V_read_V")
    return None, ("not compared: a bench's voltage needs the instrument's capacitance "
                  "([instrument] capacitance_pF; the ideal V_OC is what no instrument reads)")


def parse_measured(items) -> dict[str, float]:
    """``["V_pp_V=4.2", "Q_pp_nC=1.42"]`` (``tengfield run --reference``) -> file-level
    ``{"V_pp_V": 4.2, ...}``; ValueError (one line) for an item without ``=``, an
    unknown key (with the closest) or a value that is not a number. The values are
    checked as ``[reference]`` keys by the scene."""
    import difflib

    out: dict[str, float] = {}
    for item in items:
        key, sep, text = str(item).partition("=")
        key = key.strip()
        if not sep:
            raise ValueError(f"--reference {item!r}: expected KEY=VALUE, e.g. V_pp_V=4.2")
        if key not in MEASURED:
            close = difflib.get_close_matches(key, list(MEASURED), n=1, cutoff=0.6)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise ValueError(f"--reference {key} is not a measured quantity{hint}; known: "
                             + ", ".join(MEASURED))
        if key in out:
            raise ValueError(f"--reference {key} is given twice ({out[key]:g} and "
                             f"{text.strip()}): allowed once")
        try:
            value = float(text)
        except ValueError:
            raise ValueError(f"--reference {key} = {text!r}: expected a number") from None
        unit = MEASURED[key][2]
        if not MIN_MEASURED <= value <= MAX_MEASURED:   # NaN too; 0 would mean "not given"
            raise ValueError(f"--reference {key} = {text.strip()} is out of range: allowed "
                             f"[{MIN_MEASURED:g}, {MAX_MEASURED:g}] {unit} (a measured "
                             "magnitude; leave a key out that was not measured)")
        out[key] = value
    return out


#: a measured magnitude ``--reference`` accepts, in its key's unit (V, nC, uA, uW): below
#: 1e-12 of the unit no instrument reads, and the difference in % would be meaningless
MIN_MEASURED = 1e-12
MAX_MEASURED = 1e30


def percent_text(percent: float | None) -> str:
    """A difference in % as the terminal shows it: ``+12.3 %``, ``+1.2e+06 %`` when large."""
    if percent is None or not math.isfinite(percent):
        return "n/a"
    return f"{percent:+.1f} %" if abs(percent) < 1e4 else f"{percent:+.3g} %"


def compare_measured(summary: dict, measured: dict[str, float]) -> dict | None:
    """summary.json's ``measured_comparison`` block: for each measured value
    (``{[reference] key: value [SI]}``, e.g. ``scene.reference.given()``) the tool's
    value, the measured one (both in the measured unit), the difference (tool -
    measured) / measured in %, and which tool quantity it is compared with. None
    without measured values."""
    if not measured:
        return None
    rows = {}
    for key, value in measured.items():
        _, _, unit, factor = MEASURED[key]
        dotted, why = reference_key(key, summary)
        tool = None if dotted is None else summary_value(summary, dotted)
        rows[key] = {
            "measured_value": value / factor, "unit": unit,
            "tool_value": None if tool is None else tool / factor,
            "difference_percent": (None if tool is None
                                   else 100.0 * (tool - value) / value),
            "tool_key": dotted, "tool_label": (why if dotted is None else describe(
                dotted.replace("load.V_load_peak_to_peak_V", "peak_to_peak.V_load_V"),
                unit=False)),
            "compared_with": why}
    return {"quantities": rows,
            "rule": "difference_percent = 100 (tool - measured) / measured; a measured "
                    "voltage is compared with the voltage the instrument reads (V_read_V, "
                    "[instrument] capacitance_pF > 0), with a load's voltage without one, "
                    "else with nothing; with an [instrument] a charge or current with the "
                    "read one (Q_read_C, I_read_A)"}


#: the outputs of a study whose contacts make the charge (``[charge] model = "contact"``:
#: the summary's ``charge`` block) as the terminal and the figures name them (the values
#: are shown in these units: the block's own)
CHARGE_LABELS = {"charge.steady_uC_per_m2": "steady ball charge σ [µC/m²]",
                 "charge.rise_time_90_s": "rise time to 90 % of it [s]"}
