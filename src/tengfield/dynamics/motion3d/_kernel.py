"""Compiled integrator of the 3D ball (numba). Table frame, SI units.

State: centre position p (z = 0 is the lowest point of the cavity: the tube's
lower electrode face, the shell's bottom; z axis = the drive's axis),
velocity v and angular velocity w relative to the table, plus one tangential
history spring xi per surface (lower, upper, wall or band).
Acceleration: ``g_vec - Y''(t) + F/m``, ``w' = torque / I``.

Two modes:

* FLIGHT (no surface touched): exact free flight
  ``p = p0 + v0 s + g s^2/2 - (Y(t) - Y(t0) - Y'(t0) s)``, w constant. Each
  step is as long as a guaranteed bound allows (no surface can be reached,
  ``|accel| <= |g| + max|Y''|``); a step that would touch is cut back by
  bisection to the entry time.
* CONTACT (at least one surface touched): classical RK4 with a step that
  resolves the contact oscillation (``steps`` per natural period of the
  stiffest active contact and per penetration time at the current speed);
  a step that starts or ends a contact is cut back by bisection so every
  episode starts and ends on a step boundary.

Parameters ``P`` = (m, R, I, H, R_t, g_x, g_y, g_z, then the three surfaces'
geometry rows from :func:`tengfield.field.cells.contact_surfaces.contact_surfaces`:
kind (floor, ceiling, cylinder, sphere zone), p0, p1, lo, hi, 0). H and R_t
(the tube's plate spacing and radius) serve the tube's flight bound only; a
cell whose first surface is a sphere zone (the spherical shell: lower
electrode, upper electrode, band of one sphere) bounds its flights by the sphere.

Per surface parameters ``S[s]`` (s = 0 lower, 1 upper, 2 wall or band):
``law`` (0 Hertz, 1 power), ``kn`` (F = kn delta^e), ``e``, ``cn`` (Hertz:
gamma_n = cn delta^(1/4); power: c_max of the STEP), ``kt`` (Hertz:
k_t = kt delta^(1/2); power: k_t = kt e delta^(e-1)), ``ct`` (like cn), ``dmax`` (STEP
depth, power law), ``clamp`` (1: the normal force never pulls), ``mu_s``,
``mu_d``.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from .._kernel import table_state

N_STATE = 18
GEOM = 8                  # P[GEOM:]: the three surfaces' rows (kind, p0, p1, lo, hi, 0)
GEOM_WIDTH = 6
FLOOR_KIND, CEILING_KIND, CYLINDER_KIND, SPHERE_KIND = 0.0, 1.0, 2.0, 3.0
KNOT_WIDTH = 11           # t, p(3), v(3), w(3), mode
FLIGHT, CONTACT = 0.0, 1.0
BISECTIONS = 48
EDGE_FRACTION = 0.25
EDGE_REFINE = 64.0
DAMPED_STEP = 0.25


@njit(cache=True)
def table3(t, kx, px, bx, cx, ky, py, by, cy, kz, pz, bz, cz):
    """(Y, Y', Y'') of the table on the three axes at t (arrays of 3)."""
    y = np.empty(3)
    yd = np.empty(3)
    ydd = np.empty(3)
    a, b, c, _ = table_state(t, kx, px, bx, cx)
    y[0] = a
    yd[0] = b
    ydd[0] = c
    a, b, c, _ = table_state(t, ky, py, by, cy)
    y[1] = a
    yd[1] = b
    ydd[1] = c
    a, b, c, _ = table_state(t, kz, pz, bz, cz)
    y[2] = a
    yd[2] = b
    ydd[2] = c
    return y, yd, ydd


@njit(cache=True)
def _geometry(s, p, R, P):
    """(delta, nx, ny, nz) of surface s: penetration [m] and unit normal pushing the ball.

    The surface's row of the geometry table starts at ``P[GEOM + GEOM_WIDTH s]``:
    (kind, p0, p1, lo, hi) as :mod:`tengfield.field.cells.contact_surfaces` writes it.
    A sphere zone that does not hold the contact point returns delta = -p1 (apart).
    """
    b = GEOM + GEOM_WIDTH * s
    kind = P[b]
    if kind == FLOOR_KIND:
        return R - (p[2] - P[b + 1]), 0.0, 0.0, 1.0
    if kind == CEILING_KIND:
        return p[2] + R - P[b + 1], 0.0, 0.0, -1.0
    if kind == CYLINDER_KIND:
        Rt = P[b + 1]
        rho = math.sqrt(p[0] * p[0] + p[1] * p[1])
        if rho < 1e-300:
            return R - Rt, -1.0, 0.0, 0.0
        return rho + R - Rt, -p[0] / rho, -p[1] / rho, 0.0
    # SPHERE_KIND: the inside of the sphere (0, 0, p0), radius p1, zone [lo, hi]
    a = P[b + 2]
    dz = p[2] - P[b + 1]
    dist = math.sqrt(p[0] * p[0] + p[1] * p[1] + dz * dz)
    if dist < 1e-300:
        return R - a, 0.0, 0.0, 1.0
    nx, ny, nz = -p[0] / dist, -p[1] / dist, -dz / dist
    height = a * dz / dist   # the contact point's height above the centre
    if height < P[b + 3] or height > P[b + 4]:
        return -a, nx, ny, nz
    return dist + R - a, nx, ny, nz


@njit(cache=True)
def _step_fn(x, dmax):
    """STEP(x; 0, 0, dmax, 1): cubic smooth ramp, 1 beyond dmax (1 at once if dmax = 0)."""
    if dmax <= 0.0 or x >= dmax:
        return 1.0
    if x <= 0.0:
        return 0.0
    u = x / dmax
    return u * u * (3.0 - 2.0 * u)


@njit(cache=True)
def _coefficients(S, s, delta):
    """(normal damping, tangential stiffness, tangential damping) at penetration delta."""
    if S[s, 0] == 0.0:
        q = delta ** 0.25
        return S[s, 3] * q, S[s, 4] * q * q, S[s, 5] * q
    st = _step_fn(delta, S[s, 6])
    e = S[s, 2]
    kt = S[s, 4] if e == 1.0 else S[s, 4] * e * delta ** (e - 1.0)
    return S[s, 3] * st, kt, S[s, 5] * st


@njit(cache=True)
def _touched_set_changed(d, d_new):
    """Whether the set of touched surfaces (penetration > 0) differs between the
    penetrations ``d`` and ``d_new`` [m] of the three surfaces."""
    for s in range(3):
        if (d[s] > 0.0) != (d_new[s] > 0.0):
            return True
    return False


@njit(cache=True)
def _normal_force(s, delta, v, nx, ny, nz, S):
    """(normal force [N] of surface s at overlap delta [m] and ball velocity v, before
    any clipping at zero; tangential stiffness; tangential damping)."""
    ddot = -(v[0] * nx + v[1] * ny + v[2] * nz)
    cn, ktt, ctt = _coefficients(S, s, delta)
    return S[s, 1] * delta ** S[s, 2] + cn * ddot, ktt, ctt


@njit(cache=True)
def _slip_velocity(v, w, R, nx, ny, nz):
    """Tangential velocity [m/s] of the ball's material point at the contact point
    r_c = -R n (ball velocity v, angular velocity w, unit normal n pushing the ball)."""
    rx, ry, rz = -R * nx, -R * ny, -R * nz
    vcx = v[0] + w[1] * rz - w[2] * ry
    vcy = v[1] + w[2] * rx - w[0] * rz
    vcz = v[2] + w[0] * ry - w[1] * rx
    vn = vcx * nx + vcy * ny + vcz * nz
    return vcx - vn * nx, vcy - vn * ny, vcz - vn * nz


@njit(cache=True)
def _contact(s, p, v, w, xi, sliding, P, S, out):
    """Force and torque of surface s on the ball added to out[0:3], out[3:6].

    Returns (delta, normal force, tangential force magnitude)."""
    R = P[1]
    delta, nx, ny, nz = _geometry(s, p, R, P)
    if delta <= 0.0:
        return delta, 0.0, 0.0
    fn, ktt, ctt = _normal_force(s, delta, v, nx, ny, nz, S)
    if S[s, 7] != 0.0 and fn < 0.0:
        fn = 0.0
    vtx, vty, vtz = _slip_velocity(v, w, R, nx, ny, nz)
    k = 3 * s
    xn = xi[k] * nx + xi[k + 1] * ny + xi[k + 2] * nz
    ftx = -ktt * (xi[k] - xn * nx) - ctt * vtx
    fty = -ktt * (xi[k + 1] - xn * ny) - ctt * vty
    ftz = -ktt * (xi[k + 2] - xn * nz) - ctt * vtz
    ft = math.sqrt(ftx * ftx + fty * fty + ftz * ftz)
    fpos = fn if fn > 0.0 else 0.0
    mu = S[s, 9] if sliding[s] else S[s, 8]
    if ft > mu * fpos:
        scale = S[s, 9] * fpos / ft if ft > 0.0 else 0.0
        ftx *= scale
        fty *= scale
        ftz *= scale
        ft = S[s, 9] * fpos
    out[0] += fn * nx + ftx
    out[1] += fn * ny + fty
    out[2] += fn * nz + ftz
    rx, ry, rz = -R * nx, -R * ny, -R * nz   # torque r_c x f_t about the centre, r_c = -R n
    out[3] += ry * ftz - rz * fty
    out[4] += rz * ftx - rx * ftz
    out[5] += rx * fty - ry * ftx
    return delta, fn, ft


@njit(cache=True)
def _deriv(t, y, dy, out, sliding, P, S, kx, px, bx, cx, ky, py, by, cy, kz, pz, bz, cz):
    """dy/dt into ``dy`` (``out``: 6 scratch values for force and torque)."""
    for i in range(6):
        out[i] = 0.0
    p = y[0:3]
    v = y[3:6]
    w = y[6:9]
    xi = y[9:18]
    R = P[1]
    for s in range(3):
        delta, nx, ny, nz = _geometry(s, p, R, P)
        if delta > 0.0:
            _contact(s, p, v, w, xi, sliding, P, S, out)
            dy[9 + 3 * s], dy[10 + 3 * s], dy[11 + 3 * s] = _slip_velocity(v, w, R, nx, ny, nz)
        else:
            dy[9 + 3 * s] = 0.0
            dy[10 + 3 * s] = 0.0
            dy[11 + 3 * s] = 0.0
    ax = table_state(t, kx, px, bx, cx)[2]
    ay = table_state(t, ky, py, by, cy)[2]
    az = table_state(t, kz, pz, bz, cz)[2]
    m = P[0]
    inertia = P[2]
    for i in range(3):
        dy[i] = v[i]
        dy[6 + i] = out[3 + i] / inertia
    dy[3] = P[5] - ax + out[0] / m
    dy[4] = P[6] - ay + out[1] / m
    dy[5] = P[7] - az + out[2] / m


@njit(cache=True)
def _rk4(t, y, h, sliding, P, S, kx, px, bx, cx, ky, py, by, cy, kz, pz, bz, cz):
    n = y.size
    k1 = np.empty(n)
    k2 = np.empty(n)
    k3 = np.empty(n)
    k4 = np.empty(n)
    tmp = np.empty(n)
    out = np.empty(6)
    _deriv(t, y, k1, out, sliding, P, S, kx, px, bx, cx, ky, py, by, cy, kz, pz, bz, cz)
    for i in range(n):
        tmp[i] = y[i] + 0.5 * h * k1[i]
    _deriv(t + 0.5 * h, tmp, k2, out, sliding, P, S, kx, px, bx, cx, ky, py, by, cy, kz, pz, bz,
           cz)
    for i in range(n):
        tmp[i] = y[i] + 0.5 * h * k2[i]
    _deriv(t + 0.5 * h, tmp, k3, out, sliding, P, S, kx, px, bx, cx, ky, py, by, cy, kz, pz, bz,
           cz)
    for i in range(n):
        tmp[i] = y[i] + h * k3[i]
    _deriv(t + h, tmp, k4, out, sliding, P, S, kx, px, bx, cx, ky, py, by, cy, kz, pz, bz, cz)
    for i in range(n):
        tmp[i] = y[i] + (h / 6.0) * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
    return tmp


@njit(cache=True)
def _settle_history(y, sliding, P, S):
    """After a step: history springs into the tangent plane, capped at mu F_n (stick/slip)."""
    p = y[0:3]
    v = y[3:6]
    w = y[6:9]
    R = P[1]
    for s in range(3):
        k = 9 + 3 * s
        delta, nx, ny, nz = _geometry(s, p, R, P)
        if delta <= 0.0:
            y[k] = 0.0
            y[k + 1] = 0.0
            y[k + 2] = 0.0
            sliding[s] = False
            continue
        xn = y[k] * nx + y[k + 1] * ny + y[k + 2] * nz
        y[k] -= xn * nx
        y[k + 1] -= xn * ny
        y[k + 2] -= xn * nz
        fn, ktt, ctt = _normal_force(s, delta, v, nx, ny, nz, S)
        fpos = fn if fn > 0.0 else 0.0
        vtx, vty, vtz = _slip_velocity(v, w, R, nx, ny, nz)
        ftx = -ktt * y[k] - ctt * vtx
        fty = -ktt * y[k + 1] - ctt * vty
        ftz = -ktt * y[k + 2] - ctt * vtz
        ft = math.sqrt(ftx * ftx + fty * fty + ftz * ftz)
        mu = S[s, 9] if sliding[s] else S[s, 8]
        if ft > mu * fpos:
            sliding[s] = True
            if ktt > 0.0 and ft > 0.0:
                spring = S[s, 9] * fpos / (ktt * ft)
                y[k] = -ftx * spring
                y[k + 1] = -fty * spring
                y[k + 2] = -ftz * spring
            else:
                y[k] = 0.0
                y[k + 1] = 0.0
                y[k + 2] = 0.0
        else:
            sliding[s] = False


@njit(cache=True)
def overlaps(y, P):
    """Overlaps [m] of the ball with the lower plate, upper plate, wall (> 0: touching)."""
    d = np.empty(3)
    for s in range(3):
        d[s] = _geometry(s, y[0:3], P[1], P)[0]
    return d


@njit(cache=True)
def _contact_step(y, P, S, steps):
    """RK4 step [s] resolving every active contact with ``steps`` steps per period.

    Near the edge of a Hertz contact (delta -> 0, where delta^(1/4) and
    delta^(1/2) are not smooth) the step also stays below EDGE_FRACTION
    delta / |d delta/dt| (never below 1/EDGE_REFINE of the bulk step), so
    entry and exit are resolved geometrically.
    """
    m = P[0]
    h = math.inf
    h_edge = math.inf
    for s in range(3):
        delta, nx, ny, nz = _geometry(s, y[0:3], P[1], P)
        if delta <= 0.0:
            continue
        e = S[s, 2]
        kn = S[s, 1]
        stiff = kn * e * delta ** (e - 1.0)
        cn, ktt, ctt = _coefficients(S, s, delta)
        omega = math.sqrt(max(stiff, 3.5 * ktt) / m)
        damp = max(cn, 3.5 * ctt) / m
        # oscillation: `steps` per period; an overdamped mode (|eigenvalue| <= c/m)
        # only has to decay stably and smoothly: h c/m <= DAMPED_STEP * 64 / steps
        if omega > 0.0:
            h = min(h, 2.0 * math.pi / omega / steps)
        if damp > 0.0:
            h = min(h, DAMPED_STEP * 64.0 / steps / damp)
        speed = abs(y[3] * nx + y[4] * ny + y[5] * nz)
        if speed > 0.0:
            # time to the largest penetration of an undamped impact at this speed
            dm = ((e + 1.0) * m * speed * speed / (2.0 * kn)) ** (1.0 / (e + 1.0))
            h = min(h, 2.0 * math.pi * dm / speed / steps)
            if S[s, 0] == 0.0:
                h_edge = min(h_edge, EDGE_FRACTION * delta / speed)
    if h_edge < h:
        h = max(h_edge, h / EDGE_REFINE)
    return h


@njit(cache=True)
def _flight_state(t, t0, y0, Y0, Yd0, P, kx, px, bx, cx, ky, py, by, cy, kz, pz, bz, cz):
    s = t - t0
    Y, Yd, _ = table3(t, kx, px, bx, cx, ky, py, by, cy, kz, pz, bz, cz)
    y = y0.copy()
    for i in range(3):
        y[i] = y0[i] + y0[3 + i] * s + 0.5 * P[5 + i] * s * s - (Y[i] - Y0[i] - Yd0[i] * s)
        y[3 + i] = y0[3 + i] + P[5 + i] * s - (Yd[i] - Yd0[i])
    return y


@njit(cache=True)
def _flight_bound(y, P, acc_z, acc_xy):
    """Longest time [s] in which free flight from y cannot touch any surface."""
    if P[GEOM] == SPHERE_KIND:
        return _flight_bound_sphere(y, P, acc_z, acc_xy)
    R = P[1]
    H = P[3]
    Rt = P[4]
    vz = y[5]
    tau = math.inf
    d_low = y[2] - R
    d_up = H - R - y[2]
    if acc_z > 0.0:
        tau = min(tau, (vz + math.sqrt(vz * vz + 2.0 * acc_z * max(d_low, 0.0))) / acc_z)
        tau = min(tau, (-vz + math.sqrt(vz * vz + 2.0 * acc_z * max(d_up, 0.0))) / acc_z)
    else:
        if vz < 0.0:
            tau = min(tau, max(d_low, 0.0) / -vz)
        if vz > 0.0:
            tau = min(tau, max(d_up, 0.0) / vz)
    # wall: rho(s) <= |q + u s| + acc_xy s^2 / 2 must stay <= Rt - R
    rmax = Rt - R
    qx, qy, ux, uy = y[0], y[1], y[3], y[4]
    q2 = qx * qx + qy * qy
    qu = qx * ux + qy * uy
    u2 = ux * ux + uy * uy
    if tau == math.inf:
        tau = 1.0
    for _ in range(60):
        r = math.sqrt(max(q2 + 2.0 * qu * tau + u2 * tau * tau, 0.0)) + 0.5 * acc_xy * tau * tau
        if r <= rmax:
            return tau
        tau *= 0.5
    return 0.0


@njit(cache=True)
def _flight_bound_sphere(y, P, acc_z, acc_xy):
    """Longest time [s] in which free flight from y cannot reach the spherical wall:
    ``|q + u s| + acc s^2 / 2 <= a - R`` (q: the centre from the sphere's centre,
    u: the velocity, acc: the bound of |g - Y''| on the three axes)."""
    R = P[1]
    a = P[GEOM + 2]
    rmax = a - R
    qx, qy, qz = y[0], y[1], y[2] - P[GEOM + 1]
    ux, uy, uz = y[3], y[4], y[5]
    q2 = qx * qx + qy * qy + qz * qz
    qu = qx * ux + qy * uy + qz * uz
    u2 = ux * ux + uy * uy + uz * uz
    acc = math.sqrt(acc_z * acc_z + acc_xy * acc_xy)
    room = rmax - math.sqrt(q2)
    if room <= 0.0:
        return 0.0
    un = math.sqrt(u2)
    # the triangle inequality's bound |q| + |u| s + acc s^2/2 <= rmax (always valid)
    if acc > 0.0:
        safe = 2.0 * room / (un + math.sqrt(un * un + 2.0 * acc * room))
    elif un > 0.0:
        safe = room / un
    else:
        safe = math.inf
    tau = 1.0
    for _ in range(60):
        if tau <= safe:
            return safe if safe < math.inf else tau
        r = math.sqrt(max(q2 + 2.0 * qu * tau + u2 * tau * tau, 0.0)) + 0.5 * acc * tau * tau
        if r <= rmax:
            return tau
        tau *= 0.5
    return safe


@njit(cache=True)
def _grow(buf, n):
    if n < buf.shape[0]:
        return buf
    new = np.empty((2 * buf.shape[0], buf.shape[1]))
    new[:buf.shape[0]] = buf
    return new


@njit(cache=True)
def _put_episode(episodes, n, s, t_in, speed_in, initial):
    episodes[n, 0] = s
    episodes[n, 1] = t_in
    episodes[n, 2] = math.nan
    episodes[n, 3] = speed_in
    episodes[n, 4] = math.nan
    episodes[n, 5] = 0.0
    episodes[n, 6] = initial


@njit(cache=True)
def run_3d(P, S, steps, t_start, t_end, y_start, rest_start, max_steps,
           kx, px, bx, cx, ky, py, by, cy, kz, pz, bz, cz, acc_z, acc_xy):
    """Integrate from t_start to t_end; returns (status, knots, n_knots, episodes, n_episodes).

    knots[i] = (t, p, v, w, mode); episodes[j] = (surface, t_in, t_out, speed_in,
    speed_out, steps, initial) with speeds the normal approach/departure
    speeds [m/s]; status 0 ok, 1 step budget exhausted.
    """
    knots = np.empty((4096, KNOT_WIDTH))
    episodes = np.empty((256, 7))
    n_k = 0
    n_e = 0
    open_ep = np.full(3, -1, dtype=np.int64)
    sliding = np.zeros(3, dtype=np.bool_)
    y = y_start.copy()
    t = t_start
    d = overlaps(y, P)
    for s in range(3):
        if d[s] > 0.0:
            episodes = _grow(episodes, n_e)
            _put_episode(episodes, n_e, s, t, 0.0, 1.0 if rest_start else 0.0)
            open_ep[s] = n_e
            n_e += 1
    total = 0
    h_probe_min = 1e-12
    while t < t_end:
        total += 1
        if total > max_steps:
            knots = _grow(knots, n_k)
            knots[n_k, 0] = t
            knots[n_k, 1:10] = y[0:9]
            knots[n_k, 10] = CONTACT
            return 1, knots, n_k + 1, episodes, n_e
        d = overlaps(y, P)
        in_contact = d[0] > 0.0 or d[1] > 0.0 or d[2] > 0.0
        knots = _grow(knots, n_k)
        knots[n_k, 0] = t
        knots[n_k, 1:10] = y[0:9]
        knots[n_k, 10] = CONTACT if in_contact else FLIGHT
        n_k += 1
        if not in_contact:
            Y0, Yd0, _ = table3(t, kx, px, bx, cx, ky, py, by, cy, kz, pz, bz, cz)
            tau = _flight_bound(y, P, acc_z, acc_xy)
            # a probe step no shorter than a fine contact step at the closing speed
            speed = math.sqrt(y[3] * y[3] + y[4] * y[4] + y[5] * y[5])
            probe = max(_probe(y, P, S, steps, speed), h_probe_min)
            tau = max(tau, probe)
            tau = min(tau, t_end - t)
            y1 = _flight_state(t + tau, t, y, Y0, Yd0, P, kx, px, bx, cx, ky, py, by, cy,
                               kz, pz, bz, cz)
            d1 = overlaps(y1, P)
            if d1[0] > 0.0 or d1[1] > 0.0 or d1[2] > 0.0:
                lo = 0.0
                hi = tau
                for _ in range(BISECTIONS):
                    mid = 0.5 * (lo + hi)
                    ym = _flight_state(t + mid, t, y, Y0, Yd0, P, kx, px, bx, cx, ky, py, by,
                                       cy, kz, pz, bz, cz)
                    dm = overlaps(ym, P)
                    if dm[0] > 0.0 or dm[1] > 0.0 or dm[2] > 0.0:
                        hi = mid
                    else:
                        lo = mid
                tau = hi
                y1 = _flight_state(t + tau, t, y, Y0, Yd0, P, kx, px, bx, cx, ky, py, by, cy,
                                   kz, pz, bz, cz)
                d1 = overlaps(y1, P)
                for s in range(3):
                    if d1[s] > 0.0:
                        _, nx, ny, nz = _geometry(s, y1[0:3], P[1], P)
                        episodes = _grow(episodes, n_e)
                        _put_episode(episodes, n_e, s, t + tau,
                                     -(y1[3] * nx + y1[4] * ny + y1[5] * nz), 0.0)
                        open_ep[s] = n_e
                        n_e += 1
            y = y1
            t = t + tau
            continue
        # contact step
        h = min(_contact_step(y, P, S, steps), t_end - t)
        y1 = _rk4(t, y, h, sliding, P, S, kx, px, bx, cx, ky, py, by, cy, kz, pz, bz, cz)
        d1 = overlaps(y1, P)
        if _touched_set_changed(d, d1):
            # cut the step back to the first change of the set of touched surfaces
            lo = 0.0
            hi = h
            for _ in range(BISECTIONS):
                mid = 0.5 * (lo + hi)
                ym = _rk4(t, y, mid, sliding, P, S, kx, px, bx, cx, ky, py, by, cy, kz, pz, bz,
                          cz)
                if not _touched_set_changed(d, overlaps(ym, P)):
                    lo = mid
                else:
                    hi = mid
            h = hi
            y1 = _rk4(t, y, h, sliding, P, S, kx, px, bx, cx, ky, py, by, cy, kz, pz, bz, cz)
            d1 = overlaps(y1, P)
        for s in range(3):
            if d[s] > 0.0 and open_ep[s] >= 0:
                episodes[open_ep[s], 5] += 1.0
        t = t + h
        for s in range(3):
            _, nx, ny, nz = _geometry(s, y1[0:3], P[1], P)
            vn = y1[3] * nx + y1[4] * ny + y1[5] * nz
            if d[s] > 0.0 and not d1[s] > 0.0:
                if open_ep[s] >= 0:
                    episodes[open_ep[s], 2] = t
                    episodes[open_ep[s], 4] = vn
                    open_ep[s] = -1
            elif d1[s] > 0.0 and not d[s] > 0.0:
                episodes = _grow(episodes, n_e)
                _put_episode(episodes, n_e, s, t, -vn, 0.0)
                open_ep[s] = n_e
                n_e += 1
        _settle_history(y1, sliding, P, S)
        y = y1
    knots = _grow(knots, n_k)
    knots[n_k, 0] = t
    knots[n_k, 1:10] = y[0:9]
    d = overlaps(y, P)
    knots[n_k, 10] = CONTACT if (d[0] > 0.0 or d[1] > 0.0 or d[2] > 0.0) else FLIGHT
    n_k += 1
    return 0, knots, n_k, episodes, n_e


@njit(cache=True)
def _probe(y, P, S, steps, speed):
    """Shortest flight step [s]: a contact step of the stiffest surface at ``speed``."""
    m = P[0]
    v = max(speed, 1e-3)
    h = math.inf
    for s in range(3):
        e = S[s, 2]
        kn = S[s, 1]
        dm = ((e + 1.0) * m * v * v / (2.0 * kn)) ** (1.0 / (e + 1.0))
        h = min(h, 2.0 * math.pi * dm / v / steps)
    return h


@njit(cache=True)
def sample_knots(times, knots, n_k, P, kx, px, bx, cx, ky, py, by, cy, kz, pz, bz, cz):
    """States (p, v, w) at ``times`` from the knots: exact flight, cubic Hermite in contact."""
    out = np.empty((times.size, 9))
    kt = knots[:n_k, 0]
    for j in range(times.size):
        t = times[j]
        i = np.searchsorted(kt, t, side="right") - 1
        if i < 0:
            i = 0
        if i > n_k - 2:
            i = n_k - 2 if n_k >= 2 else 0
        y0 = np.zeros(N_STATE)
        y0[0:9] = knots[i, 1:10]
        if knots[i, 10] == FLIGHT or n_k < 2:
            Y0, Yd0, _ = table3(knots[i, 0], kx, px, bx, cx, ky, py, by, cy, kz, pz, bz, cz)
            ys = _flight_state(t, knots[i, 0], y0, Y0, Yd0, P, kx, px, bx, cx, ky, py, by, cy,
                               kz, pz, bz, cz)
            out[j, 0:9] = ys[0:9]
            continue
        t0 = knots[i, 0]
        t1 = knots[i + 1, 0]
        h = t1 - t0
        u = (t - t0) / h if h > 0.0 else 0.0
        h00 = 2 * u ** 3 - 3 * u ** 2 + 1
        h10 = u ** 3 - 2 * u ** 2 + u
        h01 = -2 * u ** 3 + 3 * u ** 2
        h11 = u ** 3 - u ** 2
        d00 = (6 * u ** 2 - 6 * u) / h if h > 0.0 else 0.0
        d10 = 3 * u ** 2 - 4 * u + 1
        d01 = -d00
        d11 = 3 * u ** 2 - 2 * u
        for a in range(3):
            p0 = knots[i, 1 + a]
            p1 = knots[i + 1, 1 + a]
            v0 = knots[i, 4 + a]
            v1 = knots[i + 1, 4 + a]
            out[j, a] = h00 * p0 + h10 * h * v0 + h01 * p1 + h11 * h * v1
            out[j, 3 + a] = d00 * p0 + d10 * v0 + d01 * p1 + d11 * v1
            out[j, 6 + a] = (1.0 - u) * knots[i, 7 + a] + u * knots[i + 1, 7 + a]
    return out
