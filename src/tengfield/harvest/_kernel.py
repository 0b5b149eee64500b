"""The compiled kernels of :mod:`tengfield.harvest` (numba ``@njit(cache=True)``):
the bridges' diode laws, the backward-Euler transfer into the store, the store's
sinks and the time stepping of :func:`_harvest_kernel` (the scheme is described
in :mod:`tengfield.harvest`). Pure numerics on floats and arrays, SI."""
from __future__ import annotations

import math

import numpy as np

try:  # numba is a hard dependency of tengfield; the fallback keeps imports light in docs builds
    from numba import njit
except ImportError:  # pragma: no cover
    def njit(*args, **kwargs):
        return (lambda f: f) if not args or not callable(args[0]) else args[0]


@njit(cache=True)
def _path_current(x, model, forward, i_sat, n_vt, r_series):
    """Two diodes in series at total voltage x [V] -> current [A] (see :class:`Diode`)."""
    return _path_current_slope(x, model, forward, i_sat, n_vt, r_series)[0]


@njit(cache=True)
def _path_current_slope(x, model, forward, i_sat, n_vt, r_series):
    """(current [A], di/dx [S]) of two diodes in series at total voltage x [V]."""
    if model == 0:
        excess = x - 2.0 * forward
        if excess <= 0.0:
            return 0.0, 0.0
        if r_series > 0.0:
            return excess / r_series, 1.0 / r_series
        return math.inf, math.inf
    # Shockley: x = 2 n V_T ln(1 + i/I_s) + 2 R_s i  (two diodes, R_s each)
    a = 2.0 * n_vt
    r = 2.0 * r_series
    if r == 0.0:
        arg = x / a
        if arg > 700.0:
            return math.inf, math.inf
        return i_sat * math.expm1(arg), i_sat * math.exp(arg) / a
    # in y = ln(1 + i/I_s): h(y) = a y + r I_s (e^y - 1) - x is convex and increasing;
    # Newton converges monotonically once right of the root (after at most one step)
    ris = r * i_sat
    if x > 0.0:
        y = min(x / a, math.log1p(x / ris))
    else:
        y = x / a
    for _ in range(100):
        ey = math.exp(min(y, 700.0))
        h = a * y + ris * (ey - 1.0) - x
        new = y - h / (a + ris * ey)
        if abs(new - y) <= 1e-15 * (abs(new) + 1.0):
            y = new
            break
        y = new
    ey = math.exp(min(y, 700.0))
    return i_sat * math.expm1(min(y, 700.0)), i_sat * ey / (a + ris * ey)


@njit(cache=True)
def _cell_after(v, c, u_new, h, model, forward, i_sat, n_vt, r_series):
    """Terminal voltage V' [V] of one cell after the transfer step, store at u_new."""
    if model == 0:
        if v - u_new - 2.0 * forward > 0.0:
            target = u_new + 2.0 * forward
        elif -v - u_new - 2.0 * forward > 0.0:
            target = -(u_new + 2.0 * forward)
        else:
            return v
        if r_series == 0.0:
            return target
        g = h / r_series
        return (c * v + g * target) / (c + g)
    # Shockley. The equations are odd in V (paths A <-> B), so solve for |V| with path A
    # forward: i_A(V') = [C (v - V') + h i_B(V')] / h must equal i(V' - U), i.e.
    # R(V') = (V' - U) - x(i_A(V')) = 0 with x(i) = a ln(1 + i/I_s) + r i the path's
    # (explicit) inverse law: R is increasing and smooth, R(min(U, v) - 1) < 0 <= R(v).
    sign = 1.0 if v >= 0.0 else -1.0
    w = abs(v)
    a = 2.0 * n_vt
    r = 2.0 * r_series
    lo = min(u_new, w) - 1.0
    hi = w
    x = hi
    for it in range(300):
        i_b, g_b = _path_current_slope(-x - u_new, model, forward, i_sat, n_vt, r_series)
        i_a = (c * (w - x) + h * i_b) / h
        if i_a <= -i_sat:
            res = math.inf
            slope = math.inf
        else:
            res = (x - u_new) - (a * math.log1p(i_a / i_sat) + r * i_a)
            slope = 1.0 + (a / (i_sat + i_a) + r) * (c / h + g_b)
        if res > 0.0:
            hi = x
        else:
            lo = x
        # safeguarded Newton: every fourth step bisects, so the bracket always shrinks
        newton = math.isfinite(res) and math.isfinite(slope) and it % 4 != 3
        new = x - res / slope if newton else 0.5 * (lo + hi)
        if not (lo < new < hi):
            new = 0.5 * (lo + hi)
            newton = False
        # a Newton step that barely moves is a root only where the residual is small
        # too: at no transfer (i_A ~ -I_s) the law's slope is ~1e13 and the step tiny
        # with a residual of volts (issue #53: a 1.6 V spike of a Shockley bridge)
        if (newton and abs(new - x) <= 1e-14 * (abs(new) + 1e-3)
                and abs(res) <= 1e-9 * (abs(x) + 1e-3)) \
                or hi - lo <= 1e-14 * (abs(new) + 1e-3):
            return sign * new
        x = new
    return sign * x


