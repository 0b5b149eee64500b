"""The yardstick of the compiled impact map: the same guaranteed-step algorithm in plain
Python with SciPy's brentq for the contact time (issue #9.2).

Sine table, rigid plates, Newton restitution, sticking with exact lift-off/release
times and the Zeno collapse of chatter, as in tengfield.dynamics._kernel, but:
each free flight marches with the global contact-free step (|z''| <= g + A w^2)
until the ball is within CLOSE of a plate, then brackets the contact and finds it
with ``scipy.optimize.brentq``.

    .venv/bin/python benchmarks/dynamics_python_yardstick.py [--duration-s 20]

prints impacts per second of this loop and of ``tengfield.dynamics.simulate`` on the
single-plate scene of issue #9 (Gamma = 1.3, e = 0.8, 20 Hz, 3 mm stroke) and their
ratio. ``benchmarks/dynamics_speed.py`` imports :func:`python_impact_map`.
"""
from __future__ import annotations

import argparse
import math
import time

from scipy.optimize import brentq

G = 9.80665
CLOSE = 1e-9          # [m] switch from stepping to brentq
Z_TOL = 1e-13         # [m] contact when this close (grazing)
V_ZERO = 1e-9         # [m/s]
CHATTER_FRACTION = 1e-4


def python_impact_map(amplitude, omega, phase, stroke, restitution, t_end, g=G):
    """Impact times of the ball from rest on the lower plate at t = 0 (a list)."""
    aw2 = amplitude * omega * omega
    m_bound = g + aw2
    period = 2.0 * math.pi / omega

    def table(t):
        th = omega * t + phase
        return amplitude * math.sin(th), amplitude * omega * math.cos(th), -aw2 * math.sin(th)

    def crossing(t, falling):
        """Next time > t where g + y'' crosses zero (falling: lift-off)."""
        if aw2 <= g:
            return math.inf
        base = math.asin(g / aw2) if falling else math.pi - math.asin(g / aw2)
        k = math.ceil((omega * t + phase - base) / (2 * math.pi))
        tc = (base + 2 * math.pi * k - phase) / omega
        return tc if tc > t else tc + period

    def root(d, rate, m):
        disc = math.sqrt(rate * rate + 2.0 * m * d)
        return (rate + disc) / m if rate >= 0 else 2.0 * d / (disc - rate)

    impacts = []
    t, z, v = 0.0, 0.0, 0.0
    leave = False          # just reached a lift-off / release instant: depart
    while t < t_end:
        y0, yd0, ydd0 = table(t)
        a = -g - ydd0
        on_lower = z <= 0.0 and v <= V_ZERO
        on_upper = z >= stroke and v >= -V_ZERO
        if on_lower or on_upper:
            sign = 1.0 if on_lower else -1.0
            z = 0.0 if on_lower else stroke
            if abs(v) >= V_ZERO:                     # impact
                impacts.append(t)
                v = -restitution * v
                a_in = -sign * a
                if a_in > 0 and restitution < 1:
                    zeno = 2 * abs(v) / (a_in * (1 - restitution))
                    if zeno < CHATTER_FRACTION * period:
                        t += zeno
                        v = 0.0
                        continue
            else:                                    # at rest on the plate
                v = 0.0
                if sign * a <= 0.0 and not leave:    # pressed: wait for lift-off / release
                    t = crossing(t, on_lower)
                    leave = True
                    continue
                leave = False
                # leave with zero velocity: dist >= a s^2/2 + j s^3/6 - S s^4/24 (S = A w^4)
                j = sign * aw2 * omega * math.cos(omega * t + phase)
                snap = aw2 * omega * omega
                disc = (j / 6) ** 2 + snap / 24 * 2 * sign * a
                s = min(0.5 * (j / 6 + math.sqrt(max(disc, 0.0))) / (snap / 12), 0.25 * period)
                y, yd, _ = table(t + s)
                z = z - 0.5 * g * s * s - (y - y0 - yd0 * s)
                v = -g * s - (yd - yd0)
                t += s
                continue
        # free flight from (t, z, v): guaranteed steps, then brentq
        t0, z0, v0 = t, z, v

        def gap(s, t0=t0, z0=z0, v0=v0, y0=y0, yd0=yd0):
            y, _, _ = table(t0 + s)
            return z0 + v0 * s - 0.5 * g * s * s - (y - y0 - yd0 * s)

        def velocity(s, t0=t0, v0=v0, yd0=yd0):
            return v0 - g * s - (table(t0 + s)[1] - yd0)

        s, zc, vc = 0.0, z0, v0
        while True:
            h = min(root(max(zc, 0.0), vc, m_bound), root(max(stroke - zc, 0.0), -vc, m_bound))
            if t0 + s + h >= t_end:
                return impacts
            s += h
            zc, vc = gap(s), velocity(s)
            near_lower = zc < CLOSE and vc < 0
            near_upper = stroke - zc < CLOSE and vc > 0
            if near_lower or near_upper:
                target = 0.0 if near_lower else stroke
                if abs(zc - target) <= Z_TOL:            # grazing: on the plate (as the kernel)
                    t, z, v = t0 + s, target, vc
                    break
                width = 2.0 * abs(zc - target) / abs(vc) + 1e-15
                for _ in range(8):                   # bracket the contact ahead
                    if (gap(s + width) - target) * (zc - target) <= 0:
                        break
                    width *= 2.0
                else:
                    continue                         # grazing miss: keep stepping
                s = brentq(lambda q: gap(q) - target, s, s + width, xtol=1e-16, rtol=8.9e-16)
                t, z, v = t0 + s, target, velocity(s)
                break
    return impacts


