"""Parameter sweeps: one surrogate, many excitations and loads (paper Figs. 9e-f, S13).

:func:`sweep_point` simulates one excitation and reports the same
peak-to-peak values as ``tengfield run`` (:func:`tengfield.electrical.terminal_peaks`:
steady window, samples and impact instants) and the mean power into each
load; :func:`sweep` runs it over a frequency x amplitude grid in worker
processes, or over the ranks of an MPI job (``mpirun -n N tengfield sweep``,
:func:`run_tasks`). :func:`write_sweep_csv` writes the rows (sweep.csv).
"""
from __future__ import annotations

import math
import warnings
from typing import Callable, Sequence

import numpy as np

from ._args import checked_write
from . import electrical
from ._json import regime_dict
from .quantities import SURFACE_CHARGE_KEY, TERMINAL, column_name  # noqa: F401
from .files import figure_file

#: the columns of sweep.csv and its writer live with the other tables (tengfield.io)
from .io import (LOAD_SWEEP_COLUMNS, SWEEP_COLUMNS, TERMINAL_COLUMNS,  # noqa: E402,F401
                 write_sweep_csv)


def _default_simulate():
    from .dynamics import simulate
    return simulate


def sweep_point(scene, table, frequency: float, amplitude: float,
                loads=(), simulate: Callable | None = None) -> list[dict]:
    """Peak-to-peak V_OC, Q_SC, I_SC at one excitation (frequency [Hz],
    amplitude [m]) and the mean power into each load [ohm] (steady window).

    ``table``: the scene's :class:`tengfield.surrogate.SurrogateTable`. One
    row per load (``load_ohm`` None and no power without loads). ``frequency`` and
    ``amplitude`` None: the scene's own excitation as it is (a ``--vary`` sweep without
    those axes).
    """
    simulate = simulate or _default_simulate()
    point = scene if frequency is None and amplitude is None else \
        point_scene(scene, frequency, amplitude)
    dynamics = simulate(point)
    point, curves, _, charge, dynamics = _point_charge(point, dynamics, table)
    extremes = electrical.terminal_extremes(point, dynamics, curves)
    regime = regime_dict(dynamics.regime) or {}
    exc = point.excitation
    base = {"frequency_hz": float(exc.frequency if frequency is None else frequency),
            "amplitude_mm": float(exc.amplitude if amplitude is None else amplitude) * 1e3,
            "regime": regime.get("regime", ""), "period": regime.get("period", 0)}
    for column, stat, name in TERMINAL_COLUMNS:
        base[column] = extremes[stat].get(name)
    base.update(charge)
    if not len(loads):
        return [{**base, "load_ohm": None, "P_mean_W": None, "power_density_W_per_m3": None}]
    rows = []
    grid = electrical.LoadGrid(point, dynamics, curves)   # shared by the loads
    t = electrical.elapsed_times(dynamics)
    for load in loads:
        loaded = point.with_values(circuit={"kind": "load", "load_ohm": float(load)})
        result = electrical.steady_load(loaded, dynamics, curves, grid=grid)
        rows.append({**base, **load_columns(loaded, result, t)})
    return rows


def _point_charge(point, dynamics, table):
    """``(point, curves, table, charge columns, dynamics)`` of a sweep point: with
    ``[charge] model = "contact"`` the point at its steady charge, its
    :class:`ContactCurves`, the table (per unit ball charge), the
    :data:`~tengfield.contact_run.CHARGE_COLUMNS` (the charge its contacts make along this
    point's own trajectory, :func:`tengfield.contact_run.contact_source`, the numbers
    ``tengfield run`` gives) and the trajectory its electrical stage covers (the run's
    last periods, :func:`tengfield.contact_run.electrical_window`); otherwise the point,
    its :class:`TerminalCurves`, the table, no columns and ``dynamics``."""
    if not point.charge.from_contacts:
        from .surrogate import TerminalCurves
        return (point, TerminalCurves(table, point.circuit.reference, point.device.ball_charge),
                table, {}, dynamics)
    from .contact_run import charge_columns, contact_source

    run = contact_source(point, dynamics, table)
    return run.scene, run.curves, run.table, charge_columns(run.block), run.dynamics


def load_columns(loaded, result, t) -> dict:
    """A sweep row's load columns of one :func:`~tengfield.electrical.steady_load`
    ``result`` of the scene ``loaded`` (``[circuit] kind = "load"``) on the run's time
    axis ``t``: through the load block a run writes (``load_block``: the same window,
    the same numbers)."""
    from .electrical.circuits.load import load_block

    mask, _ = electrical.steady_window(t, loaded)
    block = load_block(loaded, result, {"time_s": t, "V_load_V": result["V_load"],
                                        "I_load_A": result["I_load"]}, mask)
    r, power = float(loaded.circuit.load), float(block["mean_power_W"])
    return {"load_ohm": r, "P_mean_W": power,
            "power_density_W_per_m3": block["power_density_W_per_m3"],
            "V_load_pp_V": block["V_load_peak_to_peak_V"],
            "I_load_pp_A": block["I_load_peak_to_peak_A"],
            "V_load_rms_V": math.sqrt(max(power, 0.0) * r),
            "I_load_rms_A": math.sqrt(max(power, 0.0) / r)}


