"""Limits of work, size and geometry, and the checks that apply them
(docs/stability.md, "bad input and faults").

Work limits (samples, periods, cell-periods, synthesised records) are checked when a
scene is built; the field-only ranges relative to the geometry (domain radius, feature
sizes, mesh size, the contact rule's smallest gap) only where a field stage runs
(:func:`field_problems`, reported by ``check_field``).
"""
from __future__ import annotations

import math

from ..errors import SceneError
from ..errors import show_number  # noqa: F401 - its home is the bottom layer (errors.py)
from .shapes import shape_mesh_features, shape_of
from .shapes.methods import AUTO, FIELD_METHODS, resolve, takes


# -- limits of work, checked at load --
#: Output samples per run, ``duration_s x sample_rate_hz``: 2e7 is 1000 s at 20 kHz
#: (four float64 arrays of 0.64 GB; the CSV holds about 1 GB).
MAX_SAMPLES = 2e7
#: ... and at least this many (a 1e-300 s run, or a 1e-300 Hz sample rate, had none).
MIN_SAMPLES = 2
#: Output samples of an ensemble, ``realisations x duration_s x sample_rate_hz``: each
#: realisation runs the dynamics and the circuit over every sample, as a sweep point
#: does (tengfield.sweeps.MAX_SWEEP_WORK, the same 1e10: ~20 min of circuit alone).
MAX_ENSEMBLE_WORK = 1e10
#: Excitation periods per run, ``duration_s x frequency_hz``: 1e6 is 14 h at 20 Hz.
MAX_PERIODS = 1e6
#: ``[array]`` cells with their own dynamics (a spread set) x excitation periods: the
#: run's peak memory is about 1.4 kB per cell-period (455 cells x 1000 periods: 642 MB,
#: benchmarks/harvest_array_speed.py; the segments are kept twice, per cell and in one
#: bundle), so 5e6 is about 7 GB.
MAX_ARRAY_CELL_PERIODS = 5e6
#: peak bytes per cell-period (the estimate in the message)
ARRAY_BYTES_PER_CELL_PERIOD = 1.4e3
#: Events per period the impact map provisions (its first allocation); with
#: MAX_PERIODS this bounds the first allocation at 1.6e7 events (1.3 GB).
EVENTS_PER_PERIOD_ESTIMATE = 16
#: components of a harmonics excitation
MAX_HARMONICS = 1000
#: samples per period of the highest frequency in a synthesised record
#: (tengfield.dynamics.vibration.SAMPLES_PER_PERIOD; bounds its size at load)
VIBRATION_SAMPLES_PER_PERIOD = 32
#: samples of a synthesised record (its quintic spline: about 1 kB of memory per sample
#: while it is built, so 2e6 samples are ~2 GB; 2 s of a 31 kHz band)
MAX_RECORD_SAMPLES = 2e6
#: the record runs this many periods of its lowest frequency past the run's end, and
#: starts this many samples before it (tengfield.dynamics.vibration.PAD_PERIODS,
#: LEAD_SAMPLES)
VIBRATION_PAD_PERIODS = 1.0
VIBRATION_LEAD_SAMPLES = 64
#: half a noise block is this many periods of min(band's lower edge, band's width)
#: (tengfield.dynamics.vibration.BLOCK_PERIODS, noise_block_samples)
VIBRATION_BLOCK_PERIODS = 16
#: samples of one noise block (synthesised whole by an FFT: about 100 bytes per sample,
#: measured: a [0.01, 200] Hz band's 2.0e7-sample blocks took 2.0 GB), so 2e7 is ~2 GB
MAX_NOISE_BLOCK_SAMPLES = 2e7

