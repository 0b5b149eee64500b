"""Contact laws of the 3D ball: parameters from the scene (derivations in docs/motion3d.md).

Hertz (``[contact] law = "hertz"``), per surface (lower plate, upper plate, wall):

* normal ``F_n = (4/3) E* sqrt(R_e) delta^(3/2) + gamma_n d(delta)/dt`` (clamped at 0),
  ``1/E* = (1 - nu_b^2)/E_b + (1 - nu_s^2)/E_s``;
* damping from the restitution e (Chrono's SMC form)
  ``gamma_n = -2 sqrt(5/6) beta sqrt(S_n m)``, ``S_n = 2 E* sqrt(R_e delta)``,
  with ``beta = ln e / sqrt(ln^2 e + pi^2)`` (``damping_model = "chrono"``) or
  (``"calibrated"``, default) the beta for which the clamped contact rebounds
  with exactly e: with this damping form the rebound does not depend on the
  impact speed, so one scalar per e, found once from the dimensionless
  contact ``x'' = -x^1.5 - a x^(1/4) x'`` (clamped) (a = 2 sqrt(5/6) sqrt(3/2) |beta|);
* tangential spring ``k_t = 8 G* sqrt(R_e delta)``,
  ``1/G* = 2(2 - nu_b)(1 + nu_b)/E_b + 2(2 - nu_s)(1 + nu_s)/E_s``, damping
  ``gamma_t = -2 sqrt(5/6) beta sqrt(S_t m)``, ``S_t = k_t``;
* R_e: the ball radius R on a plate; on the concave tube wall (radius R_t) the
  principal relative radii are R (along the axis) and R R_t/(R_t - R) (around
  it); Johnson's equivalent radius is their geometric mean; inside a concave
  sphere (the spherical shell's cavity, radius a) both are R a/(a - R).

The surfaces, their kinds, radii and materials (``plate``: the electrodes,
``wall``: the tube's wall or the shell's insulating band) come from the cell
(:func:`tengfield.field.cells.contact_surfaces.contact_surfaces`).

Power law (``law = "power"``, the multibody IMPACT form)
``F_n = k delta^e + STEP(delta; 0, 0, d_max, c_max) d(delta)/dt`` (not clamped,
as Eq. 1), ``k = stiffness_N_per_m``, ``e = exponent``; ``c_max`` =
``damping_N_s_per_m`` or, if that is negative, ``2 zeta sqrt(m k)`` of Eq. 3
(exact restitution for e = 1). Tangential spring ``(2/7) dF/d(delta)``
(equal normal and tangential periods) with damping ``(2/7) c``.
"""
from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from ...errors import SceneError
from ..soft import damping_ratio

SURFACES = ("lower", "upper", "wall")   # the tube's names (a shell's third is "band")
SQRT_5_6 = math.sqrt(5.0 / 6.0)


def effective_modulus(e1: float, nu1: float, e2: float, nu2: float) -> float:
    """E* [Pa] of two elastic bodies (Young's moduli [Pa], Poisson ratios)."""
    return 1.0 / ((1.0 - nu1**2) / e1 + (1.0 - nu2**2) / e2)


def effective_shear_modulus(e1: float, nu1: float, e2: float, nu2: float) -> float:
    """G* [Pa] of two elastic bodies (Mindlin; the form of DESIGN.md section 8)."""
    return 1.0 / (2.0 * (2.0 - nu1) * (1.0 + nu1) / e1 + 2.0 * (2.0 - nu2) * (1.0 + nu2) / e2)


def beta(restitution: float) -> float:
    """Chrono's beta = ln e / sqrt(ln^2 e + pi^2) (<= 0; -1 for e = 0)."""
    if restitution >= 1.0:
        return 0.0
    if restitution <= 0.0:
        return -1.0
    ln_e = math.log(restitution)
    return ln_e / math.sqrt(ln_e**2 + math.pi**2)


MIN_CALIBRATED_RESTITUTION = 0.01


def rebound_of_damping(a: float) -> float:
    """Rebound speed ratio of ``x'' = -x^1.5 - a x^(1/4) x'`` (force clamped at 0), x'(0) = 1."""
    from scipy.integrate import solve_ivp

    def rhs(_t, s):
        x, v = s
        xp = max(x, 0.0)
        force = xp**1.5 + a * xp**0.25 * v
        return [v, -max(force, 0.0)]

    def leave(_t, s):
        return s[0]
    leave.terminal = True
    leave.direction = -1.0
    sol = solve_ivp(rhs, (0.0, 1e3), [1e-12, 1.0], events=leave, rtol=1e-10, atol=1e-13,
                    method="LSODA")
    if not sol.t_events[0].size:
        return 0.0
    return float(-sol.y_events[0][0][1])


@lru_cache(maxsize=64)
def calibrated_beta(restitution: float) -> float:
    """beta (<= 0) for which the clamped Hertz contact with Chrono's damping form rebounds with e."""
    from scipy.optimize import brentq

    e = max(float(restitution), MIN_CALIBRATED_RESTITUTION)
    if e >= 1.0:
        return 0.0
    scale = 2.0 * SQRT_5_6 * math.sqrt(1.5)
    hi = 1.0
    while rebound_of_damping(hi) > e:
        hi *= 2.0
    a = brentq(lambda x: rebound_of_damping(x) - e, 0.0, hi, xtol=1e-10, rtol=1e-10)
    return -a / scale


