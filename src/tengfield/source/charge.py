"""The charge the contacts make: contact electrification of the ball, impact by impact.

Pure physics, SI units, numbers in and numbers out (issue #52; docs/charge.md):

* Hertz (Johnson, *Contact Mechanics*, 1985, §11.4): a sphere of radius R and mass m
  hitting a flat at normal speed v is pressed in by
  ``delta_max = (15 m v^2 / (16 E* sqrt(R)))^(2/5)`` and touches the area
  ``S = pi R delta_max`` (proportional to v^(4/5)), with
  ``1/E* = (1 - nu_b^2)/E_b + (1 - nu_p^2)/E_p``.
* The condenser model of impact charging (Matsusaka, Ghadiri & Masuda, J. Phys. D 33:2311,
  2000), for a ball that turns between contacts so that its touched patches spread over
  its whole surface A = pi d^2: a contact moves ``dq = eta (S/A)(sigma_eq A - q)`` onto
  the ball (eta in (0, 1]: the fraction of the patch brought to equilibrium); equal
  contacts give ``q_n = sigma_eq A (1 - (1 - eta S/A)^n)`` from an uncharged ball.
* Leakage between contacts (surface and volume conduction, air ions):
  ``q(t) = q(t_n) exp(-(t - t_n)/tau)``; ``tau = 0``: none.
* A cap: ``|q| <= sigma_cap A`` at each contact and separation (the air-breakdown level
  of the band the user picks; ``inf``: none).

Sign convention: ``q`` is the ball's charge [C], of the sign of ``sigma_eq`` (negative
for PTFE); the charge the ball gains at a contact comes from the electrode it touches
(that electrode's charge changes by ``-dq``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: PTFE (the paper's Table 1: E = 0.4 GPa, nu = 0.4) and copper (handbook: 120 GPa, 0.34)
PTFE_MODULUS_PA = 0.4e9
PTFE_POISSON = 0.4
COPPER_MODULUS_PA = 120e9
COPPER_POISSON = 0.34


def effective_modulus(ball_modulus: float, ball_poisson: float,
                      plate_modulus: float, plate_poisson: float) -> float:
    """Hertz's contact modulus E* [Pa]: 1/E* = (1 - nu_b^2)/E_b + (1 - nu_p^2)/E_p."""
    return 1.0 / ((1.0 - ball_poisson ** 2) / ball_modulus
                  + (1.0 - plate_poisson ** 2) / plate_modulus)


def hertz_indentation(mass: float, radius: float, speed, modulus: float):
    """The largest indentation delta_max [m] of a sphere (mass [kg], radius [m]) hitting a
    flat at normal ``speed`` [m/s] (array or number), contact modulus E* [Pa]:
    (15 m v^2 / (16 E* sqrt(R)))^(2/5) (elastic: all the kinetic energy stored)."""
    v = np.abs(np.asarray(speed, dtype=float))
    return (15.0 * mass * v ** 2 / (16.0 * modulus * math.sqrt(radius))) ** 0.4


def hertz_contact_area(mass: float, radius: float, speed, modulus: float):
    """The contact area S = pi R delta_max [m^2] at the largest indentation (the circle of
    radius a = sqrt(R delta_max))."""
    return math.pi * radius * hertz_indentation(mass, radius, speed, modulus)


@dataclass(frozen=True)
class ContactCharging:
    """The condenser law of one ball: ``equilibrium`` sigma_eq [C/m^2] (signed),
    ``efficiency`` eta in (0, 1], ``initial`` sigma at t = 0 [C/m^2], ``leakage_time`` tau
    [s] (0: none), ``cap`` the largest |sigma| [C/m^2] the air holds (inf: none),
    ``ball_area`` A = pi d^2 [m^2]."""
    equilibrium: float
    efficiency: float
    ball_area: float
    initial: float = 0.0
    leakage_time: float = 0.0
    cap: float = math.inf

    def __post_init__(self):
        if not 0.0 < self.efficiency <= 1.0:
            raise ValueError(f"efficiency = {self.efficiency!r}: allowed (0, 1]")
        if not self.ball_area > 0.0:
            raise ValueError(f"ball_area = {self.ball_area!r}: allowed > 0")
        if self.leakage_time < 0.0:
            raise ValueError(f"leakage_time = {self.leakage_time!r}: allowed >= 0 (0: none)")
        if not self.cap > 0.0:
            raise ValueError(f"cap = {self.cap!r}: allowed > 0 (inf: none)")


