"""Soft contact (the paper's Eq. 1): a linear spring-dashpot at each plate.

Relative coordinates as everywhere (z = gap, v = dz/dt relative to the
table). With m the ball mass,

    m z'' = -m g - m y''(t) + F(z, v),
    F = -k z - c v                 if z < 0          (lower plate)
    F = -k (z - dh) - c v          if z > dh         (upper plate)
    F = 0                          otherwise,

``k = scene.contact.stiffness`` and ``c = 2 zeta sqrt(m k)`` with
``zeta = -ln e / sqrt(ln^2 e + pi^2)`` (Eq. 3), for which an isolated
contact has restitution exactly e. The force is used as written in Eq. 1
(the dashpot may pull briefly before the ball leaves the plate).

Each phase (free, lower contact, upper contact) has a smooth right-hand
side and is integrated by SciPy's stiff ``Radau`` solver until an event
(contact entry or exit) ends it; the next phase restarts there. The
penetration (z < 0 or z > dh) is part of the result, so ``gap`` may leave
[0, dh] by about m (g + |y''|) / k.
"""
from __future__ import annotations

import math
import time as _time

import numpy as np

from ..errors import DynamicsError
from ..scene.constants import G
from .result import DynamicsResult
from .run import prepare_run, run_result
from ._kernel import PPOLY, SINE
from .table import TableMotion

FREE, IN_LOWER, IN_UPPER = 0, 1, 2

#: The soft model refuses a stiffness whose estimated penetration exceeds this
#: fraction of the stroke (the ball would pass through the plate).
MAX_PENETRATION_FRACTION = 0.1
#: Runs of the soft model longer than this many excitation periods are refused.
MAX_SOFT_PERIODS = 100_000


def penetration_estimate(mass: float, stiffness: float, acc_bound: float, stroke: float,
                         g: float = G) -> float:
    """Largest penetration [m] to expect from a linear contact of stiffness k [N/m].

    The larger of the static sink under the largest pressing acceleration,
    ``m (g + max|y''|) / k``, and the dynamic one of an impact at the speed of a
    fall through the stroke under that acceleration, ``v sqrt(m / k)`` with
    ``v = sqrt(2 (g + max|y''|) stroke)`` (an undamped spring stops a ball of
    speed v within v / omega_c).
    """
    pressing = g + acc_bound
    static = mass * pressing / stiffness
    dynamic = math.sqrt(2.0 * pressing * stroke) * math.sqrt(mass / stiffness)
    return max(static, dynamic)


def check_stiffness(contact, device, table: TableMotion, stroke: float) -> None:
    """Refuse a soft contact so weak that the ball would sink through the plate."""
    from ..errors import SceneError

    mass = device.ball_mass
    k = contact.stiffness
    depth = penetration_estimate(mass, k, table.acc_bound, stroke)
    allowed = MAX_PENETRATION_FRACTION * stroke
    if depth > allowed:
        # both estimates scale as 1/k or 1/sqrt(k): solve each for the allowed depth
        pressing = G + table.acc_bound
        need = 1.01 * max(mass * pressing / allowed, 2.0 * pressing * stroke * mass / allowed**2)
        raise SceneError(
            f"[contact] stiffness_N_per_m = {k:g}: the ball would sink about "
            f"{depth * 1e3:.3g} mm into a plate (m (g + max|y''|) / k or v sqrt(m / k)), more "
            f"than {MAX_PENETRATION_FRACTION:g} x the stroke = {allowed * 1e3:.3g} mm; "
            f"allowed >= {need:.3g} N/m for this ball, stroke and drive")


def damping_ratio(restitution: float) -> float:
    """zeta of Eq. (3): the linear contact with this damping ratio has restitution e."""
    if restitution <= 0.0:
        return 1.0
    if restitution >= 1.0:
        return 0.0
    ln_e = math.log(restitution)
    return -ln_e / math.sqrt(ln_e**2 + math.pi**2)


def damping_coefficient(restitution: float, mass: float, stiffness: float) -> float:
    """c = 2 zeta sqrt(m k) [N s/m] (Eq. 3); mass [kg], stiffness [N/m]."""
    return 2.0 * damping_ratio(restitution) * math.sqrt(mass * stiffness)


