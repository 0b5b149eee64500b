"""The dynamics' files (``tengfield dynamics``, ``tengfield map`` and the motion part of
``tengfield run``): trajectory.csv, impacts.csv, contacts.csv (3D), map.csv and the
trajectory figures. :mod:`tengfield.io` hands them on under their old names."""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..files import figure_file, writable_target, write_csv, write_rows


def dynamics_tables(dynamics, scene) -> dict:
    """The dynamics' tables as ``{table: {column: array}}``: ``trajectory`` and
    ``impacts`` (a 3D run: its extra trajectory columns and ``contacts``), the columns
    of trajectory.csv, impacts.csv and contacts.csv."""
    tables = {"trajectory": {"time_s": dynamics.t, "gap_m": dynamics.gap,
                             "gap_velocity_m_per_s": dynamics.gap_velocity,
                             "table_m": dynamics.table}}
    lateral = dynamics.lateral       # the 3D model: its own columns and contacts
    if lateral:
        tables["trajectory"].update(trajectory_columns(dynamics))
    imp = dynamics.impacts
    tables["impacts"] = {"time_s": imp.time,
                         "plate": np.where(imp.plate == "upper", "upper", "lower"),
                         "speed_before_m_per_s": imp.speed_before,
                         "speed_after_m_per_s": imp.speed_after}
    if lateral:
        c = dynamics.contacts
        time_in = np.asarray(c["time_in"], dtype=float)
        time_out = np.asarray(c["time_out"], dtype=float)
        tables["contacts"] = {
            "surface": np.asarray(c["surface"]).astype(str), "time_in_s": time_in,
            "time_out_s": time_out, "dwell_s": time_out - time_in,
            "speed_in_m_per_s": np.asarray(c["speed_in"], dtype=float),
            "speed_out_m_per_s": np.asarray(c["speed_out"], dtype=float),
            "steps": np.asarray(c["steps"]).astype(int),
            "initial_rest": np.asarray(c["initial"]).astype(bool).astype(np.int8)}
    return tables


def write_trajectory_csv(result, path: str | Path) -> Path:
    """time_s, gap_m, gap_velocity_m_per_s, table_m of a DynamicsResult (full precision);
    a long run's columns sampled on request are sampled and written a chunk at a time."""
    header = ["time_s", "gap_m", "gap_velocity_m_per_s", "table_m"]
    columns = [result.t, result.gap, result.gap_velocity, result.table]
    if not hasattr(result.t, "chunks") or isinstance(result.t, np.ndarray):
        return write_csv(path, header, columns)
    from .columns import CHUNK
    for i0 in range(0, len(result.t), CHUNK):
        write_csv(path, header, [c[i0:i0 + CHUNK] for c in columns], append=i0 > 0)
    return Path(path)


def write_impacts_csv(result, path: str | Path) -> Path:
    """One row per impact: time_s, plate, speed before/after [m/s] (full precision)."""
    import pyarrow as pa

    imp = result.impacts
    plate = pa.DictionaryArray.from_arrays(   # the two names, not 600k strings
        pa.array((imp.plate == "upper").astype(np.int8)), pa.array(["lower", "upper"]))
    return write_csv(path, ["time_s", "plate", "speed_before_m_per_s", "speed_after_m_per_s"],
                     [imp.time, plate, imp.speed_before, imp.speed_after])


MAP_COLUMNS = ["frequency_hz", "amplitude_mm", "regime", "period", "max_gap_mm",
               "lower_contacts_per_period", "upper_contacts_per_period", "error"]


def write_map_csv(result, path: str | Path) -> Path:
    """map.csv of a :class:`tengfield.dynamics.mapping.MapResult`: one row per grid point."""
    return write_rows(path, MAP_COLUMNS, (
        [f"{r['frequency_hz']:.10g}", f"{r['amplitude_m'] * 1e3:.10g}", r["regime"],
         r["period"], f"{r['max_gap_m'] * 1e3:.10g}", f"{r['lower_contacts_per_period']:.6g}",
         f"{r['upper_contacts_per_period']:.6g}", r["error"]] for r in result.records()))


