"""The device as a SPICE subcircuit (issue #39): ``tengfield run ... --spice`` and
:func:`export` write ``teng.lib``, a subcircuit ``teng`` with two pins for ngspice and
LTspice, so a user's own circuit (a converter, a PMIC, a multiplier) runs on the device a
run computed.

The model is the standard one of a TENG (Niu et al. 2013): between its pins

    V(p, n) = V_OC(t) - Q(t) / C_T(t),      Q(t) = ∫ i dt,

with ``i`` the current leaving pin ``p`` into the external circuit (and returning into
``n``), ``V_OC`` = Q_SC / C_T and ``C_T`` the run's own (``waveforms.csv``: ``V_oc_V``,
``C_T_F``, cells in parallel), given as piecewise-linear tables over the run's time
(from its start, when the ball rests in the reference state: Q = 0 and V_OC = 0). It is
the terminal law tengfield's circuits integrate, ``V = (Q_SC - Q) / C_T``.

A capacitor whose value changes in time is not an element both simulators share, so
the subcircuit states it with elements both accept:

* ``Vvoc`` and ``Vct``: PWL voltage sources holding V_OC(t) [V] and C_T(t) [pF];
* ``Vsense``: a 0 V source in series with the pins, measuring ``i``;
* ``Bq`` + ``Cq``: the transferred charge Q, integrated on a 1 nF capacitor (V(q) = Q in
  nC; ``Rq`` a 1e18 ohm path to ground for the DC operating point);
* ``Bv``: the behavioural voltage source V_OC - Q / C_T = V(voc) - 1e3 V(q) / V(ct).

Time-varying values go in as data, so the simulator's own time step only needs to honour
the table's breakpoints (both do, for PWL sources). The pins are ``p`` = the lower
electrode and ``n`` = the upper one (tengfield's V = V_lower - V_upper).

``examples/teng_load.cir`` is a top-level netlist with a resistor load
(``ngspice -b teng_load.cir`` from examples/).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

#: the subcircuit's name and pins
SUBCIRCUIT = "teng"
PINS = ("p", "n")
#: PWL points per line of the netlist
POINTS_PER_LINE = 4


def tables(result) -> dict[str, np.ndarray]:
    """``{"time_s", "V_oc_V", "C_T_F"}`` of a run (a :class:`tengfield.pipeline.RunResult`
    or its ``waveforms``), the run's time from its first sample [s]."""
    waveforms = getattr(result, "waveforms", result)
    t = np.asarray(waveforms["time_s"], dtype=float)
    v = np.asarray(waveforms["V_oc_V"], dtype=float)
    if "C_T_F" not in waveforms:
        raise ValueError("the run has no C_T_F column (a run of this tengfield has one)")
    c = np.asarray(waveforms["C_T_F"], dtype=float)
    if not np.all(np.isfinite(c)) or np.any(c <= 0):
        raise ValueError("C_T_F is not finite and positive (an uncharged ball: Q_SC = 0 "
                         "everywhere): nothing to export")
    out = {"time_s": t - t[0], "V_oc_V": v, "C_T_F": c}
    return _with_impacts(result, out)


def _with_impacts(result, out: dict) -> dict:
    """``out`` with a point at every impact (where V_OC's slope jumps: I_SC jumps), so the
    table's straight lines do not cut the corners the output samples straddle."""
    scene = getattr(result, "scene", None)
    dynamics = getattr(result, "dynamics", None)
    curves = getattr(result, "curves", None)
    if (scene is None or dynamics is None or curves is None or getattr(curves, "radial", False)
            or scene.array.cells > 0):      # an array's cells have their own impacts
        return out
    from . import electrical
    t = out["time_s"]
    impacts = electrical.impact_elapsed(dynamics, float(t[0]), float(t[-1]))
    impacts = impacts[(impacts > t[0]) & (impacts < t[-1])]
    if not impacts.size:
        return out
    _, _, gap, velocity = electrical.impact_states(scene, dynamics,
                                                   impacts + electrical.time_origin(dynamics))
    at = electrical.scene_terminal_waveforms(scene, curves, gap, velocity)
    times = np.concatenate([t, impacts])
    order = np.argsort(times, kind="stable")
    keep = np.r_[True, np.diff(times[order]) > 0]
    idx = order[keep]
    return {"time_s": times[idx],
            "V_oc_V": np.concatenate([out["V_oc_V"], at["V_oc"]])[idx],
            "C_T_F": np.concatenate([out["C_T_F"], at["C_T"]])[idx]}


def _pwl(name: str, node: str, t, values, scale: float = 1.0) -> list[str]:
    pairs = [f"{ti:.12g} {vi * scale:.10g}" for ti, vi in zip(t, values)]
    lines = [f"{name} {node} 0 PWL("]
    for i in range(0, len(pairs), POINTS_PER_LINE):
        lines.append("+ " + " ".join(pairs[i:i + POINTS_PER_LINE]))
    lines.append("+ )")
    return lines


def subcircuit(result, *, title: str = "") -> str:
    """The text of ``teng.lib`` for ``result`` (see the module docstring)."""
    tab = tables(result)
    t = tab["time_s"]
    head = [f"* tengfield SPICE model of a TENG{': ' + title if title else ''}",
            "* V(p,n) = V_OC(t) - Q/C_T(t), Q = integral of the current out of pin p",
            f"* {t.size} points, t = 0 .. {t[-1]:.6g} s; p = lower electrode, n = upper",
            "* usage: .include teng.lib  then  X1 a b teng",
            f".subckt {SUBCIRCUIT} {' '.join(PINS)}"]
    body = _pwl("Vvoc", "voc", t, tab["V_oc_V"])
    body += _pwl("Vct", "ct", t, tab["C_T_F"], 1e12)          # C_T in pF
    body += ["Vsense x n 0",
             "Bq 0 q I=-I(Vsense)",                             # i into q: V(q) = Q / 1 nF
             "Cq q 0 1n",
             "Rq q 0 1e18",
             "Bv p x V=V(voc)-1e3*V(q)/V(ct)",
             f".ends {SUBCIRCUIT}"]
    return "\n".join(head + body) + "\n"


def export(result, path) -> Path:
    """Write the subcircuit ``teng`` of ``result`` to ``path`` (``teng.lib``); returns it."""
    from .files import write_text

    path = Path(path)
    write_text(path, subcircuit(result, title=str(getattr(getattr(result, "scene", None),
                                                          "source", "") or "")))
    return path


def load_netlist(load_ohm: float, stop_s: float, step_s: float, *, library: str = "teng.lib",
                 output: str = "teng_load.csv") -> str:
    """A top-level netlist: the device on a resistor ``load_ohm``, a transient to ``stop_s``
    with steps of at most ``step_s``, V(out) written to ``output`` (ngspice's
    ``wrdata``: time, value columns)."""
    return "\n".join([
        "* tengfield: the TENG on a resistor load (ngspice -b teng_load.cir)",
        f".include {library}",
        "X1 out 0 teng",
        f"Rload out 0 {load_ohm:.6g}",
        f".tran {step_s:.6g} {stop_s:.6g} 0 {step_s:.6g}",
        ".control",
        "run",
        f"wrdata {output} v(out)",
        "quit 0",             # ngspice -b ends a .control block with status 1 without it
        ".endc",
        ".end", ""])
