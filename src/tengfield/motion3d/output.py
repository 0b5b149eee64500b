"""Writers and the figure of a 3D run (the CLI wiring is in tengfield.commands)."""
from __future__ import annotations


import numpy as np

#: trajectory.csv columns of a 3D run, after the 1-D ones (time_s, gap_m, gap_velocity_m_per_s, table_m)
EXTRA_COLUMNS = ("x_m", "y_m", "radial_m", "vx_m_per_s", "vy_m_per_s", "spin_x_rad_per_s",
                 "spin_y_rad_per_s", "spin_z_rad_per_s")


def trajectory_columns(result) -> dict[str, np.ndarray]:
    """The extra trajectory columns of a :class:`Motion3DResult`, by CSV header name (SI)."""
    return {"x_m": result.x, "y_m": result.y, "radial_m": result.radial,
            "vx_m_per_s": result.velocity[:, 0], "vy_m_per_s": result.velocity[:, 1],
            "spin_x_rad_per_s": result.spin[:, 0], "spin_y_rad_per_s": result.spin[:, 1],
            "spin_z_rad_per_s": result.spin[:, 2]}


def write_trajectory3d_csv(result, path) -> None:
    """trajectory.csv: the 1-D columns then :data:`EXTRA_COLUMNS` (full precision)."""
    from ..io import write_csv

    extra = trajectory_columns(result)
    write_csv(path, ["time_s", "gap_m", "gap_velocity_m_per_s", "table_m", *EXTRA_COLUMNS],
              [result.t, result.gap, result.gap_velocity, result.table]
              + [extra[k] for k in EXTRA_COLUMNS])


def write_contacts_csv(result, path) -> None:
    """contacts.csv: every contact episode (surface, entry/exit time, normal speeds, steps)."""
    from ..io import write_csv

    c = result.contacts
    write_csv(path, ["surface", "time_in_s", "time_out_s", "dwell_s", "speed_in_m_per_s",
                     "speed_out_m_per_s", "steps", "initial_rest"],
              [c["surface"], np.asarray(c["time_in"], dtype=float),
               np.asarray(c["time_out"], dtype=float),
               np.asarray(c["time_out"], dtype=float) - np.asarray(c["time_in"], dtype=float),
               np.asarray(c["speed_in"], dtype=float), np.asarray(c["speed_out"], dtype=float),
               np.asarray(c["steps"]).astype(int), np.asarray(c["initial"]).astype(bool).astype(int)])


def plot_trajectory3d(result, path, *, title: str | None = None):
    """trajectory3d.png: side view (gap z and radial offset r vs time) and top view (x-y) [mm].

    Drawn without pyplot (the caller's matplotlib backend is left alone).
    """
    from matplotlib.patches import Circle

    from ..plotting import new_figure

    t = result.t
    clearance_mm = result.tube_clearance * 1e3
    fig = new_figure((11, 5))
    ax_side = fig.add_subplot(1, 2, 1)
    ax_top = fig.add_subplot(1, 2, 2)
    ax_side.plot(t, result.gap * 1e3, color="#1f77b4", lw=1.2, label="gap $z$")
    ax_side.plot(t, result.radial * 1e3, color="#d62728", lw=1.0, label="radial offset $r$")
    ax_side.axhline(0.0, color="0.35", lw=0.8)
    ax_side.axhline(result.stroke * 1e3, color="0.6", lw=0.8, ls="--", label="upper plate")
    ax_side.axhline(clearance_mm, color="#d62728", lw=0.8, ls=":", label="tube wall (r)")
    ax_side.set_xlabel("time [s]")
    ax_side.set_ylabel("[mm]")
    ax_side.set_title("side view")
    ax_side.legend(loc="upper right", fontsize=8)
    ax_side.grid(alpha=0.3)
    ax_top.plot(result.x * 1e3, result.y * 1e3, color="#2ca02c", lw=0.8)
    circle = Circle((0.0, 0.0), clearance_mm, fill=False, color="0.3", ls="--")
    ax_top.add_patch(circle)
    lim = 1.15 * max(clearance_mm, float(np.max(result.radial, initial=0.0)) * 1e3)
    ax_top.set_xlim(-lim, lim)
    ax_top.set_ylim(-lim, lim)
    ax_top.set_aspect("equal")
    ax_top.set_xlabel("x [mm]")
    ax_top.set_ylabel("y [mm]")
    ax_top.set_title("top view (centre; dashed: wall contact)")
    ax_top.grid(alpha=0.3)
    head = title or "ball in 3D"
    s = result.summary()
    fig.suptitle(f"{head}: regime {s['regime']}, {s['impacts']} plate impacts, "
                 f"{s['wall_contacts']} wall contacts", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    return path
