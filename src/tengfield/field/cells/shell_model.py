"""gmsh model of the spherical shell in the axisymmetric (r, z) half-plane.

Coordinates as :mod:`tengfield.field.geometry_axisymmetric`: x = r >= 0,
y = z, the cavity's centre at the origin, SI. The electrodes are the arcs of
the cavity circle ``|x| = a`` below ``z = -w/2`` and above ``z = +w/2``
(zero-thickness conductors); the shell ``a <= |x| <= b`` is a dielectric
(meshed as ``walls`` when its permittivity is not 1); the ball is the half
disk of radius d/2 at ``(0, z_c)``.

The far field is the tube's (the same half-disk of radius R around the origin,
and for ``kelvin`` its Kelvin image shifted by ``2.5 R`` with periodic arcs),
and the physical groups carry the tube's names and tags
(:data:`~tengfield.field.geometry_axisymmetric.CELL_TAGS`, ``FACET_TAGS``), so
the tube's solver (``axisymmetric.discretise``, ``solve_discretisation``)
assembles this model unchanged.

Mesh grading (sizes scale with the base size h), as for the tube:

* radical grading toward the four electrode rims (the edges of the band),
  ``s = h (ρ/L)^(1-μ)``, μ = RIM_EXPONENT / degree;
* ``0.4 h`` on the ball surface, growing linearly away;
* in the ball-wall gaps at the bottom and top, ``(h / 1 mm)·w(ρ)`` with the
  local gap width ``w(ρ) = g + ρ²/2 (1/r_b - 1/a)``, and outside the gaps no finer than
  ``(h / 1 mm)·(d_ball + d_cavity)`` (the distances to the two surfaces: their sum is
  the width in a gap and grows away from it, so the rule stays local);
* ``h`` on the shell's surfaces (dielectric interfaces), growing linearly;
* far away the size grows with the distance to the cell.
"""
from __future__ import annotations

import itertools
import math
import os
from dataclasses import dataclass, field

import numpy as np

from ...errors import FieldError
from .. import contact
from ..geometry_axisymmetric import (GRADING_REACH, INTERFACE_GROWTH, RIM_EXPONENT,
                                     finish_size_fields, register_groups, surface_groups)

_model_counter = itertools.count()


@dataclass(frozen=True)
class ShellLayout:
    """Dimensions of one axisymmetric shell geometry (SI). The attributes the tube's
    solver reads (``table``, ``kelvin``, ``shift``, ``domain_radius``,
    ``ball_centre_z``) have the tube layout's meaning."""
    ball_radius: float
    ball_centre_z: float
    cavity_radius: float
    outer_radius: float
    band: float
    walls: bool
    domain_radius: float
    kelvin: bool
    shift: float
    gap_lower: float
    gap_upper: float
    requested_gap: float
    effective_gap: float
    mesh_size: float
    grading_exponent: float
    table: bool = False
    inversion_centre_z: float = 0.0
    info: dict = field(default_factory=dict)
    #: the conductors, in the order of the field's matrices: the two caps, or ("lower",)
    #: for the single-electrode shell (its upper cap bare)
    electrodes: tuple = ("lower", "upper")

    @property
    def z_lower(self) -> float:
        """The cavity's bottom [m] (field.png's height origin: the gap z reads there)."""
        return -self.cavity_radius

    def plot_outline(self, points: int = 91) -> dict:
        """What field.png draws (SI, (r, z) polylines for r >= 0): ``electrodes`` (the two
        arcs), ``walls`` (the band and the shell's outer surface), ``half_width`` and
        ``z_range`` of the frame, ``on_electrode(r, z, tol)`` (arrays [m]) where field
        lines stop, ``height_label`` (where the height axis has its zero)."""
        a, b = self.cavity_radius, self.outer_radius
        phi0 = math.asin(0.5 * self.band / a)

        def arc(radius, lo, hi):
            phi = np.linspace(lo, hi, points)
            return np.column_stack([radius * np.cos(phi), radius * np.sin(phi)])

        def on_electrode(r, z, tol):
            near = np.abs(np.hypot(r, z) - a) < tol
            lower = z <= -0.5 * self.band
            return near & (lower | ((z >= 0.5 * self.band) & ("upper" in self.electrodes)))

        single = "upper" not in self.electrodes
        walls = [arc(a, -phi0, 0.5 * math.pi if single else phi0)] + (
            [arc(b, -0.5 * math.pi, 0.5 * math.pi)] if self.walls else [])
        margin = 0.15 * b
        caps = {"lower": arc(a, -0.5 * math.pi, -phi0), "upper": arc(a, phi0, 0.5 * math.pi)}
        return {"electrodes": [caps[name] for name in self.electrodes],
                "walls": walls, "half_width": b + margin, "z_range": (-b - margin, b + margin),
                "on_electrode": on_electrode, "height_label": "the cavity's bottom"}

    @property
    def rims(self) -> list[tuple[float, float]]:
        """(r, z) of the electrode rims: the band's edges on the cavity circle."""
        h = 0.5 * self.band
        r = math.sqrt(max(self.cavity_radius**2 - h * h, 0.0))
        return [(r, -h), (r, h)]


