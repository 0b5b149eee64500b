"""The device as a SPICE subcircuit (issue #39): ``tengfield run ... --spice`` and
:func:`export` write ``teng.lib``, a subcircuit ``teng`` with two pins for ngspice (its
PWL repeat ``r=``; LTspice spells a repeat ``PWL REPEAT FOREVER (...) ENDREPEAT``), so a
user's own circuit (a converter, a PMIC, a multiplier) runs on the device a run computed.

The model is the standard one of a TENG (Niu et al. 2013): between its pins

    V(p, n) = V_OC(t) - Q(t) / C_T(t),      Q(t) = ∫ i dt,

with ``i`` the current leaving pin ``p`` into the external circuit (and returning into
``n``), ``V_OC`` = Q_SC / C_T and ``C_T`` the run's own (``waveforms.csv``: ``V_oc_V``,
``C_T_F``, cells in parallel), given as piecewise-linear tables. It is the terminal law
tengfield's circuits integrate, ``V = (Q_SC - Q) / C_T``.

The device is periodic (issue #53): the tables hold ONE steady period of the run (the
regime's period, k excitation periods; the last whole one of the steady window),
repeated for ever by the PWL sources' ``r=`` (ngspice's repeat point), so the file's
size does not grow with ``[run] duration_s`` and the device does not stop where the run
did. With ``start_up`` (``tengfield run --spice-start-up``) the tables first hold the
run's own start-up, t = 0 .. ``settle_periods`` excitation periods (the ball resting in
the reference state at t = 0: Q = 0, V_OC = 0), and the period repeats from there on:
a transient from t = 0 then reproduces the run. Without it, t = 0 is the start of the
steady period, at the same excitation phase as the run's t = 0. The rows are read from
the run a range at a time (a streamed run's :meth:`terminal_rows`): memory bounded by
the period and the start-up, not by the run (issue #54.10).

A capacitor whose value changes in time is not an element both simulators share, so
the subcircuit states it with elements both accept:

* ``Vvoc`` and ``Vct``: PWL voltage sources holding V_OC(t) [V] and C_T(t) [pF];
* ``Vsense``: a 0 V source in series with the pins, measuring ``i``;
* ``Bq`` + ``Cq``: the transferred charge Q, integrated on a 1 nF capacitor (V(q) = Q in
  nC; ``Rq`` a 1e18 ohm path to ground for the DC operating point);
* ``Bv``: the behavioural voltage source V_OC - Q / C_T = V(voc) - 1e3 V(q) / V(ct).

Time-varying values go in as data, so the simulator's own time step only needs to honour
the table's breakpoints (both do, for PWL sources). The header names the scene and its
``--set`` settings, escaped by :func:`tengfield.files.one_line` (a name cannot start a
live netlist line, issue #54.2). The pins are ``p`` = the lower
electrode and ``n`` = the upper one (tengfield's V = V_lower - V_upper).

``examples/teng_load.cir`` is a top-level netlist with a resistor load
(``ngspice -b teng_load.cir`` from examples/).
"""
from __future__ import annotations

import bisect
import math
from pathlib import Path

import numpy as np

from .errors import TengfieldError

#: the subcircuit's name and pins
SUBCIRCUIT = "teng"
PINS = ("p", "n")
#: PWL points per line of the netlist
POINTS_PER_LINE = 4
#: the simulator's tolerances teng.lib sets (``.options reltol trtol``; see subcircuit)
RELTOL = 1e-5
TRTOL = 1.0


class SpiceError(TengfieldError, ValueError):
    """The run cannot be exported as a SPICE device (one line, said before the work where
    the scene shows it: ``tengfield run --spice`` with sigma = 0)."""


def check_exportable(scene) -> None:
    """Refuse, before any work, a scene whose run cannot give a SPICE device: an uncharged
    ball (sigma = 0: Q_SC = 0 everywhere, so no field is solved and C_T(t) is unknown)."""
    from .scene.schema import SURFACE_CHARGE_KEY

    if scene.device.surface_charge == 0.0:
        raise SpiceError(f"--spice with [device] {SURFACE_CHARGE_KEY} = 0: an uncharged ball "
                         "gives V_OC = 0 and no field solve, so C_T(t) is unknown and there is "
                         "no device to export; give sigma != 0 (e.g. -8), or leave out --spice")


