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

Across geometries (design and uncertainty candidates that differ only in their
dimensions): the reference of a rung is not meshed for the candidate but *mapped* from
the mesh of its **canonical geometry** (:func:`canonical_length`: every length of the
geometry rounded to a logarithmic grid of ratio :data:`CANONICAL_RATIO`, so at most
~5 % away), meshed once per process for that rung and kept as a *template* of its
*family* (:func:`geometry_family`: the shape, the topology, the far field, the
permittivities, the mesh size and degree; not the dimensions). The map
(:func:`map_nodes`: a piecewise-linear map per region, in r and z for the tube, in
radius and polar angle for the shell, that puts every interface on its new position and
blends back to the identity before the far boundary, then the ball corrected to its new
place and size rigidly with the blending weight) keeps the template's compiled forms,
dofs, sparsity and restriction; the operator and the ball's load are assembled again.
A map is accepted only if every triangle keeps its orientation and its shape quality
(4√3·area / Σ edge²) within :data:`MAP_QUALITY_BOUND` of the quality gmsh meshed the
template with; otherwise the rung is meshed for the candidate itself (counted
``map_refused``). Every candidate is mapped from the canonical mesh of its own
dimensions, never from another candidate's, so its numbers are a function of the
candidate alone: the same in any order, on any number of ranks
(``tests/field/test_mapped_mesh.py``). ``TENGFIELD_MESH_MAPPING=0`` turns the mapping
off (to measure it).