def measure(python_duration: float, compiled_duration: float) -> dict:
    """The issue #9 scene (Gamma = 1.3, e = 0.8, 20 Hz): impacts per CPU second of this
    plain-Python loop over ``python_duration`` [s] and of ``simulate()`` over
    ``compiled_duration`` [s] (best of 3, compiled kernel loaded first)."""
    from tengfield.dynamics import simulate
    from tengfield.scene import default_scene

    f, gamma, e = 20.0, 1.3, 0.8
    omega = 2 * math.pi * f
    amplitude = gamma * G / omega**2
    c0 = time.process_time()
    n_py = len(python_impact_map(amplitude, omega, 0.0, 3e-3, e, python_duration))
    py_rate = n_py / (time.process_time() - c0)
    scene = default_scene().with_values(
        excitation={"frequency_hz": f, "amplitude_mm": amplitude * 1e3},
        contact={"restitution": e},
        run={"duration_s": compiled_duration, "sample_rate_hz": 20.0})
    simulate(scene, duration=1.0)                      # load the compiled kernel
    best = math.inf
    for _ in range(3):
        c0 = time.process_time()
        res = simulate(scene)
        best = min(best, time.process_time() - c0)
    return {"python_impacts": n_py, "python_rate": py_rate, "impacts": len(res.impacts),
            "cpu_s": best, "rate": len(res.impacts) / best, "regime": res.regime.name,
            "period": res.regime.period}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--duration-s", type=float, default=20.0, help="Python run [s]")
    ap.add_argument("--compiled-duration-s", type=float, default=2000.0)
    args = ap.parse_args()
    m = measure(args.duration_s, args.compiled_duration_s)
    print(f"plain Python + brentq: {m['python_impacts']} impacts in {args.duration_s:g} s "
          f"simulated, {m['python_rate']:.3g} impacts per CPU second")
    print(f"simulate(): {m['impacts']} impacts in {args.compiled_duration_s:g} s simulated, "
          f"{m['cpu_s']:.3f} CPU s, {m['rate']:.3g} impacts per CPU second ({m['regime']}, "
          f"period {m['period']})")
    print(f"ratio compiled / Python: {m['rate'] / m['python_rate']:.1f}")


if __name__ == "__main__":
    main()