@njit(cache=True)
def _cell_charges(v, va, c, u_new, h, model, forward, i_sat, n_vt, r_series):
    """(forward-path charge, reverse-path charge) [C] of one cell's bridge over the step,
    from the cell's charge balance C (v - V') = h (i_fwd - i_rev) (so both are exact
    for the computed V'); the forward path is the one V' biases forward."""
    if model == 0:
        return c * abs(v - va), 0.0
    sign = 1.0 if v >= 0.0 else -1.0
    q_rev = h * _path_current(-sign * va - u_new, model, forward, i_sat, n_vt, r_series)
    return c * (abs(v) - sign * va) + q_rev, q_rev


@njit(cache=True)
def _store_charge(volts, caps, u_new, h, model, forward, i_sat, n_vt, r_series, v_after):
    """Charge [C] into the store when it ends at u_new; fills v_after."""
    total = 0.0
    for k in range(volts.size):
        va = _cell_after(volts[k], caps[k], u_new, h, model, forward, i_sat, n_vt, r_series)
        v_after[k] = va
        q_fwd, q_rev = _cell_charges(volts[k], va, caps[k], u_new, h, model, forward, i_sat,
                                     n_vt, r_series)
        total += q_fwd + q_rev
    return total


@njit(cache=True)
def _transfer_clamp(volts, caps, u, c_store, forward, v_after):
    """Ideal clamping bridges (R_s = 0): ``C_L (U' - U) = sum C_j (a_j - U')_+`` with
    ``a_j = |V_j| - 2 V_F`` is piecewise linear and increasing in U': solved
    exactly by walking the sorted thresholds (O(n log n), no iteration)."""
    n = volts.size
    above = np.empty(n)
    index = np.empty(n, dtype=np.int64)
    m = 0
    for j in range(n):
        a = abs(volts[j]) - 2.0 * forward
        v_after[j] = volts[j]
        if a > u:
            above[m] = a
            index[m] = j
            m += 1
    if m == 0:
        return u
    order = np.argsort(-above[:m])
    num = c_store * u
    den = c_store
    u_new = u
    for k in range(m):
        j = index[order[k]]
        num += caps[j] * above[order[k]]
        den += caps[j]
        u_new = num / den
        if k == m - 1 or u_new >= above[order[k + 1]]:
            break
    for k in range(m):
        j = index[k]
        if above[k] > u_new:
            v_after[j] = (u_new + 2.0 * forward) * (1.0 if volts[j] >= 0.0 else -1.0)
    return u_new


