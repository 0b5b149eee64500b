"""The waveform core: the one place that turns z(t) into V_OC, Q_SC, I_SC.

Every consumer (:func:`tengfield.pipeline.run`, :mod:`tengfield.sweeps`,
:mod:`tengfield.array`, :mod:`tengfield.accuracy_report`, :mod:`tengfield.fit`, the
demos) calls these functions, so they give the same numbers for the same scene;
what a circuit does with the terminal is in :mod:`tengfield.electrical.circuits`:

* :func:`terminal_waveforms`: V_OC (always the ideal open-circuit voltage), the
  voltage V_read an instrument of capacitance C_p reads, Q_SC, I_SC (and C_T)
  along sampled z(t), ż(t) for ``cells`` identical cells in parallel;
* :func:`scene_waveforms`: the same for a dynamics result, with ``cells``
  and C_p taken from the scene, as the ``waveforms.csv`` columns;
* :func:`steady_window`: the samples after ``[run] settle_periods`` periods
  (:func:`steady_start`, the one rule; a DynamicsResult's ``window_start`` is
  the same instant on the absolute axis);
* :func:`terminal_extremes`: peak-to-peak and peak (max |x|) of V_OC, Q_SC, I_SC
  (and V_read) over the steady window, over the samples *and* just before/after
  every impact (where I_SC jumps and takes its extremes); :func:`terminal_peaks`
  its peak-to-peak half; :func:`extreme_times` and :func:`extremes` are the same
  rule for a model sampled elsewhere (fit).

Units are SI; signs are those of :mod:`tengfield.terminals` (V = V_lower -
V_upper, charges and currents counted lower -> upper through the external
circuit, reference state z = 0).
"""
from __future__ import annotations

import math

import numpy as np

from .. import lumped
from ..source import Source, terminal_quantities
from .instrument import READ_COLUMNS, Reader, as_terminal, has_read, read_names

#: ∫ y dx by the trapezoidal rule: numpy 2's name (numpy 1 has only ``trapz``, which
#: numpy 2 deprecates)
trapezoid = np.trapezoid if hasattr(np, "trapezoid") else np.trapz

#: columns of ``waveforms.csv`` (SI units in the names)
WAVEFORM_COLUMNS = ["time_s", "gap_m", "gap_velocity_m_per_s", "table_m",
                    "V_oc_V", "Q_sc_C", "I_sc_A", "C_T_F"]
#: the peak-to-peak quantities and their ``waveforms`` column
PEAK_QUANTITIES = {"V_oc": "V_oc_V", "Q_sc": "Q_sc_C", "I_sc": "I_sc_A"}
#: the column of the voltage read through C_p (``[circuit] parallel_capacitance_pF`` > 0)
READ_COLUMN = "V_read_V"
#: the pre-/post-impact states are sampled this many excitation periods from an impact
IMPACT_OFFSET_PERIODS = 1e-9


# ---------------------------------------------------------------------------
# the run's own time axis
def time_origin(dynamics) -> float:
    """``[initial] time_s`` of ``dynamics`` [s] (its ``time_origin``; 0 without one)."""
    return float(getattr(dynamics, "time_origin", 0.0) or 0.0)


def elapsed_times(dynamics) -> np.ndarray:
    """The output times of ``dynamics`` on the run's own axis, ``t - time_origin`` [s]
    (exact: ``dynamics.elapsed`` when it has one). Every circuit is integrated on this
    axis, so its precision does not depend on the absolute time (at t ~ 1.7e9 s the
    doubles are 2.4e-7 s apart, far coarser than the impact offsets). A long run's
    column sampled on request (:class:`tengfield.dynamics.columns.SampledColumn`: len,
    slices, items) is returned as it is: the streamed stage reads it a chunk at a time."""
    elapsed = getattr(dynamics, "elapsed", None)
    if elapsed is not None:
        return elapsed if _sampled(elapsed) else np.asarray(elapsed, dtype=float)
    return np.asarray(dynamics.t, dtype=float) - time_origin(dynamics)


def _sampled(column) -> bool:
    """A column sampled on request (a long run's): not an array, but sliceable."""
    return not isinstance(column, np.ndarray) and hasattr(column, "chunks") \
        and hasattr(column, "__len__")