def steady_period(result) -> tuple[float, str]:
    """``(P [s], words)``: the period the device repeats, the regime's (k excitation
    periods) when it has one and the steady window holds it, else one excitation period
    (said: an approximation for a chaotic or unsettled motion or a drive that does not
    repeat each period, :func:`tengfield.dynamics.excitation.repeats_each_period`; the
    rest regime repeats trivially)."""
    scene = result.scene
    exc = scene.excitation
    period = exc.period
    regime = (getattr(result, "summary", None) or {}).get("regime") or {}
    name, k = regime.get("regime") or "?", int(regime.get("period") or 0)
    from .dynamics.excitation import repeats_each_period

    if not repeats_each_period(scene):
        return period, (f"the drive ([excitation] kind = {exc.kind!r}) does not repeat each "
                        "period: its last excitation period repeated, an approximation")
    if name == "rest":
        return period, "regime rest: one excitation period repeated"
    if name in ("chaos", "not-settled") or k < 1:
        return period, (f"regime {name} (aperiodic): the last excitation period repeated, an "
                        "approximation")
    return k * period, f"regime {name}, period {k}: {k} excitation period(s) repeated"


def tables(result, *, start_up: bool = False) -> dict:
    """The device's tables of a run (a :class:`tengfield.pipeline.RunResult`):
    ``{"time_s", "V_oc_V", "C_T_F"}`` (the table's time [s], from 0) and ``repeat_s`` (the
    table time the period repeats from, the PWL ``r=``), ``period_s``, ``taken_from_s``
    (the run's elapsed time the period was taken at), ``start_up_s`` (the start-up's
    length, 0 without), ``period_words`` and ``closing`` (|last - first| of V_OC [V] and
    C_T [F] over the period: the repeat joins them at the first values)."""
    scene = getattr(result, "scene", None)
    waveforms = getattr(result, "waveforms", None)
    if scene is None or waveforms is None:
        raise TypeError(f"spice: expected a run's result (tengfield.run), got "
                        f"{type(result).__name__}")
    source = getattr(waveforms, "source_of", None)     # a streamed run's own column
    t = source("time_s") if source is not None else waveforms["time_s"]
    rows = len(t)
    if "C_T_F" not in waveforms:
        raise SpiceError("the run has no C_T_F column (a run of this tengfield has one)")
    t0, t_end = float(t[0]), float(t[rows - 1]) - float(t[0])
    period, words = steady_period(result)
    settle = scene.run.settle_periods * scene.excitation.period
    if settle + period > t_end * (1 + 1e-12):
        period, words = scene.excitation.period, (
            f"{words}; the steady window ({t_end - settle:g} s) holds less than that: one "
            "excitation period repeated, an approximation")
        if settle + period > t_end * (1 + 1e-12):
            raise SpiceError(f"the run's steady window ({t_end - settle:g} s after "
                             f"settle_periods = {scene.run.settle_periods}) holds no whole "
                             f"excitation period ({period:g} s): raise [run] duration_s")
    whole = math.floor((t_end - settle) / period * (1 + 1e-12))
    taken = settle + (whole - 1) * period              # the last whole period, in phase
    times, v, c = _points(result, waveforms, t, t0, taken, taken + period)
    closing = (abs(float(v[-1] - v[0])), abs(float(c[-1] - c[0])))
    v[-1], c[-1] = v[0], c[0]                          # the repeat joins them
    origin = settle if start_up else 0.0
    times = times - taken + origin
    times[0], times[-1] = origin, origin + period
    if start_up and settle > 0:
        t_s, v_s, c_s = _points(result, waveforms, t, t0, 0.0, settle)
        times = np.concatenate([t_s[:-1], times])
        v, c = np.concatenate([v_s[:-1], v]), np.concatenate([c_s[:-1], c])
    # a row within round-off of the repeat point or the period's end would print as the
    # same time (non-increasing PWL points): the later point (the table's own) is kept
    printed = [_time(x) for x in times]
    keep = np.array([a != b for a, b in zip(printed[:-1], printed[1:])] + [True])
    times, v, c = times[keep], v[keep], c[keep]
    if not np.all(np.isfinite(c)) or np.any(c <= 0):
        raise SpiceError("--spice: the run has no C_T(t) (the ball never leaves the lower "
                         "plate, or is uncharged: no field was solved), so there is no device "
                         "to export; leave out --spice, or drive the ball off the plate "
                         "([excitation] amplitude_mm, frequency_hz)")
    return {"time_s": times, "V_oc_V": v, "C_T_F": c, "repeat_s": origin,
            "period_s": period, "taken_from_s": taken, "start_up_s": origin,
            "period_words": words, "closing": closing}