#: fewest steady periods of a point whose run is extended (:func:`point_duration`)
MIN_STEADY_PERIODS = 2


def steady_periods(scene) -> int:
    """Steady periods a point gets when its run must be extended: as many as the scene
    has at its own frequency (``duration_s x frequency_hz - settle_periods``), at least
    :data:`MIN_STEADY_PERIODS`."""
    exc, run = scene.excitation, scene.run
    return max(MIN_STEADY_PERIODS, int(run.duration * exc.frequency - run.settle_periods))


def extended_duration(settle_periods: int, duration: float, frequency: float,
                      steady: int) -> float:
    """THE rule of a run too short for its settling: ``duration`` [s], or, where
    ``settle_periods`` periods of ``frequency`` [Hz] fill it (no steady window),
    ``settle_periods + steady`` periods of that frequency (a sweep point,
    :func:`point_duration`; ``tengfield run``, :func:`extend_for_settling`)."""
    if settle_periods / float(frequency) < duration:
        return duration
    return (settle_periods + steady) / float(frequency)


def point_duration(scene, frequency: float) -> float:
    """The run length [s] of a sweep point at ``frequency`` [Hz]: ``[run] duration_s``,
    or, where ``settle_periods`` periods fill it (no steady window), extended to
    ``settle_periods + steady_periods(scene)`` periods of that frequency."""
    run = scene.run
    return extended_duration(run.settle_periods, run.duration, frequency, steady_periods(scene))


def extend_for_settling(base, settings, error):
    """``(scene, block)`` of ``tengfield run`` with ``--set`` ``settings`` on ``base``
    (the scene before them) whose settling fills the run (``error``: the
    :class:`~tengfield.scene.limits.SteadyWindowError` they gave): ``[run] duration_s``
    extended by the rule a sweep point gets (:func:`extended_duration`, with the steady
    periods ``base`` has: the run at 8 Hz is the sweep's point at 8 Hz), applied as one
    more ``--set run.duration_s``; ``block``: summary.json's ``run_extended`` (its
    ``reason`` is the terminal line). A ``--set run.duration_s`` of the user's own is
    kept: the error is raised again."""
    from .scene.parse import parse_setting, with_settings

    if any(parse_setting(text)[0] == ["run", "duration_s"] for text in settings):
        raise error
    frequency = 1.0 / error.period
    steady = steady_periods(base)
    duration = float(f"{extended_duration(error.settle_periods, error.duration, frequency, steady):.12g}")
    scene = with_settings(base, [*settings, f"run.duration_s={duration!r}"])
    reason = (f"run: [run] settle_periods = {error.settle_periods} leaves no steady window in "
              f"duration_s = {error.duration:g} s at {frequency:g} Hz: extended to "
              f"duration_s = {duration:g} s (settle_periods + {steady} steady periods, as "
              "sweep extends its points)")
    return scene, {"duration_s": duration, "stated_duration_s": error.duration,
                   "settle_periods": error.settle_periods, "steady_periods": steady,
                   "reason": reason}


def point_scene(scene, frequency: float, amplitude: float):
    """The scene of one sweep point (frequency [Hz], amplitude [m]), its run extended
    where the settling leaves no steady window (:func:`point_duration`)."""
    values = {"excitation": {"frequency_hz": float(frequency),
                             "amplitude_mm": float(amplitude) * 1e3}}
    duration = point_duration(scene, frequency)
    if duration != scene.run.duration:
        values["run"] = {"duration_s": float(f"{duration:.12g}")}
    return scene.with_values(**values)


def extension_line(scene, frequencies) -> str | None:
    """One line saying which points run longer than ``[run] duration_s`` (None: none)."""
    longer = sorted(float(f) for f in frequencies
                    if point_duration(scene, f) != scene.run.duration)
    if not longer:
        return None
    run = scene.run
    count = len(longer)
    return (f"sweep: [run] settle_periods = {run.settle_periods} leaves no steady window in "
            f"duration_s = {run.duration:g} s at frequency_hz <= {longer[-1]:g}: "
            f"{'that point runs' if count == 1 else f'those {count} frequencies run'} "
            f"settle_periods + {steady_periods(scene)} periods "
            f"(up to {point_duration(scene, longer[0]):.3g} s)")


def _sweep_task(args):
    """One point; a one-line error (a TengfieldError) names the point it happened at."""
    from .errors import TengfieldError

    try:
        return sweep_point(*args)
    except TengfieldError as exc:
        _, _, frequency, amplitude, _ = args
        try:
            named = type(exc)(f"sweep point frequency_hz = {frequency:g}, amplitude_mm = "
                              f"{amplitude * 1e3:g}: {exc}")
        except TypeError:     # an error class with other arguments: as it is
            raise exc from None
        raise named from None


from ._farm import run_tasks  # noqa: E402,F401 - the farm every study uses