def layout(cell, position: float, *, mesh_size: float, degree: int = 2,
           domain_radius: float | None = None, far_field: str = "kelvin",
           grading_size: float | None = None) -> ShellLayout:
    """Dimensions for ``cell`` (a :class:`SphericalShell`) with the ball at gap
    ``position`` [m] above the cavity's bottom, clamped by the contact rule to
    [g, stroke - g] (g = ``MIN_GAP_FRACTION`` x the cavity diameter)."""
    if far_field not in ("kelvin", "robin", "dirichlet"):
        raise FieldError(f"[field] far_field = {far_field!r}: allowed kelvin, robin, dirichlet")
    mesh_size = float(mesh_size)
    if not (mesh_size > 0 and math.isfinite(mesh_size)):
        raise FieldError(f"[field] mesh_size_mm = {mesh_size * 1e3:g} is out of range: "
                         "allowed (0, 100] mm")
    grading_size = mesh_size if grading_size is None else float(grading_size)
    R = float(cell.far_radius if domain_radius is None else domain_radius)
    b = cell.outer_radius
    if R <= 1.05 * b:
        raise FieldError(f"[field] domain_radius_mm = {R * 1e3:g} is too small: it must exceed "
                         f"{1.05e3 * b:.3g} mm (the shell's outer radius)")
    gap = contact.clamp_gap(float(position), cell.stroke, cell.electrode_spacing)
    a = cell.cavity_radius
    return ShellLayout(
        ball_radius=cell.ball_radius, ball_centre_z=cell.ball_centre_z(gap),
        cavity_radius=a, outer_radius=b, band=cell.electrode_band,
        walls=cell.wall_permittivity != 1.0, domain_radius=R, kelvin=far_field == "kelvin",
        shift=2.5 * R, gap_lower=gap, gap_upper=cell.stroke - gap, requested_gap=float(position),
        effective_gap=gap, mesh_size=mesh_size, grading_exponent=RIM_EXPONENT / max(degree, 1),
        electrodes=tuple(cell.electrodes),
        info={"device_extent_m": b, "rim_reach_m": min(0.5 * a, GRADING_REACH * grading_size),
              "bulk_length_m": min(b, GRADING_REACH * grading_size)})


