"""Field figures (pyvista, off-screen): the open-circuit potential of an
axisymmetric solve and the weighting potential of a 3D solve, from a
:class:`~tengfield.field.result.FieldSolution`. Serial (a figure needs the
whole mesh on one process). The colour bar picks its unit (kV, V, mV, ...)
and decimals from the data (:func:`colour_bar_scale`), so its tick labels
stay distinct at any potential.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

#: units of the potential colour bar, largest first: (volts per unit, label)
POTENTIAL_UNITS = ((1e3, "kV"), (1.0, "V"), (1e-3, "mV"), (1e-6, "uV"), (1e-9, "nV"),
                   (1e-12, "pV"))


def colour_bar_scale(limit: float, n_labels: int = 5) -> tuple[float, str, str]:
    """(volts per unit, unit, printf format) for a colour bar over [-limit, limit] [V]
    with ``n_labels`` evenly spaced labels: the unit brings ``limit`` into
    [1, 1000) and the format has enough decimals for every label to differ."""
    if not (math.isfinite(limit) and limit > 0.0):
        return 1.0, "V", "%.0f"
    factor, unit = next(((f, u) for f, u in POTENTIAL_UNITS if limit >= f), POTENTIAL_UNITS[-1])
    step = 2.0 * (limit / factor) / max(n_labels - 1, 1)
    decimals = max(0, 1 - math.floor(math.log10(step)))
    return factor, unit, f"%.{decimals}f"


def colour_bar_labels(limit: float, n_labels: int = 5) -> list[str]:
    """The labels the potential colour bar shows over [-limit, limit] [V]."""
    factor, _, fmt = colour_bar_scale(limit, n_labels)
    values = np.linspace(-limit, limit, n_labels) / factor
    values[np.abs(values) < 1e-12 * max(abs(limit / factor), 1e-300)] = 0.0   # no "-0"
    return [fmt % v for v in values]


def nice_ticks(lo: float, hi: float, target: int = 5) -> tuple[float, float, int, str]:
    """Round axis labels over [lo, hi] (mm): ``(start, stop, count, printf format)`` with
    start <= lo, stop >= hi, both on a grid of step 1, 2 or 5 x 10^k, and ``count``
    labels start, start + step, ..., stop: of the steps giving 4 to 10 labels (about
    ``target``), the one padding [lo, hi] least."""
    span = hi - lo
    if not (math.isfinite(span) and span > 0.0):
        return lo, hi, 2, "%g"
    power = 10.0 ** math.floor(math.log10(span / max(target - 1, 1)))
    best = None
    for step in (m * power * k for k in (0.1, 1.0, 10.0) for m in (1.0, 2.0, 5.0)):
        start = math.floor(lo / step + 1e-9) * step
        stop = math.ceil(hi / step - 1e-9) * step
        count = int(round((stop - start) / step)) + 1
        if 4 <= count <= 10:
            key = ((stop - start) - span, abs(count - target))
            if best is None or key < best[0]:
                best = (key, step, start, stop, count)
    if best is None:
        return lo, hi, 2, "%g"
    _, step, start, stop, count = best
    decimals = max(0, -int(math.floor(math.log10(step) + 1e-9)))
    return start, stop, count, f"%.{decimals}f"


#: the potential colour bar (pyvista scalar_bar_args, viewport fractions): right of the
#: plot's frame, its title (drawn above the bar) below the figure's title
COLOUR_BAR = dict(vertical=True, position_x=0.87, position_y=0.12, height=0.62, width=0.04,
                  title_font_size=22, label_font_size=18, color="black")


def height_origin(lay) -> float:
    """Where field.png's vertical axis has its zero [m, mesh coordinates]: the lower
    electrode's face, so the axis reads the gap z of the title (the mesh's own origin
    is the midplane between the plates)."""
    return lay.z_lower


def render_potential_png(path, solution, phi: np.ndarray, *, title: str,
                         window_size=(1400, 1100)) -> None:
    """Paper figure of an axisymmetric ``solution``: φ [V] (local dof values on
    ``solution.space``) on a meridian plane (mirrored to -r), equipotentials,
    field lines, ball and electrodes outlined, colour bar in an automatic unit."""
    import pyvista as pv

    from . import _dolfinx as dx_api

    lay = solution.geometry
    topology, cell_types, points = dx_api.vtk_arrays(solution.space)
    grid = pv.UnstructuredGrid(topology, cell_types, points.copy())
    grid.point_data["phi"] = phi
    # keep the device part only (drop the Kelvin image)
    mask = np.ones(grid.n_cells, dtype=bool)
    mask[solution.hidden_cells] = False
    grid = grid.extract_cells(np.flatnonzero(mask))
    mirrored = grid.copy()
    mirrored.points[:, 0] *= -1.0
    full = grid.merge(mirrored)
    mm = 1e3
    full.points[:] *= mm  # plot in mm

    cell = lay.plot_outline()   # every layout draws its own cell (the tube's, field/cells)
    half_w = cell["half_width"] * mm
    z0, z1 = (z * mm for z in cell["z_range"])
    n_r = 400  # even: no sample sits exactly on the axis (the seam of the mirrored halves)
    step = 2 * half_w / n_r
    plane = pv.ImageData(dimensions=(n_r, int((z1 - z0) / step), 1), spacing=(step, step, 1.0),
                         origin=(-half_w + 0.5 * step, z0 + 0.5 * step, 0.0))
    sampled = plane.sample(full)
    shape = (sampled.dimensions[1], sampled.dimensions[0])
    phi_grid = np.asarray(sampled.point_data["phi"], dtype=float).copy()
    valid = (np.asarray(sampled.point_data["vtkValidPointMask"]).astype(bool)
             & np.isfinite(phi_grid))
    phi_grid[~valid] = np.nan            # outside the mesh (below a grounded table)
    sampled.point_data["phi"] = phi_grid
    lim = float(np.nanmax(np.abs(phi_grid), initial=0.0)) if np.any(valid) else 0.0
    factor, unit, _ = colour_bar_scale(lim, 5)
    lim = lim or 1.0
    # round colour-bar labels: the symmetric range widened to a round limit (in the unit)
    low, high, n_labels, fmt = nice_ticks(-lim / factor, lim / factor)
    lim = max(-low, high) * factor
    if -low != high:
        low, high, n_labels, fmt = nice_ticks(-lim / factor, lim / factor)
    sampled.point_data["phi"] = phi_grid / factor
    grad_z, grad_r = np.gradient(np.nan_to_num(phi_grid).reshape(shape), step)

    plotter = pv.Plotter(off_screen=True, window_size=window_size)
    plotter.set_background("white")
    bar = dict(COLOUR_BAR, title=f"potential ({unit})", fmt=fmt, n_labels=n_labels)
    plotter.add_mesh(sampled, scalars="phi", cmap="RdBu_r", clim=(-lim / factor, lim / factor),
                     scalar_bar_args=bar, show_edges=False, nan_opacity=0.0)
    contours = sampled.contour(isosurfaces=np.linspace(-lim, lim, 25)[1:-1] / factor,
                               scalars="phi")
    if contours.n_points:
        plotter.add_mesh(contours, color="black", line_width=1.0, opacity=0.35)
    rb, zb = lay.ball_radius * mm, lay.ball_centre_z * mm
    xs = -half_w + 0.5 * step + step * np.arange(shape[1])
    ys = z0 + 0.5 * step + step * np.arange(shape[0])
    valid_grid = valid.reshape(shape)
    angles = np.linspace(0.0, 2.0 * np.pi, 32, endpoint=False) + np.pi / 32
    seeds = np.column_stack([1.03 * rb * np.sin(angles), zb + 1.03 * rb * np.cos(angles)])

    def outside_mesh(p):
        i = np.clip(np.rint((p[:, 1] - ys[0]) / step).astype(int), 0, shape[0] - 1)
        j = np.clip(np.rint((p[:, 0] - xs[0]) / step).astype(int), 0, shape[1] - 1)
        return ~valid_grid[i, j]

    def on_electrode(p):
        return cell["on_electrode"](p[:, 0] / mm, p[:, 1] / mm, 0.5 * step / mm)

    lines = trace_field_lines(-grad_r, -grad_z, xs, ys, seeds, step_length=0.4 * step,
                              max_steps=3000,
                              stop=lambda p: (np.hypot(p[:, 0], p[:, 1] - zb) < rb)
                              | on_electrode(p) | outside_mesh(p))
    for line in lines:
        if len(line) > 3 and np.all(np.isfinite(line)) and \
                np.linalg.norm(line[int(0.3 * len(line)) + 1] - line[int(0.3 * len(line)) - 1]) > 0:
            poly = pv.lines_from_points(np.column_stack([line, np.full(len(line), 0.04)]))
            plotter.add_mesh(poly, color="#202020", line_width=2.5, render_lines_as_tubes=True)
            mid = int(0.3 * len(line))
            direction = line[mid + 1] - line[mid - 1]
            arrow = pv.Arrow(start=(*line[mid], 0.06), direction=(*direction, 0.0), scale=0.45,
                             tip_length=0.5, tip_radius=0.25, shaft_radius=0.0)
            plotter.add_mesh(arrow, color="#202020")
    circle = pv.Circle(radius=rb, resolution=200)
    circle.points[:, 1] += zb
    circle.points[:, 2] = 0.05
    plotter.add_mesh(circle.extract_feature_edges(), color="black", line_width=4,
                     render_lines_as_tubes=True)
    # the cell's outline, both halves of the meridian plane: walls grey, electrodes copper over them
    for kind, colour, width in (("walls", "#555555", 2), ("electrodes", "#b87333", 8)):
        for line in cell[kind]:
            for sign in (1.0, -1.0):
                xyz = np.column_stack([sign * line[:, 0] * mm, line[:, 1] * mm,
                                       np.full(len(line), 0.05)])
                plotter.add_mesh(pv.lines_from_points(xyz), color=colour, line_width=width)
    if cell.get("table_z") is not None:   # the grounded table
        zt = cell["table_z"] * mm
        plotter.add_mesh(pv.Line((-half_w, zt, 0.05), (half_w, zt, 0.05)),
                         color="black", line_width=6)
    plotter.add_text(title, position="upper_edge", font_size=14, color="black")
    # the vertical axis is the title's z: height above the lower electrode's face (the
    # mesh's origin is the midplane); the ball's bottom sits at the gap z
    base = height_origin(lay) * mm
    height = cell["height_label"]
    # round tick values in mm: the axes span round bounds holding the cell
    r_lo, r_hi, n_r_labels, r_fmt = nice_ticks(-half_w, half_w)
    h_lo, h_hi, n_z_labels, z_fmt = nice_ticks(z0 - base, z1 - base)
    plotter.show_bounds(xtitle="r (mm)", ytitle=f"z: height above {height} (mm)",
                        color="black", font_size=14, location="outer", ticks="outside",
                        bounds=(r_lo, r_hi, h_lo + base, h_hi + base, 0, 0),
                        axes_ranges=[r_lo, r_hi, h_lo, h_hi, 0, 0],
                        n_xlabels=n_r_labels, n_ylabels=n_z_labels,
                        fmt=max(r_fmt, z_fmt, key=lambda f: int(f[2:-1])))   # more decimals
    plotter.view_xy()
    plotter.camera.zoom(1.15)
    plotter.screenshot(str(Path(path)))
    plotter.close()


def trace_field_lines(Ex, Ey, xs, ys, seeds, *, step_length: float, max_steps: int,
                      stop=None) -> list[np.ndarray]:
    """Field lines of the sampled field (Ex, Ey on the grid xs × ys, shape (len(ys), len(xs))).

    Every seed is traced forward and backward along the unit field direction
    (midpoint rule, fixed ``step_length``, all seeds at once) until it leaves
    the grid, the field vanishes, or ``stop(points)`` (a boolean per point,
    e.g. "hit a conductor") becomes true. Returns one (n, 2) array per seed.
    """
    from scipy.interpolate import RegularGridInterpolator

    fx = RegularGridInterpolator((ys, xs), Ex, bounds_error=False, fill_value=0.0)
    fy = RegularGridInterpolator((ys, xs), Ey, bounds_error=False, fill_value=0.0)
    floor = 1e-9 * (float(np.max(np.hypot(Ex, Ey))) or 1.0)

    def direction(p):
        yx = p[:, ::-1]
        e = np.column_stack([fx(yx), fy(yx)])
        n = np.hypot(e[:, 0], e[:, 1])
        ok = n > floor
        e[ok] /= n[ok, None]
        return e, ok

    def trace(sign):
        p = np.asarray(seeds, dtype=float).copy()
        paths = [[q.copy()] for q in p]
        active = np.ones(len(p), dtype=bool)
        for _ in range(max_steps):
            if not active.any():
                break
            idx = np.flatnonzero(active)
            d, ok1 = direction(p[idx])
            d_mid, ok2 = direction(p[idx] + 0.5 * sign * step_length * d)
            q = p[idx] + sign * step_length * d_mid
            inside_grid = ((xs[0] <= q[:, 0]) & (q[:, 0] <= xs[-1])
                           & (ys[0] <= q[:, 1]) & (q[:, 1] <= ys[-1]))
            alive = ok1 & ok2 & inside_grid
            if stop is not None:
                alive &= ~stop(q)
            for k, i in enumerate(idx):
                if alive[k]:
                    paths[i].append(q[k].copy())
            p[idx] = q
            active[idx[~alive]] = False
        return [np.array(path) for path in paths]

    backward, forward = trace(-1.0), trace(1.0)
    return [np.vstack([b[::-1], f[1:]]) for b, f in zip(backward, forward)]


def shown_weighting(solution) -> tuple:
    """``(ψ, its name, what carries the 1 V)`` that a 3D field.png draws: the upper
    electrode's ψ, or the single-electrode cell's one ψ_lower."""
    if len(solution.weighting) > 1:
        return solution.weighting[1], "psi_upper", "the upper electrode"
    return solution.weighting[0], "psi_lower", "the one electrode"


def render_weighting_png_3d(path, solution, device, *, title: str,
                            window_size=(1200, 1100)) -> None:
    """3D runs: the weighting potential ψ_upper (dimensionless: the potential for
    1 V on the upper electrode, 0 V on the lower one, uncharged ball; the
    single-electrode cell's ψ_lower) on the
    meridian plane through the axis and the ball centre, with equipotentials,
    the ball and the electrodes outlined. Serial meshes only (a plot needs the
    whole mesh on one process)."""
    import pyvista as pv

    from . import _dolfinx as dx_api

    psi, label, _ = shown_weighting(solution)
    topology, cell_types, points = dx_api.vtk_arrays(solution.space)
    grid = pv.UnstructuredGrid(topology, cell_types, points.copy())
    grid.point_data["psi"] = np.asarray(psi.x.array.real, dtype=float)
    mm = 1e3
    centre = np.asarray(solution.ball_centre, dtype=float)
    angle = math.atan2(centre[1], centre[0]) if np.hypot(centre[0], centre[1]) > 0 else 0.0
    normal = (-math.sin(angle), math.cos(angle), 0.0)   # plane holding the axis and the ball centre
    section = grid.slice(normal=normal, origin=(0.0, 0.0, 0.0))
    # in-plane coordinates (s along the offset direction, z up), in mm
    s = section.points[:, 0] * math.cos(angle) + section.points[:, 1] * math.sin(angle)
    flat = section.copy()
    flat.points = np.column_stack([s * mm, section.points[:, 2] * mm, np.zeros(len(s))])
    outline = solution.geometry.outline()   # every 3D cell draws its own (electrodes first)
    points = np.vstack(outline)
    ro, zo = float(np.max(np.abs(points[:, 0]))) * mm, float(np.max(np.abs(points[:, 1]))) * mm
    flat = flat.clip_box((-ro - 2.0, ro + 2.0, -zo - 1.5, zo + 1.5, -1.0, 1.0), invert=False)

    plotter = pv.Plotter(off_screen=True, window_size=window_size)
    plotter.set_background("white")
    bar = dict(title=f"{label} (1)", vertical=True, position_x=0.84, position_y=0.15,
               height=0.7, width=0.05, title_font_size=22, label_font_size=18, fmt="%.2f",
               color="black", n_labels=6)
    plotter.add_mesh(flat, scalars="psi", cmap="viridis", clim=(0.0, 1.0),
                     scalar_bar_args=bar, show_edges=False)
    contours = flat.contour(isosurfaces=np.linspace(0.05, 0.95, 19), scalars="psi")
    if contours.n_points:
        plotter.add_mesh(contours, color="white", line_width=1.0, opacity=0.6)
    # walls (black), then the electrodes over them (copper: the outline's first, one per
    # potential), both halves
    n = len(solution.weighting)
    for k, line in [*list(enumerate(outline))[n:], *list(enumerate(outline))[:n]]:
        for side in (1.0, -1.0):
            xyz = np.column_stack([side * line[:, 0] * mm, line[:, 1] * mm,
                                   np.full(len(line), 0.05)])
            plotter.add_mesh(pv.lines_from_points(xyz), line_width=6 if k < n else 1.5,
                             color="#b87333" if k < n else "black")
    s_ball = (centre[0] * math.cos(angle) + centre[1] * math.sin(angle)) * mm
    ball = pv.Circle(radius=device.ball_radius * mm, resolution=128)
    ball.points += np.array([s_ball, centre[2] * mm, 0.05])
    plotter.add_mesh(ball.extract_feature_edges(), color="black", line_width=2.5)
    plotter.add_text(title, position="upper_edge", font_size=11, color="black")
    plotter.add_text("meridian section through the axis and the ball centre; "
                     f"outer radius {ro:.3g} mm",
                     position="lower_edge", font_size=9, color="black")
    plotter.view_xy()
    plotter.camera.zoom(1.15)
    plotter.screenshot(str(path))
    plotter.close()
