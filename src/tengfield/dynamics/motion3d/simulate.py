"""``simulate_3d(scene)``: the rigid ball in its cell (the tube, the spherical shell),
three-axis table motion. The walls come from the cell
(:func:`tengfield.field.cells.contact_surfaces.contact_surfaces`)."""
from __future__ import annotations

import math
import time as _time
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from ...errors import DynamicsError
from ...scene.constants import G
from .._kernel import table_state_many
from ..excitation import excitation_kind, table_from_scene
from ..regime import classify
from ..result import PLATE_NAMES, DynamicsResult, Impacts
from ..run import run_span, sample_times
from ..table import TableMotion
from . import _kernel
from .contact import KN, EXP, cell_surfaces, surface_parameters

#: RK4 steps per natural period of the stiffest active contact (and per
#: penetration time at the current speed); gives ~30-60 steps per impact.
STEPS_PER_PERIOD = 64
MAX_STEPS_PER_SECOND = 5_000_000


@dataclass
class Motion3DResult(DynamicsResult):
    """A :class:`tengfield.dynamics.DynamicsResult` plus the lateral motion and spin.

    ``gap`` is z of the ball's bottom above the lower electrode (the shell's
    cavity bottom; the ball may penetrate slightly: compliant contact); ``x``,
    ``y`` the centre's offsets [m] from the cell's axis relative to the table,
    ``radial`` = hypot(x, y), ``velocity`` (n, 3) [m/s] relative to the table,
    ``spin`` (n, 3) the angular velocity [rad/s]; ``contacts`` every contact
    episode (all three surfaces: ``surface`` lower, upper and wall for the tube,
    lower, upper and band for the shell), ``wall_contacts`` the number of
    episodes on the third surface (the tube's wall, the shell's band),
    ``steps_per_contact`` the mean number of integrator steps per episode.
    ``sample3d(times)`` gives the full state at any times.
    """

    lateral: ClassVar[bool] = True
    x: np.ndarray = field(default_factory=lambda: np.zeros(0))
    y: np.ndarray = field(default_factory=lambda: np.zeros(0))
    radial: np.ndarray = field(default_factory=lambda: np.zeros(0))
    velocity: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    spin: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    contacts: dict = field(default_factory=dict)
    wall_contacts: int = 0
    steps_per_contact: float = 0.0
    min_steps_per_contact: int = 0
    tube_clearance: float = 0.0         # R_t - R (shell: a - R) [m]: largest radial offset
    surface_names: tuple = ("lower", "upper", "wall")   # the contact surfaces, in order
    cavity_radius: float = 0.0          # the shell's a [m] (0: the tube, a cylinder)
    band_half_height: float = 0.0       # the shell's w/2 [m]: the band's rims above/below
    gravity: np.ndarray = field(default_factory=lambda: np.zeros(3))
    _sampler3d: object = field(default=None, repr=False)

    def sample3d(self, times) -> np.ndarray:
        """(n, 9) states (x, y, z_centre, vx, vy, vz, wx, wy, wz) at ``times`` [s] (SI)."""
        t = np.ascontiguousarray(np.atleast_1d(np.asarray(times, dtype=float)))
        return self._sampler3d(t)

    def dwell_times(self, surface: str = "lower") -> np.ndarray:
        """Durations [s] of the finished contact episodes with ``surface`` (impacts only)."""
        c = self.contacts
        sel = (c["surface"] == surface) & ~c["initial"] & np.isfinite(c["time_out"])
        return c["time_out"][sel] - c["time_in"][sel]

    def _summary_fields(self) -> dict:
        out = super()._summary_fields()
        r = self.radial
        out.update({
            "wall_contacts": int(self.wall_contacts),
            "mean_radial_offset_mm": float(np.mean(r) * 1e3) if r.size else 0.0,
            "max_radial_offset_mm": float(np.max(r) * 1e3) if r.size else 0.0,
            "lateral_excursion_mm": float((np.max(r) - np.min(r)) * 1e3) if r.size else 0.0,
            "max_spin_rad_per_s": float(np.max(np.linalg.norm(self.spin, axis=1)))
            if self.spin.size else 0.0,
            "steps_per_contact": float(self.steps_per_contact),
            "min_steps_per_contact": int(self.min_steps_per_contact),
            "mean_lower_dwell_ms": _mean_ms(self.dwell_times("lower")),
            "mean_upper_dwell_ms": _mean_ms(self.dwell_times("upper")),
        })
        return out


def _mean_ms(x: np.ndarray) -> float | None:
    return float(np.mean(x) * 1e3) if x.size else None


def transfers(episodes: np.ndarray) -> np.ndarray:
    """Episodes that start where another ends (the same step): the ball crossed from one
    surface onto the next without leaving the wall (the shell's band rims)."""
    ends = episodes[np.isfinite(episodes[:, 2]), 2]
    return np.isin(episodes[:, 1], ends)