# -- sizes of the files read --
#: Bytes of a scene file: the default scene is 5 kB; tomllib needs ~130 bytes of memory
#: per byte of text (a 50 MB file took 6.7 GB), so 1 MB bounds a parse at ~150 MB.
MAX_SCENE_BYTES = 1_000_000
#: Nesting of tables and arrays in a scene file ([fit.columns.V] is 3 deep, an inline
#: table of [fit.parameters] 3): deeper structures are refused (tomllib recurses).
MAX_TOML_DEPTH = 8
#: Data rows a recorded excitation needs: the table motion is a quintic spline
#: (``tengfield.dynamics.table.recorded_table``).
MIN_RECORDED_ROWS = 6
#: Bytes and data rows of a recorded excitation (checked before reading): 2e6 rows is
#: 100 s at 20 kHz; the quintic spline and its bounds take ~0.5 kB per row (1 GB), and
#: Python's CSV reader ~2 s per million rows. A 30M-row file exhausted memory after 49 s.
MAX_RECORDED_ROWS = 2_000_000
MAX_RECORDED_BYTES = 200_000_000
#: |displacement| [m] (1 km, the amplitude_mm bound) and |acceleration| [m/s^2] (1e8 g)
#: of a record: the spline's bounds (up to the 4th derivative) stay finite
MAX_RECORDED_DISPLACEMENT = 1e3
MAX_RECORDED_ACCELERATION = 1e9
#: |time| [s] of a record, the [initial] time_s bound (1e12 s: doubles keep 0.1 ms)
MAX_RECORDED_TIME = 1e12
#: a time step below this fraction of the record's median step is refused: far below the
#: data's resolution (a near-duplicate stamp 1e-15 s apart made the spline ring)
MIN_STEP_FRACTION = 1e-3
#: a recorded excitation's time step may be at most this many times its median step: a
#: longer step is a gap (rows missing), where the spline would invent the table's motion
MAX_STEP_FACTOR = 10.0
#: points of a PSD table (psd_file)
MAX_PSD_ROWS = 100000

# -- field-only ranges relative to the geometry (checked by check_field) --
#: ``domain_radius_mm = "auto"``: this factor x the device's bounding radius,
#: rounded up at two significant digits (the paper's device: 2.2 x 8.9 mm -> 20 mm).
DOMAIN_AUTO_FACTOR = 2.2
#: The far-field sphere must exceed 1.2 x (bounding radius + ball offset) ...
DOMAIN_MIN_FACTOR = 1.2
#: ... and stay below 50 x the bounding radius (gmsh/OpenCASCADE fail far beyond).
DOMAIN_MAX_FACTOR = 50.0
#: Every feature (ball, plates, tube wall, electrode) >= 1e-3 x the bounding radius.
FEATURE_MIN_FRACTION = 1e-3
#: Smallest base mesh size as a fraction of the device's smallest feature, per
#: solver (the mesh is graded finer still at rims and gaps). Measured, paper's
#: device, degree 2, one (r, z) solve: 0.5 mm 1.3e4 dofs; 0.15 mm 1.3e5 dofs,
#: 0.4 GB; the limit 0.075 mm 5.1e5 dofs, 78 s, 1.2 GB (dofs ~ h^-2).
MESH_MIN_FRACTION = {"axisymmetric": 1.0 / 20.0, "3d": 1.0 / 4.0}
#: smallest meshed ball-electrode gap, as a fraction of the electrode spacing h (the
#: contact rule of both field solvers, tengfield.field.contact)
MIN_GAP_FRACTION = 2e-3
#: The contact rule meshes ball-electrode gaps down to min_gap and extrapolates
#: from gaps g, 2g, 4g at both plates: the stroke must hold 8 of them.
CONTACT_GAPS_IN_STROKE = 8
#: Smallest length a field mesh may hold [m] (the smallest meshed gap, MIN_GAP_FRACTION x
#: the plate spacing): OpenCASCADE merges points closer than 1e-7 m. Measured, the
#: paper's device divided by k, ball at contact: k = 66 (smallest gap 0.30 µm) meshes as
#: the paper's, k = 75 (0.27 µm) gives gmsh elements dolfinx cannot read, k = 1000 loses
#: the electrodes; 0.5 µm keeps a margin (k <= 40).
MIN_MESHED_LENGTH = 5e-7
#: The default ``[field] mesh_size_mm`` (0.5 mm) resolves the paper's device, whose
#: smallest features are these [m]. Without ``mesh_size_mm`` in the scene, the default
#: size is scaled (:func:`default_mesh_scale`): a device whose features are all k >= 1
#: times the paper's gets the paper's mesh scaled by k (same cost, same relative error);
#: one whose features are all smaller than the paper's (k < 1) gets it scaled by the
#: largest k (the paper's device divided by 30: the paper's mesh divided by 30; the 0.5 mm
#: default left its gaps unresolved and devices /100 and below failed in gmsh); a device
#: with features on both sides of the paper's keeps the default. A ``mesh_size_mm``
#: written in the scene (or passed as an override) is never scaled.
PAPER_FEATURES = {"ball_diameter_mm": 7.0e-3, "electrode_radius_mm": 4.0e-3, "stroke_mm": 3.0e-3}
#: ... and, with dielectric walls (``wall_permittivity != 1``), the walls and the
#: ball's clearance to the tube (plate thickness also under a grounded table)
PAPER_WALL_FEATURES = {"tube_outer_radius_mm - tube_inner_radius_mm": 1.5e-3,
                       "plate_thickness_mm": 2.0e-3,
                       "tube_inner_radius_mm - ball_diameter_mm / 2": 0.5e-3}
