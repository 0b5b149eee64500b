"""Potentials on the ball surface for the air-breakdown check (needs the solution).

The air gaps between the ball and each electrode are checked along lines from
the ball surface to the electrode (:mod:`tengfield.breakdown` does the
Paschen arithmetic). Every potential is a superposition of three basis
solutions of one position, ``φ = σ·φ_1 + V_lower·ψ_lower + V_upper·ψ_upper``
(φ_1: the potential of a unit surface charge density, σ = 1 C/m², with both
electrodes grounded, in V per C/m²). The gap voltage of a line is
``φ(surface point) − V_electrode``: the electrode is an equipotential, so only
the three basis values at the surface point are needed, per line and side.

Lines (:data:`LINE_ANGLES_DEG`): from the surface point at polar angle θ from
the axis (θ = 0: the point nearest the electrode) straight to the electrode,
parallel to the axis. On the axis that line is a field line (symmetry). Off the
axis it is the shortest path from that point to the electrode plane, so no
field line from there is shorter: with a breakdown curve that does not fall
with the gap (:mod:`tengfield.paschen`), pairing the voltage with this length
errs on the safe side (a lower σ_max). A line whose foot lies beyond the
electrode rim is not used (it ends on the plate's dielectric).
"""
from __future__ import annotations

import numpy as np

#: polar angles of the lines on each side of the ball [deg] (0: on the axis)
LINE_ANGLES_DEG = tuple(float(a) for a in range(0, 90, 5))


def surface_points(ball_centre_z: float, ball_radius: float, angles_deg=LINE_ANGLES_DEG
                   ) -> np.ndarray:
    """Points (2, n, 3) on the ball surface in (r, z, 0): [lower side, upper side]."""
    theta = np.radians(np.asarray(angles_deg, dtype=float))
    r = ball_radius * np.sin(theta)
    dz = ball_radius * np.cos(theta)
    lower = np.column_stack([r, ball_centre_z - dz, np.zeros_like(r)])
    upper = np.column_stack([r, ball_centre_z + dz, np.zeros_like(r)])
    return np.stack([lower, upper])


def line_basis(dx_api, disc, unit_source, weighting, lay, angles_deg=LINE_ANGLES_DEG
               ) -> np.ndarray:
    """Basis values (2 sides, n lines, 3) at the lines' surface points: [φ_1 (V per
    C/m²), ψ_lower, ψ_upper] from the dof vectors of one serial discretisation
    (``disc``: its space ``V`` and ``facet_tags``).

    The values are read from the dofs on the ball's surface (the curved P2 facets'
    nodes, 0.4 h apart) and interpolated linearly in the polar angle: a point exactly
    on the curved interface can fall between the cells' pull-backs of a point search.
    """
    from .geometry_axisymmetric import FACET_TAGS

    dofs = np.unique(dx_api.facet_dofs(disc.V, disc.facet_tags, FACET_TAGS["ball_surface"]))
    xy = dx_api.dof_coordinates(disc.V)[dofs]
    # 0 at the bottom, π at the top; |r|: a node on the axis may carry r = -1e-21, whose
    # arctan2 is -π instead of π (the top node then sorted first, the upper axial line
    # read from the node 0.4 h away)
    polar = np.arctan2(np.abs(xy[:, 0]), lay.ball_centre_z - xy[:, 1])
    order = np.argsort(polar)
    polar, dofs = polar[order], dofs[order]
    theta = np.radians(np.asarray(angles_deg, dtype=float))
    out = np.empty((2, theta.size, 1 + len(weighting)))   # [φ_1, ψ_k for each electrode]
    for k, vector in enumerate((unit_source, *weighting)):
        values = np.asarray(vector)[dofs]
        out[0, :, k] = np.interp(theta, polar, values)
        out[1, :, k] = np.interp(np.pi - theta, polar, values)
    return out


def mirror_lines(lines) -> np.ndarray:
    """The basis values of the mirror image z -> Δh - z: sides swapped, ψ_lower <-> ψ_upper."""
    lines = np.asarray(lines, dtype=float)
    return lines[::-1][..., [0, 2, 1]].copy()