def build_model(gmsh, lay: ShellLayout, *, geometry_order: int = 2) -> str:
    """Create and mesh the gmsh model of ``lay``; returns its unique name (left current)."""
    name = f"tengfield_shell_axisym_{os.getpid()}_{next(_model_counter)}"
    gmsh.model.add(name)
    occ = gmsh.model.occ
    R, a, b = lay.domain_radius, lay.cavity_radius, lay.outer_radius
    rb, zb = lay.ball_radius, lay.ball_centre_z
    phi0 = math.asin(0.5 * lay.band / a)

    def half_disk(zc, radius):
        disk = occ.addDisk(0.0, zc, 0.0, radius, radius)
        box = occ.addRectangle(0.0, zc - radius, 0.0, radius, 2.0 * radius)
        out, _ = occ.intersect([(2, disk)], [(2, box)])
        return out[0][1]

    domain = half_disk(0.0, R)
    ball = half_disk(zb, rb)
    tools = [(2, ball)]
    if lay.walls:
        shell, _ = occ.cut([(2, half_disk(0.0, b))], [(2, half_disk(0.0, a))])
        tools += list(shell)
    centre = occ.addPoint(0.0, 0.0, 0.0)

    def arc(lo, hi):
        start = occ.addPoint(a * math.cos(lo), a * math.sin(lo), 0.0)
        end = occ.addPoint(a * math.cos(hi), a * math.sin(hi), 0.0)
        return (1, occ.addCircleArc(start, centre, end))

    # the caps: the lower one, and the upper one unless it is bare (the single-electrode
    # shell's: without walls nothing is there, with walls it is their face)
    electrodes = [arc(-0.5 * math.pi, -phi0)] + ([arc(phi0, 0.5 * math.pi)]
                                                 if "upper" in lay.electrodes else [])
    _, children = occ.fragment([(2, domain)], tools + electrodes)
    ball_parts = {tag for _, tag in children[1]}
    wall_parts = {tag for parts in children[2:2 + len(tools) - 1] for _, tag in parts}
    image = half_disk(lay.shift, R) if lay.kelvin else None
    occ.synchronize()
    gmsh.model.occ.remove([(0, centre)])   # the arcs' centre point, if left unused
    occ.synchronize()

    groups = surface_groups(gmsh, image, ball_parts, wall_parts)

    tol = 1e-9 * R
    pad = 2e-7 + 1e-6 * R
    edge = 0.5 * lay.band
    mids: dict[int, float] = {}
    interfaces = []
    for _, c in gmsh.model.getEntities(1):
        lo, hi = gmsh.model.getParametrizationBounds(1, c)
        x, y, _ = gmsh.model.getValue(1, c, [0.5 * (lo[0] + hi[0])])
        bb = gmsh.model.getBoundingBox(1, c)   # xmin, ymin, zmin, xmax, ymax, zmax
        mids[c] = y
        if x < tol and bb[3] < pad:
            continue   # the symmetry axis
        if image is not None and y > R + tol:
            if abs(math.hypot(x, y - lay.shift) - R) < 1e3 * tol:
                groups["far_boundary_image"].append(c)
        elif abs(math.hypot(x, y - zb) - rb) < 1e3 * tol:
            groups["ball_surface"].append(c)
        elif abs(math.hypot(x, y) - R) < 1e3 * tol:
            groups["far_boundary"].append(c)
        elif abs(math.hypot(x, y) - a) < 1e3 * tol:
            if bb[4] <= -edge + pad:
                groups["electrode_lower"].append(c)
            elif bb[1] >= edge - pad and "upper" in lay.electrodes:
                groups["electrode_upper"].append(c)
            else:
                interfaces.append(c)   # the band
        elif abs(math.hypot(x, y) - b) < 1e3 * tol:
            interfaces.append(c)

    register_groups(gmsh, groups, mids, kelvin_shift=None if image is None else lay.shift,
                    what="spherical shell", name=name, electrodes=lay.electrodes)
    _size_fields(gmsh, lay)
    gmsh.model.mesh.generate(2)
    if geometry_order > 1:
        gmsh.model.mesh.setOrder(geometry_order)
    return name