#: ... and a spherical shell's band and shell thickness, against the paper's electrode
#: radius and tube wall (the sizes the default mesh resolves there)
PAPER_SHELL_FEATURES = {"electrode_band_mm": 4.0e-3, "shell_thickness_mm": 1.5e-3}


# ---------------------------------------------------------------------------
class SteadyWindowError(SceneError):
    """:func:`check_steady_window`'s refusal, with its numbers (``settle_periods``,
    ``period`` [s], ``duration`` [s]): ``tengfield run`` extends such a run as a sweep
    does (:func:`tengfield.sweeps.extend_for_settling`)."""

    def __init__(self, message: str, settle_periods: int, period: float, duration: float):
        super().__init__(message)
        self.settle_periods, self.period, self.duration = settle_periods, period, duration


def check_steady_window(exc, settle_periods: int, duration: float,
                        name: str = "duration_s") -> None:
    """Refuse a run of ``duration`` [s] that ends before its regime window starts (after
    ``settle_periods`` excitation periods): the same rule for every excitation kind
    ("recorded": frequency_hz is the reference period of the analysis). ``name`` is how
    the message names the duration (a scene key, an option)."""
    settle = settle_periods * exc.period
    if settle >= duration:
        raise SteadyWindowError(
            f"[run] settle_periods = {settle_periods} leaves no steady window: "
            f"settle_periods / frequency_hz = {settle:g} s must be < {name} = {duration:g}"
            + (f" (set [run] duration_s > {settle:g} or settle_periods < "
               f"{duration / exc.period:g}; `tengfield run` with --set extends the run "
               "itself)" if name == "duration_s" else ""),
            settle_periods, exc.period, duration)


def past(value: float, limit: float) -> str:
    """``value`` in 3 digits, or in as many as show it differs from ``limit`` (a value
    just past a limit read "2e+07 samples: allowed <= 2e+07")."""
    text = f"{value:.3g}"
    return text if text != f"{limit:.3g}" else f"{value:.12g}"


def refuse_past(count: float, limit: float, expression: str, noun: str, hint: str,
                key: str = "") -> None:
    """The one bound of a size the user sets (samples, readings): ``count`` up to
    ``limit`` is allowed, the limit itself included (1e-12 of it: rounding of the
    product), past it one SceneError ``{key: }{expression} = {count} {noun}: allowed <=
    {limit} ({hint})`` (``key`` names the key and value the bound is on, when one key is
    to change)."""
    if count > limit * (1.0 + 1e-12):
        raise SceneError(f"{key + ': ' if key else ''}{expression} = {past(count, limit)} "
                         f"{noun}: allowed <= {limit:.3g} ({hint})")


