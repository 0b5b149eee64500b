"""Where the surrogate samples: nested Chebyshev–Lobatto sets in z (and in s = r² for
the (z, r) surrogate), mirror symmetry, and the sampling defaults.

``z_j = Δh (1 - cos(π j / (n-1))) / 2`` with ``n = 2^k + 1`` positions
(clustered at both ends of the stroke); each refinement adds the ``n - 1``
angular midpoints, so ``n -> 2n - 1`` and every earlier solve is reused. The
radial offsets ``r`` of an off-axis ball are Lobatto-spaced in ``s = r²`` over
``[0, r_max²]`` (``r_max`` = tube inner radius − ball radius), from ``{0, r_max}``.
For the spherical shell the ball's region is a sphere, so the admissible offset
depends on z; its table's offsets are scaled to it (:func:`offset_coordinate`).
"""
from __future__ import annotations

import dataclasses

import numpy as np

#: the first Lobatto set has 2^INITIAL_LEVEL + 1 positions
INITIAL_LEVEL = 3
#: initial number of positions (a Chebyshev–Lobatto set, 2^k + 1): 9
INITIAL_POSITIONS = 2 ** INITIAL_LEVEL + 1
#: the adaptive surrogate always solves the first refinement too, so it never
#: ends with fewer positions than this (17)
FEWEST_POSITIONS = 2 * INITIAL_POSITIONS - 1
#: the refinement stops here even if the tolerance is not met (then converged = False): 65
MAX_POSITIONS = 2 ** (INITIAL_LEVEL + 3) + 1

#: first offset set of the (z, r) surrogate: s = r² in {0, r_max²} (then 3, 5, 9 offsets)
INITIAL_OFFSETS = 2
#: the (z, r) refinement stops at these counts even if the tolerance is not met
MAX_POSITIONS_ZR = 33
MAX_OFFSETS = 9
#: default 3D discretisation of the (z, r) surrogate (docs/field3d.md: degree 2,
#: 1.5 mm has a field error of ~1e-2, ~10 s of CPU per solve)
DEFAULT_MESH_SIZE_MM = 1.5
DEFAULT_DEGREE = 2
#: default interpolation tolerance of the (z, r) surrogate: finer than the 3D field
#: error is wasted
DEFAULT_TOLERANCE = 1.0e-2


def is_lobatto_count(count: int) -> bool:
    """True for ``count = 2^k + 1`` with k >= 1 (the sizes of nested Lobatto sets)."""
    return count >= 3 and not (count - 1) & (count - 2)


def lobatto_positions(stroke: float, count: int) -> np.ndarray:
    """``count`` Chebyshev–Lobatto gaps [m] on [0, stroke], ascending, ends included,
    bitwise symmetric about the middle (so mirror images land on set members)."""
    if count < 2:
        raise ValueError(f"count = {count}: at least 2 positions are needed")
    j = np.arange(count)
    z = 0.5 * stroke * (1.0 - np.cos(np.pi * j / (count - 1)))
    upper = j >= count // 2 + count % 2
    z[upper] = stroke - z[count - 1 - j[upper]]   # exactly symmetric: z_(n-1-j) = Δh - z_j
    z[0], z[-1] = 0.0, stroke
    return z


def refinement_positions(stroke: float, count: int) -> np.ndarray:
    """The ``count - 1`` positions that refine a Lobatto set of ``count`` to ``2 count - 1``."""
    finer = lobatto_positions(stroke, 2 * count - 1)
    return finer[1::2]


def is_mirror_symmetric(scene) -> bool:
    """True when the device is symmetric under z -> Δh - z with lower <-> upper.

    Both plates are built alike (same thickness, electrode radius and
    material), so only the environment can break the mirror symmetry: a
    grounded table under the lower plate does, free space does not; the single-electrode
    cell (one electrode, the upper plate bare) is not symmetric.
    """
    return scene.field.environment == "free-space" and scene.device.electrodes == "both"


def mirrored(result, stroke: float):
    """The solve at ``stroke - z`` implied by mirror symmetry: C_ll <-> C_uu, q_l <-> q_u
    and f_l <-> f_u (the induced charges and fractions; wall and solve times 0: nothing
    was solved)."""
    C = np.asarray(result.capacitance, dtype=float)
    q = np.asarray(result.induced_charge, dtype=float)
    fraction = np.asarray(result.induced_fraction, dtype=float)
    if q.size != 2:      # one electrode (the single-electrode cell) has no mirror image
        raise ValueError(f"mirrored: a solve of {q.size} electrode(s) has no mirror image "
                         "(the pair's z -> stroke - z swaps its two electrodes)")
    info = {**getattr(result, "info", {}), "mirrored_from": result.position}
    for key in ("breakdown_lines", "breakdown_lines_check"):   # sides and ψ's swap too
        if key in info:
            info[key] = np.asarray(info[key], dtype=float)[::-1][..., [0, 2, 1]].copy()
    return dataclasses.replace(result, position=stroke - result.position,
                               capacitance=C[::-1, ::-1].copy(), induced_charge=q[::-1].copy(),
                               induced_fraction=fraction[::-1].copy(),
                               wall_time=0.0, solve_time=0.0,   # no solve of its own
                               info=info)