def _index(t, value: float, side: str) -> int:
    """The first row of the sorted time column ``t`` at or after (``"left"``) or after
    (``"right"``) ``value``; a column sampled on request is bisected a sample at a time."""
    if isinstance(t, np.ndarray):
        return int(np.searchsorted(t, value, side=side))
    return (bisect.bisect_left if side == "left" else bisect.bisect_right)(t, value)


def _rows(waveforms, i0: int, i1: int) -> dict:
    """time, V_OC and C_T of the rows ``i0:i1`` only."""
    if hasattr(waveforms, "terminal_rows"):            # a streamed run: those rows alone
        return waveforms.terminal_rows(i0, i1)
    return {k: np.asarray(waveforms[k][i0:i1], dtype=float)
            for k in ("time_s", "V_oc_V", "C_T_F")}


def _points(result, waveforms, t, t0: float, lo: float, hi: float):
    """``(times, V_OC, C_T)`` from ``lo`` to ``hi`` [s of the run's elapsed time]: the
    rows strictly inside, a point at every impact there and the values at ``lo`` and
    ``hi`` themselves (straight lines between the neighbouring points)."""
    i0 = max(_index(t, t0 + lo, "right") - 1, 0)
    i1 = min(_index(t, t0 + hi, "left") + 1, len(t))
    rows = _rows(waveforms, i0, i1)
    out = _with_impacts(result, {"time_s": rows["time_s"] - t0, "V_oc_V": rows["V_oc_V"],
                                 "C_T_F": rows["C_T_F"]})
    times, v, c = out["time_s"], out["V_oc_V"], out["C_T_F"]
    inside = (times > lo) & (times < hi)

    def along(values):
        return np.concatenate([[np.interp(lo, times, values)], values[inside],
                               [np.interp(hi, times, values)]])
    return np.concatenate([[lo], times[inside], [hi]]), along(v), along(c)


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
    from .source import Source
    t = out["time_s"]
    impacts = electrical.impact_elapsed(dynamics, float(t[0]), float(t[-1]))
    impacts = impacts[(impacts > t[0]) & (impacts < t[-1])]
    if not impacts.size:
        return out
    _, _, gap, velocity = electrical.impact_states(scene, dynamics,
                                                   impacts + electrical.time_origin(dynamics))
    at = Source.of_scene(scene, curves, dynamics).terminal(impacts, gap, velocity)
    times = np.concatenate([t, impacts])
    order = np.argsort(times, kind="stable")
    keep = np.r_[True, np.diff(times[order]) > 0]
    idx = order[keep]
    return {"time_s": times[idx],
            "V_oc_V": np.concatenate([out["V_oc_V"], at["V_oc"]])[idx],
            "C_T_F": np.concatenate([out["C_T_F"], at["C_T"]])[idx]}


def _time(value: float) -> str:
    return f"{value:.12g}"


def _pwl(name: str, node: str, t, values, scale: float = 1.0, repeat: float = 0.0) -> list[str]:
    pairs = [f"{_time(ti)} {vi * scale:.10g}" for ti, vi in zip(t, values)]
    lines = [f"{name} {node} 0 PWL("]
    for i in range(0, len(pairs), POINTS_PER_LINE):
        lines.append("+ " + " ".join(pairs[i:i + POINTS_PER_LINE]))
    lines.append(f"+ ) r={_time(repeat)}")
    return lines


