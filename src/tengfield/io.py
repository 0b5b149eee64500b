"""Every CSV and JSON file tengfield writes (the edge of the library).

* ``waveforms.csv`` (:func:`write_waveforms_csv`), ``summary.json`` and the
  plots of ``tengfield run`` (:func:`write_run_outputs`);
* ``trajectory.csv`` and ``impacts.csv`` of the dynamics
  (:func:`write_trajectory_csv`, :func:`write_impacts_csv`);
* ``sweep.csv`` (:func:`write_sweep_csv`);
* ``report.csv`` and ``report.json`` (:func:`write_report_csv`,
  :func:`write_report_json`).

Numbers are SI with the unit in the column name. The time column of
``waveforms.csv`` is written with 17 significant digits (``%.17g``, exact
round trip) so that the samples of a long run stay distinct; the other
waveform columns with 10, the dynamics files with 12.
"""
from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np

from ._json import jsonable
from .electrical import LOAD_COLUMNS, RECTIFIER_COLUMNS, WAVEFORM_COLUMNS

#: format of a time column: every double round-trips
TIME_FORMAT = "%.17g"
#: format of the other waveform columns
VALUE_FORMAT = "%.10g"


def write_json(path: str | Path, data) -> Path:
    """``data`` as indented strict JSON (NaN -> null, see :func:`tengfield._json.jsonable`)."""
    path = Path(path)
    path.write_text(json.dumps(jsonable(data), indent=2) + "\n")
    return path


# ---------------------------------------------------------------------------
# tengfield run
def write_waveforms_csv(path: str | Path, waveforms: dict) -> Path:
    """CSV with the columns of ``WAVEFORM_COLUMNS`` (+ ``LOAD_COLUMNS``,
    ``RECTIFIER_COLUMNS`` if present)."""
    columns = WAVEFORM_COLUMNS + [c for c in LOAD_COLUMNS + RECTIFIER_COLUMNS if c in waveforms]
    data = np.column_stack([waveforms[c] for c in columns])
    np.savetxt(path, data, delimiter=",", header=",".join(columns), comments="",
               fmt=[TIME_FORMAT] + [VALUE_FORMAT] * (len(columns) - 1))
    return Path(path)


def write_run_outputs(result, out_dir: str | Path, *, plots: bool = True) -> list[Path]:
    """waveforms.csv, summary.json and, with ``plots``, waveforms.png and surrogate.png
    of a :class:`tengfield.pipeline.RunResult` (see also :func:`write_dynamics_outputs`)."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written = [write_waveforms_csv(out / "waveforms.csv", result.waveforms)]
    if plots:
        from .plotting.waveforms import plot_surrogate, plot_waveforms
        shown = 5.0 * result.scene.excitation.period       # the last 5 periods, readable
        written.append(plot_waveforms(result.waveforms, out / "waveforms.png",
                                      title=_run_title(result) + ", last 5 periods",
                                      last_seconds=shown))
        if result.curves is not None:
            written.append(plot_surrogate(result.table, result.curves, out / "surrogate.png",
                                          cells=result.scene.device.cells))
        written += write_harvest_plots(result, out)
    written.append(write_json(out / "summary.json", result.summary))
    return written


def write_harvest_plots(result, out: Path) -> list[Path]:
    """charging.png (rectifier), vq.png (load or rectifier) and array.png (an
    ``[array]`` run) of a :class:`tengfield.pipeline.RunResult`, where they apply."""
    from .plotting import harvest as hp

    extras = getattr(result, "extras", {}) or {}
    written = []
    if extras.get("_fine") is not None:
        written.append(hp.plot_charging(extras["_fine"], result.scene, out / "charging.png",
                                        title=_run_title(result)))
    if extras.get("_vq"):
        written.append(hp.plot_vq(extras["_vq"], result.summary.get("energy_per_cycle", {}),
                                  out / "vq.png", title=_run_title(result)))
    if extras.get("_array") is not None:
        written.append(hp.plot_array(extras["_array"], result.summary.get("array", {}),
                                     out / "array.png", title=_run_title(result)))
    return written


def _run_title(result) -> str:
    exc = result.scene.excitation
    regime = result.summary.get("regime") or {}
    name = regime.get("regime", regime.get("name", "")) if isinstance(regime, dict) else ""
    return (f"{exc.frequency:g} Hz, A = {exc.amplitude * 1e3:g} mm, "
            f"{result.summary.get('cells', result.scene.device.cells)} cell(s), "
            f"{result.scene.circuit.reference}"
            + (f", {name}" if name else ""))


# ---------------------------------------------------------------------------
# dynamics
def write_trajectory_csv(result, path: str | Path) -> Path:
    """time_s, gap_m, gap_velocity_m_per_s, table_m of a DynamicsResult."""
    data = np.column_stack([result.t, result.gap, result.gap_velocity, result.table])
    np.savetxt(path, data, delimiter=",", fmt="%.12g",
               header="time_s,gap_m,gap_velocity_m_per_s,table_m", comments="")
    return Path(path)


def write_impacts_csv(result, path: str | Path) -> Path:
    """One row per impact: time_s, plate, speed before/after [m/s]."""
    imp = result.impacts
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["time_s", "plate", "speed_before_m_per_s", "speed_after_m_per_s"])
        for t, p, vb, va in zip(imp.time, imp.plate, imp.speed_before, imp.speed_after):
            w.writerow([f"{t:.12g}", p, f"{vb:.12g}", f"{va:.12g}"])
    return Path(path)


def write_dynamics_outputs(result, out_dir: str | Path, *, plots: bool) -> list[Path]:
    """trajectory.csv, impacts.csv (and trajectory.png, last 5 periods) of a
    :class:`tengfield.pipeline.RunResult`'s dynamics."""
    out = Path(out_dir)
    written = [write_trajectory_csv(result.dynamics, out / "trajectory.csv"),
               write_impacts_csv(result.dynamics, out / "impacts.csv")]
    if plots:
        from .plotting.dynamics import plot_trajectory
        exc = result.scene.excitation
        plot_trajectory(result.dynamics, out / "trajectory.png", max_periods=5,
                        title=f"{exc.amplitude * 1e3:g} mm, {exc.frequency:g} Hz, "
                              f"e = {result.scene.contact.restitution:g}")
        written.append(out / "trajectory.png")
    return written