def run_samples(run, duration: float | None = None) -> None:
    """``duration_s x sample_rate_hz`` of a run (``duration``: another span than
    ``[run] duration_s``, e.g. ``simulate(duration=...)``) within [MIN_SAMPLES,
    MAX_SAMPLES]."""
    duration = run.duration if duration is None else duration
    samples = duration * run.sample_rate
    if samples < MIN_SAMPLES:
        raise SceneError(
            f"[run] duration_s x sample_rate_hz = {duration:g} x {run.sample_rate:g} = "
            f"{samples:.3g} samples: allowed >= {MIN_SAMPLES:g} (the run's output needs "
            "samples to report)")
    # 1000 s x 20 kHz is the limit, not past it
    refuse_past(samples, MAX_SAMPLES, f"[run] duration_s x sample_rate_hz = {duration:g} x "
                f"{run.sample_rate:g}", "samples", "lower sample_rate_hz or split the run")


def check_work(exc, run, instrument=None, window_periods: int | None = None) -> None:
    """Refuse runs whose sample, reading or event count would exhaust memory (product
    named). ``window_periods``: the steady window is at most that many periods at the
    run's end (``[charge] window_periods`` of a contact run)."""
    run_samples(run)
    if instrument is not None and instrument.sample_rate > 0.0:
        # the readings of a run are taken (and held) as one array each, as its samples
        rate = instrument.sample_rate
        refuse_past(run.duration * rate, MAX_SAMPLES,
                    f"[run] duration_s x [instrument] sample_rate_hz = {run.duration:g} x "
                    f"{rate:g}", "readings",
                    f"for this run sample_rate_hz <= {MAX_SAMPLES / run.duration:.3g}, or 0: "
                    "a reading at every output sample",
                    key=f"[instrument] sample_rate_hz = {rate:g}")
        check_readings_in_window(exc, run, rate, window_periods)
    periods = run.duration * exc.frequency
    if periods > MAX_PERIODS:
        raise SceneError(
            f"[run] duration_s x [excitation] frequency_hz = {run.duration:g} x "
            f"{exc.frequency:g} = {periods:.3g} excitation periods (about "
            f"{EVENTS_PER_PERIOD_ESTIMATE * periods:.3g} impact-map events at "
            f"{EVENTS_PER_PERIOD_ESTIMATE} per period): allowed <= {MAX_PERIODS:.3g} periods")


#: readings an ``[instrument]`` must take inside the steady window: a peak-to-peak
#: needs two (fewer read a held value: peaks of 0, or of the ball at rest)
MIN_WINDOW_READINGS = 2


def window_readings(start: float, end: float, rate: float) -> int:
    """Readings k / ``rate`` (k = 0, 1, ...: the reader's instants on the run's own axis,
    :class:`tengfield.electrical.instrument.SampleHold`) in [``start``, ``end``] [s]
    (1e-9 of a reading period: rounding, as the reader's)."""
    first = math.ceil(start * rate - 1e-9)
    last = math.floor(end * rate + 1e-9)
    return max(0, last - first + 1)