def wall_radius(ball_radius: float, tube_radius: float) -> float:
    """Equivalent contact radius [m] of the ball inside the tube wall."""
    around = ball_radius * tube_radius / (tube_radius - ball_radius)
    return math.sqrt(ball_radius * around)


def sphere_radius(ball_radius: float, cavity_radius: float) -> float:
    """Equivalent contact radius [m] of the ball inside a concave sphere: R a / (a - R)."""
    return ball_radius * cavity_radius / (cavity_radius - ball_radius)


def cell_surfaces(scene):
    """The contact surfaces of ``scene``'s cell (:class:`~tengfield.field.cells.
    contact_surfaces.ContactSurfaces`); a shape without them is a SceneError."""
    from ...field.cells import cell_of
    from ...field.cells.contact_surfaces import contact_surfaces
    try:
        return contact_surfaces(cell_of(scene))
    except ValueError as exc:
        raise SceneError(f"[contact] model = '3d': {exc}") from None


def equivalent_radius(ball_radius: float, surface) -> float:
    """Hertz equivalent radius [m] of the ball on ``surface`` (a ``ContactSurface``)."""
    from ...field.cells.contact_surfaces import CYLINDER, SPHERE
    if surface.kind == CYLINDER:
        return wall_radius(ball_radius, surface.concave_radius)
    if surface.kind == SPHERE:
        return sphere_radius(ball_radius, surface.concave_radius)
    return ball_radius


def hertz_contact_time(mass: float, stiffness: float, speed: float) -> float:
    """Duration [s] of an undamped Hertz impact (F = k delta^1.5) at ``speed`` [m/s]."""
    delta_max = (1.25 * mass * speed**2 / stiffness) ** 0.4
    return 2.943 * delta_max / speed


# column layout of the kernel's per-surface table
LAW, KN, EXP, CN, KT, CT, DMAX, CLAMP, MU_S, MU_D = range(10)


def surface_parameters(scene, surfaces=None) -> np.ndarray:
    """(3, 10) table of the kernel's per-surface contact parameters (SI) for the cell's
    ``surfaces`` (default: :func:`cell_surfaces` of the scene)."""
    c = scene.contact
    dev = scene.device
    if surfaces is None:
        surfaces = cell_surfaces(scene)
    m = dev.ball_mass
    radius = dev.ball_radius
    if c.friction_dynamic > c.friction_static:
        raise SceneError(f"[contact] friction_dynamic = {c.friction_dynamic:g} exceeds "
                         f"friction_static = {c.friction_static:g}: allowed [0, friction_static]")
    if c.restitution_model != "constant" and c.restitution_exponent != 0.0:
        raise SceneError(f"[contact] restitution_model = {c.restitution_model!r} with model = '3d': "
                         "the compliant 3D contact takes a constant restitution")
    S = np.zeros((3, 10))
    if c.law == "hertz" and c.damping_model == "calibrated":
        b = calibrated_beta(c.restitution)
    else:
        b = beta(c.restitution)
    for s, surface in enumerate(surfaces.surfaces):
        S[s, MU_S] = c.friction_static
        S[s, MU_D] = c.friction_dynamic
        if c.law == "hertz":
            if surface.material == "wall":
                e_s, nu_s = c.wall_youngs_modulus, c.wall_poisson_ratio
            else:
                e_s, nu_s = c.plate_youngs_modulus, c.plate_poisson_ratio
            r_e = equivalent_radius(radius, surface)
            e_star = effective_modulus(c.ball_youngs_modulus, c.ball_poisson_ratio, e_s, nu_s)
            g_star = effective_shear_modulus(c.ball_youngs_modulus, c.ball_poisson_ratio, e_s, nu_s)
            S[s, LAW] = 0.0
            S[s, KN] = 4.0 / 3.0 * e_star * math.sqrt(r_e)
            S[s, EXP] = 1.5
            S[s, CN] = -2.0 * SQRT_5_6 * b * math.sqrt(2.0 * e_star * math.sqrt(r_e) * m)
            S[s, KT] = 8.0 * g_star * math.sqrt(r_e)
            S[s, CT] = -2.0 * SQRT_5_6 * b * math.sqrt(8.0 * g_star * math.sqrt(r_e) * m)
            S[s, CLAMP] = 1.0
        else:
            k = c.stiffness
            if c.damping >= 0.0:
                cmax = c.damping
            elif c.exponent == 1.0:
                cmax = 2.0 * damping_ratio(c.restitution) * math.sqrt(m * k)
            else:
                raise SceneError(f"[contact] damping_N_s_per_m = {c.damping:g}: with exponent = "
                                 f"{c.exponent:g} the damping is not derived from the "
                                 "restitution; allowed [0, 1e12] N s/m")
            S[s, LAW] = 1.0
            S[s, KN] = k
            S[s, EXP] = c.exponent
            S[s, CN] = cmax
            S[s, KT] = 2.0 / 7.0 * k
            S[s, CT] = 2.0 / 7.0 * cmax
            S[s, DMAX] = c.penetration_max
            S[s, CLAMP] = 0.0
    return S
