"""Random and multi-harmonic table motion (pure functions, SI units).

Two excitation kinds beside the sine and the recorded trace:

* **random**: a stationary Gaussian table acceleration with a one-sided
  power spectral density ``S(f)`` [(m/s^2)^2/Hz], given either as a flat band
  (``band_psd``: ``S = a_rms^2 / (f2 - f1)`` on ``[f1, f2]``) or as a table
  (``tabulated_psd``: log-log interpolation between the given points, in
  (m/s^2)^2/Hz or g^2/Hz with g = 9.80665 m/s^2). ``S`` is zero outside its
  band: below the band's lower edge (or the table's first frequency) the
  signal is high-passed by construction, so the displacement has no drift.
* **harmonics**: ``y = sum_i A_i sin(2 pi f_i t + phi_i)``, optionally with
  random noise on top.

Synthesis (spectral representation, e.g. Shinozuka & Deodatis, Appl. Mech.
Rev. 44:191, 1991, with Gaussian rather than random-phase coefficients so the
process is Gaussian): on the FFT grid ``f_k = k / T`` of a record of length
``T``,

    a(t) = sum_k sigma_k (alpha_k cos 2 pi f_k t + beta_k sin 2 pi f_k t),
    sigma_k = sqrt(S(f_k) df),   alpha_k, beta_k ~ N(0, 1) from ``seed``,

whose variance is ``sum_k S(f_k) df`` (the requested mean square, up to the
quadrature of S on the grid). The noise is made of such periodic blocks, each 32
periods of the band's lowest frequency (or of its width, if narrower) long with its own seed, crossfaded with
power-complementary weights (:func:`noise_signal`), so a realisation is a function of
the seed and of the run's own clock only: a longer run extends it, never changes it. The displacement is the exact double integral
of each term, ``-a_k / (2 pi f_k)^2``, so displacement, velocity and
acceleration are consistent and periodic over ``T`` (no drift). The table
motion the kernel sees is the C^4 quintic spline through the displacement
samples (:func:`tengfield.dynamics.table.recorded_table`), with the
guaranteed bound ``acc_bound >= max |y''|`` that the event-exact step uses.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import DynamicsError
from .table import TableMotion, recorded_table, sine_phase_at, sine_table

#: standard gravity [m/s^2] (g^2/Hz PSD tables)
STANDARD_GRAVITY = 9.80665
#: samples per period of the highest frequency in the synthesised record: the
#: quintic spline's acceleration then matches the synthesised one to ~1e-6
SAMPLES_PER_PERIOD = 32
#: the record extends this many of the lowest-frequency periods past the run's end
PAD_PERIODS = 1.0
#: and starts this many samples before the run (the spline's end conditions
#: disturb its first and last few pieces; 64 samples are 2 periods of the highest
#: frequency, where the disturbance has decayed below 1e-7 of the amplitude)
LEAD_SAMPLES = 64
#: the noise is synthesised in crossfaded blocks of 2 x BLOCK_PERIODS periods of the
#: band's lowest frequency (:func:`noise_signal`), so a realisation does not depend on
#: the length of the run; BLOCK_OFFSET keeps the blocks' seed words non-negative
BLOCK_PERIODS = 16
BLOCK_OFFSET = 1024


@dataclass(frozen=True)
class PSD:
    """One-sided acceleration PSD: ``frequencies`` [Hz] (increasing, > 0) and
    ``values`` [(m/s^2)^2/Hz], interpolated log-log (``flat``: constant on the band)."""
    frequencies: np.ndarray
    values: np.ndarray
    flat: bool = False

    @property
    def band(self) -> tuple[float, float]:
        return float(self.frequencies[0]), float(self.frequencies[-1])

    def __call__(self, f) -> np.ndarray:
        """S(f) [(m/s^2)^2/Hz]; zero outside the band."""
        f = np.asarray(f, dtype=float)
        lo, hi = self.band
        inside = (f >= lo) & (f <= hi)
        out = np.zeros_like(f)
        if self.flat:
            out[inside] = self.values[0]
            return out
        logf = np.log(f[inside])
        with np.errstate(divide="ignore"):
            logs = np.log(self.values)
        s = np.exp(np.interp(logf, np.log(self.frequencies), logs))
        out[inside] = s
        return out

    def scaled(self, rms_acceleration: float) -> "PSD":
        """The same shape with the given rms acceleration [m/s^2]."""
        total = self.mean_square()
        if not total > 0.0:
            raise DynamicsError("a PSD without power cannot be scaled to an rms")
        factor = float(rms_acceleration) ** 2 / total
        return PSD(self.frequencies, self.values * factor, self.flat)

    def mean_square(self) -> float:
        """Integral of S over its band [(m/s^2)^2] (the acceleration's variance): exact,
        segment by segment (:func:`loglog_integral`)."""
        lo, hi = self.band
        if self.flat:
            return float(self.values[0] * (hi - lo))
        return loglog_integral(self.frequencies, self.values)


def loglog_integral(frequencies, values) -> float:
    """Integral of the log-log interpolation of (``frequencies``, ``values``) over the
    table: on each segment ``S = S0 (f / f0)^b``, ``b = ln(S1 / S0) / ln(f1 / f0)``,
    whose integral is ``S0 f0 ((f1 / f0)^(b + 1) - 1) / (b + 1)`` (``S0 f0 ln(f1 / f0)`` at
    b = -1); a segment with a zero end is zero everywhere (log 0 = -inf)."""
    f = np.asarray(frequencies, dtype=float)
    s = np.asarray(values, dtype=float)
    f0, f1, s0, s1 = f[:-1], f[1:], s[:-1], s[1:]
    live = (s0 > 0.0) & (s1 > 0.0)
    if not live.any():
        return 0.0
    f0, f1, s0, s1 = f0[live], f1[live], s0[live], s1[live]
    ratio = np.log(f1 / f0)
    b1 = np.log(s1 / s0) / ratio + 1.0
    # (r^(b+1) - 1) / (b+1) = ratio * expm1(b1 ratio) / (b1 ratio), -> ratio as b1 -> 0
    x = b1 * ratio
    small = np.abs(x) < 1e-12
    factor = np.where(small, ratio, np.expm1(x) / np.where(small, 1.0, b1))
    return float(np.sum(s0 * f0 * factor))


def band_psd(band_hz: tuple[float, float], rms_acceleration: float) -> PSD:
    """Flat PSD on ``band_hz = (f1, f2)`` [Hz] with the given rms acceleration [m/s^2]."""
    f1, f2 = float(band_hz[0]), float(band_hz[1])
    if not 0.0 < f1 < f2:
        raise DynamicsError(f"band_hz = [{f1:g}, {f2:g}]: needs 0 < f1 < f2")
    level = float(rms_acceleration) ** 2 / (f2 - f1)
    return PSD(np.array([f1, f2]), np.array([level, level]), flat=True)


def tabulated_psd(frequencies, values, unit: str = "m2_per_s4_per_hz") -> PSD:
    """PSD from a table: ``frequencies`` [Hz] strictly increasing and > 0, ``values``
    >= 0 in (m/s^2)^2/Hz (``unit = "m2_per_s4_per_hz"``) or g^2/Hz (``"g2_per_hz"``)."""
    f = np.asarray(frequencies, dtype=float)
    v = np.asarray(values, dtype=float)
    if f.ndim != 1 or f.size < 2 or f.shape != v.shape:
        raise DynamicsError("a PSD table needs at least 2 (frequency, value) rows")
    if not (np.all(np.isfinite(f)) and np.all(np.isfinite(v))):
        raise DynamicsError("a PSD table holds NaN or inf")
    if f[0] <= 0.0 or np.any(np.diff(f) <= 0.0):
        raise DynamicsError("PSD frequencies must be > 0 and strictly increasing")
    if np.any(v < 0.0):
        raise DynamicsError("PSD values must be >= 0")
    if unit == "g2_per_hz":
        v = v * STANDARD_GRAVITY**2
    elif unit != "m2_per_s4_per_hz":
        raise DynamicsError(f"PSD unit {unit!r}: allowed 'g2_per_hz', 'm2_per_s4_per_hz'")
    return PSD(f, v)


@dataclass(frozen=True)
class Harmonic:
    """``amplitude`` [m] sin(2 pi ``frequency`` [Hz] t + ``phase`` [rad])."""
    frequency: float
    amplitude: float
    phase: float = 0.0


def record_grid(duration: float, max_frequency: float, min_frequency: float
                ) -> tuple[int, float]:
    """(number of samples M (even), spacing dt [s]) of a record covering ``duration``
    plus padding (LEAD_SAMPLES before the start, PAD_PERIODS of ``min_frequency``
    after the end), sampled SAMPLES_PER_PERIOD times per period of ``max_frequency``."""
    dt = 1.0 / (SAMPLES_PER_PERIOD * max_frequency)
    span = duration + PAD_PERIODS / min_frequency
    m = int(math.ceil(span / dt)) + 1 + LEAD_SAMPLES
    return m + (m % 2), dt


def noise_record(psd: PSD, samples: int, dt: float, seed
                 ) -> tuple[np.ndarray, np.ndarray]:
    """(displacement [m], acceleration [m/s^2]) of one Gaussian realisation on the
    grid ``n dt``, n < ``samples`` (even), periodic over ``samples * dt``."""
    m = int(samples)
    freqs = np.fft.rfftfreq(m, dt)
    df = freqs[1]
    sigma = np.sqrt(psd(freqs) * df)
    sigma[0] = 0.0            # no mean acceleration
    sigma[-1] = 0.0           # no Nyquist term (no sine partner on the grid)
    rng = np.random.default_rng(seed)     # an int or a numpy SeedSequence
    alpha = rng.standard_normal(freqs.size)
    beta = rng.standard_normal(freqs.size)
    acc_coeff = 0.5 * m * sigma * (alpha - 1j * beta)
    omega = 2.0 * np.pi * freqs
    disp_coeff = np.zeros_like(acc_coeff)
    disp_coeff[1:] = -acc_coeff[1:] / omega[1:] ** 2
    return np.fft.irfft(disp_coeff, m), np.fft.irfft(acc_coeff, m)


def noise_block_frequency(band: tuple[float, float]) -> float:
    """The frequency [Hz] whose BLOCK_PERIODS periods make half a noise block: the band's
    lower edge f1, or its width f2 - f1 when narrower. A block is then 2 BLOCK_PERIODS /
    that long, so its FFT grid (spacing 1 / block) puts at least 2 BLOCK_PERIODS = 32
    lines across the band: the realised variance is the requested one up to the edge
    lines (a 2 Hz band at 100 Hz had no line at all on a grid of f1 / 32 and stood still)."""
    lo, hi = float(band[0]), float(band[1])
    return min(lo, hi - lo)


def noise_block_samples(psd: PSD, dt: float) -> int:
    """Samples of one noise block (:func:`noise_signal`, even): ``2 H``, ``H`` =
    BLOCK_PERIODS periods of :func:`noise_block_frequency` at the step ``dt`` [s]."""
    return 2 * int(math.ceil(BLOCK_PERIODS / (noise_block_frequency(psd.band) * dt)))


def noise_signal(psd: PSD, dt: float, seed: int, index: np.ndarray) -> np.ndarray:
    """Displacement [m] of the Gaussian noise at the times ``index * dt`` [s] of the run's
    own clock (``index``: integers, 0 at the run's start), independent of how long a
    record is asked for: a run of 1 s and one of 10 s see the same noise over their
    first second.

    The noise is made of periodic blocks (:func:`noise_record`) of ``2 H`` samples,
    ``H = BLOCK_PERIODS`` periods of the band's lowest frequency (of its width, for a
    band narrower than its lower edge: :func:`noise_block_frequency`), block j centred at
    sample ``j H`` with its own seed ``SeedSequence([seed, j + BLOCK_OFFSET])``, joined
    by power-complementary weights ``cos(pi (n - j H) / (2 H))`` (``w_j^2 + w_(j+1)^2 = 1``:
    independent blocks keep the variance exactly stationary). The weights vary over
    ``H`` samples, slowly against the band (``H f >= 16`` periods): the extra terms of
    ``y''`` they bring (``2 w' y' + w'' y``) are below 1/32 of it in amplitude and
    1e-3 in power.
    """
    idx = np.asarray(index, dtype=np.int64)
    half = noise_block_samples(psd, dt) // 2
    y = np.zeros(idx.size)
    first, last = int(np.floor(idx.min() / half)), int(np.floor(idx.max() / half)) + 1
    for j in range(first, last + 1):
        local = idx - (j - 1) * half
        inside = (local >= 0) & (local <= 2 * half)
        if not inside.any():
            continue
        if j + BLOCK_OFFSET < 0:
            raise DynamicsError("a random excitation cannot start this far before its run")
        block, _ = noise_record(psd, 2 * half, dt,
                                np.random.SeedSequence([int(seed), j + BLOCK_OFFSET]))
        weight = np.cos(0.5 * np.pi * (idx[inside] - j * half) / half)
        y[inside] += weight * block[local[inside] % (2 * half)]
    return y


def vibration_table(*, duration: float, seed: int = 0, harmonics: tuple[Harmonic, ...] = (),
                    psd: PSD | None = None, origin: float = 0.0,
                    start: float = 0.0) -> TableMotion:
    """The table motion of harmonics plus optional Gaussian noise, on the time axis
    ``t - origin`` [s], covering ``[start, start + duration]`` (the harmonics' phases
    refer to absolute time ``t``; the noise realisation depends only on ``seed``, the
    PSD and the sampling step, not on ``duration``: :func:`noise_signal`).

    One harmonic and no noise gives exactly :func:`sine_table` (bit for bit the
    sine excitation). Otherwise the displacement is sampled on the record grid
    (:func:`record_grid`) and turned into the C^4 quintic table spline.
    """
    if not harmonics and psd is None:
        raise DynamicsError("a vibration needs at least one harmonic or a PSD")
    if len(harmonics) == 1 and psd is None:
        h = harmonics[0]
        return sine_table(h.amplitude, 2.0 * math.pi * h.frequency,
                          sine_phase_at(h.frequency, h.phase, origin))
    freqs = [h.frequency for h in harmonics]
    if psd is not None:
        freqs += list(psd.band)
    m, dt = record_grid(duration, max(freqs), min(freqs))
    t = start + (np.arange(m) - LEAD_SAMPLES) * dt
    y = np.zeros(m)
    for h in harmonics:
        y += h.amplitude * np.sin(2.0 * math.pi * h.frequency * t
                                  + sine_phase_at(h.frequency, h.phase, origin))
    if psd is not None:   # on the run's own clock: sample n at start + n dt
        y += noise_signal(psd, dt, seed, np.arange(m) - LEAD_SAMPLES)
    return recorded_table(t, y, "displacement", origin=0.0)


def scene_psd(exc) -> PSD | None:
    """The noise PSD of a scene's ``[excitation]`` (None without noise): a flat band with
    ``rms_acceleration``, or the PSD table (rescaled to ``rms_acceleration`` if > 0)."""
    if exc.band:
        return band_psd(exc.band, exc.rms_acceleration)
    if exc.psd_frequencies is not None:
        psd = tabulated_psd(exc.psd_frequencies, exc.psd_values)
        return psd.scaled(exc.rms_acceleration) if exc.rms_acceleration > 0.0 else psd
    return None


def scene_vibration_table(scene, origin: float = 0.0, *, axis: str = "z") -> TableMotion:
    """The table motion of a random or harmonics ``[excitation]`` along ``axis`` on the
    time axis ``t - origin`` [s], covering the run (``[initial] time_s`` to
    ``+ [run] duration_s``). Vertical: the components plus the noise. Lateral (3D
    model): ``amplitude_x_mm``/``phase_x_deg`` at the fundamental (as for a sine) plus,
    with ``rms_acceleration_x_m_per_s2`` > 0, noise of the same PSD shape at that rms,
    from its own seed (the realisation's seed spawned per axis)."""
    exc = scene.excitation
    start = scene.initial.time - origin
    psd = scene_psd(exc)
    if axis == "z":
        harmonics = tuple(Harmonic(f, a, p) for f, a, p in exc.harmonics)
        seed = exc.seed
    else:
        amplitude = exc.amplitude_x if axis == "x" else exc.amplitude_y
        phase = exc.phase_x if axis == "x" else exc.phase_y
        rms = exc.rms_acceleration_x if axis == "x" else exc.rms_acceleration_y
        harmonics = (Harmonic(exc.frequency, amplitude, phase),) if amplitude > 0.0 else ()
        psd = psd.scaled(rms) if (psd is not None and rms > 0.0) else None
        seed = int(np.random.SeedSequence([exc.seed, 1 if axis == "x" else 2])
                   .generate_state(1, dtype=np.uint32)[0])
        if not harmonics and psd is None:
            return sine_table(0.0, exc.omega, 0.0)
    return vibration_table(duration=scene.run.duration, seed=seed, harmonics=harmonics,
                           psd=psd, origin=origin, start=start)