def gravity_vector(scene) -> np.ndarray:
    """Gravity [m/s^2] in the device frame: tilted by ``tilt`` from -z toward ``tilt_azimuth``."""
    th, ph = scene.device.tilt, scene.device.tilt_azimuth
    return G * np.array([math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), -math.cos(th)])


def lateral_tables(scene) -> tuple[TableMotion, TableMotion]:
    """Table motion along x and y, as the excitation's kind gives it
    (:data:`tengfield.dynamics.excitation.EXCITATIONS`: sine per axis, recorded
    columns of the same CSV (read with the scene), or for random/harmonics the
    fundamental's sine plus noise per axis)."""
    return excitation_kind(scene).lateral(scene)


def _table_args(tx: TableMotion, ty: TableMotion, tz: TableMotion) -> tuple:
    args = []
    for tab in (tx, ty, tz):
        args += [tab.kind, np.ascontiguousarray(tab.params, dtype=float),
                 np.ascontiguousarray(tab.breaks, dtype=float),
                 np.ascontiguousarray(tab.coeffs, dtype=float)]
    return tuple(args)


def integrate_3d(scene, *, t_start: float, t_end: float, position0, velocity0, spin0=(0, 0, 0),
                 gravity=None, tables=None, steps: int = STEPS_PER_PERIOD, rest_start=None):
    """Run the compiled integrator; returns (status, knots, episodes, params, table args).

    ``position0`` is the ball centre [m] (z from the lower electrode face),
    ``velocity0`` [m/s] and ``spin0`` [rad/s] relative to the table;
    ``gravity`` [m/s^2] defaults to the scene's tilted g; ``tables``
    = (x, y, z) :class:`TableMotion` (default: the scene's excitation).
    ``rest_start`` marks an initial contact as resting, not an impact
    (default: when the ball starts touching a surface).
    """
    dev = scene.device
    m = dev.ball_mass
    radius = dev.ball_radius
    g_vec = gravity_vector(scene) if gravity is None else np.asarray(gravity, dtype=float)
    if tables is None:
        tx, ty = lateral_tables(scene)
        tz = table_from_scene(scene)
    else:
        tx, ty, tz = tables
    surfaces = cell_surfaces(scene)
    S = surface_parameters(scene, surfaces)
    P = np.concatenate([[m, radius, 0.4 * m * radius**2, surfaces.height,
                         surfaces.surfaces[2].concave_radius, g_vec[0], g_vec[1], g_vec[2]],
                        surfaces.table().ravel()])
    y0 = np.zeros(_kernel.N_STATE)
    y0[0:3] = position0
    y0[3:6] = velocity0
    y0[6:9] = spin0
    if rest_start is None:
        rest_start = bool(np.any(_kernel.overlaps(y0, P) > 0.0))
    acc_z = abs(g_vec[2]) + tz.acc_bound
    acc_xy = math.hypot(g_vec[0], g_vec[1]) + math.hypot(tx.acc_bound, ty.acc_bound)
    targs = _table_args(tx, ty, tz)
    max_steps = int(MAX_STEPS_PER_SECOND * max(t_end - t_start, 1e-3))
    status, knots, n_k, episodes, n_e = _kernel.run_3d(
        P, S, float(steps), float(t_start), float(t_end), y0, bool(rest_start), max_steps,
        *targs, float(acc_z), float(acc_xy))
    return status, knots[:n_k].copy(), episodes[:n_e].copy(), P, S, targs, surfaces


def resting_position(scene, t0: float, gap0: float, x0: float = 0.0, y0: float = 0.0,
                     gravity=None) -> np.ndarray:
    """Centre of a ball resting on the lower plate at t0: static penetration under its load."""
    dev = scene.device
    S = surface_parameters(scene)
    g_vec = gravity_vector(scene) if gravity is None else np.asarray(gravity, dtype=float)
    _, _, acc = table_from_scene(scene).evaluate(np.array([t0]))
    load = dev.ball_mass * max(-g_vec[2] + float(acc[0]), 0.0)
    delta = (load / S[0, KN]) ** (1.0 / S[0, EXP]) if load > 0 else 0.0
    return np.array([x0, y0, dev.ball_radius - delta + gap0])