def header_lines(result, tab: dict) -> list[str]:
    """The netlist's comment lines: the scene and its ``--set`` settings (each escaped:
    :func:`tengfield.files.one_line`), the model, what repeats and from where."""
    from .files import comment_lines, one_line

    scene = result.scene
    t = tab["time_s"]
    dv, dc = tab["closing"]
    lines = ["tengfield SPICE model of a TENG",
             f"scene: {one_line(scene.source)}"]
    lines += [f"--set {one_line(s)}" for s in getattr(scene, "settings", ())]
    lines += ["V(p,n) = V_OC(t) - Q/C_T(t), Q = integral of the current out of pin p",
              f"periodic: {tab['period_words']}; the period {tab['period_s']:.9g} s (the run's "
              f"t = {tab['taken_from_s']:.9g} .. {tab['taken_from_s'] + tab['period_s']:.9g} s) "
              f"repeats for ever from t = {_time(tab['repeat_s'])} s (PWL r=, ngspice)",
              (f"start-up: t = 0 .. {tab['start_up_s']:.9g} s is the run's own start (Q = 0, "
               "V_OC = 0 at t = 0)" if tab["start_up_s"] > 0 else
               "no start-up (tengfield run --spice-start-up adds it): t = 0 is the start of "
               "the steady period, at the run's excitation phase of t = 0"),
              f"the period closes within {dv:.3g} V (V_OC) and {dc * 1e12:.3g} pF (C_T)",
              f"{t.size} points, t = 0 .. {t[-1]:.9g} s; p = lower electrode, n = upper",
              "usage: .include teng.lib  then  X1 a b teng"]
    return comment_lines("\n".join(lines), "* ")


def subcircuit(result, *, start_up: bool = False) -> str:
    """The text of ``teng.lib`` for ``result`` (see the module docstring)."""
    tab = tables(result, start_up=start_up)
    t, repeat = tab["time_s"], tab["repeat_s"]
    head = header_lines(result, tab) + [
        "* V_OC - Q/C_T cancels kV to the volts across the pins: at ngspice's default",
        "* tolerances (reltol 1e-3, trtol 7) the load voltage errs by tens of % once the",
        "* period repeats (its PWL repeats do not restart the step at the table's points);",
        f"* reltol {RELTOL:g} and trtol {TRTOL:g} keep it within 1 % (a later .options wins)",
        f".options reltol={RELTOL:g} trtol={TRTOL:g}",
        f".subckt {SUBCIRCUIT} {' '.join(PINS)}"]
    body = _pwl("Vvoc", "voc", t, tab["V_oc_V"], repeat=repeat)
    body += _pwl("Vct", "ct", t, tab["C_T_F"], 1e12, repeat=repeat)      # C_T in pF
    body += ["Vsense x n 0",
             "Bq 0 q I=-I(Vsense)",                             # i into q: V(q) = Q / 1 nF
             "Cq q 0 1n",
             "Rq q 0 1e18",
             "Bv p x V=V(voc)-1e3*V(q)/V(ct)",
             f".ends {SUBCIRCUIT}"]
    return "\n".join(head + body) + "\n"


#: what a run's result holds that the export reads (tengfield.pipeline.RunResult)
RUN_RESULT_PARTS = ("scene", "dynamics", "waveforms", "summary", "curves", "peaks")


def export(result, path, *, start_up: bool = False) -> Path:
    """Write the subcircuit ``teng`` of ``result`` to ``path`` (``teng.lib``); returns it.
    ``start_up``: the run's start-up before the repeated period (module docstring)."""
    from ._args import flag, path as path_argument
    from .files import write_text

    # a run's result by what it holds (tengfield.pipeline.RunResult, which exports
    # through this module: no import of it here)
    if not all(hasattr(result, name) for name in RUN_RESULT_PARTS):
        raise TypeError(f"tengfield.spice.export(result={type(result).__name__}): expected a "
                        "run's result (tengfield.run(scene)), got "
                        f"{type(result).__name__}")
    path = path_argument("tengfield.spice.export", path, "path", what="a file name")
    start_up = flag("tengfield.spice.export", start_up, "start_up")
    check_folder("tengfield.spice.export", path)
    write_text(path, subcircuit(result, start_up=start_up))
    return path


def check_folder(function: str, path: Path) -> None:
    """The folder ``path`` is written into exists: else one line naming the function and
    the folder (never the temporary file an atomic write would have made there)."""
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        from .errors import OutputError
        raise OutputError(f"{function}(path={str(path)!r}): the folder {str(folder)!r} does "
                          "not exist; create it first, or write into an existing one")


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
