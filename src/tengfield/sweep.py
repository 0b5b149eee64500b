"""Parameter sweeps: one surrogate, many excitations and loads (paper Figs. 9e-f, S13).

:func:`sweep_point` simulates one excitation and reports the same
peak-to-peak values as ``tengfield run`` (:func:`tengfield.electrical.terminal_peaks`:
steady window, samples and impact instants) and the mean power into each
load; :func:`sweep` runs it over a frequency x amplitude grid in worker
processes, or over the ranks of an MPI job (``mpirun -n N tengfield sweep``,
:func:`run_tasks`). ``tengfield.io.write_sweep_csv`` writes the rows.
"""
from __future__ import annotations

from typing import Callable, Sequence

from . import electrical
from ._json import regime_dict
from .quantities import TERMINAL, column_name

#: the terminal statistics of a sweep row: (column, statistic, short name), names from
#: :mod:`tengfield.quantities` (``V_oc_pp_V``, ..., ``I_sc_peak_A``, ``V_read_pp_V``)
TERMINAL_COLUMNS = [(column_name(name, stat), stat, name[:name.rindex("_")])
                    for stat in ("peak_to_peak", "peak") for name in (*TERMINAL, "V_read_V")]
#: columns of ``sweep.csv`` (one row per grid point and load); ``V_read_*`` empty without
#: an instrument (``[circuit] parallel_capacitance_pF`` = 0)
SWEEP_COLUMNS = (["frequency_hz", "amplitude_mm", "load_ohm", "regime", "period"]
                 + [column_name(n, "peak_to_peak") for n in TERMINAL]   # the first columns,
                 + ["P_mean_W", "power_density_W_per_m3"]                # kept in place
                 + [c for c, _, _ in TERMINAL_COLUMNS if c not in
                    [column_name(n, "peak_to_peak") for n in TERMINAL]])


def _default_simulate():
    from .dynamics import simulate
    return simulate


def sweep_point(scene, table, frequency: float, amplitude: float,
                loads=(), simulate: Callable | None = None) -> list[dict]:
    """Peak-to-peak V_OC, Q_SC, I_SC at one excitation (frequency [Hz],
    amplitude [m]) and the mean power into each load [ohm] (steady window).

    ``table``: the scene's :class:`tengfield.surrogate.SurrogateTable`. One
    row per load (``load_ohm`` None and no power without loads).
    """
    from .surrogate import TerminalCurves

    simulate = simulate or _default_simulate()
    point = point_scene(scene, frequency, amplitude)
    dynamics = simulate(point)
    curves = TerminalCurves(table, point.circuit.reference)
    extremes = electrical.terminal_extremes(point, dynamics, curves)
    regime = regime_dict(dynamics.regime) or {}
    base = {"frequency_hz": float(frequency), "amplitude_mm": float(amplitude) * 1e3,
            "regime": regime.get("regime", ""), "period": regime.get("period", 0)}
    for column, stat, name in TERMINAL_COLUMNS:
        base[column] = extremes[stat].get(name)
    if not len(loads):
        return [{**base, "load_ohm": None, "P_mean_W": None, "power_density_W_per_m3": None}]
    rows = []
    volume = point.device.cell_volume * point.device.cells
    for load in loads:
        loaded = point.with_values(circuit={"kind": "load", "load_ohm": float(load)})
        result = electrical.steady_load(loaded, dynamics, curves)
        rows.append({**base, "load_ohm": float(load), "P_mean_W": result["mean_power_W"],
                     "power_density_W_per_m3": result["mean_power_W"] / volume})
    return rows


#: fewest steady periods of a point whose run is extended (:func:`point_duration`)
MIN_STEADY_PERIODS = 2


def steady_periods(scene) -> int:
    """Steady periods a point gets when its run must be extended: as many as the scene
    has at its own frequency (``duration_s x frequency_hz - settle_periods``), at least
    :data:`MIN_STEADY_PERIODS`."""
    exc, run = scene.excitation, scene.run
    return max(MIN_STEADY_PERIODS, int(run.duration * exc.frequency - run.settle_periods))


def point_duration(scene, frequency: float) -> float:
    """The run length [s] of a sweep point at ``frequency`` [Hz]: ``[run] duration_s``,
    or, where ``settle_periods`` periods fill it (no steady window), extended to
    ``settle_periods + steady_periods(scene)`` periods of that frequency."""
    run = scene.run
    if run.settle_periods / float(frequency) < run.duration:
        return run.duration
    return (run.settle_periods + steady_periods(scene)) / float(frequency)


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


def run_tasks(work: Callable, tasks: Sequence, *, comm=None, jobs: int | None = None,
              progress: Callable[[int], None] | None = None, mp_context: str | None = None) -> list:
    """``[work(task) for task in tasks]``, in order, spread over the workers at hand.

    * ``comm`` with more than one rank (``mpirun -n N``): the MPI task farm
      :func:`tengfield._mpi.farm` (dynamic schedule, every rank returns the
      whole list, an exception on any rank aborts all ranks with its message);
      ``jobs`` must be None or 1 (:func:`tengfield._mpi.check_jobs`).
    * otherwise ``jobs`` worker processes (default: all cores; ``work`` and
      the tasks must be picklable; ``mp_context``: a start method, default
      tengfield's one, :func:`tengfield._pool.pool_context`), or a plain loop for
      one job or one task.

    ``progress(n)``: called with the number of further tasks done (rank 0 only
    under MPI). Used by :func:`sweep`; ``tengfield map`` can use it too.
    """
    import os

    from ._mpi import check_jobs, farm, size_of

    check_jobs(jobs, comm)
    tasks = list(tasks)
    if size_of(comm) > 1:
        return farm(comm, tasks, work, progress=progress)
    jobs = max(1, min(jobs or os.cpu_count() or 1, len(tasks)))
    results = []
    if jobs == 1:
        for task in tasks:
            results.append(work(task))
            if progress is not None:
                progress(1)
        return results
    from ._pool import process_pool
    with process_pool(jobs, mp_context) as pool:
        for result in pool.map(work, tasks):
            results.append(result)
            if progress is not None:
                progress(1)
    return results


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