The numbers differ from a remeshed solve by the discretisation error (the tables
agree within their error estimates: ``tests/field/test_moving_mesh.py``), so
``mesh_motion = "move"`` is part of the field hash; "remesh" (the default) leaves the
hash as it was.
"""
from __future__ import annotations

import dataclasses
import math
import os
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
#: how many positions were placed by moving a reference mesh, how many gmsh meshings
#: were done (the references, the canonical templates and the positions a move would
#: have spoilt), how many references were mapped from a canonical geometry's mesh, and
#: how many maps were refused
COUNTS = {"moved": 0, "meshed": 0, "mapped": 0, "map_refused": 0}
#: smallest factor by which a mapped triangle's shape quality may fall against the one
#: gmsh meshed the canonical template with
MAP_QUALITY_BOUND = 2.0
#: templates kept for mapping (canonical meshes, one per family, rung and canonical
#: geometry; the least recently used forgotten)
MAX_TEMPLATES = 256
#: ratio between neighbouring values of the canonical lengths' logarithmic grid: a
#: candidate's lengths are at most sqrt(1.1) - 1 ≈ 4.9 % from its canonical geometry's
CANONICAL_RATIO = 1.1
#: the map is the identity outside the box (tube) or disk (shell) of this fraction of
#: the domain radius: the far boundary and the Kelvin image never move
MAP_REACH = 0.7
#: environment switch: "0" turns the mapping across geometries off
MAPPING_ENV = "TENGFIELD_MESH_MAPPING"

_references: OrderedDict = OrderedDict()
_templates: OrderedDict = OrderedDict()   # (family, rung, canonical key) -> Reference


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
    quality0: np.ndarray | None = None  # shape quality per triangle as gmsh meshed it
    family: tuple | None = None  # geometry_family: what a mapped geometry shares
    rung: tuple | None = None    # reference_rung's rung: (side, index or "half")
    template: tuple | None = None  # (key, canonical Reference) the mesh was mapped from


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
                     centre=lay.ball_centre_z, placed_at=lay.ball_centre_z,
                     quality0=shape_quality(x0, triangles))


def reference_position(lay, minimum_gap: float) -> float:
    """The gap [m] whose mesh the position of ``lay`` is moved from: on the side of the
    nearer wall, the ladder gap ``g · LADDER_FACTOR^k`` (g the smallest meshed gap; the
    last rung half the stroke) nearest to that side's gap in ratio. A function of the
    position alone, so a table's numbers do not depend on the order of its solves or
    on how the positions were spread over the ranks."""
    return reference_rung(lay, minimum_gap)[0]


def _ladder(stroke: float, minimum_gap: float) -> list[float]:
    """The reference gaps [m] on one side: g, g·LADDER_FACTOR, ... below half the
    stroke, then half the stroke."""
    half = 0.5 * stroke
    ladder, rung = [], minimum_gap
    while rung < half * (1.0 - 1e-9):
        ladder.append(rung)
        rung *= LADDER_FACTOR
    ladder.append(half)
    return ladder


def reference_rung(lay, minimum_gap: float) -> tuple[float, tuple]:
    """``(gap [m], rung)`` of :func:`reference_position`, ``rung`` = (side, k) for the
    k-th ladder gap or (side, "half"): what a mapped geometry's reference shares with
    its template."""
    stroke = lay.gap_lower + lay.gap_upper
    near = max(min(lay.gap_lower, lay.gap_upper), minimum_gap)
    ladder = _ladder(stroke, minimum_gap)
    k = min(range(len(ladder)), key=lambda i: abs(math.log(near / ladder[i])))
    lower = lay.gap_lower <= lay.gap_upper
    name = ("lower" if lower else "upper", "half" if k == len(ladder) - 1 else k)
    return (ladder[k] if lower else stroke - ladder[k]), name


def rung_gap(stroke: float, minimum_gap: float, rung: tuple) -> float | None:
    """The gap [m] of ``rung`` (:func:`reference_rung`) on a geometry of this stroke and
    smallest meshed gap, or None when its ladder has no such rung."""
    ladder = _ladder(stroke, minimum_gap)
    side, k = rung
    if k == "half":
        gap = ladder[-1]
    elif k < len(ladder) - 1:
        gap = ladder[k]
    else:
        return None
    return gap if side == "lower" else stroke - gap


def canonical_length(value: float) -> float:
    """``value`` [m] rounded to the canonical grid: the nearest power of
    :data:`CANONICAL_RATIO` in millimetres (6 significant digits; the sign kept, 0 stays
    0), so within ~4.9 % of it. A function of the value alone."""
    if value == 0.0 or not math.isfinite(value):
        return value
    k = round(math.log(abs(value) * 1e3) / math.log(CANONICAL_RATIO))
    return math.copysign(float(f"{CANONICAL_RATIO ** k:.6g}") * 1e-3, value)


def canonical_domain_radius(radius: float, far_field: str) -> float:
    """The canonical geometry's far-field radius [m]: on the grid, except for a Robin
    far field, whose 1/R is compiled into the forms (part of the family)."""
    return radius if far_field == "robin" else canonical_length(radius)


def geometry_family(lay, **settings) -> tuple:
    """What two geometries must share for one's mesh to be mapped onto the other's: the
    shape and its topology (walls, table, the electrodes, the electrode rim against the
    bore and the tube's outside; the shell's band or none), the far field (domain radius, inversion
    centre, Kelvin shift) and the mesh rule (mesh size, grading exponent), plus
    ``settings`` (permittivities, degree, grading size...). Not the dimensions."""
    # the domain radius scales with the device (map_nodes scales the far field and the
    # Kelvin image with it) unless a Robin condition's 1/R is compiled into the forms
    radius = float(lay.domain_radius) if settings.get("far_field") == "robin" else None
    common = (type(lay).__name__, bool(lay.walls), bool(lay.table), bool(lay.kelvin),
              radius, float(lay.inversion_centre_z),
              float(lay.mesh_size), float(lay.grading_exponent),
              # the conductors: a pair's mesh is never mapped onto one electrode's
              tuple(lay.electrodes))
    if hasattr(lay, "cavity_radius"):
        topology = (lay.band > 0.0,)
    else:
        topology = (int(np.sign(lay.electrode_radius - lay.tube_inner_radius)),
                    int(np.sign(lay.electrode_radius - lay.tube_outer_radius)),
                    lay.tube_inner_radius < lay.tube_outer_radius)
    return common + topology + tuple(sorted((k, repr(v)) for k, v in settings.items()))


def _breaks(old: list, new: list):
    """Sorted breakpoints (old, new) of a piecewise-linear map, or None when the new
    ones are not in the old ones' order (the map would fold)."""
    pairs = sorted(set(zip(old, new)))
    o, n = np.array([p[0] for p in pairs]), np.array([p[1] for p in pairs])
    if np.any(np.diff(o) <= 0.0) or np.any(np.diff(n) <= 0.0):
        return None
    return o, n