#: Grid points (frequencies x amplitudes) of one sweep: each runs the scene's dynamics
#: (~10 ms to 1 s), so 1e5 points is hours on one core (a 1e10-point grid ran silently).
MAX_SWEEP_POINTS = 100_000
#: Rows (points x loads): each row is a dict of ~1 kB kept until sweep.csv is written.
MAX_SWEEP_ROWS = 1_000_000
#: Output samples evaluated (points x (1 + loads) x duration_s x sample_rate_hz): the
#: terminal values and each load's ODE touch every sample (~0.1 us each: ~20 min).
MAX_SWEEP_WORK = 1e10


def check_sweep_size(scene, n_frequencies: int, n_amplitudes: int, n_loads: int = 0) -> None:
    """Refuse a sweep too large to finish, before anything is allocated, naming the limit
    (as ``tengfield map`` does, :func:`tengfield.dynamics.mapping.check_map_size`)."""
    from .errors import SceneError

    points = n_frequencies * n_amplitudes
    if points > MAX_SWEEP_POINTS:
        raise SceneError(f"sweep points = {n_frequencies} frequencies x {n_amplitudes} "
                         f"amplitudes = {points:.3g}: allowed <= {MAX_SWEEP_POINTS:.0e} (each "
                         "point runs the dynamics; use fewer points or `tengfield map` for "
                         "regimes only)")
    rows = points * max(n_loads, 1)
    if rows > MAX_SWEEP_ROWS:
        raise SceneError(f"sweep rows = {points} points x {n_loads} loads = {rows:.3g}: allowed "
                         f"<= {MAX_SWEEP_ROWS:.0e}")
    samples = scene.run.duration * scene.run.sample_rate
    work = points * (1 + n_loads) * samples
    if work > MAX_SWEEP_WORK:
        raise SceneError(f"sweep work = {points} points x (1 + {n_loads} loads) x {samples:.3g} "
                         f"samples ([run] duration_s x sample_rate_hz) = {work:.3g}: allowed <= "
                         f"{MAX_SWEEP_WORK:.0e} (fewer points or loads, or a shorter run)")


def check_grid(scene, frequencies, amplitudes) -> None:
    """Validate the scene of every grid point (frequencies [Hz] x amplitudes [m]) as a
    scene file would be: a bad point raises :class:`SceneError` naming the point, before
    any work (the CLI calls this before it computes a surrogate).

    Every rule a point can break is monotone in the frequency or in the amplitude (their
    ranges, the period and sample counts, the steady window, the array's work), so the
    grid's corners stand for all of it: the check costs four scene builds at any size."""
    from .errors import SceneError

    from .dynamics.excitation import excitation_kind

    kind = scene.excitation.kind
    if not excitation_kind(scene).periodic:   # every point would run the scene's own record
        raise SceneError(f"[excitation] kind = {kind!r}: a sweep varies a sine's frequency_hz "
                         f"and amplitude_mm, which a {kind} excitation does not have (every "
                         f"point would be the same run); sweep a kind = \"sine\" scene, or use "
                         f"[run] realisations (noise) or `tengfield design` with "
                         f"[design.excitation]")
    check_sweep_size(scene, len(frequencies), len(amplitudes))
    fs = sorted({min(map(float, frequencies)), max(map(float, frequencies))}) \
        if len(frequencies) else []
    amps = sorted({min(map(float, amplitudes)), max(map(float, amplitudes))}) \
        if len(amplitudes) else []
    for f in fs:
        for a in amps:
            try:
                point_scene(scene, f, a)
            except SceneError as exc:
                raise SceneError(f"sweep point frequency_hz = {float(f):g}, amplitude_mm = "
                                 f"{float(a) * 1e3:g}: {exc}") from None


class SweepRows(list):
    """The rows of :func:`sweep` (a list of dicts, one per grid point and load) with
    :meth:`plot`."""

    def plot(self):
        """The sweep figure (a matplotlib Figure; ``tengfield sweep`` saves it as sweep.png):
        peak-to-peak V_OC, Q_SC, I_SC against frequency per amplitude, and mean power
        against load when the sweep has loads."""
        from .plotting.waveforms import sweep_figure   # the edge, imported on use

        return sweep_figure(self)


def sweep(scene, table, frequencies, amplitudes, loads=(), *,
          jobs: int | None = None, comm=None, progress: bool = False) -> list[dict]:
    """:func:`sweep_point` over the grid ``frequencies`` [Hz] x ``amplitudes`` [m]
    (frequency outer, amplitude inner, loads innermost), with a progress bar
    (stderr, only when it is a terminal).

    ``comm``: an MPI communicator (``COMM_WORLD`` under ``mpirun -n N``,
    passed by the CLI); with more than one rank the grid points are farmed
    over the ranks (:func:`run_tasks`) and every rank returns all rows, the
    same as a serial run. Otherwise ``jobs`` worker processes (default: all
    cores) on this machine.
    """
    from ._console import progress_bar
    from ._mpi import check_jobs

    check_jobs(jobs, comm)
    check_sweep_size(scene, len(frequencies), len(amplitudes), len(loads))
    check_grid(scene, frequencies, amplitudes)   # on every rank, before any work
    tasks = [(scene, table, float(f), float(a), tuple(loads)) for f in frequencies for a in amplitudes]
    bar = progress_bar(len(tasks), "sweep", progress, unit="point", comm=comm)
    try:
        results = run_tasks(_sweep_task, tasks, comm=comm, jobs=jobs, progress=bar.update)
    finally:
        bar.close()
    return SweepRows(row for rows in results for row in rows)