def check_readings_in_window(exc, run, rate: float, window_periods: int | None = None
                             ) -> None:
    """Refuse an ``[instrument] sample_rate_hz`` that takes fewer than
    :data:`MIN_WINDOW_READINGS` readings in the steady window (after ``[run]
    settle_periods`` periods, to ``duration_s``; at most ``window_periods`` periods long
    when given): its peaks would be a held reading's (0 from the ball at rest) with no
    word. Only when the run has a steady window (:func:`check_steady_window` refuses the
    others first)."""
    start = run.settle_periods * exc.period
    end = run.duration
    if start >= end:
        return
    rule = f"after [run] settle_periods = {run.settle_periods} periods"
    if window_periods is not None and end - start > window_periods * exc.period:
        start = end - window_periods * exc.period
        rule = f"the last [charge] window_periods = {window_periods} periods"
    count = window_readings(start, end, rate)
    if count < MIN_WINDOW_READINGS:
        needed = MIN_WINDOW_READINGS / (end - start)
        raise SceneError(
            f"[instrument] sample_rate_hz = {rate:g}: {count} reading(s) in the steady window "
            f"t = {start:.4g} to {end:.4g} s ({rule}): the read peaks need at least "
            f"{MIN_WINDOW_READINGS}; allowed sample_rate_hz >= {needed:.3g} for this window, "
            "or 0 (a reading at every output sample), or a longer "
            + ("[run] duration_s" if rule.startswith("after") else "[charge] window_periods"))


def check_ensemble_work(run) -> None:
    """Refuse an ensemble whose total samples (``realisations`` x the run's samples)
    pass :data:`MAX_ENSEMBLE_WORK`, naming the keys (before any realisation starts)."""
    samples = run.duration * run.sample_rate
    work = run.realisations * samples
    if run.realisations > 1 and work > MAX_ENSEMBLE_WORK:
        raise SceneError(
            f"[run] realisations x duration_s x sample_rate_hz = {run.realisations} x "
            f"{run.duration:g} x {run.sample_rate:g} = {work:.3g} samples: allowed <= "
            f"{MAX_ENSEMBLE_WORK:.0e} (fewer realisations, a shorter run or a lower "
            "sample rate)")


def _noise_band(exc) -> tuple[float, float] | None:
    """(lower, upper) edge [Hz] of the noise PSD (band_hz or the PSD table), or None."""
    if exc.band:
        return float(exc.band[0]), float(exc.band[1])
    if exc.psd_frequencies is not None:
        return float(exc.psd_frequencies[0]), float(exc.psd_frequencies[-1])
    return None


def _vibration_frequencies(exc) -> list[float]:
    """Every frequency [Hz] the synthesised record spans: the components, the noise band's
    edges and (3D lateral sine of a random kind) the analysis frequency."""
    freqs = [c[0] for c in exc.harmonics]
    band = _noise_band(exc)
    if band is not None:
        freqs += list(band)
    if exc.kind == "random" and (exc.amplitude_x > 0.0 or exc.amplitude_y > 0.0):
        freqs.append(exc.frequency)
    return freqs


def _noise_key(exc) -> str:
    if exc.band:
        return "band_hz = [" + ", ".join(f"{b:g}" for b in exc.band) + "]"
    return f"psd_file = {exc.psd_file!r}"