def _piecewise(x: np.ndarray, breaks) -> np.ndarray:
    """The piecewise-linear map through ``breaks`` (old, new), the identity outside them."""
    old, new = breaks
    return np.where((x < old[0]) | (x > old[-1]), x, np.interp(x, old, new))


def _ramp(value: np.ndarray, one: float, zero: float) -> np.ndarray:
    """1 for value <= one, falling linearly to 0 at value >= zero."""
    return np.clip((zero - value) / (zero - one), 0.0, 1.0)


def _map_tube(r, z, old, new):
    """The tube's region map: piecewise-linear in r (axis, electrode rim, bore, outside)
    and in z (plate bottoms, electrode planes, plate tops), each displacement blended to
    0 outside the device's rows/columns, the identity outside the box of
    :data:`MAP_REACH` x the domain radius."""
    reach = MAP_REACH * old.domain_radius
    zK = old.inversion_centre_z
    size = max(max(lay.tube_outer_radius, lay.electrode_radius,
                   abs(lay.z_lower - lay.plate_thickness - zK),
                   abs(lay.z_upper + lay.plate_thickness - zK)) for lay in (old, new))
    if size >= 0.9 * reach:
        return None
    radial = _breaks([0.0, old.electrode_radius, old.tube_inner_radius, old.tube_outer_radius,
                      reach],
                     [0.0, new.electrode_radius, new.tube_inner_radius, new.tube_outer_radius,
                      reach])
    axial = _breaks([zK - reach, old.z_lower - old.plate_thickness, old.z_lower, old.z_upper,
                     old.z_upper + old.plate_thickness, zK + reach],
                    [zK - reach, new.z_lower - new.plate_thickness, new.z_lower, new.z_upper,
                     new.z_upper + new.plate_thickness, zK + reach])
    if radial is None or axial is None:
        return None
    dr = _piecewise(r, radial) - r
    dz = _piecewise(z, axial) - z
    outside = max(old.tube_outer_radius, old.electrode_radius)
    bottom, top = old.z_lower - old.plate_thickness, old.z_upper + old.plate_thickness
    rows = np.minimum(_ramp(bottom - z, 0.0, bottom - zK + reach),
                      _ramp(z - top, 0.0, zK + reach - top))
    return r + dr * rows, z + dz * _ramp(r, outside, reach)


def _map_shell(r, z, old, new):
    """The shell's region map: piecewise-linear in the distance to the cavity's centre
    (cavity, outside of the shell) and in the polar angle (the band's edges), the angle's
    change blended to 0 beyond the shell, the identity beyond :data:`MAP_REACH` x the
    domain radius."""
    reach = MAP_REACH * old.domain_radius
    if max(old.outer_radius, new.outer_radius) >= 0.9 * reach:
        return None
    radial = _breaks([0.0, old.cavity_radius, old.outer_radius, reach],
                     [0.0, new.cavity_radius, new.outer_radius, reach])
    edge_old = math.asin(min(0.5 * old.band / old.cavity_radius, 1.0))
    edge_new = math.asin(min(0.5 * new.band / new.cavity_radius, 1.0))
    polar = _breaks([-0.5 * math.pi, -edge_old, edge_old, 0.5 * math.pi],
                    [-0.5 * math.pi, -edge_new, edge_new, 0.5 * math.pi])
    if radial is None or polar is None:
        return None
    rho = np.hypot(r, z)
    theta = np.arctan2(z, r)
    rho_new = _piecewise(rho, radial)
    theta_new = theta + (_piecewise(theta, polar) - theta) * _ramp(rho, old.outer_radius,
                                                                    reach)
    return rho_new * np.cos(theta_new), rho_new * np.sin(theta_new)