# ---------------------------------------------------------------------------
# a parametric sweep over any scene key (``--vary section.key=START:STOP:N``)
#: the excitation keys the frequency/amplitude axes set (a --vary of one of them beside
#: its axis would be two settings of one key)
AXIS_KEYS = {"excitation.frequency_hz": "--frequency-hz", "excitation.amplitude_mm": "--amplitude-mm"}


#: most values one --vary range may give (as a command-line START:STOP:N range)
MAX_RANGE_VALUES = 100_000


def _number_text(value: float) -> str:
    """``:g`` when that is the number itself, else the shortest text that is (``repr``)."""
    text = f"{value:g}"
    return text if not math.isfinite(value) or float(text) == value else repr(value)


def _range_values(text: str, where: str, *, log: bool = False) -> list | None:
    """``START:STOP:N`` -> N values, both ends included (linear, or logarithmic with
    ``log``), each the shortest decimal of its double; None when ``text`` is no range.
    Raises :class:`SceneError` naming ``where`` for a bad range."""
    from .errors import SceneError

    parts = text.split(":")
    if len(parts) == 1:
        return None
    if len(parts) != 3:
        raise SceneError(f"{where}: expected START:STOP:N (e.g. 1:5:9) or a list v1,v2,...")
    try:
        start, stop, count = float(parts[0]), float(parts[1]), int(parts[2])
    except ValueError:
        raise SceneError(f"{where}: START and STOP must be numbers and N a whole number, "
                         "e.g. 1:5:9") from None
    if not (math.isfinite(start) and math.isfinite(stop)):
        raise SceneError(f"{where}: START and STOP must be finite")
    if not 1 <= count <= MAX_RANGE_VALUES:
        raise SceneError(f"{where}: N = {count} is out of range: allowed [1, {MAX_RANGE_VALUES}]")
    if log and min(start, stop) <= 0:
        raise SceneError(f"{where}: every value must be > 0 (spaced logarithmically)")
    values = np.logspace(math.log10(start), math.log10(stop), count) if log else \
        np.linspace(start, stop, count)
    return [float(_number_text(float(v))) for v in values]


def parse_vary(text: str) -> tuple[str, list]:
    """``section.key=START:STOP:N`` (N values, both ends included, linear), a list
    ``section.key=1,2,4`` or ``section.key=[1, 2, 4]`` (TOML values: numbers, strings,
    ``true``), or one value -> (``"section.key"``, values in file units). Raises
    :class:`SceneError` naming the text and what is allowed; the values are checked
    later, in each point's scene (:func:`vary_points`)."""
    from .errors import SceneError
    from .scene.parse import parse_setting

    key, eq, value = text.partition("=")
    key, value = key.strip(), value.strip()
    if not eq or key.count(".") < 1 or not all(key.split(".")) or not value:
        raise SceneError(f"--vary {text!r}: write section.key=START:STOP:N or "
                         "section.key=v1,v2,..., e.g. --vary device.stroke_mm=1:5:9")
    if key == "circuit.parallel_capacitance_pF":   # deprecated: said once, as by --set
        from .scene.model import warn_deprecated_capacitance
        warn_deprecated_capacitance(value, option="--vary", stacklevel=3)
    values = _range_values(value, f"--vary {text!r}")
    if values is not None:
        return key, values
    listed = value if value.startswith("[") and value.endswith("]") else f"[{value}]"
    try:   # a TOML list of the values (each may itself be a list: [[20, 1], [40, 0.5]])
        values = parse_setting(f"{key}={listed}", option="--vary")[1]
    except SceneError:
        values = None
    if not isinstance(values, list):
        # bare words (kind=load,open or [load, open]): each value its own --set text
        items = value[1:-1] if value.startswith("[") and value.endswith("]") else value
        if "[" in items or "]" in items:   # nested lists that are no TOML: said as written
            parse_setting(f"{key}={value}", option="--vary")
        values = [parse_setting(f"{key}={item.strip()}", option="--vary")[1]
                  for item in items.split(",") if item.strip()]
    if not values:
        raise SceneError(f"--vary {text!r}: no values; write section.key=v1,v2,...")
    return key, values


def _toml_value(value) -> str:
    """``value`` as the text of a TOML value (what ``--set key=TEXT`` reads)."""
    import json

    if isinstance(value, (bool, np.bool_)):
        return "true" if value else "false"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        value = float(value)
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, (list, tuple, np.ndarray)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    raise TypeError(f"a --vary value must be a number, a string or a list, not {value!r:.60}")


def _vary_values(key: str, values) -> list:
    """The values of one ``vary`` entry: a list/array, one value, or a range text."""
    if isinstance(values, str):
        return parse_vary(f"{key}={values}")[1]
    if isinstance(values, (list, tuple, np.ndarray)):
        out = [v.item() if isinstance(v, np.generic) else v for v in values]
    else:
        out = [values.item() if isinstance(values, np.generic) else values]
    if not out:
        from .errors import SceneError
        raise SceneError(f"vary {key!r}: no values")
    return out