class SoftTrajectory:
    """Dense output of the phases: callable ``(times) -> (z, v, y)``."""

    def __init__(self, table: TableMotion):
        self.table = table
        self.starts: list[float] = []
        self.solutions = []

    def add(self, t0: float, sol) -> None:
        self.starts.append(t0)
        self.solutions.append(sol)

    def cover(self, lo: float, hi: float) -> tuple[float, float]:
        """An interval [a, b] [s] holding every solver step that meets [lo, hi] whole,
        with one step to spare on each side: sampling all samples of [a, b] evaluates each
        of those steps' interpolants on the same points as sampling the whole record (the
        interpolant's matrix product gives the same bits; a long run's columns are sampled
        a range at a time, :mod:`.columns`)."""
        bounds = getattr(self, "_bounds", None)
        if bounds is None or bounds.size == 0:
            bounds = self._bounds = np.unique(np.concatenate(
                [np.asarray(sol.ts, dtype=float) for sol in self.solutions]
                + [np.asarray(self.starts, dtype=float)]))
        i = int(np.searchsorted(bounds, lo, side="right")) - 2
        j = int(np.searchsorted(bounds, hi, side="left")) + 1
        a = bounds[i] if i >= 0 else -np.inf
        b = bounds[j] if j < bounds.size else np.inf
        return float(a), float(b)

    def __call__(self, times):
        t = np.atleast_1d(np.asarray(times, dtype=float))
        z = np.empty(t.size)
        v = np.empty(t.size)
        idx = np.clip(np.searchsorted(np.asarray(self.starts), t, side="right") - 1, 0, None)
        for k in np.unique(idx):
            sel = idx == k
            zv = self.solutions[k](t[sel])
            z[sel] = zv[0]
            v[sel] = zv[1]
        y, _, _ = self.table.evaluate(t)
        return z, v, y


