"""The walls a cell's ball can touch, as the 3D contact model consumes them (issue #32).

``contact_surfaces(cell) -> ContactSurfaces``: three surfaces, always in the order
of the 3D model's contact columns (``lower``, ``upper``, then the wall or band),
each a small numeric description: its kind, its parameters, the material it is
made of (``"plate"``: the electrodes' material keys ``[contact] plate_*``;
``"wall"``: ``[contact] wall_*``) and the principal radius of the concave wall
(for the Hertz equivalent radius, which :mod:`tengfield.dynamics.motion3d.contact`
computes). Pure numbers: no scene attribute of a shape is read outside this
module and the cells.

Frame of the dynamics (SI): x, y across the drive's axis, z along it, with
``z = 0`` the lowest point the ball's bottom can reach (the tube's lower electrode
face, the shell's cavity bottom), so the ball's gap on the axis is ``z_centre - R``
as in the 1-D models. The cell's own frame (centre at the origin) is shifted by
``shift = -(cell.ball_centre_z(0) - R)``.

Kinds (columns of :meth:`ContactSurfaces.table`: kind, p0, p1, lo, hi, 0):

* ``FLOOR`` (0): the plane ``z = p0``, the ball above it (normal +z);
* ``CEILING`` (1): the plane ``z = p0``, the ball below it (normal -z);
* ``CYLINDER`` (2): the inside of the cylinder of radius ``p0`` about the z axis;
* ``SPHERE`` (3): the inside of the sphere of centre ``(0, 0, p0)`` and radius
  ``p1``, only where the contact point's height above the centre,
  ``p1 (z - p0) / |c|``, lies in ``[lo, hi]``. The shell's cavity is three such
  zones of one sphere: the lower electrode (``<= -w/2``), the insulating band
  (between) and the upper electrode (``>= +w/2``), so the surface touched, its
  material and the output column follow the contact point's height.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..._registry import lookup

FLOOR, CEILING, CYLINDER, SPHERE = 0, 1, 2, 3
KIND_NAMES = ("floor", "ceiling", "cylinder", "sphere")
TABLE_WIDTH = 6


@dataclass(frozen=True)
class ContactSurface:
    """One contact surface (SI, the dynamics frame; see the module docstring)."""

    name: str                    # output name: "lower", "upper", "wall" or "band"
    kind: int                    # FLOOR, CEILING, CYLINDER, SPHERE
    params: tuple = (0.0, 0.0)   # (p0, p1)
    zone: tuple = (-math.inf, math.inf)   # SPHERE: contact point height range [m]
    material: str = "plate"      # "plate" or "wall" ([contact] plate_* / wall_* keys)
    concave_radius: float = math.inf      # CYLINDER, SPHERE: the wall's radius [m]

    def row(self) -> np.ndarray:
        return np.array([float(self.kind), float(self.params[0]), float(self.params[1]),
                         float(self.zone[0]), float(self.zone[1]), 0.0])


@dataclass(frozen=True)
class ContactSurfaces:
    """The three contact surfaces of a cell and the extents of its cavity.

    ``height``: the top of the ball's centre's travel plus R (the tube's plate
    spacing, the shell's cavity diameter) [m]; ``clearance``: the largest offset of
    the centre from the axis without contact [m] (R_t - R, a - R);
    ``shift``: the cell frame's z + shift = the dynamics frame's z [m].
    """

    surfaces: tuple
    height: float
    clearance: float
    shift: float

    @property
    def names(self) -> tuple:
        return tuple(s.name for s in self.surfaces)

    @property
    def spherical(self) -> bool:
        return self.surfaces[0].kind == SPHERE

    def table(self) -> np.ndarray:
        """(3, TABLE_WIDTH) rows (kind, p0, p1, lo, hi, 0) for the compiled kernel."""
        return np.array([s.row() for s in self.surfaces])


def tube_surfaces(cell) -> ContactSurfaces:
    """The tube: the lower and upper electrode planes and the cylindrical wall."""
    dev = cell.device
    h, rt = dev.plate_spacing, dev.tube_inner_radius
    return ContactSurfaces(
        surfaces=(ContactSurface("lower", FLOOR, (0.0, 0.0)),
                  ContactSurface("upper", CEILING, (h, 0.0)),
                  ContactSurface("wall", CYLINDER, (rt, 0.0), material="wall",
                                 concave_radius=rt)),
        height=h, clearance=rt - cell.ball_radius, shift=0.5 * h)


def shell_surfaces(cell) -> ContactSurfaces:
    """The spherical shell: one concave sphere (the cavity, radius a), split by the
    contact point's height into the lower electrode, the band and the upper electrode."""
    a, w = cell.cavity_radius, 0.5 * cell.electrode_band
    centre = (a, a)
    sphere = dict(kind=SPHERE, params=centre, concave_radius=a)
    return ContactSurfaces(
        surfaces=(ContactSurface("lower", zone=(-math.inf, -w), material="plate", **sphere),
                  ContactSurface("upper", zone=(w, math.inf), material="plate", **sphere),
                  ContactSurface("band", zone=(math.nextafter(-w, math.inf),
                                               math.nextafter(w, -math.inf)),
                                 material="wall", **sphere)),
        height=2.0 * a, clearance=a - cell.ball_radius, shift=a)


def contact_surfaces(cell) -> ContactSurfaces:
    """The contact surfaces of ``cell`` (a ``CELLS`` entry): its shape's ``contact_walls``
    (looked up in ``CELLS``); ``ValueError`` naming the shape when its walls are not
    described yet (the honeycomb's hexagonal bore)."""
    from . import CELLS

    walls = lookup(CELLS, cell.name, "[device] shape").contact_walls
    if walls is None:
        described = ", ".join(repr(name) for name, entry in CELLS.items()
                              if entry.contact_walls is not None)
        raise ValueError(f"shape = {cell.name!r}: its walls are not described for the 3D "
                         f"contact model yet; allowed {described}")
    return walls(cell)