@njit(cache=True)
def _transfer(volts, caps, u, c_store, h, model, forward, i_sat, n_vt, r_series, v_after):
    """Backward-Euler bridge conduction at fixed capacitances; returns U'."""
    if model == 0 and r_series == 0.0:
        return _transfer_clamp(volts, caps, u, c_store, forward, v_after)
    # G(U') = C_L (U' - U) - Q_store(U') is increasing in U'
    g0 = -_store_charge(volts, caps, u, h, model, forward, i_sat, n_vt, r_series, v_after)
    if g0 == 0.0:
        return u
    charge = 2.0 * h * i_sat * volts.size     # bound on what the step can move [C]
    for k in range(volts.size):
        charge += caps[k] * abs(volts[k])
    if g0 > 0.0:                      # net reverse leakage: the root lies in [0, U)
        lo = max(0.0, u - charge / c_store)
        hi = u
    else:
        lo = u
        hi = u + charge / c_store
        for _ in range(60):           # make sure G(hi) > 0
            if c_store * (hi - u) - _store_charge(volts, caps, hi, h, model, forward, i_sat,
                                                  n_vt, r_series, v_after) > 0.0:
                break
            hi = u + 2.0 * (hi - u)
    tol = 1e-15 * (hi - lo) + 1e-300
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        g = c_store * (mid - u) - _store_charge(volts, caps, mid, h, model, forward, i_sat,
                                                n_vt, r_series, v_after)
        if g > 0.0:
            hi = mid
        else:
            lo = mid
        if hi - lo <= tol:
            break
    u_new = 0.5 * (lo + hi)
    _store_charge(volts, caps, u_new, h, model, forward, i_sat, n_vt, r_series, v_after)
    return u_new


@njit(cache=True)
def _decay(u, h, c_store, leak, quiescent, power, on, rising, falling):
    """Store over h [s]: leakage U/R, a constant current and (while on) constant power.

    Returns (U', on', leak energy, quiescent energy, chip energy, on time).
    Each sink acts exactly over the step in turn (Lie splitting); the lockout
    switches off at the exact instant U^2 falls through uvlo_falling^2.
    """
    e_leak = e_q = e_chip = on_time = 0.0
    u0 = u
    if leak < math.inf and leak > 0.0:
        u = u * math.exp(-h / (leak * c_store))
        e_leak = 0.5 * c_store * (u0 * u0 - u * u)
    if quiescent > 0.0 and u > 0.0:
        drop = min(u, quiescent * h / c_store)
        u1 = u - drop
        e_q = 0.5 * c_store * (u * u - u1 * u1)
        u = u1
    if on and power > 0.0:
        # d(U^2)/dt = -2 P / C_L until U = falling
        u2 = u * u - 2.0 * power * h / c_store
        if u2 <= falling * falling:
            t_off = 0.5 * c_store * (u * u - falling * falling) / power
            t_off = min(max(t_off, 0.0), h)
            on_time = t_off
            e_chip = power * t_off
            u = min(u, falling)
            on = False
        else:
            u1 = math.sqrt(u2)
            on_time = h
            e_chip = 0.5 * c_store * (u * u - u1 * u1)
            u = u1
    return u, on, e_leak, e_q, e_chip, on_time