def sample_elapsed(dynamics, elapsed):
    """(gap, gap velocity, table) of ``dynamics`` at ``elapsed`` times [s] after its origin."""
    sampler = getattr(dynamics, "sample_elapsed", None)
    if sampler is not None:
        return sampler(elapsed)
    return dynamics.sample(np.asarray(elapsed, dtype=float) + time_origin(dynamics))


def impact_elapsed(dynamics, start: float, end: float) -> np.ndarray:
    """:func:`impact_times` on the run's own axis (``start``, ``end`` and the result in
    seconds after ``time_origin``). The stored impact times are absolute (rounded to the
    doubles near ``time_origin``); with a non-zero origin each one is put back on the
    exact velocity jump of the trajectory by bisection over those few ulp."""
    origin = time_origin(dynamics)
    if origin == 0.0:
        return impact_times(dynamics, start, end)
    absolute = impact_times(dynamics, -math.inf, math.inf)
    if absolute.size == 0 or not (hasattr(dynamics, "sample")
                                  or hasattr(dynamics, "sample_elapsed")):
        return np.empty(0)
    approx = absolute - origin
    ulp = np.spacing(np.abs(absolute))
    lo, hi = np.maximum(approx - ulp, 0.0), approx + ulp
    _, v_lo, _ = sample_elapsed(dynamics, lo)
    _, v_hi, _ = sample_elapsed(dynamics, hi)
    v_lo, v_hi = np.array(v_lo, dtype=float), np.array(v_hi, dtype=float)
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        active = (mid > lo) & (mid < hi)
        if not active.any():
            break
        _, v_mid, _ = sample_elapsed(dynamics, mid)
        before = np.abs(v_mid - v_lo) <= np.abs(v_mid - v_hi)   # mid is before the jump
        lo = np.where(active & before, mid, lo)
        v_lo = np.where(active & before, v_mid, v_lo)
        hi = np.where(active & ~before, mid, hi)
        v_hi = np.where(active & ~before, v_mid, v_hi)
    times = np.unique(hi)
    return times[(times > start) & (times < end)]


# ---------------------------------------------------------------------------
# waveforms: the device as a source (tengfield.source.Source) at the output samples
def terminal_waveforms(curves, gap, gap_velocity, *, cells: int = 1,
                       parallel_capacitance: float = 0.0, radial=None,
                       radial_velocity=None, times=None) -> dict[str, np.ndarray]:
    """Open-circuit voltage, short-circuit charge and current along a trajectory:
    :func:`tengfield.source.terminal_quantities` (the one definition; its keys
    ``V_oc``, ``V_read``, ``Q_sc``, ``I_sc``, ``C_T``, ``dC_T_dt``). ``curves``: the
    :class:`tengfield.surrogate.Curves` of ONE cell, or None when Q_SC is identically
    zero (then C_T is unknown and NaN); ``cells`` identical cells in parallel read through
    ``parallel_capacitance`` C_p [F]; ``radial``, ``radial_velocity`` for (z, r) curves;
    ``times`` [s] (the run's own axis) where the ball's charge follows its contacts."""
    return terminal_quantities(curves, gap, gap_velocity, cells=cells,
                               parallel_capacitance=parallel_capacitance, radial=radial,
                               radial_velocity=radial_velocity, times=times)


def on_axis(curves) -> tuple:
    """The extra arguments of ``curves``' functions for the ball on the axis: ``(0.0,)``
    (r = 0) for (z, r) curves, none for curves of z alone."""
    return (0.0,) if curves.radial else ()


def terminal_waveforms_zr(curves, gap, gap_velocity, radial, radial_velocity, *,
                          cells: int = 1, parallel_capacitance: float = 0.0) -> dict:
    """:func:`terminal_waveforms` for an off-axis trajectory: ``radial`` r(t) [m] and
    ``radial_velocity`` dr/dt [m/s] at the samples (the name the (z, r) docs use)."""
    return terminal_waveforms(curves, gap, gap_velocity, cells=cells,
                              parallel_capacitance=parallel_capacitance, radial=radial,
                              radial_velocity=radial_velocity)


