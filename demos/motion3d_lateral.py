"""A horizontally shaken device: how the motion and the TENG's output change as the
lateral drive grows, and the contact dwell times at 3 mm / 30 Hz.

The paper's multibody model (Fig. 7, 3 mm / 30 Hz) shows contacts with the
plates of ~10 ms. Here the ball is the 3D compliant-contact model
(tengfield.dynamics.motion3d, Hertz with PTFE/copper/PMMA handbook moduli, friction
0.1 / 0.05); the table moves 3 mm vertically at 30 Hz plus a lateral sine
of growing amplitude (x axis, 45 degrees phase). For each lateral amplitude:
upper-plate impacts per period and mean upper impact speed (the charge
transfer needs the ball to reach the upper electrode; the open-circuit
voltage of an on-axis ball follows z(t)), wall contacts, mean radial offset.

The electrical output (full mode, or ``--field``): ``tengfield run`` of each
case, open circuit, with the real field: the axisymmetric surrogate on the
axis and, once the ball leaves it, the (z, r) surrogate of 3D solves
anchored to it (tengfield.surrogate.radial; the first run computes and caches
it, about a minute on 2 ranks, two serially). Reported: peak-to-peak Q_SC,
V_OC and I_SC against the lateral amplitude, relative to the vertical-only
drive. ``--fast`` (the test) leaves the field out.

Dwell times, two ways: the mean contact episode (the compliant ball touching
the plate, from entry to exit, including a resting phase) and the time the
ball stays within 1 % of the stroke of the lower plate ("near-plate dwell",
what a camera resolves), next to the paper's ~10 ms.

    .venv/bin/python demos/motion3d_lateral.py [--fast] [-o DIR]
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from tengfield.dynamics.motion3d import simulate_3d
from tengfield.scene import default_scene

from demo_mpi import is_root, world


def near_plate_dwell(t, gap, stroke, upper: bool, fraction: float = 0.01) -> np.ndarray:
    """Durations [s] of the intervals in which the ball stays within fraction*stroke of a plate."""
    near = (gap > (1 - fraction) * stroke) if upper else (gap < fraction * stroke)
    edges = np.diff(near.astype(int))
    starts = np.flatnonzero(edges == 1) + 1
    ends = np.flatnonzero(edges == -1) + 1
    if near[0]:
        starts = np.r_[0, starts]
    n = min(starts.size, ends.size)
    starts, ends = starts[:n], ends[:n]
    ok = ends > starts
    return t[ends[ok]] - t[starts[ok]]


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fast", action="store_true", help="fewer amplitudes, shorter runs")
    ap.add_argument("-o", "--output", default="demos/out", help="output directory")
    ap.add_argument("--field", action=argparse.BooleanOptionalAction, default=None,
                    help="also the electrical output through the field surrogates "
                         "(default: on, off with --fast)")
    args = ap.parse_args(argv)
    with_field = (not args.fast) if args.field is None else args.field
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    lateral_mm = [0.0, 0.5, 2.0] if args.fast else [0.0, 0.1, 0.25, 0.5, 1.0, 1.5, 2.0, 3.0]
    duration = 0.5 if args.fast else 2.0
    base = default_scene().with_values(
        contact={"model": "3d"}, excitation={"frequency_hz": 30.0, "amplitude_mm": 3.0},
        run={"duration_s": duration, "settle_periods": 5, "sample_rate_hz": 20000.0})
    rows = []
    last = None
    for ax in lateral_mm:
        r = simulate_3d(base.with_values(excitation={"amplitude_x_mm": ax, "phase_x_deg": 45.0}))
        win = r.impacts.time >= r.window_start
        upper = win & (r.impacts.plate == "upper")
        periods = (r.t[-1] - r.window_start) / r.period
        keep = r.t >= r.window_start
        dw_low = near_plate_dwell(r.t[keep], r.gap[keep], r.stroke, upper=False)
        rows.append({
            "lateral_mm": ax,
            "upper_per_period": np.count_nonzero(upper) / periods,   # impact episodes
            "upper_speed": float(np.mean(r.impacts.speed_before[upper])) if np.any(upper) else 0.0,
            "wall_per_period": np.count_nonzero(
                (r.contacts["surface"] == "wall") & (r.contacts["time_in"] >= r.window_start))
            / periods,
            "mean_r_mm": float(np.mean(r.radial[keep]) * 1e3),
            "episode_lower_ms": float(np.mean(r.dwell_times("lower")) * 1e3),
            "episode_upper_ms": float(np.mean(r.dwell_times("upper")) * 1e3)
            if r.dwell_times("upper").size else float("nan"),
            "near_lower_ms": float(np.mean(dw_low) * 1e3) if dw_low.size else float("nan"),
            "regime": r.regime.name,
            "steps_per_contact": r.steps_per_contact,
            "wall_time": r.wall_time,
        })
        last = r
    print("lateral  upper impacts/period  upper speed  wall/period  mean r   regime")
    print("  [mm]                   [m/s]                   [mm]")
    for row in rows:
        print(f"{row['lateral_mm']:6.2f}  {row['upper_per_period']:18.3f}  "
              f"{row['upper_speed']:10.3f}  {row['wall_per_period']:10.2f}  "
              f"{row['mean_r_mm']:7.3f}  {row['regime']}")
    r0 = rows[0]
    print(f"dwell at 3 mm / 30 Hz, on the axis: one Hertz episode lasts "
          f"{r0['episode_lower_ms']:.3f} ms (lower), {r0['episode_upper_ms']:.3f} ms (upper); "
          f"the ball stays within 1 % of the stroke of the lower plate for "
          f"{r0['near_lower_ms']:.2f} ms per contact; paper (Fig. 7, multibody): ~10 ms")
    print(f"steps per contact episode {r0['steps_per_contact']:.0f}; run time "
          f"{r0['wall_time']:.2f} s for {duration:g} s of motion")
    write_rows(out / "motion3d_lateral.csv", rows)

    import matplotlib.pyplot as plt
    from tengfield.plotting.dynamics import plot_trajectory3d
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4))
    x = [row["lateral_mm"] for row in rows]
    a1.plot(x, [row["upper_per_period"] for row in rows], "o-", label="upper impacts / period")
    a1.plot(x, [row["upper_speed"] for row in rows], "s-", label="upper impact speed [m/s]")
    a1.set_xlabel("lateral amplitude [mm] (vertical 3 mm, 30 Hz)")
    a1.legend(fontsize=8)
    a1.grid(alpha=0.3)
    a2.plot(x, [row["wall_per_period"] for row in rows], "o-", color="#d62728",
            label="wall contacts / period")
    a2.plot(x, [row["mean_r_mm"] for row in rows], "s-", color="0.3", label="mean radial offset [mm]")
    a2.set_xlabel("lateral amplitude [mm]")
    a2.legend(fontsize=8)
    a2.grid(alpha=0.3)
    fig.suptitle("3D ball, horizontally shaken device (paper: multibody contacts ~10 ms)",
                 fontsize=10)
    fig.tight_layout()
    if is_root():
        fig.savefig(out / "motion3d_lateral.png", dpi=120)
    plt.close(fig)
    if is_root():
        plot_trajectory3d(last, out / "motion3d_lateral_trajectory3d.png",
                          title=f"lateral {lateral_mm[-1]:g} mm")
    print(f"-> {out}/motion3d_lateral.png, motion3d_lateral.csv")
    electrical = electrical_rows(base, lateral_mm, out) if with_field else []
    return {"rows": rows, "electrical": electrical}


def electrical_rows(base, lateral_mm, out: Path) -> list[dict]:
    """Peak-to-peak Q_SC [nC], V_OC [V], I_SC [nA] of ``tengfield run`` per lateral
    amplitude (open circuit, the scene's field settings), and which surrogate served."""
    from tengfield import pipeline

    rows = []
    for ax in lateral_mm:
        res = pipeline.run(base.with_values(excitation={"amplitude_x_mm": ax, "phase_x_deg": 45.0}),
                           comm=world(), progress=True)
        rows.append({"lateral_mm": ax, "Q_sc_pp_nC": res.peaks["Q_sc"] * 1e9,
                     "V_oc_pp_V": res.peaks["V_oc"], "I_sc_pp_nA": res.peaks["I_sc"] * 1e9,
                     "surrogate": "(z, r)" if "field_zr" in res.stages else "axis"})
    q0 = rows[0]["Q_sc_pp_nC"] or float("nan")
    print("lateral   Q_SC p-p   relative   V_OC p-p   I_SC p-p   surrogate")
    print("  [mm]       [nC]                   [V]       [nA]")
    for row in rows:
        row["Q_sc_relative"] = row["Q_sc_pp_nC"] / q0
        print(f"{row['lateral_mm']:6.2f}  {row['Q_sc_pp_nC']:9.4f}  {row['Q_sc_relative']:9.4f}  "
              f"{row['V_oc_pp_V']:9.1f}  {row['I_sc_pp_nA']:9.2f}   {row['surrogate']}")
    write_rows(out / "motion3d_lateral_electrical.csv", rows)
    return rows


def write_rows(path: Path, rows: list[dict]) -> None:
    """A CSV with one line per row dict (the keys of the first as the header; rank 0
    only under mpirun)."""
    if not is_root():
        return
    with open(path, "w") as fh:
        fh.write(",".join(rows[0]) + "\n")
        for row in rows:
            fh.write(",".join(str(v) for v in row.values()) + "\n")


if __name__ == "__main__":
    main()