def map_nodes(x: np.ndarray, old, new) -> np.ndarray | None:
    """The nodes ``x`` (n, >= 2: r, z) of a mesh of layout ``old`` placed on the geometry
    of layout ``new`` (same :func:`geometry_family`), or None when the map would fold.
    The region map (:func:`_map_tube`, :func:`_map_shell`) puts every interface on its
    new position; then the ball, which the region map may have distorted, is put rigidly
    on its new centre at its new size: each node moves by ``w(x) · c(p(x))``, w the
    blending weight of ``old`` (1 in the ball, 0 on and outside the cavity's walls), p
    the nearest point of the ball and c the correction there."""
    region = _map_shell if hasattr(old, "cavity_radius") else _map_tube
    x = np.array(x, dtype=float, copy=True)
    scale_far = new.domain_radius / old.domain_radius
    if scale_far != 1.0:   # the whole model scaled first (the far field, the Kelvin image)
        if old.inversion_centre_z != 0.0 or new.inversion_centre_z != 0.0:
            return None
        image = x[:, 1] > 1.25 * old.domain_radius
        x[:, 0] *= scale_far
        x[:, 1] = np.where(image, new.shift + scale_far * (x[:, 1] - old.shift),
                           scale_far * x[:, 1])
        old = _scaled_layout(old, scale_far)

    def mapped(r, z):
        return region(r, z, old, new)

    r, z = x[:, 0].copy(), x[:, 1].copy()
    out = mapped(r, z)
    if out is None:
        return None
    dr, dz = r, z - old.ball_centre_z
    dist = np.hypot(dr, dz)
    pull = np.minimum(1.0, old.ball_radius / np.maximum(dist, 1e-300))
    pr, pz = dr * pull, old.ball_centre_z + dz * pull          # nearest ball point
    scale = new.ball_radius / old.ball_radius
    region_r, region_z = mapped(pr, pz)
    corr_r = scale * pr - region_r
    corr_z = new.ball_centre_z + scale * (pz - old.ball_centre_z) - region_z
    w = blending_weight(x, old)
    y = x
    y[:, 0] = out[0] + w * corr_r
    y[:, 1] = out[1] + w * corr_z
    y[r == 0.0, 0] = 0.0   # the axis stays the axis
    return y


def _scaled_layout(lay, factor: float):
    """``lay`` scaled by ``factor`` about the origin (its inversion centre)."""
    lengths = ["ball_radius", "ball_centre_z", "domain_radius", "shift", "gap_lower",
               "gap_upper", "requested_gap", "effective_gap"]
    lengths += (["cavity_radius", "outer_radius", "band"] if hasattr(lay, "cavity_radius")
                else ["plate_spacing", "plate_thickness", "electrode_radius",
                      "tube_inner_radius", "tube_outer_radius"])
    return dataclasses.replace(lay, **{k: factor * getattr(lay, k) for k in lengths})