def scene_terminal_waveforms(scene, curves, gap, gap_velocity, radial=None,
                             radial_velocity=None, *, times=None) -> dict[str, np.ndarray]:
    """:func:`terminal_waveforms` with ``[device] cells`` and ``[circuit]
    parallel_capacitance_pF`` of ``scene`` (``times``: the samples' on the run's axis):
    :meth:`tengfield.source.Source.terminal` of the scene's source."""
    return Source.of_scene(scene, curves).terminal(times, gap, gap_velocity, radial,
                                                   radial_velocity)


def scene_waveforms(scene, dynamics, curves) -> dict[str, np.ndarray]:
    """The ``WAVEFORM_COLUMNS`` of ``dynamics`` (a DynamicsResult or anything with
    ``t, gap, gap_velocity, table``) for ``scene``: time, trajectory and the
    terminal waveforms at the output samples (:meth:`tengfield.source.Source.rows`);
    with ``[circuit] parallel_capacitance_pF`` > 0 also ``V_read_V`` (the voltage read
    through C_p)."""
    t = np.asarray(dynamics.t, dtype=float)
    terminal = Source.of_scene(scene, curves, dynamics).rows()
    return waveform_columns(scene, t, terminal, getattr(dynamics, "table", None))


def waveform_columns(scene, t, terminal: dict, table=None) -> dict[str, np.ndarray]:
    """The ``WAVEFORM_COLUMNS`` (and ``V_read_V`` where the scene reads through C_p) of
    output rows at times ``t`` [s] from a :meth:`tengfield.source.Source.rows` record
    ``terminal`` and the table's displacement ``table`` [m] (None: zeros)."""
    out = {"time_s": t, "gap_m": terminal["gap"],
           "gap_velocity_m_per_s": terminal["gap_velocity"],
           "table_m": np.zeros_like(t) if table is None else np.asarray(table, dtype=float),
           "V_oc_V": terminal["V_oc"], "Q_sc_C": terminal["Q_sc"], "I_sc_A": terminal["I_sc"],
           "C_T_F": terminal["C_T"]}
    if has_read(scene):
        out[READ_COLUMN] = terminal["V_read"]
    return out


def read_instrument(scene, dynamics, waveforms: dict, loaded: bool) -> None:
    """With an ``[instrument]``: ``waveforms``' ``V_read_V`` (the voltage across the
    instrument: the terminal's through C_p, or the circuit's), ``Q_read_C`` and
    ``I_read_A`` become what the instrument records (:mod:`.instrument`); ``loaded``:
    its input resistance loads the open terminal. Without one: nothing changes."""
    if not scene.instrument.given:
        return
    reader = Reader(scene, loaded)
    waveforms.update(reader.read(elapsed_times(dynamics), waveforms, waveforms.get("C_T_F")))


def peak_quantities(scene) -> dict[str, str]:
    """The quantities :func:`terminal_extremes` reports for ``scene`` and their
    ``waveforms`` column: ``PEAK_QUANTITIES`` (+ ``V_read`` with C_p > 0)."""
    out = dict(PEAK_QUANTITIES)
    for name in read_names(scene):
        out[name] = READ_COLUMNS[name][0]
    return out


def impact_names(scene, read_at_samples: bool = False) -> dict[str, str]:
    """``{peak quantity: terminal quantity}`` of the quantities whose extremes are also
    sought just before and after every impact: the terminal's, and each read one the
    reader leaves as the terminal's own (:func:`.instrument.as_terminal`: Q_read and
    I_read with an input resistance alone too, which loads only the voltage; not a
    circuit's voltage, continuous at the impacts). A filtered reading is taken at its
    samples alone."""
    out = {name: name for name in PEAK_QUANTITIES}
    out.update(as_terminal(scene, read_at_samples))
    return out


# ---------------------------------------------------------------------------
# the steady window and the impacts
def steady_start(scene) -> float:
    """Length [s] of the settling before the steady window: ``[run] settle_periods``
    excitation periods (the rule of :func:`tengfield.dynamics.simulate`, whose result
    holds ``window_start`` = ``time_origin`` + this)."""
    return scene.run.settle_periods * scene.excitation.period


def steady_window(times, scene) -> tuple[np.ndarray, str]:
    """Boolean mask of the samples after ``[run] settle_periods`` excitation periods,
    and the rule in words (the whole run when that leaves fewer than 2 samples)."""
    t = np.asarray(times, dtype=float)
    start = t[0] + steady_start(scene)
    mask = t >= start
    whole = np.count_nonzero(mask) < 2
    return (np.ones_like(t, dtype=bool) if whole else mask), _window_rule(scene, t, start, whole)