def point_label(values: dict) -> str:
    """``device.stroke_mm = 2, circuit.load_ohm = 1e+08`` (a point's varied values)."""
    def text(v):
        number = isinstance(v, (int, float)) and not isinstance(v, bool)
        return _number_text(float(v)) if number else repr(v)

    return ", ".join(f"{k} = {text(v)}" for k, v in values.items())


#: sections no sweep row reads (a --vary of their keys would change nothing): why
NOT_READ = {"fit": "[fit] is tengfield fit's (a sweep fits nothing)",
            "design": "[design] is tengfield design's (a sweep searches nothing)",
            "uncertainty": "[uncertainty] is tengfield uncertainty's (a sweep draws nothing)",
            "reference": "[reference] holds measured values run compares with (a sweep row "
                         "has no comparison)",
            "array": "[array] cells are run by tengfield run (a sweep point is one cell; "
                     "[device] cells scales it)"}
#: keys of a read section that no sweep row reads: why
KEYS_NOT_READ = {"run.realisations": "a sweep point is one realisation",
                 "run.output_format": "it is the format of run's tables (sweep writes "
                                      "sweep.csv)"}
#: [circuit] keys every row reads: the reference state, the instrument's capacitance
CIRCUIT_READ = ("reference", "parallel_capacitance_pF")
#: what a --vary can reach, said with each refusal
VARIABLE = ("vary keys of [device], [excitation], [contact], [initial], [run], [field], "
            "[instrument], [breakdown] (with sigma = \"breakdown\"), [charge] (with model = "
            "\"contact\"), [circuit] reference, or "
            "the load's keys with a [circuit] kind that has a load ({kinds}) and no --load-ohm")


def _loaded_kinds() -> list[str]:
    from .electrical import CIRCUITS

    return [name for name, entry in CIRCUITS.items() if entry.has_load]


def vary_problem(key: str, points, loads=()) -> str | None:
    """Why a ``--vary`` of ``key`` reaches no row of the sweep of ``points`` (``[(values,
    point scene)]``) with ``loads`` (None: it does, each point's scene carries it to the
    outputs). A row holds the terminal outputs of each point's dynamics and field, and
    the mean power of its circuit's load (a ``--load-ohm`` axis: the R ∥ C_p load at each
    of those loads, whatever the kind)."""
    from .air_breakdown import uses_breakdown_charge
    from .electrical import circuit_for

    section, name = key.split(".", 1)
    if section in NOT_READ:
        return NOT_READ[section]
    if key in KEYS_NOT_READ:
        return KEYS_NOT_READ[key]
    from .charge_models import charge_model_of, models_reading
    if section == "charge" and not any(charge_model_of(s).reads(name) for _, s in points):
        return ("[charge] " + name + " acts only with [charge] model = " + models_reading(name)
                + " (tengfield.charge_models); this sweep's charge is "
                + ", ".join(sorted({repr(s.charge.model) for _, s in points})))
    if section == "breakdown" and not any(uses_breakdown_charge(s) for _, s in points):
        return ("[breakdown] sets the air-breakdown limit, which a sweep row uses only with "
                f"[device] {SURFACE_CHARGE_KEY} = \"breakdown\"")
    if section != "circuit" or name in CIRCUIT_READ:
        return None
    if len(loads):
        return ("the --load-ohm axis sets the circuit of every row (the R || C_p load at "
                "each load), so [circuit] " + name + " changes nothing; drop --load-ohm")
    entries = [circuit_for(s) for _, s in points]
    if name == "kind":
        if any(e.has_load for e in entries):
            return None
        return ("no kind varied has a load, and a row holds the terminal outputs (the "
                "same for every kind) and the load's power")
    if any(e.has_load and name in e.keys for e in entries):
        return None
    kinds = sorted({s.circuit.kind for _, s in points})
    reported = sorted({k for e in entries if e.has_load for k in e.keys})
    reads = (f"the rows report {', '.join(reported)}" if reported else
             "no varied kind has a load, whose power a row reports")
    return (f"[circuit] kind = {', '.join(map(repr, kinds))} does not report {name} in a "
            f"sweep row ({reads})")


def check_vary_reaches(vary: dict, points, loads=()) -> None:
    """Refuse, in one line before any work, a varied key that reaches no row
    (:func:`vary_problem`): naming the key, why, and what can be varied."""
    from .errors import SceneError

    for key in vary:
        problem = vary_problem(key, points, loads)
        if problem is not None:
            raise SceneError(f"--vary {key}: {problem}; "
                             + VARIABLE.format(kinds=", ".join(map(repr, _loaded_kinds()))))


