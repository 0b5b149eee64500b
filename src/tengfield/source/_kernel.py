"""The source's compiled kernels, in their own module so that ``import tengfield`` does not
load numba; warmed by ``python -m tengfield._warmup``: the contact-charging recurrence of
:func:`tengfield.source.charge.charge_history` (a Python loop costs ~2.5 µs a contact; a
10-minute start-up at 20 Hz with chatter holds ~10^5-10^6 contacts) and the surrogate's
splines at many cells' gaps in one pass (:meth:`tengfield.source.Source.each_cell`, an
``[array]``'s cells)."""
import numpy as np
from numba import njit


@njit(cache=True)
def contact_recurrence(decay, fraction, q_eq, q_cap, start):
    """Per contact n: q <- decay[n] q (leakage since the last), then
    q <- q + fraction[n] (q_eq - q), both clipped to [-q_cap, q_cap]; returns the
    charges just before and just after each contact [C]."""
    before = np.empty(decay.size)
    after = np.empty(decay.size)
    q = start
    for n in range(decay.size):
        q = min(max(q * decay[n], -q_cap), q_cap)
        before[n] = q
        q = min(max(q + fraction[n] * (q_eq - q), -q_cap), q_cap)
        after[n] = q
    return before, after


@njit(cache=True)
def spline_terminal(z, v, knots, cq, cc, stroke):
    """Q_SC(z) [C], C_T(z) [F] and (dQ_SC/dz) v [A] of the surrogate's cubic splines (their
    piecewise coefficients ``cq``, ``cc`` on ``knots``), z [m] clipped to [0, stroke], at
    the gap rates ``v`` [m/s]: one interval search for the three."""
    n = z.size
    q = np.empty(n)
    c = np.empty(n)
    i = np.empty(n)
    last = knots.size - 2
    for k in range(n):
        x = min(max(z[k], 0.0), stroke)
        j = np.searchsorted(knots, x, side="right") - 1
        j = min(max(j, 0), last)
        d = x - knots[j]
        q[k] = ((cq[0, j] * d + cq[1, j]) * d + cq[2, j]) * d + cq[3, j]
        c[k] = ((cc[0, j] * d + cc[1, j]) * d + cc[2, j]) * d + cc[3, j]
        slope = (3.0 * cq[0, j] * d + 2.0 * cq[1, j]) * d + cq[2, j]
        i[k] = slope * v[k]
    return q, c, i