def contact_first_order(positions: np.ndarray, stroke: float, estimated=()) -> np.ndarray:
    """Indices ordering positions dearest first, the order the task farm hands them out
    in (longest first balances the ranks): the positions in ``estimated`` (solved again
    on a mesh of half the size for the field error estimate: 4-8x a plain solve) first,
    then by distance to the nearer plate, closest first (near contact the contact rule
    meshes three gaps)."""
    positions = np.asarray(positions, dtype=float)
    gap = np.minimum(positions, stroke - positions)
    marks = np.asarray(estimated, dtype=float).reshape(-1)
    dear = (np.min(np.abs(positions[:, None] - marks[None, :]), axis=1) <= 1e-12 * stroke
            if marks.size and positions.size else np.zeros(positions.size, dtype=bool))
    return np.lexsort((gap, ~dear))


# ---------------------------------------------------------------------------
# sampling in r (the (z, r) surrogate)
def max_offset(device) -> float:
    """Largest radial offset of the ball centre [m], the (z, r) table's last offset: the
    cell's (``scene/shapes/``): tube inner radius − ball radius for the tube, the
    centre's sphere radius a − d/2 for the spherical shell."""
    from ..scene.shapes import shape_of

    return float(shape_of(device.shape).max_offset(device))


def offset_coordinate(device) -> str:
    """How the (z, r) table's offsets read (``scene/shapes/`` per shape):
    ``"radial"``: the offset r [m] itself (the tube: r <= r_max at every z);
    ``"scaled"``: ``u = R r / r_max(z)`` [m] with ``R`` = :func:`max_offset` and
    ``r_max(z) = sqrt(R² − (z − Δh/2)²)`` (the spherical shell, whose ball centre stays
    in a sphere of radius R = Δh/2: u = R is the wall at every height)."""
    from ..scene.shapes import shape_of

    return str(getattr(shape_of(device.shape), "offset_coordinate", "radial"))


def admissible_offset(z, stroke: float, largest: float):
    """r_max(z) [m] of a ``"scaled"`` table: ``sqrt(max(R² − (z − Δh/2)², 0))``."""
    z = np.asarray(z, dtype=float)
    return np.sqrt(np.maximum(largest**2 - (z - 0.5 * stroke) ** 2, 0.0))


def physical_offset(z, u, stroke: float, largest: float):
    """The offset r [m] of the ``"scaled"`` table coordinate ``u`` [m] at gap ``z`` [m]."""
    return np.asarray(u, dtype=float) * admissible_offset(z, stroke, largest) / largest


def scaled_offset(z, r, stroke: float, largest: float):
    """The ``"scaled"`` table coordinate u [m] of the offset ``r`` [m] at gap ``z`` [m]
    (``|r|`` clipped to r_max(z); 0 where r_max(z) = 0, the ends of the stroke)."""
    r_max = admissible_offset(z, stroke, largest)
    r = np.abs(np.asarray(r, dtype=float))
    with np.errstate(invalid="ignore", divide="ignore"):
        u = np.where(r_max > 0.0, largest * np.minimum(r / np.where(r_max > 0.0, r_max, 1.0),
                                                       1.0), 0.0)
    return u


def offset_positions(largest: float, count: int) -> np.ndarray:
    """``count`` offsets r [m] in [0, ``largest``], Lobatto-spaced in s = r² (ascending)."""
    if count == 2:
        return np.array([0.0, float(largest)])
    return np.sqrt(lobatto_positions(largest**2, count))


def offset_refinement(largest: float, count: int) -> np.ndarray:
    """The ``count - 1`` offsets that refine :func:`offset_positions` to ``2 count - 1``."""
    return np.sqrt(refinement_positions(largest**2, count))


def grid_key(z: float, r: float) -> tuple[int, int]:
    """The dictionary key of the grid point (z, r) [m]."""
    return (round(z * 1e13), round(r * 1e13))   # 0.1 pm: exact for the nested sets


def scaled_offset_jacobian(z, r, u, stroke: float, largest: float):
    """``(∂u/∂z, ∂u/∂r)`` of the scaled coordinate ``u`` [m] of offset ``r`` at gap ``z``:
    ``u (z − Δh/2) / r_max²`` and ``R / r_max``; 0 where u is clipped (r >= r_max) or
    r_max = 0 (the ends of the stroke)."""
    z, r = np.broadcast_arrays(np.clip(np.asarray(z, dtype=float), 0.0, stroke),
                               np.abs(np.asarray(r, dtype=float)))
    r_max = admissible_offset(z, stroke, largest)
    inside = (r_max > 0.0) & (r < r_max)
    safe = np.where(inside, r_max, 1.0)
    return (np.where(inside, u * (z - 0.5 * stroke) / safe**2, 0.0),
            np.where(inside, largest / safe, 0.0))
