"""The 3D gmsh model of the spherical shell: what :func:`tengfield.field.geometry3d.build_model`
asks a cell (``placement_3d``, ``contact_rule_3d``, ``extent_3d``, ``occ_parts``,
``rim_distance_expr``, ``gap_refinements_3d``), answered for
:class:`~tengfield.field.cells.SphericalShell` (its methods call these functions).

Coordinates (SI): the cavity's centre at the origin, z up. The ball at gap
``position`` z (above the cavity's bottom, on the axis) and lateral ``offset`` r
at ``offset_angle`` φ from +x has its centre at ``(r cos φ, r sin φ, z - R)``
with ``R = a - d/2`` (= stroke/2) the radius of the region the centre may reach:
``|c| <= R``, so at height z the offset is at most
``r_max(z) = sqrt(z (stroke - z))`` (:func:`admissible_offset`).

Model: the far-field sphere, the ball, the two electrodes (zero-thickness
spherical caps of the cavity sphere ``|x| = a``, below ``z = -w/2`` and above
``z = +w/2``: each the revolution of an arc, embedded in the mesh) and, unless
``wall_permittivity = 1``, the shell ``a <= |x| <= b`` (a hollow sphere whose
inner surface the caps split into the electrodes and the band). The physical
groups are the tube's 3D ones (ball, walls, air, ball_surface, electrode_lower,
electrode_upper, far_boundary), so :mod:`tengfield.field.solver3d` solves it as is.

Contact rule (the tube's along the wall's normal): no mesh has a ball-wall gap
``g = R - |c|`` below ``g_min = MIN_GAP_FRACTION x cavity diameter``; a ball
closer than that to the wall (anywhere, on an electrode or on the band) is
extrapolated from the gaps (g_min, 2 g_min, 4 g_min) along the same radius. On
the axis this is the tube's rule in z. Mesh grading: the 3D tube's (radical
grading to the two rim circles, 0.5 h on the ball, half the gap in the ball-wall
gap along the radius, growth to the far sphere).

gmsh is imported by the caller (``occ`` is passed in); this module is numpy only.
"""
from __future__ import annotations

import math

import numpy as np

from ...errors import FieldError, show_number
from .. import contact


def _num(value) -> str:
    return repr(float(value))


def centre_radius(shell) -> float:
    """R = a - d/2 [m]: the ball centre stays in ``|c| <= R``."""
    return shell.cavity_radius - shell.ball_radius


def admissible_offset(shell, position: float) -> float:
    """Largest lateral offset [m] of the ball at gap ``position`` [m]:
    ``sqrt(R² - z_c²) = sqrt(z (stroke - z))``."""
    z = min(max(float(position), 0.0), shell.stroke)
    return math.sqrt(max(z * (shell.stroke - z), 0.0))


def _check(shell, position: float, offset: float) -> None:
    stroke = shell.stroke
    if not (math.isfinite(position) and 0.0 <= position <= stroke * (1 + 1e-12)):
        raise FieldError(f"position_mm = {show_number(position * 1e3, 0.0, stroke * 1e3)} is "
                         "out of range: allowed "
                         f"[0, {stroke * 1e3:g}] mm (the stroke, cavity_diameter_mm - "
                         "ball_diameter_mm)")
    largest = admissible_offset(shell, position)
    if not (math.isfinite(offset) and 0.0 <= offset <= largest * (1 + 1e-9) + 1e-15):
        raise FieldError(f"offset_mm = {show_number(offset * 1e3, 0.0, largest * 1e3)} is out "
                         "of range at position_mm = "
                         f"{position * 1e3:g}: allowed [0, {largest * 1e3:.6g}] mm (the ball "
                         "must stay inside the cavity: |centre| <= cavity radius - ball radius; "
                         "a run tabulates the whole stroke at [field] ball_offset_mm, so a "
                         "shell's run needs 0 there, tengfield field --offset-mm solves one "
                         "position)")
    g_min = contact.minimum_gap(shell.electrode_spacing)
    if centre_radius(shell) < 4 * g_min:
        raise FieldError(f"[device] ball_diameter_mm = {shell.ball_diameter * 1e3:g} nearly fills "
                         f"the cavity for the 3D mesh: the stroke must exceed "
                         f"{8e3 * g_min:g} mm (8 x the minimum meshed gap)")