def steady_window_index(times, scene) -> tuple[int, str]:
    """The first sample of :func:`steady_window` for non-decreasing ``times`` and its rule,
    without an n-sized mask (the streamed stage of a long run; a column sampled on
    request is searched by bisection, a sample at a time)."""
    if _sampled(times):
        import bisect
        t = times
        start = float(t[0]) + steady_start(scene)
        index = bisect.bisect_left(t, start)                # the first t >= start
    else:
        t = np.asarray(times, dtype=float)
        start = t[0] + steady_start(scene)
        index = int(np.searchsorted(t, start, side="left"))   # the first t >= start
    whole = len(t) - index < 2
    return (0 if whole else index), _window_rule(scene, t, start, whole)


def _window_rule(scene, t, start: float, whole: bool) -> str:
    if whole:
        return (f"whole run: settle_periods x period = {start - t[0]:g} s leaves fewer "
                "than 2 samples")
    return f"t >= {start:g} s (after settle_periods = {scene.run.settle_periods} periods)"


def impact_times(dynamics, start: float, end: float) -> np.ndarray:
    """Sorted distinct times [s] of the impacts (velocity jumps) strictly inside (start, end).

    ``dynamics.impacts`` may be :class:`tengfield.dynamics.Impacts`, a record
    array with a ``time`` field, an array whose first column is the time, or
    a list of objects with ``time`` (or ``t``); no ``impacts``: none.
    """
    impacts = getattr(dynamics, "impacts", None)
    if impacts is None:
        return np.empty(0)
    if hasattr(impacts, "time"):                      # tengfield.dynamics.Impacts
        times = np.asarray(impacts.time, dtype=float).reshape(-1)
    elif hasattr(impacts, "dtype") and impacts.dtype.names and "time" in impacts.dtype.names:
        times = np.asarray(impacts["time"], dtype=float)
    elif isinstance(impacts, np.ndarray):
        times = np.asarray(impacts, dtype=float).reshape(len(impacts), -1)[:, 0] \
            if impacts.size else np.empty(0)
    else:
        times = np.asarray([getattr(i, "time", getattr(i, "t", math.nan)) for i in impacts],
                           dtype=float)
    times = times[np.isfinite(times)]
    return np.unique(times[(times > start) & (times < end)])


def impact_states(scene, dynamics, impacts) -> tuple[np.ndarray, ...]:
    """``(gap_before, velocity_before, gap_after, velocity_after)`` at the ``impacts``
    [s], sampled ``IMPACT_OFFSET_PERIODS`` periods before and after each one."""
    return _impact_states(scene, dynamics, np.asarray(impacts, dtype=float)
                          - time_origin(dynamics))


def _impact_states(scene, dynamics, impacts) -> tuple[np.ndarray, ...]:
    """:func:`impact_states` at ``impacts`` on the run's own axis (:func:`elapsed_times`)."""
    if not len(impacts) or not (hasattr(dynamics, "sample")
                                or hasattr(dynamics, "sample_elapsed")):
        empty = np.empty(0)
        return empty, empty, empty, empty
    eps = IMPACT_OFFSET_PERIODS * scene.excitation.period
    gap_pre, vel_pre, _ = sample_elapsed(dynamics, impacts - eps)
    gap_post, vel_post, _ = sample_elapsed(dynamics, impacts + eps)
    return gap_pre, vel_pre, gap_post, vel_post


# ---------------------------------------------------------------------------
# peaks
def extreme_times(scene, dynamics, start: float) -> np.ndarray:
    """Sorted times [s] at which a waveform's extremes after ``start`` are sought:
    the dynamics' output samples from ``start`` on and just before and after
    every impact there (``IMPACT_OFFSET_PERIODS``), the same instants as
    :func:`terminal_peaks` uses."""
    t = np.asarray(dynamics.t, dtype=float)
    t = t[t >= start]
    impacts = impact_times(dynamics, t[0], t[-1]) if t.size else np.empty(0)
    eps = IMPACT_OFFSET_PERIODS * scene.excitation.period
    return np.sort(np.concatenate([t, impacts - eps, impacts + eps]))


