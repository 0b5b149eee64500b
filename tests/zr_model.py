"""An analytic (z, r) stand-in for the 3D field solve (tests only): the plate model of
``plate_model`` with a radial dependence, even in r and mirror-symmetric in z, so the
(z, r) surrogate, its cache and the 3D runs are tested without dolfinx."""
from __future__ import annotations

import numpy as np

from tengfield import surrogate
from tengfield.field.result import PositionResult
from tengfield.surrogate import obtain_radial_table, obtain_table

import plate_model as fx

def zr_model(scene, z, r):
    """(C_ll, C_lu, C_uu, q_l, q_u) of the plate model with a radial dependence.

    Even in r (a smooth function of rho² = (r / r_max)²), steepening toward the
    wall like a dielectric wall coming close, and mirror-symmetric in z at any r.
    """
    c_ll, c_lu, c_uu, q_l, q_u = fx.plate_model(scene, z)
    stroke = scene.device.stroke
    rho2 = (np.asarray(r, dtype=float) / surrogate.max_offset(scene.device))**2
    wall = 0.02 * rho2 / (1.5 - rho2)            # grows fast toward rho = 1
    z = np.asarray(z, dtype=float)
    bulge = np.sin(np.pi * z / stroke)          # the offset matters most mid-stroke
    mutual = -c_lu * (1.0 + 0.5 * wall)
    c_ll = c_ll * (1.0 + wall) - c_lu * 0.5 * wall
    c_uu = c_uu * (1.0 + wall) - c_lu * 0.5 * wall
    share = 1.0 - 0.05 * rho2 * (0.5 + bulge)   # field lines escape to the wall
    return c_ll, -mutual, c_uu, q_l * share, q_u * share


def zr_model_solve(scene, position, *, comm=None, offset=0.0, method="3d", **_):
    c_ll, c_lu, c_uu, q_l, q_u = (float(v) for v in zr_model(scene, position, offset))
    return PositionResult(position=float(position), offset=float(offset),
                          capacitance=[[c_ll, c_lu], [c_lu, c_uu]],
                          induced_charge=[q_l, q_u], ball_charge=scene.device.ball_charge,
                          dofs=1000, cells=2000, method="3d", degree=2, wall_time=0.01,
                          relative_error_estimate=1e-6, solve_time=0.005)




#: a 3D scene with a lateral drive and coarse field settings (its surrogates seeded by
#: :func:`seed_cache`)
LATERAL = """\
[excitation]
frequency_hz = 30.0
amplitude_mm = 1.0
amplitude_x_mm = 0.5
phase_x_deg = 30.0

[contact]
model = "3d"

""" + fx.SMALL_SCENE


def seed_cache(scene, cache):
    """Both surrogates of ``scene`` in ``cache`` (analytic stand-in): (table, zr_table)."""
    table, _ = obtain_table(scene, cache_dir=cache, solve=zr_model_solve)
    zr_table, _ = obtain_radial_table(scene, cache_dir=cache, solve=zr_model_solve)
    return table, zr_table