# ---------------------------------------------------------------------------
# tengfield sweep
def write_sweep_csv(path: str | Path, rows: list[dict]) -> Path:
    """``sweep.csv``: the ``tengfield.sweep.SWEEP_COLUMNS`` of every row (None -> empty)."""
    from .sweep import SWEEP_COLUMNS

    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=SWEEP_COLUMNS)
        writer.writeheader()
        for row in rows:
            writer.writerow({k: ("" if row.get(k) is None else row[k]) for k in SWEEP_COLUMNS})
    return Path(path)


# ---------------------------------------------------------------------------
# tengfield report
REPORT_COLUMNS = ["stage", "setting", "wall_time_s", "error_max", "error_V_oc", "error_Q_sc",
                  "error_I_sc", "error_P_load", "error_V_load", "error_position", "knobs",
                  "reference", "note"]


def format_number(x) -> str:
    """4 significant digits; empty for None, NaN and inf."""
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return ""
    return f"{x:.4g}"


def report_row_record(row) -> dict:
    """A CSV/JSON record of one :class:`tengfield.report.Row`."""
    rec = {"stage": row.stage, "setting": row.setting, "wall_time_s": row.wall_time_s,
           "error_max": row.error, "error_position": row.error_position,
           "knobs": json.dumps(row.knobs, sort_keys=True), "reference": row.reference,
           "note": row.note}
    for q in ("V_oc", "Q_sc", "I_sc", "P_load", "V_load"):
        rec[f"error_{q}"] = row.errors.get(q, math.nan)
    return rec


def write_report_csv(path: str | Path, report) -> Path:
    """``report.csv``: one line per measured row of a :class:`tengfield.report.Report`."""
    with open(path, "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=REPORT_COLUMNS)
        writer.writeheader()
        for row in report.rows:
            rec = report_row_record(row)
            writer.writerow({k: (format_number(v) if isinstance(v, float) else v)
                             for k, v in rec.items()})
    return Path(path)


def write_report_json(path: str | Path, report) -> Path:
    """``report.json``: rows (with knobs and errors), references and recommendations."""
    import dataclasses

    data = {"scene": report.scene.source, "fast": report.fast, "wall_time_s": report.wall_time_s,
            "references": report.references, "trajectory": report.trajectory,
            "rows": [report_row_record(r) | {"knobs": r.knobs, "errors": r.errors}
                     for r in report.rows],
            "recommendations": [dataclasses.asdict(r) for r in report.recommendations]}
    return write_json(path, data)
