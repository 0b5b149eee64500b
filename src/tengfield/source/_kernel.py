"""The contact-charging recurrence of :func:`tengfield.source.charge.charge_history`,
compiled (a Python loop costs ~2.5 µs a contact; a 10-minute start-up at 20 Hz with
chatter holds ~10^5-10^6 contacts); its own module so that ``import tengfield`` does not
load numba; warmed by ``python -m tengfield._warmup``."""
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