def _centre(shell, position: float, offset: float, offset_angle: float) -> np.ndarray:
    return np.array([offset * math.cos(offset_angle), offset * math.sin(offset_angle),
                     shell.ball_centre_z(position)])


def placement(shell, position: float, offset: float,
              offset_angle: float = 0.0) -> tuple[np.ndarray, float]:
    """(ball centre [m], meshed ball-wall gap [m]): the centre moved along its radius
    so that the gap is at least ``g_min``."""
    _check(shell, position, offset)
    c = _centre(shell, position, offset, offset_angle)
    big_r = centre_radius(shell)
    g_min = contact.minimum_gap(shell.electrode_spacing)
    norm = float(np.linalg.norm(c))
    if big_r - norm < g_min:
        c = c * ((big_r - g_min) / norm)
        norm = big_r - g_min
    return c, big_r - norm


def contact_rule(shell, position: float, offset: float, offset_angle: float = 0.0):
    """``None`` when the ball-wall gap is at least ``g_min``; else the anchors (g_min,
    2 g_min, 4 g_min) of the gap along the ball's radius and ``place(g) -> (position,
    offset)`` of each (see :func:`tengfield.field.cells.plate_model3d._plate_cell_contact_rule`)."""
    _check(shell, position, offset)
    c = _centre(shell, position, offset, offset_angle)
    big_r = centre_radius(shell)
    g_min = contact.minimum_gap(shell.electrode_spacing)
    norm = float(np.linalg.norm(c))
    gap = big_r - norm
    if gap >= g_min:
        return None
    unit = c / norm
    radial = math.hypot(unit[0], unit[1])

    def place(g: float) -> tuple[float, float]:
        rho = big_r - g
        return rho * unit[2] + big_r, rho * radial

    return {"coordinate": max(gap, 0.0), "anchors": (g_min, 2.0 * g_min, 4.0 * g_min),
            "span": 2.0 * big_r, "place": place}


def occ_parts(shell, occ) -> tuple[list[int], list[int]]:
    """Add the electrode caps (one per name of ``shell.electrodes``: the lower, the upper)
    and (unless εr = 1) the hollow shell to the OCC model: ``(electrode surface tags in
    the order of electrodes, wall volume tags)``."""
    a, e = shell.cavity_radius, 0.5 * shell.electrode_band
    rim = math.sqrt(a * a - e * e)
    origin = occ.addPoint(0.0, 0.0, 0.0)
    electrodes = []
    for sign in ({"lower": -1.0, "upper": 1.0}[name] for name in shell.electrodes):
        pole = occ.addPoint(0.0, 0.0, sign * a)
        edge = occ.addPoint(rim, 0.0, sign * e)
        arc = occ.addCircleArc(pole, origin, edge)
        out = occ.revolve([(1, arc)], 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 2.0 * math.pi)
        electrodes.append(next(tag for dim, tag in out if dim == 2))
    occ.remove([(0, origin)])
    walls = []
    if shell.wall_permittivity != 1.0:
        outer = occ.addSphere(0.0, 0.0, 0.0, shell.outer_radius)
        inner = occ.addSphere(0.0, 0.0, 0.0, a)
        hollow, _ = occ.cut([(3, outer)], [(3, inner)])
        walls = [tag for _, tag in hollow]
    return electrodes, walls


def rim_distance_expr(shell) -> str:
    """gmsh MathEval distance [m] to the nearer rim circle (``z = ±w/2`` on the cavity
    sphere; exact)."""
    a, e = shell.cavity_radius, 0.5 * shell.electrode_band
    rim = math.sqrt(a * a - e * e)
    return f"sqrt((sqrt(x*x+y*y)-{_num(rim)})^2+(abs(z)-{_num(e)})^2)"


def gap_refinements(shell, centre, size: float, ball_factor: float) -> list:
    """``[(s_min [m], point [m])]``: the ball-wall gap along the ball's radius (half the
    gap, at least 0.02 h, at most ``ball_factor`` h, at its midpoint); none at the centre."""
    c = np.asarray(centre, dtype=float)
    norm = float(np.linalg.norm(c))
    if norm <= 1e-12 * shell.cavity_radius:
        return []
    gap = centre_radius(shell) - norm
    s_min = min(max(0.5 * gap, 0.02 * size), ball_factor * size)
    mid = (norm + shell.ball_radius + 0.5 * gap) * c / norm
    return [(s_min, tuple(float(v) for v in mid))]