def write_dynamics_files(dynamics, scene, out_dir: str | Path, *, plots: bool,
                         max_periods: float | None = None, figures=None,
                         tables: bool = True, written_elsewhere=()) -> list[Path]:
    """The dynamics' files, for ``tengfield dynamics`` and ``tengfield run`` alike:
    trajectory.csv and impacts.csv (a 3D run: its trajectory columns and contacts.csv),
    and with ``plots`` trajectory.png (the last ``max_periods`` periods; default the
    plot's limit) and, 3D, trajectory3d.png.

    Arrow's writer runs without the GIL: the tables are written on other threads, one
    each, while trajectory.png is drawn, by ``figures`` (a
    :class:`tengfield.plotting.process.FigureProcess`) if given, else here. Every file
    is complete when this returns (with ``figures``: the figure after
    ``figures.finish()``, which the caller calls); an error in any is raised here after
    all have ended."""
    from concurrent.futures import ThreadPoolExecutor

    out = Path(out_dir)
    want_tables = tables
    three_d = dynamics.lateral   # trajectory3d.csv, contacts.csv
    if three_d:
        tables = [(write_trajectory3d_csv, "trajectory.csv"), (write_contacts_csv, "contacts.csv")]
    else:
        tables = [(write_trajectory_csv, "trajectory.csv")]
    tables.append((write_impacts_csv, "impacts.csv"))
    if written_elsewhere:   # tengfield run: waveforms.csv holds these; time_s joins them
        if three_d:         # the 3D model's own columns (x, y, r, spin, ...) stay
            tables[0] = (_trajectory_without(set(written_elsewhere) - {"time_s"}, scene),
                         "trajectory.csv")
        else:               # a 1-D trajectory is time, gap, velocity, table: all in waveforms.csv
            tables.pop(0)
    if not want_tables:    # they are in run.h5 (write_run_hdf5)
        tables = []
    written = [writable_target(out / name) for _, name in tables]
    drawing = None
    if plots:
        from .excitation import excitation_kind
        from ..plotting.dynamics import (draw_trajectory, motion_words, plot_trajectory3d,
                                         trajectory_figure)
        title = motion_words(scene) if excitation_kind(scene).periodic else "recorded excitation"
        data = trajectory_figure(dynamics, max_periods=max_periods, title=title)
        for name in (figure_file("trajectory"), figure_file("trajectory3d")) if three_d else (figure_file("trajectory"),):
            writable_target(out / name)
        if figures is not None:
            drawing = figures.draw(draw_trajectory, data, out / figure_file("trajectory"))
    # the figure process draws on a core of its own: leave it one
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    threads = max(1, min(len(tables) or 1, (cores or 1) - (drawing is not None)))
    with ThreadPoolExecutor(max_workers=threads, thread_name_prefix="tengfield-csv") as pool:
        pending = [pool.submit(write, dynamics, out / name) for write, name in tables]
        if plots:
            if three_d:
                plot_trajectory3d(dynamics, out / figure_file("trajectory3d"))
                written.append(out / figure_file("trajectory3d"))
            if drawing is None:
                draw_trajectory(data, out / figure_file("trajectory"))
            written.append(out / figure_file("trajectory"))
        for job in pending:
            job.result()
    return written


def _trajectory_without(columns: set, scene):
    """A trajectory.csv writer that leaves ``columns`` out (they are in waveforms.csv)."""
    def write(dynamics, path):
        table = {k: v for k, v in dynamics_tables(dynamics, scene)["trajectory"].items()
                 if k not in columns}
        return write_csv(path, list(table), list(table.values()))
    return write


#: trajectory.csv columns of a 3D run, after the 1-D ones (time_s, gap_m, gap_velocity_m_per_s, table_m)
EXTRA_COLUMNS = ("x_m", "y_m", "radial_m", "vx_m_per_s", "vy_m_per_s", "spin_x_rad_per_s",
                 "spin_y_rad_per_s", "spin_z_rad_per_s")


def trajectory_columns(result) -> dict[str, np.ndarray]:
    """The extra trajectory columns of a
    :class:`tengfield.dynamics.motion3d.Motion3DResult`, by CSV header name (SI)."""
    return {"x_m": result.x, "y_m": result.y, "radial_m": result.radial,
            "vx_m_per_s": result.velocity[:, 0], "vy_m_per_s": result.velocity[:, 1],
            "spin_x_rad_per_s": result.spin[:, 0], "spin_y_rad_per_s": result.spin[:, 1],
            "spin_z_rad_per_s": result.spin[:, 2]}


def write_trajectory3d_csv(result, path) -> None:
    """trajectory.csv: the 1-D columns then :data:`EXTRA_COLUMNS` (full precision)."""
    extra = trajectory_columns(result)
    write_csv(path, ["time_s", "gap_m", "gap_velocity_m_per_s", "table_m", *EXTRA_COLUMNS],
              [result.t, result.gap, result.gap_velocity, result.table]
              + [extra[k] for k in EXTRA_COLUMNS])


def write_contacts_csv(result, path) -> None:
    """contacts.csv: every contact episode (surface, entry/exit time, normal speeds, steps)."""
    c = result.contacts
    write_csv(path, ["surface", "time_in_s", "time_out_s", "dwell_s", "speed_in_m_per_s",
                     "speed_out_m_per_s", "steps", "initial_rest"],
              [c["surface"], np.asarray(c["time_in"], dtype=float),
               np.asarray(c["time_out"], dtype=float),
               np.asarray(c["time_out"], dtype=float) - np.asarray(c["time_in"], dtype=float),
               np.asarray(c["speed_in"], dtype=float), np.asarray(c["speed_out"], dtype=float),
               np.asarray(c["steps"]).astype(int), np.asarray(c["initial"]).astype(bool).astype(int)])
