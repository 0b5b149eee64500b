"""The load ODE's compiled recurrence (:func:`tengfield.lumped.load_response`): its own
module, so that ``import tengfield`` does not load numba (the other kernels live in
``dynamics/_kernel.py``, ``harvest/_kernel.py``); warmed by ``python -m tengfield._warmup``."""
import numpy as np
from numba import njit


@njit(cache=True)
def deficit_recurrence(decay, source, start):
    """D_0 = ``start``, D_{k+1} = ``decay[k]`` D_k + ``source[k]`` [C]: the linear
    recurrence of :func:`tengfield.lumped.load_response`, O(n), compiled (a Python loop costs ~1 µs a
    sample); the same operations in the same order, so the same numbers."""
    deficit = np.empty(decay.size + 1)
    deficit[0] = start
    d = start
    for k in range(decay.size):
        d = decay[k] * d + source[k]
        deficit[k + 1] = d
    return deficit