def check_vibration_work(exc, run) -> None:
    """Refuse a synthesised record that would not fit: the record (the run, one period
    of the lowest frequency after it, 32 samples per period of the highest) must stay
    below MAX_RECORD_SAMPLES, and one noise block (32 periods of the band's lower edge,
    or of its width if narrower, at that step) below MAX_NOISE_BLOCK_SAMPLES."""
    if exc.kind not in ("random", "harmonics") or (exc.kind == "harmonics" and len(exc.harmonics) == 1
                                                    and not exc.has_noise):
        return
    freqs = _vibration_frequencies(exc)
    if not freqs:
        return
    fmax, fmin = max(freqs), min(freqs)
    spp = VIBRATION_SAMPLES_PER_PERIOD
    count = run.duration * spp * fmax
    if not count < MAX_RECORD_SAMPLES:
        raise SceneError(
            f"[run] duration_s x {spp} x the highest excitation "
            f"frequency = {run.duration:g} x {spp} x {fmax:g} Hz = "
            f"{count:.3g} record samples: allowed < {MAX_RECORD_SAMPLES:.0e} (a shorter run "
            "or a lower band)")
    band = _noise_band(exc)
    if band is not None:
        lo, hi = band
        block_f = min(lo, hi - lo)
        block = 2.0 * math.ceil(VIBRATION_BLOCK_PERIODS * spp * fmax / block_f)
        if not block <= MAX_NOISE_BLOCK_SAMPLES:
            what = "lower edge" if block_f == lo else "width"
            ratio = MAX_NOISE_BLOCK_SAMPLES / (2 * VIBRATION_BLOCK_PERIODS * spp)
            raise SceneError(
                f"[excitation] {_noise_key(exc)}: the noise is synthesised in blocks of "
                f"{2 * VIBRATION_BLOCK_PERIODS} periods of the band's {what} ({block_f:g} Hz) "
                f"sampled {spp} times per period of the highest frequency ({fmax:g} Hz): "
                f"{block:.3g} samples: allowed <= {MAX_NOISE_BLOCK_SAMPLES:.0e} (highest "
                f"frequency / min(lower edge, width) <= {ratio:.3g}; here {fmax / block_f:.3g})")
    padded = (run.duration + VIBRATION_PAD_PERIODS / fmin) * spp * fmax + VIBRATION_LEAD_SAMPLES
    if not padded < MAX_RECORD_SAMPLES:
        lowest = (_noise_key(exc) if band is not None and fmin == band[0]
                  else "frequency_hz = [" + ", ".join(f"{c[0]:g}" for c in exc.harmonics) + "]"
                  if exc.harmonics else f"frequency_hz = {exc.frequency:g}")
        raise SceneError(
            f"[excitation] {lowest}: the synthesised record spans the run and one period "
            f"of the lowest frequency ({fmin:g} Hz) after it, sampled {spp} times per period "
            f"of the highest ({fmax:g} Hz): ({run.duration:g} s + 1 / {fmin:g} Hz) x {spp} x "
            f"{fmax:g} Hz = {padded:.3g} samples: allowed < {MAX_RECORD_SAMPLES:.0e} (raise "
            "the lowest frequency or lower the highest)")


def check_array_work(arr, exc, run) -> None:
    """Refuse an ``[array]`` whose cells' trajectories would not fit in memory: every cell
    of a spread set has its own dynamics, kept for the electrical stage (identical cells
    share one)."""
    spread = arr.phase_spread > 0 or arr.restitution_spread > 0 or arr.velocity_spread > 0
    if arr.cells == 0 or not spread:
        return
    cell_periods = arr.cells * run.duration * exc.frequency
    if cell_periods > MAX_ARRAY_CELL_PERIODS:
        raise SceneError(
            f"[array] cells x [run] duration_s x [excitation] frequency_hz = {arr.cells} x "
            f"{run.duration:g} x {exc.frequency:g} = {cell_periods:.3g} cell-periods: allowed "
            f"<= {MAX_ARRAY_CELL_PERIODS:.0e} (each cell keeps its trajectory: about "
            f"{cell_periods * ARRAY_BYTES_PER_CELL_PERIOD / 1e9:.3g} GB here; fewer cells or "
            "a shorter run)")


# ---------------------------------------------------------------------------
def _round_up_2(x: float) -> float:
    """``x`` > 0 rounded up at two significant digits (19.58 -> 20, 0.0213 -> 0.022)."""
    exp = math.floor(math.log10(x)) - 1
    return float(f"{math.ceil(x / 10.0**exp - 1e-9)}e{exp}")


def auto_domain_radius(device, offset: float = 0.0) -> float:
    """``[field] domain_radius_mm = "auto"`` [m]: ``DOMAIN_AUTO_FACTOR`` x the
    device's bounding radius (at least 1.3 x (bounding radius + ball offset)),
    rounded up at two significant digits in mm; 20 mm for the paper's device."""
    b = device.bounding_radius
    return 1e-3 * _round_up_2(1e3 * max(DOMAIN_AUTO_FACTOR * b, 1.3 * (b + offset)))


