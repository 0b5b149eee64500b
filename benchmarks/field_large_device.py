"""Cost of one field position against device size (issue 8, item 2).

Scales every length of the default device ([device] ball, stroke, electrodes,
tube, plates) by S = 1, 3, 10, 30 and solves the ball at mid-stroke with the
default [field] settings (axisymmetric, degree 2, mesh_size_mm = 0.5 x S, Kelvin
far field, with the error estimate), ``domain_radius_mm = 20 S`` (the default
is 20 mm for S = 1). The mesh grades away from the ball, rims, gaps and
dielectric interfaces (tengfield.field.geometry_axisymmetric.GRADING_REACH),
so the cost follows the features, not the box, and a device whose features are
all S times the paper's gets the geometrically similar mesh: the default
``mesh_size_mm`` (not written in the default scene) is scaled by the smallest
feature against the paper's (``scene.default_mesh_scale``; a written value is used
as written). A last row
(S = 0) is the default device with 100 mm electrodes. Prints one row per case:
S, dofs, wall time [s], relative error estimate, C_T [pF], q_upper/q_ball.

    .venv/bin/python benchmarks/field_large_device.py [--scales 1 30]
"""
from __future__ import annotations

import argparse
import time

LENGTH_KEYS = ("ball_diameter_mm", "stroke_mm", "electrode_radius_mm", "tube_inner_radius_mm",
               "tube_outer_radius_mm", "plate_thickness_mm")


def scaled_scene(scale: float):
    from tengfield.scene import default_scene

    base = default_scene()
    dev = base.device
    values = {"ball_diameter_mm": dev.ball_diameter, "stroke_mm": dev.stroke,
              "electrode_radius_mm": dev.electrode_radius,
              "tube_inner_radius_mm": dev.tube_inner_radius,
              "tube_outer_radius_mm": dev.tube_outer_radius,
              "plate_thickness_mm": dev.plate_thickness}
    return base.with_values(device={k: v * 1e3 * scale for k, v in values.items()},
                            field={"domain_radius_mm": base.field.domain_radius * 1e3 * scale})


def wide_scene():
    """The default device with 100 mm electrodes (plates and tube 105 mm): the case of
    issue 8 that took over 4 minutes per position before the feature grading."""
    from tengfield.scene import default_scene

    return default_scene().with_values(
        device={"electrode_radius_mm": 100.0, "tube_inner_radius_mm": 100.0,
                "tube_outer_radius_mm": 105.0}, field={"domain_radius_mm": 150.0})


def main(argv=None) -> list[dict]:
    from mpi4py import MPI

    from tengfield.field import solve_position

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scales", type=float, nargs="+", default=[1.0, 3.0, 10.0, 30.0])
    parser.add_argument("--no-wide", action="store_true",
                        help="skip the device with 100 mm electrodes (S = 0 row)")
    args = parser.parse_args(argv)
    rows = []
    print(f"{'S':>5} {'dofs':>8} {'wall_s':>8} {'estimate':>9} {'C_T_pF':>10} {'q_up/q_ball':>12}")
    cases = [(scale, scaled_scene(scale)) for scale in args.scales]
    if not args.no_wide:
        cases.append((0.0, wide_scene()))
    for scale, scene in cases:
        start = time.perf_counter()
        res = solve_position(scene, 0.5 * scene.device.stroke, comm=MPI.COMM_SELF)
        wall = time.perf_counter() - start
        row = {"scale": scale, "dofs": res.dofs, "wall_s": wall,
               "estimate": res.relative_error_estimate,
               "C_T_pF": res.terminal_capacitance() * 1e12,
               "q_upper_fraction": float(res.induced_fractions()[1])}
        rows.append(row)
        print(f"{scale:5g} {res.dofs:8d} {wall:8.2f} {row['estimate']:9.2g} "
              f"{row['C_T_pF']:10.5g} {row['q_upper_fraction']:12.6f}", flush=True)
    return rows


if __name__ == "__main__":
    main()
