"""One mesh per geometry, moved with the ball (issue #40; ``[field] mesh_motion = "move"``).

The axisymmetric positions of one surrogate table (the tube's and the spherical
shell's) share a reference mesh: the
ball is placed at gap z by moving the mesh nodes along the axis by ``δ · w(x)`` with
``δ`` the ball's displacement from the reference and the analytic blending weight

    w = d_fixed / (d_fixed + d_ball)   inside the cavity, 0 outside it,

where ``d_ball`` is the distance to the ball (0 in it: the ball moves rigidly) and
``d_fixed`` the distance to the cavity's walls (the tube's electrode planes z = ±h/2
and bore r = r_i; the shell's cavity sphere), so the electrodes, the walls, the far field and the Kelvin image do
not move, nodes on the axis stay on it, and the same compiled forms, dofs, sparsity
and restriction P are reused: only the operator (into the same matrix) and the ball's
load are assembled again, and the reference's solver (its own options prefix, set up
once) factors the new values with its symbolic analysis kept.

The reference of a position is the mesh at a fixed rung of a ladder of gaps
(g, 4g, 16g, ... and half the stroke, g the smallest meshed gap; on the side of the
nearer wall), the rung nearest in ratio (:func:`reference_position`): a function of
the position alone, so the numbers do not depend on the order of the solves or on the
ranks. A move is accepted only if every triangle keeps its orientation and its area
changes by at most :data:`QUALITY_BOUND` (either way) against the reference mesh;
otherwise the position is meshed on its own (gmsh, as ``mesh_motion = "remesh"``). Each solve says how its meshes
were placed (``info["mesh_placements"]``), a table sums them (its provenance's
``mesh_placements``, printed by ``tengfield precompute``). Contact-scale gaps (the
contact rule's anchors g, 2g, 4g) follow the same rule: the first is meshed, the
others are the rungs or moves of them. :data:`COUNTS` says how often each happened in this process.

The numbers differ from a remeshed solve by the discretisation error (the tables
agree within their error estimates: ``tests/field/test_moving_mesh.py``), so
``mesh_motion = "move"`` is part of the field hash; "remesh" (the default) leaves the
hash as it was.
"""
from __future__ import annotations

import dataclasses
import math
from collections import OrderedDict
from dataclasses import dataclass

import numpy as np

#: largest factor by which a moved triangle's area may differ from its reference's
QUALITY_BOUND = 4.0
#: the reference gaps: g, 4 g, 16 g, ... (g the smallest meshed gap) and half the stroke
LADDER_FACTOR = 4.0
#: reference meshes kept per (scene, mesh size) in this process, and keys kept
MAX_REFERENCES = 6
MAX_KEYS = 4
#: how many positions were placed by moving a reference mesh, and how many gmsh
#: meshings were done (the references and the positions a move would have spoilt)
COUNTS = {"moved": 0, "meshed": 0}

_references: OrderedDict = OrderedDict()


@dataclass
class Reference:
    """A meshed and discretised geometry and what moving it needs."""
    lay: object              # the layout it was meshed for
    disc: object             # axisymmetric.Discretisation (its mesh is moved in place)
    x0: np.ndarray           # the geometry nodes' coordinates as meshed
    weight: np.ndarray       # blending weight w per geometry node
    triangles: np.ndarray    # (cells, 3) vertex nodes of every cell
    area0: np.ndarray        # signed areas as meshed
    centre: float            # the ball centre's z as meshed [m]
    placed_at: float = np.nan  # the centre's z now [m]


def blending_weight(x: np.ndarray, lay) -> np.ndarray:
    """w(x) for the geometry nodes ``x`` (n, >= 2: r, z) of the layout ``lay``: the
    tube's (cavity: the electrode planes and the bore) or the spherical shell's (cavity:
    the sphere of radius ``cavity_radius`` around the origin)."""
    r, z = x[:, 0], x[:, 1]
    if hasattr(lay, "cavity_radius"):
        d_fixed = lay.cavity_radius - np.hypot(r, z)
    else:
        d_fixed = np.minimum.reduce([z - lay.z_lower, lay.z_upper - z,
                                     lay.tube_inner_radius - r])
    d_ball = np.maximum(np.hypot(r, z - lay.ball_centre_z) - lay.ball_radius, 0.0)
    inside = d_fixed > 0.0
    w = np.zeros_like(r)
    w[inside] = d_fixed[inside] / (d_fixed[inside] + d_ball[inside])
    return w


def signed_areas(x: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    a, b, c = (x[triangles[:, k], :2] for k in range(3))
    return 0.5 * ((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1])
                  - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]))