def _size_fields(gmsh, lay: ShellLayout) -> None:
    """Background mesh size (one MathEval: the Min of the expressions of the module
    docstring), plus the Kelvin image's box."""
    h, mu, a = lay.mesh_size, lay.grading_exponent, lay.cavity_radius
    sizes = []
    L = lay.info["rim_reach_m"]
    d_rim = "Min(" + ", ".join(f"Sqrt((x - ({x!r}))^2 + (y - ({y!r}))^2)"
                               for x, y in lay.rims) + ")"
    rho_min = L * (h / L) ** (1.0 / mu) if h < L else L
    sizes.append(f"({h!r}) * (Max({d_rim}, ({rho_min!r})) / ({L!r}))^({1.0 - mu!r})")
    d_ball = f"Abs(Sqrt(x^2 + (y - ({lay.ball_centre_z!r}))^2) - ({lay.ball_radius!r}))"
    sizes.append(f"({0.4 * h!r}) + 0.3 * {d_ball}")
    curvature = 0.5 * (1.0 / lay.ball_radius - 1.0 / a)
    # the gap rule holds in the gap only: there the distances to the ball and to the
    # cavity add up to the local width w(ρ); away from it their sum grows, so a nearly
    # concentric ball (small curvature: w(ρ) stays below h out to many cavity radii)
    # does not refine the whole domain (issue #40: 3.7 GB for a 0.31 mm stroke)
    d_cavity = f"Abs(Sqrt(x^2 + y^2) - ({a!r}))"
    for gap, z0 in ((lay.gap_lower, -a), (lay.gap_upper, a)):
        if gap < 2.0 * h:
            sizes.append(f"({h / 1e-3!r}) * Max(({gap!r}) + (x^2 + (y - ({z0!r}))^2) * "
                         f"({curvature!r}), {d_ball} + {d_cavity})")
    if lay.walls:
        radius = "Sqrt(x^2 + y^2)"
        sizes.append(f"({h!r}) + {INTERFACE_GROWTH!r} * Min(Abs({radius} - ({a!r})), "
                     f"Abs({radius} - ({lay.outer_radius!r})))")
    else:   # the band and the electrodes' backs: h on the cavity surface
        sizes.append(f"({h!r}) + {INTERFACE_GROWTH!r} * Abs(Sqrt(x^2 + y^2) - ({a!r}))")
    extent = lay.info["bulk_length_m"]
    sizes.append(f"({h!r}) * Max(1, Sqrt(x^2 + y^2) / ({extent!r}))")
    finish_size_fields(gmsh, lay, sizes, [])


def shell_cells(lay) -> float:
    """Triangles of the spherical shell's (r, z) mesh of ``lay`` (this module's size
    fields, as :func:`~tengfield.field.geometry_axisymmetric.estimated_cells` does the
    tube's; :mod:`tengfield.field.cost` counts the dofs from it)."""
    h = lay.mesh_size
    area = 0.433 * h * h
    B, R = lay.info["bulk_length_m"], lay.domain_radius
    bulk = 0.5 * math.pi * B * B / area * (1.0 + 2.0 * math.log(max(R / B, 1.0)))
    L, mu = lay.info["rim_reach_m"], lay.grading_exponent
    rims = 2 * math.pi * L * L / (2.0 * mu * area)
    ball = math.pi * lay.ball_radius / (0.433 * 0.3 * 0.4 * h)
    a = lay.cavity_radius
    surfaces = math.pi * (a + (lay.outer_radius if lay.walls else 0.0))
    interfaces = 2.0 * surfaces / (0.433 * 0.3 * h)
    c = h / 1e-3
    kappa = max(0.5 * (1.0 / lay.ball_radius - 1.0 / a), 1e-12)
    gaps = 0.0
    for gap in (lay.gap_lower, lay.gap_upper):
        # the gap rule holds in the gap only (width w = g + κρ², size c w): a strip of
        # ∫ dρ / (0.433 c² w(ρ)) triangles out to where c w reaches h or the ball ends
        if 0.0 < gap < 2.0 * h and gap < h / c:
            reach = min(lay.ball_radius, math.sqrt((h / c - gap) / kappa))
            root = math.sqrt(gap * kappa)
            gaps += math.atan(reach * kappa / root) / (root * 0.433 * c * c)
    image = bulk * 0.5 if lay.kelvin else 0.0
    return bulk + rims + ball + interfaces + gaps + image
