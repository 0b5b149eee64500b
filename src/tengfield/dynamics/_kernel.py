"""Compiled (numba) event-driven impact map of a ball between two moving plates.

Relative coordinates: ``z`` = gap between the ball's bottom and the lower
plate (0 <= z <= gap), ``v = dz/dt`` relative to the table, positive up.
In flight ``z'' = -g - y''(t)``, so from a segment start (t0, z0, v0)

    z(t) = z0 + v0 s - g s^2 / 2 - (y(t) - y(t0) - y'(t0) s),   s = t - t0,

exactly (no time stepping error). The trajectory is stored as segments
(start time, mode, z0, v0, y(t0), y'(t0)); ``mode`` is FLIGHT, STUCK_LOWER or
STUCK_UPPER.

Finding the FIRST contact (never skipping a grazing one): with
``M = g + max|y''|`` >= |z''|, the distance to the lower plate obeys
``z(s + h) >= z + v h - M h^2 / 2``, so no contact can occur before the
positive root ``h`` of that bound (likewise for the upper plate). Marching
with these steps is a proof that the interval is contact-free; it converges
quadratically onto a transversal contact and like sqrt onto a grazing one.
It stops when the distance is below ``Z_TOL`` with the ball moving towards
the plate; two Newton steps then place the impact on the plate.

Leaving a plate with zero relative velocity (lift-off, release, after a
fully plastic impact) uses the Taylor bound
``dist(s) >= a s^2/2 + j s^3/6 - S s^4/24`` (a, j: relative acceleration and
jerk away from the plate, S >= max|y''''|) for the first step.

Chatter (Zeno): after an impact with outgoing relative speed v_n while the
relative acceleration a presses the ball on the plate, the remaining bounces
on a plate with constant acceleration end at

    t_inf = t_n + 2 v_n / (|a| (1 - e)),

(on a still table |a| = g). The kernel jumps to t_inf and sticks when that
time is shorter than ``CHATTER_FRACTION`` of an excitation period and the
table acceleration changes by less than 0.1 % of |a| meanwhile
(``jerk_bound * (t_inf - t_n) <= 1e-3 |a|``). With a speed-dependent
restitution (no geometric series) and as a backstop, a bounce lower than
``REST_HEIGHT`` ends in sticking after its flight time ``2 v_n / |a|``.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

#: Kinds of table motion (:class:`tengfield.dynamics.table.TableMotion` ``kind``; compile-time
#: constants of this kernel and of the 3D one).
SINE = 0     # y = A sin(w t + phase), params = (A, w, phase)
PPOLY = 1    # piecewise quintic on breaks/coeffs (a recorded signal)

FLIGHT = 0
STUCK_LOWER = 1
STUCK_UPPER = 2

LOWER = 0
UPPER = 1

# kernel status codes
OK = 0
CAPACITY = 1       # output arrays too small: caller retries with larger ones
EVENT_BOUND = 2    # more events per excitation period than allowed
STEP_BOUND = 3     # a root search did not converge (should not happen)

Z_TOL = 1e-13             # [m] contact when closer than this and approaching
A_TOL = 1e-9              # [m/s^2] relative accelerations below this count as zero
CHATTER_FRACTION = 1e-4   # Zeno collapse when t_inf - t_n < this * period
REST_HEIGHT = 1e-12       # [m] bounces lower than this end in sticking
V_ZERO = 1e-9             # [m/s] relative speeds at a plate below this are zero
MAX_STEPS_PER_FLIGHT = 1_000_000
LOCAL_ROUNDS = 2           # fixed-point rounds of local_safe_step
GRID_RESTART = 64          # gap_on_grid: exact sin/cos every this many samples


@njit(cache=True)
def _ppoly_index(x, t):
    i = np.searchsorted(x, t, side="right") - 1
    if i < 0:
        i = 0
    if i > x.size - 2:
        i = x.size - 2
    return i


@njit(cache=True)
def table_state(t, kind, par, x, c):
    """(y, y', y'', y''') of the table at time t (SI)."""
    if kind == SINE:
        amp = par[0]
        w = par[1]
        th = w * t + par[2]
        s = math.sin(th)
        co = math.cos(th)
        return amp * s, amp * w * co, -amp * w * w * s, -amp * w * w * w * co
    i = _ppoly_index(x, t)
    dx = t - x[i]
    c0 = c[0, i]
    c1 = c[1, i]
    c2 = c[2, i]
    c3 = c[3, i]
    c4 = c[4, i]
    c5 = c[5, i]
    y = ((((c0 * dx + c1) * dx + c2) * dx + c3) * dx + c4) * dx + c5
    y1 = (((5.0 * c0 * dx + 4.0 * c1) * dx + 3.0 * c2) * dx + 2.0 * c3) * dx + c4
    y2 = ((20.0 * c0 * dx + 12.0 * c1) * dx + 6.0 * c2) * dx + 2.0 * c3
    y3 = (60.0 * c0 * dx + 24.0 * c1) * dx + 6.0 * c2
    return y, y1, y2, y3


@njit(cache=True)
def table_state_many(times, kind, par, x, c):
    """Vectorised :func:`table_state`: (y, y', y'') arrays."""
    n = times.size
    y = np.empty(n)
    yd = np.empty(n)
    ydd = np.empty(n)
    for k in range(n):
        a, b, cc, _ = table_state(times[k], kind, par, x, c)
        y[k] = a
        yd[k] = b
        ydd[k] = cc
    return y, yd, ydd


@njit(cache=True)
def _flight(t, t0, z0, v0, y0, yd0, g, kind, par, x, c):
    """Relative (z, v, z'', z''') at t of the free flight that started at t0 from (z0, v0)."""
    s = t - t0
    y, yd, ydd, yddd = table_state(t, kind, par, x, c)
    z = z0 + v0 * s - 0.5 * g * s * s - (y - y0 - yd0 * s)
    v = v0 - g * s - (yd - yd0)
    return z, v, -g - ydd, -yddd


@njit(cache=True)
def _relative(s, z0, v0, y0, yd0, g, y, yd):
    """Relative (z, v) a time s into a free flight from (z0, v0), table (y, y') then."""
    z = z0 + v0 * s - 0.5 * g * s * s - (y - y0 - yd0 * s)
    v = v0 - g * s - (yd - yd0)
    return z, v


@njit(cache=True)
def first_root(d, rate, acc):
    """First s > 0 where ``d + rate s + acc s^2 / 2`` (d >= 0) reaches zero; inf if never.

    Written without cancellation (the small root as ``2 d / (sqrt(...) - rate)``).
    """
    if acc < 0.0:
        sq = math.sqrt(rate * rate - 2.0 * acc * d)
        if rate >= 0.0:
            return (rate + sq) / (-acc)
        return 2.0 * d / (sq - rate)
    if rate >= 0.0:
        return math.inf
    disc = rate * rate - 2.0 * acc * d
    if disc < 0.0:
        return math.inf
    return 2.0 * d / (math.sqrt(disc) - rate)


@njit(cache=True)
def safe_step(z, v, gap, m_bound):
    """Largest h such that no plate can be reached in [0, h) (|z''| <= m_bound)."""
    dl = z if z > 0.0 else 0.0
    du = gap - z
    if du < 0.0:
        du = 0.0
    hl = first_root(dl, v, -m_bound)
    hu = first_root(du, -v, -m_bound)
    return hl if hl < hu else hu


@njit(cache=True)
def local_safe_step(z, v, a, j, gap, m_bound, snap_bound, h_max):
    """A step h (<= h_max) with no plate reached in [0, h), from the local motion.

    On [0, H] the relative acceleration obeys ``z''(s) >= a + min(0, j H) - S H^2/2``
    (a = z'', j = z''' now, S >= max|y''''|) and ``z'' >= -m_bound``; likewise
    for the distance to the upper plate. With ``r(H)`` the first root of the
    quadratic lower bound of the distance built on that acceleration,
    ``min(H, r(H))`` is contact-free for any H. Starting from the global step
    (:func:`safe_step`, i.e. H = inf), ``H <- r(H)`` alternates between over-
    and under-estimates of the fixed point; the proven steps increase
    (LOCAL_ROUNDS iterations).
    """
    dl = z if z > 0.0 else 0.0
    du = gap - z
    if du < 0.0:
        du = 0.0
    h = safe_step(z, v, gap, m_bound)
    if h >= h_max:
        return h_max
    step = h
    for _ in range(LOCAL_ROUNDS):
        big = h if h < h_max else h_max
        drop = 0.5 * snap_bound * big * big
        al = a + min(0.0, j * big) - drop
        if al < -m_bound:
            al = -m_bound
        au = -a + min(0.0, -j * big) - drop
        if au < -m_bound:
            au = -m_bound
        hl = first_root(dl, v, al)
        hu = first_root(du, -v, au)
        r = hl if hl < hu else hu
        proven = r if r < big else big     # the bound holds on [0, big]
        if proven > step:
            step = proven
        h = r
    return step


@njit(cache=True)
def departure_step(a_away, j_away, snap_bound, gap, s_max):
    """First step off a plate with zero relative velocity, or 0 if none can be proven.

    ``dist(s) >= a s^2/2 + j s^3/6 - S s^4/24`` (a = a_away >= 0, j = j_away);
    returns s in (0, s_max] with that bound positive on (0, s] and the matching
    upper bound below gap/2 (so neither plate is touched meanwhile).
    """
    a = a_away if a_away > 0.0 else 0.0
    j = j_away
    big = s_max
    if snap_bound > 0.0:
        # positive root of -S/24 s^2 + j/6 s + a/2 = 0 (the bound divided by s^2)
        qa = -snap_bound / 24.0
        qb = j / 6.0
        qc = a / 2.0
        disc = qb * qb - 4.0 * qa * qc
        if disc < 0.0:
            return 0.0
        root = (-qb - math.sqrt(disc)) / (2.0 * qa)
        if root <= 0.0:
            return 0.0
        s = 0.5 * root
    elif j > 0.0 or (j == 0.0 and a > 0.0):
        s = big
    elif a > 0.0:
        s = 0.5 * (-3.0 * a / j)
    else:
        return 0.0
    if s > big:
        s = big
    for _ in range(200):
        upper = 0.5 * a * s * s + abs(j) * s * s * s / 6.0 + snap_bound * s ** 4 / 24.0
        if upper <= 0.5 * gap:
            break
        s *= 0.5
    lower = 0.5 * a * s * s + j * s * s * s / 6.0 - snap_bound * s ** 4 / 24.0
    if not lower > 0.0:
        return 0.0
    return s


@njit(cache=True)
def _cubic_roots_unit(p0, p1, p2, p3):
    """Real roots in [0, 1] of p0 u^3 + p1 u^2 + p2 u + p3 (up to 3; NaN padded)."""
    out = np.full(3, np.nan)
    scale = max(abs(p0), abs(p1), abs(p2), abs(p3))
    if scale == 0.0:
        return out
    coeffs = np.array([p0, p1, p2, p3]) / scale
    k = 0
    while k < 3 and abs(coeffs[k]) < 1e-14:
        k += 1
    if k == 3:
        return out
    roots = np.roots(coeffs[k:].astype(np.complex128))
    m = 0
    for r in roots:
        if abs(r.imag) <= 1e-9 and -1e-12 <= r.real <= 1.0 + 1e-12:
            out[m] = min(max(r.real, 0.0), 1.0)
            m += 1
    return out


@njit(cache=True)
def next_crossing(t, falling, g, kind, par, x, c, t_end):
    """First time > t where g + y'' crosses zero downwards (falling) or upwards.

    Falling crossings are lift-offs from the lower plate, rising crossings are
    releases from the upper plate. Returns inf if none before t_end.
    """
    if kind == SINE:
        aw2 = par[0] * par[1] * par[1]
        if aw2 <= g:
            return math.inf
        base = math.asin(g / aw2)   # sin(theta) = 1/Gamma with cos(theta) > 0
        if not falling:
            base = math.pi - base
        w = par[1]
        ph = par[2]
        th = w * t + ph
        k = math.ceil((th - base) / (2.0 * math.pi))
        tc = (base + 2.0 * math.pi * k - ph) / w
        if tc <= t:
            tc = (base + 2.0 * math.pi * (k + 1) - ph) / w
        return tc
    # piecewise quintic: f = g + y'' is a cubic on each piece
    i0 = _ppoly_index(x, t)
    for i in range(i0, x.size - 1):
        if x[i] > t_end:
            return math.inf
        h = x[i + 1] - x[i]
        q0 = 20.0 * c[0, i] * h ** 3
        q1 = 12.0 * c[1, i] * h ** 2
        q2 = 6.0 * c[2, i] * h
        q3 = 2.0 * c[3, i] + g
        roots = _cubic_roots_unit(q0, q1, q2, q3)
        best = math.inf
        for r in roots:
            if math.isnan(r):
                continue
            u = r
            for _ in range(3):   # Newton polish on the scaled cubic
                f = ((q0 * u + q1) * u + q2) * u + q3
                fp = (3.0 * q0 * u + 2.0 * q1) * u + q2
                if fp == 0.0:
                    break
                u -= f / fp
            fp = (3.0 * q0 * u + 2.0 * q1) * u + q2
            if (falling and fp < 0.0) or ((not falling) and fp > 0.0):
                tc = x[i] + u * h
                if tc > t and tc < best:
                    best = tc
        if best < math.inf:
            return best
    return math.inf


@njit(cache=True)
def _restitution(speed, e0, power_law, v_ref, exponent):
    if not power_law or exponent == 0.0:
        return e0
    v = speed if speed > 1e-12 else 1e-12
    e = e0 * (v / v_ref) ** (-exponent)
    return e if e < 1.0 else 1.0


@njit(cache=True)
def chatter_duration(v_after, a_in, e, constant_e, jerk_bound, chatter_time):
    """Time from an impact to the end of its chatter sequence, or -1 to keep bouncing.

    ``v_after`` rebound speed [m/s], ``a_in`` > 0 the relative acceleration
    pressing the ball on the plate [m/s^2]. Zeno: ``2 v / (a (1 - e))`` when
    that is shorter than ``chatter_time`` and the table acceleration changes
    by < 0.1 % of ``a_in`` meanwhile; otherwise, a rebound lower than
    REST_HEIGHT ends after its own flight (divided by 1 - e for a constant e).
    """
    if constant_e and e < 1.0:
        zeno = 2.0 * v_after / (a_in * (1.0 - e))
        if zeno <= chatter_time and jerk_bound * zeno <= 1e-3 * a_in:
            return zeno
    if v_after * v_after / (2.0 * a_in) <= REST_HEIGHT:
        dt = 2.0 * v_after / a_in
        if constant_e and e < 1.0:
            dt /= 1.0 - e
        return dt
    return -1.0


@njit(cache=True)
def _store(seg_t, seg_mode, seg_z, seg_v, seg_y, seg_yd, n, t, mode, z, v, y, yd):
    """Append a segment; returns the new count."""
    seg_t[n] = t
    seg_mode[n] = mode
    seg_z[n] = z
    seg_v[n] = v
    seg_y[n] = y
    seg_yd[n] = yd
    return n + 1


REACHED_END = 4   # internal: next_contact ran to t_end without contact


@njit(cache=True)
def next_contact(t0, z0, v0, y0, yd0, ydd0, yddd0, s_begin, t_end, g, gap, m_bound, snap_bound,
                 period, kind, par, x, c):
    """First contact of the free flight that starts at t0 from (z0, v0), table (y0..y0''').

    ``s_begin`` > 0 skips a first stretch already proven contact-free
    (:func:`departure_step`). Marches with :func:`local_safe_step` (one table
    evaluation per step). Returns (status, t, z, v, steps, table): status OK
    with the contact time, the plate's z (0 or gap) and the relative velocity
    there; REACHED_END if no contact occurs before t_end; STEP_BOUND if the
    search did not converge; ``steps`` = table evaluations used; ``table`` =
    (y, y', y'', y''') at the contact time (valid with status OK).
    """
    s = s_begin
    if s > 0.0:
        if t0 + s >= t_end:
            return REACHED_END, t_end, z0, v0, 0, (y0, yd0, 0.0, 0.0)
        y, yd, ydd, yddd = table_state(t0 + s, kind, par, x, c)
    else:
        y, yd, ydd, yddd = y0, yd0, ydd0, yddd0
    zc, vc = _relative(s, z0, v0, y0, yd0, g, y, yd)
    steps = 0
    s_safe = s        # start of the last proven contact-free step
    while True:
        if s > 0.0 and zc <= Z_TOL and vc <= 0.0:
            target = 0.0
            break
        if s > 0.0 and zc >= gap - Z_TOL and vc >= 0.0:
            target = gap
            break
        # beyond a period the local bound is no better than m_bound
        h = local_safe_step(zc, vc, -g - ydd, -yddd, gap, m_bound, snap_bound, period)
        if t0 + s + h >= t_end:
            return REACHED_END, t_end, zc, vc, steps, (y, yd, ydd, yddd)
        s_safe = s
        s += h
        y, yd, ydd, yddd = table_state(t0 + s, kind, par, x, c)
        zc, vc = _relative(s, z0, v0, y0, yd0, g, y, yd)
        steps += 1
        if steps > MAX_STEPS_PER_FLIGHT:
            return STEP_BOUND, t0 + s, zc, vc, steps, (y, yd, ydd, yddd)
    # Polish of the contact time from the last state, without another table
    # evaluation: the small root of d + v ds + a ds^2 / 2 = 0 (quadratic Taylor
    # model, neglected j ds^3 / 6 far below Z_TOL here). Skipped when the
    # neglected curvature is not small against the distance covered
    # (m_bound |ds| > 0.1 |v|: grazing; a fixed fraction of the period would
    # skip it at kHz drives, where slow impacts then carried time errors
    # Z_TOL / v), and never before the last point known to be contact-free.
    # The table state moves with the same Taylor step (error S ds^4 / 24).
    if vc != 0.0:
        d = zc - target
        ac = -g - ydd
        ds = -d / vc
        if m_bound * abs(ds) <= 0.1 * abs(vc):
            disc = vc * vc - 2.0 * ac * d
            if disc > 0.0:
                ds = -2.0 * d / (vc + math.copysign(math.sqrt(disc), vc))
            s_new = s + ds
            if s_new < s_safe:
                s_new = s_safe
            ds = s_new - s
            vc = vc + ac * ds
            y = y + ds * (yd + ds * (0.5 * ydd + ds * yddd / 6.0))
            yd = yd + ds * (ydd + 0.5 * ds * yddd)
            ydd = ydd + ds * yddd
            s = s_new
    # on the plate; a velocity pointing away is a round-off touch: zero
    if target == 0.0 and vc > 0.0:
        vc = 0.0
    if target == gap and vc < 0.0:
        vc = 0.0
    return OK, t0 + s, target, vc, steps, (y, yd, ydd, yddd)


@njit(cache=True)
def run_impact_map(kind, par, x, c, g, gap, t_start, t_end, z_start, v_start,
                   e0, power_law, v_ref, exponent, period, max_events_per_period,
                   acc_bound, jerk_bound, snap_bound,
                   seg_t, seg_mode, seg_z, seg_v, seg_y, seg_yd,
                   imp_t, imp_plate, imp_vb, imp_va):
    """Integrate from t_start to t_end; fill the segment and impact arrays.

    Returns (status, n_segments, n_impacts, time reached).
    """
    m_bound = g + acc_bound
    chatter_time = CHATTER_FRACTION * period
    t = t_start
    z = min(max(z_start, 0.0), gap)
    v = v_start
    n_seg = 0
    n_imp = 0
    n_events = 0
    force_depart = False
    have_table = False    # (y, yd, ydd, yddd) already known at t (from the contact search)
    y = yd = ydd = yddd = 0.0
    while True:
        n_events += 1
        if n_events > max_events_per_period * ((t - t_start) / period + 1.0):
            return EVENT_BOUND, n_seg, n_imp, t
        if n_seg >= seg_t.size or n_imp >= imp_t.size:
            return CAPACITY, n_seg, n_imp, t
        if not have_table:
            y, yd, ydd, yddd = table_state(t, kind, par, x, c)
        have_table = False
        a = -g - ydd          # relative acceleration in free flight
        s_begin = 0.0
        # on a plate: approaching it, or leaving it slower than V_ZERO (which is
        # below the resolution of z near the plate: treated as zero velocity)
        at_lower = z <= Z_TOL and v <= V_ZERO
        at_upper = z >= gap - Z_TOL and v >= -V_ZERO
        if at_lower or at_upper:
            if abs(v) < V_ZERO:
                v = 0.0
            plate = LOWER if at_lower else UPPER
            sign = 1.0 if at_lower else -1.0      # direction "away from the plate"
            z = 0.0 if at_lower else gap
            if v != 0.0:
                # ---- impact (Newton restitution) ----
                speed = abs(v)
                e = _restitution(speed, e0, power_law, v_ref, exponent)
                v_after = e * speed
                if v_after < V_ZERO:
                    v_after = 0.0
                imp_t[n_imp] = t
                imp_plate[n_imp] = plate
                imp_vb[n_imp] = speed
                imp_va[n_imp] = v_after
                n_imp += 1
                v = sign * v_after
                a_in = -sign * a             # acceleration towards the plate
                if a_in > 0.0 and v_after > 0.0:
                    constant_e = not (power_law and exponent != 0.0)
                    dt_inf = chatter_duration(v_after, a_in, e, constant_e, jerk_bound,
                                              chatter_time)
                    if dt_inf >= 0.0:
                        # the first micro-arc is kept as a flight segment (samples are clamped)
                        n_seg = _store(seg_t, seg_mode, seg_z, seg_v, seg_y, seg_yd, n_seg,
                                       t, FLIGHT, z, v, y, yd)
                        t = t + dt_inf
                        v = 0.0
                        if t >= t_end:
                            break
                        continue
                if v_after > 0.0:
                    pass   # flies off: fall through to the flight below
                else:
                    continue   # fully plastic: decide stick/depart at the same time
            else:
                # ---- zero relative velocity on a plate: stick or depart ----
                a_away = sign * a
                j_away = -sign * yddd
                s1 = 0.0
                pressed = a_away < -A_TOL or (a_away <= A_TOL and j_away <= 0.0)
                if force_depart or not pressed:
                    s1 = departure_step(a_away, j_away, snap_bound, gap, 0.25 * period)
                force_depart = False
                if s1 <= 0.0:
                    n_seg = _store(seg_t, seg_mode, seg_z, seg_v, seg_y, seg_yd, n_seg, t,
                                   STUCK_LOWER if at_lower else STUCK_UPPER, z, 0.0, y, yd)
                    t_next = next_crossing(t, at_lower, g, kind, par, x, c, t_end)
                    if t_next >= t_end:
                        break
                    t = t_next
                    force_depart = True
                    continue
                s_begin = s1
        # ---- free flight from (t, z, v) ----
        n_seg = _store(seg_t, seg_mode, seg_z, seg_v, seg_y, seg_yd, n_seg, t, FLIGHT, z, v, y, yd)
        status, t, z, v, _, state = next_contact(t, z, v, y, yd, ydd, yddd, s_begin, t_end, g,
                                                 gap, m_bound, snap_bound, period, kind, par, x, c)
        y, yd, ydd, yddd = state
        have_table = status == OK
        if status == REACHED_END:
            break
        if status == STEP_BOUND:
            return STEP_BOUND, n_seg, n_imp, t
    return OK, n_seg, n_imp, t


@njit(cache=True)
def _segment_state(t, mode, t0, z0, v0, y0, yd0, y, yd, g, gap):
    """Exact (z, v) at time ``t`` in a stored segment (mode, start t0, relative state
    z0, v0, table y0, yd0 at t0) with the table at (y, yd) at ``t``; flight values are
    clamped to [0, gap] (only the first micro-arc of a collapsed chatter sequence can
    leave it). Scalars only: called per sample, an array argument would cost a
    reference count each (3x slower)."""
    if mode == STUCK_LOWER:
        return 0.0, 0.0
    if mode == STUCK_UPPER:
        return gap, 0.0
    s = t - t0
    z = z0 + v0 * s - 0.5 * g * s * s - (y - y0 - yd0 * s)
    v = v0 - g * s - (yd - yd0)
    if z < 0.0:
        return 0.0, 0.0
    if z > gap:
        return gap, 0.0
    return z, v


@njit(cache=True)
def sample_segments(times, n_seg, seg_t, seg_mode, seg_z, seg_v, seg_y, seg_yd,
                    g, gap, kind, par, x, c):
    """Exact (z, v, y) at sorted or unsorted ``times`` from the stored segments
    (:func:`_segment_state`)."""
    n = times.size
    zs = np.empty(n)
    vs = np.empty(n)
    ys = np.empty(n)
    starts = seg_t[:n_seg]
    for k in range(n):
        t = times[k]
        i = np.searchsorted(starts, t, side="right") - 1
        if i < 0:
            i = 0
        y, yd, _, _ = table_state(t, kind, par, x, c)
        ys[k] = y
        zs[k], vs[k] = _segment_state(t, seg_mode[i], seg_t[i], seg_z[i], seg_v[i], seg_y[i],
                                      seg_yd[i], y, yd, g, gap)
    return zs, vs, ys


@njit(cache=True)
def sample_many(times, offsets, seg_t, seg_mode, seg_z, seg_v, seg_y, seg_yd,
                g, gap, kind, pars, x, c, zs, vs):
    """(z, v) of many trajectories at the sorted ``times``, into ``zs``, ``vs`` of shape
    (trajectories, times): trajectory j is segments ``offsets[j]:offsets[j + 1]`` of the
    concatenated arrays with table parameters ``pars[j]`` (the values of
    :func:`sample_segments` on each, in one call: each trajectory's segment is found
    once, then followed forward)."""
    n = times.size
    m = offsets.size - 1
    if n == 0:
        return
    for j in range(m):
        lo = offsets[j]
        hi = offsets[j + 1]
        par = pars[j]
        i = lo + max(np.searchsorted(seg_t[lo:hi], times[0], side="right") - 1, 0)
        for k in range(n):
            t = times[k]
            while i + 1 < hi and seg_t[i + 1] <= t:
                i += 1
            y, yd, _, _ = table_state(t, kind, par, x, c)
            zs[j, k], vs[j, k] = _segment_state(t, seg_mode[i], seg_t[i], seg_z[i], seg_v[i],
                                                seg_y[i], seg_yd[i], y, yd, g, gap)


@njit(cache=True)
def gap_on_grid(start, step, count, n_seg, seg_t, seg_mode, seg_z, seg_v, seg_y, seg_yd,
                g, gap, kind, par, x, c):
    """z at ``start + i * step``, i = 0..count-1 (clamped like :func:`sample_segments`).

    One forward pass over the segments. For the sine the table is advanced by
    rotation (sin, cos of the phase step), restarted from an exact sin/cos
    every GRID_RESTART samples, so the error stays at a few ulp of y.
    """
    zs = np.empty(count)
    i_seg = 0
    sin_d = math.sin(par[1] * step) if kind == SINE else 0.0
    cos_d = math.cos(par[1] * step) if kind == SINE else 0.0
    sn = 0.0
    cs = 0.0
    for k in range(count):
        t = start + k * step
        while i_seg + 1 < n_seg and seg_t[i_seg + 1] <= t:
            i_seg += 1
        if kind == SINE:
            if k % GRID_RESTART == 0:
                th = par[1] * t + par[2]
                sn = math.sin(th)
                cs = math.cos(th)
            else:
                sn, cs = sn * cos_d + cs * sin_d, cs * cos_d - sn * sin_d
            y = par[0] * sn
        else:
            y = table_state(t, kind, par, x, c)[0]
        mode = seg_mode[i_seg]
        if mode == STUCK_LOWER:
            z = 0.0
        elif mode == STUCK_UPPER:
            z = gap
        else:
            s = t - seg_t[i_seg]
            z = seg_z[i_seg] + seg_v[i_seg] * s - 0.5 * g * s * s - (y - seg_y[i_seg]
                                                                     - seg_yd[i_seg] * s)
            if z < 0.0:
                z = 0.0
            elif z > gap:
                z = gap
        zs[k] = z
    return zs


@njit(cache=True)
def count_contacts_on_grid(impact_time, impact_plate, start, step, z_grid, gap, merge_height):
    """(contacts at the lower plate, at the upper plate) among time-ordered impacts.

    An impact continues the previous contact when the previous impact was at
    the same plate and, on the grid samples between the two impacts (those
    at or after the first and before the second), the ball stayed closer to
    that plate than ``merge_height`` [m] (no sample in between: continued).
    """
    n = z_grid.size
    counts = np.zeros(2, dtype=np.int64)
    prev_cut = 0
    for k in range(impact_time.size):
        # first grid index with start + i * step >= impact time (searchsorted 'left')
        i = int(math.ceil((impact_time[k] - start) / step))
        if i < 0:
            i = 0
        while i > 0 and start + (i - 1) * step >= impact_time[k]:
            i -= 1
        while i < n and start + i * step < impact_time[k]:
            i += 1
        if i > n - 1:
            i = n - 1
        plate = impact_plate[k]
        continued = False
        if k > 0 and impact_plate[k - 1] == plate:
            far = 0.0
            for m in range(prev_cut, i):
                d = z_grid[m] if plate == LOWER else gap - z_grid[m]
                if d > far:
                    far = d
            continued = far < merge_height
        if not continued:
            counts[plate] += 1
        prev_cut = i
    return counts