def mesh_features(device, environment: str = "free-space") -> dict[str, float]:
    """The features [m] a mesh of ``device`` must resolve, by scene key (see
    :data:`PAPER_FEATURES`; a spherical shell's: :func:`shapes.shape_mesh_features`)."""
    shaped = shape_mesh_features(device)
    if shaped is not None:
        return shaped
    features = {"ball_diameter_mm": device.ball_diameter,
                "electrode_radius_mm": device.electrode_radius, "stroke_mm": device.stroke}
    walls = device.wall_permittivity != 1.0
    if walls:
        features["tube_outer_radius_mm - tube_inner_radius_mm"] = \
            device.tube_outer_radius - device.tube_inner_radius
        features["tube_inner_radius_mm - ball_diameter_mm / 2"] = \
            device.tube_inner_radius - device.ball_radius
    if walls or environment == "grounded-table":
        features["plate_thickness_mm"] = device.plate_thickness
    return features


def default_mesh_scale(device, fld) -> float:
    """Factor on the default ``mesh_size_mm`` from the ratios ``feature_i / paper_i`` over
    :func:`mesh_features`: the smallest when all are >= 1, the largest when all are < 1,
    else 1 (1.0 exactly for the paper's device)."""
    paper = {**PAPER_FEATURES, **PAPER_WALL_FEATURES, **PAPER_SHELL_FEATURES}
    ratios = [size / paper[key] for key, size in mesh_features(device, fld.environment).items()]
    if min(ratios) >= 1.0:
        return min(ratios)
    if max(ratios) < 1.0:
        return max(ratios)
    return 1.0