def vary_points(scene, vary: dict, frequencies=None, amplitudes=None) -> list[tuple[dict, object]]:
    """``[(values, point scene)]`` over the product of ``vary`` ({``"section.key"``:
    values in file units}; the first key outermost), each scene built from ``scene``
    through the path of ``--set`` (:func:`tengfield.scene.with_settings`), so every check
    of a scene file applies. A bad key or value raises :class:`SceneError` naming the
    point, the key, the value and the allowed range, before any work; with frequency or
    amplitude axes each point's corners are checked too (:func:`check_grid`)."""
    import itertools

    from .errors import SceneError
    from .scene import with_settings

    vary = {str(k): _vary_values(str(k), v) for k, v in (vary or {}).items()}
    for key in vary:
        axis = AXIS_KEYS.get(key)
        given = {"--frequency-hz": frequencies, "--amplitude-mm": amplitudes}.get(axis)
        if axis and given is not None and len(given):
            raise SceneError(f"--vary {key} and {axis} both set {key}: give one of them")
    count = math.prod(len(v) for v in vary.values())
    axes = max(1, len(frequencies) if frequencies is not None else 1) * \
        max(1, len(amplitudes) if amplitudes is not None else 1)
    if count * axes > MAX_SWEEP_POINTS:
        sizes = " x ".join(f"{len(v)} {k}" for k, v in vary.items())
        raise SceneError(f"sweep points = {sizes} x {axes} excitations = {count * axes:.3g}: "
                         f"allowed <= {MAX_SWEEP_POINTS:.0e} (each point runs the dynamics)")
    points = []
    for combo in itertools.product(*vary.values()):
        values = dict(zip(vary, combo))
        try:
            point = with_settings(scene, [f"{k}={_toml_value(v)}" for k, v in values.items()],
                                  warn=False)   # a deprecated key: said once, by parse_vary
        except TypeError as exc:
            raise SceneError(f"sweep point {point_label(values)}: {exc}") from None
        except SceneError as exc:
            text = str(exc).replace(f"{scene.source} with --set: ", "").replace(
                "<default scene> with --set: ", "")
            raise SceneError(f"sweep point {point_label(values)}: {text}") from None
        if frequencies is not None or amplitudes is not None:
            try:
                check_grid(point, _axis(point, frequencies, "frequency"),
                           _axis(point, amplitudes, "amplitude"))
            except SceneError as exc:
                raise SceneError(f"sweep point {point_label(values)}: {exc}") from None
        points.append((values, point))
    return points


def _axis(scene, values, which: str) -> list:
    """An excitation axis, or the scene's own value when the sweep has none (SI)."""
    if values is not None and len(values):
        return [float(v) for v in values]
    return [scene.excitation.frequency if which == "frequency" else scene.excitation.amplitude]


def point_tables(points, *, cache_dir=None, comm=None, solve=None, progress: bool = False,
                 command_line: str = "", tables: dict | None = None):
    """Each point's ``(scene, table)``: the scene at the charge it runs with, the table per
    unit ball charge (:func:`tengfield.run_surrogate.surrogate_for_run`, the path of
    ``tengfield run``), and
    ``{"computed": n, "cached": n, "reused": n, "geometries": n}``. Points of one geometry
    (one field hash) share one surrogate: the first obtains it (solved over ``comm``'s
    ranks or read from the cache), the others reuse it (``reused``, no field solve: a σ or
    circuit key never solves a field)."""
    from .air_breakdown import uses_breakdown_charge
    from .run_surrogate import surrogate_for_run
    from .errors import SceneError

    from .contact_run import field_scene, reference_sigma

    tables = {} if tables is None else tables
    counts = {"computed": 0, "cached": 0, "reused": 0, "geometries": 0}
    out = []
    for values, scene in points:
        try:
            key = scene.field_hash()
        except SceneError as exc:
            raise SceneError(f"sweep point {point_label(values)}: {exc}") from None
        memo = tables.get(key)
        if scene.charge.from_contacts:   # the geometry's table (per unit ball charge)
            _check_contact_point(scene, values)
            if reference_sigma(scene) == 0.0:
                out.append((scene, None))
                continue
            if memo is not None:
                out.append((scene, memo))
                counts["reused"] += 1
                continue
            scene_at = field_scene(scene)
        else:
            scene_at = scene
        if memo is not None and not uses_breakdown_charge(scene) \
                and scene.device.ball_charge != 0.0:
            out.append((scene, memo))
            counts["reused"] += 1
            continue
        try:
            with warnings.catch_warnings():   # sigma_eq beyond the limit: the cap holds
                if scene_at is not scene:
                    warnings.filterwarnings("ignore", message=".*exceeds the air-breakdown.*")
                resolved, table, outcome, _ = surrogate_for_run(
                    scene_at, cache_dir=cache_dir, comm=comm, solve=solve,
                    progress=progress, command_line=command_line)
        except SceneError as exc:
            if not values:       # a frequency x amplitude sweep: every point's geometry
                raise
            raise SceneError(f"sweep point {point_label(values)}: {exc}") from None
        if key not in tables:
            counts["geometries"] += 1
        tables.setdefault(key, table)
        counts["computed" if outcome.status == "computed" else "cached"] += 1
        out.append((scene if scene_at is not scene else resolved, table))
    return out, counts


def _check_contact_point(scene, values) -> None:
    """What a contact run refuses (a ball off the axis), named with the
    point (:func:`tengfield.pipeline.check_contact_charge`, the run's check)."""
    from .errors import SceneError
    from .contact_run import check_contact_charge

    try:
        check_contact_charge(scene)
    except SceneError as exc:
        if not values:
            raise
        raise SceneError(f"sweep point {point_label(values)}: {exc}") from None