def simulate_3d(scene, *, duration: float | None = None, position0=None, velocity0=None,
                spin0=(0.0, 0.0, 0.0), steps: int = STEPS_PER_PERIOD) -> Motion3DResult:
    """3D trajectory of ``scene`` (``[contact] model = "3d"``) -> :class:`Motion3DResult`.

    Starts from ``scene.initial`` on the axis (``position0`` [m] / ``velocity0``
    [m/s] / ``spin0`` [rad/s] override it); a ball starting on the lower plate
    at rest starts at its static penetration (as the soft model). Raises
    :class:`tengfield.errors.DynamicsError` if the step budget is exhausted.
    """
    wall0 = _time.perf_counter()
    dev = scene.device
    period = scene.excitation.period
    duration, t0, t_end = run_span(scene, duration)
    exc = scene.excitation
    if excitation_kind(scene).recorded and (t0 < exc.times[0] or t_end > exc.times[-1]):
        raise DynamicsError(f"the run [{t0:g}, {t_end:g}] s is outside the recorded excitation "
                            f"[{exc.times[0]:g}, {exc.times[-1]:g}] s")
    if position0 is None:
        if scene.initial.gap <= 0.0 and scene.initial.velocity <= 0.0 and velocity0 is None:
            position0 = resting_position(scene, t0, 0.0)
        else:
            position0 = np.array([0.0, 0.0, dev.ball_radius + scene.initial.gap])
    if velocity0 is None:
        velocity0 = np.array([0.0, 0.0, scene.initial.velocity])
    status, knots, episodes, P, S, targs, surfaces = integrate_3d(
        scene, t_start=t0, t_end=t_end, position0=position0, velocity0=velocity0, spin0=spin0,
        steps=steps)
    if status != 0:
        raise DynamicsError(f"3d motion: step budget ({MAX_STEPS_PER_SECOND:g} per second) "
                            f"exhausted near t = {knots[-1, 0]:.9g} s")
    if not np.all(np.isfinite(knots)):   # issue #21: never a NaN trajectory with exit code 0
        bad = int(np.flatnonzero(~np.all(np.isfinite(knots), axis=1))[0])
        raise DynamicsError(f"3d motion: the state became NaN or inf near t = "
                            f"{knots[max(bad - 1, 0), 0]:.9g} s (the drive or the contact "
                            "parameters are beyond what the integrator resolves)")
    n_k = knots.shape[0]
    radius = dev.ball_radius

    def sampler3d(times):
        return _kernel.sample_knots(np.ascontiguousarray(times, dtype=float), knots, n_k, P,
                                    *targs)

    tz_args = targs[8:12]

    def sampler(times):
        """(gap, gap velocity, table) at absolute ``times`` [s] (the kernel's time axis)."""
        st = sampler3d(np.ascontiguousarray(np.atleast_1d(times), dtype=float))
        yz, _, _ = table_state_many(np.ascontiguousarray(np.atleast_1d(times), dtype=float),
                                    *tz_args)
        return st[:, 2] - radius, st[:, 5], yz

    def sampler_elapsed(elapsed):
        """The same at ``elapsed`` [s] after t0 (DynamicsResult's ``_sampler`` convention)."""
        return sampler(t0 + np.asarray(elapsed, dtype=float))

    surface = np.array(surfaces.names)[episodes[:, 0].astype(int)] if episodes.size \
        else np.zeros(0, dtype="<U5")
    contacts = {"surface": surface, "time_in": episodes[:, 1], "time_out": episodes[:, 2],
                "speed_in": episodes[:, 3], "speed_out": episodes[:, 4],
                "steps": episodes[:, 5].astype(np.int64), "initial": episodes[:, 6] > 0}
    impact_sel = (episodes[:, 0] < 2) & (episodes[:, 6] == 0)
    if surfaces.spherical:   # sliding across a rim onto an electrode is no impact
        impact_sel &= ~transfers(episodes)
    ct = episodes[impact_sel, 1]
    cp = episodes[impact_sel, 0].astype(np.int64)
    cvb = episodes[impact_sel, 3]
    cva = episodes[impact_sel, 4]
    window_start = min(t0 + scene.run.settle_periods * period, t_end)
    regime = classify(sampler, ct, cp, cvb, window_start=window_start, t_end=t_end, period=period,
                      stroke=dev.stroke, g=G, upper_stuck=False)
    elapsed = sample_times(scene, duration)
    t = t0 + elapsed
    st = sampler3d(t)
    z, v, yz = sampler(t)
    finished = np.isfinite(episodes[:, 2]) & (episodes[:, 6] == 0)
    steps_done = episodes[finished, 5]
    plates = PLATE_NAMES[cp] if cp.size else np.zeros(0, dtype="<U5")
    return Motion3DResult(
        t=t, gap=z, gap_velocity=v, table=yz,
        impacts=Impacts(ct, plates, cvb, cva), regime=regime, n_events=n_k,
        wall_time=_time.perf_counter() - wall0, model="3d", stroke=dev.stroke, period=period,
        window_start=window_start, time_origin=t0, elapsed=elapsed, _sampler=sampler_elapsed,
        x=st[:, 0], y=st[:, 1], radial=np.hypot(st[:, 0], st[:, 1]), velocity=st[:, 3:6],
        spin=st[:, 6:9], contacts=contacts,
        wall_contacts=int(np.count_nonzero(episodes[:, 0] == 2)),
        steps_per_contact=float(np.mean(steps_done)) if steps_done.size else 0.0,
        min_steps_per_contact=int(np.min(steps_done)) if steps_done.size else 0,
        tube_clearance=surfaces.clearance, surface_names=surfaces.names,
        cavity_radius=surfaces.surfaces[0].concave_radius if surfaces.spherical else 0.0,
        band_half_height=surfaces.surfaces[1].zone[0] if surfaces.spherical else 0.0,
        gravity=np.asarray(P[5:8]),
        _sampler3d=sampler3d)