def field_problems(dev, fld, *, explicit: set[str]) -> list[str]:
    """Field-only problems: ranges relative to the geometry that a mesh needs
    (``explicit``: the [field] keys written in the scene)."""
    problems = []
    b = dev.bounding_radius
    b_mm = b * 1e3
    max_offset = shape_of(dev.shape).max_offset(dev)
    if fld.ball_offset > max_offset + 1e-15:
        problems.append(
            f"[field] ball_offset_mm = {show_number(fld.ball_offset * 1e3, max_offset * 1e3)} "
            "is out of range: allowed "
            f"[0, {max_offset * 1e3:g}] mm (the ball must stay inside the "
            f"{shape_of(dev.shape).enclosure})")
    if fld.method in FIELD_METHODS and not takes(fld.method, fld.ball_offset):
        problems.append(f"[field] method = {fld.method!r} needs ball_offset_mm = 0; "
                        "use method = '3d' or 'auto' for an off-axis ball")
    how = "" if "domain_radius_mm" in explicit else " ('auto')"
    lowest = DOMAIN_MIN_FACTOR * (b + fld.ball_offset)
    if fld.domain_radius <= lowest:
        problems.append(
            f"[field] domain_radius_mm = {fld.domain_radius * 1e3:g}{how} is too small: it must "
            f"exceed {lowest * 1e3:.3g} mm ({DOMAIN_MIN_FACTOR:g} x the device's bounding radius "
            "+ ball offset)")
    if fld.domain_radius > DOMAIN_MAX_FACTOR * b:
        problems.append(
            f"[field] domain_radius_mm = {fld.domain_radius * 1e3:g} is too large for this "
            f"device: allowed <= {DOMAIN_MAX_FACTOR * b_mm:.3g} mm ({DOMAIN_MAX_FACTOR:g} x the "
            f"bounding radius {b_mm:.3g} mm); 'auto' picks one")
    smallest = FEATURE_MIN_FRACTION * b
    features = [("ball_diameter_mm", dev.ball_diameter),
                ("plate_thickness_mm", dev.plate_thickness),
                ("electrode_radius_mm", dev.electrode_radius),
                ("tube_outer_radius_mm - tube_inner_radius_mm",
                 dev.tube_outer_radius - dev.tube_inner_radius)]
    shaped = shape_mesh_features(dev)
    if shaped is not None:   # the shape's own features (the stroke is added below)
        features = [(key, size) for key, size in shaped.items() if key != "stroke_mm"]
    feature_key, feature = min(features + [("stroke_mm", dev.stroke)], key=lambda kv: kv[1])
    for key, size in features:
        if size < smallest:
            problems.append(
                f"[device] {key} = {size * 1e3:.3g} is too small for a field mesh: allowed >= "
                f"{smallest * 1e3:.3g} mm ({FEATURE_MIN_FRACTION:g} x the device's bounding "
                f"radius {b_mm:.3g} mm)")
    gaps = CONTACT_GAPS_IN_STROKE * MIN_GAP_FRACTION * dev.plate_spacing
    if dev.stroke < gaps * (1 - 1e-12):
        # stroke >= n f (d + stroke)  <=>  stroke >= n f d / (1 - n f)
        nf = CONTACT_GAPS_IN_STROKE * MIN_GAP_FRACTION
        need = nf * dev.ball_diameter / (1.0 - nf)
        problems.append(
            f"[device] stroke_mm = {dev.stroke * 1e3:g} is too small for a field solve: allowed >= "
            f"{need * 1e3:.3g} mm ({CONTACT_GAPS_IN_STROKE} x the smallest meshed gap, "
            f"{MIN_GAP_FRACTION:g} x the plate spacing); dynamics-only runs accept it")
    spacing = dev.plate_spacing
    if MIN_GAP_FRACTION * spacing < MIN_MESHED_LENGTH * (1 - 1e-12):
        problems.append(
            f"[device] ball_diameter_mm + stroke_mm = {spacing * 1e3:.3g} mm is too small for a "
            f"field solve: allowed >= {MIN_MESHED_LENGTH / MIN_GAP_FRACTION * 1e3:.3g} mm (the "
            f"smallest meshed gap, {MIN_GAP_FRACTION:g} x that, must be >= "
            f"{MIN_MESHED_LENGTH * 1e6:g} µm for gmsh's geometry); dynamics-only runs accept it")
    method = fld.method
    if method == AUTO:   # kept: as tengfield.field.resolve_method, through the shape's table
        method = resolve(shape_of(dev.shape).field_methods, method, fld.ball_offset)
    finest = MESH_MIN_FRACTION[method] * feature
    # the size the mesher uses: as written, or the default scaled by the smallest feature
    mesh_size = fld.mesh_size if "mesh_size_mm" in explicit \
        else fld.mesh_size * default_mesh_scale(dev, fld)
    if mesh_size < finest * (1 - 1e-12):
        problems.append(
            f"[field] mesh_size_mm = {mesh_size * 1e3:g} is too fine for this device: "
            f"allowed >= {finest * 1e3:.3g} mm (1/{1 / MESH_MIN_FRACTION[method]:g} of the "
            f"smallest feature, [device] {feature_key} = {feature * 1e3:.3g} mm, for the "
            f"{method} solver; finer meshes exceed memory)")
    return problems


class RefusedField:
    """Stands in for :class:`~tengfield.scene.model.Field` when ``[field]`` values are bad: a dynamics-only
    run never looks at them, and any use of one raises the :class:`SceneError`."""
    __slots__ = ("problems",)

    def __init__(self, problems: tuple[str, ...]):
        object.__setattr__(self, "problems", tuple(problems))

    def __getattr__(self, name):
        if name.startswith("__"):
            raise AttributeError(name)
        raise SceneError("; ".join(self.problems))

    def __setattr__(self, name, value):
        raise AttributeError("a scene's field settings are read-only")

    def __reduce__(self):   # pickled for worker processes (map, sweep)
        return (RefusedField, (self.problems,))

    def __eq__(self, other):
        return isinstance(other, RefusedField) and other.problems == self.problems

    def __hash__(self):
        return hash(self.problems)

    def __repr__(self):
        return f"_RefusedField({self.problems!r})"