def own_load_point(scene, table, frequency=None, amplitude=None) -> list[dict]:
    """The row of a varied point whose ``[circuit]`` has a load and no ``--load-ohm``
    axis: its terminal outputs, its own ``load_ohm`` and the mean power and power density
    of its circuit (``series-rc``'s R + C_s too) from the stage ``tengfield run`` uses
    (:func:`tengfield.pipeline.electrical_stage`), so the row is that run's summary.
    ``frequency`` [Hz], ``amplitude`` [m] None: the point's own excitation."""
    from .pipeline import electrical_stage

    point = scene if frequency is None and amplitude is None else \
        point_scene(scene, frequency, amplitude)
    dynamics = _default_simulate()(point)
    point, curves, table, charge, dynamics = _point_charge(point, dynamics, table)
    stage = electrical_stage(point, dynamics, curves, table)
    regime = regime_dict(dynamics.regime) or {}
    exc = point.excitation
    row = {"frequency_hz": float(exc.frequency if frequency is None else frequency),
           "amplitude_mm": float(exc.amplitude if amplitude is None else amplitude) * 1e3,
           "regime": regime.get("regime", ""), "period": regime.get("period", 0)}
    for column, stat, name in TERMINAL_COLUMNS:
        row[column] = getattr(stage, stat).get(name)
    load = stage.summary.get("load") or {}
    row.update(load_ohm=float(point.circuit.load), P_mean_W=load.get("mean_power_W"),
               power_density_W_per_m3=load.get("power_density_W_per_m3"))
    row.update(charge)
    return [row]


def _vary_task(args):
    """One point of a varied sweep: its rows, each led by the varied values; a one-line
    error (a TengfieldError) names the varied values of the point it happened at."""
    from .errors import TengfieldError

    values, scene, table, frequency, amplitude, loads = args
    try:
        if values and not len(loads) and electrical.circuit_for(scene).has_load:
            rows = own_load_point(scene, table, frequency, amplitude)
        elif frequency is None and amplitude is None:
            rows = sweep_point(scene, table, None, None, loads)
        else:
            rows = _sweep_task((scene, table, frequency, amplitude, loads))
    except TengfieldError as exc:
        if not values:
            raise
        try:
            named = type(exc)(f"sweep point {point_label(values)}: {exc}")
        except TypeError:     # an error class with other arguments: as it is
            raise exc from None
        raise named from None
    return [{**values, **row} for row in rows]


class SweepResult(SweepRows):
    """The rows of :func:`sweep_study` (a list of dicts, one per point and load; the
    varied keys lead each row) with ``scene``, ``vary`` (the varied keys), ``summary``,
    :meth:`plot` and :meth:`write` (what ``tengfield sweep`` writes)."""

    def __init__(self, rows, *, scene=None, vary=(), surrogates=None, loads=None):
        super().__init__(rows)
        self.scene, self.vary, self.surrogates = scene, list(vary), dict(surrogates or {})
        #: the --load-ohm axis [ohm] (empty: none, a row's load is its point's own
        #: circuit's, a function of the varied keys; None: not said)
        self.loads = None if loads is None else tuple(loads)

    @property
    def columns(self) -> list[str]:
        """sweep.csv's columns: the varied keys, then :data:`SWEEP_COLUMNS`, then the
        charge's (:data:`~tengfield.contact_run.CHARGE_COLUMNS`) where the contacts make it."""
        from .contact_run import CHARGE_COLUMNS

        charge = [c for c in CHARGE_COLUMNS if any(c in row for row in self)]
        return [*self.vary, *SWEEP_COLUMNS, *charge]

    @property
    def summary(self) -> dict:
        return {"rows": len(self), "vary": list(self.vary), "surrogates": self.surrogates}

    def plot(self, key: str | None = None):
        """The figure of one varied key (default: the first; peak-to-peak V_OC, Q_SC,
        I_SC and, with loads, the mean power against its values), or sweep.png's figure
        when nothing is varied."""
        if not self.vary:
            return super().plot()
        from .plotting.sweep_vary import vary_figure

        return vary_figure(self, key or self.vary[0])

    def figure_names(self) -> dict[str, str]:
        """{varied key: its figure's file name} (``sweep_device.stroke_mm.png``)."""
        return {key: figure_file(f"sweep_{key}") for key in self.vary}

    @checked_write
    def write(self, out_dir, plots: bool = True) -> list:
        """sweep.csv and the figures (sweep.png when frequency x amplitude is swept without
        --vary; one ``sweep_<key>.png`` per varied key) in ``out_dir``; the paths written."""
        from pathlib import Path

        from .files import write_figure
        from .plotting import save_figure

        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        written = [write_sweep_csv(out / "sweep.csv", self, self.columns)]
        if plots:
            names = self.figure_names() if self.vary else {None: figure_file("sweep")}
            for key, name in names.items():
                written.append(write_figure(save_figure, self.plot(key), dpi=120,
                                            path=out / name))
        return written