@njit(cache=True)
def _harvest_kernel(q_sc, c_t, times, c_store, leak, model, forward, i_sat, n_vt, r_series,
                    has_chip, rising, falling, power, quiescent, shunt,
                    deficit, state, acc, volts, store, bridge_charge, chip_on, energies):
    """Step the cells (columns of q_sc, c_t) and the store along ``times``.

    Resumable: row 0 is the state the run is in (``deficit[j] = Q_SC - Q_b`` of
    each cell, ``state = [U, chip on, first rising crossing, first lockout]``,
    ``acc`` the 9 cumulative energies), all updated in place. Fills volts[k, j],
    store[k], bridge_charge[k, j] (cumulative from row 0, lower -> upper),
    chip_on[k] and energies[k, :] (cumulative: mechanical work, bridge, diode
    loss, store gain in transfer, leak, quiescent, chip input, shunt, the
    scheme's own dissipation)."""
    n_steps, n_cells = q_sc.shape
    v_before = np.empty(n_cells)
    v_after = np.empty(n_cells)
    caps = np.empty(n_cells)
    for j in range(n_cells):
        volts[0, j] = deficit[j] / c_t[0, j]
        bridge_charge[0, j] = 0.0
    u = state[0]
    on = state[1] != 0.0
    store[0] = u
    chip_on[0] = 1 if on else 0
    energies[0, :] = acc
    for k in range(1, n_steps):
        h = times[k] - times[k - 1]
        # 1. move, bridges blocked
        for j in range(n_cells):
            e_before = 0.5 * deficit[j] * deficit[j] / c_t[k - 1, j]
            deficit[j] += q_sc[k, j] - q_sc[k - 1, j]
            caps[j] = c_t[k, j]
            v_before[j] = deficit[j] / caps[j]
            acc[0] += 0.5 * deficit[j] * deficit[j] / caps[j] - e_before
        # 2. transfer
        pinned = False
        if h > 0.0 and has_chip and quiescent > 0.0 and u == 0.0:
            # an empty store the chip's quiescent draw holds at 0 V: if the bridges move
            # no more than I_q h over the step, the chip takes it as it comes, at U = 0:
            # nothing is stored, no energy enters the store (the split step raised U to
            # dq / C_L and drained it again, booking O(h) energy: issue #30.5)
            pinned = _store_charge(v_before, caps, 0.0, h, model, forward, i_sat, n_vt,
                                   r_series, v_after) <= quiescent * h
        if pinned:
            u_new = 0.0
        elif h > 0.0:
            u_new = _transfer(v_before, caps, u, c_store, h, model, forward, i_sat, n_vt,
                              r_series, v_after)
        else:
            u_new = u
            for j in range(n_cells):
                v_after[j] = v_before[j]
        gained = 0.0
        for j in range(n_cells):
            vm = v_before[j]
            va = v_after[j]
            moved = caps[j] * (vm - va)              # q: lower -> upper through the bridge
            if moved != 0.0:
                # mechanical work of the move, less the overshoot the blocked move added
                # (the clamped terminal never reaches vm): W = W_move - C (vm - va)^2 / 2
                if pinned and va == 0.0:
                    # clamped at 0 V: the move's field energy all went through the bridge
                    # at U = 0 (no work kept); the same expression as step 1, so an empty
                    # store's books stay exactly zero
                    acc[0] -= 0.5 * deficit[j] * deficit[j] / caps[j]
                else:
                    acc[0] -= 0.5 * caps[j] * (vm - va) ** 2
                acc[1] += va * moved                 # energy into the bridge (backward Euler)
            if moved != 0.0 or model == 1:
                q_fwd, q_rev = _cell_charges(vm, va, caps[j], u_new, h, model, forward, i_sat,
                                             n_vt, r_series)
                x_fwd = (va if vm >= 0.0 else -va) - u_new   # forward path voltage
                acc[2] += q_fwd * x_fwd + q_rev * (-x_fwd - 2.0 * u_new)
                gained += q_fwd + q_rev
            deficit[j] = caps[j] * va
            bridge_charge[k, j] = bridge_charge[k - 1, j] + moved
            volts[k, j] = va
        acc[3] += u_new * gained                     # energy into the store (backward Euler)
        acc[8] += 0.5 * c_store * (u_new - u) ** 2   # the scheme's own dissipation
        u = u_new
        if has_chip:
            if u > shunt:
                acc[7] += 0.5 * c_store * (u * u - shunt * shunt)
                u = shunt
            if (not on) and u >= rising:
                on = True
                if math.isnan(state[2]):
                    state[2] = times[k]
        # 3. store sinks
        if h > 0.0:
            was_on = on
            u, on, e_leak, e_q, e_chip, on_time = _decay(
                u, h, c_store, leak, quiescent if has_chip else 0.0,
                power if has_chip else 0.0, on, rising, falling)
            acc[4] += e_leak
            acc[5] += e_q
            acc[6] += e_chip
            if was_on and not on and math.isnan(state[3]):
                state[3] = times[k - 1] + on_time
        store[k] = u
        chip_on[k] = 1 if on else 0
        energies[k, :] = acc
    state[0] = u
    state[1] = 1.0 if on else 0.0
