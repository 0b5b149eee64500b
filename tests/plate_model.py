"""Analytic stand-ins for the field solver and the dynamics (test fixtures only).

No tests live here. ``plate_model_solve`` mimics
:func:`tengfield.field.solve_position` with a closed-form parallel-plate
model (Shockley–Ramo induced charges of a point charge at the ball centre,
a smooth position-dependent mutual capacitance); ``FakeDynamics`` mimics a
:class:`DynamicsResult` for a prescribed z(t). Neither is ever shipped as a
result: they only exercise the surrogate/circuit/pipeline machinery.
"""
from __future__ import annotations

import math

import numpy as np

from tengfield.field.result import PositionResult
from tengfield.scene import EPS0


def plate_model(scene, z):
    """(C_ll, C_lu, C_uu, q_l, q_u) of the analytic model at gap z [m] (arrays ok).

    Mirror-symmetric like the real device: z -> Δh - z swaps lower and upper.
    """
    dev = scene.device
    z = np.asarray(z, dtype=float)
    h = dev.plate_spacing
    stroke = dev.stroke
    centre = z + dev.ball_radius
    c0 = EPS0 * math.pi * dev.electrode_radius**2 / h
    decay = stroke / 6.0   # the dielectric ball near a plate raises the capacitances
    near_lower, near_upper = np.exp(-z / decay), np.exp(-(stroke - z) / decay)
    mutual = c0 * (1.0 + 0.4 * near_lower + 0.4 * near_upper)
    c_ll = mutual + c0 * (0.3 + 0.05 * near_lower)
    c_uu = mutual + c0 * (0.3 + 0.05 * near_upper)
    # Shockley–Ramo share of a point charge, bent by finite electrodes
    u = centre / h

    def share(x):
        return 0.95 * x + 0.04 * np.sin(3.0 * np.pi * x)
    q_u = -dev.ball_charge * share(u)
    q_l = -dev.ball_charge * share(1.0 - u)
    return c_ll, -mutual, c_uu, q_l, q_u


def plate_model_solve(scene, position, *, comm=None, **_):
    """Drop-in for ``solve_position`` built on :func:`plate_model`."""
    c_ll, c_lu, c_uu, q_l, q_u = (float(v) for v in plate_model(scene, position))
    return PositionResult(position=float(position), offset=0.0,
                          capacitance=[[c_ll, c_lu], [c_lu, c_uu]],
                          induced_charge=[q_l, q_u], ball_charge=scene.device.ball_charge,
                          dofs=1000, cells=2000,   # mesh cells (not [device] cells)
                          method="axisymmetric", degree=2,
                          wall_time=0.01, relative_error_estimate=1e-6, solve_time=0.005)


class CountingSolver:
    """``plate_model_solve`` that counts its calls (to see cache hits)."""

    def __init__(self):
        self.calls = 0

    def __call__(self, scene, position, *, comm=None, **kw):
        self.calls += 1
        return plate_model_solve(scene, position, comm=comm, **kw)


class FakeDynamics:
    """A prescribed trajectory with the attributes of a DynamicsResult.

    ``kind = "smooth"``: z = Δh (1 - cos ωt) / 2 (no impacts).
    ``kind = "bounce"``: a triangle wave between the plates at constant
    speed, one impact on each plate per period (velocity jumps).
    """

    PHASE = 0.1234   # keeps the impacts off the sample times

    def __init__(self, scene, kind="smooth", duration=None, sample_rate=None):
        self.scene = scene
        self.kind = kind
        self.stroke = scene.device.stroke
        self.omega = scene.excitation.omega
        self.period = scene.excitation.period
        duration = scene.run.duration if duration is None else duration
        rate = scene.run.sample_rate if sample_rate is None else sample_rate
        self.t = np.arange(int(round(duration * rate)) + 1) / rate
        self.gap, self.gap_velocity, self.table = self.sample(self.t)
        if kind == "bounce":   # impacts where the phase passes 0 (lower) and 1/2 (upper)
            k = np.arange(1, int(2 * duration / self.period) + 2)
            times = (0.5 * k - self.PHASE) * self.period
            self.impacts = times[(times > 0) & (times <= duration)]
        else:
            self.impacts = np.empty(0)
        self.regime = {"name": "prescribed", "period": 1, "contacts_per_period": 1,
                       "max_gap": float(self.gap.max())}
        self.status = "ok"
        self.message = f"prescribed {kind} trajectory"
        self.wall_time = 0.0

    def sample(self, times):
        t = np.asarray(times, dtype=float)
        table = np.zeros_like(t)
        if self.kind == "smooth":
            gap = 0.5 * self.stroke * (1.0 - np.cos(self.omega * t))
            vel = 0.5 * self.stroke * self.omega * np.sin(self.omega * t)
            return gap, vel, table
        phase = np.mod(t / self.period + self.PHASE, 1.0)
        speed = 2.0 * self.stroke / self.period
        rising = phase < 0.5
        gap = np.where(rising, phase, 1.0 - phase) * 2.0 * self.stroke
        vel = np.where(rising, speed, -speed)
        return gap, vel, table


def scene_with(**sections):
    """The default scene with file-level overrides, e.g. ``circuit={"kind": "load"}``."""
    from tengfield.scene import default_scene
    return default_scene().with_values(**sections)


#: a short run with a coarse field (seconds of work): the CLI tests' small scene
SMALL_SCENE = """\
[run]
duration_s = 0.3
settle_periods = 2
sample_rate_hz = 5000.0

[field]
mesh_size_mm = 1.5
degree = 1
tolerance = 0.05
"""