def terminal_peaks(scene, dynamics, curves, waveforms: dict | None = None) -> dict[str, float]:
    """Peak-to-peak ``V_oc`` [V], ``Q_sc`` [C], ``I_sc`` [A] (and ``V_read`` [V] with
    C_p > 0) over the steady window: the ``peak_to_peak`` half of
    :func:`terminal_extremes`."""
    return terminal_extremes(scene, dynamics, curves, waveforms)["peak_to_peak"]


def terminal_extremes(scene, dynamics, curves, waveforms: dict | None = None, *,
                      read_at_samples: bool = False) -> dict:
    """``{"peak_to_peak": {...}, "peak": {...}}``: max x - min x and max |x| of ``V_oc``
    [V], ``Q_sc`` [C], ``I_sc`` [A] (and ``V_read`` [V] with C_p > 0) over the steady
    window.

    The extremes are taken over the output samples of the window *and* just
    before and after every impact in it (``IMPACT_OFFSET_PERIODS``), where
    I_SC = (dQ_SC/dz) ż jumps and takes its extremes: the trajectory is exact
    there, so the peaks do not depend on ``[run] sample_rate_hz`` (sampled
    alone, the I_SC peak of the default scene is 3 % low at 20 kHz;
    docs/report.md). ``cells`` and C_p come from ``scene``; ``waveforms``
    (the :func:`scene_waveforms` of the same scene and dynamics) saves
    recomputing the samples. ``read_at_samples``: the ``V_read_V`` column of
    ``waveforms`` is not the terminal's open reading but a load's voltage across
    R || C_p, taken at its samples alone (it is continuous at the impacts).
    """
    if waveforms is None:
        waveforms = scene_waveforms(scene, dynamics, curves)
    # the read columns are there once the instrument has read them (an array reads later)
    quantities = {n: c for n, c in peak_quantities(scene).items() if c in waveforms}
    t = elapsed_times(dynamics)          # the rows of waveforms, on the run's own axis
    mask, _ = steady_window(t, scene)
    values = {name: [np.asarray(waveforms[column])[mask]]
              for name, column in quantities.items()}
    # the quantities of this table only (sweep and report ask before the instrument reads)
    at_impacts = {n: s for n, s in impact_names(scene, read_at_samples).items() if n in values}
    found = impact_values(scene, dynamics, curves, t[mask][0], t[-1], set(at_impacts.values()))
    for name, source in at_impacts.items():
        if source in found:
            values[name].append(found[source])
    out: dict = {"peak_to_peak": {}, "peak": {}}
    for name, v in values.items():
        x = np.concatenate(v)
        out["peak_to_peak"][name] = lumped.peak_to_peak(x)
        out["peak"][name] = float(np.max(np.abs(x))) if x.size else 0.0
    return out


def impact_values(scene, dynamics, curves, start: float, end: float, names) -> dict:
    """``{name: values}`` of the terminal quantities ``names`` (``V_oc``, ``Q_sc``...)
    just before and after every impact in (``start``, ``end``) (the run's own axis),
    where I_SC jumps: the impact half of :func:`terminal_extremes`' instants (empty
    without curves or impacts)."""
    if curves is None:
        return {}
    impacts = impact_elapsed(dynamics, start, end)
    gap_pre, vel_pre, gap_post, vel_post = _impact_states(scene, dynamics, impacts)
    if not gap_pre.size:
        return {}
    eps = IMPACT_OFFSET_PERIODS * scene.excitation.period
    extra = Source.of_scene(scene, curves, dynamics).terminal(
        np.concatenate([impacts - eps, impacts + eps]), np.concatenate([gap_pre, gap_post]),
        np.concatenate([vel_pre, vel_post]))
    return {name: extra[name] for name in names}


def extremes(values) -> tuple[float, float]:
    """(peak-to-peak, peak |x|) of a waveform sampled at the instants of the peak rule
    (:func:`extreme_times`): the numbers :func:`terminal_peaks` reports, and fit's
    ``*_pp`` / ``*_peak`` targets."""
    x = np.asarray(values, dtype=float)
    return lumped.peak_to_peak(x), float(np.max(np.abs(x)))