def integrate_soft(table: TableMotion, stroke: float, restitution: float, mass: float,
                   stiffness: float, *, t_start: float, t_end: float, gap0: float = 0.0,
                   velocity0: float = 0.0, period: float, g: float = G, rtol: float = 1e-8,
                   max_phases_per_period: int = 10_000):
    """Integrate the soft-contact model; returns (trajectory, contacts, n_phases).

    contacts = (entry time [s], plate 0/1, entry speed [m/s], exit speed [m/s]).
    """
    from scipy.integrate import solve_ivp

    omega_c = math.sqrt(stiffness / mass)
    c_over_m = damping_coefficient(restitution, mass, stiffness) / mass
    k_over_m = omega_c**2
    # the step control resolves the contact oscillation (period 2 pi / omega_c);
    # the cap only keeps event detection from striding over a table period
    max_step = 0.02 * period

    if table.kind == SINE:
        amp_w2 = table.params[0] * table.params[1] ** 2
        w, ph = table.params[1], table.params[2]

        def ydd(t):
            return -amp_w2 * math.sin(w * t + ph)
    else:
        def ydd(t):
            return table.evaluate(np.array([t]))[2][0]

    def rhs_free(t, s):
        return [s[1], -g - ydd(t)]

    def rhs_lower(t, s):
        return [s[1], -g - ydd(t) - k_over_m * s[0] - c_over_m * s[1]]

    def rhs_upper(t, s):
        return [s[1], -g - ydd(t) - k_over_m * (s[0] - stroke) - c_over_m * s[1]]

    def hit_lower(t, s):
        return s[0]

    def hit_upper(t, s):
        return s[0] - stroke

    hit_lower.terminal = hit_upper.terminal = True
    rhs = {FREE: rhs_free, IN_LOWER: rhs_lower, IN_UPPER: rhs_upper}
    jac_contact = np.array([[0.0, 1.0], [-k_over_m, -c_over_m]])
    jacobian = {FREE: np.array([[0.0, 1.0], [0.0, 0.0]]), IN_LOWER: jac_contact,
                IN_UPPER: jac_contact}

    # absolute tolerances scaled by the stroke and the speed of a fall through it
    atol = rtol * np.array([stroke, math.sqrt(2.0 * g * stroke)])
    traj = SoftTrajectory(table)
    contacts: list[list[float]] = []
    t = t_start
    state = np.array([gap0, velocity0], dtype=float)
    phase = FREE
    open_contact = False      # is contacts[-1] the contact the ball is in now?
    if gap0 <= 0.0 and velocity0 <= 0.0:
        # resting on the lower plate: start in contact (static penetration); an
        # initial resting contact is not an impact and is not listed
        phase = IN_LOWER
        state[0] = -mass * max(g + ydd(t), 0.0) / stiffness
    n_phases = 0
    while t < t_end:
        n_phases += 1
        if n_phases > max_phases_per_period * ((t - t_start) / period + 1.0):
            raise DynamicsError(f"soft contact: more than {max_phases_per_period} contact phases "
                                f"per period near t = {t:.9g} s")
        if phase == FREE:
            hit_lower.direction = -1.0
            hit_upper.direction = 1.0
            events = [hit_lower, hit_upper]
        elif phase == IN_LOWER:
            hit_lower.direction = 1.0
            events = [hit_lower]
        else:
            hit_upper.direction = -1.0
            events = [hit_upper]
        sol = solve_ivp(rhs[phase], (t, t_end), state, method="Radau", jac=jacobian[phase],
                        events=events,
                        dense_output=True, rtol=rtol, atol=atol,
                        max_step=max_step)
        if sol.status < 0:
            raise DynamicsError(f"soft contact: the stiff solver failed near t = {t:.9g} s: "
                                f"{sol.message}")
        traj.add(t, sol.sol)
        if sol.status == 0:
            break
        # which event fired
        fired = [k for k, te in enumerate(sol.t_events) if te.size]
        k = fired[0]
        t_new = float(sol.t_events[k][0])
        state = np.array(sol.y_events[k][0], dtype=float)
        t = t_new
        if phase == FREE:
            plate = 0 if events[k] is hit_lower else 1
            state[0] = 0.0 if plate == 0 else stroke
            contacts.append([t, plate, abs(state[1]), math.nan])
            open_contact = True
            phase = IN_LOWER if plate == 0 else IN_UPPER
        else:
            state[0] = 0.0 if phase == IN_LOWER else stroke
            if open_contact:
                contacts[-1][3] = abs(state[1])
            open_contact = False
            phase = FREE
    arr = np.array(contacts, dtype=float).reshape(-1, 4)
    return traj, (arr[:, 0], arr[:, 1].astype(np.int64), arr[:, 2], arr[:, 3]), n_phases


def simulate_soft(scene, *, duration: float | None = None) -> DynamicsResult:
    """Soft-contact trajectory of ``scene`` (see :func:`tengfield.dynamics.simulate`)."""
    wall0 = _time.perf_counter()
    duration, t0, table = prepare_run(scene, duration)      # integrate on t - t0
    period = scene.excitation.period
    if table.kind == PPOLY and (0.0 < table.t_first or duration > table.t_last):
        raise DynamicsError(
            f"the run [{t0:.17g}, {t0 + duration:.17g}] s is outside the recorded excitation "
            f"[{table.t_first + t0:.17g}, {table.t_last + t0:.17g}] s")
    if duration / period > MAX_SOFT_PERIODS:
        raise DynamicsError(
            f"duration x frequency = {duration / period:.3g} excitation periods: allowed <= "
            f"{MAX_SOFT_PERIODS:.0e} with [contact] model = 'soft' (shorten [run] duration_s)")
    stroke = scene.device.stroke
    check_stiffness(scene.contact, scene.device, table, stroke)
    traj, contacts, n_phases = integrate_soft(
        table, stroke, scene.contact.restitution, scene.device.ball_mass,
        scene.contact.stiffness, t_start=0.0, t_end=duration, gap0=scene.initial.gap,
        velocity0=scene.initial.velocity, period=period)
    return run_result(scene, traj, contacts, n_phases, model="soft", t0=t0, duration=duration,
                      wall0=wall0, upper_stuck=None)