def quality_ok(ref: Reference, shift: float) -> bool:
    """Whether moving ``ref``'s ball by ``shift`` [m] keeps every triangle's orientation
    and its area within :data:`QUALITY_BOUND` of the reference's."""
    x = ref.x0.copy()
    x[:, 1] += shift * ref.weight
    ratio = signed_areas(x, ref.triangles) / ref.area0
    return bool(np.all(ratio > 1.0 / QUALITY_BOUND) and np.all(ratio < QUALITY_BOUND))


def _new_reference(dx_api, lay, disc) -> Reference:
    disc.solver = {}   # the solver is set up once per reference (its own options prefix)
    x0 = np.array(disc.mesh.geometry.x, copy=True)
    triangles = dx_api.cell_vertex_nodes(disc.mesh)
    return Reference(lay=lay, disc=disc, x0=x0, weight=blending_weight(x0, lay),
                     triangles=triangles, area0=signed_areas(x0, triangles),
                     centre=lay.ball_centre_z, placed_at=lay.ball_centre_z)


def reference_position(lay, minimum_gap: float) -> float:
    """The gap [m] whose mesh the position of ``lay`` is moved from: on the side of the
    nearer wall, the ladder gap ``g · LADDER_FACTOR^k`` (g the smallest meshed gap; the
    last rung half the stroke) nearest to that side's gap in ratio. A function of the
    position alone, so a table's numbers do not depend on the order of its solves or
    on how the positions were spread over the ranks."""
    stroke = lay.gap_lower + lay.gap_upper
    near = max(min(lay.gap_lower, lay.gap_upper), minimum_gap)
    half = 0.5 * stroke
    ladder, rung = [], minimum_gap
    while rung < half * (1.0 - 1e-9):
        ladder.append(rung)
        rung *= LADDER_FACTOR
    ladder.append(half)
    best = min(ladder, key=lambda rung: abs(math.log(near / rung)))
    return best if lay.gap_lower <= lay.gap_upper else stroke - best


def placed(key, lay, layout_at, mesh_and_discretise, reassemble, dx_api, *,
           minimum_gap: float):
    """``(layout, Discretisation)`` with the ball where ``lay`` puts it: the reference
    mesh of ``key`` at :func:`reference_position` (meshed on first use:
    ``layout_at(z)`` -> layout, ``mesh_and_discretise(z)`` -> Discretisation) moved
    there when the quality bound allows, else the position meshed on its own.
    ``reassemble(disc)`` assembles the operator and the ball's load again on the moved
    mesh."""
    refs = _references.setdefault(key, {})
    _references.move_to_end(key)
    while len(_references) > MAX_KEYS:
        for old in _references.popitem(last=False)[1].values():
            _release(dx_api, old)
    z_ref = reference_position(lay, minimum_gap)
    slot = round(z_ref / minimum_gap, 6)
    ref = refs.get(slot)
    fresh = ref is None
    if fresh:
        ref_lay = layout_at(z_ref)
        ref = _new_reference(dx_api, ref_lay, mesh_and_discretise(z_ref))
        refs[slot] = ref
        if len(refs) > MAX_REFERENCES:
            _release(dx_api, refs.pop(next(iter(refs))))
    shift = lay.ball_centre_z - ref.centre
    if shift == 0.0 or quality_ok(ref, shift):
        if ref.placed_at != lay.ball_centre_z:
            x = ref.disc.mesh.geometry.x
            x[:, 1] = ref.x0[:, 1] + shift * ref.weight
            reassemble(ref.disc)
            ref.placed_at = lay.ball_centre_z
        COUNTS["meshed"] += int(fresh)
        COUNTS["moved"] += int(shift != 0.0)
        ref.disc.placement = "moved" if shift != 0.0 else "reference"
        ref.disc.meshings = int(fresh)
        moved = dataclasses.replace(ref.lay, ball_centre_z=lay.ball_centre_z,
                                    gap_lower=lay.gap_lower, gap_upper=lay.gap_upper,
                                    requested_gap=lay.requested_gap,
                                    effective_gap=lay.effective_gap)
        return moved, ref.disc
    disc = mesh_and_discretise(lay.requested_gap)   # the move would spoil the mesh
    disc.placement = "meshed"
    disc.meshings = 1 + int(fresh)
    COUNTS["meshed"] += 1 + int(fresh)
    return lay, disc


def _release(dx_api, ref: Reference) -> None:
    """Destroy the solvers the reference kept (and their PETSc options)."""
    for K, ksp, prefix in (ref.disc.solver or {}).values():
        ksp.destroy()
        K.destroy()
        dx_api.clear_options(prefix)
    ref.disc.solver = None


def clear() -> None:
    """Forget every reference mesh (their solvers destroyed) and the counts."""
    release_references()
    COUNTS.update(moved=0, meshed=0)


def release_references() -> None:
    """Forget every reference mesh, their solvers destroyed (a table is done)."""
    if _references:
        from . import _dolfinx as dx_api
        for refs in _references.values():
            for ref in refs.values():
                _release(dx_api, ref)
    _references.clear()