def sweep_study(scene, *, vary: dict | None = None, frequencies=None, amplitudes=None,
                loads=(), cache_dir=None, solve: Callable | None = None,
                jobs: int | None = None, comm=None, progress: bool = False,
                command_line: str = "", on_surrogates: Callable | None = None) -> SweepResult:
    """A sweep over any scene keys and/or the excitation: every point of
    ``vary`` ({``"section.key"``: values, file units}) x ``frequencies`` [Hz] x
    ``amplitudes`` [m] x ``loads`` [ohm] (None or empty: the axis is the scene's own).
    Each point's scene is built through ``--set``'s path (:func:`vary_points`, all
    checked before any work); each geometry's surrogate is obtained once (cached by field
    hash, :func:`point_tables`); the points are farmed like :func:`sweep` (``comm``'s
    ranks, or ``jobs`` worker processes) and every rank returns every row.
    ``on_surrogates(counts, [(scene, table)])``: called (on every rank) once the
    surrogates are at hand (the CLI's lines)."""
    from ._console import progress_bar
    from ._mpi import check_jobs
    from .errors import SceneError

    check_jobs(jobs, comm)
    if vary is not None and not isinstance(vary, dict):
        raise TypeError(f"sweep(vary={vary!r:.60}): expected a dict {{'section.key': values}}, "
                        "e.g. vary={'device.stroke_mm': '1:5:9'}")
    vary = dict(vary or {})
    freqs = None if frequencies is None or not len(frequencies) else [float(f) for f in frequencies]
    amps = None if amplitudes is None or not len(amplitudes) else [float(a) for a in amplitudes]
    if not vary and freqs is None and amps is None:
        raise SceneError("sweep: nothing to vary: give --vary section.key=START:STOP:N and/or "
                         "--frequency-hz and --amplitude-mm")
    loads = tuple(float(x) for x in loads)
    if vary:
        points = vary_points(scene, vary, freqs, amps)
        check_vary_reaches(vary, points, loads)
    else:
        check_grid(scene, _axis(scene, freqs, "frequency"), _axis(scene, amps, "amplitude"))
        points = [({}, scene)]
    check_sweep_size(scene, len(points) * len(freqs or [None]), len(amps or [None]), len(loads))
    with_tables, counts = point_tables(points, cache_dir=cache_dir, comm=comm, solve=solve,
                                       progress=progress, command_line=command_line)
    if on_surrogates is not None:
        on_surrogates(counts, with_tables)
    tasks = []
    for (values, _), (point, table) in zip(points, with_tables):
        fs = freqs or ([None] if amps is None else [point.excitation.frequency])
        amps_here = amps or ([None] if freqs is None else [point.excitation.amplitude])
        tasks += [(values, point, table, f, a, loads) for f in fs for a in amps_here]
    bar = progress_bar(len(tasks), "sweep", progress, unit="point", comm=comm)
    try:
        results = run_tasks(_vary_task, tasks, comm=comm, jobs=jobs, progress=bar.update)
    finally:
        bar.close()
    return SweepResult((row for rows in results for row in rows), scene=scene,
                       vary=list(vary), surrogates=counts, loads=loads)


def _file_axis(values, scale: float, name: str, log: bool = False):
    """A ``tf.sweep`` axis in file units (a list, one number or ``"START:STOP:N"``) -> SI."""
    if values is None:
        return None
    if isinstance(values, str):
        ranged = _range_values(values, f"{name} = {values!r}", log=log)
        if ranged is None:
            from .errors import SceneError
            try:
                ranged = [float(v) for v in values.split(",")]
            except ValueError:
                raise SceneError(f"{name} = {values!r}: expected START:STOP:N, a number or "
                                 "numbers v1,v2,...") from None
        values = ranged
    arr = np.atleast_1d(np.asarray(values, dtype=float))
    return [float(v) * scale for v in arr]


def study(scene, *, vary: dict | None = None, frequency_hz=None, amplitude_mm=None,
          load_ohm=(), cache_dir=None, jobs: int | None = None, comm=None,
          progress: bool = False, solve: Callable | None = None) -> SweepResult:
    """``tf.sweep(scene, ...)`` (a plain function: the module is ``tengfield.sweeps``):
    :func:`sweep_study` in file units, as ``tengfield sweep``
    takes them: ``vary={"device.stroke_mm": "1:5:9", "circuit.load_ohm": [1e6, 1e8]}``,
    ``frequency_hz`` [Hz] and ``amplitude_mm`` [mm] (lists, one number or
    ``"START:STOP:N"``), ``load_ohm`` [ohm]. Returns a :class:`SweepResult` (rows,
    ``.plot(key)``, ``.write(out_dir)``)."""
    from .scene.parse import verb_scene

    scene = verb_scene("tengfield.sweep", scene)
    loads = _file_axis(load_ohm, 1.0, "load_ohm", log=True) if load_ohm is not None else ()
    return sweep_study(scene, vary=vary,
                       frequencies=_file_axis(frequency_hz, 1.0, "frequency_hz"),
                       amplitudes=_file_axis(amplitude_mm, 1e-3, "amplitude_mm"),
                       loads=loads or (),
                       cache_dir=cache_dir, solve=solve, jobs=jobs, comm=comm,
                       progress=progress)
