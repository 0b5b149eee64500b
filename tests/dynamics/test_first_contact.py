"""The next impact is the FIRST contact: compared with a brute-force fine search."""
import math

import numpy as np
from scipy.optimize import minimize_scalar

from tengfield.dynamics.impact import Restitution, integrate
from tengfield.dynamics.table import sine_table
from tengfield.scene import G

N_RANDOM = 600
N_GRAZING = 600


def _flight(table_params, z0, v0, t):
    amp, w, ph = table_params
    y = amp * np.sin(w * t + ph)
    y0, yd0 = amp * math.sin(ph), amp * w * math.cos(ph)
    return z0 + v0 * t - 0.5 * G * t**2 - (y - y0 - yd0 * t)


def _first_impact(params, stroke, z0, v0, horizon):
    table = sine_table(*params)
    traj, imp, _ = integrate(table, stroke, Restitution(0.5), t_start=0.0, t_end=horizon,
                             gap0=z0, velocity0=v0, period=horizon)
    if len(imp[0]) == 0:
        return math.inf, -1
    return imp[0][0], imp[1][0]


def _brute_first_crossing(params, stroke, z0, v0, horizon, n=40001):
    t = np.linspace(0.0, horizon, n)
    z = _flight(params, z0, v0, t)
    out = np.flatnonzero((z < 0.0) | (z > stroke))
    return (t[out[0]] if out.size else math.inf), t, z


def test_no_missed_impact_random_flights():
    rng = np.random.default_rng(1)
    checked = 0
    for _ in range(N_RANDOM):
        f = rng.uniform(5, 80)
        params = (rng.uniform(0, 5e-3), 2 * math.pi * f, rng.uniform(0, 2 * math.pi))
        stroke = rng.uniform(1e-3, 5e-3)
        z0 = rng.uniform(0.05, 0.95) * stroke
        v0 = rng.uniform(-0.5, 0.5)
        horizon = 1.0 / f
        t_hit, plate = _first_impact(params, stroke, z0, v0, horizon)
        t_brute, t, z = _brute_first_crossing(params, stroke, z0, v0, horizon)
        # nothing crosses a plate before the reported impact ...
        before = t < t_hit - 1e-9
        assert np.all(z[before] >= -1e-12) and np.all(z[before] <= stroke + 1e-12)
        # ... and the reported impact is no later than the first sampled crossing
        assert t_hit <= t_brute + 1e-12
        if math.isfinite(t_hit):
            zh = _flight(params, z0, v0, np.array([t_hit]))[0]
            assert abs(zh - (0.0 if plate == 0 else stroke)) < 1e-11
            checked += 1
    assert checked > N_RANDOM // 2


def test_near_grazing_flights():
    """The upper plate sits a hair below or above the apex of the flight."""
    rng = np.random.default_rng(2)
    hits = misses = 0
    for _ in range(N_GRAZING):
        f = rng.uniform(5, 80)
        params = (rng.uniform(0, 3e-3), 2 * math.pi * f, rng.uniform(0, 2 * math.pi))
        v0 = rng.uniform(0.05, 0.4)
        horizon = 1.0 / f
        t_grid = np.linspace(0, horizon, 4001)
        z_grid = _flight(params, 0.0, v0, t_grid)
        if np.any(z_grid[1:] < 0):       # keep flights that stay above the lower plate
            first_neg = np.flatnonzero(z_grid[1:] < 0)[0] + 1
            t_grid, z_grid = t_grid[:first_neg], z_grid[:first_neg]
        k = int(np.argmax(z_grid))
        if k == 0 or k == z_grid.size - 1:
            continue
        opt = minimize_scalar(lambda s: -_flight(params, 0.0, v0, np.array([s]))[0],
                              bounds=(t_grid[k - 1], t_grid[k + 1]), method="bounded",
                              options={"xatol": 1e-14})
        apex = -opt.fun
        delta = 10 ** rng.uniform(-11, -7) * rng.choice([-1.0, 1.0])
        stroke = apex + delta
        t_hit, plate = _first_impact(params, stroke, 1e-12, v0, t_grid[-1])
        if delta < 0:   # the apex is beyond the plate: the contact must be found
            assert plate == 1, (params, v0, delta)
            assert t_hit <= opt.x + 1e-12
            hits += 1
        else:           # the ball turns back a hair below the plate: no upper contact
            assert plate != 1, (params, v0, delta)
            misses += 1
    assert hits > 100 and misses > 100