def shape_quality(x: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """4√3·area / Σ edge² per triangle (1 equilateral, 0 degenerate; signed)."""
    a, b, c = (x[triangles[:, k], :2] for k in range(3))
    edges = sum(np.sum((p - q) ** 2, axis=1) for p, q in ((a, b), (b, c), (c, a)))
    return 4.0 * math.sqrt(3.0) * signed_areas(x, triangles) / edges


def mapping_ok(template: Reference, x: np.ndarray) -> bool:
    """Whether the mapped nodes ``x`` keep every triangle's orientation and its shape
    quality within :data:`MAP_QUALITY_BOUND` of the quality gmsh meshed it with (the
    template's, or the mesh it was itself mapped from's)."""
    ratio = shape_quality(x, template.triangles) / template.quality0
    return bool(np.all(ratio > 1.0 / MAP_QUALITY_BOUND))


def mapping_enabled() -> bool:
    return os.environ.get(MAPPING_ENV, "1") != "0"


def _canonical_reference(dx_api, family, rung, lay, canonical, reassemble
                         ) -> tuple[Reference | None, int]:
    """``(reference, gmsh meshings)``: a reference for ``lay`` mapped from the template
    of its canonical geometry at ``rung`` (meshed now when this process has none), or
    None (no canonical geometry of the same family, or the map refused: the template
    kept). ``canonical(rung)`` -> ``(key, layout, family, mesh())`` of the canonical
    geometry at that rung, or None."""
    got = canonical(rung)
    if got is None:
        return None, 0
    key, lay_c, family_c, mesh_c = got
    if family_c != family:
        return None, 0
    tkey = (family, rung, key)
    template = _templates.pop(tkey, None)
    meshings = 0
    if template is None:
        template = _new_reference(dx_api, lay_c, mesh_c())
        template.disc.solver = None
        meshings = 1
    x = map_nodes(template.x0, template.lay, lay)
    if x is None or not mapping_ok(template, x):
        COUNTS["map_refused"] += 1
        _keep_template(tkey, template)
        return None, meshings
    disc = template.disc
    disc.mesh.geometry.x[:, :2] = x[:, :2]
    if getattr(disc, "far_weight", None) is not None:   # the far boundary term's κ/R
        constant, kappa = disc.far_weight
        constant.value = kappa / lay.domain_radius
    reassemble(disc)
    disc.solver = {}
    COUNTS["mapped"] += 1
    return Reference(lay=lay, disc=disc, x0=x, weight=blending_weight(x, lay),
                     triangles=template.triangles, area0=signed_areas(x, template.triangles),
                     centre=lay.ball_centre_z, placed_at=lay.ball_centre_z,
                     quality0=template.quality0, family=family, rung=rung,
                     template=(tkey, template)), meshings


def _keep_template(tkey, template: Reference) -> None:
    """Keep ``template`` (its solvers released) for mapping, the least recently used
    forgotten (discarded) past :data:`MAX_TEMPLATES`."""
    old = _templates.get(tkey)
    if old is not None and old is not template:
        _forget(old)
    _templates[tkey] = template
    _templates.move_to_end(tkey)
    while len(_templates) > MAX_TEMPLATES:
        _forget(_templates.popitem(last=False)[1])


def _forget(template: Reference) -> None:
    from . import _dolfinx as dx_api
    discard(dx_api, template.disc)


def placed(key, lay, layout_at, mesh_and_discretise, reassemble, dx_api, *,
           minimum_gap: float, family: tuple | None = None, canonical=None):
    """``(layout, Discretisation)`` with the ball where ``lay`` puts it: the reference
    mesh of ``key`` at :func:`reference_position` (meshed on first use:
    ``layout_at(z)`` -> layout, ``mesh_and_discretise(z)`` -> Discretisation) moved
    there when the quality bound allows, else the position meshed on its own.
    ``reassemble(disc)`` assembles the operator and the ball's load again on the moved
    mesh. With ``family`` (:func:`geometry_family`) and ``canonical`` (``rung`` ->
    ``(key, layout, family, mesh())`` of the canonical geometry at that rung, or None) a
    missing reference is first mapped from the canonical geometry's template
    (:func:`map_nodes`; the template meshed on first use)."""
    refs = _references.setdefault(key, {})
    _references.move_to_end(key)
    while len(_references) > MAX_KEYS:
        for old in _references.popitem(last=False)[1].values():
            _retire(dx_api, old)
    z_ref, rung = reference_rung(lay, minimum_gap)
    slot = round(z_ref / minimum_gap, 6)
    ref = refs.get(slot)
    fresh = ref is None
    mapped = False
    meshed_here = 0   # gmsh meshings for this placement (a template's included)
    if fresh:
        ref_lay = layout_at(z_ref)
        if family is not None and canonical is not None and mapping_enabled():
            ref, meshed_here = _canonical_reference(dx_api, family, rung, ref_lay, canonical,
                                                    reassemble)
            mapped = ref is not None
        if ref is None:
            ref = _new_reference(dx_api, ref_lay, mesh_and_discretise(z_ref))
            meshed_here += 1
        ref.family, ref.rung = family, rung
        refs[slot] = ref
        if len(refs) > MAX_REFERENCES:
            _retire(dx_api, refs.pop(next(iter(refs))))
    shift = lay.ball_centre_z - ref.centre
    if shift == 0.0 or quality_ok(ref, shift):
        if ref.placed_at != lay.ball_centre_z:
            x = ref.disc.mesh.geometry.x
            x[:, 1] = ref.x0[:, 1] + shift * ref.weight
            reassemble(ref.disc)
            ref.placed_at = lay.ball_centre_z
        COUNTS["meshed"] += meshed_here
        COUNTS["moved"] += int(shift != 0.0)
        ref.disc.placement = "moved" if shift != 0.0 else "reference"
        ref.disc.meshings = meshed_here
        ref.disc.mappings = int(mapped)
        moved = dataclasses.replace(ref.lay, ball_centre_z=lay.ball_centre_z,
                                    gap_lower=lay.gap_lower, gap_upper=lay.gap_upper,
                                    requested_gap=lay.requested_gap,
                                    effective_gap=lay.effective_gap)
        return moved, ref.disc
    disc = mesh_and_discretise(lay.requested_gap)   # the move would spoil the mesh
    disc.placement = "meshed"
    disc.meshings = 1 + meshed_here
    disc.mappings = int(mapped)
    COUNTS["meshed"] += 1 + meshed_here
    return lay, disc


def _release(dx_api, disc) -> None:
    """Destroy the solvers ``disc`` kept (and their PETSc options)."""
    for K, ksp, prefix in (disc.solver or {}).values():
        ksp.destroy()
        K.destroy()
        dx_api.clear_options(prefix)
    disc.solver = None


def discard(dx_api, disc) -> None:
    """Destroy the PETSc objects of a discretisation nobody keeps any more: its solvers,
    its operator A and its restriction P. Collecting the Python objects does not free
    the matrices dolfinx assembled (measured: 2.2 MB per 13k-dof mesh, 3.4 GB over a
    remeshed design of 200 candidates), so every place that drops one calls this."""
    if disc is None:
        return
    _release(dx_api, disc)
    for name in ("A", "P"):
        matrix = getattr(disc, name, None)
        if matrix is not None:
            matrix.destroy()
            setattr(disc, name, None)


def done_with(dx_api, *discs, moving: bool) -> None:
    """A solve is done with ``discs``: each one a reference does not keep (all of them
    when not ``moving``; a position meshed on its own when the move would have spoilt
    the mesh) is :func:`discard`-ed, and the PETSc objects the solve dropped on each
    mesh's communicator are destroyed (:func:`_dolfinx.release_garbage`)."""
    for disc in discs:
        if disc is None:
            continue
        comm = disc.mesh.comm   # dolfinx's own duplicate: PETSc keeps its garbage there
        if not moving or disc.placement == "meshed":
            discard(dx_api, disc)
        dx_api.release_garbage(comm)


def _retire(dx_api, ref: Reference) -> None:
    """Release ``ref``'s solvers; a reference mapped from a canonical template gives the
    template (its mesh, whose nodes the next map overwrites) back, any other is
    discarded."""
    _release(dx_api, ref.disc)
    if ref.template is not None:
        _keep_template(*ref.template)
        ref.template = None
    else:
        discard(dx_api, ref.disc)


def clear() -> None:
    """Forget every reference mesh (their solvers destroyed), every template and the
    counts."""
    release_references()
    while _templates:
        _forget(_templates.popitem()[1])
    COUNTS.update(moved=0, meshed=0, mapped=0, map_refused=0)


def release_references() -> None:
    """Release every reference mesh, their solvers destroyed (a table is done); the
    canonical templates they were mapped from are kept for mapping (:func:`placed`)."""
    if _references:
        from . import _dolfinx as dx_api
        for refs in _references.values():
            for ref in refs.values():
                _retire(dx_api, ref)
    _references.clear()