@dataclass(frozen=True)
class ChargeHistory:
    """The ball's charge over a run: ``times`` [s] of the contacts (sorted) and
    ``after`` [C], its charge just after each; ``before`` just before each;
    ``start`` [C] at ``t0``; ``leakage_time`` tau [s] (0: none). ``at(t)`` gives q(t)."""
    t0: float
    start: float
    times: np.ndarray
    before: np.ndarray
    after: np.ndarray
    leakage_time: float
    cap: float

    @property
    def contacts(self) -> int:
        return int(self.times.size)

    @property
    def gains(self) -> np.ndarray:
        """The charge each contact moved onto the ball [C] (taken from the electrode)."""
        return self.after - self.before

    def at(self, t) -> np.ndarray:
        """q(t) [C]: the charge after the last contact at or before t, leaked since."""
        t = np.asarray(t, dtype=float)
        i = np.searchsorted(self.times, t, side="right") - 1
        last_t = np.where(i >= 0, self.times[np.maximum(i, 0)] if self.times.size else self.t0,
                          self.t0)
        last_q = np.where(i >= 0, self.after[np.maximum(i, 0)] if self.times.size else self.start,
                          self.start)
        if self.leakage_time > 0.0:
            with np.errstate(over="ignore"):   # tau -> 0: all leaked (exp(-inf) = 0)
                last_q = last_q * np.exp(-(t - last_t) / self.leakage_time)
        return np.clip(last_q, -self.cap, self.cap)

    def rise_time(self, fraction: float = 0.9, steady: float | None = None) -> float | None:
        """The time [s] from ``t0`` at which |q| first reaches ``fraction`` of |steady|
        (default: the mean of the last tenth of the contacts), None if never."""
        if steady is None:
            steady = self.steady()
        if steady == 0.0:
            return None
        if abs(self.start) >= fraction * abs(steady):
            return 0.0                    # the ball starts there
        if not self.contacts:
            return None
        reached = np.nonzero(np.abs(self.after) >= fraction * abs(steady))[0]
        return float(self.times[reached[0]] - self.t0) if reached.size else None

    def steady(self) -> float:
        """The charge just after the contacts of the last tenth of the run [C] (mean)."""
        if not self.contacts:
            return float(self.start)
        tail = max(1, self.contacts // 10)
        return float(np.mean(self.after[-tail:]))


def charge_history(law: ContactCharging, times, areas, t0: float = 0.0) -> ChargeHistory:
    """Follow the ball's charge through contacts at ``times`` [s] (sorted) touching
    ``areas`` [m^2] each (Hertz's S at each impact's normal speed): between contacts it
    leaks, at each it moves ``eta (S/A)(sigma_eq A - q)``, and it never exceeds the cap
    (checked at each contact and separation). One pass over the contacts."""
    times = np.asarray(times, dtype=float)
    areas = np.asarray(areas, dtype=float)
    if times.shape != areas.shape:
        raise ValueError(f"times and areas differ in shape: {times.shape} vs {areas.shape}")
    if times.size and np.any(np.diff(times) < 0):
        raise ValueError("contact times must be sorted")
    A = law.ball_area
    q_eq = law.equilibrium * A
    q_cap = law.cap * A
    k = np.minimum(1.0, law.efficiency * areas / A)
    if law.leakage_time > 0.0:
        with np.errstate(over="ignore"):
            decay = np.exp(-np.diff(np.concatenate(([t0], times))) / law.leakage_time)
    else:
        decay = np.ones_like(times)
    from ._kernel import contact_recurrence

    start = min(max(law.initial * A, -q_cap), q_cap)
    before, after = contact_recurrence(decay, k, q_eq, q_cap, start)
    return ChargeHistory(t0=t0, start=start, times=times, before=before, after=after,
                         leakage_time=law.leakage_time, cap=q_cap)


def periodic_charge(n, equilibrium_charge: float, fraction: float):
    """Closed form of equal contacts from an uncharged ball: q_n = q_eq (1 - (1 - k)^n),
    k = eta S/A [C]."""
    return equilibrium_charge * (1.0 - (1.0 - fraction) ** np.asarray(n, dtype=float))


def leaky_steady_charge(equilibrium_charge: float, fraction: float, period: float,
                        leakage_time: float) -> float:
    """The steady charge just after a contact of equal contacts every ``period`` [s] with
    leakage tau [s], exactly: k q_eq / (1 - (1 - k) e^(-T/tau)); for k, T/tau << 1 it is
    q_eq r / (r + 1/tau), r = k / T (the rate of charging)."""
    return fraction * equilibrium_charge / (1.0 - (1.0 - fraction) * math.exp(-period / leakage_time))
